// Depth images (umbra/map/depth_image.hpp): umbra.PinholeCamera,
// umbra.back_project and OccupancyMap.insert_depth_image, with numpy
// images: depth (H, W) as uint16 raw units (with depth_scale, units per
// metre) or float metres, colors (H, W, 3) uint8, poses (4, 4) or (3, 4)
// camera-to-map (the optical frame: x right, y down, z forward).
//
// As insert(), insertion converts the arguments with the GIL held, then
// releases it while the library works.
#include <algorithm>
#include <optional>
#include <vector>

#include <pybind11/stl.h>

#include "bindings.hpp"
#include "numpy_arrays.hpp"
#include "umbra/integrate/depth_image.hpp"
#include "umbra/integrate/insert_options.hpp"

namespace umbra::python {
namespace {

std::string number_text(double value) { return py::repr(py::float_(value)); }

InsertStats insert_depth_image(OccupancyMap& map, py::handle depth_object, py::handle camera_object,
                               py::handle pose_object, py::handle colors_object, std::optional<double> depth_scale,
                               const std::string& integrator, double max_range, double surface_margin,
                               int clear_depth, int fine_steps, int threads) {
  const DepthArray depth(depth_object, "depth", depth_scale, "depth_scale");
  const PinholeCamera camera = camera_of(camera_object, "camera");
  const Pose pose = pose_of(pose_object, "pose");
  InsertOptions options = insert_options(integrator, max_range, clear_depth, fine_steps, threads);
  options.surface_margin = surface_margin;
  if (colors_object.is_none()) {
    py::gil_scoped_release released;
    return map.insert_depth_image(depth.view(), camera, pose, {}, options);
  }
  if (!map.has_color()) throw py::value_error("colors given, but the map was made without color (color=False)");
  const ColorArray colors = image_colors(colors_object, "colors", depth.height(), depth.width());
  py::gil_scoped_release released;
  return map.insert_depth_image(depth.view(), camera, pose, colors.span(), options);
}

py::object back_project_image(py::handle depth_object, py::handle camera_object, py::handle pose_object,
                              std::optional<double> depth_scale, bool return_pixels) {
  const DepthArray depth(depth_object, "depth", depth_scale, "depth_scale");
  const PinholeCamera camera = camera_of(camera_object, "camera");
  const Pose pose = pose_object.is_none() ? Pose{} : pose_of(pose_object, "pose");
  std::vector<Vec3f> points;
  std::vector<std::uint32_t> pixels;
  {
    py::gil_scoped_release released;
    back_project(depth.view(), camera, pose, points, return_pixels ? &pixels : nullptr);
  }
  py::array_t<float> point_array({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}});
  if (!points.empty()) std::copy_n(&points.data()->x, 3 * points.size(), point_array.mutable_data());
  if (!return_pixels) return point_array;
  py::array_t<std::uint32_t> pixel_array(static_cast<py::ssize_t>(pixels.size()));
  std::copy(pixels.begin(), pixels.end(), pixel_array.mutable_data());
  return py::make_tuple(point_array, pixel_array);
}

}  // namespace

void bind_depth(py::module_& m, MapClass& map) {
  py::class_<PinholeCamera>(m, "PinholeCamera",
                            "Pinhole intrinsics in pixels: pixel (u, v) (from 0 at the top-left pixel's centre) with "
                            "depth z lies at x = (u - cx) z / fx, y = (v - cy) z / fy in the optical frame (x right, "
                            "y down, z forward).")
      .def(py::init([](double fx, double fy, double cx, double cy) {
             PinholeCamera camera{fx, fy, cx, cy};
             camera.validate();
             return camera;
           }),
           py::arg("fx"), py::arg("fy"), py::arg("cx"), py::arg("cy"),
           "Focal lengths fx, fy and principal point cx, cy, pixels (focal lengths > 0, all finite).")
      .def_readonly("fx", &PinholeCamera::fx, "Focal length along u, pixels.")
      .def_readonly("fy", &PinholeCamera::fy, "Focal length along v, pixels.")
      .def_readonly("cx", &PinholeCamera::cx, "Principal point u, pixels.")
      .def_readonly("cy", &PinholeCamera::cy, "Principal point v, pixels.")
      .def("__eq__", [](const PinholeCamera& a, const PinholeCamera& b) {
        return a.fx == b.fx && a.fy == b.fy && a.cx == b.cx && a.cy == b.cy;
      })
      .def("__repr__", [](const PinholeCamera& c) {
        return "PinholeCamera(fx=" + number_text(c.fx) + ", fy=" + number_text(c.fy) + ", cx=" + number_text(c.cx) +
               ", cy=" + number_text(c.cy) + ")";
      });

  m.def("back_project", &back_project_image, py::arg("depth"), py::arg("camera"), py::arg("pose") = py::none(),
        py::kw_only(), py::arg("depth_scale") = py::none(), py::arg("return_pixels") = false,
        "The points (N, 3) float32 of the pixels of a depth image that have a reading, row by row: depth (H, W) "
        "uint16 raw units (depth_scale units per metre) or float metres (0, negative, NaN or infinite: no "
        "reading); camera a PinholeCamera or (fx, fy, cx, cy); pose (4, 4) or (3, 4) camera-to-map, None for the "
        "camera frame. With return_pixels, (points, pixels): each point's pixel index v * W + u, (N,) uint32. "
        "insert_depth_image inserts these very points.");

  map.def("insert_depth_image", &insert_depth_image, py::arg("depth"), py::arg("camera"), py::arg("pose"),
          py::arg("colors") = py::none(), py::kw_only(), py::arg("depth_scale") = py::none(),
          py::arg("integrator") = "projective", py::arg("max_range") = -1.0, py::arg("surface_margin") = 0.0,
          py::arg("clear_depth") = -1, py::arg("fine_steps") = 2, py::arg("threads") = 0,
          "Integrates one depth image taken from pose: depth (H, W) uint16 raw units (depth_scale units per "
          "metre, e.g. 1000 for millimetres) or float metres (0, negative, NaN or infinite: no reading); camera a "
          "PinholeCamera or (fx, fy, cx, cy); pose (4, 4) or (3, 4) camera-to-map, a rotation and a translation "
          "(the optical frame: x right, y down, z forward); colors (H, W, 3) uint8, one per pixel (the map needs "
          "color). Returns InsertStats. integrator 'projective': free space from the image itself, a voxel cleared "
          "when it lies more than surface_margin voxels in front of the reading it projects onto, hits from the "
          "image's points as 'discrete' gives them; any other integrator inserts back_project's points from the "
          "camera's position as insert() does. max_range <= 0: unlimited. threads: 0 for all cores.");
}

}  // namespace umbra::python
