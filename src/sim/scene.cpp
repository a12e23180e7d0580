#include "umbra/sim/scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

#include "scene_bvh.hpp"

namespace umbra::sim {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

std::string to_text(Vec3d v) {
  std::ostringstream out;
  out << '(' << v.x << ", " << v.y << ", " << v.z << ')';
  return out.str();
}

/// Parameter interval [enter, exit] in which a ray is inside a solid.
struct Interval {
  double enter = -kInfinity;
  double exit = kInfinity;
};

/// Narrows `interval` to where origin + t * direction lies in [low, high]
/// along one axis; false if that never happens.
bool clip_to_slab(double origin, double direction, double low, double high, Interval& interval) {
  if (direction == 0.0) return origin >= low && origin <= high;
  const double inverse = 1.0 / direction;
  double t_low = (low - origin) * inverse;
  double t_high = (high - origin) * inverse;
  if (t_low > t_high) std::swap(t_low, t_high);
  interval.enter = std::max(interval.enter, t_low);
  interval.exit = std::min(interval.exit, t_high);
  return interval.enter <= interval.exit;
}

bool clip_to_box(const Box& box, Vec3d origin, Vec3d direction, Interval& interval) {
  for (std::size_t axis = 0; axis < 3; ++axis) {
    if (!clip_to_slab(origin[axis], direction[axis], box.min[axis], box.max[axis], interval)) {
      return false;
    }
  }
  return true;
}

bool clip_to_cylinder(const Cylinder& cylinder, Vec3d origin, Vec3d direction, Interval& interval) {
  if (!clip_to_slab(origin.z, direction.z, cylinder.z_min, cylinder.z_max, interval)) return false;
  // Inside the infinite cylinder where |o_xy + t d_xy|^2 <= r^2: a quadratic a t^2 + 2 b t + c <=
  // 0.
  const double ox = origin.x - cylinder.center_x;
  const double oy = origin.y - cylinder.center_y;
  const double a = direction.x * direction.x + direction.y * direction.y;
  const double b = ox * direction.x + oy * direction.y;
  const double c = ox * ox + oy * oy - cylinder.radius * cylinder.radius;
  if (a == 0.0) return c <= 0.0;  // vertical ray: inside the disc or never
  const double discriminant = b * b - a * c;
  if (discriminant < 0.0) return false;
  const double root = std::sqrt(discriminant);
  interval.enter = std::max(interval.enter, (-b - root) / a);
  interval.exit = std::min(interval.exit, (-b + root) / a);
  return interval.enter <= interval.exit;
}

/// Narrows `interval` to where the ray is within `radius` of `center` (|direction| = 1).
bool clip_to_ball(Vec3d center, double radius, Vec3d origin, Vec3d direction, Interval& interval) {
  const Vec3d offset = origin - center;
  const double b = offset.dot(direction);
  const double c = offset.dot(offset) - radius * radius;
  const double discriminant = b * b - c;
  if (discriminant < 0.0) return false;
  const double root = std::sqrt(discriminant);
  interval.enter = std::max(interval.enter, -b - root);
  interval.exit = std::min(interval.exit, -b + root);
  return interval.enter <= interval.exit;
}

/// The ray's interval inside a pipe. A capsule is convex, so the interval is
/// one piece: the union of the pieces inside its two end balls and inside the
/// cylinder between the planes through its ends.
bool clip_to_pipe(const Pipe& pipe, Vec3d origin, Vec3d direction, Interval& interval) {
  Interval inside{kInfinity, -kInfinity};
  auto include = [&inside](const Interval& piece) {
    inside.enter = std::min(inside.enter, piece.enter);
    inside.exit = std::max(inside.exit, piece.exit);
  };
  for (const Vec3d end : {pipe.a, pipe.b}) {
    Interval piece;
    if (clip_to_ball(end, pipe.radius, origin, direction, piece)) include(piece);
  }
  const Vec3d axis_vector = pipe.b - pipe.a;
  const double length = axis_vector.norm();
  if (length > 0.0) {
    const Vec3d axis = axis_vector / length;
    const Vec3d offset = origin - pipe.a;
    Interval piece;
    // Between the end planes: 0 <= (offset + t direction) . axis <= length.
    if (clip_to_slab(offset.dot(axis), direction.dot(axis), 0.0, length, piece)) {
      // Within the radius of the axis line: |w0 + t wd|^2 <= r^2 with w the parts across the axis.
      const Vec3d w0 = offset - axis * offset.dot(axis);
      const Vec3d wd = direction - axis * direction.dot(axis);
      const double a = wd.dot(wd);
      const double b = w0.dot(wd);
      const double c = w0.dot(w0) - pipe.radius * pipe.radius;
      bool meets = false;
      if (a == 0.0) {
        meets = c <= 0.0;  // along the axis: inside the tube or never
      } else if (const double discriminant = b * b - a * c; discriminant >= 0.0) {
        const double root = std::sqrt(discriminant);
        piece.enter = std::max(piece.enter, (-b - root) / a);
        piece.exit = std::min(piece.exit, (-b + root) / a);
        meets = piece.enter <= piece.exit;
      }
      if (meets) include(piece);
    }
  }
  if (inside.enter > inside.exit) return false;
  interval.enter = std::max(interval.enter, inside.enter);
  interval.exit = std::min(interval.exit, inside.exit);
  return interval.enter <= interval.exit;
}

/// Distance from a point to the segment [a, b].
double distance_to_segment(Vec3d point, Vec3d a, Vec3d b) {
  const Vec3d ab = b - a;
  const double length_squared = ab.dot(ab);
  const double t = length_squared > 0.0 ? std::clamp((point - a).dot(ab) / length_squared, 0.0, 1.0) : 0.0;
  return (point - (a + ab * t)).norm();
}

/// Folds one primitive's interval into the nearest hit so far.
void keep_nearest(const Interval& interval, double& nearest) {
  if (interval.exit < 0.0) return;  // the solid is behind the origin
  nearest = std::min(nearest, std::max(interval.enter, 0.0));
}

/// Signed-distance style helper: distance to the surface from per-axis
/// outside distances (positive outside, negative inside on that axis).
double surface_distance(std::initializer_list<double> outside_by_axis) {
  double outside_sq = 0.0;
  double largest = -kInfinity;
  for (const double d : outside_by_axis) {
    if (d > 0.0) outside_sq += d * d;
    largest = std::max(largest, d);
  }
  // Outside on some axis: Euclidean distance to the solid; inside on all: nearest face.
  return largest > 0.0 ? std::sqrt(outside_sq) : -largest;
}

// --- demo scene helpers ------------------------------------------------------

constexpr double kStorey = 3.0;  // floor-to-ceiling height
constexpr double kWall = 0.2;    // wall thickness

struct Gap {
  double from;
  double to;
};

/// A full-height wall along x (from x_from to x_to, y in [y_min, y_max])
/// with door gaps, given in increasing x.
void add_wall_along_x(Scene& scene, double x_from, double x_to, double y_min, double y_max,
                      std::initializer_list<Gap> doors) {
  double start = x_from;
  for (const Gap& door : doors) {
    scene.add_box({{start, y_min, 0.0}, {door.from, y_max, kStorey}});
    start = door.to;
  }
  scene.add_box({{start, y_min, 0.0}, {x_to, y_max, kStorey}});
}

/// A table: a 4 cm top at `height` on four 3 cm legs inset 8 cm from the corners.
void add_table(Scene& scene, double center_x, double center_y, double length_x, double width_y,
               double height) {
  const double x0 = center_x - length_x / 2;
  const double x1 = center_x + length_x / 2;
  const double y0 = center_y - width_y / 2;
  const double y1 = center_y + width_y / 2;
  constexpr double top = 0.04;
  constexpr double inset = 0.08;
  scene.add_box({{x0, y0, height - top}, {x1, y1, height}});
  for (const double x : {x0 + inset, x1 - inset}) {
    for (const double y : {y0 + inset, y1 - inset}) {
      scene.add_cylinder({x, y, 0.03, 0.0, height - top});
    }
  }
}

// --- the primitives as the hierarchy sees them ------------------------------

// A leaf of the hierarchy names its primitive by kind (top two bits) and
// index in that kind's list.
enum class Kind : std::uint32_t { box = 0, cylinder = 1, pipe = 2 };
constexpr std::uint32_t kKindShift = 30;
constexpr std::uint32_t kIndexMask = (1u << kKindShift) - 1;

std::uint32_t primitive_id(Kind kind, std::size_t index) {
  if (index > kIndexMask) throw std::length_error("Scene: more than 2^30 primitives of one kind");
  return (static_cast<std::uint32_t>(kind) << kKindShift) | static_cast<std::uint32_t>(index);
}
Kind kind_of(std::uint32_t id) { return static_cast<Kind>(id >> kKindShift); }
std::size_t index_of(std::uint32_t id) { return id & kIndexMask; }

detail::BvhBox hierarchy_box(const Box& box) { return {box.min, box.max}; }
bool clip(const Box& box, Vec3d origin, Vec3d direction, Interval& interval) {
  return clip_to_box(box, origin, direction, interval);
}
bool clip(const Cylinder& cylinder, Vec3d origin, Vec3d direction, Interval& interval) {
  return clip_to_cylinder(cylinder, origin, direction, interval);
}
bool clip(const Pipe& pipe, Vec3d origin, Vec3d direction, Interval& interval) {
  return clip_to_pipe(pipe, origin, direction, interval);
}

bool contains(const Box& box, Vec3d point) {
  return point.x >= box.min.x && point.x <= box.max.x && point.y >= box.min.y && point.y <= box.max.y &&
         point.z >= box.min.z && point.z <= box.max.z;
}
bool contains(const Cylinder& cylinder, Vec3d point) {
  const double dx = point.x - cylinder.center_x;
  const double dy = point.y - cylinder.center_y;
  return dx * dx + dy * dy <= cylinder.radius * cylinder.radius && point.z >= cylinder.z_min &&
         point.z <= cylinder.z_max;
}
bool contains(const Pipe& pipe, Vec3d point) { return distance_to_segment(point, pipe.a, pipe.b) <= pipe.radius; }

double surface_distance(const Box& box, Vec3d point) {
  return surface_distance({std::max(box.min.x - point.x, point.x - box.max.x),
                           std::max(box.min.y - point.y, point.y - box.max.y),
                           std::max(box.min.z - point.z, point.z - box.max.z)});
}
double surface_distance(const Cylinder& cylinder, Vec3d point) {
  const double radial = std::hypot(point.x - cylinder.center_x, point.y - cylinder.center_y) - cylinder.radius;
  const double vertical = std::max(cylinder.z_min - point.z, point.z - cylinder.z_max);
  return surface_distance({radial, vertical});
}
double surface_distance(const Pipe& pipe, Vec3d point) {
  return std::abs(distance_to_segment(point, pipe.a, pipe.b) - pipe.radius);
}

/// Calls fn(primitive) with the primitive a hierarchy leaf names.
template <typename Fn>
decltype(auto) visit_primitive(const Scene& scene, std::uint32_t id, Fn&& fn) {
  switch (kind_of(id)) {
    case Kind::box:
      return fn(scene.boxes()[index_of(id)]);
    case Kind::cylinder:
      return fn(scene.cylinders()[index_of(id)]);
    case Kind::pipe:
      break;
  }
  return fn(scene.pipes()[index_of(id)]);
}

}  // namespace

