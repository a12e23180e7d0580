// OccupancyMap: the map users hold.
//
// It ties together the voxel grid (resolution, depth levels), the sensor
// model and thresholds, the octree, and the integrator that inserts scans.
// Every query takes a depth (0 = finest voxel; larger = coarser, up to
// depth_levels() = the root). Coordinates are metres in the map frame.
//
//   umbra::OccupancyMap map(0.05);                   // 5 cm voxels, 16 depth levels
//   map.insert_point_cloud(origin, points);          // one scan
//   if (map.state({1.0, 2.0, 0.5}) == umbra::OccupancyState::free) ...
//   if (!map.contains_occupied({1.0, 2.0, 0.5}, 4)) ...  // 80 cm block is obstacle-free
//
// Errors: a coordinate outside the map throws std::out_of_range, a bad
// parameter std::invalid_argument, each with a message naming the value.
// Thread safety: const functions may run concurrently; writers need exclusive access.
#pragma once

#include <concepts>
#include <cstdint>
#include <optional>
#include <span>

#include "umbra/core/color.hpp"
#include "umbra/core/grid.hpp"
#include "umbra/core/log_odds.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/integrate/integrator.hpp"
#include "umbra/tree/occupancy_tree.hpp"

namespace umbra {

/// Everything that defines a map besides its contents.
struct MapConfig {
  double resolution = 0.1;  ///< metres, edge of a finest voxel
  int depth_levels = 16;    ///< 1..21; 16 is OctoMap's depth
  SensorModel sensor;
  Thresholds thresholds;
  bool color = false;       ///< keep an RGB colour per voxel

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

/// One childless node, as visited by for_each_leaf.
struct LeafView {
  Key key;          ///< finest key of the node's first (lowest) voxel
  int depth;        ///< 0 for a voxel, > 0 for an inner leaf covering 8^depth voxels
  float log_odds;
  OccupancyState state;
  std::optional<Rgb> color;  ///< only in a map with colour, for coloured nodes
};

class OccupancyMap {
 public:
  explicit OccupancyMap(const MapConfig& config);
  /// A map without colour.
  explicit OccupancyMap(double resolution, int depth_levels = 16, const SensorModel& sensor = {},
                        const Thresholds& thresholds = {});

  // --- geometry -----------------------------------------------------------
  [[nodiscard]] const Grid& grid() const { return grid_; }
  [[nodiscard]] double resolution() const { return grid_.resolution(); }
  [[nodiscard]] int depth_levels() const { return grid_.depth_levels(); }
  [[nodiscard]] MapConfig config() const;
  /// Finest key of a coordinate; throws std::out_of_range outside the map.
  [[nodiscard]] Key key(Vec3d coordinate) const { return grid_.key(coordinate); }

  // --- sensor model and thresholds ----------------------------------------
  [[nodiscard]] const SensorModel& sensor_model() const { return sensor_; }
  /// Applies to future updates; stored values outside the new clamping range
  /// are clamped into it (OctoMap would leave them until their next update).
  void set_sensor_model(const SensorModel& sensor);
  [[nodiscard]] const Thresholds& thresholds() const { return thresholds_; }
  /// Changes the occupied / free thresholds; every indicator is updated at once.
  void set_thresholds(const Thresholds& thresholds);

  // --- updating single voxels ---------------------------------------------
  void update_hit(Vec3d coordinate) { update_log_odds(coordinate, sensor_.hit_log_odds()); }
  void update_miss(Vec3d coordinate) { update_log_odds(coordinate, sensor_.miss_log_odds()); }
  /// Adds `delta` (then clamps). Throws std::invalid_argument if delta is not finite.
  void update_log_odds(Vec3d coordinate, float delta);
  /// Sets the voxel's log-odds (clamped). Throws std::invalid_argument if not finite.
  void set_log_odds(Vec3d coordinate, float log_odds);
  // The Key overloads are templates taking exactly a Key, so that a braced
  // coordinate such as map.set_log_odds({1.0, 2.0, 0.5}, 0.4f) is a Vec3d and
  // not an ambiguous call (a Key is also a brace of three numbers).
  template <std::same_as<Key> K>
  void update_log_odds(K key, float delta) { update_key_log_odds(key, delta); }
  template <std::same_as<Key> K>
  void set_log_odds(K key, float log_odds) { set_key_log_odds(key, log_odds); }

