// umbra maps as the messages octomap_server publishes: octomap_msgs/Octomap
// (binary .bt or full .ot tree data, see octomap_files.hpp), the
// occupied-cell (and free-cell) cube markers per depth, and the point cloud
// of occupied cell centres; and back from an Octomap message to a map.
//
// Markers follow octomap_server's conventions so RViz set-ups keep working:
// one CUBE_LIST marker per OctoMap depth 0..16 (id = depth, namespace
// "map"), cube edge = the node size at that depth, action ADD when it holds
// cubes and DELETE when empty (so stale cubes disappear); occupied cells are
// colored by height (a hue over the cells' z range, scaled by
// color_factor) or with one color. Cells whose centre z is outside
// (min_z, max_z) are left out of markers and centres (not of the map).
//
// Cost: one pass over the map's leaves for the cells; encoding a tree
// message is one pass as for an OctoMap file (bytes held twice: the
// encoding and the message).
#pragma once

#include <octomap_msgs/Octomap.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/ColorRGBA.h>
#include <visualization_msgs/MarkerArray.h>

#include <limits>
#include <string>

#include "umbra/io/octomap_files.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra::ros_io {

/// The map as octomap_msgs/Octomap: binary (.bt data, id OcTree) or full (.ot data, OcTree/ColorOcTree).
octomap_msgs::Octomap octomap_message(const OccupancyMap& map, OctoMapFormat format, const std::string& frame,
                                      const ros::Time& stamp);

/// The map an Octomap message holds; throws FormatError (naming `name`) for bad data.
OccupancyMap map_from_message(const octomap_msgs::Octomap& message, const std::string& name = "octomap message");

struct CellStyle {
  double min_z = -std::numeric_limits<double>::infinity();  ///< occupancy_min_z
  double max_z = std::numeric_limits<double>::infinity();   ///< occupancy_max_z
  bool height_map = true;                                   ///< color occupied cells by height
  double color_factor = 0.8;                                ///< hue range used by the height map
  std_msgs::ColorRGBA color;                                ///< occupied cells without height map
  std_msgs::ColorRGBA free_color;                           ///< free cells
  bool free_cells = false;                                  ///< also build the free-cell markers
};

struct CellMessages {
  visualization_msgs::MarkerArray occupied;  ///< occupied_cells_vis_array
  visualization_msgs::MarkerArray free;      ///< free_cells_vis_array (empty unless style.free_cells)
  sensor_msgs::PointCloud2 centers;          ///< octomap_point_cloud_centers: x y z FLOAT32
};

CellMessages cell_messages(const OccupancyMap& map, const CellStyle& style, const std::string& frame,
                           const ros::Time& stamp);

}  // namespace umbra::ros_io
