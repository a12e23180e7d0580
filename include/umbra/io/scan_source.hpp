// ScanSource: one interface for every point-cloud reader.
//
// A source yields scans one at a time (so a long sequence never has to fit
// in memory): the sensor origin and the points, both in the map frame, and
// optionally one colour per point. Readers pick the format from the file
// extension unless ScanSourceOptions::format names it.
//
// Formats: OctoMap ScanGraph (.graph, poses inside), ASCII "x y z" per line
// (.xyz, .dat, .txt, and any of them compressed as .bz2; the sensor sits at
// ScanSourceOptions::origin).
//
// Errors: malformed files throw umbra::FormatError naming the file and the
// line or byte offset; a missing file throws std::runtime_error naming it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "umbra/core/color.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/io/format_error.hpp"

namespace umbra {

struct Scan {
  Vec3f origin;               ///< sensor origin, map frame
  std::vector<Vec3f> points;  ///< map frame
  std::vector<Rgb> colors;    ///< empty, or one per point
  std::string name;           ///< where it came from, e.g. "run.graph scan 3"
};

class ScanSource {
 public:
  virtual ~ScanSource() = default;
  /// Reads the next scan into `scan` (reusing its buffers); false at the end.
  virtual bool next(Scan& scan) = 0;
  /// Number of scans when the format says so up front, else 0.
  [[nodiscard]] virtual std::size_t scan_count() const = 0;
  /// Fraction of the input consumed so far, 0..1 (for progress bars).
  [[nodiscard]] virtual double progress() const = 0;
};

struct ScanSourceOptions {
  std::string format;  ///< "graph", "xyz"; empty: chosen by extension
  Vec3f origin{};      ///< sensor origin for formats that carry none (xyz)
};

/// Opens `path`; throws std::runtime_error / FormatError as described above.
std::unique_ptr<ScanSource> open_scan_source(const std::filesystem::path& path,
                                             const ScanSourceOptions& options = {});

/// The format name open_scan_source would use for `path` ("graph", "xyz"), or
/// throws std::invalid_argument listing the known extensions.
std::string scan_format_for(const std::filesystem::path& path, const std::string& format = "");

}  // namespace umbra