double distance_to_solid(const Box& box, Vec3d point) {
  double sum = 0.0;
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const double outside = std::max({box.min[axis] - point[axis], 0.0, point[axis] - box.max[axis]});
    sum += outside * outside;
  }
  return std::sqrt(sum);
}
double distance_to_solid(const Cylinder& cylinder, Vec3d point) {
  const double radial = std::max(0.0, std::hypot(point.x - cylinder.center_x, point.y - cylinder.center_y) - cylinder.radius);
  const double vertical = std::max({0.0, cylinder.z_min - point.z, point.z - cylinder.z_max});
  return std::hypot(radial, vertical);
}
double distance_to_solid(const Pipe& pipe, Vec3d point) {
  return std::max(0.0, distance_to_segment(point, pipe.a, pipe.b) - pipe.radius);
}

Box bounds_of(const Box& box) { return box; }
Box bounds_of(const Cylinder& c) {
  return {{c.center_x - c.radius, c.center_y - c.radius, c.z_min}, {c.center_x + c.radius, c.center_y + c.radius, c.z_max}};
}
Box bounds_of(const Pipe& p) {
  const Vec3d r{p.radius, p.radius, p.radius};
  return {Vec3d{std::min(p.a.x, p.b.x), std::min(p.a.y, p.b.y), std::min(p.a.z, p.b.z)} - r,
          Vec3d{std::max(p.a.x, p.b.x), std::max(p.a.y, p.b.y), std::max(p.a.z, p.b.z)} + r};
}

