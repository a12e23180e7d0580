#include "field_clearance.hpp"

#include <algorithm>
#include <stdexcept>

namespace umbra::explore {

namespace {
/// Metres kept off every comparison: a case this close is the map's to decide.
constexpr double kMargin = 1e-6;
}  // namespace

namespace {
DistanceFieldOptions field_options(double max_distance) {
  DistanceFieldOptions options;
  options.max_distance = max_distance;  // the whole known space, no box: checks range over the whole plant
  return options;
}
}  // namespace

FieldClearance::FieldClearance(const OccupancyMap& map, double max_distance)
    : map_(map),
      field_(map, field_options(max_distance)),
      max_distance_(max_distance),
      // A quarter voxel: a capsule that grazes a surface would otherwise
      // take hundreds of tiny steps; the map's check is cheaper then.
      min_step_(0.25 * map.resolution()) {}

FieldClearance::Verdict FieldClearance::ball(Vec3d p, double r, double& slack) const {
  slack = 0.0;
  const std::optional<Key> key = map_.grid().key_checked(p);
  if (!key) return Verdict::unsure;  // outside the map: the map's check says so
  const double e = (p - map_.grid().center(*key)).norm();
  field_queries_.fetch_add(1, std::memory_order_relaxed);
  const double d = field_.distance(p);
  slack = d - e - r;
  if (slack > kMargin) return Verdict::free;
  // A capped distance is a lower bound only: it proves nothing blocked.
  if (d < max_distance_ - kMargin && d + e <= r - kMargin) return Verdict::blocked;
  return Verdict::unsure;
}

bool FieldClearance::is_free(const Sphere& ball_shape) const {
  double slack = 0.0;
  const Verdict verdict = ball(ball_shape.center, ball_shape.radius, slack);
  if (verdict != Verdict::unsure) {
    balls_by_field_.fetch_add(1, std::memory_order_relaxed);
    return verdict == Verdict::free;
  }
  balls_by_map_.fetch_add(1, std::memory_order_relaxed);
  return map_.is_free(ball_shape).free;
}

bool FieldClearance::is_free(const Capsule& path) const {
  const Vec3d along = path.b - path.a;
  const double length = along.norm();
  // The stretch [0, covered] of the segment is proven clear. A point p at
  // covered with slack s clears every point within s of it (on both sides),
  // so the next point is at covered + s: the stretches stay joined.
  double covered = 0.0;
  for (;;) {
    const Vec3d p = length > 0.0 ? path.a + along * (covered / length) : path.a;
    double slack = 0.0;
    const Verdict verdict = ball(p, path.radius, slack);
    if (verdict == Verdict::blocked) {
      capsules_by_field_.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    // `unsure` leaves slack <= kMargin, so it falls here too.
    const double step = slack - kMargin;
    if (step < min_step_) {
      capsules_by_map_.fetch_add(1, std::memory_order_relaxed);
      return map_.is_free(path).free;
    }
    covered += step;
    if (covered >= length) break;
  }
  capsules_by_field_.fetch_add(1, std::memory_order_relaxed);
  return true;
}

ClearanceCounts FieldClearance::counts() const {
  return {balls_by_field_.load(std::memory_order_relaxed), balls_by_map_.load(std::memory_order_relaxed),
          capsules_by_field_.load(std::memory_order_relaxed), capsules_by_map_.load(std::memory_order_relaxed),
          field_queries_.load(std::memory_order_relaxed)};
}

}  // namespace umbra::explore
