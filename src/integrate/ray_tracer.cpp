#include "integrate/ray_tracer.hpp"

#include <algorithm>
#include <cmath>

#include "core/radix_sort.hpp"

#include "integrate/integrator.hpp"
#include "ray/voxel_walk.hpp"

namespace umbra {

void RayTracer::start(int depth_levels) {
  batch_.reset(depth_levels);
  std::fill(decisions_.begin(), decisions_.end(), NodeDecision{~std::uint64_t{0}, -1, false});
}

std::size_t RayTracer::memory_bytes() const {
  return batch_.memory_bytes() + crossings_.capacity() * sizeof(NodeCrossing) +
         decisions_.capacity() * sizeof(NodeDecision) + tail_.capacity() * sizeof(std::uint64_t);
}

bool prepare_ray(const ScanContext& scan, Vec3f point, InsertStats* stats, PreparedRay& ray) {
  auto count = [stats](std::size_t InsertStats::*field) {
    if (stats != nullptr) ++(stats->*field);
  };
  if (!point.is_finite()) {
    count(&InsertStats::non_finite);
    return false;
  }
  const Grid& grid = *scan.grid;
  // Field by field into the caller's ray, and the end key axis by axis: a
  // PreparedRay or std::optional<Key> built in a local and copied was read
  // back with 16-byte loads of fields just stored one by one, which the CPU
  // cannot forward from its store buffer (perf: those loads were half of
  // this function's time, 2% of a TUM frame at 2 cm).
  ray.begin = scan.origin;
  ray.begin_key = scan.origin_key;
  ray.end = point;
  ray.hit = true;
  ray.miss_end = false;
  const Vec3f offset = point - scan.origin;
  const double range = octomap_norm(offset);
  if (scan.max_range > 0.0 && range > scan.max_range) {
    // OctoMap: origin + normalized(direction) * (float)max_range, no hit
    // (range > max_range > 0 here: the division is by a positive length).
    // Except for a point so far away (beyond about 1.8e19 m) that the float
    // squared length overflows: OctoMap's normalized() divides by infinity,
    // gets a zero direction and updates nothing; here the direction comes
    // from double, and the ray is cut at max_range like any other.
    const auto length = static_cast<float>(range);
    Vec3f direction{offset.x / length, offset.y / length, offset.z / length};
    if (!std::isfinite(range)) {
      const Vec3d exact = Vec3d(point) - Vec3d(scan.origin);
      direction = Vec3f(exact / exact.norm());
    }
    ray.end = scan.origin + direction * static_cast<float>(scan.max_range);
    ray.hit = false;
    count(&InsertStats::truncated);
  }
  for (int axis = 0; axis < 3; ++axis) {
    const std::optional<std::uint32_t> key = grid.axis_key(ray.end[static_cast<std::size_t>(axis)]);
    if (!key) {
      count(&InsertStats::out_of_bounds);
      return false;
    }
    ray.end_key[axis] = *key;
  }
  if (scan.box) {
    const auto part = scan.box->clip(Vec3d(ray.begin), Vec3d(ray.end));
    if (!part) {
      count(&InsertStats::outside_box);
      return false;
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
  ray.end_code = morton::encode(ray.end_key);
  count(&InsertStats::rays);
  return true;
}

namespace {

/// The voxels of the brick (4x4x4 voxels from `brick`) inside the box, as a
/// brick mask (bit i: the voxel brick + i).
std::uint64_t voxels_in_box(const KeyBox& box, std::uint64_t brick) {
  const Key low = morton::decode(brick);
  const Key high{low.x + 3, low.y + 3, low.z + 3};
  if (box.contains(low) && box.contains(high)) return ~std::uint64_t{0};
  std::uint64_t mask = 0;
  for (unsigned i = 0; i < 64; ++i) mask |= std::uint64_t{box.contains(morton::decode(brick + i))} << i;
  return mask;
}

}  // namespace

template <typename Walk>
void RayTracer::add_walk_misses(const ScanContext& scan, Walk&& walk) {
  if (scan.box_keys) {
    const KeyBox box = *scan.box_keys;
    walk([&](std::uint64_t brick, std::uint64_t voxels) {
      voxels &= voxels_in_box(box, brick);
      if (voxels != 0) batch_.add_misses_in_brick(brick, voxels);
    });
  } else {
    walk([&](std::uint64_t brick, std::uint64_t voxels) { batch_.add_misses_in_brick(brick, voxels); });
  }
}

void RayTracer::add_segment_misses(const ScanContext& scan, Vec3f from, Key from_key, Vec3f to, Key to_key) {
  add_walk_misses(scan, [&](auto&& run) { walk_ray_runs(*scan.grid, from, from_key, to, to_key, run); });
}

void RayTracer::add_end(const ScanContext& scan, const PreparedRay& ray) {
  if (scan.box_keys && !scan.box_keys->contains(ray.end_key)) return;
  if (ray.miss_end) batch_.add_miss(ray.end_code);
  if (ray.hit && !scan.hits_first) batch_.add_hit(ray.end_code);
}

void RayTracer::add_hits(const ScanContext& scan, std::span<const std::vector<std::uint64_t>> hit_parts) {
  std::vector<std::uint64_t> hits;  // the finest voxels holding a hit
  for (const std::vector<std::uint64_t>& part : hit_parts) hits.insert(hits.end(), part.begin(), part.end());
  for (const std::uint64_t code : hits) batch_.add_hit(code);
  if (scan.clear_depth == 0) return;
  // Coarse nodes next to a surface are not cleared whole either: a ray that
  // grazes a wall would otherwise clear wall voxels this scan did not hit,
  // and a later scan's hit there would not make them occupied (measured on
  // the procedural building at 5 cm: recall of the occupied voxels against
  // the simple integrator 97.0% -> 99.6%).
  keep_neighbours(scan, hits, scan.clear_depth, scan.clear_depth);
  // The same one level down for the nodes split below the clear depth; their
  // ancestors are kept too, so that a split node is never cleared whole over
  // a kept child.
  if (scan.walk_depth < scan.clear_depth) keep_neighbours(scan, hits, scan.walk_depth, scan.clear_depth - 1);
}

void RayTracer::keep_neighbours(const ScanContext& scan, std::span<const std::uint64_t> hits, int depth, int up_to) {
  std::vector<std::uint64_t> nodes;  // the depth-`depth` nodes holding a hit
  nodes.reserve(hits.size());
  for (const std::uint64_t code : hits) nodes.push_back(code >> (3 * depth));
  radix_sort(nodes, 3 * (scan.grid->depth_levels() - depth), [](std::uint64_t c) { return c; });
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  const std::int64_t limit = std::int64_t{scan.grid->keys_per_axis()} >> depth;
  for (const std::uint64_t node : nodes) {
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
          batch_.keep_fine(morton::encode(first), depth, up_to);
        }
      }
    }
  }
}

