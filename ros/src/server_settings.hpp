// umbra_server's parameters: octomap_server's names and meanings, plus
// umbra's integrator settings. Read once at start-up from the node's
// private namespace (~name); docs/ros.md has the table.
//
// octomap_server parameters umbra_server reads: frame_id, resolution,
// sensor_model/{hit,miss,min,max,max_range}, pointcloud_{min,max}_z,
// occupancy_{min,max}_z, height_map, color_factor, color/{r,g,b,a},
// color_free/{r,g,b,a}, publish_free_space, latch, compress_map. Those it
// does not implement (filter_ground, filter_speckles, ground_filter/*,
// base_frame_id) are reported by name when set, never silently ignored;
// incremental_2D_projection is reported too (umbra_server projects the
// whole band after every scan: the same grid).
//
// umbra's own: integrator (simple | discrete | fast | projective),
// clear_depth, fine_steps, surface_margin, scan_resolution/{horizontal,
// vertical}, threads, keep_colors (keep an RGB per voxel from clouds with
// rgb; then the full map is a ColorOcTree); for depth images (the topics
// depth/image and depth/camera_info): image_integrator (projective by
// default: free space from the image itself), image_max_range (default:
// sensor_model/max_range), image_colors (color the voxels from rgb/image);
// for the projected map: projected_map_rule (any_free, octomap_server's, by
// default; or all_known) and projected_map_depth (0: cells of one voxel).
// Decay toward unknown: decay/occupied_per_second, decay/free_per_second
// (log-odds per second, default 0: off), applied on the clock of the
// messages' stamps as each cloud or image arrives (umbra/map/decay.hpp).
// A map that moves: window/half_extent (metres, default 0: off) keeps only
// a box around each scan's sensor origin; window/spill_path (default empty:
// dropped) appends what leaves it to that spill file
// (umbra/map/moving_window.hpp, umbra/io/spill_file.hpp).
#pragma once

#include <ros/node_handle.h>

#include <limits>
#include <string>
#include <vector>

#include "map_messages.hpp"
#include "umbra/core/log_odds.hpp"
#include "umbra/integrate/insert_options.hpp"
#include "umbra/map/decay.hpp"
#include "umbra/query/navigation_grid.hpp"

namespace umbra::ros_io {

struct ServerSettings {
  std::string frame = "map";  ///< frame_id, without a leading '/'
  double resolution = 0.05;
  /// octomap_server's defaults (the clamping range differs slightly from liboctomap's 0.1192..0.971).
  SensorModel sensor{0.7, 0.4, 0.12, 0.97};
  double pointcloud_min_z = -std::numeric_limits<double>::infinity();
  double pointcloud_max_z = std::numeric_limits<double>::infinity();
  CellStyle cells;
  /// projected_map: cells of depth-`projected_map_depth` columns, band occupancy_{min,max}_z (navigation_grid.hpp).
  ProjectionRule projected_map_rule = ProjectionRule::any_free;
  int projected_map_depth = 0;
  bool latch = true;
  bool compress_map = true;  ///< prune after every cloud (umbra's automatic pruning)
  bool color = false;  ///< keep_colors
  InsertOptions insert;  ///< clouds: max_range from sensor_model/max_range; integrator, clear_depth, ...
  /// Depth images: integrator from image_integrator, max_range from image_max_range, the rest as `insert`.
  InsertOptions image_insert;
  bool image_colors = false;  ///< image_colors: colors from rgb/image (needs keep_colors)
  // --- decay toward unknown ---
  DecayRates decay;  ///< decay/{occupied,free}_per_second; off by default
  // --- a map that moves ---
  double window_half_extent = 0.0;  ///< window/half_extent; 0: no window
  std::string window_spill_path;    ///< window/spill_path; empty: what leaves is dropped

  /// octomap_server parameters that are set but not implemented, as "name: what happens instead".
  std::vector<std::string> ignored;
};

/// Reads and checks the parameters; throws std::invalid_argument naming the parameter and its value.
ServerSettings read_settings(const ros::NodeHandle& private_node);

}  // namespace umbra::ros_io
