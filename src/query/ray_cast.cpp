// Ray casts (OccupancyMap::cast_ray and cast_ray_octomap).
//
// Both step through the voxels a ray passes exactly as OctoMap's castRay
// does (float origin and normalised float direction, double tMax/tDelta
// from the origin voxel's border, ties to the later axis), so that they hit
// the same voxel as OctoMap does on the same map. Looking voxels up goes
// through BlockingLookup: inside a node known to hold nothing that stops
// the ray, a step costs no lookup.
//
// cast_ray measures range along the ray (the distance at which it enters a
// voxel); cast_ray_octomap keeps OctoMap's rules: the origin voxel is
// checked first, the range is the distance to each voxel's centre, an
// unknown voxel ends an unsuccessful cast unless unknown space is ignored.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/assert.hpp"
#include "integrate/ray_walker.hpp"
#include "map/map_access.hpp"
#include "query/blocking_lookup.hpp"
#include "query/query_walk.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra {
namespace {

/// OctoMap's ray stepping state.
class RayStepper {
 public:
  RayStepper(const Grid& grid, Vec3f origin, Key origin_key, Vec3f direction)
      : key_{origin_key.x, origin_key.y, origin_key.z}, limit_(grid.keys_per_axis()) {
    for (int axis = 0; axis < 3; ++axis) {
      const float d = direction[axis];
      step_[axis] = d > 0.0f ? 1 : (d < 0.0f ? -1 : 0);
      if (step_[axis] != 0) {
        const double border = grid.axis_center(origin_key[axis]) + double(step_[axis] * grid.resolution() * 0.5);
        t_max_[axis] = (border - origin[axis]) / d;
        t_delta_[axis] = grid.resolution() / std::fabs(d);
      } else {
        t_max_[axis] = std::numeric_limits<double>::max();
        t_delta_[axis] = std::numeric_limits<double>::max();
      }
    }
  }

  [[nodiscard]] Key key() const {
    return {static_cast<std::uint32_t>(key_[0]), static_cast<std::uint32_t>(key_[1]),
            static_cast<std::uint32_t>(key_[2])};
  }

  /// Into the next voxel; false (staying put) at the map's edge. `entered`
  /// receives the ray parameter at which the ray enters it.
  bool advance(double& entered) {
    int dim;
    if (t_max_[0] < t_max_[1]) {
      dim = t_max_[0] < t_max_[2] ? 0 : 2;
    } else {
      dim = t_max_[1] < t_max_[2] ? 1 : 2;
    }
    const std::int64_t next = key_[dim] + step_[dim];
    // A step of 0 on the chosen axis: no axis is left to move along.
    if (step_[dim] == 0 || next < 0 || next >= limit_) return false;
    entered = t_max_[dim];
    key_[dim] = next;
    t_max_[dim] += t_delta_[dim];
    return true;
  }

 private:
  std::int64_t key_[3];
  std::int64_t limit_;
  int step_[3];
  double t_max_[3];
  double t_delta_[3];
};

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
  start.origin_key = grid.key(Vec3d(start.origin));  // throws std::out_of_range naming the coordinate
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

RayHit OccupancyMap::cast_ray(Vec3d origin, Vec3d direction, const RayCastOptions& options) const {
  if (std::isnan(options.max_range)) throw std::invalid_argument("ray cast: max_range is NaN");
  const CastStart start = prepare(grid_, origin, direction);
  return detail::MapAccess::read(*this, [&](const OccupancyTree& tree) {
    const detail::QueryScope scope = detail::scope_of(*this, options.depth);
    detail::BlockingLookup lookup(scope, {tree.thresholds(), options.stop_at_unknown});
    RayStepper stepper(grid_, start.origin, start.origin_key, start.direction);
    const bool limited = options.max_range > 0.0;
    double entered = 0.0;
    RayHit hit;
    for (;;) {
      if (limited && entered > options.max_range) return hit;
      const std::uint64_t code = morton::encode(stepper.key());
      NodeRef node{};
      if (lookup.blocks(code, &node)) {
        hit.hit = true;
        hit.node = detail::make_node(tree, grid_, node, code);
        hit.distance = entered;
        hit.point = Vec3d(start.origin) + Vec3d(start.direction) * entered;
        return hit;
      }
      if (!stepper.advance(entered)) return hit;
    }
  });
}

bool OccupancyMap::cast_ray_octomap(Vec3f origin, Vec3f direction, Vec3f& end, bool ignore_unknown,
                                    double max_range) const {
  const CastStart start = prepare(grid_, Vec3d(origin), Vec3d(direction));
  return detail::MapAccess::read(*this, [&](const OccupancyTree& tree) {
    const LogOddsThresholds& t = tree.thresholds();
    RayStepper stepper(grid_, start.origin, start.origin_key, start.direction);
    const bool limited = max_range > 0.0;
    const double max_range_squared = max_range * max_range;
    auto state_of = [&](Key key) { return t.classify(tree.find(morton::encode(key), 0).log_odds); };
    // The origin's own voxel first.
    end = grid_.center_f(start.origin_key);
    const OccupancyState first = state_of(start.origin_key);
    if (first == OccupancyState::occupied) return true;
    if (first == OccupancyState::unknown && !ignore_unknown) return false;
    double entered = 0.0;
    for (;;) {
      if (!stepper.advance(entered)) return false;  // OctoMap: "hit bounds", end stays the last voxel
      end = grid_.center_f(stepper.key());
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
  });
}

}  // namespace umbra