Scene::Scene() : bvh_(std::make_unique<detail::SceneBvh>()) {}
Scene::~Scene() = default;
Scene::Scene(const Scene& other)
    : boxes_(other.boxes_),
      cylinders_(other.cylinders_),
      pipes_(other.pipes_),
      bvh_(std::make_unique<detail::SceneBvh>(*other.bvh_)) {}
Scene& Scene::operator=(const Scene& other) {
  if (this != &other) *this = Scene(other);
  return *this;
}
// A moved-from scene is empty and usable: it gets a fresh hierarchy.
Scene::Scene(Scene&& other) noexcept
    : boxes_(std::move(other.boxes_)),
      cylinders_(std::move(other.cylinders_)),
      pipes_(std::move(other.pipes_)),
      bvh_(std::exchange(other.bvh_, std::make_unique<detail::SceneBvh>())) {
  other.boxes_.clear();
  other.cylinders_.clear();
  other.pipes_.clear();
}
Scene& Scene::operator=(Scene&& other) noexcept {
  if (this != &other) {
    boxes_ = std::move(other.boxes_);
    cylinders_ = std::move(other.cylinders_);
    pipes_ = std::move(other.pipes_);
    std::swap(bvh_, other.bvh_);
    other.boxes_.clear();
    other.cylinders_.clear();
    other.pipes_.clear();
    *other.bvh_ = detail::SceneBvh();
  }
  return *this;
}

