#include "integrate/projective_tracer.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

#include "core/assert.hpp"
#include "integrate/centre_box.hpp"
#include "umbra/core/morton.hpp"

namespace umbra {

namespace {

constexpr double kRelativeError = kProjectiveRelativeError;

}  // namespace

ProjectiveTracer::ProjectiveTracer(const ProjectiveRule& rule) : rule_(rule) {
  if (rule.tree != nullptr) cursor_.emplace(*rule.tree);
  const ProjectiveFrame& frame = *rule.frame;
  const auto axis = [&](std::size_t row) {
    return Vec3d{frame.rotation[row][0], frame.rotation[row][1], frame.rotation[row][2]};
  };
  const Vec3d x = axis(0);
  const Vec3d y = axis(1);
  const Vec3d z = axis(2);
  const double u_offset = frame.cx + 0.5;  // u = fx x / z + u_offset, as the rule's
  const double v_offset = frame.cy + 0.5;
  // In the camera frame u >= -edge / z is fx x + u_offset z + edge >= 0, and
  // u < width + edge / z is -(fx x + (u_offset - width) z) + edge > 0; v likewise.
  side_planes_ = {x * frame.fx + z * u_offset, (x * frame.fx + z * (u_offset - frame.width)) * -1.0,
                  y * frame.fy + z * v_offset, (y * frame.fy + z * (v_offset - frame.height)) * -1.0};
  side_planes_scale_ = frame.fx + frame.fy + std::abs(u_offset) + std::abs(u_offset - frame.width) +
                       std::abs(v_offset) + std::abs(v_offset - frame.height);
}

bool ProjectiveTracer::outside_image_sides(Vec3d lo, double span, double far, double pad) const {
  // A plane's linear function over the box of centres is largest at the
  // box's middle plus |normal| . half the span; a centre off by `pad`
  // metres and the rule's float rounding move it by at most plane_pad (the
  // bound of outside_planes in classify_node, whose corner coordinates are
  // bounded here by the farthest centre's distance). A voxel whose centre
  // lies beyond the edge reach outside a side is not seen
  // (projective_frame.hpp), whatever its window.
  const double half = 0.5 * span;
  const Vec3d middle = Vec3d{lo.x + half, lo.y + half, lo.z + half} - rule_.frame->origin;
  const double edge = rule_.edge_reach * (1.0 + kRelativeError);
  const double plane_pad = 1e-5 * (side_planes_scale_ * far + edge) + side_planes_scale_ * pad + 1e-9;
  for (const Vec3d& plane : side_planes_) {
    const double largest = plane.dot(middle) + (std::abs(plane.x) + std::abs(plane.y) + std::abs(plane.z)) * half;
    if (largest + edge < -plane_pad) return true;
  }
  return false;
}

ProjectiveTracer::Decision ProjectiveTracer::classify(std::uint64_t code, int depth) const {
  return classify_node(morton::decode(code), depth);
}

ProjectiveTracer::Decision ProjectiveTracer::classify_node(Key first, int depth, bool* all_in_range) const {
  UMBRA_ASSERT(depth >= 2);
  const Grid& grid = *rule_.grid;
  const ProjectiveFrame& frame = *rule_.frame;
  const std::uint32_t n = std::uint32_t{1} << depth;  // voxels per edge
  bool contained = true;  // in the box
  if (rule_.box_keys) {
    const KeyBox& box = *rule_.box_keys;
    for (std::size_t a = 0; a < 3; ++a) {
      const std::uint32_t lo = first[a];
      const std::uint32_t hi = lo + (n - 1);
      if (hi < box.min[a] || lo > box.max[a]) return Decision::none;
      if (lo < box.min[a] || hi > box.max[a]) contained = false;
    }
  }
  // The box of the node's voxel centres, in the map frame.
  const double res = grid.resolution();
  const double span = (n - 1) * res;
  const Vec3d lo{grid.axis_center(first.x), grid.axis_center(first.y), grid.axis_center(first.z)};
  const ProjectiveRule::CentreDistances distances = rule_.centre_distances(first, depth);
  const double far = std::sqrt(distances.farthest_squared);
  const double pad = kRelativeError * (1.0 + far);  // metres the float rule may differ by
  bool within_range = true;
  if (rule_.max_range > 0.0) {
    if (rule_.range_depth == 0) {
      // Voxel by voxel, in float.
      if (std::sqrt(distances.nearest_squared) - pad > rule_.max_range) return Decision::none;
      within_range = far + pad <= rule_.max_range;
    } else if (depth <= rule_.range_depth) {
      // Per depth-range_depth node (projective_frame.hpp): exactly at that
      // depth and below.
      if (!rule_.within_range(first)) return Decision::none;
    } else {
      // Above it, with a little slack: the nodes it holds are no farther
      // and no nearer.
      const double limit = rule_.max_range * rule_.max_range;
      if (distances.nearest_squared > limit * (1.0 + 1e-9)) return Decision::none;
      within_range = distances.farthest_squared * (1.0 + 1e-9) <= limit;
    }
  }
  if (all_in_range != nullptr) *all_in_range = within_range;
  // Beyond the edge reach outside a side of the image: no voxel is seen.
  // Asked before the node's corners are projected (sixteen divisions): a
  // scan's walks test many nodes beside their images (a node beside one
  // image lies in the next), most of the node tests of the 3DTK scans.
  if (outside_image_sides(lo, span, far, pad)) return Decision::none;

  // The eight corners of that box in the camera frame.
  const CentreBox box(frame, lo, span);
  const std::array<Vec3d, 8>& corners = box.corners;
  const double z_min = box.z_min;
  const double z_max = box.z_max;
  if (z_max + pad <= 0.0) return Decision::none;  // behind the camera: not seen
  const double fx = frame.fx;
  const double fy = frame.fy;
  const double u_offset = frame.cx + 0.5;
  const double v_offset = frame.cy + 0.5;
  const double width = frame.width;
  const double height = frame.height;
  // The four planes through the camera and the image's edges, moved out by
  // the farthest a window reaches (the top level's) and by the edge reach:
  // whether the node lies wholly outside one of them (then it is not seen).
  // Asked where the projections below are unstable: across or near the
  // camera plane, where a pad over a tiny depth covers the whole image (a
  // camera whose image plane lay on a face of the map's largest nodes split
  // every node along that plane down to bricks, minutes for one image).
  // Asked of every node it cost 5% of the walk.
  const auto outside_planes = [&] {
    const double reach = 1.5 * DepthPyramid::cell_pixels(rule_.top_level) + 1.0;
    const double left_offset = u_offset + reach;
    const double right_offset = u_offset - width - reach;
    const double top_offset = v_offset + reach;
    const double bottom_offset = v_offset - height - reach;
    double left = -1e300;    // max of fx x + (cx + 1/2 + reach) z: >= 0 inside
    double right = -1e300;   // max of -(fx x + (cx + 1/2 - width - reach) z): > 0 inside
    double top = -1e300;
    double bottom = -1e300;
    double scale = 0.0;
    for (const Vec3d& c : corners) {
      left = std::max(left, fx * c.x + left_offset * c.z);
      right = std::max(right, -(fx * c.x + right_offset * c.z));
      top = std::max(top, fy * c.y + top_offset * c.z);
      bottom = std::max(bottom, -(fy * c.y + bottom_offset * c.z));
      scale = std::max(scale, std::abs(fx * c.x) + std::abs(fy * c.y) +
                                  (std::abs(left_offset) + std::abs(right_offset) + std::abs(top_offset) +
                                   std::abs(bottom_offset)) * std::abs(c.z));
    }
    // A centre within the edge reach, edge_reach / z pixels outside, counts
    // as inside: u >= -edge_reach / z is fx x + (cx + 1/2) z + edge_reach >= 0.
    const double edge = rule_.edge_reach * (1.0 + kRelativeError);
    // Float rounding (relative to the terms) and coordinates off by `pad`.
    const double plane_pad = 1e-5 * (scale + edge) +
                             (fx + fy + std::abs(left_offset) + std::abs(right_offset) + std::abs(top_offset) +
                              std::abs(bottom_offset)) * pad + 1e-9;
    return left + edge < -plane_pad || right + edge < -plane_pad || top + edge < -plane_pad ||
           bottom + edge < -plane_pad;
  };
  if (z_min - pad <= 0.0) return outside_planes() ? Decision::none : Decision::split;

  // In front of the camera: the pixels the voxel centres can project onto.
  const double near = z_min - pad;
  const CentreBox::Pixels pixels = box.pixels(frame, pad);
  const double u_min = pixels.u_min;
  const double u_max = pixels.u_max;
  const double v_min = pixels.v_min;
  const double v_max = pixels.v_max;
  const double u_pad = pixels.u_pad;
  const double v_pad = pixels.v_pad;
  if ((u_pad > 1.0 || v_pad > 1.0) && outside_planes()) return Decision::none;
  const double u0 = std::floor(u_min - u_pad);
  const double u1 = std::floor(u_max + u_pad);
  const double v0 = std::floor(v_min - v_pad);
  const double v1 = std::floor(v_max + v_pad);
  // The voxels' windows (projective_frame.hpp) reach beyond their own
  // pixels by at most 1.5 cells of their level plus a pixel; the nearest
  // bricks have the largest level.
  // Cells (projective_frame.hpp) are voxels 2^c times as wide: their
  // windows reach as far as those of the widest level's.
  const double cell_scale = DepthPyramid::cell_pixels(static_cast<int>(rule_.cells.size()));
  const double w = rule_.half_voxel_pixels * cell_scale * (1.0 + kRelativeError) / near;
  const int level = w < 1.0 ? 0
                            : std::min(static_cast<int>(std::bit_width(static_cast<unsigned>(std::min(w, 1048576.0)))),
                                       rule_.top_level);
  // Centres within the edge reach outside the image read its edge (clamped).
  const double edge = rule_.edge_reach * (1.0 + kRelativeError) / near + 1.0;
  const double window_reach = level == 0 ? 0.0 : 1.5 * DepthPyramid::cell_pixels(level) + 1.0;
  const double reach = window_reach + edge;
  if (u1 + reach < 0.0 || v1 + reach < 0.0 || u0 - reach >= width || v0 - reach >= height) return Decision::none;
  // The pixels the voxels' windows can read: a centre outside the image
  // reads as if clamped onto its edge, so the rectangle is the centres'
  // pixels clamped into the image, widened by the windows' reach only (at
  // level 0 a voxel reads its own pixel). Widening by the edge reach as
  // well, a pixel or more on every side inside the image, took in the
  // readings beside the empty pixels of a LiDAR scan (the sky, the gaps
  // between its lines) and split nodes that lie wholly in their cones.
  const DepthPyramid::Range wide = frame.pyramid.fine_range(
      static_cast<int>(std::max(std::clamp(u0, 0.0, width - 1.0) - window_reach, 0.0)),
      static_cast<int>(std::max(std::clamp(v0, 0.0, height - 1.0) - window_reach, 0.0)),
      static_cast<int>(std::min(std::clamp(u1, 0.0, width - 1.0) + window_reach, width - 1.0)),
      static_cast<int>(std::min(std::clamp(v1, 0.0, height - 1.0) + window_reach, height - 1.0)));
  // Voxels near the surface decided by the rays (surface_band.hpp): a
  // node where some may be cleared is not skipped, one where some may lie
  // is not cleared whole.
  const SurfaceBandBounds band = surface_band_bounds(rule_, near, z_max + pad, u_min - u_pad, u_max + u_pad,
                                                     v_min - v_pad, v_max + v_pad);
  const Decision skip = band.may_hold ? Decision::split : Decision::none;
  if (wide.max == 0.0f) return skip;  // no reading any voxel's window can hold
  const double margin = rule_.margin;
  // d - margin is rounded to float in the rule: allow for it.
  if (near >= wide.max * (1.0 + kRelativeError) - margin) return skip;  // behind every reading
  const bool in_image = u0 >= 0.0 && v0 >= 0.0 && u1 < width && v1 < height;
  if (in_image && within_range && contained && !band.may_hold) {
    // Every voxel's window holds its own pixel: a reading beyond the node
    // on each of the node's pixels clears every voxel.
    const DepthPyramid::Range own = frame.pyramid.fine_range(static_cast<int>(u0), static_cast<int>(v0),
                                                        static_cast<int>(u1), static_cast<int>(v1));
    if (own.min > 0.0f && z_max + pad < own.min * (1.0 - kRelativeError) - margin) return Decision::all;
  }
  return Decision::split;
}

bool ProjectiveTracer::holds_obstacle(std::uint64_t code, int depth) const {
  return cursor_ && cursor_->max_log_odds(code, depth) > rule_.occupied_log_odds;
}

void ProjectiveTracer::trace_brick(std::uint64_t brick, Key first, bool in_range, UpdateBatch& batch) const {
  // Its range node was classified on the way down unless it is the brick
  // itself; a brick whose parent lies within range as a whole needs no test
  // (at 2 cm with a 5 m range the bricks are the range nodes: the test per
  // brick was 4% of a TUM frame).
  if (rule_.range_depth == 2 && !in_range && !rule_.within_range(first)) return;
  std::uint64_t voxels = apply_surface_band(rule_, first, rule_.cleared_in_range(brick, first));
  if (voxels != 0 && rule_.box_keys) voxels &= rule_.brick_voxels_in_box(brick);
  if (voxels != 0 && holds_obstacle(brick, 2)) {
    for (std::uint64_t rest = voxels; rest != 0; rest &= rest - 1) {
      const unsigned i = static_cast<unsigned>(std::countr_zero(rest));
      if (holds_obstacle(brick + i, 0) && !rule_.ray_crosses(brick + i)) voxels &= ~(std::uint64_t{1} << i);
    }
  }
  if (voxels != 0) batch.add_misses_in_brick(brick, voxels);
}

void ProjectiveTracer::trace_node(std::uint64_t code, Key first, int depth, UpdateBatch& batch) const {
  bool in_range = false;  // every voxel centre of the node within max_range (set for a split node)
  switch (classify_node(first, depth, &in_range)) {
    case Decision::none:
      return;
    case Decision::all:
      if (holds_obstacle(code, depth)) break;  // split: its obstacles are cleared only where rays cross them
      batch.add_miss_node(code, depth);
      return;
    case Decision::split:
      break;
  }
  if (depth == 2) {
    trace_brick(code, first, in_range, batch);
    return;
  }
  if (rule_.decided_by_cells(first, depth)) {
    rule_.add_cell_misses(code, first, depth, false, batch);
    return;
  }
  const int child_depth = depth - 1;
  const std::uint32_t half = std::uint32_t{1} << child_depth;
  for (std::uint32_t slot = 0; slot < 8; ++slot) {
    const std::uint64_t child = code | std::uint64_t{slot} << (3 * child_depth);
    const Key child_first{first.x + (slot & 1u ? half : 0u), first.y + (slot & 2u ? half : 0u),
                          first.z + (slot & 4u ? half : 0u)};
    // Evaluating a brick voxel by voxel (eight at a time) costs less than
    // asking the pyramid about it first: the children of a split node are
    // evaluated directly.
    if (child_depth == 2) {
      trace_brick(child, child_first, in_range, batch);
    } else {
      trace_node(child, child_first, child_depth, batch);
    }
  }
}

void ProjectiveTracer::collect(std::uint64_t code, int depth, int task_depth, std::vector<Task>& tasks) const {
  const Decision decision = classify(code, depth);
  if (decision == Decision::none) return;
  // No task below a node that cells may decide: it is traced whole.
  UMBRA_ASSERT(task_depth >= 2 + static_cast<int>(rule_.cells.size()));
  if (decision == Decision::all || depth <= task_depth) {
    tasks.push_back({code, depth, decision});
    return;
  }
  const int child_depth = depth - 1;
  for (std::uint64_t slot = 0; slot < 8; ++slot) collect(code | slot << (3 * child_depth), child_depth, task_depth, tasks);
}

}  // namespace umbra
