// OctoMap ScanGraph files (.graph): reading them scan by scan, and writing them.
//
// A ScanGraph is OctoMap's binary container for a sequence of scans with
// poses: per scan the points in the sensor frame plus a 6D pose (translation
// and unit quaternion), followed by optional graph edges. The reader streams
// one scan at a time, transforms the points into the map frame (world point =
// R p + t, sensor origin = t) and validates the whole file structure when it
// is opened, so a truncated or hostile file is reported with the byte offset
// before any scan is yielded. The writer exists so that tests and tools can
// produce ScanGraphs that OctoMap reads as well.
#pragma once

#include <filesystem>
#include <memory>
#include <vector>

#include "umbra/io/scan_source.hpp"

namespace umbra {

/// Opens an uncompressed ScanGraph. Throws std::runtime_error("cannot open
/// FILE: reason") when the file cannot be opened and FormatError (with the
/// byte offset) when its structure is invalid. open_scan_source() calls this
/// for the "graph" format.
std::unique_ptr<ScanSource> open_scan_graph(const std::filesystem::path& path);

/// Writes `scans` as a ScanGraph: one node per scan with identity rotation,
/// translation = scan.origin and the points stored relative to the origin (so
/// reading the file back gives the same map-frame points up to float
/// rounding), node ids 0, 1, ..., and no edges. Colors are not stored (the
/// format has none). The file is saved atomically (umbra/io/file_saving.hpp),
/// so readers never see a partial file.
/// Throws std::invalid_argument for a non-finite origin or a scan with more
/// than 2^32 - 1 points, std::runtime_error when writing fails.
void write_scan_graph(const std::filesystem::path& path, const std::vector<Scan>& scans);

}  // namespace umbra
