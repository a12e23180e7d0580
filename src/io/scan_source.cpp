// open_scan_source(): picks the point-cloud reader for a file.
//
// The format comes from ScanSourceOptions::format when it names a known
// format, else from the file's extension (case-insensitive, after removing a
// trailing ".bz2"): .graph is an OctoMap ScanGraph, .xyz/.dat/.txt are ASCII
// points, .ply PLY, .pcd PCD, .bin a KITTI velodyne scan, .bag a ROS bag
// (read in ROS builds by ros/src/rosbag_source.cpp; refused here); an existing folder
// without one of these extensions is a TUM RGB-D sequence when it holds
// depth/ and rgb/, KITTI velodyne scans when it holds .bin files. Telling a folder's format costs one
// directory listing. The readers live in scan_graph_reader.cpp,
// xyz_reader.cpp, ply_reader.cpp, pcd_reader.cpp, kitti_reader.cpp and
// tum_reader.cpp.
#include <algorithm>
#include <array>
#include <cctype>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>

#include "umbra/io/kitti_sequence.hpp"
#include "umbra/io/pcd_file.hpp"
#include "umbra/io/ply_file.hpp"
#include "umbra/io/scan_graph.hpp"
#include "umbra/io/scan_source.hpp"
#include "umbra/io/tum_sequence.hpp"
#include "umbra/io/xyz_file.hpp"

namespace umbra {
namespace {

struct FormatExtension {
  std::string_view extension;  // lower case, with the dot
  std::string_view format;
};

constexpr std::array<FormatExtension, 8> kExtensions{{
    {".graph", "graph"},
    {".xyz", "xyz"},
    {".dat", "xyz"},
    {".txt", "xyz"},
    {".ply", "ply"},
    {".pcd", "pcd"},
    {".bin", "kitti"},
    {".bag", "rosbag"},
}};

constexpr std::array<std::string_view, 7> kFormats{"graph", "xyz", "ply", "pcd", "kitti", "tum", "rosbag"};

std::string lower_case(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

std::string known_formats_text() {
  std::string text;
  for (const std::string_view format : kFormats) {
    if (!text.empty()) text += ", ";
    text += format;
  }
  return text;
}

std::string known_extensions_text() {
  std::string text;
  for (const auto& entry : kExtensions) {
    if (!text.empty()) text += ", ";
    text += entry.extension;
  }
  return text + " (.xyz/.dat/.txt optionally followed by .bz2; the others must be uncompressed), or a folder "
                "holding depth/ and rgb/ (TUM RGB-D) or .bin files (KITTI velodyne)";
}

/// The format of an existing folder, or empty.
std::string folder_format(const std::filesystem::path& folder) {
  std::error_code ignored;
  if (std::filesystem::is_directory(folder / "depth", ignored) && std::filesystem::is_directory(folder / "rgb", ignored)) {
    return "tum";
  }
  std::error_code error;
  for (std::filesystem::directory_iterator it(folder, error), end; !error && it != end; it.increment(error)) {
    if (lower_case(it->path().extension().string()) == ".bin") return "kitti";
  }
  return "";
}

}  // namespace

std::string scan_format_for(const std::filesystem::path& path, const std::string& format) {
  if (!format.empty()) {
    const std::string requested = lower_case(format);
    for (const std::string_view known : kFormats) {
      if (requested == known) return std::string(known);
    }
    throw std::invalid_argument("unknown scan format '" + format + "'; known formats: " +
                                known_formats_text() + "; known extensions: " + known_extensions_text());
  }

  std::string name = lower_case(path.filename().string());
  if (name.ends_with(".bz2")) name.resize(name.size() - 4);
  const std::size_t dot = name.rfind('.');
  const std::string extension = dot == std::string::npos ? std::string() : name.substr(dot);
  for (const auto& entry : kExtensions) {
    if (extension == entry.extension) return std::string(entry.format);
  }
  std::error_code ignored;
  if (std::filesystem::is_directory(path, ignored)) {
    std::string format_of_folder = folder_format(path);
    if (!format_of_folder.empty()) return format_of_folder;
    throw std::invalid_argument("cannot tell the point-cloud format of the folder " + path.string() +
                                ": it holds neither depth/ and rgb/ (a TUM RGB-D sequence) nor .bin files (KITTI "
                                "velodyne scans); known extensions: " + known_extensions_text() +
                                "; or name the format (" + known_formats_text() + ")");
  }
  throw std::invalid_argument("cannot tell the point-cloud format of " + path.string() +
                              " from its name; known extensions: " + known_extensions_text() +
                              "; or name the format (" + known_formats_text() + ")");
}

std::unique_ptr<ScanSource> open_scan_source(const std::filesystem::path& path,
                                             const ScanSourceOptions& options) {
  const std::string format = scan_format_for(path, options.format);
  if (format == "graph") return open_scan_graph(path);
  if (format == "ply") return open_ply_file(path, options.origin);
  if (format == "pcd") return open_pcd_file(path, options.origin);
  if (format == "kitti") {
    KittiOptions kitti;
    kitti.poses = options.poses;
    kitti.calibration = options.calibration;
    kitti.origin = options.origin;
    return open_kitti_velodyne(path, kitti);
  }
  if (format == "tum") {
    std::error_code ignored;
    if (std::filesystem::is_directory(path, ignored)) {
      return open_tum_sequence(find_tum_association(path, options.association), options.depth_camera);
    }
    return open_tum_sequence(path, options.depth_camera);
  }
  if (format == "rosbag") {
    throw std::runtime_error("cannot read " + path.string() +
                             ": ROS bag files (.bag) are read only by umbra built with ROS 1 (Debian's ROS packages, "
                             "listed in scripts/common.sh, present when configuring; see docs/ros.md); this build "
                             "has no ROS support");
  }
  return open_xyz_file(path, options.origin);
}

}  // namespace umbra
