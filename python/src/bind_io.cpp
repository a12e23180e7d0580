// Files: umbra.load / OccupancyMap.save for .umb, .bt and .ot
// (umbra/io/map_formats.hpp), and umbra.read_scans over every point-cloud
// reader (umbra/io/scan_source.hpp), yielding numpy arrays.
//
// Errors: a malformed file raises umbra.FormatError (a ValueError) with the
// library's message (file, line or byte offset); a missing path
// FileNotFoundError; any other failure to read or write a file OSError; an
// unknown extension or format ValueError. Reading and writing release the
// GIL; each scan's arrays are copied once out of the reader's vectors.
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <mutex>

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.hpp"
#include "numpy_arrays.hpp"
#include "umbra/io/format_error.hpp"
#include "umbra/io/map_formats.hpp"
#include "umbra/io/scan_source.hpp"

namespace umbra::python {
namespace {

namespace fs = std::filesystem;

/// A file the library could not open, read or write: raised as OSError.
class FileAccessError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Runs a file operation, turning the library's I/O errors (plain
/// std::runtime_error, not FormatError) into FileAccessError.
template <typename Operation>
decltype(auto) file_operation(const Operation& operation) {
  try {
    return operation();
  } catch (const FormatError&) {
    throw;
  } catch (const std::runtime_error& e) {
    throw FileAccessError(e.what());
  }
}

/// FileNotFoundError (with errno and file name, as open() raises it) when nothing is at `path`.
void require_exists(const fs::path& path) {
  std::error_code error;
  if (fs::exists(path, error)) return;
  const py::object exception = py::module_::import("builtins")
                                   .attr("FileNotFoundError")(ENOENT, std::strerror(ENOENT), path.string());
  PyErr_SetObject(PyExc_FileNotFoundError, exception.ptr());
  throw py::error_already_set();
}

/// A scan source as a Python iterator of (origin, points, colors).
class ScanReader {
 public:
  explicit ScanReader(std::unique_ptr<ScanSource> source) : source_(std::move(source)) {}

  py::object next() {
    Scan scan;
    bool more = false;
    {
      py::gil_scoped_release released;
      std::lock_guard lock(mutex_);  // a reader serves one thread at a time
      more = file_operation([&] { return source_->next(scan); });
      if (more) {
        name_ = scan.name;
        stamp_ = scan.stamp;
      }
    }
    if (!more) throw py::stop_iteration();
    const auto n = static_cast<py::ssize_t>(scan.points.size());
    py::array_t<float> origin(3);
    std::copy_n(&scan.origin.x, 3, origin.mutable_data());
    py::array_t<float> points({n, py::ssize_t{3}});
    if (n > 0) std::copy_n(&scan.points.data()->x, 3 * scan.points.size(), points.mutable_data());
    py::object colors = py::none();
    if (!scan.colors.empty()) {
      py::array_t<std::uint8_t> rgb({n, py::ssize_t{3}});
      std::copy_n(&scan.colors.data()->r, 3 * scan.colors.size(), rgb.mutable_data());
      colors = std::move(rgb);
    }
    return py::make_tuple(origin, points, colors);
  }
  // With the GIL held: next() gives the lock up before it takes the GIL back.
  [[nodiscard]] std::size_t scan_count() {
    std::lock_guard lock(mutex_);
    return source_->scan_count();
  }
  [[nodiscard]] double progress() {
    std::lock_guard lock(mutex_);
    return source_->progress();
  }
  [[nodiscard]] std::string name() {
    std::lock_guard lock(mutex_);
    return name_;
  }
  [[nodiscard]] std::optional<double> stamp() {
    std::lock_guard lock(mutex_);
    return stamp_;
  }

 private:
  std::unique_ptr<ScanSource> source_;
  std::string name_;
  std::optional<double> stamp_;
  std::mutex mutex_;
};

std::unique_ptr<ScanReader> read_scans(const fs::path& path, const std::optional<std::string>& format, py::handle origin,
                      const std::optional<fs::path>& poses, const std::optional<fs::path>& calibration,
                      const std::optional<fs::path>& association, const std::optional<DepthCamera>& camera) {
  ScanSourceOptions options;
  options.format = format.value_or("");
  options.origin = Vec3f(vec3_of(origin, "origin"));
  options.poses = poses.value_or(fs::path());
  options.calibration = calibration.value_or(fs::path());
  options.association = association.value_or(fs::path());
  if (camera) options.depth_camera = *camera;
  require_exists(path);
  py::gil_scoped_release released;
  return std::make_unique<ScanReader>(file_operation([&] { return open_scan_source(path, options); }));
}

}  // namespace

void bind_io(py::module_& m, MapClass& map) {
  py::register_exception<FormatError>(m, "FormatError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr error) {
    try {
      if (error) std::rethrow_exception(error);
    } catch (const FileAccessError& e) {
      PyErr_SetString(PyExc_OSError, e.what());
    }
  });

