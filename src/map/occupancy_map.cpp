#include "umbra/map/occupancy_map.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace umbra {

void MapConfig::validate() const {
  Grid(resolution, depth_levels);  // throws for a bad resolution or depth
  sensor.validate();
  thresholds.validate();
}

OccupancyMap::OccupancyMap(const MapConfig& config)
    : grid_(config.resolution, config.depth_levels),
      sensor_((config.sensor.validate(), config.sensor)),
      thresholds_((config.thresholds.validate(), config.thresholds)),
      tree_(config.depth_levels, LogOddsRange::from(config.sensor), LogOddsThresholds::from(config.thresholds),
            config.color),
      integrator_() {}

OccupancyMap::OccupancyMap(double resolution, int depth_levels, const SensorModel& sensor,
                           const Thresholds& thresholds)
    : OccupancyMap(MapConfig{resolution, depth_levels, sensor, thresholds, false}) {}

MapConfig OccupancyMap::config() const {
  return {grid_.resolution(), grid_.depth_levels(), sensor_, thresholds_, tree_.has_color()};
}

void OccupancyMap::set_sensor_model(const SensorModel& sensor) {
  sensor.validate();
  sensor_ = sensor;
  tree_.set_range(LogOddsRange::from(sensor));
}

void OccupancyMap::set_thresholds(const Thresholds& thresholds) {
  thresholds.validate();
  thresholds_ = thresholds;
  tree_.set_thresholds(LogOddsThresholds::from(thresholds));
}

namespace {
void require_finite(float value, const char* what) {
  if (!std::isfinite(value)) {
    throw std::invalid_argument(std::string(what) + " must be finite, got " + std::to_string(value));
  }
}
}  // namespace

void OccupancyMap::update_log_odds(Vec3d coordinate, float delta) {
  update_key_log_odds(grid_.key(coordinate), delta);
}

void OccupancyMap::set_log_odds(Vec3d coordinate, float log_odds) {
  set_key_log_odds(grid_.key(coordinate), log_odds);
}

void OccupancyMap::update_key_log_odds(Key key, float delta) {
  require_finite(delta, "log-odds delta");
  tree_.update(morton::encode(key), delta);
}

void OccupancyMap::set_key_log_odds(Key key, float log_odds) {
  require_finite(log_odds, "log-odds value");
  tree_.set(morton::encode(key), log_odds);
}

InsertStats OccupancyMap::insert_point_cloud(Vec3f origin, std::span<const Vec3f> points,
                                             const InsertOptions& options) {
  return integrator_.insert(tree_, grid_, sensor_, origin, points, {}, options, bounding_box_);
}

InsertStats OccupancyMap::insert_point_cloud(Vec3f origin, std::span<const Vec3f> points,
                                             std::span<const Rgb> colors, const InsertOptions& options) {
  if (!colors.empty() && !has_color()) {
    throw std::invalid_argument("colours given, but the map was made without colour (MapConfig::color)");
  }
  if (!colors.empty() && colors.size() != points.size()) {
    throw std::invalid_argument("colours given for " + std::to_string(colors.size()) + " points, the scan has " +
                                std::to_string(points.size()));
  }
  return integrator_.insert(tree_, grid_, sensor_, origin, points, colors, options, bounding_box_);
}

void OccupancyMap::set_bounding_box(const std::optional<Aabb>& box) {
  if (box) box->validate();
  bounding_box_ = box;
}

namespace {
void require_color(const OccupancyMap& map) {
  if (!map.has_color()) throw std::logic_error("the map was made without colour (MapConfig::color)");
}
}  // namespace

std::optional<Rgb> OccupancyMap::color(Vec3d coordinate, int depth) const {
  return tree_.color(summary(coordinate, depth).node);
}

std::optional<Rgb> OccupancyMap::key_color(Key key, int depth) const { return tree_.color(node(key, depth).node); }

void OccupancyMap::add_color(Vec3d coordinate, Rgb rgb) {
  require_color(*this);
  tree_.add_color(morton::encode(grid_.key(coordinate)), rgb);
}

void OccupancyMap::set_color(Key key, Rgb rgb) {
  require_color(*this);
  (void)node(key, 0);  // checks the key
  tree_.set_color(morton::encode(key), rgb);
}

void OccupancyMap::check_depth(int depth) const {
  if (depth < 0 || depth > grid_.depth_levels()) {
    throw std::out_of_range("depth " + std::to_string(depth) + " is outside [0, " +
                            std::to_string(grid_.depth_levels()) + "]");
  }
}

NodeSummary OccupancyMap::node(Key key, int depth) const {
  check_depth(depth);
  const std::uint32_t limit = grid_.keys_per_axis();
  if (key.x >= limit || key.y >= limit || key.z >= limit) {
    throw std::out_of_range("key (" + std::to_string(key.x) + ", " + std::to_string(key.y) + ", " +
                            std::to_string(key.z) + ") is outside [0, " + std::to_string(limit) + ")");
  }
  return tree_.find(morton::encode(key), depth);
}

NodeSummary OccupancyMap::summary(Vec3d coordinate, int depth) const {
  check_depth(depth);
  return tree_.find(morton::encode(grid_.key(coordinate)), depth);
}

OccupancyState OccupancyMap::state(Vec3d coordinate, int depth) const {
  const NodeSummary s = summary(coordinate, depth);
  const LogOddsThresholds& t = tree_.thresholds();
  if (t.is_occupied(s.log_odds)) return OccupancyState::occupied;
  // The value is the maximum: below the free threshold means every voxel is free.
  if (t.is_free(s.log_odds)) return OccupancyState::free;
  return OccupancyState::unknown;
}

float OccupancyMap::log_odds(Vec3d coordinate, int depth) const { return summary(coordinate, depth).log_odds; }

double OccupancyMap::occupancy(Vec3d coordinate, int depth) const {
  return probability(log_odds(coordinate, depth));
}

bool OccupancyMap::contains_occupied(Vec3d coordinate, int depth) const {
  return tree_.thresholds().is_occupied(summary(coordinate, depth).log_odds);
}

bool OccupancyMap::contains_free(Vec3d coordinate, int depth) const {
  return summary(coordinate, depth).contains_free;
}

bool OccupancyMap::contains_unknown(Vec3d coordinate, int depth) const {
  return summary(coordinate, depth).contains_unknown;
}

std::size_t OccupancyMap::memory_bytes() const {
  return sizeof(*this) - sizeof(tree_) - sizeof(integrator_) + tree_.memory_bytes() +
         integrator_.memory_bytes();
}

}  // namespace umbra
