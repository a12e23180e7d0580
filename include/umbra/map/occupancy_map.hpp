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
//
// Concurrency. Every member function may be called from any thread at any
// time; the map orders the calls itself:
//  - queries (const functions, and the ranges of query()) run concurrently
//    with each other and with insert_point_cloud. Each query sees the map as
//    it was after some whole scan: never half a scan, never a coarse node
//    that disagrees with its children.
//  - insert_point_cloud traces its rays while queries go on (tracing only
//    reads the map) and applies the traced scan in one short exclusive
//    phase: a query waits at most for one such phase.
//  - everything else that changes the map (single-voxel updates, colors,
//    prune(), set_auto_prune(), thresholds, sensor model, clear(), the box,
//    a decay step of advance_clock or a stamped scan, a move of the moving
//    window) is exclusive in the same way; two writers take turns.
//  - an open query range holds the map for reading until it is destroyed; a
//    thread that changes the map while it holds a range of its own gets
//    std::logic_error (it would wait for itself). Destroy a range on the
//    thread that made it.
// Nodes and results are values: they never point into the map. Moving or
// destroying the map itself while other threads use it is the caller's
// business, as for any object.
#pragma once

#include <concepts>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "umbra/core/aabb.hpp"
#include "umbra/core/color.hpp"
#include "umbra/core/function_ref.hpp"
#include "umbra/core/grid.hpp"
#include "umbra/core/log_odds.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/integrate/depth_image.hpp"
#include "umbra/integrate/insert_options.hpp"
#include "umbra/map/decay.hpp"
#include "umbra/map/moving_window.hpp"
#include "umbra/map/voxel_box.hpp"
#include "umbra/query/collision.hpp"
#include "umbra/query/information_gain.hpp"
#include "umbra/query/predicate.hpp"
#include "umbra/query/query_range.hpp"
#include "umbra/query/shapes.hpp"
#include "umbra/core/node.hpp"
#include "umbra/core/pose.hpp"
#include "umbra/map/map_merge.hpp"

namespace umbra {

namespace detail {
struct MapState;
class MapAccess;
}  // namespace detail

/// Everything that defines a map besides its contents.
struct MapConfig {
  double resolution = 0.1;  ///< metres, edge of a finest voxel
  int depth_levels = 16;    ///< 1..21; 16 is OctoMap's depth
  SensorModel sensor;
  Thresholds thresholds;
  bool color = false;       ///< keep an RGB color per voxel

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

class OccupancyMap {
 public:
  explicit OccupancyMap(const MapConfig& config);
  /// A map without color.
  explicit OccupancyMap(double resolution, int depth_levels = 16, const SensorModel& sensor = {},
                        const Thresholds& thresholds = {});
  ~OccupancyMap();
  /// A deep copy (the source is read as one consistent whole).
  OccupancyMap(const OccupancyMap& other);
  OccupancyMap& operator=(const OccupancyMap& other);
  OccupancyMap(OccupancyMap&& other) noexcept;
  OccupancyMap& operator=(OccupancyMap&& other) noexcept;

  // --- geometry (fixed for the map's life) ----------------------------------
  [[nodiscard]] const Grid& grid() const { return grid_; }
  [[nodiscard]] double resolution() const { return grid_.resolution(); }
  [[nodiscard]] int depth_levels() const { return grid_.depth_levels(); }
  [[nodiscard]] MapConfig config() const;
  /// Finest key of a coordinate; throws std::out_of_range outside the map.
  [[nodiscard]] Key key(Vec3d coordinate) const { return grid_.key(coordinate); }

  // --- sensor model and thresholds ----------------------------------------
  [[nodiscard]] SensorModel sensor_model() const;
  /// Applies to future updates; stored values outside the new clamping range
  /// are clamped into it (OctoMap would leave them until their next update).
  void set_sensor_model(const SensorModel& sensor);
  [[nodiscard]] Thresholds thresholds() const;
  /// Changes the occupied / free thresholds; every indicator is updated at once.
  void set_thresholds(const Thresholds& thresholds);

  // --- updating single voxels ---------------------------------------------
  void update_hit(Vec3d coordinate);
  void update_miss(Vec3d coordinate);
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

