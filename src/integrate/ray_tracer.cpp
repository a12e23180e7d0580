#include "umbra/integrate/ray_tracer.hpp"

#include <algorithm>

#include "umbra/core/radix_sort.hpp"

#include "umbra/integrate/integrator.hpp"
#include "umbra/integrate/ray_walker.hpp"

namespace umbra {

void RayTracer::start(int depth_levels) { batch_.reset(depth_levels); }

std::size_t RayTracer::memory_bytes() const {
  return batch_.memory_bytes() + runs_.capacity() * sizeof(BrickRun) + crossings_.capacity() * sizeof(NodeCrossing);
}

std::optional<RayTracer::Ray> RayTracer::prepare(const ScanContext& scan, Vec3f point, InsertStats* stats) const {
  auto count = [stats](std::size_t InsertStats::*field) {
    if (stats != nullptr) ++(stats->*field);
  };
  if (!point.is_finite()) {
    count(&InsertStats::non_finite);
    return std::nullopt;
  }
  const Grid& grid = *scan.grid;
  Ray ray{scan.origin, scan.origin_key, point, {}, true, false};
  const Vec3f offset = point - scan.origin;
  const double range = octomap_norm(offset);
  if (scan.max_range > 0.0 && range > scan.max_range) {
    // OctoMap: origin + normalized(direction) * (float)max_range, no hit.
    const auto length = static_cast<float>(range);
    const Vec3f direction = range > 0.0 ? Vec3f{offset.x / length, offset.y / length, offset.z / length} : offset;
    ray.end = scan.origin + direction * static_cast<float>(scan.max_range);
    ray.hit = false;
    count(&InsertStats::truncated);
  }
  const std::optional<Key> end_key = grid.key_checked(ray.end);
  if (!end_key) {
    count(&InsertStats::out_of_bounds);
    return std::nullopt;
  }
  ray.end_key = *end_key;
  if (scan.box) {
    const auto part = scan.box->clip(Vec3d(ray.begin), Vec3d(ray.end));
    if (!part) {
      count(&InsertStats::outside_box);
      return std::nullopt;
    }
    const Vec3d from(ray.begin);
    const Vec3d d = Vec3d(ray.end) - from;
    if (part->first > 0.0) {
      ray.begin = static_cast<Vec3f>(from + d * part->first);
      ray.begin_key = grid.key(Vec3d(ray.begin));
    }
    if (part->second < 1.0) {
      ray.end = static_cast<Vec3f>(from + d * part->second);
      ray.end_key = grid.key(Vec3d(ray.end));
      ray.hit = false;
      ray.miss_end = true;
    }
  }
  count(&InsertStats::rays);
  return ray;
}

void RayTracer::add_segment_misses(const ScanContext& scan, Vec3f from, Key from_key, Vec3f to, Key to_key) {
  // A walk takes at most one step per key along the way, plus at most one
  // overshoot per axis where rounding makes it miss the end voxel.
  std::size_t steps = 4;
  for (int axis = 0; axis < 3; ++axis) {
    steps += from_key[axis] > to_key[axis] ? from_key[axis] - to_key[axis] : to_key[axis] - from_key[axis];
  }
  if (runs_.size() < steps + 1) runs_.resize(steps + 1);
  // Append to the current run or start a new one, without a branch on which:
  // whether the brick changes is hard to predict (measured 17% faster than
  // handing over each run as soon as the walk leaves its brick).
  BrickRun* runs = runs_.data();
  runs[0] = {~std::uint64_t{0}, 0};  // no code lies in this brick
  std::size_t last = 0;
  auto collect = [&](std::uint64_t code) {
    const bool same_brick = ((code ^ runs[last].code) >> 6) == 0;
    last += same_brick ? 0 : 1;
    const std::uint64_t earlier = same_brick ? runs[last].voxels : 0;
    runs[last] = {code, earlier | (std::uint64_t{1} << (code & 63))};
  };
  if (scan.box_keys) {
    const KeyBox box = *scan.box_keys;
    walk_ray(*scan.grid, from, from_key, to, to_key, [&](std::uint64_t code) {
      if (box.contains(morton::decode(code))) collect(code);
    });
  } else {
    walk_ray(*scan.grid, from, from_key, to, to_key, collect);
  }
  for (std::size_t i = 1; i <= last; ++i) batch_.add_misses_in_brick(runs[i].code, runs[i].voxels);
}

void RayTracer::add_end(const ScanContext& scan, const Ray& ray) {
  if (scan.box_keys && !scan.box_keys->contains(ray.end_key)) return;
  if (ray.miss_end) batch_.add_miss(morton::encode(ray.end_key));
  if (ray.hit && !scan.hits_first) batch_.add_hit(morton::encode(ray.end_key));
}

void RayTracer::add_hits(const ScanContext& scan, std::span<const Vec3f> ends) {
  std::vector<std::uint64_t> coarse;  // the coarse nodes holding a hit
  const int depth = scan.clear_depth;
  for (const Vec3f& end : ends) {
    const std::optional<Ray> ray = prepare(scan, end, nullptr);
    if (!ray || !ray->hit || (scan.box_keys && !scan.box_keys->contains(ray->end_key))) continue;
    const std::uint64_t code = morton::encode(ray->end_key);
    batch_.add_hit(code);
    coarse.push_back(code >> (3 * depth));
  }
  if (depth == 0) return;
  // Coarse nodes next to a surface are not cleared whole either: a ray that
  // grazes a wall would otherwise clear wall voxels this scan did not hit,
  // and a later scan's hit there would not make them occupied (measured on
  // the procedural building at 5 cm: recall of the occupied voxels against
  // the simple integrator 97.0% -> 99.6%).
  radix_sort(coarse, 3 * (scan.grid->depth_levels() - depth), [](std::uint64_t c) { return c; });
  coarse.erase(std::unique(coarse.begin(), coarse.end()), coarse.end());
  const std::int64_t limit = std::int64_t{scan.grid->keys_per_axis()} >> depth;
  for (const std::uint64_t node : coarse) {
    const Key k = morton::decode(node);
    for (int dz = -1; dz <= 1; ++dz) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const std::int64_t x = std::int64_t{k.x} + dx;
          const std::int64_t y = std::int64_t{k.y} + dy;
          const std::int64_t z = std::int64_t{k.z} + dz;
          if (x < 0 || y < 0 || z < 0 || x >= limit || y >= limit || z >= limit) continue;
          const Key first{static_cast<std::uint32_t>(x << depth), static_cast<std::uint32_t>(y << depth),
                          static_cast<std::uint32_t>(z << depth)};
          batch_.keep_fine(morton::encode(first), depth);
        }
      }
    }
  }
}

