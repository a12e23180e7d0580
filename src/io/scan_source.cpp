// open_scan_source(): picks the point-cloud reader for a file.
//
// The format comes from ScanSourceOptions::format when it names a known
// format, else from the file's extension (case-insensitive, after removing a
// trailing ".bz2"): .graph is an OctoMap ScanGraph, .xyz/.dat/.txt are ASCII
// points. The readers themselves live in scan_graph_reader.cpp and
// xyz_reader.cpp.
#include <algorithm>
#include <array>
#include <cctype>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>

#include "umbra/io/scan_graph.hpp"
#include "umbra/io/scan_source.hpp"
#include "umbra/io/xyz_file.hpp"

namespace umbra {
namespace {

struct FormatExtension {
  std::string_view extension;  // lower case, with the dot
  std::string_view format;
};

constexpr std::array<FormatExtension, 4> kExtensions{{
    {".graph", "graph"},
    {".xyz", "xyz"},
    {".dat", "xyz"},
    {".txt", "xyz"},
}};

constexpr std::array<std::string_view, 2> kFormats{"graph", "xyz"};

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
  return text + " (each optionally followed by .bz2; .graph files must be uncompressed)";
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
  throw std::invalid_argument("cannot tell the point-cloud format of " + path.string() +
                              " from its name; known extensions: " + known_extensions_text() +
                              "; or name the format (" + known_formats_text() + ")");
}

std::unique_ptr<ScanSource> open_scan_source(const std::filesystem::path& path,
                                             const ScanSourceOptions& options) {
  const std::string format = scan_format_for(path, options.format);
  if (format == "graph") return open_scan_graph(path);
  return open_xyz_file(path, options.origin);
}

}  // namespace umbra
