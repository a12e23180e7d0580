// Writing the map a command made (map_output.hpp).
#include "map_output.hpp"

#include <cstdio>
#include <stdexcept>

#include "umbra/io/map_file.hpp"
#include "umbra/io/octomap_files.hpp"

namespace umbra::cli {

MapFileFormat check_map_output(const std::string& path, int depth_levels, const std::string& what) {
  const std::optional<MapFileFormat> format = map_file_format(path);
  if (!format) {
    try {
      (void)map_file_format_for(path);  // its message names the extension and the known ones
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(what + " " + e.what());
    }
  }
  if (*format != MapFileFormat::umb && depth_levels != kOctoMapDepthLevels) {
    throw std::invalid_argument(what + " '" + path + "': OctoMap files (." + to_string(*format) + ") hold " +
                                std::to_string(kOctoMapDepthLevels) + " depth levels, this map has " +
                                std::to_string(depth_levels) + "; write a .umb file");
  }
  return *format;
}

void print_format_notes(const OccupancyMap& map, std::optional<MapFileFormat> input, MapFileFormat output) {
  if (output == MapFileFormat::umb) return;
  if (output == MapFileFormat::bt && input != MapFileFormat::bt) {
    std::fprintf(stderr, "note: .bt keeps only free / occupied per leaf (OctoMap's maximum likelihood): every value "
                         "becomes the clamping minimum or maximum when read back%s\n",
                 map.has_color() ? ", and colors are dropped" : "");
  }
  if (input == MapFileFormat::umb && (!(map.sensor_model() == SensorModel{}) || !(map.thresholds() == Thresholds{}))) {
    std::fprintf(stderr, "note: OctoMap files store no sensor model or thresholds; reading the file back gives "
                         "OctoMap's defaults\n");
  }
}

void save_map_as(const OccupancyMap& map, const std::string& path, unsigned threads) {
  if (map_file_format_for(path) == MapFileFormat::umb) {
    save_map(map, path, MapSaveOptions{threads});
  } else {
    save_any_map(map, path);
  }
}

}  // namespace umbra::cli
