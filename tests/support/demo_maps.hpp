// The procedural demo building mapped by the simulated LiDAR: the map several
// suites (rendering, images, the CLI) draw and compare.
#pragma once

#include <cstddef>
#include <functional>
#include <vector>

#include "umbra/core/color.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/io/scan_source.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra::test {

/// Color of point `index` of a scan, at `point`.
using PointColor = std::function<Rgb(std::size_t index, Vec3f point)>;

/// sim::make_demo_scene() scanned along sim::demo_path() by a 16-ring LiDAR
/// with 360 azimuth steps, each scan inserted with the LiDAR's max range.
/// With config.color, `color` colors every point.
OccupancyMap demo_lidar_map(const MapConfig& config, const PointColor& color = {});

/// Every other pose of the demo path through the procedural building, each a
/// scan of a 16-ring LiDAR (360 steps, 1 cm range noise): sparse rings.
std::vector<Scan> lidar_building_scans();

}  // namespace umbra::test
