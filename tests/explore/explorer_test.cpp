// Tests of the explorer's loop (examples/explore/explorer.hpp) and its
// simulated clock (sim_clock.hpp): a few simulated seconds of exploring the
// plant on umbra (mapping and planning in two threads) whose coverage is
// recounted from the final map, whose robot never came near a surface, and
// whose frames arrived at the frame rate; coverage times interpolated as
// stated; and actors of the clock keeping step in simulated time.
#include <gtest/gtest.h>

#include <latch>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "explorer.hpp"
#include "sim_clock.hpp"
#include "umbra/sim/industrial_scene.hpp"
#include "umbra/sim/reachable_space.hpp"
#include "umbra_exploration_map.hpp"

namespace umbra::explore {
namespace {

TEST(Explorer, AFewSecondsOfExploringThePlantOnUmbra) {
  const sim::IndustrialPlant plant = sim::make_industrial_scene(1);
  ExplorerConfig config;
  config.planner.bounds = Aabb{plant.interior.min, plant.interior.max};
  config.camera.width = 64;
  config.camera.height = 34;
  config.camera.emit_no_return = true;
  config.camera.no_return_range = config.camera.max_range + 1.0;
  config.yaw_rate = 3.0;  // the first turn takes 2.1 s, then it plans and flies
  config.budget = 5.0;
  config.coverage_period = 0.5;
  UmbraExplorationMap map(UmbraMapOptions{});
  const sim::ReachableSpace truth(plant.scene, plant.interior, map.resolution(), config.planner.robot_radius,
                                  plant.start);
  const ExplorationResult result = explore(map, plant.scene, truth, {plant.start, 0.0}, config);

  EXPECT_EQ(result.map_name, "umbra");
  EXPECT_DOUBLE_EQ(result.reachable_m3, truth.volume());
  // A frame every 0.1 s from 0 to the budget, each inserted or dropped.
  EXPECT_EQ(result.insertions.count + result.frames_dropped, 51u);
  EXPECT_GE(result.planner.steps, 1u);
  EXPECT_GE(result.motions.size(), 2u);  // the turn, then at least one planned edge
  EXPECT_GT(result.flight_distance, 0.0);

  // Coverage: sampled in time order, growing, and the last sample is the
  // final map's free leaves counted against the ground truth again.
  ASSERT_GE(result.coverage.size(), 5u);
  for (std::size_t i = 1; i < result.coverage.size(); ++i) {
    EXPECT_GT(result.coverage[i].time, result.coverage[i - 1].time);
  }
  EXPECT_GT(result.coverage.back().coverage, 2.0 * result.coverage.front().coverage);
  std::size_t cells = 0;
  for (const Node& node : map.map().query(pred::leaf() && pred::free())) {
    cells += truth.count_in(node.min_corner(), node.max_corner());
  }
  EXPECT_DOUBLE_EQ(result.coverage.back().coverage, double(cells) / double(truth.cell_count()));

  // The robot (0.3 m) never touched the plant, flying or turning.
  EXPECT_GE(min_clearance(result, plant.scene), config.planner.robot_radius);
  for (const Motion& m : result.motions) {
    EXPECT_LE(m.t0, m.t1);
    EXPECT_TRUE(truth.reachable(m.to.position));
  }
}

TEST(Explorer, BadConfigAndBadStartAreRefused) {
  const sim::IndustrialPlant plant = sim::make_industrial_scene(1);
  ExplorerConfig config;
  config.planner.bounds = Aabb{plant.interior.min, plant.interior.max};
  UmbraExplorationMap map(UmbraMapOptions{});
  const sim::ReachableSpace truth(plant.scene, plant.interior, map.resolution(), config.planner.robot_radius,
                                  plant.start);
  ExplorerConfig bad = config;
  bad.camera.hfov_deg = 90.0;  // not the planner's camera
  EXPECT_THROW(explore(map, plant.scene, truth, {plant.start, 0.0}, bad), std::invalid_argument);
  bad = config;
  bad.frame_rate = 0.0;
  EXPECT_THROW(explore(map, plant.scene, truth, {plant.start, 0.0}, bad), std::invalid_argument);
  // A start inside the floor slab.
  EXPECT_THROW(explore(map, plant.scene, truth, {{plant.start.x, plant.start.y, -0.1}, 0.0}, config),
               std::invalid_argument);
}

TEST(Explorer, TimeToCoverageInterpolatesBetweenSamples) {
  ExplorationResult result;
  result.coverage = {{0.0, 0.0, 0.1}, {10.0, 0.0, 0.5}, {20.0, 0.0, 0.9}, {30.0, 0.0, 0.96}};
  EXPECT_DOUBLE_EQ(result.time_to(0.05), 0.0);
  EXPECT_DOUBLE_EQ(result.time_to(0.3), 5.0);
  EXPECT_DOUBLE_EQ(result.time_to(0.9), 20.0);
  EXPECT_DOUBLE_EQ(result.time_to(0.95), 20.0 + 10.0 * 0.05 / 0.06);
  EXPECT_LT(result.time_to(0.97), 0.0);
}

TEST(SimClock, ActorsKeepStepInSimulatedTime) {
  // Each actor waits for its own times; no actor goes on past time t before
  // the other has reached t, so the events come in time order.
  SimClock clock(SimClock::Mode::accelerated);
  std::mutex mutex;
  std::latch both_joined(2);  // no actor may start before the other exists
  std::vector<std::string> events;
  auto record = [&](const std::string& event) {
    const std::lock_guard lock(mutex);
    events.push_back(event);
  };
  std::thread a([&] {
    SimClock::Actor actor(clock);
    both_joined.arrive_and_wait();
    for (const double t : {1.0, 3.0, 5.0}) {
      actor.wait_until(t);
      EXPECT_GE(actor.now(), t);
      record("a" + std::to_string(int(t)));
    }
    actor.finish();
  });
  std::thread b([&] {
    SimClock::Actor actor(clock);
    both_joined.arrive_and_wait();
    for (const double t : {2.0, 4.0, 6.0}) {
      actor.wait_until(t);
      record("b" + std::to_string(int(t)));
    }
    actor.finish();
  });
  a.join();
  b.join();
  // a5 and b6 may come in either order only if a finished first; a5 < b6 in
  // time, and b waits for a's 5 before its 6.
  EXPECT_EQ(events, (std::vector<std::string>{"a1", "b2", "a3", "b4", "a5", "b6"}));
}

TEST(SimClock, MutexCarriesTheReleaseTimeToTheTaker) {
  SimClock clock(SimClock::Mode::accelerated);
  SimMutex mutex;
  std::thread first([&] {
    SimClock::Actor actor(clock);
    actor.wait_until(7.0);
    mutex.lock();
    mutex.unlock();  // released at 7 s (and a little CPU)
    actor.finish();
  });
  first.join();
  SimClock::Actor actor(clock);
  EXPECT_LT(actor.now(), 1.0);
  mutex.lock();
  EXPECT_GE(actor.now(), 7.0);
  mutex.unlock();
}

}  // namespace
}  // namespace umbra::explore
