// OccupancyMap's query members: each holds the map for reading (MapAccess)
// and runs the algorithm of src/query on its tree. Checks of bad options
// that need no tree come first; a batch holds the map a chunk (is_free) or a
// pose (information_gain) at a time, so that a writer waits for one part,
// not for the whole batch.
#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "core/thread_pool.hpp"
#include "map/map_access.hpp"
#include "query/collision_check.hpp"
#include "query/gain_counter.hpp"
#include "query/projection.hpp"
#include "query/query_walk.hpp"
#include "query/ray_cast.hpp"
#include "umbra/map/occupancy_map.hpp"
#include "umbra/query/navigation_grid.hpp"

namespace umbra {
namespace {

void validate(const GainOptions& options, int depth_levels) {
  if (options.fast_depth < 0 || options.fast_depth > depth_levels) {
    throw std::invalid_argument("information gain: fast_depth must lie in [0, " + std::to_string(depth_levels) +
                                "], got " + std::to_string(options.fast_depth));
  }
}

/// One collision check, holding the map for reading.
template <CollisionShape Shape>
CollisionResult check_one(const OccupancyMap& map, const Grid& grid, const Shape& shape,
                          const CollisionOptions& options) {
  return detail::MapAccess::read(
      map, [&](const OccupancyTree& tree) { return detail::check_collision(tree, grid, shape, options); });
}

}  // namespace

// --- predicate queries ----------------------------------------------------------------

QueryRange OccupancyMap::query(const Predicate& predicate, int depth) const {
  return QueryRange(new detail::QueryWalk(detail::MapAccess::gate(*this), detail::MapAccess::tree_unlocked(*this),
                                          grid_, predicate, depth));
}

NearestRange OccupancyMap::query_nearest(Vec3d point, const Predicate& predicate, int depth,
                                         double max_distance) const {
  return NearestRange(new detail::NearestWalk(detail::MapAccess::gate(*this), detail::MapAccess::tree_unlocked(*this),
                                              grid_, point, predicate, depth, max_distance));
}

std::size_t OccupancyMap::count(const Predicate& predicate, int depth) const {
  return detail::QueryWalk(detail::MapAccess::gate(*this), detail::MapAccess::tree_unlocked(*this), grid_, predicate,
                           depth)
      .count_rest();
}

// --- collision checks and ray casts ------------------------------------------------------

CollisionResult OccupancyMap::is_free(const Aabb& box, const CollisionOptions& options) const {
  return check_one(*this, grid_, box, options);
}
CollisionResult OccupancyMap::is_free(const Sphere& sphere, const CollisionOptions& options) const {
  return check_one(*this, grid_, sphere, options);
}
CollisionResult OccupancyMap::is_free(const OrientedBox& box, const CollisionOptions& options) const {
  return check_one(*this, grid_, box, options);
}
CollisionResult OccupancyMap::is_free(const Capsule& capsule, const CollisionOptions& options) const {
  return check_one(*this, grid_, capsule, options);
}
CollisionResult OccupancyMap::is_free(const Segment& segment, const CollisionOptions& options) const {
  return check_one(*this, grid_, segment, options);
}

template <CollisionShape Shape>
void OccupancyMap::is_free(std::span<const Shape> shapes, std::span<std::uint8_t> free,
                           const CollisionOptions& options) const {
  if (free.size() != shapes.size()) {
    throw std::invalid_argument("is_free: " + std::to_string(shapes.size()) + " shapes but room for " +
                                std::to_string(free.size()) + " answers");
  }
  constexpr std::size_t kChunk = 256;
  for (std::size_t begin = 0; begin < shapes.size(); begin += kChunk) {
    const std::size_t end = std::min(shapes.size(), begin + kChunk);
    detail::MapAccess::read(*this, [&](const OccupancyTree& tree) {
      for (std::size_t i = begin; i < end; ++i) {
        free[i] = detail::check_collision(tree, grid_, shapes[i], options).free ? 1 : 0;
      }
    });
  }
}
// The shapes of CollisionShape, the only ones the header lets callers name.
template void OccupancyMap::is_free(std::span<const Aabb>, std::span<std::uint8_t>, const CollisionOptions&) const;
template void OccupancyMap::is_free(std::span<const Sphere>, std::span<std::uint8_t>, const CollisionOptions&) const;
template void OccupancyMap::is_free(std::span<const OrientedBox>, std::span<std::uint8_t>,
                                    const CollisionOptions&) const;
template void OccupancyMap::is_free(std::span<const Capsule>, std::span<std::uint8_t>, const CollisionOptions&) const;
template void OccupancyMap::is_free(std::span<const Segment>, std::span<std::uint8_t>, const CollisionOptions&) const;

RayHit OccupancyMap::cast_ray(Vec3d origin, Vec3d direction, const RayCastOptions& options) const {
  return detail::MapAccess::read(
      *this, [&](const OccupancyTree& tree) { return detail::cast_ray(tree, grid_, origin, direction, options); });
}

bool OccupancyMap::cast_ray_octomap(Vec3f origin, Vec3f direction, Vec3f& end, bool ignore_unknown,
                                    double max_range) const {
  return detail::MapAccess::read(*this, [&](const OccupancyTree& tree) {
    return detail::cast_ray_octomap(tree, grid_, origin, direction, end, ignore_unknown, max_range);
  });
}

// --- information gain ------------------------------------------------------------------

GainResult OccupancyMap::information_gain(const Frustum& frustum, const GainOptions& options) const {
  frustum.validate();
  validate(options, depth_levels());
  detail::GainCounter counter(grid());
  return detail::MapAccess::read(*this, [&](const OccupancyTree& tree) { return counter.count(tree, frustum, options); });
}

std::vector<GainResult> OccupancyMap::information_gain(std::span<const Frustum> frustums,
                                                       const GainOptions& options) const {
  validate(options, depth_levels());
  for (const Frustum& frustum : frustums) frustum.validate();
  std::vector<GainResult> results(frustums.size());
  const unsigned threads = std::min<std::size_t>(options.threads == 0 ? ThreadPool::hardware_threads() : options.threads,
                                                 std::max<std::size_t>(frustums.size(), 1));
  // One counter (image and buffers) per thread; the map is held per pose.
  std::vector<detail::GainCounter> counters;
  counters.reserve(threads);
  for (unsigned t = 0; t < threads; ++t) counters.emplace_back(grid());
  auto answer = [&](std::size_t i, unsigned worker) {
    results[i] = detail::MapAccess::read(
        *this, [&](const OccupancyTree& tree) { return counters[worker].count(tree, frustums[i], options); });
  };
  if (threads <= 1) {
    for (std::size_t i = 0; i < frustums.size(); ++i) answer(i, 0);
  } else {
    ThreadPool pool(threads);
    pool.run(frustums.size(), answer);
  }
  return results;
}

// --- the navigation grid ----------------------------------------------------------------

NavigationGrid project_to_grid(const OccupancyMap& map, const ProjectionOptions& options) {
  return detail::MapAccess::read(
      map, [&](const OccupancyTree& tree) { return detail::project_tree_to_grid(tree, map.grid(), options); });
}

}  // namespace umbra
