// The concurrency contract (occupancy_map.hpp): one thread inserts scans
// while others query and iterate; every reader must see the map as it was
// after some whole scan.
//
// The scans are first inserted into a separate map, copying it after each
// scan (the snapshots). Then the writer inserts the same scans into a fresh
// map while readers ask questions; around each question a reader reads two
// counters (scans finished before it asked, scans started after it got the
// answer), and the answer must equal the same question asked of one of the
// snapshots in that range. Questions cover point lookups at every depth,
// collision checks, whole-map iterations and counts; every iteration also
// checks that each inner node it meets agrees with its children (never a
// coarse node that disagrees with them). Integrators, thread counts, color
// and automatic pruning vary, and decay steps (advance_clock) or moves of a
// moving window (move_window) run between the scans in two tests. The same test runs under ThreadSanitizer in
// the `tsan` label (tests/map/run_tsan_stress.sh).
#include <atomic>
#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "umbra/map/occupancy_map.hpp"
#include "umbra/field/distance_field.hpp"
#include "umbra/sim/lidar.hpp"
#include "umbra/sim/scene.hpp"

namespace umbra {
namespace {

struct Scans {
  std::vector<Vec3f> origins;
  std::vector<std::vector<Vec3f>> points;
  std::vector<std::vector<Rgb>> colors;
};

/// Simulated LiDAR scans in the demo building, with random ray clutter.
Scans make_scans(std::size_t count, unsigned seed) {
  Scans scans;
  const sim::Scene scene = sim::make_demo_scene();
  sim::LidarModel lidar;
  lidar.rings = 8;
  lidar.azimuth_steps = 120;
  lidar.range_noise_stddev = 0.03;
  lidar.seed = seed;
  const auto path = sim::demo_path();
  std::mt19937 rng(seed);
  for (std::size_t i = 0; i < count; ++i) {
    const sim::SensorPose& pose = path[(i * 5) % path.size()];
    scans.origins.push_back(static_cast<Vec3f>(pose.position));
    std::vector<Vec3f> points = sim::simulate_scan(scene, pose, lidar);
    std::uniform_int_distribution<int> channel(0, 255);
    std::vector<Rgb> colors(points.size());
    for (Rgb& c : colors) c = {std::uint8_t(channel(rng)), std::uint8_t(channel(rng)), std::uint8_t(channel(rng))};
    scans.points.push_back(std::move(points));
    scans.colors.push_back(std::move(colors));
  }
  return scans;
}

struct Setup {
  IntegratorKind integrator;
  unsigned threads;
  bool color;
  bool auto_prune;
  bool decay = false;  ///< each scan preceded by a decay step (advance_clock), a step of its own
  bool window = false;  ///< each scan preceded by a move of a moving window to its origin, a step of its own
};

/// One question a reader asks; its answer as a string (comparable across maps).
using Question = std::function<std::string(const OccupancyMap&)>;

/// Walks every node of the map at `depth`, checking that each node with
/// children has the maximum of its children as its value and the indicators
/// they imply; returns the count of occupied leaves (or "inconsistent ...").
std::string consistent_walk(const OccupancyMap& map, int depth) {
  // Parents come before children: keep the open parents on a stack.
  struct Open {
    Node node;
    float max = -1e30f;
    bool any_free = false;
    bool any_unknown = false;
    int seen = 0;
  };
  std::vector<Open> open;
  std::size_t occupied = 0;
  auto close_finished = [&]() -> std::string {
    while (!open.empty() && open.back().seen == 8) {
      const Open done = open.back();
      open.pop_back();
      if (done.max != done.node.log_odds || done.any_free != done.node.contains_free ||
          done.any_unknown != done.node.contains_unknown) {
        return "inconsistent node at depth " + std::to_string(done.node.depth);
      }
      if (!open.empty()) {
        Open& parent = open.back();
        parent.max = std::max(parent.max, done.node.log_odds);
        parent.any_free |= done.node.contains_free;
        parent.any_unknown |= done.node.contains_unknown;
        ++parent.seen;
      }
    }
    return {};
  };
  for (const Node& node : map.query(pred::any(), depth)) {
    const bool leaf = node.depth <= depth || !node.has_children;
    if (leaf) {
      occupied += node.state == OccupancyState::occupied;
      if (!open.empty()) {
        Open& parent = open.back();
        parent.max = std::max(parent.max, node.log_odds);
        parent.any_free |= node.contains_free;
        parent.any_unknown |= node.contains_unknown;
        ++parent.seen;
      }
      if (std::string problem = close_finished(); !problem.empty()) return problem;
    } else {
      open.push_back({node});
    }
  }
  if (!open.empty()) return "iteration ended inside an open node";
  return "occupied leaves " + std::to_string(occupied);
}

std::vector<Question> questions(unsigned seed) {
  std::vector<Question> out;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(0.0, 20.0), y(0.0, 12.0), z(0.0, 3.0), r(0.1, 1.0);
  for (int i = 0; i < 6; ++i) {
    const Vec3d p{x(rng), y(rng), z(rng)};
    const double radius = r(rng);
    out.push_back([p, radius](const OccupancyMap& m) {
      const CollisionResult c = m.is_free(Sphere{p, radius});
      return std::to_string(c.free) + (c.blocking ? " " + std::to_string(c.blocking->code()) : "");
    });
    // The nodes on the path to p, root to leaf, in one query (several
    // node() calls would be several reads, each of a whole scan, but not
    // necessarily the same one).
    out.push_back([p](const OccupancyMap& m) {
      std::string s;
      for (const Node& n : m.query(pred::intersects(Aabb{p, p}))) {
        s += std::to_string(n.log_odds) + (n.color ? "c" + std::to_string(n.color->r) : "") + " ";
      }
      return s;
    });
  }
  out.push_back([](const OccupancyMap& m) { return std::to_string(m.count(pred::leaf() && pred::occupied(), 1)); });
  out.push_back([](const OccupancyMap& m) { return consistent_walk(m, 0); });
  out.push_back([](const OccupancyMap& m) { return consistent_walk(m, 2); });
  out.push_back([](const OccupancyMap& m) {
    const RayHit hit = m.cast_ray({2.0, 2.0, 1.5}, {1.0, 0.3, 0.05}, {15.0, false, 0});
    return std::to_string(hit.hit) + " " + std::to_string(hit.distance);
  });
  return out;
}

void run_contract(const Setup& setup, std::size_t scan_count, int readers, int rounds) {
  const Scans scans = make_scans(scan_count, 7);
  MapConfig config;
  config.resolution = 0.1;
  config.depth_levels = 12;
  config.color = setup.color;
  InsertOptions options;
  options.integrator = setup.integrator;
  options.threads = setup.threads;
  options.max_range = 12.0;
  auto insert = [&](OccupancyMap& map, std::size_t i) {
    if (setup.color) {
      map.insert_point_cloud(scans.origins[i], scans.points[i], scans.colors[i], options);
    } else {
      map.insert_point_cloud(scans.origins[i], scans.points[i], options);
    }
  };
  // The writer's steps, each seen whole by readers: the scans, and with
  // decay a clock step before each (fast rates: states change every step).
  // With a moving window the move to each scan's origin before it.
  const bool two_steps = setup.decay || setup.window;
  const std::size_t step_count = two_steps ? 2 * scan_count : scan_count;
  auto step = [&](OccupancyMap& map, std::size_t s) {
    if (!two_steps) return insert(map, s);
    if (s % 2 == 0) {
      if (setup.decay) return map.advance_clock(0.5 * static_cast<double>(s));
      return static_cast<void>(map.move_window(Vec3d(scans.origins[s / 2])));
    }
    insert(map, s / 2);
  };
  auto new_map = [&] {
    OccupancyMap map(config);
    map.set_auto_prune(setup.auto_prune);
    if (setup.decay) map.set_decay({1.0, 0.4, std::nullopt});
    if (setup.window) {
      MovingWindow window;
      window.half_extent = 2.0;  // the demo path's poses lie metres apart: every move forgets something
      window.follow_scans = false;
      map.set_moving_window(window);
    }
    return map;
  };

  // The snapshots: the map after 0, 1, ... steps.
  std::vector<OccupancyMap> snapshots;
  {
    OccupancyMap map = new_map();
    snapshots.push_back(map);
    for (std::size_t i = 0; i < step_count; ++i) {
      step(map, i);
      snapshots.push_back(map);
    }
  }
  const std::vector<Question> asked = questions(11);
  std::vector<std::vector<std::string>> expected(asked.size());
  for (std::size_t q = 0; q < asked.size(); ++q) {
    for (const OccupancyMap& s : snapshots) expected[q].push_back(asked[q](s));
  }

  for (int round = 0; round < rounds; ++round) {
    OccupancyMap map = new_map();
    std::atomic<std::size_t> started{0};
    std::atomic<std::size_t> finished{0};
    std::atomic<bool> done{false};
    std::atomic<std::size_t> answers{0};
    std::atomic<std::size_t> failures{0};
    std::string first_failure;
    std::mutex failure_lock;

    std::vector<std::thread> threads;
    for (int r = 0; r < readers; ++r) {
      threads.emplace_back([&, r] {
        std::size_t q = static_cast<std::size_t>(r);
        while (!done.load()) {
          q = (q + 1) % asked.size();
          const std::size_t low = finished.load();
          const std::string answer = asked[q](map);
          const std::size_t high = started.load();
          bool matched = false;
          for (std::size_t k = low; k <= high && k < expected[q].size(); ++k) matched |= expected[q][k] == answer;
          answers.fetch_add(1);
          if (!matched) {
            failures.fetch_add(1);
            std::lock_guard guard(failure_lock);
            if (first_failure.empty()) {
              first_failure = "question " + std::to_string(q) + " answered '" + answer + "' between scans " +
                              std::to_string(low) + " and " + std::to_string(high);
            }
          }
        }
      });
    }
    for (std::size_t i = 0; i < step_count; ++i) {
      started.store(i + 1);
      step(map, i);
      finished.store(i + 1);
    }
    // Let the readers see the finished map too.
    while (answers.load() < asked.size() * static_cast<std::size_t>(readers) * 2) std::this_thread::yield();
    done.store(true);
    for (std::thread& t : threads) t.join();
    EXPECT_EQ(failures.load(), 0u) << first_failure;
    EXPECT_GT(answers.load(), 0u);
    for (std::size_t q = 0; q < asked.size(); ++q) EXPECT_EQ(asked[q](map), expected[q].back()) << "question " << q;
  }
}

TEST(Concurrency, ReadersSeeWholeScansWithEveryIntegrator) {
  for (const IntegratorKind kind : {IntegratorKind::simple, IntegratorKind::discrete, IntegratorKind::fast}) {
    SCOPED_TRACE(to_string(kind));
    run_contract({kind, 1, false, true}, 8, 2, 1);
  }
}

/// Decay steps (advance_clock) between the scans: readers see each step whole.
TEST(Concurrency, ReadersSeeWholeDecaySteps) {
  run_contract({IntegratorKind::discrete, 1, false, true, true}, 6, 2, 1);
  run_contract({IntegratorKind::fast, 2, true, false, true}, 5, 2, 1);
}

/// Moves of a moving window between the scans: readers see each move whole.
TEST(Concurrency, ReadersSeeWholeWindowMoves) {
  run_contract({IntegratorKind::discrete, 1, false, true, false, true}, 6, 2, 1);
  run_contract({IntegratorKind::fast, 2, true, false, false, true}, 5, 2, 1);
}

TEST(Concurrency, ReadersSeeWholeScansWithThreadsColorAndNoPruning) {
  run_contract({IntegratorKind::discrete, 2, false, true}, 8, 2, 1);
  run_contract({IntegratorKind::fast, 2, false, false}, 8, 2, 1);
  run_contract({IntegratorKind::discrete, 1, true, true}, 6, 2, 1);
  // The projective integrator's workers' batches are applied side by side
  // (tree/apply_batches.cpp), inside the same exclusive phase.
  run_contract({IntegratorKind::projective, 2, true, false}, 6, 2, 1);
}

/// The distance field's contract (distance_field.hpp): a writer inserts a
/// scan and updates the field while readers ask the field in batches; every
/// batch answer equals the field of one snapshot between the updates
/// finished before it and those started after it (never half an update).
TEST(Concurrency, FieldReadersSeeWholeUpdates) {
  const std::size_t scan_count = 3;
  const Scans scans = make_scans(scan_count, 9);
  InsertOptions options;
  options.max_range = 12.0;
  DistanceFieldOptions field_options;
  field_options.max_distance = 0.3;
  std::vector<Vec3d> probe;
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> x(0.0, 20.0), y(0.0, 12.0), z(0.0, 3.0);
  for (int i = 0; i < 300; ++i) probe.push_back({x(rng), y(rng), z(rng)});
  const auto ask = [&](const DistanceField& field) {
    std::vector<DistanceSample> samples(probe.size());
    field.distance_and_gradient(probe, samples);
    std::vector<double> flat;
    for (const DistanceSample& s : samples) flat.insert(flat.end(), {s.occupied, s.unknown, s.gradient.x});
    return flat;
  };
  std::vector<std::vector<double>> expected;
  {
    OccupancyMap map(0.1, 12);
    expected.push_back(ask(DistanceField(map, field_options)));
    for (std::size_t i = 0; i < scan_count; ++i) {
      map.insert_point_cloud(scans.origins[i], scans.points[i], options);
      expected.push_back(ask(DistanceField(map, field_options)));
    }
  }
  OccupancyMap map(0.1, 12);
  DistanceField field(map, field_options);
  std::atomic<std::size_t> started{0}, finished{0}, answers{0}, failures{0};
  std::atomic<bool> done{false};
  std::vector<std::thread> readers;
  for (int r = 0; r < 2; ++r) {
    readers.emplace_back([&] {
      while (!done.load()) {
        const std::size_t low = finished.load();
        const std::vector<double> answer = ask(field);
        const std::size_t high = started.load();
        bool matched = false;
        for (std::size_t k = low; k <= high && k < expected.size(); ++k) matched |= expected[k] == answer;
        failures.fetch_add(matched ? 0 : 1);
        answers.fetch_add(1);
      }
    });
  }
  for (std::size_t i = 0; i < scan_count; ++i) {
    started.store(i + 1);
    map.insert_point_cloud(scans.origins[i], scans.points[i], options);
    field.update();
    finished.store(i + 1);
  }
  while (answers.load() < 4) std::this_thread::yield();
  done.store(true);
  for (std::thread& t : readers) t.join();
  EXPECT_EQ(failures.load(), 0u);
  EXPECT_EQ(ask(field), expected.back());
}

TEST(Concurrency, ChangingTheMapWhileThisThreadHoldsARangeThrows) {
  OccupancyMap map(0.1, 8);
  const std::vector<Vec3f> points = {{1.0f, 0.0f, 0.0f}};
  map.insert_point_cloud({0, 0, 0}, points);
  for (const Node& node : map.query(pred::leaf() && pred::occupied())) {
    (void)node;
    EXPECT_THROW(map.insert_point_cloud({0, 0, 0}, points), std::logic_error);
    EXPECT_THROW(map.prune(), std::logic_error);
    EXPECT_THROW(map.set_thresholds({0.6, 0.4}), std::logic_error);
    EXPECT_EQ(map.state({1.0, 0.0, 0.0}), OccupancyState::occupied);  // nested reads are fine
  }
  // After the loop the range is gone and changes go through.
  EXPECT_NO_THROW(map.insert_point_cloud({0, 0, 0}, points));
}

TEST(Concurrency, ExclusiveChangesWaitForRangesOfOtherThreads) {
  OccupancyMap map(0.1, 8);
  const std::vector<Vec3f> points = {{1.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}};
  map.insert_point_cloud({0, 0, 0}, points);
  std::atomic<bool> holding{false};
  std::atomic<bool> release{false};
  std::atomic<std::size_t> seen_during{0};
  std::thread reader([&] {
    auto range = map.query(pred::leaf() && pred::occupied());
    std::size_t n = 0;
    for (auto it = range.begin(); it != range.end(); ++it) {
      ++n;
      if (n == 1) {
        holding.store(true);
        while (!release.load()) std::this_thread::yield();
      }
    }
    seen_during.store(n);
  });
  while (!holding.load()) std::this_thread::yield();
  std::atomic<bool> cleared{false};
  std::thread writer([&] {
    map.clear();  // must wait for the reader's range
    cleared.store(true);
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_FALSE(cleared.load()) << "clear() ran while another thread iterated";
  release.store(true);
  reader.join();
  writer.join();
  EXPECT_TRUE(cleared.load());
  EXPECT_EQ(seen_during.load(), 2u);  // the iteration saw the whole map before the clear
  EXPECT_EQ(map.count(pred::leaf() && pred::occupied()), 0u);
}

}  // namespace
}  // namespace umbra
