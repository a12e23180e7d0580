#include "explorer.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <latch>
#include <limits>
#include <mutex>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace umbra::explore {

namespace {

[[noreturn]] void bad_field(const char* field, const std::string& requirement, double value) {
  std::ostringstream out;
  out << "ExplorerConfig::" << field << " must be " << requirement << ", got " << value;
  throw std::invalid_argument(out.str());
}

/// The robot's motions, appended by the planning thread and read by the
/// mapping thread (a pose at a frame's time). The planner appends a motion
/// only from its own time on, and the mapper asks only for times it has
/// reached, which the planner has too: a pose once read never changes.
class Trajectory {
 public:
  explicit Trajectory(const Pose& start) : start_(start) {}

  void append(const Motion& motion) {
    const std::lock_guard lock(mutex_);
    motions_.push_back(motion);
  }

  [[nodiscard]] Pose at(double time) const {
    const std::lock_guard lock(mutex_);
    Pose pose = start_;
    for (const Motion& m : motions_) {
      if (time < m.t0) break;
      if (time >= m.t1) {
        pose = m.to;
        continue;
      }
      const double s = (time - m.t0) / (m.t1 - m.t0);
      pose.position = m.from.position + (m.to.position - m.from.position) * s;
      pose.yaw = m.from.yaw + (m.to.yaw - m.from.yaw) * s;
      break;
    }
    return pose;
  }

  [[nodiscard]] std::vector<Motion> motions() const {
    const std::lock_guard lock(mutex_);
    return motions_;
  }

 private:
  Pose start_;
  mutable std::mutex mutex_;
  std::vector<Motion> motions_;
};

/// Yaw of `to` unwrapped next to `from`: the turn the short way.
double unwrapped_yaw(double from, double to) {
  double turn = std::remainder(to - from, 2.0 * std::numbers::pi);
  return from + turn;
}

}  // namespace

void ExplorerConfig::validate() const {
  planner.validate();
  camera.validate();
  if (camera.hfov_deg != planner.camera.hfov_deg || camera.vfov_deg != planner.camera.vfov_deg) {
    bad_field("camera.hfov_deg", "planner.camera.hfov_deg (and the vfov too)", camera.hfov_deg);
  }
  if (!(frame_rate > 0.0)) bad_field("frame_rate", "> 0", frame_rate);
  if (!(speed > 0.0)) bad_field("speed", "> 0", speed);
  if (!(yaw_rate > 0.0)) bad_field("yaw_rate", "> 0", yaw_rate);
  if (!(start_clearance >= planner.check_radius())) {
    bad_field("start_clearance", ">= the planner's check radius", start_clearance);
  }
  if (!(budget > 0.0)) bad_field("budget", "> 0", budget);
  if (!(coverage_period > 0.0)) bad_field("coverage_period", "> 0", coverage_period);
}

double ExplorationResult::time_to(double fraction) const {
  for (std::size_t i = 0; i < coverage.size(); ++i) {
    if (coverage[i].coverage < fraction) continue;
    if (i == 0) return coverage[i].time;
    const CoverageSample& a = coverage[i - 1];
    const CoverageSample& b = coverage[i];
    return a.time + (b.time - a.time) * (fraction - a.coverage) / (b.coverage - a.coverage);
  }
  return -1.0;
}

