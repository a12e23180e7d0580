// projected_map.hpp: the navigation grid as nav_msgs/OccupancyGrid.
#include "projected_map.hpp"

#include <algorithm>
#include <cstring>

namespace umbra::ros_io {

ProjectionOptions projection_for(const OccupancyMap& map, double min_z, double max_z, int depth, ProjectionRule rule) {
  const double half = map.grid().half_extent();
  // An infinite bound is the map's own (project_to_grid cuts a finite band to the map itself).
  return {std::max(min_z, -half), std::min(max_z, half), depth, rule};
}

nav_msgs::OccupancyGrid occupancy_grid_message(const NavigationGrid& grid, const std::string& frame,
                                               const ros::Time& stamp) {
  nav_msgs::OccupancyGrid message;
  message.header.frame_id = frame;
  message.header.stamp = stamp;
  message.info.map_load_time = stamp;
  message.info.resolution = static_cast<float>(grid.resolution);
  message.info.width = grid.width;
  message.info.height = grid.height;
  message.info.origin.position.x = grid.origin_x;
  message.info.origin.position.y = grid.origin_y;
  message.info.origin.position.z = 0.0;
  message.info.origin.orientation.w = 1.0;
  message.data.resize(grid.cells.size());
  static_assert(sizeof(GridCell) == sizeof(std::int8_t));
  if (!grid.cells.empty()) std::memcpy(message.data.data(), grid.cells.data(), grid.cells.size());
  return message;
}

}  // namespace umbra::ros_io
