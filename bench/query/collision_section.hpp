// The collision sections of the query benchmark: sphere checks and segment
// checks, umbra against liboctomap as its users write them, on the same map
// and the same shapes, every answer compared.
//
// Spheres (a planner's robot-sized ball at RRT nodes): centres uniform in
// the free voxels. umbra: the batch is_free(span<const Sphere>). OctoMap,
// unknown blocking: every voxel key of the sphere's bounding box whose cube
// meets the ball, search() each, blocked by an occupied or unknown one (the
// first ends the check). OctoMap, occupied only: begin_leafs_bbx over the
// ball's box, blocked by an occupied leaf whose cube meets the ball.
// Segments: both ends uniform in the free voxels (cut to `max_length` when
// it is > 0, as RRT edges are). umbra: is_free(span<const Segment>), unknown blocking.
// OctoMap: computeRayKeys(a, b) plus b's key, search() each.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "datasets.hpp"

namespace umbra_bench {

struct CollisionRow {
  std::string dataset;
  std::string what;              // "sphere r=0.25, unknown blocks", ...
  std::size_t checks = 0;        // umbra's, timed
  double umbra_us = 0.0;         // per check
  double blocked_share = 0.0;    // of umbra's checks
  std::size_t octomap_checks = 0;  // the first ones, timed with OctoMap
  double octomap_us = 0.0;         // per check
  double umbra_us_on_octomap_checks = 0.0;
  std::size_t mismatches = 0;  // answers that differ on the checks both made
};

struct CollisionSettings {
  std::size_t checks = 1'000'000;
  std::size_t octomap_checks = 10'000;
  double radius = 0.25;      // spheres
  double max_length = 0.0;   // segments: > 0 cuts them to that length
  int repeat = 3;
  std::uint64_t seed = 1;
};

/// Both sphere rows (unknown blocks; occupied only) for one dataset.
std::vector<CollisionRow> run_sphere_checks(const Dataset& data, const CollisionSettings& settings);
CollisionRow run_segment_checks(const Dataset& data, const CollisionSettings& settings);
std::string collision_table(const std::vector<CollisionRow>& rows);

}  // namespace umbra_bench
