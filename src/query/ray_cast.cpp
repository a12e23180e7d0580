// Ray casts on a tree (the algorithms behind OccupancyMap::cast_ray and
// cast_ray_octomap, which hold the map for reading around them).
//
// Both step through the voxels a ray passes exactly as OctoMap's castRay
// does (float origin and normalised float direction, double tMax/tDelta
// from the origin voxel's border, ties to the later axis), so that they hit
// the same voxel as OctoMap does on the same map. Looking voxels up goes
// through BlockingLookup: inside a node known to hold nothing that stops
// the ray, a step costs no lookup, and a cast jumps over such a node of
// 2^3 voxels or more in one step (ExactDda::leave_node, exact).
//
// cast_ray measures range along the ray (the distance at which it enters a
// voxel); cast_ray_octomap keeps OctoMap's rules: the origin voxel is
// checked first, the range is the distance to each voxel's centre, an
// unknown voxel ends an unsuccessful cast unless unknown space is ignored.
#include "query/ray_cast.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/assert.hpp"
#include "query/blocking_lookup.hpp"
#include "query/query_walk.hpp"
#include "ray/exact_dda.hpp"
#include "ray/ray_direction.hpp"
#include "tree/make_node.hpp"

namespace umbra {
namespace {

using detail::ExactDda;

/// The float origin and normalised float direction OctoMap casts with.
struct CastStart {
  Vec3f origin;
  Key origin_key;
  Vec3f direction;
};

CastStart prepare(const Grid& grid, Vec3d origin, Vec3d direction) {
  if (!origin.is_finite()) throw std::invalid_argument("ray cast: the origin is not finite");
  if (!direction.is_finite()) throw std::invalid_argument("ray cast: the direction is not finite");
  CastStart start;
  start.origin = Vec3f(origin);
  start.origin_key = key_of_rounded(grid, start.origin, "ray cast: the origin");  // throws std::out_of_range
  // A direction whose float squares overflow or vanish (1e20, 1e-25, or a
  // double beyond float range, which became inf) is first scaled by a power
  // of two, which changes no bit of the normalised direction otherwise; its
  // normalised float form used to be NaN or 0, and the walk then never moved
  // (an endless loop without max_range).
  const double largest = std::max({std::fabs(direction.x), std::fabs(direction.y), std::fabs(direction.z)});
  if (largest > 0x1p40 || (largest > 0.0 && largest < 0x1p-40)) {
    const int exponent = -std::ilogb(largest);  // scalbn per component: 2^exponent alone may overflow
    direction = {std::scalbn(direction.x, exponent), std::scalbn(direction.y, exponent),
                 std::scalbn(direction.z, exponent)};
  }
  Vec3f d(direction);
  const double length = octomap_norm(d);
  if (!(length > 0.0)) throw std::invalid_argument("ray cast: the direction is zero");
  const auto l = static_cast<float>(length);
  start.direction = {d.x / l, d.y / l, d.z / l};
  UMBRA_ASSERT(start.direction.is_finite() && octomap_norm(start.direction) > 0.5);
  return start;
}

}  // namespace

namespace detail {

RayHit cast_ray(const OccupancyTree& tree, const Grid& grid, Vec3d origin, Vec3d direction,
                const RayCastOptions& options) {
  if (std::isnan(options.max_range)) throw std::invalid_argument("ray cast: max_range is NaN");
  const CastStart start = prepare(grid, origin, direction);
  const QueryScope scope = scope_of(tree, grid, options.depth);
  BlockingLookup lookup(scope, {tree.thresholds(), options.stop_at_unknown});
  ExactDda stepper(grid, start.origin, start.origin_key, start.direction, ExactDda::HalfVoxel::kDouble);
  const bool limited = options.max_range > 0.0;
  const double limit = limited ? options.max_range : std::numeric_limits<double>::infinity();
  double entered = 0.0;
  RayHit hit;
  for (;;) {
    if (limited && entered > options.max_range) return hit;
    const std::uint64_t code = stepper.code();
    NodeRef node{};
    if (lookup.blocks(code, &node)) {
      hit.hit = true;
      hit.node = make_node(tree, grid, node, code);
      hit.distance = entered;
      hit.point = Vec3d(start.origin) + Vec3d(start.direction) * entered;
      return hit;
    }
    // Inside a node holding nothing that stops the ray (from 2^3 voxels
    // up), the cast jumps to the first voxel past it.
    if (lookup.clear_depth() >= 1) {
      if (stepper.leave_node(lookup.clear_depth(), limit, entered) != ExactDda::Left::kOut) return hit;
    } else if (!stepper.advance(entered)) {
      return hit;
    }
  }
}

bool cast_ray_octomap(const OccupancyTree& tree, const Grid& grid, Vec3f origin, Vec3f direction, Vec3f& end,
                      bool ignore_unknown, double max_range) {
  const CastStart start = prepare(grid, Vec3d(origin), Vec3d(direction));
  const LogOddsThresholds& t = tree.thresholds();
  ExactDda stepper(grid, start.origin, start.origin_key, start.direction, ExactDda::HalfVoxel::kDouble);
  const bool limited = max_range > 0.0;
  const double max_range_squared = max_range * max_range;
  auto state_of = [&](Key key) { return t.classify(tree.find(morton::encode(key), 0).log_odds); };
  // The origin's own voxel first.
  end = grid.center_f(start.origin_key);
  const OccupancyState first = state_of(start.origin_key);
  if (first == OccupancyState::occupied) return true;
  if (first == OccupancyState::unknown && !ignore_unknown) return false;
  double entered = 0.0;
  for (;;) {
    if (!stepper.advance(entered)) return false;  // OctoMap: "hit bounds", end stays the last voxel
    end = grid.center_f(stepper.key());
    if (limited) {
      double distance_squared = 0.0;
      for (int axis = 0; axis < 3; ++axis) {
        const float d = end[axis] - origin[axis];
        distance_squared += d * d;  // float product, double sum, as OctoMap
      }
      if (distance_squared > max_range_squared) return false;
    }
    const OccupancyState state = state_of(stepper.key());
    if (state == OccupancyState::occupied) return true;
    if (state == OccupancyState::unknown && !ignore_unknown) return false;
  }
}

}  // namespace detail
}  // namespace umbra
