// Map files of every format umbra knows, chosen by the file name's extension.
//
//   .umb  umbra's own format (map_file.hpp): exact, every setting kept
//   .bt   OctoMap binary (octomap_files.hpp): free/occupied per leaf only
//   .ot   OctoMap full (octomap_files.hpp): log-odds per node, color in a ColorOcTree
//
// The extension is matched without regard to case. Cost: that of the
// format's own reader or writer; choosing it costs nothing.
// Errors: an unknown extension throws std::invalid_argument naming it and
// the known ones; the readers and writers throw what their headers say.
#pragma once

#include <filesystem>
#include <optional>

#include "umbra/core/log_odds.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra {

enum class MapFileFormat : unsigned char { umb, bt, ot };

/// "umb", "bt" or "ot".
const char* to_string(MapFileFormat format);

/// The format of `path` by its extension, or nothing when it is not one of
/// .umb, .bt, .ot (any case).
[[nodiscard]] std::optional<MapFileFormat> map_file_format(const std::filesystem::path& path);

/// The same, throwing std::invalid_argument ("'x.foo': unknown map file
/// extension '.foo' (known: .umb, .bt, .ot)") when there is none.
[[nodiscard]] MapFileFormat map_file_format_for(const std::filesystem::path& path);

/// Loads a map of any known format. `sensor` is used for OctoMap files only
/// (they store no sensor model; a .umb file carries its own).
[[nodiscard]] OccupancyMap load_any_map(const std::filesystem::path& path, const SensorModel& sensor = {});

/// Saves `map` in the format its extension names, atomically (every writer
/// writes a temporary file and renames it over `path`).
void save_any_map(const OccupancyMap& map, const std::filesystem::path& path);

}  // namespace umbra