ExplorationResult explore(ExplorationMap& map, const sim::Scene& scene, const sim::ReachableSpace& truth,
                          const Pose& start, const ExplorerConfig& config,
                          const std::function<void(const CoverageSample&)>& progress) {
  config.validate();
  if (std::abs(truth.cell_size() - map.resolution()) > 1e-12 * map.resolution()) {
    throw std::invalid_argument("explore: the reachable space's cells must be the map's voxels");
  }
  if (scene.is_inside_solid(start.position) ||
      scene.distance_to_nearest_surface(start.position) < config.start_clearance) {
    throw std::invalid_argument("explore: the scene is not clear within start_clearance of the robot's start");
  }
  const auto wall_start = std::chrono::steady_clock::now();

  ExplorationResult result;
  result.map_name = map.name();
  result.reachable_m3 = truth.volume();
  map.assume_free(Sphere{start.position, config.start_clearance});

  SimClock clock(config.clock);
  Trajectory trajectory(start);
  // The first motion: one turn on the spot, to see around.
  const double turn_time = 2.0 * std::numbers::pi / config.yaw_rate;
  trajectory.append({0.0, turn_time, start, {start.position, start.yaw + 2.0 * std::numbers::pi}});

  std::atomic<bool> inserting{false};
  std::atomic<bool> planner_done{false};
  std::atomic<double> planner_end{config.budget};
  std::atomic<bool> failed{false};  // a thread threw: the other stops too
  std::exception_ptr mapping_error;
  std::exception_ptr planning_error;
  // Neither thread may take a step in simulated time before the other is an
  // actor of the clock (it would not be waited for).
  std::latch actors_ready(2);

  std::thread mapping([&] {
    SimClock::Actor actor(clock);
    actors_ready.arrive_and_wait();
    try {
      const double period = 1.0 / config.frame_rate;
      sim::DepthCameraModel camera = config.camera;
      std::vector<Vec3f> points;
      double next_frame = 0.0;
      double next_sample = 0.0;
      double last_frame = -1.0;
      // Coverage after the frame of `time`, outside simulated time.
      auto measure = [&](double time) {
        actor.pause();
        std::size_t cells = 0;
        map.for_each_free_node([&](Vec3d min, Vec3d max) { cells += truth.count_in(min, max); });
        const double cell = truth.cell_size();
        const CoverageSample sample{time, double(cells) * cell * cell * cell,
                                    double(cells) / double(std::max<std::size_t>(1, truth.cell_count()))};
        result.coverage.push_back(sample);
        if (progress) progress(sample);
        actor.resume();
      };
      for (std::uint64_t index = 0;; ++index) {
        actor.wait_until(next_frame);
        // The newest frame: those the mapper was too slow for are dropped.
        const double frame = std::max(next_frame, std::floor(actor.now() * config.frame_rate) / config.frame_rate);
        const double end = planner_done.load() ? planner_end.load() : config.budget;
        if (frame > std::min(end, config.budget) || failed.load()) break;
        result.frames_dropped += std::uint64_t(std::llround((frame - next_frame) * config.frame_rate));

        const Pose pose = trajectory.at(frame);
        actor.pause();
        camera.seed = config.seed + std::uint32_t(index);
        sim::simulate_depth_image(
            scene, {pose.position, pose.yaw, config.planner.camera.pitch_deg * std::numbers::pi / 180.0}, camera,
            points);
        actor.resume();

        inserting.store(true);
        const auto t0 = std::chrono::steady_clock::now();
        map.insert(Vec3f(pose.position), points, camera.max_range);
        result.insertions.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        ++result.insertions.count;
        inserting.store(false);

        last_frame = frame;
        if (frame >= next_sample) {
          measure(frame);
          while (next_sample <= frame) next_sample += config.coverage_period;
        }
        next_frame = frame + period;
      }
      if (last_frame >= 0.0 && (result.coverage.empty() || result.coverage.back().time < last_frame)) {
        measure(last_frame);
      }
    } catch (...) {
      mapping_error = std::current_exception();
      failed.store(true);
    }
    actor.finish();
  });

  std::thread planning([&] {
    SimClock::Actor actor(clock);
    actors_ready.arrive_and_wait();
    try {
      NbvPlanner planner(config.planner, config.seed, &inserting);
      actor.wait_until(turn_time);
      Pose robot = trajectory.at(turn_time);
      for (;;) {
        const double began = actor.now();
        if (began >= config.budget || failed.load()) break;
        const PlanStep step = planner.plan(map, robot);
        const double planned = actor.now();
        result.planning_time += planned - began;
        if (!step.gain_found) {
          result.finished = planned < config.budget;
          break;
        }
        Pose next = step.next;
        next.yaw = unwrapped_yaw(robot.yaw, next.yaw);
        const double distance = (next.position - robot.position).norm();
        const double duration = std::max(distance / config.speed, std::abs(next.yaw - robot.yaw) / config.yaw_rate);
        trajectory.append({planned, planned + duration, robot, next});
        result.flight_time += duration;
        result.flight_distance += distance;
        actor.wait_until(planned + duration);
        robot = next;
      }
      planner_end.store(actor.now());
      result.planner = planner.stats();
    } catch (...) {
      planning_error = std::current_exception();
      failed.store(true);
      planner_end.store(actor.now());
    }
    planner_done.store(true);
    actor.finish();
  });

  planning.join();
  mapping.join();
  if (planning_error) std::rethrow_exception(planning_error);
  if (mapping_error) std::rethrow_exception(mapping_error);
  result.motions = trajectory.motions();
  result.end_time = result.coverage.empty() ? 0.0 : result.coverage.back().time;
  result.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return result;
}

double min_clearance(const ExplorationResult& result, const sim::Scene& scene, double step) {
  double clearance = std::numeric_limits<double>::infinity();
  auto at = [&](Vec3d p) {
    const double d = scene.is_inside_solid(p) ? 0.0 : scene.distance_to_nearest_surface(p);
    clearance = std::min(clearance, d);
  };
  for (const Motion& m : result.motions) {
    const Vec3d delta = m.to.position - m.from.position;
    const int pieces = std::max(1, int(std::ceil(delta.norm() / step)));
    for (int i = 0; i <= pieces; ++i) at(m.from.position + delta * (double(i) / pieces));
  }
  return clearance;
}

}  // namespace umbra::explore
