// walk_nodes: the nodes of one depth that a ray crosses, with where it
// enters and leaves each.
//
// A 3D DDA (Amanatides & Woo) on the grid of depth-`depth` nodes (edge
// resolution * 2^depth), in double precision, used by the fast integrator to
// clear free space a coarse node at a time. Unlike walk_ray it makes no
// attempt to round as OctoMap does: the fast integrator has no OctoMap
// counterpart. Cost: a few additions and compares per node.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

#include "umbra/core/grid.hpp"
#include "umbra/core/morton.hpp"
#include "umbra/core/vec3.hpp"

namespace umbra {

/// One node a ray crosses: the code of its first finest voxel, and the
/// distances from the ray's origin (metres) at which the ray enters and leaves it.
struct NodeCrossing {
  std::uint64_t code;
  double t_in;
  double t_out;
};

/// Calls visit(NodeCrossing) for the depth-`depth` nodes from the node of
/// `origin` up to, not including, the node of `end` (both inside the map,
/// with finest keys `origin_key` and `end_key`).
template <typename Visit>
void walk_nodes(const Grid& grid, int depth, Vec3d origin, Key origin_key, Vec3d end, Key end_key, Visit&& visit) {
  std::int64_t node[3];
  std::int64_t end_node[3];
  for (int axis = 0; axis < 3; ++axis) {
    node[axis] = origin_key[axis] >> depth;
    end_node[axis] = end_key[axis] >> depth;
  }
  if (node[0] == end_node[0] && node[1] == end_node[1] && node[2] == end_node[2]) return;

  const Vec3d d = end - origin;
  const double length = d.norm();
  const double size = grid.node_size(depth);
  const std::int64_t limit = std::int64_t{grid.keys_per_axis()} >> depth;
  double t_max[3];
  double t_delta[3];
  int step[3];
  for (int axis = 0; axis < 3; ++axis) {
    const double u = d[axis] / length;
    step[axis] = u > 0.0 ? 1 : (u < 0.0 ? -1 : 0);
    if (step[axis] == 0) {
      t_max[axis] = std::numeric_limits<double>::infinity();
      t_delta[axis] = std::numeric_limits<double>::infinity();
      continue;
    }
    // The border the ray leaves the current node through, in metres.
    const std::int64_t border_node = node[axis] + (step[axis] > 0 ? 1 : 0);
    const double border = static_cast<double>((border_node << depth) - std::int64_t{grid.key_offset()}) *
                          grid.resolution();
    t_max[axis] = (border - origin[axis]) / u;
    t_delta[axis] = size / std::fabs(u);
  }
  double t_in = 0.0;
  for (;;) {
    const int axis = t_max[0] < t_max[1] ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
    const double t_out = std::min(t_max[axis], length);
    const Key first{static_cast<std::uint32_t>(node[0] << depth), static_cast<std::uint32_t>(node[1] << depth),
                    static_cast<std::uint32_t>(node[2] << depth)};
    visit(NodeCrossing{morton::encode(first), t_in, t_out});
    node[axis] += step[axis];
    if (node[0] == end_node[0] && node[1] == end_node[1] && node[2] == end_node[2]) return;
    // Rounding can carry the walk past the end node: stop at the ray's end
    // or the map's edge.
    if (t_max[axis] >= length || node[axis] < 0 || node[axis] >= limit) return;
    t_in = t_max[axis];
    t_max[axis] += t_delta[axis];
  }
}

}  // namespace umbra
