// The shapes of queries (umbra/query/shapes.hpp) as small immutable Python
// classes. Each is validated when it is made, so a bad shape raises
// ValueError at the line that wrote it. Vectors come back as tuples.
#include <sstream>

#include <pybind11/operators.h>

#include "bindings.hpp"
#include "numpy_arrays.hpp"
#include "umbra/query/shapes.hpp"

namespace umbra::python {
namespace {

std::string text(Vec3d v) {
  std::ostringstream s;
  s << "(" << v.x << ", " << v.y << ", " << v.z << ")";
  return s.str();
}

std::string text(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

template <typename Shape>
Shape validated(Shape shape) {
  shape.validate();
  return shape;
}

/// A 3x3 rotation matrix (its columns: the box's axes in map coordinates).
std::array<Vec3d, 3> axes_of(py::handle rotation) {
  const auto matrix = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(rotation);
  if (!matrix || matrix.ndim() != 2 || matrix.shape(0) != 3 || matrix.shape(1) != 3) {
    PyErr_Clear();
    throw py::value_error("rotation must be a 3x3 matrix whose columns are the box's axes");
  }
  std::array<Vec3d, 3> axes;
  for (int column = 0; column < 3; ++column) {
    axes[static_cast<std::size_t>(column)] = {matrix.at(0, column), matrix.at(1, column), matrix.at(2, column)};
  }
  return axes;
}

py::array_t<double> rotation_of(const OrientedBox& box) {
  py::array_t<double> matrix({3, 3});
  auto out = matrix.mutable_unchecked<2>();
  for (int column = 0; column < 3; ++column) {
    for (int row = 0; row < 3; ++row) out(row, column) = box.axes[static_cast<std::size_t>(column)][static_cast<std::size_t>(row)];
  }
  return matrix;
}

void bind_boxes(py::module_& m) {
  py::class_<Aabb>(m, "Aabb", "An axis-aligned box [min, max] in metres. ValueError unless min <= max, finite.")
      .def(py::init([](py::handle min, py::handle max) {
             return validated(Aabb{vec3_of(min, "min"), vec3_of(max, "max")});
           }),
           py::arg("min"), py::arg("max"), "The box from corner min (3,) to corner max (3,).")
      .def_property_readonly("min", [](const Aabb& b) { return to_tuple(b.min); }, "Lowest corner.")
      .def_property_readonly("max", [](const Aabb& b) { return to_tuple(b.max); }, "Highest corner.")
      .def(py::self == py::self)
      .def("__repr__", [](const Aabb& b) { return "Aabb(min=" + text(b.min) + ", max=" + text(b.max) + ")"; });

  py::class_<OrientedBox>(m, "OrientedBox",
                          "A box turned in space: centre, half edge lengths along its own axes, and a rotation "
                          "matrix whose columns are those axes in map coordinates (orthonormal; identity when "
                          "None).")
      .def(py::init([](py::handle center, py::handle half_extents, py::handle rotation) {
             OrientedBox box;
             box.center = vec3_of(center, "center");
             box.half_extents = vec3_of(half_extents, "half_extents");
             if (!rotation.is_none()) box.axes = axes_of(rotation);
             return validated(box);
           }),
           py::arg("center"), py::arg("half_extents"), py::arg("rotation") = py::none(),
           "The box of half edge lengths half_extents (3,) about center (3,), turned by rotation (3, 3) "
           "(None: not turned).")
      .def_static(
          "from_yaw_pitch_roll",
          [](py::handle center, py::handle half_extents, double yaw, double pitch, double roll) {
            return validated(OrientedBox::from_yaw_pitch_roll(vec3_of(center, "center"),
                                                              vec3_of(half_extents, "half_extents"), yaw, pitch, roll));
          },
          py::arg("center"), py::arg("half_extents"), py::arg("yaw"), py::arg("pitch") = 0.0, py::arg("roll") = 0.0,
          "The box's x axis along (cos p cos y, cos p sin y, sin p), y and z turned by roll about it (radians).")
      .def_static(
          "from_quaternion",
          [](py::handle center, py::handle half_extents, py::handle quaternion) {
            const auto q = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(quaternion);
            if (!q || q.ndim() != 1 || q.shape(0) != 4) {
              PyErr_Clear();
              throw py::value_error("quaternion must be four numbers (w, x, y, z)");
            }
            return validated(OrientedBox::from_quaternion(vec3_of(center, "center"),
                                                          vec3_of(half_extents, "half_extents"), q.at(0), q.at(1),
                                                          q.at(2), q.at(3)));
          },
          py::arg("center"), py::arg("half_extents"), py::arg("quaternion"),
          "The box turned by the quaternion (w, x, y, z), normalised first.")
      .def_property_readonly("center", [](const OrientedBox& b) { return to_tuple(b.center); }, "Centre.")
      .def_property_readonly(
          "half_extents", [](const OrientedBox& b) { return to_tuple(b.half_extents); },
          "Half edge lengths along the box's axes.")
      .def_property_readonly("rotation", rotation_of, "3x3 matrix whose columns are the box's axes.")
      .def("__repr__", [](const OrientedBox& b) {
        return "OrientedBox(center=" + text(b.center) + ", half_extents=" + text(b.half_extents) + ", axes=(" +
               text(b.axes[0]) + ", " + text(b.axes[1]) + ", " + text(b.axes[2]) + "))";
      });
}

void bind_round_shapes(py::module_& m) {
  py::class_<Sphere>(m, "Sphere", "A ball: centre and radius (>= 0) in metres.")
      .def(py::init([](py::handle center, double radius) { return validated(Sphere{vec3_of(center, "center"), radius}); }),
           py::arg("center"), py::arg("radius"), "The ball of radius about center (3,).")
      .def_property_readonly("center", [](const Sphere& s) { return to_tuple(s.center); }, "Centre.")
      .def_readonly("radius", &Sphere::radius, "Radius.")
      .def("__repr__", [](const Sphere& s) { return "Sphere(center=" + text(s.center) + ", radius=" + text(s.radius) + ")"; });

  py::class_<Capsule>(m, "Capsule", "The points within radius of the segment from a to b.")
      .def(py::init([](py::handle a, py::handle b, double radius) {
             return validated(Capsule{vec3_of(a, "a"), vec3_of(b, "b"), radius});
           }),
           py::arg("a"), py::arg("b"), py::arg("radius"),
           "The points within radius of the segment from a (3,) to b (3,).")
      .def_property_readonly("a", [](const Capsule& c) { return to_tuple(c.a); }, "One end of the axis.")
      .def_property_readonly("b", [](const Capsule& c) { return to_tuple(c.b); }, "The other end.")
      .def_readonly("radius", &Capsule::radius, "Radius.")
      .def("__repr__", [](const Capsule& c) {
        return "Capsule(a=" + text(c.a) + ", b=" + text(c.b) + ", radius=" + text(c.radius) + ")";
      });

  py::class_<Segment>(m, "Segment",
                      "A line segment; in checks, the voxels of its ray walk from start (OctoMap's computeRayKeys) "
                      "plus the voxel of end.")
      .def(py::init([](py::handle start, py::handle end) {
             return validated(Segment{vec3_of(start, "start"), vec3_of(end, "end")});
           }),
           py::arg("start"), py::arg("end"), "The segment from start (3,) to end (3,).")
      .def_property_readonly("start", [](const Segment& s) { return to_tuple(s.from); }, "First point.")
      .def_property_readonly("end", [](const Segment& s) { return to_tuple(s.to); }, "Last point.")
      .def("__repr__", [](const Segment& s) { return "Segment(start=" + text(s.from) + ", end=" + text(s.to) + ")"; });
}

void bind_frustum(py::module_& m) {
  py::class_<Frustum>(m, "Frustum",
                      "A sensor's field of view from origin, looking along (cos p cos y, cos p sin y, sin p); "
                      "angles in radians, full fields of view in (0, pi), min_range <= |d| <= max_range.")
      .def(py::init([](py::handle origin, double yaw, double pitch, double hfov, double vfov, double min_range,
                       double max_range) {
             return validated(Frustum{vec3_of(origin, "origin"), yaw, pitch, hfov, vfov, min_range, max_range});
           }),
           py::arg("origin"), py::arg("yaw"), py::arg("pitch"), py::arg("hfov"), py::arg("vfov"),
           py::arg("min_range"), py::arg("max_range"),
           "The field of view from origin (3,), angles in radians (from_degrees takes degrees).")
      .def_static(
          "from_degrees",
          [](py::handle origin, double yaw, double pitch, double hfov, double vfov, double min_range,
             double max_range) {
            return validated(
                Frustum::from_degrees(vec3_of(origin, "origin"), yaw, pitch, hfov, vfov, min_range, max_range));
          },
          py::arg("origin"), py::arg("yaw"), py::arg("pitch"), py::arg("hfov"), py::arg("vfov"), py::arg("min_range"),
          py::arg("max_range"), "The same with the four angles in degrees.")
      .def_property_readonly("origin", [](const Frustum& f) { return to_tuple(f.origin); }, "Sensor position.")
      .def_readonly("yaw", &Frustum::yaw, "Heading, radians.")
      .def_readonly("pitch", &Frustum::pitch, "Elevation, radians (positive looks up).")
      .def_readonly("hfov", &Frustum::hfov, "Full horizontal field of view, radians.")
      .def_readonly("vfov", &Frustum::vfov, "Full vertical field of view, radians.")
      .def_readonly("min_range", &Frustum::min_range, "Nearest distance seen.")
      .def_readonly("max_range", &Frustum::max_range, "Farthest distance seen.")
      .def(
          "contains",
          [](const Frustum& f, py::handle points) {
            const PointArray p(points, "points");
            py::array_t<bool> inside(p.leading_shape());
            auto* out = reinterpret_cast<std::uint8_t*>(inside.mutable_data());
            for (std::size_t i = 0; i < p.size(); ++i) out[i] = f.contains(p[i]) ? 1 : 0;
            return inside;
          },
          py::arg("points"), "Whether each point (..., 3) lies in the frustum: a bool array (...).")
      .def("__repr__", [](const Frustum& f) {
        return "Frustum(origin=" + text(f.origin) + ", yaw=" + text(f.yaw) + ", pitch=" + text(f.pitch) +
               ", hfov=" + text(f.hfov) + ", vfov=" + text(f.vfov) + ", min_range=" + text(f.min_range) +
               ", max_range=" + text(f.max_range) + ")";
      });
}

}  // namespace

void bind_shapes(py::module_& m) {
  bind_boxes(m);
  bind_round_shapes(m);
  bind_frustum(m);
}

}  // namespace umbra::python