  m.def(
      "load",
      [](const fs::path& path, const std::optional<SensorModel>& sensor) {
        require_exists(path);
        py::gil_scoped_release released;
        return file_operation([&] { return load_any_map(path, sensor.value_or(SensorModel{})); });
      },
      py::arg("path"), py::arg("sensor_model") = py::none(),
      "Loads a map from a .umb, .bt or .ot file (by extension). sensor_model applies to OctoMap files only "
      "(they store none).");
  map.def(
      "save",
      [](const OccupancyMap& self, const fs::path& path) {
        py::gil_scoped_release released;
        file_operation([&] { save_any_map(self, path); });
      },
      py::arg("path"),
      "Saves the map as .umb, .bt or .ot (by extension), atomically: a temporary file renamed over path.");

  py::class_<DepthCamera>(m, "DepthCamera",
                          "A pinhole depth camera: pixel (u, v) with raw depth d lies at z = d / depth_scale "
                          "metres, x = (u - cx) z / fx, y = (v - cy) z / fy. Defaults: the TUM fr2 Kinect.")
      .def(py::init([](double fx, double fy, double cx, double cy, double depth_scale) {
             return DepthCamera{fx, fy, cx, cy, depth_scale};
           }),
           py::arg("fx") = 580.8, py::arg("fy") = 581.8, py::arg("cx") = 308.8, py::arg("cy") = 253.0,
           py::arg("depth_scale") = 5000.0, "The intrinsics in pixels and raw units per metre.")
      .def_readonly("fx", &DepthCamera::fx, "Focal length along u, pixels.")
      .def_readonly("fy", &DepthCamera::fy, "Focal length along v, pixels.")
      .def_readonly("cx", &DepthCamera::cx, "Principal point u, pixels.")
      .def_readonly("cy", &DepthCamera::cy, "Principal point v, pixels.")
      .def_readonly("depth_scale", &DepthCamera::depth_scale, "Raw depth units per metre.")
      .def("__repr__",
           [](py::handle self) { return repr_of_attributes(self, "DepthCamera", {"fx", "fy", "cx", "cy", "depth_scale"}); });

  py::class_<ScanReader>(m, "ScanReader",
                         "An iterator of scans (origin (3,) float32, points (N, 3) float32, colors (N, 3) uint8 "
                         "or None), read one at a time.")
      .def("__iter__", [](ScanReader& r) -> ScanReader& { return r; })
      .def("__next__", &ScanReader::next)
      .def_property_readonly("scan_count", &ScanReader::scan_count,
                             "Number of scans when the format says so up front, else 0.")
      .def_property_readonly("progress", &ScanReader::progress, "Fraction of the input read, 0..1.")
      .def_property_readonly("name", &ScanReader::name, "Where the last scan came from, e.g. 'run.graph scan 3'.")
      .def_property_readonly("stamp", &ScanReader::stamp,
                             "The last scan's time in seconds where the input states it (TUM: the depth image's "
                             "name; ROS bags: header.stamp), else None: pass it to Map.insert(stamp=...) for decay.")
      .def("__repr__",
           [](py::handle self) { return repr_of_attributes(self, "ScanReader", {"name", "scan_count", "progress"}); });

  m.def("read_scans", &read_scans, py::arg("path"), py::arg("format") = py::none(), py::kw_only(),
        py::arg("origin") = py::make_tuple(0.0, 0.0, 0.0), py::arg("poses") = py::none(),
        py::arg("calibration") = py::none(), py::arg("association") = py::none(), py::arg("camera") = py::none(),
        "Reads the scans of a point-cloud file or folder: a ScanReader. format: 'graph', 'xyz', 'ply', 'pcd', "
        "'kitti' or 'tum' (None: by name). origin: the sensor for formats without a pose; poses, calibration: "
        "KITTI; association, camera (a DepthCamera): TUM RGB-D.");
}

}  // namespace umbra::python