void Scene::add_box(const Box& box) {
  if (!box.min.is_finite() || !box.max.is_finite()) {
    throw std::invalid_argument("Scene::add_box: corners must be finite, got min " +
                                to_text(box.min) + " max " + to_text(box.max));
  }
  if (!(box.min.x < box.max.x && box.min.y < box.max.y && box.min.z < box.max.z)) {
    throw std::invalid_argument("Scene::add_box: need min < max on every axis, got min " +
                                to_text(box.min) + " max " + to_text(box.max));
  }
  bvh_->insert(hierarchy_box(bounds_of(box)), primitive_id(Kind::box, boxes_.size()));
  boxes_.push_back(box);
}

void Scene::add_cylinder(const Cylinder& cylinder) {
  const bool finite = std::isfinite(cylinder.center_x) && std::isfinite(cylinder.center_y) &&
                      std::isfinite(cylinder.radius) && std::isfinite(cylinder.z_min) &&
                      std::isfinite(cylinder.z_max);
  if (!finite || !(cylinder.radius > 0.0) || !(cylinder.z_min < cylinder.z_max)) {
    std::ostringstream out;
    out << "Scene::add_cylinder: need finite values, radius > 0 and z_min < z_max, got centre ("
        << cylinder.center_x << ", " << cylinder.center_y << ") radius " << cylinder.radius
        << " z [" << cylinder.z_min << ", " << cylinder.z_max << "]";
    throw std::invalid_argument(out.str());
  }
  bvh_->insert(hierarchy_box(bounds_of(cylinder)), primitive_id(Kind::cylinder, cylinders_.size()));
  cylinders_.push_back(cylinder);
}

void Scene::add_pipe(const Pipe& pipe) {
  if (!pipe.a.is_finite() || !pipe.b.is_finite() || !std::isfinite(pipe.radius) || !(pipe.radius > 0.0)) {
    std::ostringstream out;
    out << "Scene::add_pipe: need finite ends and radius > 0, got a " << to_text(pipe.a) << " b "
        << to_text(pipe.b) << " radius " << pipe.radius;
    throw std::invalid_argument(out.str());
  }
  bvh_->insert(hierarchy_box(bounds_of(pipe)), primitive_id(Kind::pipe, pipes_.size()));
  pipes_.push_back(pipe);
}

