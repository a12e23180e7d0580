// umbra_server's parameters: see server_settings.hpp.
#include "server_settings.hpp"

#include <cmath>
#include <stdexcept>

#include "cloud_message.hpp"

namespace umbra::ros_io {
namespace {

template <typename T>
T param(const ros::NodeHandle& node, const std::string& name, T fallback) {
  T value = fallback;
  node.param(name, value, fallback);
  return value;
}

std_msgs::ColorRGBA color_param(const ros::NodeHandle& node, const std::string& prefix, std_msgs::ColorRGBA fallback) {
  std_msgs::ColorRGBA c;
  c.r = static_cast<float>(param<double>(node, prefix + "/r", fallback.r));
  c.g = static_cast<float>(param<double>(node, prefix + "/g", fallback.g));
  c.b = static_cast<float>(param<double>(node, prefix + "/b", fallback.b));
  c.a = static_cast<float>(param<double>(node, prefix + "/a", fallback.a));
  return c;
}

std_msgs::ColorRGBA rgba(float r, float g, float b, float a) {
  std_msgs::ColorRGBA c;
  c.r = r;
  c.g = g;
  c.b = b;
  c.a = a;
  return c;
}

/// Rethrows a library's std::invalid_argument with the parameter names in front.
template <typename F>
void check(const std::string& names, F&& validate) {
  try {
    validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("bad parameter " + names + ": " + e.what());
  }
}

}  // namespace

ServerSettings read_settings(const ros::NodeHandle& node) {
  ServerSettings s;
  s.frame = tf2_frame(param<std::string>(node, "frame_id", s.frame));
  if (s.frame.empty()) throw std::invalid_argument("bad parameter ~frame_id: empty");
  s.resolution = param(node, "resolution", s.resolution);
  if (!(s.resolution > 0.0)) {
    throw std::invalid_argument("bad parameter ~resolution: " + std::to_string(s.resolution) + " (must be > 0 metres)");
  }
  s.sensor.p_hit = param(node, "sensor_model/hit", s.sensor.p_hit);
  s.sensor.p_miss = param(node, "sensor_model/miss", s.sensor.p_miss);
  s.sensor.clamp_min = param(node, "sensor_model/min", s.sensor.clamp_min);
  s.sensor.clamp_max = param(node, "sensor_model/max", s.sensor.clamp_max);
  check("~sensor_model/{hit,miss,min,max}", [&] { s.sensor.validate(); });
  s.insert.max_range = param(node, "sensor_model/max_range", s.insert.max_range);
  s.pointcloud_min_z = param(node, "pointcloud_min_z", s.pointcloud_min_z);
  s.pointcloud_max_z = param(node, "pointcloud_max_z", s.pointcloud_max_z);
  s.cells.min_z = param(node, "occupancy_min_z", s.cells.min_z);
  s.cells.max_z = param(node, "occupancy_max_z", s.cells.max_z);
  if (!(s.cells.min_z < s.cells.max_z)) {
    throw std::invalid_argument("bad parameters ~occupancy_min_z " + std::to_string(s.cells.min_z) +
                                " and ~occupancy_max_z " + std::to_string(s.cells.max_z) +
                                ": the minimum must be below the maximum");
  }
  const std::string rule = param<std::string>(node, "projected_map_rule", std::string(to_string(s.projected_map_rule)));
  check("~projected_map_rule", [&] { s.projected_map_rule = parse_projection_rule(rule); });
  s.projected_map_depth = param(node, "projected_map_depth", s.projected_map_depth);
  if (s.projected_map_depth < 0 || s.projected_map_depth > 16) {
    throw std::invalid_argument("bad parameter ~projected_map_depth: " + std::to_string(s.projected_map_depth) +
                                " (must be 0 to 16)");
  }
  s.cells.height_map = param(node, "height_map", s.cells.height_map);
  s.cells.color_factor = param(node, "color_factor", s.cells.color_factor);
  s.cells.color = color_param(node, "color", rgba(0, 0, 1, 1));
  s.cells.free_color = color_param(node, "color_free", rgba(0, 1, 0, 1));
  s.cells.free_cells = param(node, "publish_free_space", s.cells.free_cells);
  s.latch = param(node, "latch", s.latch);
  s.compress_map = param(node, "compress_map", s.compress_map);

  s.color = param(node, "keep_colors", s.color);
  const std::string integrator = param<std::string>(node, "integrator", "simple");
  check("~integrator", [&] { s.insert.integrator = parse_integrator_kind(integrator); });
  s.insert.clear_depth = param(node, "clear_depth", s.insert.clear_depth);
  s.insert.fine_steps = param(node, "fine_steps", s.insert.fine_steps);
  s.insert.surface_margin = param(node, "surface_margin", s.insert.surface_margin);
  s.insert.scan_resolution.horizontal = param(node, "scan_resolution/horizontal", s.insert.scan_resolution.horizontal);
  s.insert.scan_resolution.vertical = param(node, "scan_resolution/vertical", s.insert.scan_resolution.vertical);
  const int threads = param(node, "threads", 0);
  if (threads < 0) throw std::invalid_argument("bad parameter ~threads: " + std::to_string(threads) + " (0: all cores)");
  s.insert.threads = static_cast<unsigned>(threads);
  check("~integrator/~clear_depth/~fine_steps/~surface_margin/~scan_resolution", [&] { s.insert.validate(16); });

  // Depth images: the same settings but for the integrator (the projective one reads images as images) and the
  // range (depth cameras reach a few metres, a LiDAR on the same robot tens).
  s.image_insert = s.insert;
  const std::string image_integrator = param<std::string>(node, "image_integrator", "projective");
  check("~image_integrator", [&] { s.image_insert.integrator = parse_integrator_kind(image_integrator); });
  s.image_insert.max_range = param(node, "image_max_range", s.insert.max_range);
  check("~image_max_range", [&] { s.image_insert.validate(16); });
  s.image_colors = param(node, "image_colors", s.image_colors);
  if (s.image_colors && !s.color) {
    throw std::invalid_argument("bad parameter ~image_colors: true needs ~keep_colors true (a map without color "
                                "cannot take the color images)");
  }

  // Decay toward unknown (off by default).
  s.decay.occupied_per_second = param(node, "decay/occupied_per_second", s.decay.occupied_per_second);
  s.decay.free_per_second = param(node, "decay/free_per_second", s.decay.free_per_second);
  check("~decay/{occupied_per_second,free_per_second}", [&] { s.decay.validate(); });

  // A map that moves (off by default).
  s.window_half_extent = param(node, "window/half_extent", s.window_half_extent);
  s.window_spill_path = param(node, "window/spill_path", s.window_spill_path);
  if (!(std::isfinite(s.window_half_extent) && s.window_half_extent >= 0.0)) {
    throw std::invalid_argument("bad parameter ~window/half_extent: " + std::to_string(s.window_half_extent) +
                                " (metres, finite and >= 0; 0: no window)");
  }
  if (!s.window_spill_path.empty() && s.window_half_extent == 0.0) {
    throw std::invalid_argument("bad parameter ~window/spill_path: '" + s.window_spill_path +
                                "' needs ~window/half_extent > 0 (without a window nothing leaves the map)");
  }

  const auto ignored_if = [&](const std::string& name, const std::string& instead) {
    if (param(node, name, false)) s.ignored.push_back(name + ": " + instead);
  };
  ignored_if("filter_ground", "umbra_server does not segment the ground; every point is inserted");
  ignored_if("filter_speckles", "umbra_server publishes every occupied cell");
  ignored_if("incremental_2D_projection",
             "umbra_server projects the whole band after every scan (the same grid, from the octree's nodes)");
  if (node.hasParam("base_frame_id")) s.ignored.push_back("base_frame_id: only used by filter_ground, which umbra_server lacks");
  if (node.hasParam("ground_filter")) s.ignored.push_back("ground_filter/*: umbra_server does not segment the ground");
  return s;
}

}  // namespace umbra::ros_io
