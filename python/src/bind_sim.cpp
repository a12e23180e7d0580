// umbra.sim: the procedural office and the simulated LiDAR
// (umbra/sim/scene.hpp, lidar.hpp), so that Python users, tests and the
// example have deterministic scans without any data file. Simulating
// releases the GIL (a scan of the default model takes a few milliseconds).
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "numpy_arrays.hpp"
#include "umbra/sim/lidar.hpp"
#include "umbra/sim/scene.hpp"

namespace umbra::python {

void bind_sim(py::module_& m) {
  py::module_ sim = m.def_submodule("sim", "A procedural building and a simulated LiDAR (deterministic scans).");
  using sim::LidarModel;
  using sim::Scene;
  using sim::SensorPose;

  py::class_<SensorPose>(sim, "SensorPose", "Where a sensor is and its heading (yaw, radians about +z).")
      .def(py::init([](py::handle position, double yaw) { return SensorPose{vec3_of(position, "position"), yaw}; }),
           py::arg("position"), py::arg("yaw") = 0.0,
           "A sensor at position (3,) metres, heading yaw radians counter-clockwise from +x.")
      .def_property_readonly("position", [](const SensorPose& p) { return to_tuple(p.position); }, "Metres.")
      .def_readonly("yaw", &SensorPose::yaw, "Heading, radians counter-clockwise from +x.")
      .def("__repr__", [](const SensorPose& p) {
        return "SensorPose(position=" + std::string(py::repr(to_tuple(p.position))) + ", yaw=" + std::to_string(p.yaw) +
               ")";
      });

  py::class_<Scene>(sim, "Scene", "Solid axis-aligned boxes and vertical cylinders.")
      .def(py::init<>(), "An empty scene.")
      .def(
          "add_box",
          [](Scene& s, py::handle min, py::handle max) { s.add_box({vec3_of(min, "min"), vec3_of(max, "max")}); },
          py::arg("min"), py::arg("max"), "Adds a solid box [min, max] (min < max on every axis).")
      .def(
          "add_cylinder",
          [](Scene& s, double center_x, double center_y, double radius, double z_min, double z_max) {
            s.add_cylinder({center_x, center_y, radius, z_min, z_max});
          },
          py::arg("center_x"), py::arg("center_y"), py::arg("radius"), py::arg("z_min"), py::arg("z_max"),
          "Adds a solid vertical cylinder.")
      .def(
          "bounds",
          [](const Scene& s) {
            const sim::Box b = s.bounds();
            return py::make_tuple(to_tuple(b.min), to_tuple(b.max));
          },
          "(min, max) of the smallest box holding every solid.")
      .def(
          "is_inside_solid",
          [](const Scene& s, py::handle points) {
            const PointArray p(points, "points");
            py::array_t<bool> inside(p.leading_shape());
            auto* out = reinterpret_cast<std::uint8_t*>(inside.mutable_data());
            for (std::size_t i = 0; i < p.size(); ++i) out[i] = s.is_inside_solid(p[i]) ? 1 : 0;
            return inside;
          },
          py::arg("points"), "Whether each point (..., 3) lies inside or on a solid: a bool array (...).");

  py::class_<LidarModel>(sim, "LidarModel",
                         "A spinning LiDAR: rings x azimuth_steps beams, elevations from fov_down_deg to "
                         "fov_up_deg, hits within max_range, optional Gaussian range noise (seeded).")
      .def(py::init([](int rings, double fov_down_deg, double fov_up_deg, int azimuth_steps, double max_range,
                       double range_noise_stddev, std::uint32_t seed) {
             LidarModel model{};
             model.rings = rings;
             model.fov_down_deg = fov_down_deg;
             model.fov_up_deg = fov_up_deg;
             model.azimuth_steps = azimuth_steps;
             model.max_range = max_range;
             model.range_noise_stddev = range_noise_stddev;
             model.seed = seed;
             model.validate();
             return model;
           }),
           py::arg("rings") = 32, py::arg("fov_down_deg") = -25.0, py::arg("fov_up_deg") = 15.0,
           py::arg("azimuth_steps") = 720, py::arg("max_range") = 30.0, py::arg("range_noise_stddev") = 0.0,
           py::arg("seed") = 1, "The beams and their noise; raises ValueError for a model that cannot scan.")
      .def_readonly("rings", &LidarModel::rings, "Beams per azimuth step.")
      .def_readonly("azimuth_steps", &LidarModel::azimuth_steps, "Beams per ring over 360 degrees.")
      .def_readonly("max_range", &LidarModel::max_range, "Metres; farther hits are not returned.")
      .def("__repr__", [](py::handle self) {
        return repr_of_attributes(self, "LidarModel", {"rings", "azimuth_steps", "max_range"});
      });

  sim.def("demo_scene", &sim::make_demo_scene,
          "The office floor of the demo: x in [0, 20], y in [0, 12], z in [0, 3], a corridor at y in [5, 7] and "
          "six rooms.");
  sim.def("demo_path", &sim::demo_path, "Ten SensorPoses at 1.2 m along the demo office's corridor and into a room.");
  sim.def(
      "simulate_scan",
      [](const Scene& scene, const SensorPose& pose, const std::optional<LidarModel>& model) {
        std::vector<Vec3f> points;
        {
          py::gil_scoped_release released;
          sim::simulate_scan(scene, pose, model.value_or(LidarModel{}), points);
        }
        py::array_t<float> array({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}});
        if (!points.empty()) std::copy_n(&points.data()->x, 3 * points.size(), array.mutable_data());
        return array;
      },
      py::arg("scene"), py::arg("pose"), py::arg("model") = py::none(),
      "End points (N, 3) float32 of one scan from pose, in the map frame (the sensor is at pose.position).");
}

}  // namespace umbra::python
