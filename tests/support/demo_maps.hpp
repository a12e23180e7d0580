// The procedural demo building mapped by the simulated LiDAR: the map several
// suites (rendering, images, the CLI) draw and compare.
#pragma once

#include <cstddef>
#include <functional>

#include "umbra/core/color.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra::test {

/// Colour of point `index` of a scan, at `point`.
using PointColour = std::function<Rgb(std::size_t index, Vec3f point)>;

/// sim::make_demo_scene() scanned along sim::demo_path() by a 16-ring LiDAR
/// with 360 azimuth steps, each scan inserted with the LiDAR's max range.
/// With config.color, `colour` colours every point.
OccupancyMap demo_lidar_map(const MapConfig& config, const PointColour& colour = {});

}  // namespace umbra::test
