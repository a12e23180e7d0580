// Printing what the commands found: map statistics as text or JSON, sizes.
#pragma once

#include <cstdio>
#include <string>

#include "umbra/map/map_statistics.hpp"

namespace umbra::cli {

/// "12.3 MiB"
std::string human_bytes(std::size_t bytes);
/// Several indented lines: resolution, nodes, memory, voxels, volumes, bounds.
void print_statistics(std::FILE* out, const MapStatistics& stats);
/// One JSON object (keys in docs/cli.md); always valid JSON (a non-finite number would be null).
std::string statistics_json(const MapStatistics& stats);

}  // namespace umbra::cli
