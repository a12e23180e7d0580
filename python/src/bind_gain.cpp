// Information gain (umbra/query/information_gain.hpp) on umbra.OccupancyMap:
// information_gain(frustum) for one pose, information_gains(...) for many,
// given as a list of Frustums or as numpy arrays of poses (origins (N, 3),
// yaw and pitch (N,) in degrees; every other number (N,) or one for all).
//
// The batch answers go into a structured array (umbra.GAIN_DTYPE: the
// fields of GainResult). The poses are checked one by one first, so that a
// bad one is named by its index (ValueError for a bad field of view,
// IndexError for an origin outside the map); then the GIL is released and
// the library's batch runs on `threads` threads, taking the map for reading
// pose by pose. Building a Frustum per pose (a few numbers) costs nothing
// next to counting what it sees.
#include <string>
#include <vector>

#include <pybind11/stl.h>

#include "bindings.hpp"
#include "numpy_arrays.hpp"
#include "umbra/integrate/insert_options.hpp"  // max_threads()
#include "umbra/query/information_gain.hpp"
#include "umbra/query/shapes.hpp"

namespace umbra::python {
namespace {

/// One row of umbra.GAIN_DTYPE.
struct GainRecord {
  std::uint64_t unknown_voxels;
  double volume;
  double entropy_bits;
};

GainOptions gain_options(const std::string& method, int fast_depth, int threads) {
  if (threads < 0) throw std::invalid_argument("threads must be >= 0 (0: all cores), got " + std::to_string(threads));
  // The bound insert() has (InsertOptions): thousands of threads would end
  // the interpreter when the system refuses them.
  if (static_cast<unsigned>(threads) > max_threads()) {
    throw std::invalid_argument("threads must be at most " + std::to_string(max_threads()) +
                                " (4 per hardware thread, at least 16; umbra's max_threads()), got " +
                                std::to_string(threads));
  }
  GainOptions options;
  if (method == "exact") {
    options.method = GainMethod::exact;
  } else if (method == "fast") {
    options.method = GainMethod::fast;
  } else {
    throw std::invalid_argument("method must be 'exact' or 'fast', got '" + method + "'");
  }
  options.fast_depth = fast_depth;
  options.threads = static_cast<unsigned>(threads);
  return options;
}

/// Throws (with the pose's index) what the library would throw for it.
void check_pose(const OccupancyMap& map, const Frustum& frustum, std::size_t i) {
  try {
    frustum.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("pose " + std::to_string(i) + ": " + e.what());
  }
  if (!map.grid().key_checked(frustum.origin) || !map.grid().key_checked(Vec3f(frustum.origin))) {
    try {
      (void)map.grid().key(frustum.origin);  // its message names the coordinate and the map's extent
      (void)map.grid().key(Vec3d(Vec3f(frustum.origin)));
    } catch (const std::out_of_range& e) {
      throw std::out_of_range("pose " + std::to_string(i) + ": origin outside the map: " + e.what());
    }
  }
}

py::array gains(const OccupancyMap& map, const std::vector<Frustum>& frustums, const GainOptions& options) {
  for (std::size_t i = 0; i < frustums.size(); ++i) check_pose(map, frustums[i], i);
  py::array_t<GainRecord> answers(static_cast<py::ssize_t>(frustums.size()));
  GainRecord* out = answers.mutable_data();
  {
    py::gil_scoped_release released;
    const std::vector<GainResult> results = map.information_gain(std::span<const Frustum>(frustums), options);
    for (std::size_t i = 0; i < results.size(); ++i) {
      out[i] = {results[i].unknown_voxels, results[i].volume, results[i].entropy_bits};
    }
  }
  return answers;
}

}  // namespace

void bind_gain(py::module_& module, MapClass& map) {
  PYBIND11_NUMPY_DTYPE(GainRecord, unknown_voxels, volume, entropy_bits);
  module.attr("GAIN_DTYPE") = py::dtype::of<GainRecord>();

  py::class_<GainResult>(module, "GainResult", "The information gain of one sensor pose.")
      .def_readonly("unknown_voxels", &GainResult::unknown_voxels,
                    "Unknown finest voxels whose centre lies in the frustum and is visible from its origin.")
      .def_readonly("volume", &GainResult::volume, "Their volume, cubic metres.")
      .def_readonly("entropy_bits", &GainResult::entropy_bits,
                    "Sum of the binary entropy of their occupancy, bits (unknown_voxels with the default "
                    "thresholds).")
      .def("__repr__", [](const GainResult& g) {
        return "GainResult(unknown_voxels=" + std::to_string(g.unknown_voxels) +
               ", volume=" + std::string(py::repr(py::float_(g.volume))) +
               ", entropy_bits=" + std::string(py::repr(py::float_(g.entropy_bits))) + ")";
      });

  map.def(
         "information_gain",
         [](const OccupancyMap& m, const Frustum& frustum, const std::string& method, int fast_depth) {
           const GainOptions options = gain_options(method, fast_depth, 1);
           py::gil_scoped_release released;
           return m.information_gain(frustum, options);
         },
         py::arg("frustum"), py::kw_only(), py::arg("method") = "exact", py::arg("fast_depth") = 2,
         "The unknown finest voxels a sensor with this Frustum would see (centre in the frustum, no occupied "
         "voxel on the ray from its origin): a GainResult. method 'exact' counts them voxel by voxel; 'fast' "
         "decides nodes of up to 2^fast_depth voxels per edge by their corner voxels.")
      .def(
          "information_gains",
          [](const OccupancyMap& m, const std::vector<Frustum>& frustums, const std::string& method, int fast_depth,
             int threads) { return gains(m, frustums, gain_options(method, fast_depth, threads)); },
          py::arg("frustums"), py::kw_only(), py::arg("method") = "exact", py::arg("fast_depth") = 2,
          py::arg("threads") = 0,
          "information_gain of many poses: a list of Frustums, or origins (N, 3), yaw and pitch (N,) in degrees "
          "and hfov, vfov (degrees), min_range, max_range, each (N,) or one number for all. Returns a "
          "structured array (N,) of umbra.GAIN_DTYPE (unknown_voxels, volume, entropy_bits). threads: 0 for "
          "all cores. A bad pose raises ValueError (IndexError for an origin outside the map) naming its "
          "index.")
      .def(
          "information_gains",
          [](const OccupancyMap& m, py::handle origins, py::handle yaw, py::handle pitch, py::handle hfov,
             py::handle vfov, py::handle min_range, py::handle max_range, const std::string& method, int fast_depth,
             int threads) {
            const GainOptions options = gain_options(method, fast_depth, threads);
            const RowArray o(origins, "origins");
            const ValueArray y(yaw, "yaw");
            const ValueArray p(pitch, "pitch");
            const ValueArray h(hfov, "hfov");
            const ValueArray v(vfov, "vfov");
            const ValueArray near(min_range, "min_range");
            const ValueArray far(max_range, "max_range");
            const std::size_t n = batch_count({{o.name(), o.count()},
                                               {y.name(), y.count()},
                                               {p.name(), p.count()},
                                               {h.name(), h.count()},
                                               {v.name(), v.count()},
                                               {near.name(), near.count()},
                                               {far.name(), far.count()}});
            std::vector<Frustum> frustums;
            frustums.reserve(n);
            for (std::size_t i = 0; i < n; ++i) {
              frustums.push_back(Frustum::from_degrees(o[i], y[i], p[i], h[i], v[i], near[i], far[i]));
            }
            return gains(m, frustums, options);
          },
          py::arg("origins"), py::arg("yaw"), py::arg("pitch"), py::arg("hfov"), py::arg("vfov"),
          py::arg("min_range"), py::arg("max_range"), py::kw_only(), py::arg("method") = "exact",
          py::arg("fast_depth") = 2, py::arg("threads") = 0);
}

}  // namespace umbra::python
