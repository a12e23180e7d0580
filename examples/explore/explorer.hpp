// explore(): a flying robot explores a simulated scene with the
// next-best-view planner, mapping and planning in two threads on one map.
//
// The robot is a ball (PlannerConfig::robot_radius) carrying the depth camera
// (sim/depth_camera.hpp) at a fixed pitch. It is put down in a clear spot:
// the ball of `start_clearance` around the start is assumed free (the camera
// cannot see steeply up or down, so without it no path could leave the
// start). It turns once on the spot, then repeats:
// plan a step (nbv_planner.hpp) while hovering, fly the step's edge at
// `speed` and `yaw_rate` (straight line, yaw turned the short way), plan
// again; it stops when the planner finds no gain or the budget of simulated
// time is spent.
//
// Two threads share the map:
//  - mapping: every 1 / frame_rate s of simulated time it renders the
//    camera's image at the robot's pose then and inserts it; if inserting
//    takes longer than a frame period, the frames in between are dropped
//    (as a sensor driver with a queue of one does). After a frame it
//    measures coverage every `coverage_period` s: the known-free part of the
//    reachable space (sim/reachable_space.hpp), from the map's free leaves.
//  - planning: the loop above.
// Simulated time comes from a SimClock (sim_clock.hpp): real time, or as
// fast as the machine allows with every CPU second of inserting and planning
// charged. Rendering the image and measuring coverage cost no simulated time.
//
// Cost: the study's (docs/exploration.md); a frame costs its rendering
// (width x height scene ray casts) and its insertion.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "exploration_map.hpp"
#include "nbv_planner.hpp"
#include "sim_clock.hpp"
#include "umbra/sim/depth_camera.hpp"
#include "umbra/sim/reachable_space.hpp"
#include "umbra/sim/scene.hpp"

namespace umbra::explore {

struct ExplorerConfig {
  PlannerConfig planner;
  /// Image size and range; its fields of view must equal planner.camera's.
  sim::DepthCameraModel camera;
  double frame_rate = 10.0;  ///< Hz of simulated time
  double speed = 1.0;        ///< m/s
  double yaw_rate = 1.0;     ///< rad/s
  /// Metres around the start assumed free (and checked free in the scene).
  double start_clearance = 1.0;
  double budget = 900.0;     ///< seconds of simulated time
  double coverage_period = 2.0;  ///< seconds of simulated time between coverage samples
  SimClock::Mode clock = SimClock::Mode::accelerated;
  std::uint32_t seed = 1;

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

struct CoverageSample {
  double time = 0.0;         ///< simulated seconds
  double explored_m3 = 0.0;  ///< reachable space the map knows as free
  double coverage = 0.0;     ///< explored_m3 / reachable volume
};

/// A piece of the robot's motion: from `from` at t0 to `to` at t1 (linear;
/// yaw unwrapped, so it turns the way it says). Between pieces it hovers.
struct Motion {
  double t0 = 0.0;
  double t1 = 0.0;
  Pose from;
  Pose to;
};

struct ExplorationResult {
  std::string map_name;
  std::vector<CoverageSample> coverage;
  std::vector<Motion> motions;
  PlannerStats planner;
  QueryTally insertions;            ///< frames inserted and the seconds it took
  std::uint64_t frames_dropped = 0;  ///< frames skipped because inserting lagged
  double planning_time = 0.0;        ///< simulated seconds spent planning (hovering)
  double flight_time = 0.0;          ///< simulated seconds flying
  double flight_distance = 0.0;      ///< metres
  bool finished = false;             ///< the planner found no gain left
  double end_time = 0.0;             ///< simulated time the run ended
  double wall_seconds = 0.0;         ///< real time the run took
  double reachable_m3 = 0.0;

  /// First time coverage reached `fraction` (linear between samples), or a negative number.
  [[nodiscard]] double time_to(double fraction) const;
};

/// Runs one exploration (see the file comment). `truth` must use cells of
/// the map's resolution. `progress`, if set, is called from the mapping
/// thread with every coverage sample. Throws std::invalid_argument for a bad
/// config, a start that is not free in `scene`, or mismatched cells.
ExplorationResult explore(ExplorationMap& map, const sim::Scene& scene, const sim::ReachableSpace& truth,
                          const Pose& start, const ExplorerConfig& config,
                          const std::function<void(const CoverageSample&)>& progress = {});

/// The robot's smallest distance to any surface of `scene` along its motions,
/// checked every `step` metres (and at every motion's ends).
double min_clearance(const ExplorationResult& result, const sim::Scene& scene, double step = 0.01);

}  // namespace umbra::explore
