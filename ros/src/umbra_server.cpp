// umbra_server: a ROS 1 node that builds an umbra map from PointCloud2 clouds
// and serves it as octomap_server does (map_server.hpp; docs/ros.md).
//
//   umbra_server [MAP_FILE] [_param:=value ...] [cloud_in:=/my/points]
//
// MAP_FILE (.umb, .bt or .ot) is the starting map; without it the map starts
// empty at ~resolution. Exits with 1 when a parameter or the file is bad.
#include <ros/ros.h>

#include <exception>

#include "crash_log.hpp"
#include "map_server.hpp"
#include "umbra/io/map_formats.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "umbra_server");  // removes the remappings and _param:=value arguments
  umbra::ros_io::install_crash_log();     // a crash inside a library still leaves a line naming the cloud
  ros::NodeHandle node;
  ros::NodeHandle private_node("~");
  try {
    umbra::ros_io::ServerSettings settings = umbra::ros_io::read_settings(private_node);
    for (const std::string& ignored : settings.ignored) ROS_WARN("umbra_server: ignoring ~%s", ignored.c_str());
    umbra::MapConfig config;
    config.resolution = settings.resolution;
    config.sensor = settings.sensor;
    config.color = settings.color;
    umbra::OccupancyMap map(config);
    const bool from_file = argc > 1;
    if (from_file) {
      map = umbra::load_any_map(argv[1], settings.sensor);
      if (map.depth_levels() != umbra::kOctoMapDepthLevels) {
        ROS_FATAL("umbra_server: %s has %d depth levels; OctoMap messages need 16", argv[1], map.depth_levels());
        return 1;
      }
      ROS_INFO("umbra_server: loaded %s (resolution %g m)", argv[1], map.resolution());
    }
    umbra::ros_io::MapServer server(node, private_node, std::move(settings), std::move(map));
    if (from_file) server.publish_all(ros::Time::now());
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL("umbra_server: %s", e.what());
    return 1;
  }
  return 0;
}
