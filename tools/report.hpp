// Printing what the commands found: map statistics as text or JSON, sizes.
#pragma once

#include <cstdio>
#include <string>

#include "umbra/map/occupancy_map.hpp"

#include "umbra/map/map_statistics.hpp"

namespace umbra::cli {

/// "12.3 MiB"
std::string human_bytes(std::size_t bytes);
/// Several indented lines: resolution, nodes, memory, voxels, volumes, bounds.
void print_statistics(std::FILE* out, const MapStatistics& stats);
/// One JSON object (keys in the README, "The command-line program"); always
/// valid JSON (a non-finite number would be null). `extra`: more members,
/// ", \"key\": value" each, written before the closing brace.
std::string statistics_json(const MapStatistics& stats, const std::string& extra = {});

/// The nodes liboctomap would hold for this map (its OcTree::size(), as
/// when the map is written as .ot and read by liboctomap): OctoMap stores a
/// node only where something below it was observed, so it counts the
/// childless nodes whose value is not exactly 0 (unknown) and every node
/// above one. umbra's own count (NodeCounts) is larger: a node with children
/// has all eight, unknown ones included (docs/design.md, Semantics). One pass over the
/// childless nodes.
std::size_t octomap_node_count(const OccupancyMap& map);

}  // namespace umbra::cli
