// Writing the map a command made (build, convert, crop): the format by the
// output's extension (.umb, .bt, .ot), the checks that can be made before
// any work, what an OctoMap format will not keep, and the atomic save of
// the library's writers (umbra/io/file_saving.hpp). Cost: that of the
// format's writer.
#pragma once

#include <optional>
#include <string>

#include "umbra/io/map_formats.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra::cli {

/// Throws std::invalid_argument (a usage error) when `path` has no map
/// extension, or names an OctoMap format (16 depth levels, always) for a map
/// of other `depth_levels`; the message names `what` ("output", "-o") and
/// the value.
MapFileFormat check_map_output(const std::string& path, int depth_levels, const std::string& what);

/// Notes on stderr, before writing, about what the output format drops:
/// .bt keeps free / occupied only (and no color); OctoMap files keep no
/// sensor model or thresholds. `input`: the format the map was read from
/// (none: it was built from scans).
void print_format_notes(const OccupancyMap& map, std::optional<MapFileFormat> input, MapFileFormat output);

/// Saves `map` in the format its extension names, atomically; .umb with
/// `threads` compressing (0: all cores).
void save_map_as(const OccupancyMap& map, const std::string& path, unsigned threads = 0);

}  // namespace umbra::cli
