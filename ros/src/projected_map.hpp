// The projected 2D map umbra_server publishes on `projected_map`
// (nav_msgs/OccupancyGrid), as octomap_server does: the map's band between
// ~occupancy_min_z and ~occupancy_max_z projected onto cells
// (umbra/query/navigation_grid.hpp), -1 unknown, 0 free, 100 occupied, row
// 0 the lowest y; info.origin is the lower-left corner of cell (0, 0) at
// z 0, yaw 0. A map with nothing known in the band gives a 0 x 0 grid.
//
// Unbounded heights (octomap_server's defaults, +-infinity) mean the whole
// map: they are cut to the map's extent before projecting.
//
// Cost: project_to_grid's (two walks over the nodes in the band, a byte per
// cell) plus one copy of the cells into the message.
#pragma once

#include <nav_msgs/OccupancyGrid.h>

#include <string>

#include "umbra/map/occupancy_map.hpp"
#include "umbra/query/navigation_grid.hpp"

namespace umbra::ros_io {

/// The projection options for a band that may be unbounded (min_z -inf, max_z +inf).
ProjectionOptions projection_for(const OccupancyMap& map, double min_z, double max_z, int depth, ProjectionRule rule);

/// The grid as nav_msgs/OccupancyGrid in `frame`, stamped `stamp` (also its map_load_time).
nav_msgs::OccupancyGrid occupancy_grid_message(const NavigationGrid& grid, const std::string& frame,
                                               const ros::Time& stamp);

}  // namespace umbra::ros_io
