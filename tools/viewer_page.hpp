// The page of `umbra view`: one self-contained HTML file showing a map in 3D.
//
// The page is the template and script of tools/viewer/ (three.js, bundled at
// build time into a generated header: nothing is fetched when the page
// opens), followed by the map's numbers and node layers (viewer_data.hpp).
// A build configured without node and npm has no template: then
// viewer_page_available() is false. Used by `umbra view` and by the
// exploration study's runner (bench/explore). Cost: building the string,
// about 3-6 bytes per node of the layers.
#pragma once

#include <string>

#include "umbra/map/occupancy_map.hpp"
#include "viewer_data.hpp"

namespace umbra::cli {

/// Whether this build holds the page's template and script.
bool viewer_page_available();
/// The version of three.js in the page ("" without the page).
std::string viewer_three_version();
/// The whole page for `map` with `data` (collect_viewer_data) under `title`.
/// Throws std::logic_error when !viewer_page_available().
std::string viewer_page(const OccupancyMap& map, const ViewerData& data, const std::string& title);

}  // namespace umbra::cli