void RayTracer::trace(const ScanContext& scan, std::span<const Vec3f> ends, InsertStats& stats) {
  for (const Vec3f& point : ends) {
    PreparedRay ray;
    if (!prepare_ray(scan, point, &stats, ray)) continue;
    if (ray.hit) ++stats.hits;
    add_segment_misses(scan, ray.begin, ray.begin_key, ray.end, ray.end_key);
    add_end(scan, ray);
  }
}

bool RayTracer::clear_node_whole(const ScanContext& scan, std::uint64_t code, int depth,
                                 OccupancyTree::Cursor& cursor) {
  NodeDecision& decision = decisions_[((code >> (3 * depth)) ^ (std::uint64_t(depth) << 9)) & (kDecisions - 1)];
  if (decision.code == code && decision.depth == depth) return decision.cleared;
  decision.code = code;
  decision.depth = depth;
  decision.cleared = false;
  if (cursor.max_log_odds(code, depth) > scan.tree->thresholds().occupied) return false;  // a known obstacle
  if (scan.box_keys) {
    const Key first = morton::decode(code);
    const std::uint32_t last = (1u << depth) - 1;
    if (!scan.box_keys->contains(first) || !scan.box_keys->contains({first.x + last, first.y + last, first.z + last})) {
      return false;
    }
  }
  decision.cleared = batch_.add_miss_node_unless_hit(code, depth);  // refuses nodes that hold or touch a hit
  return decision.cleared;
}

namespace {

/// Node index along one axis at depth `depth` of a coordinate, clamped to the map.
std::uint32_t node_index(const Grid& grid, double coordinate, int depth) {
  const double key = std::floor(coordinate / grid.resolution()) + double(grid.key_offset());
  const double clamped = std::clamp(key, 0.0, double(grid.keys_per_axis() - 1));
  return static_cast<std::uint32_t>(clamped) >> depth;
}

}  // namespace

