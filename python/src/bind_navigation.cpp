// The navigation grid in Python: OccupancyMap.project(z_min, z_max, ...)
// returns a umbra.NavigationGrid whose cells are a numpy int8 array
// (height, width), -1 unknown, 0 free, 100 occupied, row 0 the lowest y (the
// layout of nav_msgs/OccupancyGrid); .save(path) writes map_server's PGM +
// YAML. The projection runs with the GIL released; the cells are a view of
// the grid's own memory, kept alive by the array (no copy).
#include <filesystem>
#include <stdexcept>
#include <string>

#include <pybind11/stl/filesystem.h>

#include "bindings.hpp"
#include "umbra/io/navigation_grid_files.hpp"
#include "umbra/query/navigation_grid.hpp"

namespace umbra::python {

void bind_navigation(py::module_& module, MapClass& map) {
  static_assert(sizeof(GridCell) == sizeof(std::int8_t));
  py::class_<NavigationGrid>(module, "NavigationGrid",
                             "A map projected between two heights (OccupancyMap.project): a 2D grid of cells.")
      .def_property_readonly(
          "cells",
          [](py::object self) {
            const auto& grid = self.cast<const NavigationGrid&>();
            const auto* data = reinterpret_cast<const std::int8_t*>(grid.cells.data());
            py::array_t<std::int8_t> cells({py::ssize_t(grid.height), py::ssize_t(grid.width)}, data, self);
            py::detail::array_proxy(cells.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
            return cells;
          },
          "The cells, an int8 array (height, width): -1 unknown, 0 free, 100 occupied; cells[j, i] is column i "
          "(x) of row j (y), row 0 the lowest y (nav_msgs/OccupancyGrid's layout). Read-only.")
      .def_readonly("resolution", &NavigationGrid::resolution, "Edge of a cell, metres.")
      .def_readonly("depth", &NavigationGrid::depth, "The map depth whose node columns are the cells.")
      .def_property_readonly(
          "origin", [](const NavigationGrid& g) { return py::make_tuple(g.origin_x, g.origin_y); },
          "(x, y) of the lower-left corner of cell [0, 0], metres.")
      .def_readonly("width", &NavigationGrid::width, "Cells along x.")
      .def_readonly("height", &NavigationGrid::height, "Cells along y.")
      .def(
          "save",
          [](const NavigationGrid& grid, const std::filesystem::path& path) {
            std::string failure;  // a file that cannot be written: OSError, raised with the GIL held
            {
              py::gil_scoped_release released;
              try {
                return save_navigation_grid(grid, path).string();
              } catch (const std::invalid_argument&) {
                throw;
              } catch (const std::runtime_error& e) {
                failure = e.what();
              }
            }
            PyErr_SetString(PyExc_OSError, failure.c_str());
            throw py::error_already_set();
          },
          py::arg("path"),
          "Writes map_server's PGM picture to path (.pgm) and its YAML description beside it (.yaml), both "
          "atomically; returns the YAML file's path. ValueError for an empty grid or a path not ending in .pgm, "
          "OSError when a file cannot be written.")
      .def("__repr__", [](const NavigationGrid& g) {
        return "NavigationGrid(width=" + std::to_string(g.width) + ", height=" + std::to_string(g.height) +
               ", resolution=" + std::string(py::repr(py::float_(g.resolution))) + ", origin=(" +
               std::string(py::repr(py::float_(g.origin_x))) + ", " + std::string(py::repr(py::float_(g.origin_y))) +
               "))";
      });

  map.def(
      "project",
      [](const OccupancyMap& m, double z_min, double z_max, int depth, const std::string& rule) {
        ProjectionOptions options{z_min, z_max, depth, parse_projection_rule(rule)};
        py::gil_scoped_release released;
        return project_to_grid(m, options);
      },
      py::arg("z_min"), py::arg("z_max"), py::kw_only(), py::arg("depth") = 0, py::arg("rule") = "all_known",
      "The map projected between heights z_min and z_max (metres): a NavigationGrid. A cell (the column of a "
      "depth-`depth` node) is occupied if a voxel of its band (the voxel rows from the one holding z_min to the "
      "one holding z_max) is occupied; free if every voxel of the band is free (rule 'all_known') or if at least "
      "one is (rule 'any_free', octomap_server's); unknown otherwise. The grid spans the cells whose band holds a "
      "known voxel (empty when none does). ValueError for z_min >= z_max, a bad depth or rule; IndexError when "
      "the band lies outside the map.");
}

}  // namespace umbra::python