  // --- color (maps made with MapConfig::color) ---------------------------
  [[nodiscard]] bool has_color() const { return color_; }
  /// Color of the depth-`depth` node containing the coordinate: a voxel's
  /// running average of the points that fell in it, a coarser node's the
  /// average of its colored children; nothing when uncolored.
  [[nodiscard]] std::optional<Rgb> color(Vec3d coordinate, int depth = 0) const;
  template <std::same_as<Key> K>
  [[nodiscard]] std::optional<Rgb> color(K key, int depth = 0) const { return node(key, depth).color; }
  /// One more color sample for the voxel (running average).
  void add_color(Vec3d coordinate, Rgb rgb);
  /// Sets the voxel's color outright.
  void set_color(Key key, Rgb rgb);

  // --- bounding box ---------------------------------------------------------
  /// Limits future insertions to a box: rays are clipped to it and only its
  /// voxels change (points outside still clear the space inside). Nothing: no
  /// limit. Throws std::invalid_argument for a box with min > max.
  void set_bounding_box(const std::optional<Aabb>& box);
  [[nodiscard]] std::optional<Aabb> bounding_box() const;

  // --- decay toward unknown (umbra/map/decay.hpp; src/map/map_decay.cpp) ---
  /// How fast the map forgets: from now on every advance of the clock moves
  /// each voxel (in rates.region, if given) toward unknown by rate x the
  /// time advanced. Both rates 0 (the default): no decay. Throws
  /// std::invalid_argument for bad rates (DecayRates::validate) and
  /// std::out_of_range for a region wholly outside the map.
  void set_decay(const DecayRates& rates);
  [[nodiscard]] DecayRates decay() const;
  /// Advances the map's clock to `time` (seconds, any epoch) and decays the
  /// map by the time passed, in one step that readers see whole. The first
  /// time sets the clock without decay; a time earlier than the clock
  /// changes nothing (a late scan is inserted without decay). Scans with
  /// InsertOptions::stamp call it before they are inserted. Throws
  /// std::invalid_argument for a non-finite time.
  void advance_clock(double time);
  /// The clock's time; nothing before the first advance_clock or stamp.
  [[nodiscard]] std::optional<double> clock() const;

  // --- a map that moves (umbra/map/moving_window.hpp; src/map/map_window.cpp) ---
  /// Keeps only a box around the robot from now on (nothing: no limit; the
  /// map keeps what it holds). The box is placed by the next move_window, or
  /// by the next scan with window.follow_scans; until then scans are not
  /// limited. Setting a window forgets the box of an earlier one. Throws
  /// std::invalid_argument for a bad window (MovingWindow::validate).
  void set_moving_window(const std::optional<MovingWindow>& window);
  [[nodiscard]] std::optional<MovingWindow> moving_window() const;
  /// Re-centres the box on `position` (the robot): when the step holding it
  /// changed, the voxels that leave the box go to window.spill and are then
  /// forgotten (unknown, nodes freed), in one exclusive phase that readers
  /// see whole; the first call places the box and does the same for
  /// everything outside it. Throws std::logic_error without a window,
  /// std::out_of_range for a position outside the map, and what spill
  /// throws (the map is then unchanged).
  WindowMove move_window(Vec3d position);
  /// The window's box as keys; nothing before it is placed or without a window.
  [[nodiscard]] std::optional<VoxelBox> window_box() const;

  // --- inserting scans ----------------------------------------------------
  /// Integrates one scan. Simple and discrete integrators: OctoMap's
  /// insertPointCloud (discretize false / true), voxel for voxel: one miss
  /// for every voxel a ray passes, one hit for the end voxel, each voxel at
  /// most once per scan, a hit winning over a miss; points beyond max_range
  /// clear up to it without a hit; NaN points and points outside the map are
  /// skipped and counted. Fast: free space cleared a coarse node at a time
  /// (see InsertOptions). With a moving window that follows scans, the box
  /// first moves to the origin, and the scan changes only the box's voxels.
  /// Throws std::invalid_argument for a non-finite origin
  /// or bad options and std::out_of_range for an origin outside the map; the
  /// map is unchanged then.
  InsertStats insert_point_cloud(Vec3f origin, std::span<const Vec3f> points,
                                 const InsertOptions& options = {});
  /// The same with one color per point: every point that gives a hit adds
  /// its color to its voxel. Throws std::invalid_argument when the map has
  /// no color or the sizes differ.
  InsertStats insert_point_cloud(Vec3f origin, std::span<const Vec3f> points, std::span<const Rgb> colors,
                                 const InsertOptions& options = {});

