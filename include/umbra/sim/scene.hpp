// Scene: a small world of solid primitives for the simulated sensor.
//
// A scene is a list of axis-aligned boxes (walls, floor, ceiling, furniture)
// and vertical cylinders (pillars, table legs). It exists so that tests,
// examples and benchmarks have deterministic input that needs no data files:
// make_demo_scene() builds an office floor of about 20 m x 12 m x 3 m, and
// demo_path() walks a sensor down its corridor and into a room.
//
// Coordinates are metres in the map frame, z up. Solids are closed sets: a
// point on a surface is inside. Cost model: intersect() and the other queries
// test every primitive (brute force, O(primitives) per call), which is right
// for scenes of a few hundred primitives; there is no acceleration structure.
#pragma once

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

/// Where a sensor is and which way it looks: `yaw` is the heading in
/// radians, counter-clockwise from +x about +z (the sensor is kept level).
struct SensorPose {
  Vec3d position;
  double yaw = 0.0;
};

class Scene {
 public:
  /// Adds a box; throws std::invalid_argument unless its corners are finite
  /// and min < max on every axis.
  void add_box(const Box& box);
  /// Adds a cylinder; throws std::invalid_argument unless its values are
  /// finite, radius > 0 and z_min < z_max.
  void add_cylinder(const Cylinder& cylinder);

  [[nodiscard]] const std::vector<Box>& boxes() const { return boxes_; }
  [[nodiscard]] const std::vector<Cylinder>& cylinders() const { return cylinders_; }
  [[nodiscard]] bool empty() const { return boxes_.empty() && cylinders_.empty(); }

  /// Distance along the ray to the first surface hit, if it is within
  /// [0, max_range]. A ray that starts inside (or on) a solid returns 0.
  /// Throws std::invalid_argument if origin is not finite, unit_direction is
  /// not of length 1 (within 1e-6), or max_range is negative or NaN
  /// (infinity is allowed).
  [[nodiscard]] std::optional<double> intersect(Vec3d origin, Vec3d unit_direction,
                                                double max_range) const;

  /// The same without the argument checks, for callers that already
  /// guarantee them (the simulated LiDAR, once per beam).
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
  std::vector<Box> boxes_;
  std::vector<Cylinder> cylinders_;
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
