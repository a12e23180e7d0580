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

namespace {

/// The colour samples of a scan: the points that give a hit, in scan order,
/// then stably sorted by voxel (so each voxel blends its samples in order).
std::vector<OccupancyTree::ColorSample> color_samples(const Grid& grid, Vec3f origin, std::span<const Vec3f> points,
                                                      std::span<const Rgb> colors, const InsertOptions& options) {
  std::vector<OccupancyTree::ColorSample> samples;
  samples.reserve(points.size());
  const bool limited = options.max_range > 0.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].is_finite()) continue;
    const std::optional<Key> key = grid.key_checked(points[i]);
    if (!key) continue;
    // The hit is decided by the end point the ray goes to: the point itself,
    // or the centre of its voxel for the discrete integrator.
    const Vec3f end = options.integrator == IntegratorKind::discrete ? grid.center_f(*key) : points[i];
    if (limited && octomap_norm(end - origin) > options.max_range) continue;
    samples.push_back({morton::encode(*key), colors[i]});
  }
  std::stable_sort(samples.begin(), samples.end(),
                   [](const OccupancyTree::ColorSample& a, const OccupancyTree::ColorSample& b) { return a.code < b.code; });
  return samples;
}

}  // namespace

InsertStats Integrator::insert(OccupancyTree& tree, const Grid& grid, const SensorModel& sensor,
                               Vec3f origin, std::span<const Vec3f> points, std::span<const Rgb> colors,
                               const InsertOptions& options) {
  if (!colors.empty() && colors.size() != points.size()) {
    throw std::invalid_argument("one colour per point expected: " + std::to_string(colors.size()) + " colours, " +
                                std::to_string(points.size()) + " points");
  }
  if (!colors.empty() && !tree.has_color()) throw std::invalid_argument("colours given to a map without colour");
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
  if (!colors.empty()) tree.add_colors(color_samples(grid, origin, points, colors, options));
  return stats;
}

void Integrator::trace(const Grid& grid, Vec3f origin, std::span<const Vec3f> points, double max_range,
                       InsertStats& stats) {
  const bool limited = max_range > 0.0;
  const Key origin_key = grid.key(Vec3d(origin));  // checked by insert()
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
      if (const std::optional<Key> end_key = grid.key_checked(end)) {
        add_ray_misses(grid, origin, origin_key, end, *end_key);
      } else {
        ++stats.out_of_bounds;
      }
      continue;
    }
    const std::optional<Key> end_key = grid.key_checked(p);
    if (!end_key) {
      ++stats.out_of_bounds;
      continue;
    }
    ++stats.rays;
    add_ray_misses(grid, origin, origin_key, p, *end_key);
    batch_.add_hit(morton::encode(*end_key));
    ++stats.hits;
  }
}

void Integrator::add_ray_misses(const Grid& grid, Vec3f origin, Key origin_key, Vec3f end, Key end_key) {
  // A walk takes at most one step per key along the way, plus at most one
  // overshoot per axis where rounding makes it miss the end voxel.
  std::size_t steps = 4;
  for (int axis = 0; axis < 3; ++axis) {
    steps += origin_key[axis] > end_key[axis] ? origin_key[axis] - end_key[axis] : end_key[axis] - origin_key[axis];
  }
  if (runs_.size() < steps + 1) runs_.resize(steps + 1);
  // Append to the current run or start a new one, without a branch on which:
  // whether the brick changes is hard to predict (measured 17% faster than
  // handing over each run as soon as the walk leaves its brick).
  BrickRun* runs = runs_.data();
  runs[0] = {~std::uint64_t{0}, 0};  // no code lies in this brick
  std::size_t last = 0;
  walk_ray(grid, origin, origin_key, end, end_key, [&](std::uint64_t code) {
    const bool same_brick = ((code ^ runs[last].code) >> 6) == 0;
    last += same_brick ? 0 : 1;
    const std::uint64_t earlier = same_brick ? runs[last].voxels : 0;
    runs[last] = {code, earlier | (std::uint64_t{1} << (code & 63))};
  });
  for (std::size_t i = 1; i <= last; ++i) batch_.add_misses_in_brick(runs[i].code, runs[i].voxels);
}

}  // namespace umbra