std::optional<double> Scene::intersect(Vec3d origin, Vec3d unit_direction, double max_range) const {
  if (!origin.is_finite()) {
    throw std::invalid_argument("Scene::intersect: origin must be finite, got " + to_text(origin));
  }
  if (!unit_direction.is_finite() || std::abs(unit_direction.norm() - 1.0) > 1e-6) {
    throw std::invalid_argument("Scene::intersect: unit_direction must have length 1, got " +
                                to_text(unit_direction));
  }
  if (!(max_range >= 0.0)) {
    std::ostringstream out;
    out << "Scene::intersect: max_range must be >= 0, got " << max_range;
    throw std::invalid_argument(out.str());
  }
  return intersect_unchecked(origin, unit_direction, max_range);
}

std::optional<double> Scene::intersect_unchecked(Vec3d origin, Vec3d unit_direction,
                                                 double max_range) const {
  double nearest = kInfinity;
  bvh_->cast(origin, unit_direction, max_range, [&](std::uint32_t id, double t_max) {
    Interval interval;
    const bool meets = visit_primitive(*this, id, [&](const auto& primitive) {
      return clip(primitive, origin, unit_direction, interval);
    });
    if (meets) keep_nearest(interval, nearest);
    return std::min(t_max, nearest);
  });
  if (nearest <= max_range) return nearest;
  return std::nullopt;
}

bool Scene::is_inside_solid(Vec3d point) const {
  bool inside = false;
  // A ball of radius 0 around the point: the primitives whose bounds hold it.
  bvh_->visit_near(point, 0.0, [&](std::uint32_t id, double limit) {
    if (!inside) inside = visit_primitive(*this, id, [&](const auto& primitive) { return contains(primitive, point); });
    return inside ? -1.0 : limit;  // found: a negative limit ends the walk
  });
  return inside;
}

double Scene::distance_to_nearest_surface(Vec3d point) const {
  // A primitive's surface lies inside its bounds, so the distance to the
  // bounds is a lower bound of the distance to the surface.
  double nearest = kInfinity;
  bvh_->visit_near(point, kInfinity, [&](std::uint32_t id, double) {
    nearest = std::min(nearest, visit_primitive(*this, id, [&](const auto& primitive) {
                         return surface_distance(primitive, point);
                       }));
    return nearest * nearest;
  });
  return nearest;
}

Box Scene::bounds() const {
  if (empty()) throw std::logic_error("Scene::bounds: the scene is empty");
  return {bvh_->bounds().min, bvh_->bounds().max};
}

