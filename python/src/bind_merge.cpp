// OccupancyMap.merge and MergeStats (umbra/map/map_merge.hpp).
#include <string>

#include "bindings.hpp"
#include "numpy_arrays.hpp"

namespace umbra::python {
namespace {

VoxelOffset offset_of(py::handle object) {
  const py::sequence values = py::reinterpret_borrow<py::sequence>(object);
  if (!py::isinstance<py::sequence>(object) || py::len(values) != 3) {
    throw py::value_error("offset must be three integers (voxels), got " + std::string(py::repr(object)));
  }
  VoxelOffset offset;
  try {
    offset = {values[0].cast<std::int64_t>(), values[1].cast<std::int64_t>(), values[2].cast<std::int64_t>()};
  } catch (const py::cast_error&) {
    throw py::value_error("offset must be three integers (voxels), got " + std::string(py::repr(object)));
  }
  return offset;
}

MergeStats merge(OccupancyMap& map, const OccupancyMap& other, const py::object& offset, const py::object& transform) {
  if (!offset.is_none() && !transform.is_none()) {
    throw py::value_error("merge: give offset or transform, not both");
  }
  if (!transform.is_none()) {
    const Pose pose = pose_of(transform, "transform");
    py::gil_scoped_release released;
    return map.merge(other, pose);
  }
  const VoxelOffset shift = offset.is_none() ? VoxelOffset{} : offset_of(offset);
  py::gil_scoped_release released;
  return map.merge(other, shift);
}

}  // namespace

void bind_merge(py::module_& m, MapClass& map) {
  py::class_<MergeStats>(m, "MergeStats", "What a merge did.")
      .def_readonly("voxels", &MergeStats::voxels,
                    "Finest voxels of the map that received a value (a pruned node counts all its voxels).")
      .def_readonly("nodes", &MergeStats::nodes,
                    "Node additions applied to the tree (fewer than voxels where pruned blocks land whole).")
      .def("__repr__", [](py::handle self) { return repr_of_attributes(self, "MergeStats", {"voxels", "nodes"}); });
  map.def("merge", &merge, py::arg("other"), py::arg("offset") = py::none(), py::arg("transform") = py::none(),
          "Adds other's log-odds to this map's, voxel by voxel, clamped to this map's sensor model; voxels other "
          "never observed change nothing. offset (3 ints): other's voxel k lands on k + offset. transform ((4, 4) "
          "or (3, 4), other's frame to this map's, rigid): each voxel takes other's voxel its centre maps back "
          "into. Colors average by their sample counts where both maps have color. ValueError for other "
          "resolutions or depth levels, a transform that is not rigid, or both offset and transform; IndexError "
          "when a known voxel of other lands outside this map (the map is unchanged then). Returns MergeStats.");
}

}  // namespace umbra::python
