// Scene: a small world of solid primitives for the simulated sensors.
//
// A scene is a list of axis-aligned boxes (walls, floors, furniture),
// vertical cylinders (pillars, tanks, table legs) and pipes (capsules: the
// points within a radius of a segment, at any slant). It exists so that
// tests, examples and benchmarks have deterministic input that needs no data
// files: make_demo_scene() builds an office floor of about 20 m x 12 m x 3 m,
// and demo_path() walks a sensor down its corridor and into a room;
// industrial_scene.hpp builds larger plants.
//
// Coordinates are metres in the map frame, z up. Solids are closed sets: a
// point on a surface is inside. Cost model: the scene keeps a bounding volume
// hierarchy over its primitives' bounds, updated by every add (O(log n)), so
// intersect() and the other queries test only the primitives near the ray or
// the point: a depth image of a plant of thousands of primitives costs little
// more than one of a few dozen. A const Scene may be shared between threads;
// copies are deep, and a moved-from scene is empty.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <vector>

#include "umbra/core/vec3.hpp"

namespace umbra::sim {

/// An axis-aligned box [min, max] (every component of min < the one of max).
struct Box {
  Vec3d min;
  Vec3d max;
};

/// A solid vertical cylinder: a disc of `radius` around (center_x, center_y),
/// extruded from z_min to z_max.
struct Cylinder {
  double center_x = 0.0;
  double center_y = 0.0;
  double radius = 0.0;
  double z_min = 0.0;
  double z_max = 0.0;
};

/// A solid pipe: the points within `radius` of the segment from `a` to `b`
/// (a capsule; the rounded ends stand for elbows and flanges). a == b is a ball.
struct Pipe {
  Vec3d a;
  Vec3d b;
  double radius = 0.0;
};

/// Distance from a point to a solid primitive: 0 inside or on it, else the
/// Euclidean distance to its surface. For per-primitive work such as
/// rasterising a scene (reachable_space.hpp); Scene answers for the whole scene.
double distance_to_solid(const Box& box, Vec3d point);
double distance_to_solid(const Cylinder& cylinder, Vec3d point);
double distance_to_solid(const Pipe& pipe, Vec3d point);

/// The smallest axis-aligned box holding a primitive.
Box bounds_of(const Box& box);
Box bounds_of(const Cylinder& cylinder);
Box bounds_of(const Pipe& pipe);

/// Where a sensor is and which way it looks: `yaw` is the heading in
/// radians, counter-clockwise from +x about +z (the sensor is kept level).
struct SensorPose {
  Vec3d position;
  double yaw = 0.0;
};

namespace detail {
class SceneBvh;
}

class Scene {
 public:
  Scene();
  ~Scene();
  Scene(const Scene& other);
  Scene& operator=(const Scene& other);
  Scene(Scene&& other) noexcept;
  Scene& operator=(Scene&& other) noexcept;

  /// Adds a box; throws std::invalid_argument unless its corners are finite
  /// and min < max on every axis.
  void add_box(const Box& box);
  /// Adds a cylinder; throws std::invalid_argument unless its values are
  /// finite, radius > 0 and z_min < z_max.
  void add_cylinder(const Cylinder& cylinder);
  /// Adds a pipe; throws std::invalid_argument unless its values are finite
  /// and radius > 0.
  void add_pipe(const Pipe& pipe);

  [[nodiscard]] const std::vector<Box>& boxes() const { return boxes_; }
  [[nodiscard]] const std::vector<Cylinder>& cylinders() const { return cylinders_; }
  [[nodiscard]] const std::vector<Pipe>& pipes() const { return pipes_; }
  [[nodiscard]] std::size_t primitive_count() const { return boxes_.size() + cylinders_.size() + pipes_.size(); }
  [[nodiscard]] bool empty() const { return primitive_count() == 0; }

  /// Distance along the ray to the first surface hit, if it is within
  /// [0, max_range]. A ray that starts inside (or on) a solid returns 0.
  /// Throws std::invalid_argument if origin is not finite, unit_direction is
  /// not of length 1 (within 1e-6), or max_range is negative or NaN
  /// (infinity is allowed).
  [[nodiscard]] std::optional<double> intersect(Vec3d origin, Vec3d unit_direction,
                                                double max_range) const;

  /// The same without the argument checks, for callers that already
  /// guarantee them (the simulated sensors, once per beam).
  [[nodiscard]] std::optional<double> intersect_unchecked(Vec3d origin, Vec3d unit_direction,
                                                          double max_range) const;

  /// True if the point lies inside or on any solid.
  [[nodiscard]] bool is_inside_solid(Vec3d point) const;

  /// Distance from the point to the nearest surface of any primitive (from
  /// outside or inside it); +infinity for an empty scene.
  [[nodiscard]] double distance_to_nearest_surface(Vec3d point) const;

  /// The smallest box holding every primitive; throws std::logic_error for
  /// an empty scene.
  [[nodiscard]] Box bounds() const;

 private:
  // The hierarchy's leaves name a primitive by kind and index (scene.cpp).
  std::vector<Box> boxes_;
  std::vector<Cylinder> cylinders_;
  std::vector<Pipe> pipes_;
  std::unique_ptr<detail::SceneBvh> bvh_;
};

/// An office floor, deterministic and built in code: the building spans
/// x in [0, 20], y in [0, 12], z in [0, 3] (floor slab below z = 0, ceiling
/// slab above z = 3, 0.2 m walls). A 2 m corridor runs east-west at
/// y in [5, 7]; three rooms open off it to the north and three to the south
/// through 1 m (one 1.2 m) door gaps. The rooms hold tables with legs,
/// shelves, crates, a sofa, workbenches and two pillars.
Scene make_demo_scene();

/// Ten sensor poses at 1.2 m height in make_demo_scene(): along the
/// corridor from its west end, then through the door of the middle north
/// room and into it. Every pose is in free space, at least 0.3 m from any
/// surface.
std::vector<SensorPose> demo_path();

}  // namespace umbra::sim
