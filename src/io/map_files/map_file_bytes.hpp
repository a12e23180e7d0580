// A .umb map file as bytes in memory, for io's own code (the spill file of
// a moving window holds one per piece). Not installed.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "umbra/map/occupancy_map.hpp"

namespace umbra::detail {

/// The bytes save_map would write for `map` (compressed on this thread).
[[nodiscard]] std::vector<std::uint8_t> encode_map_file(const OccupancyMap& map);

/// The map in `bytes`, a whole .umb file, validated as load_map does;
/// FormatError names `name` and offsets counted from the first byte.
[[nodiscard]] OccupancyMap decode_map_file(const std::string& name, std::span<const std::uint8_t> bytes);

}  // namespace umbra::detail