  // --- colour (maps made with MapConfig::color) ---------------------------
  [[nodiscard]] bool has_color() const { return tree_.has_color(); }
  /// Colour of the depth-`depth` node containing the coordinate: a voxel's
  /// running average of the points that fell in it, a coarser node's the
  /// average of its coloured children; nothing when uncoloured.
  [[nodiscard]] std::optional<Rgb> color(Vec3d coordinate, int depth = 0) const;
  template <std::same_as<Key> K>
  [[nodiscard]] std::optional<Rgb> color(K key, int depth = 0) const { return key_color(key, depth); }
  /// One more colour sample for the voxel (running average).
  void add_color(Vec3d coordinate, Rgb rgb);
  /// Sets the voxel's colour outright.
  void set_color(Key key, Rgb rgb);

  // --- bounding box ---------------------------------------------------------
  /// Limits future insertions to a box: rays are clipped to it and only its
  /// voxels change (points outside still clear the space inside). Nothing: no
  /// limit. Throws std::invalid_argument for a box with min > max.
  void set_bounding_box(const std::optional<Aabb>& box);
  [[nodiscard]] const std::optional<Aabb>& bounding_box() const { return bounding_box_; }

  // --- inserting scans ----------------------------------------------------
  /// Integrates one scan (see integrate/integrator.hpp for the exact rules).
  InsertStats insert_point_cloud(Vec3f origin, std::span<const Vec3f> points,
                                 const InsertOptions& options = {});
  /// The same with one colour per point: every point that gives a hit adds
  /// its colour to its voxel. Throws std::invalid_argument when the map has
  /// no colour or the sizes differ.
  InsertStats insert_point_cloud(Vec3f origin, std::span<const Vec3f> points, std::span<const Rgb> colors,
                                 const InsertOptions& options = {});

  // --- reading ------------------------------------------------------------
  /// State of the depth-`depth` node containing the coordinate: occupied if
  /// any voxel in it is, free if all are, unknown otherwise.
  [[nodiscard]] OccupancyState state(Vec3d coordinate, int depth = 0) const;
  [[nodiscard]] float log_odds(Vec3d coordinate, int depth = 0) const;
  /// Probability of the node (the maximum over its voxels).
  [[nodiscard]] double occupancy(Vec3d coordinate, int depth = 0) const;
  [[nodiscard]] bool contains_occupied(Vec3d coordinate, int depth = 0) const;
  [[nodiscard]] bool contains_free(Vec3d coordinate, int depth = 0) const;
  [[nodiscard]] bool contains_unknown(Vec3d coordinate, int depth = 0) const;
  [[nodiscard]] NodeSummary node(Key key, int depth = 0) const;

  /// Calls visit(const LeafView&) for every childless node, in Morton order.
  template <typename Visit>
  void for_each_leaf(Visit&& visit) const {
    tree_.for_each_leaf([&](NodeRef node, std::uint64_t code) {
      const float value = tree_.log_odds(node);
      visit(LeafView{morton::decode(code), node.depth, value, tree_.thresholds().classify(value), tree_.color(node)});
    });
  }

  // --- pruning ------------------------------------------------------------
  /// On by default. Switch off while readers iterate during insertion;
  /// switching it on again prunes the whole map.
  void set_auto_prune(bool on) { tree_.set_auto_prune(on); }
  [[nodiscard]] bool auto_prune() const { return tree_.auto_prune(); }
  void prune() { tree_.prune(); }
  void clear() { tree_.clear(); }

  // --- statistics ---------------------------------------------------------
  [[nodiscard]] NodeCounts node_counts() const { return tree_.count_nodes(); }
  /// Bytes allocated for the map (the tree's capacity, and this object).
  [[nodiscard]] std::size_t memory_bytes() const;

  /// The octree itself, for file readers/writers and tests.
  [[nodiscard]] const OccupancyTree& tree() const { return tree_; }
  [[nodiscard]] OccupancyTree& tree() { return tree_; }

 private:
  void check_depth(int depth) const;
  [[nodiscard]] NodeSummary summary(Vec3d coordinate, int depth) const;
  void update_key_log_odds(Key key, float delta);
  void set_key_log_odds(Key key, float log_odds);
  [[nodiscard]] std::optional<Rgb> key_color(Key key, int depth) const;

  Grid grid_;
  SensorModel sensor_;
  Thresholds thresholds_;
  OccupancyTree tree_;
  Integrator integrator_;
  std::optional<Aabb> bounding_box_;
};

}  // namespace umbra
