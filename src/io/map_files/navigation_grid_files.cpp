// map_server's PGM + YAML for a navigation grid (navigation_grid_files.hpp).
#include "umbra/io/navigation_grid_files.hpp"

#include <cstdio>
#include <span>
#include <stdexcept>
#include <string>

#include "umbra/io/file_saving.hpp"

namespace umbra {
namespace {

void check_grid(const NavigationGrid& grid) {
  if (grid.empty() || grid.width == 0 || grid.height == 0) {
    throw std::invalid_argument("the navigation grid is empty (nothing known between the heights): no picture to write");
  }
  if (grid.cells.size() != std::size_t{grid.width} * grid.height) {
    throw std::invalid_argument("the navigation grid has " + std::to_string(grid.cells.size()) + " cells, not width " +
                                std::to_string(grid.width) + " x height " + std::to_string(grid.height));
  }
}

/// Twelve significant digits: metres to far below a voxel, without the
/// 17-digit tails (-6.5600000000000005) of corners computed as key * res.
std::string number_text(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.12g", value);
  std::string text(buffer);
  // YAML reads "1e-05" and "3" as numbers too, but keep a decimal point so every reader sees a float.
  if (text.find_first_of(".en") == std::string::npos) text += ".0";
  return text;
}

/// A YAML double-quoted scalar: any file name, spaces, colons and quotes included.
std::string yaml_quoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char escape[8];
      std::snprintf(escape, sizeof escape, "\\x%02x", static_cast<unsigned char>(c));
      out += escape;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

}  // namespace

std::vector<std::uint8_t> navigation_grid_pgm(const NavigationGrid& grid) {
  check_grid(grid);
  const std::string header = "P5\n# CREATOR: umbra project, " + number_text(grid.resolution) + " m/pix\n" +
                             std::to_string(grid.width) + " " + std::to_string(grid.height) + "\n255\n";
  std::vector<std::uint8_t> bytes(header.begin(), header.end());
  bytes.reserve(header.size() + grid.cells.size());
  for (std::uint32_t row = grid.height; row-- > 0;) {  // the first row is the highest y
    for (std::uint32_t x = 0; x < grid.width; ++x) {
      const GridCell cell = grid.at(x, row);
      bytes.push_back(cell == GridCell::free ? kPgmFree : cell == GridCell::occupied ? kPgmOccupied : kPgmUnknown);
    }
  }
  return bytes;
}

std::string navigation_grid_yaml(const NavigationGrid& grid, const std::string& image_name) {
  check_grid(grid);
  return "image: " + yaml_quoted(image_name) + "\nmode: trinary\nresolution: " + number_text(grid.resolution) +
         "\norigin: [" + number_text(grid.origin_x) + ", " + number_text(grid.origin_y) +
         ", 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
}

std::filesystem::path navigation_grid_yaml_path(const std::filesystem::path& image_path) {
  if (image_path.extension() != ".pgm" || image_path.stem().empty()) {
    throw std::invalid_argument("a navigation grid's picture must be a .pgm file, got '" + image_path.string() + "'");
  }
  std::filesystem::path yaml = image_path;
  yaml.replace_extension(".yaml");
  return yaml;
}

std::filesystem::path save_navigation_grid(const NavigationGrid& grid, const std::filesystem::path& image_path) {
  const std::filesystem::path yaml_path = navigation_grid_yaml_path(image_path);
  const std::vector<std::uint8_t> pgm = navigation_grid_pgm(grid);
  const std::string yaml = navigation_grid_yaml(grid, image_path.filename().string());
  write_file_atomically(image_path, {std::span<const std::uint8_t>(pgm)}, "picture");
  write_file_atomically(
      yaml_path, {std::span(reinterpret_cast<const std::uint8_t*>(yaml.data()), yaml.size())}, "map description");
  return yaml_path;
}

}  // namespace umbra