Scene make_demo_scene() {
  Scene scene;
  constexpr double width = 20.0;  // x
  constexpr double depth = 12.0;  // y

  // Shell: floor and ceiling slabs, then the four outer walls (the west and
  // east walls stop at the north and south ones so that no boxes overlap).
  scene.add_box({{0.0, 0.0, -kWall}, {width, depth, 0.0}});
  scene.add_box({{0.0, 0.0, kStorey}, {width, depth, kStorey + kWall}});
  scene.add_box({{0.0, 0.0, 0.0}, {width, kWall, kStorey}});
  scene.add_box({{0.0, depth - kWall, 0.0}, {width, depth, kStorey}});
  scene.add_box({{0.0, kWall, 0.0}, {kWall, depth - kWall, kStorey}});
  scene.add_box({{width - kWall, kWall, 0.0}, {width, depth - kWall, kStorey}});

  // Corridor y in [5, 7]: its two walls, with one door gap per room.
  add_wall_along_x(scene, kWall, width - kWall, 7.0, 7.0 + kWall,
                   {{3.0, 4.0}, {9.5, 10.5}, {15.5, 16.5}});
  add_wall_along_x(scene, kWall, width - kWall, 5.0 - kWall, 5.0,
                   {{2.5, 3.5}, {9.0, 10.2}, {16.5, 17.5}});

  // Walls between the rooms: x = 7 and 13 in the north, x = 6 and 14 in the
  // south (offset so the two sides are told apart in a picture).
  for (const double x : {7.0, 13.0}) {
    scene.add_box({{x - kWall / 2, 7.0 + kWall, 0.0}, {x + kWall / 2, depth - kWall, kStorey}});
  }
  for (const double x : {6.0, 14.0}) {
    scene.add_box({{x - kWall / 2, kWall, 0.0}, {x + kWall / 2, 5.0 - kWall, kStorey}});
  }

  // North-west office: two desks, a shelf on the west wall, a filing cabinet.
  add_table(scene, 2.0, 10.6, 1.6, 0.8, 0.75);
  add_table(scene, 5.0, 10.6, 1.6, 0.8, 0.75);
  scene.add_box({{kWall, 8.0, 0.0}, {0.6, 10.0, 2.0}});
  scene.add_box({{5.8, 7.6, 0.0}, {6.7, 8.2, 1.2}});

  // North-middle meeting room: a long table, six stools, a sideboard.
  add_table(scene, 10.0, 9.8, 3.0, 1.2, 0.75);
  for (const double x : {9.0, 10.0, 11.0}) {
    for (const double y : {8.6, 11.0}) scene.add_cylinder({x, y, 0.22, 0.0, 0.45});
  }
  scene.add_box({{8.0, 11.4, 0.0}, {12.0, depth - kWall, 0.9}});

  // North-east store: two rows of tall shelving and a stack of crates.
  scene.add_box({{14.0, 9.0, 0.0}, {18.5, 9.5, 2.2}});
  scene.add_box({{14.0, 10.8, 0.0}, {18.5, 11.3, 2.2}});
  scene.add_box({{13.6, 7.6, 0.0}, {14.4, 8.4, 0.8}});
  scene.add_box({{13.7, 7.7, 0.8}, {14.3, 8.3, 1.4}});  // a smaller crate on top
  scene.add_box({{14.5, 7.6, 0.0}, {15.1, 8.2, 0.6}});

  // South-west lounge: a sofa (seat and back), a coffee table, a plant pot.
  scene.add_box({{1.0, 0.3, 0.0}, {3.5, 1.2, 0.45}});
  scene.add_box({{1.0, 0.3, 0.45}, {3.5, 0.5, 0.9}});
  add_table(scene, 2.25, 2.2, 1.2, 0.6, 0.45);
  scene.add_cylinder({5.3, 4.2, 0.25, 0.0, 0.7});

  // South-middle lab: two structural pillars, workbenches, a tall cabinet.
  scene.add_cylinder({8.0, 2.5, 0.25, 0.0, kStorey});
  scene.add_cylinder({12.0, 2.5, 0.25, 0.0, kStorey});
  add_table(scene, 8.5, 0.8, 2.0, 0.8, 0.9);
  add_table(scene, 11.5, 0.8, 2.0, 0.8, 0.9);
  add_table(scene, 10.0, 2.5, 1.6, 1.0, 0.9);
  scene.add_box({{6.2, 3.5, 0.0}, {6.7, 4.7, 1.9}});

  // South-east server room: two racks and a box on the floor.
  scene.add_box({{15.0, 0.6, 0.0}, {15.6, 3.6, 2.0}});
  scene.add_box({{17.0, 0.6, 0.0}, {17.6, 3.6, 2.0}});
  scene.add_box({{18.6, 3.8, 0.0}, {19.4, 4.5, 0.5}});

  // Corridor: a low bench against its south wall.
  scene.add_box({{11.0, 5.0, 0.0}, {13.0, 5.4, 0.45}});
  return scene;
}

std::vector<SensorPose> demo_path() {
  constexpr double height = 1.2;
  constexpr double east = 0.0;
  constexpr double north = std::numbers::pi / 2;
  // clang-format off
  return {
      {{1.0, 6.0, height}, east},      // west end of the corridor
      {{2.5, 6.0, height}, east},
      {{4.0, 6.0, height}, east},
      {{5.5, 6.0, height}, east},
      {{7.0, 6.0, height}, east},
      {{8.5, 6.0, height}, east},
      {{9.6, 6.2, height}, north / 2}, // turning towards the meeting-room door
      {{10.0, 6.6, height}, north},
      {{10.0, 7.1, height}, north},    // in the doorway
      {{10.0, 7.9, height}, north},    // just inside the meeting room
  };
  // clang-format on
}

}  // namespace umbra::sim
