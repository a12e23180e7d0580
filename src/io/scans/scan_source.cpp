// open_scan_source(): picks the point-cloud reader for a file from the
// registry of scan formats.
//
// The registry is a table of formats, each with its name, its extensions and
// the function that opens it: the built-in readers (scan_graph_reader.cpp,
// xyz_reader.cpp, ply_reader.cpp, pcd_reader.cpp, kitti_reader.cpp,
// tum_reader.cpp) and what register_scan_format() adds (ros/ adds the
// reader of "rosbag", .bag, which without it is refused with a message).
// The format comes from ScanSourceOptions::format when it names a known
// format, else from the file's extension (case-insensitive, after removing a
// trailing ".bz2"); an existing folder without a known extension is a TUM
// RGB-D sequence when it holds depth/ and rgb/, KITTI velodyne scans when it
// holds .bin files. Telling a folder's format costs one directory listing;
// the table is looked up under a mutex (a few entries).
#include <algorithm>
#include <array>
#include <cctype>
#include <filesystem>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "umbra/io/kitti_sequence.hpp"
#include "umbra/io/pcd_file.hpp"
#include "umbra/io/ply_file.hpp"
#include "umbra/io/scan_graph.hpp"
#include "umbra/io/scan_source.hpp"
#include "umbra/io/tum_sequence.hpp"
#include "umbra/io/xyz_file.hpp"

namespace umbra {
namespace {

struct ScanFormat {
  std::string name;
  std::vector<std::string> extensions;  // lower case, with the dot
  ScanSourceOpener open;                // null: known but not readable in this build
};

std::unique_ptr<ScanSource> open_tum(const std::filesystem::path& path, const ScanSourceOptions& options) {
  std::error_code ignored;
  if (std::filesystem::is_directory(path, ignored)) {
    return open_tum_sequence(find_tum_association(path, options.association), options.depth_camera);
  }
  return open_tum_sequence(path, options.depth_camera);
}

std::unique_ptr<ScanSource> open_kitti(const std::filesystem::path& path, const ScanSourceOptions& options) {
  KittiOptions kitti;
  kitti.poses = options.poses;
  kitti.calibration = options.calibration;
  kitti.origin = options.origin;
  return open_kitti_velodyne(path, kitti);
}

/// The formats, in the order messages list them.
struct Registry {
  std::mutex mutex;
  std::vector<ScanFormat> formats{
      {"graph", {".graph"}, [](const auto& path, const auto&) { return open_scan_graph(path); }},
      {"xyz", {".xyz", ".dat", ".txt"}, [](const auto& path, const auto& o) { return open_xyz_file(path, o.origin); }},
      {"ply", {".ply"}, [](const auto& path, const auto& o) { return open_ply_file(path, o.origin); }},
      {"pcd", {".pcd"}, [](const auto& path, const auto& o) { return open_pcd_file(path, o.origin); }},
      {"kitti", {".bin"}, open_kitti},
      {"tum", {}, open_tum},
      {"rosbag", {".bag"}, nullptr},  // ros/ registers the reader (register_rosbag_format)
  };
};

Registry& registry() {
  static Registry instance;
  return instance;
}

std::string lower_case(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

std::string known_formats_text(const std::vector<ScanFormat>& formats) {
  std::string text;
  for (const ScanFormat& format : formats) {
    if (!text.empty()) text += ", ";
    text += format.name;
  }
  return text;
}

std::string known_extensions_text(const std::vector<ScanFormat>& formats) {
  std::string text;
  for (const ScanFormat& format : formats) {
    for (const std::string& extension : format.extensions) {
      if (!text.empty()) text += ", ";
      text += extension;
    }
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

/// The format's name, looked up in `formats` (the registry, locked by the caller).
std::string format_for(const std::vector<ScanFormat>& formats, const std::filesystem::path& path,
                       const std::string& format) {
  if (!format.empty()) {
    const std::string requested = lower_case(format);
    for (const ScanFormat& known : formats) {
      if (requested == known.name) return known.name;
    }
    throw std::invalid_argument("unknown scan format '" + format + "'; known formats: " +
                                known_formats_text(formats) + "; known extensions: " + known_extensions_text(formats));
  }

  std::string name = lower_case(path.filename().string());
  if (name.ends_with(".bz2")) name.resize(name.size() - 4);
  const std::size_t dot = name.rfind('.');
  const std::string extension = dot == std::string::npos ? std::string() : name.substr(dot);
  for (const ScanFormat& known : formats) {
    if (std::find(known.extensions.begin(), known.extensions.end(), extension) != known.extensions.end()) {
      return known.name;
    }
  }
  std::error_code ignored;
  if (std::filesystem::is_directory(path, ignored)) {
    std::string format_of_folder = folder_format(path);
    if (!format_of_folder.empty()) return format_of_folder;
    throw std::invalid_argument("cannot tell the point-cloud format of the folder " + path.string() +
                                ": it holds neither depth/ and rgb/ (a TUM RGB-D sequence) nor .bin files (KITTI "
                                "velodyne scans); known extensions: " + known_extensions_text(formats) +
                                "; or name the format (" + known_formats_text(formats) + ")");
  }
  throw std::invalid_argument("cannot tell the point-cloud format of " + path.string() +
                              " from its name; known extensions: " + known_extensions_text(formats) +
                              "; or name the format (" + known_formats_text(formats) + ")");
}

}  // namespace

std::string scan_format_for(const std::filesystem::path& path, const std::string& format) {
  Registry& known = registry();
  const std::lock_guard lock(known.mutex);
  return format_for(known.formats, path, format);
}

void register_scan_format(const std::string& name, const std::vector<std::string>& extensions,
                          ScanSourceOpener open) {
  if (name.empty() || name != lower_case(name) || !open) {
    throw std::invalid_argument("register_scan_format: the name must be non-empty lower case ('" + name +
                                "') and the opener set");
  }
  Registry& known = registry();
  const std::lock_guard lock(known.mutex);
  auto entry = std::find_if(known.formats.begin(), known.formats.end(),
                            [&](const ScanFormat& format) { return format.name == name; });
  if (entry == known.formats.end()) entry = known.formats.insert(known.formats.end(), ScanFormat{name, {}, nullptr});
  entry->open = std::move(open);
  for (const std::string& extension : extensions) {
    const std::string lower = lower_case(extension);
    if (std::find(entry->extensions.begin(), entry->extensions.end(), lower) == entry->extensions.end()) {
      entry->extensions.push_back(lower);
    }
  }
}

std::unique_ptr<ScanSource> open_scan_source(const std::filesystem::path& path,
                                             const ScanSourceOptions& options) {
  ScanSourceOpener open;
  std::string format;
  {
    Registry& known = registry();
    const std::lock_guard lock(known.mutex);
    format = format_for(known.formats, path, options.format);
    for (const ScanFormat& entry : known.formats) {
      if (entry.name == format) open = entry.open;
    }
  }
  if (!open) {  // "rosbag" without ros/
    throw std::runtime_error("cannot read " + path.string() +
                             ": ROS bag files (.bag) are read only by umbra built with ROS 1 (Debian's ROS packages, "
                             "listed in scripts/common.sh, present when configuring; see docs/ros.md); this build "
                             "has no ROS support");
  }
  return open(path, options);
}

}  // namespace umbra
