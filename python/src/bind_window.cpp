// A map that moves: OccupancyMap.set_moving_window, move_window, window_box,
// WindowMove and load_spill (umbra/map/moving_window.hpp, umbra/io/spill_file.hpp).
#include <filesystem>
#include <optional>

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.hpp"
#include "numpy_arrays.hpp"
#include "umbra/io/spill_file.hpp"

namespace umbra::python {
namespace {

void set_moving_window(OccupancyMap& map, const std::optional<double>& half_extent,
                       const std::optional<std::filesystem::path>& spill_path, int step_depth, bool follow_scans) {
  py::gil_scoped_release released;
  if (!half_extent) {
    map.set_moving_window(std::nullopt);
    return;
  }
  MovingWindow window;
  window.half_extent = *half_extent;
  window.step_depth = step_depth;
  window.follow_scans = follow_scans;
  if (spill_path) window.spill = spill_to_file(*spill_path);
  map.set_moving_window(window);
}

py::object window_box(const OccupancyMap& map) {
  std::optional<VoxelBox> box;
  {
    py::gil_scoped_release released;
    box = map.window_box();
  }
  if (!box) return py::none();
  return py::make_tuple(py::make_tuple(box->lo.x, box->lo.y, box->lo.z), py::make_tuple(box->hi.x, box->hi.y, box->hi.z));
}

}  // namespace

void bind_window(py::module_& m, MapClass& map) {
  py::class_<WindowMove>(m, "WindowMove", "What one move of the moving window did.")
      .def_readonly("moved", &WindowMove::moved, "False when the box was already there.")
      .def_readonly("groups_freed", &WindowMove::groups_freed, "Groups of eight nodes returned to the tree's pools.")
      .def_readonly("spilled", &WindowMove::spilled, "Whether a piece was appended to the spill file.")
      .def("__repr__",
           [](py::handle self) { return repr_of_attributes(self, "WindowMove", {"moved", "groups_freed", "spilled"}); });
  map.def("set_moving_window", &set_moving_window, py::arg("half_extent"), py::arg("spill_path") = py::none(),
          py::arg("step_depth") = -1, py::arg("follow_scans") = true,
          "Keeps only a box around the robot: every point within half_extent metres of it on each axis, in whole "
          "nodes of depth step_depth (-1: automatic). With follow_scans every insert first re-centres the box on "
          "its origin, and scans change only the box. What leaves the box is appended to spill_path (a spill "
          "file, see load_spill) or dropped, then forgotten (unknown, memory freed). None: no window (the map "
          "keeps what it holds). ValueError for a bad half_extent or step_depth.");
  map.def("move_window", [](OccupancyMap& self, py::handle position) {
            const Vec3d where = vec3_of(position, "position");
            py::gil_scoped_release released;
            return self.move_window(where);
          },
          py::arg("position"),
          "Re-centres the moving window's box on position (the robot); what leaves goes to the spill file or is "
          "dropped. RuntimeError without a window, IndexError outside the map. Returns a WindowMove.");
  map.def_property_readonly("window_box", &window_box,
                            "The moving window's box as ((lo keys), (hi keys)), inclusive; None before it is placed.");
  m.def(
      "load_spill",
      [](const std::filesystem::path& path) {
        py::gil_scoped_release released;
        return load_spill(path);
      },
      py::arg("path"),
      "Every piece of a moving window's spill file merged into one map (log-odds added); merge the window's map "
      "into it to get the whole run. FormatError naming the byte offset for a damaged file.");
}

}  // namespace umbra::python