void RayTracer::trace_group(const ScanContext& scan, std::span<const PreparedRay> rays,
                            OccupancyTree::Cursor& cursor) {
  if (rays.empty()) return;
  const Grid& grid = *scan.grid;
  const int depth = scan.clear_depth;
  const std::size_t fine = static_cast<std::size_t>(scan.fine_steps);

  // The guide is the group's middle ray. At a fraction s of their lengths,
  // all rays of the group lie within (1 - s) begin_spread + s end_spread of
  // the guide's point (begins differ only when a box clips them).
  const PreparedRay& guide = rays[rays.size() / 2];
  const Vec3d guide_begin(guide.begin);
  const Vec3d guide_end(guide.end);
  double begin_spread = 0.0;
  double end_spread = 0.0;
  for (const PreparedRay& ray : rays) {
    begin_spread = std::max(begin_spread, (Vec3d(ray.begin) - guide_begin).norm());
    end_spread = std::max(end_spread, (Vec3d(ray.end) - guide_end).norm());
  }
  // Walking the guide, every node the group's rays may cross along each of
  // its nodes (a box around the guide's segment, widened by the spread) is
  // cleared whole, until one of them may not be (it holds an obstacle or a
  // hit, is next to one, or is one of the last `fine`): from there on every
  // ray goes by itself, so that every ray crosses nodes it may not clear
  // itself, voxel by voxel, as the exact integrators do.
  crossings_.clear();
  walk_nodes(grid, depth, guide_begin, guide.begin_key, guide_end, guide.end_key,
             [this](const NodeCrossing& c) { crossings_.push_back(c); });
  const std::size_t guide_coarse = crossings_.size() > fine ? crossings_.size() - fine : 0;
  const Vec3d guide_direction = guide_end - guide_begin;
  const double guide_length = guide_direction.norm();
  double stop_share = 0.0;  // the fraction of their lengths where the rays go on by themselves
  for (std::size_t i = 0; i < guide_coarse; ++i) {
    const double s_in = crossings_[i].t_in / guide_length;
    const double s_out = crossings_[i].t_out / guide_length;
    // (Less a millionth of a voxel: the guide's own entry and exit points lie
    // on the faces of its node, and rounding must not add the neighbours.)
    const double spread = std::max((1.0 - s_in) * begin_spread + s_in * end_spread,
                                   (1.0 - s_out) * begin_spread + s_out * end_spread) -
                          1e-6 * grid.resolution();
    const Vec3d a = guide_begin + guide_direction * s_in;
    const Vec3d b = guide_begin + guide_direction * s_out;
    std::uint32_t low[3];
    std::uint32_t high[3];
    for (int axis = 0; axis < 3; ++axis) {
      low[axis] = node_index(grid, std::min(a[axis], b[axis]) - spread, depth);
      high[axis] = node_index(grid, std::max(a[axis], b[axis]) + spread, depth);
      // A group of rays that runs along a node border (one ray along a face,
      // such as x = 0 from a sensor at x = 0): the shrinking put low above
      // high, and the empty box counted as cleared, so that nothing was
      // cleared along the whole ray. Such rays lie in the node their
      // coordinate rounds into, as in the voxel walk. (A crossing shorter
      // than the shrinking, where the guide only grazes a node's edge or
      // corner, still clears nothing: which side the voxel walk takes
      // there is rounding.)
      if (low[axis] > high[axis] && s_out - s_in > 2e-6 * grid.resolution() / guide_length) {
        low[axis] = high[axis] = node_index(grid, 0.5 * (a[axis] + b[axis]), depth);
      }
    }
    bool all_cleared = true;
    for (std::uint32_t z = low[2]; z <= high[2] && all_cleared; ++z) {
      for (std::uint32_t y = low[1]; y <= high[1] && all_cleared; ++y) {
        for (std::uint32_t x = low[0]; x <= high[0] && all_cleared; ++x) {
          all_cleared =
              clear_node_whole(scan, morton::encode({x << depth, y << depth, z << depth}), depth, cursor);
        }
      }
    }
    if (!all_cleared) break;
    stop_share = s_out;
  }
  for (const PreparedRay& ray : rays) {
    if (stop_share == 0.0) {
      trace_rest(scan, ray, ray.begin, ray.begin_key, cursor);
    } else {
      const Vec3d begin(ray.begin);
      const Vec3f from = static_cast<Vec3f>(begin + (Vec3d(ray.end) - begin) * stop_share);
      if (const std::optional<Key> from_key = grid.key_checked(from)) trace_rest(scan, ray, from, *from_key, cursor);
    }
    add_end(scan, ray);
  }
}

