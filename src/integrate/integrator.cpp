#include "umbra/integrate/integrator.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "umbra/integrate/ray_walker.hpp"

namespace umbra {

IntegratorKind parse_integrator_kind(const std::string& name) {
  if (name == "simple") return IntegratorKind::simple;
  if (name == "discrete") return IntegratorKind::discrete;
  throw std::invalid_argument("unknown integrator '" + name + "' (expected simple or discrete)");
}

const char* to_string(IntegratorKind kind) {
  return kind == IntegratorKind::simple ? "simple" : "discrete";
}

void InsertOptions::validate() const {
  if (std::isnan(max_range)) throw std::invalid_argument("max_range is NaN");
}

InsertStats& InsertStats::operator+=(const InsertStats& other) {
  points += other.points;
  rays += other.rays;
  hits += other.hits;
  truncated += other.truncated;
  non_finite += other.non_finite;
  out_of_bounds += other.out_of_bounds;
  return *this;
}

InsertStats Integrator::insert(OccupancyTree& tree, const Grid& grid, const SensorModel& sensor,
                               Vec3f origin, std::span<const Vec3f> points,
                               const InsertOptions& options) {
  options.validate();
  if (!origin.is_finite()) {
    throw std::invalid_argument("sensor origin is not finite: (" + std::to_string(origin.x) + ", " +
                                std::to_string(origin.y) + ", " + std::to_string(origin.z) + ")");
  }
  (void)grid.key(Vec3d(origin));  // throws std::out_of_range with the coordinate and the extent

  InsertStats stats;
  stats.points = points.size();
  batch_.reset(grid.depth_levels());

  if (options.integrator == IntegratorKind::simple) {
    trace(grid, origin, points, options.max_range, stats);
  } else {
    // One ray per end voxel, to the voxel centre (OctoMap's computeDiscreteUpdate).
    std::vector<std::uint64_t> end_codes;
    end_codes.reserve(points.size());
    for (const Vec3f& p : points) {
      if (!p.is_finite()) {
        ++stats.non_finite;
      } else if (auto key = grid.key_checked(p)) {
        end_codes.push_back(morton::encode(*key));
      } else {
        ++stats.out_of_bounds;
      }
    }
    // Sorting also orders the rays in Morton order of their ends, which keeps
    // consecutive rays on nearby paths in the batch.
    std::sort(end_codes.begin(), end_codes.end());
    end_codes.erase(std::unique(end_codes.begin(), end_codes.end()), end_codes.end());
    std::vector<Vec3f> centres;
    centres.reserve(end_codes.size());
    for (const std::uint64_t code : end_codes) centres.push_back(grid.center_f(morton::decode(code)));
    end_codes = {};
    trace(grid, origin, centres, options.max_range, stats);
  }

  tree.apply(batch_, sensor.hit_log_odds(), sensor.miss_log_odds());
  batch_.reset(grid.depth_levels());  // give the scan's scratch memory back
  return stats;
}

void Integrator::trace(const Grid& grid, Vec3f origin, std::span<const Vec3f> points,
                       double max_range, InsertStats& stats) {
  const bool limited = max_range > 0.0;
  UpdateBatch::MissCollector misses(batch_);
  auto add_miss = [&misses](std::uint64_t code) { misses.add(code); };
  for (const Vec3f& p : points) {
    if (!p.is_finite()) {
      ++stats.non_finite;
      continue;
    }
    const Vec3f offset = p - origin;
    const double range = octomap_norm(offset);
    if (limited && range > max_range) {
      // OctoMap: origin + normalized(direction) * (float)max_range, no hit.
      const auto length = static_cast<float>(range);
      const Vec3f direction =
          range > 0.0 ? Vec3f{offset.x / length, offset.y / length, offset.z / length} : offset;
      const Vec3f end = origin + direction * static_cast<float>(max_range);
      ++stats.truncated;
      ++stats.rays;
      if (!walk_ray(grid, origin, end, add_miss)) ++stats.out_of_bounds;
      continue;
    }
    const std::optional<Key> end_key = grid.key_checked(p);
    if (!end_key) {
      ++stats.out_of_bounds;
      continue;
    }
    ++stats.rays;
    walk_ray(grid, origin, p, add_miss);
    misses.flush();  // the batch must see this ray's misses before its hit moves the cached path
    batch_.add_hit(morton::encode(*end_key));
    ++stats.hits;
  }
}

}  // namespace umbra
