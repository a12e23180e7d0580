// umbra.DistanceField: the distance field of a map (distance_field.hpp),
// queried with numpy arrays of points. The field keeps its map alive
// (keep_alive), and every call releases the GIL while the library works.
#include <optional>

#include <pybind11/stl.h>

#include "bindings.hpp"
#include "numpy_arrays.hpp"
#include "umbra/query/distance_field.hpp"

namespace umbra::python {
namespace {

/// Answers per point, in an array of the points' leading shape plus `width` (none for 1).
py::array_t<double> answers(const PointArray& points, std::size_t width) {
  std::vector<py::ssize_t> shape = points.leading_shape();
  if (width > 1) shape.push_back(static_cast<py::ssize_t>(width));
  return py::array_t<double>(shape);
}

std::vector<Vec3d> copy_points(const PointArray& points) {
  std::vector<Vec3d> out(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) out[i] = points[i];
  return out;
}

}  // namespace

void bind_field(py::module_& m) {
  py::class_<DistanceField>(m, "DistanceField",
                            "Distances from any point to the nearest occupied and the nearest unknown voxel of a map, "
                            "capped at max_distance, with the gradient; kept up to date by update() after scans.")
      .def(py::init([](const OccupancyMap& map, double max_distance, int depth, const std::optional<Aabb>& box,
                       unsigned threads) {
             DistanceFieldOptions options;
             options.max_distance = max_distance;
             options.depth = depth;
             options.box = box;
             options.threads = threads;
             py::gil_scoped_release released;
             return std::make_unique<DistanceField>(map, options);
           }),
           py::arg("map"), py::kw_only(), py::arg("max_distance") = 1.0, py::arg("depth") = 0,
           py::arg("box") = py::none(), py::arg("threads") = 1, py::keep_alive<1, 2>(),
           "Builds the field of `map` (kept alive by the field): cells of depth `depth`, distances capped at "
           "max_distance metres, inside `box` (an Aabb) or, without one, over the whole known space; built and "
           "updated by `threads` threads (0: all).")
      .def("update", &DistanceField::update, py::call_guard<py::gil_scoped_release>(),
           "Brings the field up to date with the map, recomputing only near what changed since the last update.")
      .def("rebuild", &DistanceField::rebuild, py::call_guard<py::gil_scoped_release>(), "Recomputes everything.")
      .def("set_box", &DistanceField::set_box, py::arg("box"), py::call_guard<py::gil_scoped_release>(),
           "Moves the box (an Aabb, or None: the whole known space) and rebuilds.")
      .def_property_readonly(
          "max_distance", [](const DistanceField& f) { return f.options().max_distance; }, "Metres; distances are capped here.")
      .def_property_readonly(
          "depth", [](const DistanceField& f) { return f.options().depth; }, "Depth of the cells (0: finest voxels).")
      .def("memory_bytes", &DistanceField::memory_bytes, py::call_guard<py::gil_scoped_release>(),
           "Bytes the field holds.")
      .def(
          "distance",
          [](const DistanceField& field, py::handle points_object) {
            const PointArray points(points_object, "points");
            py::array_t<double> out = answers(points, 1);
            double* data = out.mutable_data();
            const std::vector<Vec3d> rows = copy_points(points);
            {
              py::gil_scoped_release released;
              field.distance(rows, std::span<double>(data, rows.size()));
            }
            return out;
          },
          py::arg("points"),
          "Distance to the nearest blocking (occupied or unknown) voxel of each point (..., 3): an array (...). "
          "A point outside the map (or the box) raises IndexError naming its index.")
      .def(
          "distance_and_gradient",
          [](const DistanceField& field, py::handle points_object) {
            const PointArray points(points_object, "points");
            py::array_t<double> out = answers(points, 5);
            double* data = out.mutable_data();
            const std::vector<Vec3d> rows = copy_points(points);
            {
              py::gil_scoped_release released;
              std::vector<DistanceSample> samples(rows.size());
              field.distance_and_gradient(rows, samples);
              for (std::size_t i = 0; i < samples.size(); ++i) {
                const DistanceSample& s = samples[i];
                double* row = data + 5 * i;
                row[0] = s.occupied;
                row[1] = s.unknown;
                row[2] = s.gradient.x;
                row[3] = s.gradient.y;
                row[4] = s.gradient.z;
              }
            }
            return out;
          },
          py::arg("points"),
          "For each point (..., 3) the row (d_occupied, d_unknown, gx, gy, gz): metres to the nearest occupied and "
          "unknown voxel (capped at max_distance) and the unit vector away from the nearest blocking one: an array "
          "(..., 5).");
}

}  // namespace umbra::python