void RayTracer::trace_rest(const ScanContext& scan, const PreparedRay& ray, Vec3f from, Key from_key,
                           OccupancyTree::Cursor& cursor) {
  const Grid& grid = *scan.grid;
  const int depth = scan.clear_depth;
  // The end node and the `fine_steps` nodes before it (nodes of walk_depth)
  // are traced voxel by voxel whatever they hold: found walking back from the end.
  const int tail_depth = scan.walk_depth;
  const std::size_t tail = static_cast<std::size_t>(scan.fine_steps) + 1;
  tail_.clear();
  tail_.push_back(morton::node_begin(ray.end_code, tail_depth));
  bool whole_ray_in_tail = morton::node_begin(morton::encode(from_key), tail_depth) == tail_.front();
  if (tail > 1 && !whole_ray_in_tail) {
    walk_nodes(grid, tail_depth, Vec3d(ray.end), ray.end_key, Vec3d(from), from_key, [&](const NodeCrossing& c) {
      if (tail_.size() < tail + 1) tail_.push_back(c.code);
    });
    // walk_nodes gives the end node too, and stops before the node of `from`.
    whole_ray_in_tail = tail_.size() < tail + 1;
  }
  if (whole_ray_in_tail) {
    add_segment_misses(scan, from, from_key, ray.end, ray.end_key);
    return;
  }
  if (tail_depth == depth) {
    const auto skip = [&](std::uint64_t node) {
      return std::find(tail_.begin(), tail_.end(), node) == tail_.end() && clear_node_whole(scan, node, depth, cursor);
    };
    add_walk_misses(scan, [&](auto&& run) {
      walk_ray_skipping(grid, depth, from, from_key, ray.end, ray.end_key, skip, run);
    });
    return;
  }
  // Node by node, splitting the nodes that may not be cleared whole (those
  // holding a tail node among them) down to walk_depth.
  end_code_ = ray.end_code;
  end_ = ray.end;
  const Vec3d begin(from);
  const Vec3d direction = Vec3d(ray.end) - begin;
  const double length = direction.norm();
  const auto at = [&](double t) { return begin + direction * (t / length); };
  double last_out = 0.0;
  walk_nodes(grid, depth, begin, from_key, Vec3d(ray.end), ray.end_key, [&](const NodeCrossing& c) {
    if (holds_tail(c.code, depth) || !clear_node_whole(scan, c.code, depth, cursor)) {
      split_node(scan, c.code, depth, at(c.t_in), at(c.t_out), cursor);
    }
    last_out = c.t_out;
  });
  split_node(scan, morton::node_begin(ray.end_code, depth), depth, at(last_out), Vec3d(ray.end), cursor);
}

bool RayTracer::holds_tail(std::uint64_t code, int depth) const {
  return std::any_of(tail_.begin(), tail_.end(), [&](std::uint64_t t) { return morton::node_begin(t, depth) == code; });
}

namespace {

/// The finest key of `p`, moved into the depth-`depth` node whose first
/// voxel is `node` (rounding at a node's faces can put a point into the
/// neighbour). Inline: Grid::key, out of line and checked, was 12% of a
/// 2 mm frame.
Key key_in_node(const Grid& grid, Vec3d p, Key node, int depth) {
  const std::uint32_t last = (1u << depth) - 1;
  Key key = node;
  for (int axis = 0; axis < 3; ++axis) {
    if (const std::optional<std::uint32_t> k = grid.axis_key(p[axis])) {
      key[axis] = std::clamp(*k, node[axis], node[axis] + last);
    }
  }
  return key;
}

}  // namespace

void RayTracer::split_node(const ScanContext& scan, std::uint64_t code, int depth, Vec3d a, Vec3d b,
                           OccupancyTree::Cursor& cursor) {
  const Grid& grid = *scan.grid;
  const Key node = morton::decode(code);
  const Key a_key = key_in_node(grid, a, node, depth);
  if (depth <= scan.walk_depth) {
    if (code == morton::node_begin(end_code_, depth)) {  // up to, not including, the end voxel
      const Key end_key = morton::decode(end_code_);
      if (a_key != end_key) add_segment_misses(scan, static_cast<Vec3f>(a), a_key, end_, end_key);
      return;
    }
    const Key b_key = key_in_node(grid, b, node, depth);
    if (a_key != b_key) add_segment_misses(scan, static_cast<Vec3f>(a), a_key, static_cast<Vec3f>(b), b_key);
    if (!scan.box_keys || scan.box_keys->contains(b_key)) batch_.add_miss(morton::encode(b_key));
    return;
  }
  const Key b_key = key_in_node(grid, b, node, depth);
  const int child_depth = depth - 1;
  const Vec3d direction = b - a;
  const double length = direction.norm();
  const auto at = [&](double t) { return length > 0.0 ? a + direction * (t / length) : a; };
  const auto child = [&](std::uint64_t child_code, double t_in, double t_out) {
    if (holds_tail(child_code, child_depth) || !clear_node_whole(scan, child_code, child_depth, cursor)) {
      split_node(scan, child_code, child_depth, at(t_in), at(t_out), cursor);
    }
  };
  double last_out = 0.0;
  walk_nodes(grid, child_depth, a, a_key, b, b_key, [&](const NodeCrossing& c) {
    child(c.code, c.t_in, c.t_out);
    last_out = c.t_out;
  });
  child(morton::node_begin(morton::encode(b_key), child_depth), last_out, length);
}

}  // namespace umbra