  /// Integrates one depth image taken from `pose` (the camera's optical frame
  /// to the map) with intrinsics `camera` (depth_image.hpp). With
  /// IntegratorKind::projective free space comes from the image itself: a
  /// voxel is cleared when its centre projects onto a pixel with a reading
  /// and lies in front of it (and the rest of its 4 x 4 x 4 brick is in view;
  /// docs/design.md, "The projective integrator"); the hits are the discrete
  /// integrator's on the image's points. Any other integrator inserts the
  /// image's points (back_project) from the camera's position as a point
  /// cloud. `colors`: empty, or one per pixel (the map must have color).
  /// Throws std::invalid_argument for bad intrinsics, a pose that is not a
  /// rotation and translation, a color count that is not the pixel count,
  /// or bad options, and std::out_of_range for a camera outside the map; the
  /// map is unchanged then.
  InsertStats insert_depth_image(const DepthImage& depth, const PinholeCamera& camera, const Pose& pose,
                                 std::span<const Rgb> colors = {}, const InsertOptions& options = {});

  // --- reading single nodes -----------------------------------------------
  /// State of the depth-`depth` node containing the coordinate: occupied if
  /// any voxel in it is, free if all are, unknown otherwise.
  [[nodiscard]] OccupancyState state(Vec3d coordinate, int depth = 0) const;
  [[nodiscard]] float log_odds(Vec3d coordinate, int depth = 0) const;
  /// Probability of the node (the maximum over its voxels).
  [[nodiscard]] double occupancy(Vec3d coordinate, int depth = 0) const;
  [[nodiscard]] bool contains_occupied(Vec3d coordinate, int depth = 0) const;
  [[nodiscard]] bool contains_free(Vec3d coordinate, int depth = 0) const;
  [[nodiscard]] bool contains_unknown(Vec3d coordinate, int depth = 0) const;
  /// The node at `depth` containing finest key `key`, or the childless node
  /// above it that covers it (its depth is then larger). Throws
  /// std::out_of_range for a key or depth outside the map.
  [[nodiscard]] Node node(Key key, int depth = 0) const;
  [[nodiscard]] Node node(Vec3d coordinate, int depth = 0) const;

  /// Calls visit(node) for every childless node, in Morton order (a pruned
  /// node once, at its depth). Holds the map for reading meanwhile: `visit`
  /// must not change the map.
  void for_each_leaf(FunctionRef<void(const Node&)> visit) const;

  // --- queries (include/umbra/query/) ---------------------------------------
  /// The nodes `predicate` holds for, visiting the tree down to `depth`
  /// (depth-`depth` nodes count as leaves), parents before children, in
  /// Morton order. Only subtrees that can match are visited. See
  /// predicate.hpp and query_range.hpp; throws std::out_of_range for a bad depth.
  [[nodiscard]] QueryRange query(const Predicate& predicate, int depth = 0) const;
  /// The same, nearest to `point` first (distance to the node's cube, 0
  /// inside), up to `max_distance` metres.
  [[nodiscard]] NearestRange query_nearest(Vec3d point, const Predicate& predicate, int depth = 0,
                                           double max_distance = std::numeric_limits<double>::infinity()) const;
  /// How many nodes query(predicate, depth) yields.
  [[nodiscard]] std::size_t count(const Predicate& predicate, int depth = 0) const;

