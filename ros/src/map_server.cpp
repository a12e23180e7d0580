// MapServer: see map_server.hpp.
#include "map_server.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <vector>

#include "cloud_message.hpp"
#include "crash_log.hpp"
#include "map_messages.hpp"
#include "umbra/io/spill_file.hpp"

namespace umbra::ros_io {
namespace {

constexpr std::uint32_t kCloudQueue = 5;  // as octomap_server: clouds waiting for their transform
/// ~clear_bbx sets voxels one by one (the map has no whole-node setter): boxes with more known voxels than this
/// (about a minute of work) are refused rather than stalling the node.
constexpr std::uint64_t kMaxClearedVoxels = std::uint64_t{1} << 26;

/// Keys from..to (inclusive) on each axis.
struct KeyBox {
  Key min;
  Key max;
};

/// The voxel keys of the box [a, b] (either corner order), clamped to the map.
KeyBox key_box(const OccupancyMap& map, const geometry_msgs::Point& a, const geometry_msgs::Point& b) {
  const double half = map.grid().half_extent();
  const double inside = half - map.resolution() * 0.5;  // a coordinate whose voxel is in the map
  auto axis_key = [&](double c) {
    return map.key(Vec3d{std::clamp(c, -inside, inside), 0.0, 0.0}).x;
  };
  const std::array<double, 3> lo{std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
  const std::array<double, 3> hi{std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
  KeyBox box;
  for (int axis = 0; axis < 3; ++axis) {
    box.min[axis] = axis_key(lo[static_cast<std::size_t>(axis)]);
    box.max[axis] = axis_key(hi[static_cast<std::size_t>(axis)]);
  }
  return box;
}

}  // namespace

MapServer::MapServer(ros::NodeHandle& node, ros::NodeHandle& private_node, ServerSettings settings, OccupancyMap map)
    : settings_(std::move(settings)),
      map_(std::move(map)),
      tf_buffer_(ros::Duration(60.0)),
      tf_listener_(tf_buffer_, node),
      cloud_subscriber_(node, "cloud_in", kCloudQueue),
      cloud_filter_(cloud_subscriber_, tf_buffer_, settings_.frame, kCloudQueue, node),
      cloud_wait_(node, tf_buffer_, settings_.frame),
      image_input_(node, tf_buffer_, settings_.frame, settings_.image_colors,
                   [this](const sensor_msgs::Image::ConstPtr& depth, const sensor_msgs::CameraInfo::ConstPtr& info,
                          const sensor_msgs::Image::ConstPtr& color) { insert_image(depth, info, color); },
                   [this](const sensor_msgs::Image::ConstPtr& depth, DepthImageInput::Drop why) { drop_image(depth, why); }) {
  map_.set_auto_prune(settings_.compress_map);
  map_.set_decay(settings_.decay);
  if (settings_.window_half_extent > 0.0) {
    // Re-centred on each cloud's or image's sensor origin as it is inserted.
    MovingWindow window;
    window.half_extent = settings_.window_half_extent;
    if (!settings_.window_spill_path.empty()) window.spill = spill_to_file(settings_.window_spill_path);
    map_.set_moving_window(window);
  }
  cloud_filter_.registerCallback(&MapServer::insert_cloud, this);
  cloud_filter_.registerFailureCallback(
      [this](const sensor_msgs::PointCloud2::ConstPtr& cloud, tf2_ros::filter_failure_reasons::FilterFailureReason why) {
        drop_cloud(cloud, why);
      });
  cloud_subscriber_.registerCallback(
      [this](const sensor_msgs::PointCloud2::ConstPtr& cloud) { cloud_wait_.arrived(*cloud); });
  const bool latch = settings_.latch;
  binary_publisher_ = node.advertise<octomap_msgs::Octomap>("octomap_binary", 1, latch);
  full_publisher_ = node.advertise<octomap_msgs::Octomap>("octomap_full", 1, latch);
  occupied_publisher_ = node.advertise<visualization_msgs::MarkerArray>("occupied_cells_vis_array", 1, latch);
  free_publisher_ = node.advertise<visualization_msgs::MarkerArray>("free_cells_vis_array", 1, latch);
  centers_publisher_ = node.advertise<sensor_msgs::PointCloud2>("octomap_point_cloud_centers", 1, latch);
  projected_publisher_ = node.advertise<nav_msgs::OccupancyGrid>("projected_map", 1, latch);
  binary_service_ = node.advertiseService("octomap_binary", &MapServer::get_binary, this);
  full_service_ = node.advertiseService("octomap_full", &MapServer::get_full, this);
  reset_service_ = private_node.advertiseService("reset", &MapServer::reset, this);
  clear_bbx_service_ = private_node.advertiseService("clear_bbx", &MapServer::clear_bbx, this);
  check_collision_service_ = private_node.advertiseService("check_collision", &MapServer::check_collision, this);
  merge_service_ = private_node.advertiseService("merge", &MapServer::merge, this);
  log_start();
}

void MapServer::log_start() const {
  ROS_INFO("umbra_server: mapping in frame '%s' at %g m (integrator %s): clouds from '%s' and depth images from %s, "
           "each once TF can move its frame into '%s'", settings_.frame.c_str(), map_.resolution(),
           to_string(settings_.insert.integrator), cloud_subscriber_.getTopic().c_str(), image_input_.topics().c_str(),
           settings_.frame.c_str());
  std::string topics = "'" + binary_publisher_.getTopic() + "', '" + full_publisher_.getTopic() + "', '" +
                       occupied_publisher_.getTopic() + "', '" + centers_publisher_.getTopic() + "', '" +
                       projected_publisher_.getTopic() + "'";
  if (settings_.cells.free_cells) topics += ", '" + free_publisher_.getTopic() + "'";
  ROS_INFO("umbra_server: publishing %s; services '%s', '%s', '%s', '%s', '%s', '%s'", topics.c_str(),
           binary_service_.getService().c_str(), full_service_.getService().c_str(), reset_service_.getService().c_str(),
           clear_bbx_service_.getService().c_str(), check_collision_service_.getService().c_str(),
           merge_service_.getService().c_str());
}

bool MapServer::wanted(const ros::Publisher& publisher) const {
  return settings_.latch || publisher.getNumSubscribers() > 0;
}

void MapServer::drop_cloud(const sensor_msgs::PointCloud2::ConstPtr& cloud,
                           tf2_ros::filter_failure_reasons::FilterFailureReason reason) {
  cloud_wait_.left();
  ++clouds_dropped_;
  // Throttled: until TF knows the frame every cloud is dropped; the count says how many were.
  const std::string why = reason == tf2_ros::filter_failure_reasons::EmptyFrameID
                              ? "it has no frame_id"
                              : "tf2 had no transform from '" + cloud->header.frame_id + "' to the map frame '" +
                                    settings_.frame + "' at its stamp (" + cloud_wait_.known_frames() + ")";
  ROS_WARN_THROTTLE(5.0, "umbra_server: dropped the cloud in frame '%s' at %f: %s (clouds dropped so far: %zu)",
                    cloud->header.frame_id.c_str(), cloud->header.stamp.toSec(), why.c_str(), clouds_dropped_);
}

void MapServer::insert_cloud(const sensor_msgs::PointCloud2::ConstPtr& cloud) {
  cloud_wait_.left();
  const std::string name = "cloud in frame '" + cloud->header.frame_id + "' at " + std::to_string(cloud->header.stamp.toSec());
  // Whatever goes wrong with one cloud (a malformed message, a transform tf2 cannot give, an error inside the
  // integrator) is logged and the cloud dropped: the node keeps its map and goes on with the next one.
  set_crash_context("inserting the " + name);
  try {
    const std::string cloud_frame = tf2_frame(cloud->header.frame_id);
    RigidTransform to_map;
    if (cloud_frame != settings_.frame) {
      to_map = to_rigid_transform(tf_buffer_.lookupTransform(settings_.frame, cloud_frame, cloud->header.stamp).transform);
    }
    // Colors only when the map keeps them: otherwise the rgb field is not even looked at.
    const std::size_t non_finite = cloud_to_scan(*cloud, to_map, settings_.color, decoded_, scan_, name);
    const std::size_t total = scan_.points.size();
    if (std::isfinite(settings_.pointcloud_min_z) || std::isfinite(settings_.pointcloud_max_z)) {
      // Keep points strictly inside (min_z, max_z) in the map frame; NaN points go too.
      std::size_t kept = 0;
      for (std::size_t i = 0; i < scan_.points.size(); ++i) {
        const float z = scan_.points[i].z;
        if (!(z >= settings_.pointcloud_min_z && z <= settings_.pointcloud_max_z)) continue;
        scan_.points[kept] = scan_.points[i];
        if (!scan_.colors.empty()) scan_.colors[kept] = scan_.colors[i];
        ++kept;
      }
      scan_.points.resize(kept);
      if (!scan_.colors.empty()) scan_.colors.resize(kept);
    }
    const InsertOptions options = stamped(settings_.insert, cloud->header.stamp);
    const InsertStats stats = settings_.color && !scan_.colors.empty()
                                  ? map_.insert_point_cloud(scan_.origin, scan_.points, scan_.colors, options)
                                  : map_.insert_point_cloud(scan_.origin, scan_.points, options);
    if (non_finite > 0) {
      ROS_INFO_THROTTLE(5.0, "umbra_server: %zu of the %zu points of the %s are NaN or infinite and were skipped",
                        non_finite, total, name.c_str());
    }
    if (stats.out_of_bounds > 0) {
      ROS_WARN_THROTTLE(5.0, "umbra_server: %zu points of a cloud lie outside the map and were skipped", stats.out_of_bounds);
    }
  } catch (const FormatError& e) {  // its message starts with the cloud's name
    ROS_ERROR("umbra_server: cannot insert the %s", e.what());
    set_crash_context("");
    return;
  } catch (const std::exception& e) {
    ROS_ERROR("umbra_server: cannot insert the %s: %s", name.c_str(), e.what());
    set_crash_context("");
    return;
  } catch (...) {
    ROS_ERROR("umbra_server: cannot insert the %s: an exception of unknown type", name.c_str());
    set_crash_context("");
    return;
  }
  publish_after(name, cloud->header.stamp);
}

InsertOptions MapServer::stamped(const InsertOptions& options, const ros::Time& stamp) const {
  // With decay on, the message's stamp is the map's clock; without, no stamp
  // at all, so that the map is exactly the one without decay.
  InsertOptions with_stamp = options;
  if (settings_.decay.enabled()) with_stamp.stamp = stamp.toSec();
  return with_stamp;
}

void MapServer::insert_image(const sensor_msgs::Image::ConstPtr& depth, const sensor_msgs::CameraInfo::ConstPtr& info,
                             const sensor_msgs::Image::ConstPtr& color) {
  const std::string name =
      "depth image in frame '" + depth->header.frame_id + "' at " + std::to_string(depth->header.stamp.toSec());
  // As for clouds: whatever is wrong with one image is logged, naming it, and the image dropped.
  set_crash_context("inserting the " + name);
  try {
    decode_depth_image(*depth, decoded_image_, name);
    const PinholeCamera camera = camera_of(*info, decoded_image_.width, decoded_image_.height, name);
    if (color) decode_color_image(*color, decoded_image_.width, decoded_image_.height, image_colors_, name);
    // The image's frame is the camera's optical frame (x right, y down, z forward), as Pose expects.
    Pose pose;
    const std::string image_frame = tf2_frame(depth->header.frame_id);
    if (image_frame != settings_.frame) {
      const geometry_msgs::Transform to_map =
          tf_buffer_.lookupTransform(settings_.frame, image_frame, depth->header.stamp).transform;
      pose = Pose::from_translation_quaternion(to_map.translation.x, to_map.translation.y, to_map.translation.z,
                                               to_map.rotation.w, to_map.rotation.x, to_map.rotation.y,
                                               to_map.rotation.z);
    }
    const InsertStats stats =
        map_.insert_depth_image(decoded_image_.view(), camera, pose,
                                color ? std::span<const Rgb>(image_colors_) : std::span<const Rgb>(),
                                stamped(settings_.image_insert, depth->header.stamp));
    if (stats.out_of_bounds > 0) {
      ROS_WARN_THROTTLE(5.0, "umbra_server: %zu points of the %s lie outside the map and were skipped",
                        stats.out_of_bounds, name.c_str());
    }
  } catch (const FormatError& e) {  // its message starts with the image's name
    ++images_refused_;
    ROS_ERROR("umbra_server: cannot insert the %s (%s)", e.what(), refused_images_text().c_str());
    set_crash_context("");
    return;
  } catch (const std::exception& e) {
    ++images_refused_;
    ROS_ERROR("umbra_server: cannot insert the %s: %s (%s)", name.c_str(), e.what(), refused_images_text().c_str());
    set_crash_context("");
    return;
  } catch (...) {
    ++images_refused_;
    ROS_ERROR("umbra_server: cannot insert the %s: an exception of unknown type (%s)", name.c_str(),
              refused_images_text().c_str());
    set_crash_context("");
    return;
  }
  publish_after(name, depth->header.stamp);
}

void MapServer::drop_image(const sensor_msgs::Image::ConstPtr& depth, DepthImageInput::Drop why) {
  ++images_refused_;
  // At most one warning per reason every 5 s: until tf2 knows the camera (or while no CameraInfo matches), every
  // image is dropped; the count says how many were.
  ros::WallTime& last = last_drop_warning_[static_cast<std::size_t>(why)];
  const ros::WallTime now = ros::WallTime::now();
  if (!last.isZero() && (now - last).toSec() < 5.0) return;
  last = now;
  ROS_WARN("umbra_server: dropped the depth image in frame '%s' at %f: %s (%s)", depth->header.frame_id.c_str(),
           depth->header.stamp.toSec(), image_input_.describe(why).c_str(), refused_images_text().c_str());
}

std::string MapServer::refused_images_text() const {
  return "depth images refused so far: " + std::to_string(images_refused_) + " of " +
         std::to_string(image_input_.received());
}

void MapServer::publish_after(const std::string& name, const ros::Time& stamp) {
  set_crash_context("publishing the map after the " + name);
  try {
    publish_all(stamp);
  } catch (const std::exception& e) {
    ROS_ERROR("umbra_server: cannot publish the map after the %s: %s", name.c_str(), e.what());
  }
  set_crash_context("");
}

void MapServer::publish_all(const ros::Time& stamp) {
  if (wanted(binary_publisher_)) binary_publisher_.publish(octomap_message(map_, OctoMapFormat::bt, settings_.frame, stamp));
  if (wanted(full_publisher_)) full_publisher_.publish(octomap_message(map_, OctoMapFormat::ot, settings_.frame, stamp));
  const bool free_cells = settings_.cells.free_cells && wanted(free_publisher_);
  if (wanted(occupied_publisher_) || wanted(centers_publisher_) || free_cells) {
    CellStyle style = settings_.cells;
    style.free_cells = free_cells;
    const CellMessages cells = cell_messages(map_, style, settings_.frame, stamp);
    if (wanted(occupied_publisher_)) occupied_publisher_.publish(cells.occupied);
    if (wanted(centers_publisher_)) centers_publisher_.publish(cells.centers);
    if (free_cells) free_publisher_.publish(cells.free);
  }
  if (wanted(projected_publisher_)) {
    const ProjectionOptions band = projection_for(map_, settings_.cells.min_z, settings_.cells.max_z,
                                                  settings_.projected_map_depth, settings_.projected_map_rule);
    projected_publisher_.publish(occupancy_grid_message(project_to_grid(map_, band), settings_.frame, stamp));
  }
}

bool MapServer::reset(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  map_.clear();
  ROS_INFO("umbra_server: map cleared");
  publish_all(ros::Time::now());
  return true;
}

bool MapServer::clear_bbx(octomap_msgs::BoundingBoxQuery::Request& request, octomap_msgs::BoundingBoxQuery::Response&) {
  const auto finite = [](const geometry_msgs::Point& p) {
    return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
  };
  if (!finite(request.min) || !finite(request.max)) {
    ROS_ERROR("umbra_server: ~clear_bbx needs finite corners");
    return false;
  }
  if (request.min.x > request.max.x || request.min.y > request.max.y || request.min.z > request.max.z) {
    ROS_ERROR("umbra_server: ~clear_bbx needs min <= max on every axis");
    return false;
  }
  const KeyBox box = key_box(map_, request.min, request.max);
  const float free_value = map_.sensor_model().clamp_min_log_odds();
  // First the parts of known leaves inside the box (a pruned leaf may reach outside it), then set them.
  std::vector<KeyBox> parts;
  const Aabb region{{request.min.x, request.min.y, request.min.z}, {request.max.x, request.max.y, request.max.z}};
  for (const Node& leaf : map_.query(pred::leaf() && !pred::unknown() && pred::intersects(region))) {
    if (leaf.log_odds == free_value) continue;
    const std::uint32_t last = (std::uint32_t{1} << leaf.depth) - 1u;
    KeyBox part;
    bool inside = true;
    for (int axis = 0; axis < 3; ++axis) {
      part.min[axis] = std::max(leaf.key[axis], box.min[axis]);
      part.max[axis] = std::min(leaf.key[axis] + last, box.max[axis]);
      inside = inside && part.min[axis] <= part.max[axis];
    }
    if (inside) parts.push_back(part);
  }
  std::uint64_t voxels = 0;
  for (const KeyBox& part : parts) {
    voxels += std::uint64_t{part.max.x - part.min.x + 1} * (part.max.y - part.min.y + 1) * (part.max.z - part.min.z + 1);
  }
  if (voxels > kMaxClearedVoxels) {
    ROS_ERROR("umbra_server: ~clear_bbx refused: the box holds %llu known voxels to set, more than %llu; clear smaller "
              "boxes", static_cast<unsigned long long>(voxels), static_cast<unsigned long long>(kMaxClearedVoxels));
    return false;
  }
  for (const KeyBox& part : parts) {
    for (std::uint32_t x = part.min.x; x <= part.max.x; ++x) {
      for (std::uint32_t y = part.min.y; y <= part.max.y; ++y) {
        for (std::uint32_t z = part.min.z; z <= part.max.z; ++z) map_.set_log_odds(Key{x, y, z}, free_value);
      }
    }
  }
  ROS_INFO("umbra_server: cleared the box (%g %g %g)..(%g %g %g): %zu leaves changed", request.min.x, request.min.y,
           request.min.z, request.max.x, request.max.y, request.max.z, parts.size());
  publish_all(ros::Time::now());
  return true;
}

bool MapServer::get_binary(octomap_msgs::GetOctomap::Request&, octomap_msgs::GetOctomap::Response& response) {
  response.map = octomap_message(map_, OctoMapFormat::bt, settings_.frame, ros::Time::now());
  return true;
}

bool MapServer::get_full(octomap_msgs::GetOctomap::Request&, octomap_msgs::GetOctomap::Response& response) {
  response.map = octomap_message(map_, OctoMapFormat::ot, settings_.frame, ros::Time::now());
  return true;
}

bool MapServer::check_collision(umbra_msgs::CheckCollision::Request& request,
                                umbra_msgs::CheckCollision::Response& response) {
  const Vec3d a{request.a.x, request.a.y, request.a.z};
  const Vec3d b{request.b.x, request.b.y, request.b.z};
  const CollisionOptions options{request.unknown_is_free != 0, request.depth};
  try {
    CollisionResult result;
    switch (request.shape) {
      case umbra_msgs::CheckCollision::Request::SPHERE: result = map_.is_free(Sphere{a, request.radius}, options); break;
      case umbra_msgs::CheckCollision::Request::BOX: result = map_.is_free(Aabb{a, b}, options); break;
      case umbra_msgs::CheckCollision::Request::CAPSULE: result = map_.is_free(Capsule{a, b, request.radius}, options); break;
      case umbra_msgs::CheckCollision::Request::SEGMENT: result = map_.is_free(Segment{a, b}, options); break;
      default:
        throw std::invalid_argument("unknown shape " + std::to_string(request.shape) +
                                    " (SPHERE=0, BOX=1, CAPSULE=2, SEGMENT=3)");
    }
    response.valid = true;
    response.free = result.free;
    if (result.blocking) {
      response.blocking_center.x = result.blocking->center.x;
      response.blocking_center.y = result.blocking->center.y;
      response.blocking_center.z = result.blocking->center.z;
      response.blocking_size = result.blocking->size;
      // A blocking node that holds no occupied voxel blocks because it holds unknown space.
      response.blocking_state = result.blocking->contains_occupied() ? umbra_msgs::CheckCollision::Response::OCCUPIED
                                                                     : umbra_msgs::CheckCollision::Response::UNKNOWN;
    }
  } catch (const std::exception& e) {  // a bad shape or depth, a region outside the map
    response.valid = false;
    response.free = false;
    response.error = e.what();
  }
  return true;
}

// --- ~merge (umbra_msgs/MergeMap) ------------------------------------------------

bool MapServer::merge(umbra_msgs::MergeMap::Request& request, umbra_msgs::MergeMap::Response& response) {
  const std::string& frame = request.map.header.frame_id;
  if (!frame.empty() && frame != settings_.frame) {
    response.error = "the map is in frame '" + frame + "', the node maps in '" + settings_.frame +
                     "' (~merge does not transform maps)";
  } else {
    try {
      const OccupancyMap other = map_from_message(request.map, "~merge request's map");
      response.voxels = map_.merge(other, VoxelOffset{request.offset_x, request.offset_y, request.offset_z}).voxels;
      response.success = true;
    } catch (const std::exception& error) {
      response.error = error.what();
    }
  }
  if (!response.success) {
    ROS_ERROR("umbra_server: ~merge refused: %s", response.error.c_str());
    return true;  // answered: the response says why
  }
  ROS_INFO("umbra_server: merged a map: %llu voxels", static_cast<unsigned long long>(response.voxels));
  publish_all(ros::Time::now());
  return true;
}

}  // namespace umbra::ros_io
