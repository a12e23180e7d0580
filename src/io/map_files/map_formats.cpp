// Format dispatch by extension for loading and saving maps (map_formats.hpp).
//
// Cost: a case-insensitive comparison of the extension, then the format's
// own reader or writer.
#include "umbra/io/map_formats.hpp"

#include <cctype>
#include <stdexcept>
#include <string>

#include "umbra/io/map_file.hpp"
#include "umbra/io/octomap_files.hpp"

namespace umbra {

const char* to_string(MapFileFormat format) {
  switch (format) {
    case MapFileFormat::umb:
      return "umb";
    case MapFileFormat::bt:
      return "bt";
    case MapFileFormat::ot:
      return "ot";
  }
  return "?";
}

std::optional<MapFileFormat> map_file_format(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (extension == ".umb") return MapFileFormat::umb;
  if (extension == ".bt") return MapFileFormat::bt;
  if (extension == ".ot") return MapFileFormat::ot;
  return std::nullopt;
}

MapFileFormat map_file_format_for(const std::filesystem::path& path) {
  if (const auto format = map_file_format(path)) return *format;
  const std::string extension = path.extension().string();
  throw std::invalid_argument("'" + path.string() + "': " +
                              (extension.empty() ? std::string("no file extension")
                                                 : "unknown map file extension '" + extension + "'") +
                              " (known: .umb umbra, .bt OctoMap binary, .ot OctoMap full)");
}

OccupancyMap load_any_map(const std::filesystem::path& path, const SensorModel& sensor) {
  switch (map_file_format_for(path)) {
    case MapFileFormat::umb:
      return load_map(path);
    case MapFileFormat::bt:
    case MapFileFormat::ot:
      return load_octomap(path, sensor);  // the first line tells .bt from .ot
  }
  throw std::logic_error("load_any_map: unhandled format");
}

void save_any_map(const OccupancyMap& map, const std::filesystem::path& path) {
  switch (map_file_format_for(path)) {
    case MapFileFormat::umb:
      save_map(map, path);
      return;
    case MapFileFormat::bt:
      save_octomap(map, path, OctoMapFormat::bt);
      return;
    case MapFileFormat::ot:
      save_octomap(map, path, OctoMapFormat::ot);
      return;
  }
}

}  // namespace umbra