  // --- collision checks, line checks, ray casts (query/collision.hpp) -------
  /// Whether no voxel of the region blocks (occupied, or unknown unless
  /// options.unknown_is_free), and if one does, a blocking node. A voxel is
  /// in the region when its cube meets it (shapes.hpp); a Segment is the
  /// voxels of its ray walk, the first blocking one reported; a Capsule is a
  /// segment with a radius. Throws std::out_of_range when the region reaches
  /// outside the map, std::invalid_argument for a bad shape or depth.
  [[nodiscard]] CollisionResult is_free(const Aabb& box, const CollisionOptions& options = {}) const;
  [[nodiscard]] CollisionResult is_free(const Sphere& sphere, const CollisionOptions& options = {}) const;
  [[nodiscard]] CollisionResult is_free(const OrientedBox& box, const CollisionOptions& options = {}) const;
  [[nodiscard]] CollisionResult is_free(const Capsule& capsule, const CollisionOptions& options = {}) const;
  [[nodiscard]] CollisionResult is_free(const Segment& segment, const CollisionOptions& options = {}) const;
  /// Many checks at once, of any CollisionShape: free[i] = 1 when shapes[i]
  /// is free, else 0 (the sizes must match). The map is held for reading a
  /// chunk at a time.
  template <CollisionShape Shape>
  void is_free(std::span<const Shape> shapes, std::span<std::uint8_t> free, const CollisionOptions& options = {}) const;
  /// The first voxel (or depth-`options.depth` node) along the ray from
  /// `origin` in `direction` that is occupied (or unknown, when asked),
  /// within options.max_range; the voxels are those OctoMap's castRay steps
  /// through. Throws std::out_of_range for an origin outside the map,
  /// std::invalid_argument for a zero or non-finite direction.
  [[nodiscard]] RayHit cast_ray(Vec3d origin, Vec3d direction, const RayCastOptions& options = {}) const;
  /// OctoMap's OcTree::castRay(origin, direction, end, ignoreUnknown,
  /// maxRange), rule for rule, for code that migrates: true when an occupied
  /// voxel is hit (`end` = its centre, the origin's own voxel included);
  /// false at an unknown voxel unless `ignore_unknown`, beyond `max_range`
  /// (> 0: distance to voxel centres) or at the map's edge (`end` = the last
  /// voxel's centre). Unknown means the state unknown (OctoMap: no node
  /// stored). Bad arguments throw as for cast_ray.
  bool cast_ray_octomap(Vec3f origin, Vec3f direction, Vec3f& end, bool ignore_unknown = false,
                        double max_range = -1.0) const;
  // --- information gain (query/information_gain.hpp) ------------------------
  /// The unknown finest voxels a sensor with this field of view would see:
  /// centre in the frustum, no occupied voxel on the ray from its origin.
  /// Throws std::invalid_argument for a bad frustum or options,
  /// std::out_of_range when the frustum's origin lies outside the map.
  [[nodiscard]] GainResult information_gain(const Frustum& frustum, const GainOptions& options = {}) const;
  /// The same for many poses: result[i] is the gain of frustums[i]. Poses
  /// run on options.threads threads; the map is held for reading one pose
  /// at a time. Every frustum is checked before any is answered.
  [[nodiscard]] std::vector<GainResult> information_gain(std::span<const Frustum> frustums,
                                                         const GainOptions& options = {}) const;

  // --- pruning ------------------------------------------------------------
  /// On by default: eight equal children are merged into their parent. With
  /// it off no node ever disappears (readers may keep keys of nodes), and
  /// queries still treat eight equal childless children as one leaf.
  /// Switching it on prunes the whole map.
  void set_auto_prune(bool on);
  [[nodiscard]] bool auto_prune() const;
  void prune();
  /// Everything unknown again.
  void clear();

  // --- merging maps (map_merge.hpp, src/map/map_merge.cpp) -------------------
  /// Adds `other`'s log-odds to this map's, voxel by voxel (clamped to this
  /// map's sensor model); other's voxel k lands on k + offset. Voxels other
  /// never observed change nothing; a pruned node covers all its voxels.
  /// Color: where both maps have it, a voxel's color becomes the average of
  /// the two weighted by their sample counts (docs/design.md, "Merging maps").
  /// Throws std::invalid_argument when the resolutions or depth levels
  /// differ (naming both), std::out_of_range when a known voxel of other
  /// would land outside this map; the map is unchanged then. Merging a map
  /// into itself doubles its log-odds.
  MergeStats merge(const OccupancyMap& other, VoxelOffset offset = {});
  /// The same with other placed by a rigid transform (other's frame to this
  /// map's), resampled: this map's voxel with centre c takes other's voxel
  /// containing T^-1 c. Also throws std::invalid_argument for a transform
  /// that is not rigid. A transform that is a whole-voxel translation merges
  /// as that VoxelOffset (the same result, faster).
  MergeStats merge(const OccupancyMap& other, const Pose& transform);

  // --- statistics ---------------------------------------------------------
  [[nodiscard]] NodeCounts node_counts() const;
  /// Bytes allocated for the map (the tree's capacity, the integrator's
  /// buffers kept between scans, the change journal kept for distance
  /// fields, and this object; a DistanceField reports its own).
  [[nodiscard]] std::size_t memory_bytes() const;

 private:
  friend class detail::MapAccess;
  void update_key_log_odds(Key key, float delta);
  void set_key_log_odds(Key key, float log_odds);

  Grid grid_;
  bool color_;
  std::unique_ptr<detail::MapState> state_;
};

}  // namespace umbra