void RayTracer::trace(const ScanContext& scan, std::span<const Vec3f> ends, InsertStats& stats) {
  std::optional<OccupancyTree::Cursor> cursor;
  if (scan.fast) cursor.emplace(*scan.tree);
  for (const Vec3f& point : ends) {
    const std::optional<Ray> ray = prepare(scan, point, &stats);
    if (!ray) continue;
    if (ray->hit) ++stats.hits;
    if (scan.fast) {
      trace_fast(scan, *ray, *cursor);
    } else {
      add_segment_misses(scan, ray->begin, ray->begin_key, ray->end, ray->end_key);
    }
    add_end(scan, *ray);
  }
}

void RayTracer::trace_fast(const ScanContext& scan, const Ray& ray, OccupancyTree::Cursor& cursor) {
  const Grid& grid = *scan.grid;
  const int depth = scan.clear_depth;
  crossings_.clear();
  walk_nodes(grid, depth, Vec3d(ray.begin), ray.begin_key, Vec3d(ray.end), ray.end_key,
             [this](const NodeCrossing& c) { crossings_.push_back(c); });
  const Vec3d begin(ray.begin);
  const Vec3d direction = Vec3d(ray.end) - begin;
  const double length = direction.norm();
  const Vec3d unit = length > 0.0 ? direction / length : direction;
  // Segment ends are nudged a hundredth of a voxel past a node's exit, so
  // that the voxel walk covers every voxel of the node along the ray.
  const double nudge = 0.01 * grid.resolution();
  const float occupied = scan.tree->thresholds().occupied;
  const std::size_t total = crossings_.size();
  const std::size_t fine = static_cast<std::size_t>(scan.fine_steps);
  const std::size_t coarse = scan.fine_steps == 0 ? total : (total > fine ? total - fine : 0);
  for (std::size_t i = 0; i < coarse; ++i) {
    const NodeCrossing& c = crossings_[i];
    bool whole = cursor.max_log_odds(c.code, depth) <= occupied;  // no obstacle the map knows of
    if (whole && scan.box_keys) {
      const Key first = morton::decode(c.code);
      const std::uint32_t last = (1u << depth) - 1;
      whole = scan.box_keys->contains(first) &&
              scan.box_keys->contains({first.x + last, first.y + last, first.z + last});
    }
    if (whole && batch_.add_miss_node_unless_hit(c.code, depth)) continue;
    // Voxel by voxel through this node.
    const Vec3f from = static_cast<Vec3f>(begin + unit * c.t_in);
    const Vec3f to = static_cast<Vec3f>(begin + unit * std::min(c.t_out + nudge, length));
    const std::optional<Key> from_key = grid.key_checked(from);
    const std::optional<Key> to_key = grid.key_checked(to);
    if (from_key && to_key) add_segment_misses(scan, from, *from_key, to, *to_key);
  }
  if (scan.fine_steps == 0) return;
  // The last nodes before the end, and the end node, voxel by voxel.
  const double t_start = coarse < total ? crossings_[coarse].t_in : 0.0;
  const Vec3f from = t_start > 0.0 ? static_cast<Vec3f>(begin + unit * t_start) : ray.begin;
  if (const std::optional<Key> from_key = grid.key_checked(from)) {
    add_segment_misses(scan, from, *from_key, ray.end, ray.end_key);
  }
}

}  // namespace umbra
