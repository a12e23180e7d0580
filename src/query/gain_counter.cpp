#include "query/gain_counter.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "core/memory_budget.hpp"
#include "ray/voxel_walk.hpp"

namespace umbra::detail {
namespace {

double binary_entropy_bits(float log_odds) {
  const double p = probability(log_odds);
  if (p <= 0.0 || p >= 1.0) return 0.0;
  return -(p * std::log2(p) + (1.0 - p) * std::log2(1.0 - p));
}

/// A float point widened to double, through a volatile copy: GCC 12.2 at
/// -O2 and above (Debian 12's compiler) drops the float rounding of x and y
/// when it sees a double -> float -> double round trip of a point (its SLP
/// vectorizer; five-line reproducer in docs/design.md). The rays start and
/// end at float points, and their keys and the image's geometry must use
/// exactly those.
Vec3d widen(Vec3f p) {
  const volatile float x = p.x;
  const volatile float y = p.y;
  const volatile float z = p.z;
  return {double(x), double(y), double(z)};
}

/// Key of child `slot` (x = 1, y = 2, z = 4) of the node at `depth` whose first voxel is `key`.
Key child_key(Key key, int depth, unsigned slot) {
  const std::uint32_t half = 1u << (depth - 1);
  return {key.x + ((slot & 1u) ? half : 0u), key.y + ((slot & 2u) ? half : 0u), key.z + ((slot & 4u) ? half : 0u)};
}

Aabb grown(const Aabb& box, double by) {
  return {box.min - Vec3d{by, by, by}, box.max + Vec3d{by, by, by}};
}

/// Whether the segment from `a` to `a + d` meets the box shrunk by `margin`
/// on every side (`inside`) and the box grown by it (`near`): one slab test
/// for both. `inverse` holds 1 / d per axis (computed once per segment: the
/// segment is tested against several boxes).
struct SegmentBox {
  bool inside;
  bool near;
};
SegmentBox segment_meets(Vec3d a, Vec3d d, Vec3d inverse, const Aabb& box, double margin) {
  double in0 = 0.0, in1 = 1.0, out0 = 0.0, out1 = 1.0;
  for (int axis = 0; axis < 3; ++axis) {
    const double low = box.min[axis] - a[axis];
    const double high = box.max[axis] - a[axis];
    if (d[axis] == 0.0) {
      if (low - margin > 0.0 || high + margin < 0.0) return {false, false};
      if (low + margin > 0.0 || high - margin < 0.0) in0 = 2.0;  // never inside the shrunk box
      continue;
    }
    double enter = (low + margin) * inverse[axis];
    double leave = (high - margin) * inverse[axis];
    if (enter > leave) std::swap(enter, leave);
    in0 = std::max(in0, enter);
    in1 = std::min(in1, leave);
    enter = (low - margin) * inverse[axis];
    leave = (high + margin) * inverse[axis];
    if (enter > leave) std::swap(enter, leave);
    out0 = std::max(out0, enter);
    out1 = std::min(out1, leave);
    if (out0 > out1) return {false, false};
  }
  return {in0 <= in1, true};
}

/// A bound on how far the voxels a walk from `origin` visits stray from
/// the exact segment, and on how far a voxel centre rounded to float lies
/// from the exact one, for rays of at most `range`: the walk steps along a
/// normalised float direction (relative error below 4e-7), from borders
/// placed with float half voxels; centres are rounded to float (relative
/// 6e-8). Four times that, to be sure.
/// The voxels of a walk of any length that lie within `range` of the
/// origin stray by no more either: the walk follows its float line, whose
/// direction is off by under 4e-7 plus the end's rounding over the length
/// (at most 6e-8 (|origin| + length) / length), so at distance t it lies
/// within about 4e-7 t + 6e-8 (|origin| + t) of the exact segment (per
/// coordinate; the factor four covers the rest).
double margin_for(Vec3d origin, double range, double resolution) {
  const double coordinates = std::max({std::fabs(origin.x), std::fabs(origin.y), std::fabs(origin.z)}) + range;
  return 4.0 * (4e-7 * range + 6e-8 * coordinates + 3e-8 * resolution);
}

// Image resolution: a pixel is about a voxel seen at the far range (finer
// buys little: the footprints of the nodes the walk asks about are larger),
// within a pixel budget.
constexpr double kPixelsPerFarVoxel = 1.0;
constexpr double kMaxPixels = 400000.0;
// Widest cone (in voxels across, where its obstacles are) worth sweeping.
constexpr double kMaxSweepWidth = 16.0;
// Child slots from the one nearest a point to the one farthest from it (to
// be XORed with the nearest's slot): by the number of axes crossed.
constexpr std::array<unsigned, 8> kNearToFar = {0, 1, 2, 4, 3, 5, 6, 7};
// Steps (GainOptions::max_steps) are about as dear as a decision by the
// image: a walked voxel costs an eighth of one, a block of centres counted
// three.
constexpr std::uint64_t kWalkedVoxelsPerStep = 8;
constexpr std::uint64_t kStepsPerBlock = 3;

/// The range at which a frustum of f's angles needs about `steps` steps to
/// count unknown space along its boundary alone: its four side faces and
/// its far cap have an area of R^2 (2 atan(tan(v/2) cos(h/2)) + 2 atan(tan(h/2)
/// cos(v/2)) + 4 asin(sin(h/2) sin(v/2))), and counting costs about a step
/// per 3 voxel faces of it (blocks of 4^3 centres and the nodes above them;
/// measured on a map of one scan at 50 and 100 m).
double boundary_range(const Frustum& f, double resolution, std::uint64_t steps) {
  const double h = f.hfov / 2;
  const double v = f.vfov / 2;
  const double area_per_r2 = 2.0 * std::atan(std::tan(v) * std::cos(h)) + 2.0 * std::atan(std::tan(h) * std::cos(v)) +
                             4.0 * std::asin(std::sin(h) * std::sin(v));
  return resolution * std::sqrt(3.0 * double(steps) / area_per_r2);
}

// Regions of up to 2^k voxels per edge across the frustum's boundary are
// counted as one block of centres (FrustumGeometry::count_grid_points).
constexpr int kBlockCountDepth = 2;

}  // namespace

GainCounter::GainCounter(const Grid& grid) : grid_(grid) {}

// (Grid::center and min_corner are out of line; these inline forms are the
// same formulas for finest voxels and aligned node keys: 3% of a 20 cm query.)
Vec3d GainCounter::centre_of(Key key) const {
  return {grid_.axis_center(key.x), grid_.axis_center(key.y), grid_.axis_center(key.z)};
}

Aabb GainCounter::centres_of(Key key, int depth) const {
  const Vec3d low = centre_of(key);
  const double span = grid_.resolution() * double((1u << depth) - 1u);
  return {low, low + Vec3d{span, span, span}};
}

bool GainCounter::in_frustum(Key key, Overlap parent) const {
  if (parent == Overlap::inside) return true;
  return frustum_->contains_quickly(centre_of(key));
}

Aabb GainCounter::cube_of(Key key, int depth) const {
  const auto offset = std::int64_t{grid_.key_offset()};
  const double res = grid_.resolution();
  const Vec3d low{double(std::int64_t{key.x} - offset) * res, double(std::int64_t{key.y} - offset) * res,
                  double(std::int64_t{key.z} - offset) * res};
  const double size = grid_.node_size(depth);
  return {low, low + Vec3d{size, size, size}};
}

GainResult GainCounter::count(const OccupancyTree& tree, const Frustum& frustum, const GainOptions& options) {
  tree_ = &tree;
  thresholds_ = tree.thresholds();
  fast_ = options.method == GainMethod::fast;
  fast_depth_ = options.fast_depth;
  voxels_ = 0;
  entropy_ = 0.0;
  steps_ = 0;
  max_steps_ = options.max_steps == 0 ? ~std::uint64_t{0} : options.max_steps;
  clear_shift_ = 64;
  path_depth_ = 64;
  setup_pose(frustum);
  // A sensor inside an obstacle sees nothing: every walk starts in its voxel.
  OccupancyTree::Cursor cursor(tree);
  const bool inside_obstacle = thresholds_.is_occupied(cursor.max_log_odds(morton::encode(origin_key_), 0));
  if (!inside_obstacle) visit_node(tree_->root(), Key{}, Overlap::partly);
  GainResult result;
  result.unknown_voxels = voxels_;
  const double r = grid_.resolution();
  result.volume = double(voxels_) * r * r * r;
  result.entropy_bits = entropy_;
  return result;
}

void GainCounter::setup_pose(const Frustum& frustum) {
  requested_range_ = frustum.max_range;
  const double res = grid_.resolution();
  // No centre of the map lies beyond its farthest corner: a longer range
  // counts the same voxels (its far cap lies outside the map), but its
  // geometry would decide nothing "inside" (its margins grow with the range).
  const double half = grid_.half_extent();
  const Aabb map_box{{-half, -half, -half}, {half, half, half}};
  Frustum clipped = frustum;
  const double map_reach = std::sqrt(farthest_distance_squared(frustum.origin, map_box)) * (1.0 + 1e-9) + res;
  clipped.max_range = std::min(frustum.max_range, std::max(map_reach, frustum.min_range + res));
  frustum_.emplace(clipped);
  origin_ = Vec3f(frustum.origin);
  const Vec3d apex = widen(origin_);
  origin_key_ = grid_.key(apex);  // throws std::out_of_range outside the map
  const double apex_shift = (apex - frustum.origin).norm();
  // Rays end at centres in the map.
  const double in_map = std::sqrt(farthest_distance_squared(apex, map_box));
  const double range = std::min(frustum.max_range + apex_shift, in_map);
  // The margins (see margin_for()). A walk strays from its segment by at
  // most margin_for(its distance from the apex), so near obstacles it
  // strays only by the margin of the farthest obstacle's distance: that one
  // grows the obstacles and tests rays against them. Beyond the last
  // obstacle nothing can block, however long the ray. The targets (rounded
  // centres) and the sweeps, which follow walks to their ends, keep the
  // margin of the whole range.
  target_margin_ = margin_for(apex, range, res);
  const double obstacles_within = obstacle_reach(apex, range + 2.0 * target_margin_);
  margin_ = margin_for(apex, std::min(range, obstacles_within), res);
  last_blocking_step_ = static_cast<std::uint64_t>(std::min(std::sqrt(3.0) * obstacles_within / res + 3.0, 1e18)) + 1;
  obstacles_.clear();
  obstacle_keys_.clear();
  touching_ = false;
  // With margins not small against a voxel the image would decide little;
  // walk every ray then (and the walk's own reasoning needs them small).
  use_image_ = margin_ < res / 64.0;
  sweeps_ = use_image_ && !fast_;
  if (!use_image_) return;

  ViewImage::Setup setup;
  setup.apex = apex;
  setup.f = frustum_->f;
  setup.l = frustum_->l;
  setup.u = frustum_->u;
  const double tan_h = std::tan(frustum.hfov / 2);
  const double tan_v = std::tan(frustum.vfov / 2);
  double pixel = res / (clipped.max_range * kPixelsPerFarVoxel);
  const double area = 4.0 * (tan_h + 4 * pixel) * (tan_v + 4 * pixel);
  if (area / (pixel * pixel) > kMaxPixels) pixel = std::sqrt(area / kMaxPixels);
  // The border holds every centre of the frustum as seen from the apex
  // (the frustum is defined from the exact origin): centres other than the
  // origin's lie at least res/4 away, so their direction moves by at most
  // apex_shift / (res/4) radians, stretched by 1 + x^2 + y^2 on the plane.
  const double stretch = 1.0 + tan_h * tan_h + tan_v * tan_v;
  const double border = 2.0 * pixel + 1.01 * apex_shift / (res / 4) * stretch;
  setup.half_width = tan_h + border;
  setup.half_height = tan_v + border;
  setup.pixel = pixel;
  setup.near_plane = res * 1e-3;
  setup.candidates = true;
  setup.maxima = sweeps_;  // only the sweeps read them
  image_.reset(setup);

  // Obstacles anywhere in the image's pyramid up to the range (also before
  // min_range: they block just the same).
  Frustum view = clipped;
  view.origin = apex;
  view.hfov = 2.0 * std::atan(setup.half_width);
  view.vfov = 2.0 * std::atan(setup.half_height);
  view.min_range = 0.0;
  view.max_range = range + 2.0 * target_margin_;
  touching_distance_ = setup.near_plane * std::sqrt(1.0 + setup.half_width * setup.half_width +
                                                    setup.half_height * setup.half_height);
  draw_obstacles(FrustumGeometry(view), tree_->root(), Key{}, Overlap::partly);
  image_.finish();
  // Only the sweeps read the bits, and fast sweeps nothing.
  if (sweeps_) fill_occupied_bitmap(view.max_range);
  sweep_pose_ = {&occupied_, &grid_, apex, origin_key_, target_margin_};
}

double GainCounter::obstacle_reach(Vec3d apex, double range) const {
  // Branch and bound over the nodes holding occupied voxels within `range`:
  // the farthest first, skipping nodes that cannot beat the best so far.
  // It stops as soon as the best is the range itself.
  const double range2 = range * range;
  double best2 = 0.0;
  auto search = [&](auto& self, NodeRef ref, Key key) -> void {
    if (best2 >= range2 || !thresholds_.is_occupied(tree_->log_odds(ref))) return;
    const int depth = ref.depth;
    const Aabb cube = cube_of(key, depth);
    if (distance_squared(apex, cube) > range2) return;
    const double farthest2 = farthest_distance_squared(apex, cube);
    if (farthest2 <= best2) return;
    if (!tree_->has_children(ref) || tree_->all_children_same(ref)) {
      best2 = farthest2;
      return;
    }
    const Vec3d middle = (cube.min + cube.max) * 0.5;
    const unsigned near_slot = (apex.x >= middle.x ? 1u : 0u) | (apex.y >= middle.y ? 2u : 0u) | (apex.z >= middle.z ? 4u : 0u);
    for (auto order = kNearToFar.rbegin(); order != kNearToFar.rend(); ++order) {
      const unsigned slot = *order ^ near_slot;
      self(self, tree_->child(ref, slot), child_key(key, depth, slot));
    }
  };
  search(search, tree_->root(), Key{});
  // A walk's voxel at distance t from the apex holds a point of its float
  // line at parameter t (the float direction is a unit vector within 1e-6).
  return std::sqrt(best2) * (1.0 + 1e-6);
}

void GainCounter::fill_occupied_bitmap(double reach) {
  // The box of the drawn obstacles' voxels (within the box of the image's
  // pyramid cut at the range): what the sweeps can read, sized by the
  // obstacles in view, not by the range.
  const Vec3d apex = image_.setup().apex;
  const ViewImage::Setup& setup = image_.setup();
  Vec3d low = apex;
  Vec3d high = apex;
  for (const double side : {-setup.half_width, setup.half_width}) {
    for (const double up : {-setup.half_height, setup.half_height}) {
      const Vec3d corner = apex + (setup.f + setup.l * side + setup.u * up) * reach;
      for (int a = 0; a < 3; ++a) {
        low[a] = std::min(low[a], corner[a]);
        high[a] = std::max(high[a], corner[a]);
      }
    }
  }
  const double res = grid_.resolution();
  const auto last = std::int64_t{grid_.keys_per_axis()} - 1;
  std::int64_t box_low[3];
  std::int64_t box_high[3];
  for (int a = 0; a < 3; ++a) {
    const double from = std::max(low[a], apex[a] - reach) / res;
    const double to = std::min(high[a], apex[a] + reach) / res;
    box_low[a] = std::clamp<std::int64_t>(std::int64_t(std::floor(from)) + grid_.key_offset() - 1, 0, last);
    box_high[a] = std::clamp<std::int64_t>(std::int64_t(std::floor(to)) + grid_.key_offset() + 1, 0, last);
  }
  std::int64_t used_low[3] = {last, last, last};
  std::int64_t used_high[3] = {0, 0, 0};
  for (const ObstacleKeys& o : obstacle_keys_) {
    for (int a = 0; a < 3; ++a) {
      used_low[a] = std::min<std::int64_t>(used_low[a], o.first[a]);
      used_high[a] = std::max<std::int64_t>(used_high[a], std::int64_t{o.first[a]} + o.last);
    }
  }
  Key low_key;
  Key high_key{0, 0, 0};  // (an empty box when nothing was drawn: one voxel, clear)
  for (int a = 0; a < 3; ++a) {
    low_key[a] = std::uint32_t(std::max(box_low[a], used_low[a]));
    high_key[a] = std::uint32_t(std::max(std::min(box_high[a], used_high[a]), std::int64_t{low_key[a]}));
  }
  const std::uint64_t bytes = OccupiedBitmap::bytes_for(low_key, high_key);
  const auto what = [&] {
    char text[256];
    std::snprintf(text, sizeof text,
                  "max_range %g m at resolution %g m: the bitmap of the occupied voxels in view (a box of %u x %u x %u voxels)",
                  requested_range_, res, high_key.x - low_key.x + 1, high_key.y - low_key.y + 1, high_key.z - low_key.z + 1);
    return std::string(text);
  };
  require_memory("information gain", what(), bytes);
  naming_bad_alloc("information gain", what(), bytes, [&] { occupied_.reset(low_key, high_key); });
  for (const ObstacleKeys& o : obstacle_keys_) {
    occupied_.set_box(o.first, {o.first.x + o.last, o.first.y + o.last, o.first.z + o.last});
  }
}

void GainCounter::draw_obstacles(const FrustumGeometry& view, NodeRef ref, Key key, Overlap overlap) {
  if (!thresholds_.is_occupied(tree_->log_odds(ref))) return;
  const int depth = ref.depth;
  if (!tree_->has_children(ref) || tree_->all_children_same(ref)) {
    draw_solid_obstacle(view, key, depth);
    return;
  }
  const Aabb cube = cube_of(key, depth);
  if (overlap != Overlap::inside) {
    overlap = view.overlap(grown(cube, margin_));
    if (overlap == Overlap::outside) return;
  }
  // Children nearest the apex first: the candidate lists are sorted by
  // distance, and obstacles drawn near to far mostly append to them.
  const Vec3d middle = (cube.min + cube.max) * 0.5;
  const Vec3d apex = image_.setup().apex;
  const unsigned near_slot = (apex.x >= middle.x ? 1u : 0u) | (apex.y >= middle.y ? 2u : 0u) | (apex.z >= middle.z ? 4u : 0u);
  for (const unsigned order : kNearToFar) {
    const unsigned slot = order ^ near_slot;
    const NodeRef child = tree_->child(ref, slot);
    // Tested here, not in the call: most children of a surface are free or
    // unknown, and a call per child was a tenth of a 20 cm query.
    if (thresholds_.is_occupied(tree_->log_odds(child))) {
      draw_obstacles(view, child, child_key(key, depth, slot), overlap);
    }
  }
}

void GainCounter::draw_solid_obstacle(const FrustumGeometry& view, Key key, int depth) {
  // Every voxel in it is occupied. Its part before the near plane lies
  // within near_plane / cos(widest angle) of the apex; an obstacle that
  // close could block rays there without showing in their pixels, so the
  // image then proves no visibility at all.
  // (Its footprint below tells whether it is in the view's angles.)
  const Aabb cube = cube_of(key, depth);
  const Aabb reach = grown(cube, margin_);
  const ViewImage::Setup& s = image_.setup();
  const double near = std::sqrt(distance_squared(s.apex, reach));
  if (near > view.frustum.max_range) return;
  if (near <= touching_distance_) touching_ = true;
  PixelRect rect;
  bool clipped = false;
  if (!image_.footprint(reach, rect, clipped)) return;
  image_.draw(rect, near, static_cast<std::uint32_t>(obstacles_.size()));
  obstacles_.push_back(cube);
  if (sweeps_) obstacle_keys_.push_back({key, (1u << depth) - 1});
}

// --- the walk over unknown space ------------------------------------------------------

void GainCounter::visit_node(NodeRef ref, Key key, Overlap overlap) {
  if (!tree_->contains_unknown(ref)) return;
  const int depth = ref.depth;
  if (!tree_->has_children(ref) || tree_->all_children_same(ref)) {
    visit_region(key, depth, tree_->log_odds(ref), overlap);
    return;
  }
  if (overlap != Overlap::inside) {
    overlap = frustum_->overlap(centres_of(key, depth));
    if (overlap == Overlap::outside) return;
  }
  switch (decide(key, depth, tree_->log_odds(ref), overlap)) {
    case Visibility::visible: count_node(ref, key, overlap); return;
    case Visibility::blocked: return;
    case Visibility::undecided: break;
  }
  for (unsigned slot = 0; slot < 8; ++slot) {
    const NodeRef child = tree_->child(ref, slot);
    // Tested before the call: many children hold no unknown space.
    if (tree_->contains_unknown(child)) visit_node(child, child_key(key, depth, slot), overlap);
  }
}

void GainCounter::visit_region(Key key, int depth, float value, Overlap overlap) {
  if (depth == 0) {
    if (in_frustum(key, overlap) && voxel_visible(key)) add(1, value);
    return;
  }
  if (overlap != Overlap::inside) {
    overlap = frustum_->overlap(centres_of(key, depth));
    if (overlap == Overlap::outside) return;
  }
  switch (decide(key, depth, value, overlap)) {
    case Visibility::visible: count_region(key, depth, value, overlap); return;
    case Visibility::blocked: return;
    case Visibility::undecided: break;
  }
  for (unsigned slot = 0; slot < 8; ++slot) visit_region(child_key(key, depth, slot), depth - 1, value, overlap);
}

GainCounter::Visibility GainCounter::decide(Key key, int depth, float value, Overlap overlap) {
  spend(1);
  // Fast: the two opposite corner voxels decide a node without obstacles
  // inside when they agree (with an obstacle inside, the voxels in front of
  // it and behind it differ).
  const bool corners_decide = fast_ && depth <= fast_depth_ && !thresholds_.is_occupied(value);
  // Fast sweeps nothing: a node a sweep would prove hidden is split until
  // its parts' corners say blocked, the same answer, and that measured
  // cheaper (20 cm 457 -> 441 us/pose, 5 cm 12.5 -> 11.8 ms/pose).
  if (!corners_decide) return node_visibility(key, depth, /*sweep=*/sweeps_);
  // A node the sweep proves hidden has both corners blocked, and one wholly
  // in the frustum that the image proves visible has both corners visible,
  // so the corners alone give the same answers there, for less: most of
  // these small nodes are proven neither way, and footprints and sweeps
  // were 7% and 5% of fast at 20 cm. (A node across the frustum's boundary
  // may be proven visible for its voxels in the frustum while a corner
  // outside it is hidden: the image is asked first there.)
  if (overlap != Overlap::inside) {
    const Visibility surely = node_visibility(key, depth, /*sweep=*/false);
    if (surely != Visibility::undecided) return surely;
  }
  const std::uint32_t last = (1u << depth) - 1;
  const bool low = voxel_visible(key);
  const bool high = voxel_visible({key.x + last, key.y + last, key.z + last});
  if (low != high) return Visibility::undecided;
  return low ? Visibility::visible : Visibility::blocked;
}

void GainCounter::count_node(NodeRef ref, Key key, Overlap overlap) {
  if (!tree_->contains_unknown(ref)) return;
  const int depth = ref.depth;
  if (!tree_->has_children(ref) || tree_->all_children_same(ref)) {
    count_region(key, depth, tree_->log_odds(ref), overlap);
    return;
  }
  if (overlap != Overlap::inside) {
    overlap = frustum_->overlap(centres_of(key, depth));
    if (overlap == Overlap::outside) return;
  }
  for (unsigned slot = 0; slot < 8; ++slot) {
    const NodeRef child = tree_->child(ref, slot);
    if (tree_->contains_unknown(child)) count_node(child, child_key(key, depth, slot), overlap);
  }
}

void GainCounter::count_region(Key key, int depth, float value, Overlap overlap) {
  spend(1);
  if (depth == 0) {
    if (in_frustum(key, overlap)) add(1, value);
    return;
  }
  if (overlap != Overlap::inside) {
    overlap = frustum_->overlap(centres_of(key, depth));
    if (overlap == Overlap::outside) return;
  }
  if (overlap == Overlap::inside) {
    add(std::uint64_t{1} << (3 * depth), value);
    return;
  }
  if (depth <= kBlockCountDepth) {
    // A small region across the frustum's boundary: its centres tested as
    // one block, not a subtree of overlap tests and single points.
    spend(kStepsPerBlock - 1);
    const int n = 1 << depth;
    std::array<double, 8> xs, ys, zs;
    for (int i = 0; i < n; ++i) {
      xs[std::size_t(i)] = grid_.axis_center(key.x + std::uint32_t(i));
      ys[std::size_t(i)] = grid_.axis_center(key.y + std::uint32_t(i));
      zs[std::size_t(i)] = grid_.axis_center(key.z + std::uint32_t(i));
    }
    const int inside = frustum_->count_grid_points(xs.data(), ys.data(), zs.data(), n);
    if (inside > 0) add(std::uint64_t(inside), value);
    return;
  }
  for (unsigned slot = 0; slot < 8; ++slot) count_region(child_key(key, depth, slot), depth - 1, value, overlap);
}

void GainCounter::refuse() const {
  Frustum f = frustum_->frustum;
  f.max_range = requested_range_;
  const double res = grid_.resolution();
  const double boundary = boundary_range(f, res, max_steps_);
  char hint[200];
  if (boundary < f.max_range) {
    std::snprintf(hint, sizeof hint, "a frustum of these angles needs that many in unknown space alone from about %.3g m on",
                  boundary);
  } else {
    std::snprintf(hint, sizeof hint, "here the shadows of obstacles take most of them");
  }
  char text[700];
  std::snprintf(text, sizeof text,
                "information gain: max_range %g m at resolution %g m needs more than %llu steps "
                "(GainOptions::max_steps): the voxels along the edges of the frustum and of the shadows in it "
                "are decided one by one, more of them the longer the range (%s). Use a shorter max_range or a "
                "coarser map, or raise max_steps",
                f.max_range, res, static_cast<unsigned long long>(max_steps_), hint);
  throw std::invalid_argument(text);
}

void GainCounter::add(std::uint64_t voxels, float value) {
  voxels_ += voxels;
  if (value != entropy_value_) {
    entropy_value_ = value;
    entropy_of_value_ = binary_entropy_bits(value);
  }
  entropy_ += double(voxels) * entropy_of_value_;
}

// --- visibility --------------------------------------------------------------------

GainCounter::Visibility GainCounter::node_visibility(Key key, int depth, bool sweep) {
  if (!use_image_) return Visibility::undecided;
  // The centres the walks aim at (rounded to float: within the margin).
  const Aabb targets = grown(centres_of(key, depth), target_margin_);
  const ViewImage::Setup& s = image_.setup();
  // Near the apex directions are not what the image assumes (and the
  // origin's own voxel has an empty walk): the image says nothing there.
  PixelRect rect;
  bool clipped = false;
  if (touching_ || distance_squared(s.apex, targets) < 0.0625 * grid_.resolution() * grid_.resolution() ||
      !image_.footprint(targets, rect, clipped) || clipped) {
    return Visibility::undecided;
  }
  const double obstacle_free = double(image_.nearest(rect));  // no obstacle nearer in the cone
  if (obstacle_free > std::sqrt(farthest_distance_squared(s.apex, targets))) return Visibility::visible;
  // (Fast decides the small nodes this mostly proves by their corners.)
  if (sweeps_ && hidden_by_one_candidate(targets, rect)) return Visibility::blocked;
  // For eight voxels or fewer a sweep costs more than the rays it saves.
  if (!sweep || depth < 2) return Visibility::undecided;
  // Some rays reach the node's near side without passing an obstacle: a
  // sweep would not prove it hidden.
  const double obstacles_before = double(image_.nearest_in_every_pixel(rect));
  if (obstacles_before >= std::sqrt(distance_squared(s.apex, targets))) return Visibility::undecided;
  // Wide cones straddle the edges of what hides them: their parts will do.
  const double across = double(std::max(rect.x1 - rect.x0, rect.y1 - rect.y0) + 1) * s.pixel * obstacles_before;
  if (across > kMaxSweepWidth * grid_.resolution()) return Visibility::undecided;
  return sweep_.hidden(sweep_pose_, targets, obstacle_free) ? Visibility::blocked : Visibility::undecided;
}

bool GainCounter::hidden_by_one_candidate(const Aabb& targets, const PixelRect& rect) const {
  // An obstacle that hides every point of the targets hides all their
  // directions, so it is drawn into every pixel of their footprint: the
  // candidates of its middle pixel are enough to look at.
  int count = 0;
  bool overflow = false;
  const ViewImage::Candidate* candidates = image_.candidates((rect.x0 + rect.x1) / 2, (rect.y0 + rect.y1) / 2, count, overflow);
  const Vec3d o = image_.setup().apex;
  const double nearest = std::sqrt(distance_squared(o, targets));
  for (int i = 0; i < count && double(candidates[i].near) < nearest; ++i) {
    const Aabb inside = grown(obstacles_[candidates[i].index], -margin_);
    for (int a = 0; a < 3; ++a) {
      // The obstacle's slab along a lies between the apex and the targets:
      // every segment from the apex to a target crosses its middle plane,
      // at a point in the convex hull of where the targets' corners' segments
      // cross it. If those lie inside the obstacle (shrunk by the margin),
      // every walk to the targets visits it, as in ray_visibility_from_image.
      double side = 0.0;
      if (o[a] < inside.min[a] && inside.max[a] < targets.min[a]) side = 1.0;
      if (o[a] > inside.max[a] && inside.min[a] > targets.max[a]) side = -1.0;
      if (side == 0.0) continue;
      const double plane = 0.5 * (inside.min[a] + inside.max[a]);
      const int b = (a + 1) % 3;
      const int c = (a + 2) % 3;
      // (A relative hair for the rounding of the crossings.)
      const double hair = 1e-12 * (std::fabs(o[b]) + std::fabs(o[c]) + nearest + 1.0);
      bool all = true;
      for (unsigned corner = 0; corner < 8 && all; ++corner) {
        const Vec3d p{(corner & 1u) ? targets.max.x : targets.min.x, (corner & 2u) ? targets.max.y : targets.min.y,
                      (corner & 4u) ? targets.max.z : targets.min.z};
        const double along = (plane - o[a]) / (p[a] - o[a]);
        const double qb = o[b] + along * (p[b] - o[b]);
        const double qc = o[c] + along * (p[c] - o[c]);
        all = qb > inside.min[b] + hair && qb < inside.max[b] - hair && qc > inside.min[c] + hair && qc < inside.max[c] - hair;
      }
      if (all) return true;
    }
  }
  return false;
}

bool GainCounter::voxel_visible(Key key) {
  spend(1);
  if (key == origin_key_) return true;  // the walk to the origin's own voxel is empty
  switch (ray_visibility_from_image(key)) {
    case Visibility::visible: return true;
    case Visibility::blocked: return false;
    case Visibility::undecided: break;
  }
  return walk_is_clear(key);
}

GainCounter::Visibility GainCounter::ray_visibility_from_image(Key key) const {
  if (!use_image_) return Visibility::undecided;
  const Vec3d apex = image_.setup().apex;
  const Vec3d target = widen(grid_.center_f(key));
  const Vec3d d = target - apex;
  int px = 0;
  int py = 0;
  if (!image_.pixel_of(d, px, py)) return Visibility::undecided;
  const double distance = d.norm();
  if (!touching_ && double(image_.nearest(px, py)) > distance) return Visibility::visible;
  int count = 0;
  bool overflow = false;
  const ViewImage::Candidate* candidates = image_.candidates(px, py, count, overflow);
  bool grazed = false;
  Vec3d inverse;
  for (int axis = 0; axis < 3; ++axis) inverse[axis] = d[axis] == 0.0 ? 0.0 : 1.0 / d[axis];
  for (int i = 0; i < count && double(candidates[i].near) <= distance; ++i) {
    const Aabb& cube = obstacles_[candidates[i].index];
    // Through the inside, shrunk by the margin: the walk surely visits it
    // (before the target's voxel, which is unknown and so not in it).
    const SegmentBox meets = segment_meets(apex, d, inverse, cube, margin_);
    if (meets.inside) return Visibility::blocked;
    grazed |= meets.near;
  }
  if (!grazed && !overflow && !touching_) return Visibility::visible;
  return Visibility::undecided;
}

bool GainCounter::walk_is_clear(Key key) {
  bool blocked = false;
  // The walk steps one axis at a time, always the same way along each: its
  // n-th voxel lies n keys (L1) from the origin's, at least n res / sqrt(3)
  // from it, so at least n res / sqrt(3) - res sqrt(3) from the apex. From
  // the voxel where that passes the farthest obstacle on, nothing can block.
  std::uint64_t visited = 0;
  auto visit = [&](std::uint64_t code) {
    if (++visited > last_blocking_step_) return false;  // (not blocked: beyond every obstacle)
    if (clear_shift_ < 64 && (code >> clear_shift_) == clear_prefix_) return true;
    // Resume from the deepest node of the last lookup that also holds this
    // voxel (consecutive voxels of a walk share most of their path; from
    // the root each lookup read ~13 levels of the 3DTK tree). The nodes
    // above it were occupied, or the last descent would have stopped there.
    NodeRef ref = tree_->root();
    if (path_depth_ < ref.depth) {
      const std::uint64_t differ = code ^ path_code_;
      int depth = path_depth_;
      while (depth < ref.depth && (differ >> (3 * depth)) != 0) ++depth;
      ref = path_[std::size_t(depth)];
    }
    path_code_ = code;
    for (;;) {
      path_[std::size_t(ref.depth)] = ref;
      path_depth_ = ref.depth;
      if (!thresholds_.is_occupied(tree_->log_odds(ref))) {
        clear_shift_ = 3u * unsigned(ref.depth);
        clear_prefix_ = code >> clear_shift_;
        return true;
      }
      if (!tree_->has_children(ref)) {
        blocked = true;
        return false;
      }
      ref = tree_->child(ref, morton::slot(code, ref.depth - 1));
    }
  };
  walk_ray(grid_, origin_, origin_key_, grid_.center_f(key), key, visit);
  spend(1 + visited / kWalkedVoxelsPerStep);
  return !blocked;
}

}  // namespace umbra::detail
