// umbra maps as octomap_server's messages: see map_messages.hpp.
#include "map_messages.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <vector>

namespace umbra::ros_io {
namespace {

/// A fully saturated, fully bright color of hue `h` (0..1 around the color wheel).
std_msgs::ColorRGBA hue_color(double h) {
  const double sector = std::clamp(h, 0.0, 1.0) * 6.0;
  const int i = std::min(static_cast<int>(sector), 5);
  const double f = sector - i;
  const double rising = f;
  const double falling = 1.0 - f;
  std_msgs::ColorRGBA c;
  c.a = 1.0f;
  const double rgb[6][3] = {{1, rising, 0}, {falling, 1, 0}, {0, 1, rising},
                            {0, falling, 1}, {rising, 0, 1}, {1, 0, falling}};
  c.r = static_cast<float>(rgb[i][0]);
  c.g = static_cast<float>(rgb[i][1]);
  c.b = static_cast<float>(rgb[i][2]);
  return c;
}

void finish_markers(visualization_msgs::MarkerArray& markers, const OccupancyMap& map, const std_msgs::ColorRGBA& color,
                    const std::string& frame, const ros::Time& stamp) {
  for (std::size_t octomap_depth = 0; octomap_depth < markers.markers.size(); ++octomap_depth) {
    visualization_msgs::Marker& marker = markers.markers[octomap_depth];
    const double size = map.grid().node_size(map.depth_levels() - static_cast<int>(octomap_depth));
    marker.header.frame_id = frame;
    marker.header.stamp = stamp;
    marker.ns = "map";
    marker.id = static_cast<int>(octomap_depth);
    marker.type = visualization_msgs::Marker::CUBE_LIST;
    marker.scale.x = marker.scale.y = marker.scale.z = size;
    marker.pose.orientation.w = 1.0;
    marker.color = color;
    marker.action = marker.points.empty() ? visualization_msgs::Marker::DELETE : visualization_msgs::Marker::ADD;
  }
}

}  // namespace

octomap_msgs::Octomap octomap_message(const OccupancyMap& map, OctoMapFormat format, const std::string& frame,
                                      const ros::Time& stamp) {
  const OctoMapTreeData tree = encode_octomap_tree(map, format);
  octomap_msgs::Octomap message;
  message.header.frame_id = frame;
  message.header.stamp = stamp;
  message.binary = format == OctoMapFormat::bt;
  message.id = tree.id;
  message.resolution = tree.resolution;
  message.data.resize(tree.data.size());
  if (!tree.data.empty()) std::memcpy(message.data.data(), tree.data.data(), tree.data.size());
  return message;
}

OccupancyMap map_from_message(const octomap_msgs::Octomap& message, const std::string& name) {
  const std::span<const std::uint8_t> data(reinterpret_cast<const std::uint8_t*>(message.data.data()),
                                           message.data.size());
  return decode_octomap_tree(message.binary ? OctoMapFormat::bt : OctoMapFormat::ot, message.id, message.resolution,
                             data, name);
}

CellMessages cell_messages(const OccupancyMap& map, const CellStyle& style, const std::string& frame,
                           const ros::Time& stamp) {
  CellMessages out;
  const int levels = map.depth_levels();
  out.occupied.markers.resize(static_cast<std::size_t>(levels) + 1);
  if (style.free_cells) out.free.markers.resize(static_cast<std::size_t>(levels) + 1);
  std::vector<float> centers;
  double lowest = std::numeric_limits<double>::infinity();
  double highest = -std::numeric_limits<double>::infinity();
  map.for_each_leaf([&](const Node& leaf) {
    if (leaf.state == OccupancyState::unknown) return;
    if (!(leaf.center.z > style.min_z && leaf.center.z < style.max_z)) return;
    geometry_msgs::Point point;
    point.x = leaf.center.x;
    point.y = leaf.center.y;
    point.z = leaf.center.z;
    const auto slot = static_cast<std::size_t>(levels - leaf.depth);  // OctoMap's depth: 0 the root
    if (leaf.state == OccupancyState::occupied) {
      out.occupied.markers[slot].points.push_back(point);
      centers.insert(centers.end(), {static_cast<float>(point.x), static_cast<float>(point.y), static_cast<float>(point.z)});
      lowest = std::min(lowest, point.z);
      highest = std::max(highest, point.z);
    } else if (style.free_cells) {
      out.free.markers[slot].points.push_back(point);
    }
  });
  if (style.height_map) {
    const double range = highest > lowest ? highest - lowest : 1.0;
    for (visualization_msgs::Marker& marker : out.occupied.markers) {
      marker.colors.reserve(marker.points.size());
      for (const geometry_msgs::Point& point : marker.points) {
        // High cells at the start of the hue range, low ones towards its end, as octomap_server does.
        marker.colors.push_back(hue_color((1.0 - (point.z - lowest) / range) * style.color_factor));
      }
    }
  }
  finish_markers(out.occupied, map, style.color, frame, stamp);
  if (style.free_cells) finish_markers(out.free, map, style.free_color, frame, stamp);

  sensor_msgs::PointCloud2& cloud = out.centers;
  cloud.header.frame_id = frame;
  cloud.header.stamp = stamp;
  cloud.height = 1;
  cloud.width = static_cast<std::uint32_t>(centers.size() / 3);
  const char* names[3] = {"x", "y", "z"};
  for (std::uint32_t axis = 0; axis < 3; ++axis) {
    sensor_msgs::PointField field;
    field.name = names[axis];
    field.offset = 4 * axis;
    field.datatype = sensor_msgs::PointField::FLOAT32;
    field.count = 1;
    cloud.fields.push_back(field);
  }
  cloud.is_bigendian = std::endian::native == std::endian::big;  // the floats are copied as they are
  cloud.point_step = 12;
  cloud.row_step = cloud.point_step * cloud.width;
  cloud.is_dense = true;
  cloud.data.resize(centers.size() * sizeof(float));
  if (!centers.empty()) std::memcpy(cloud.data.data(), centers.data(), cloud.data.size());
  return out;
}

}  // namespace umbra::ros_io
