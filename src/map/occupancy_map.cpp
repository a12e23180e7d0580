#include "umbra/map/occupancy_map.hpp"

#include <chrono>
#include <cmath>
#include <mutex>
#include <stdexcept>
#include <string>

#include "tree/make_node.hpp"
#include "map/map_decay.hpp"
#include "map/map_state.hpp"
#include "map/map_window.hpp"

namespace umbra {

void MapConfig::validate() const {
  Grid(resolution, depth_levels);  // throws for a bad resolution or depth
  sensor.validate();
  thresholds.validate();
}

namespace {

const MapConfig& validated(const MapConfig& config) {
  config.validate();
  return config;
}

/// A change that readers must not see half done: the map's writer, with the
/// gate closed. A thread that is itself reading the map (an open query
/// range) would wait for itself: it gets std::logic_error before it waits.
template <typename Change>
decltype(auto) exclusively(detail::MapState& state, Change&& change) {
  if (state.gate.held_by_this_thread()) state.gate.close();  // throws the logic_error
  std::lock_guard writer(state.writer);
  detail::ClosedGate closed(state.gate);
  return std::forward<Change>(change)();
}

template <typename Read>
decltype(auto) reading(const detail::MapState& state, Read&& read) {
  detail::ReadLock lock(state.gate);
  return std::forward<Read>(read)();
}

void require_finite(float value, const char* what) {
  if (!std::isfinite(value)) {
    throw std::invalid_argument(std::string(what) + " must be finite, got " + std::to_string(value));
  }
}

void require_color(bool has_color) {
  if (!has_color) throw std::logic_error("the map was made without color (MapConfig::color)");
}

void check_depth(const Grid& grid, int depth) {
  if (depth < 0 || depth > grid.depth_levels()) {
    throw std::out_of_range("depth " + std::to_string(depth) + " is outside [0, " +
                            std::to_string(grid.depth_levels()) + "]");
  }
}

void check_key(const Grid& grid, Key key) {
  const std::uint32_t limit = grid.keys_per_axis();
  if (key.x >= limit || key.y >= limit || key.z >= limit) {
    throw std::out_of_range("key (" + std::to_string(key.x) + ", " + std::to_string(key.y) + ", " +
                            std::to_string(key.z) + ") is outside [0, " + std::to_string(limit) + ")");
  }
}

}  // namespace

OccupancyMap::OccupancyMap(const MapConfig& config)
    : grid_(validated(config).resolution, config.depth_levels),
      color_(config.color),
      state_(std::make_unique<detail::MapState>(config.depth_levels, config.sensor, config.thresholds, config.color)) {}

OccupancyMap::OccupancyMap(double resolution, int depth_levels, const SensorModel& sensor,
                           const Thresholds& thresholds)
    : OccupancyMap(MapConfig{resolution, depth_levels, sensor, thresholds, false}) {}

OccupancyMap::~OccupancyMap() = default;
OccupancyMap::OccupancyMap(OccupancyMap&& other) noexcept = default;
OccupancyMap& OccupancyMap::operator=(OccupancyMap&& other) noexcept = default;

OccupancyMap::OccupancyMap(const OccupancyMap& other) : grid_(other.grid_), color_(other.color_) {
  reading(*other.state_, [&] {
    const detail::MapState& from = *other.state_;
    state_ = std::make_unique<detail::MapState>(grid_.depth_levels(), from.sensor, from.thresholds, color_);
    state_->tree = from.tree;
    state_->bounding_box = from.bounding_box;
    state_->decay = from.decay;
    state_->decay_keys = from.decay_keys;
    state_->clock = from.clock;
    state_->decay_totals = from.decay_totals;
  });
}

OccupancyMap& OccupancyMap::operator=(const OccupancyMap& other) {
  if (this != &other) *this = OccupancyMap(other);
  return *this;
}

MapConfig OccupancyMap::config() const {
  return reading(*state_, [&] {
    return MapConfig{grid_.resolution(), grid_.depth_levels(), state_->sensor, state_->thresholds, color_};
  });
}

// --- sensor model and thresholds ------------------------------------------------

SensorModel OccupancyMap::sensor_model() const {
  return reading(*state_, [&] { return state_->sensor; });
}

void OccupancyMap::set_sensor_model(const SensorModel& sensor) {
  sensor.validate();
  exclusively(*state_, [&] {
    state_->sensor = sensor;
    state_->tree.set_range(LogOddsRange::from(sensor));
    state_->journal->record_everything();  // clamping may change states
  });
}

Thresholds OccupancyMap::thresholds() const {
  return reading(*state_, [&] { return state_->thresholds; });
}

void OccupancyMap::set_thresholds(const Thresholds& thresholds) {
  thresholds.validate();
  exclusively(*state_, [&] {
    state_->thresholds = thresholds;
    state_->tree.set_thresholds(LogOddsThresholds::from(thresholds));
    state_->journal->record_everything();
  });
}

// --- single voxels ----------------------------------------------------------------

void OccupancyMap::update_hit(Vec3d coordinate) {
  const Key k = grid_.key(coordinate);
  exclusively(*state_, [&] {
    state_->tree.update(morton::encode(k), state_->sensor.hit_log_odds());
    state_->journal->record(morton::encode(k), 0);
  });
}

void OccupancyMap::update_miss(Vec3d coordinate) {
  const Key k = grid_.key(coordinate);
  exclusively(*state_, [&] {
    state_->tree.update(morton::encode(k), state_->sensor.miss_log_odds());
    state_->journal->record(morton::encode(k), 0);
  });
}

void OccupancyMap::update_log_odds(Vec3d coordinate, float delta) { update_key_log_odds(grid_.key(coordinate), delta); }

void OccupancyMap::set_log_odds(Vec3d coordinate, float log_odds) { set_key_log_odds(grid_.key(coordinate), log_odds); }

void OccupancyMap::update_key_log_odds(Key key, float delta) {
  require_finite(delta, "log-odds delta");
  check_key(grid_, key);
  exclusively(*state_, [&] {
    state_->tree.update(morton::encode(key), delta);
    state_->journal->record(morton::encode(key), 0);
  });
}

void OccupancyMap::set_key_log_odds(Key key, float log_odds) {
  require_finite(log_odds, "log-odds value");
  check_key(grid_, key);
  exclusively(*state_, [&] {
    state_->tree.set(morton::encode(key), log_odds);
    state_->journal->record(morton::encode(key), 0);
  });
}

// --- color -------------------------------------------------------------------------

std::optional<Rgb> OccupancyMap::color(Vec3d coordinate, int depth) const { return node(coordinate, depth).color; }

void OccupancyMap::add_color(Vec3d coordinate, Rgb rgb) {
  require_color(color_);
  const Key k = grid_.key(coordinate);
  exclusively(*state_, [&] { state_->tree.add_color(morton::encode(k), rgb); });
}

void OccupancyMap::set_color(Key key, Rgb rgb) {
  require_color(color_);
  check_key(grid_, key);
  exclusively(*state_, [&] { state_->tree.set_color(morton::encode(key), rgb); });
}

// --- bounding box -------------------------------------------------------------------

void OccupancyMap::set_bounding_box(const std::optional<Aabb>& box) {
  if (box) box->validate();
  exclusively(*state_, [&] { state_->bounding_box = box; });
}

std::optional<Aabb> OccupancyMap::bounding_box() const {
  return reading(*state_, [&] { return state_->bounding_box; });
}

// --- inserting ----------------------------------------------------------------------

InsertStats OccupancyMap::insert_point_cloud(Vec3f origin, std::span<const Vec3f> points,
                                             const InsertOptions& options) {
  return insert_point_cloud(origin, points, {}, options);
}

namespace {

/// One scan: with a moving window that follows scans, the window's move to
/// `sensor` (its own exclusive phase); with a stamp, the clock's advance
/// (decay toward unknown, its own exclusive phase). `check` first throws
/// for what trace would refuse, so that a refused scan leaves the map
/// unchanged. Then `trace(box)` (which only reads the tree: readers go on
/// meanwhile) with the box the scan is clipped to, then the apply phase.
template <typename Check, typename Trace>
InsertStats insert_scan(detail::MapState& state, const Grid& grid, Vec3d sensor, const std::optional<double>& stamp,
                        unsigned threads, Check&& check, Trace&& trace) {
  if (state.gate.held_by_this_thread()) state.gate.close();  // throws: this thread is reading the map
  std::lock_guard writer(state.writer);
  const bool follow = state.window && state.window->follow_scans;
  if (stamp || follow) std::forward<Check>(check)();
  // The move first: if its spill throws, nothing has changed yet.
  if (follow) detail::move_window_locked(state, grid, grid.key(sensor));
  // The decay step runs on the scan's threads.
  if (stamp) detail::advance_clock_locked(state, *stamp, state.integrator.workers(threads));
  const detail::InsertionBox box = detail::insertion_box(state, grid);
  if (box.empty) return InsertStats{};  // the bounding box and the window do not meet
  InsertStats stats = std::forward<Trace>(trace)(box.box);
  {
    const auto start = std::chrono::steady_clock::now();
    detail::ClosedGate closed(state.gate);
    for (const UpdateBatch* batch : state.integrator.pending_batches()) state.journal->record_batch(*batch);
    state.integrator.apply(state.tree, state.sensor);
    stats.exclusive_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  state.integrator_bytes.store(state.integrator.memory_bytes(), std::memory_order_relaxed);
  return stats;
}

}  // namespace

InsertStats OccupancyMap::insert_point_cloud(Vec3f origin, std::span<const Vec3f> points,
                                             std::span<const Rgb> colors, const InsertOptions& options) {
  if (!colors.empty() && !color_) {
    throw std::invalid_argument("colors given, but the map was made without color (MapConfig::color)");
  }
  if (!colors.empty() && colors.size() != points.size()) {
    throw std::invalid_argument("colors given for " + std::to_string(colors.size()) + " points, the scan has " +
                                std::to_string(points.size()));
  }
  detail::MapState& state = *state_;
  const auto check = [&] {
    options.validate(grid_.depth_levels());
    if (!origin.is_finite()) throw std::invalid_argument("sensor origin is not finite");
    static_cast<void>(grid_.key(Vec3d(origin)));  // throws std::out_of_range outside the map
  };
  return insert_scan(state, grid_, Vec3d(origin), options.stamp, options.threads, check, [&](const std::optional<Aabb>& box) {
    return state.integrator.trace(state.tree, grid_, origin, points, colors, options, box);
  });
}

InsertStats OccupancyMap::insert_depth_image(const DepthImage& depth, const PinholeCamera& camera, const Pose& pose,
                                             std::span<const Rgb> colors, const InsertOptions& options) {
  if (!colors.empty() && !color_) {
    throw std::invalid_argument("colors given, but the map was made without color (MapConfig::color)");
  }
  detail::MapState& state = *state_;
  const auto check = [&] {
    options.validate(grid_.depth_levels());
    camera.validate();
    if (!colors.empty() && colors.size() != depth.pixel_count()) {
      throw std::invalid_argument("one color per pixel expected: " + std::to_string(colors.size()) + " colors, " +
                                  std::to_string(depth.pixel_count()) + " pixels");
    }
    if (!pose.is_rigid()) throw std::invalid_argument("the camera pose must be a rotation and a translation");
    static_cast<void>(grid_.key(Vec3d(pose.translation())));  // throws std::out_of_range outside the map
  };
  return insert_scan(state, grid_, Vec3d(pose.translation()), options.stamp, options.threads, check, [&](const std::optional<Aabb>& box) {
    return state.integrator.trace_image(state.tree, grid_, depth, camera, pose, colors, options, box);
  });
}

// --- reading ------------------------------------------------------------------------

Node OccupancyMap::node(Key key, int depth) const {
  check_depth(grid_, depth);
  check_key(grid_, key);
  const std::uint64_t code = morton::encode(key);
  return reading(*state_, [&] {
    const OccupancyTree& tree = state_->tree;
    return detail::make_node(tree, grid_, tree.find(code, depth).node, code);
  });
}

Node OccupancyMap::node(Vec3d coordinate, int depth) const {
  check_depth(grid_, depth);
  return node(grid_.key(coordinate), depth);
}

OccupancyState OccupancyMap::state(Vec3d coordinate, int depth) const { return node(coordinate, depth).state; }

float OccupancyMap::log_odds(Vec3d coordinate, int depth) const { return node(coordinate, depth).log_odds; }

double OccupancyMap::occupancy(Vec3d coordinate, int depth) const { return probability(log_odds(coordinate, depth)); }

bool OccupancyMap::contains_occupied(Vec3d coordinate, int depth) const {
  return node(coordinate, depth).contains_occupied();
}

bool OccupancyMap::contains_free(Vec3d coordinate, int depth) const { return node(coordinate, depth).contains_free; }

bool OccupancyMap::contains_unknown(Vec3d coordinate, int depth) const {
  return node(coordinate, depth).contains_unknown;
}

void OccupancyMap::for_each_leaf(FunctionRef<void(const Node&)> visit) const {
  reading(*state_, [&] {
    const OccupancyTree& tree = state_->tree;
    tree.for_each_leaf([&](NodeRef ref, std::uint64_t code) { visit(detail::make_node(tree, grid_, ref, code)); });
  });
}

// --- pruning ------------------------------------------------------------------------

void OccupancyMap::set_auto_prune(bool on) {
  exclusively(*state_, [&] { state_->tree.set_auto_prune(on); });
}

bool OccupancyMap::auto_prune() const {
  return reading(*state_, [&] { return state_->tree.auto_prune(); });
}

void OccupancyMap::prune() {
  exclusively(*state_, [&] { state_->tree.prune(); });
}

void OccupancyMap::clear() {
  exclusively(*state_, [&] {
    state_->tree.clear();
    state_->journal->record_everything();
  });
}

// --- statistics ---------------------------------------------------------------------

NodeCounts OccupancyMap::node_counts() const {
  return reading(*state_, [&] { return state_->tree.count_nodes(); });
}

std::size_t OccupancyMap::memory_bytes() const {
  const std::size_t tree_bytes =
      reading(*state_, [&] { return state_->tree.memory_bytes() + state_->journal->memory_bytes(); });
  return sizeof(*this) + sizeof(detail::MapState) - sizeof(state_->tree) - sizeof(state_->integrator) + tree_bytes +
         state_->integrator_bytes.load(std::memory_order_relaxed);
}

}  // namespace umbra
