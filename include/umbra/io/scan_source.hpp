// ScanSource: one interface for every point-cloud reader.
//
// A source yields scans one at a time (so a long sequence never has to fit
// in memory): the sensor origin and the points, both in the map frame, and
// optionally one color per point. Readers pick the format from the file
// extension unless ScanSourceOptions::format names it.
//
// Formats (format name: what open_scan_source accepts):
//   graph  OctoMap ScanGraph, .graph: many scans, poses inside.
//   xyz    ASCII "x y z [r g b]" per line, .xyz .dat .txt (each also .bz2):
//          one scan at ScanSourceOptions::origin.
//   ply    PLY, .ply (ascii, binary little/big endian): one scan at
//          ScanSourceOptions::origin; colors from red/green/blue.
//   pcd    PCL point cloud, .pcd (ascii, binary, binary_compressed): one
//          scan; a non-identity VIEWPOINT is the sensor pose (points are
//          in the sensor frame and are transformed by it, origin = its
//          translation), else the points are taken as they are and the
//          origin is ScanSourceOptions::origin. Colors from rgb/rgba.
//   kitti  KITTI velodyne scans (float32 x y z reflectance): a folder of
//          .bin files with ScanSourceOptions::poses (KITTI odometry poses,
//          one 3x4 camera pose per scan) and optionally calibration
//          (calib.txt, its Tr velodyne-to-camera); or one .bin file, which
//          without poses is one scan at ScanSourceOptions::origin.
//   tum    TUM RGB-D: the sequence folder (holding depth/ and rgb/ and one
//          *assoc*.txt association file, or ScanSourceOptions::association)
//          or the association file itself with format "tum"; every row
//          whose depth and color images exist is one scan, back-projected
//          with ScanSourceOptions::depth_camera, origin = the camera position.
//   rosbag ROS 1 bag, .bag: PointCloud2 messages on ScanSourceOptions::topics
//          moved into the frame ScanSourceOptions::frame with the bag's TF.
//          Read only by umbra built with ROS, whose umbra_ros library
//          registers its reader (register_scan_format, below;
//          ros/include/umbra_ros/rosbag_source.hpp); without it
//          open_scan_source refuses .bag files with a message saying so.
// See ply_file.hpp, pcd_file.hpp, kitti_sequence.hpp and tum_sequence.hpp.
//
// Errors: malformed files throw umbra::FormatError naming the file and the
// line or byte offset; a missing file throws std::runtime_error naming it.
// Memory: a scan whose points need more than umbra::memory_limit() (12 bytes
// a point, 15 with color; see umbra/core/memory_limit.hpp) is refused with
// umbra::MemoryLimitError naming the file, the need and the limit: at open
// when the header declares the count (PLY, PCD, ScanGraph), else before the
// points are read (KITTI by file size, TUM by image size) or as they arrive
// (xyz). Any std::bad_alloc while opening or reading comes out as a
// MemoryLimitError naming the file.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "umbra/core/color.hpp"
#include "umbra/core/pose.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/map/depth_image.hpp"
#include "umbra/io/format_error.hpp"

namespace umbra {

/// The depth image a scan was made from (TUM RGB-D frames), for the
/// projective integrator (OccupancyMap::insert_depth_image): the scan's
/// points are back_project(view(), camera, pose), in that order.
struct ScanImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint16_t> raw;  ///< raw depths, `units_per_metre` per metre; 0: no reading
  double units_per_metre = 1000.0;
  std::vector<Rgb> colors;  ///< empty, or one per pixel
  PinholeCamera camera;
  Pose pose;  ///< the camera's optical frame to the map

  [[nodiscard]] DepthImage view() const { return DepthImage::raw(raw, width, height, units_per_metre); }
};

struct Scan {
  Vec3f origin;               ///< sensor origin, map frame
  std::vector<Vec3f> points;  ///< map frame
  std::vector<Rgb> colors;    ///< empty, or one per point
  std::string name;           ///< where it came from, e.g. "run.graph scan 3"
  /// When the scan was taken (seconds, the input's own epoch), from readers
  /// whose input says so: TUM (the depth image's file name, e.g.
  /// depth/1311877812.987032.png) and ROS bags (the cloud's header.stamp);
  /// nothing otherwise. InsertOptions::stamp takes it for decay.
  std::optional<double> stamp;
  /// Set by readers of depth images: the image the points came from.
  std::optional<ScanImage> image;
};

class ScanSource {
 public:
  virtual ~ScanSource() = default;
  /// Reads the next scan into `scan` (reusing its buffers); false at the end.
  virtual bool next(Scan& scan) = 0;
  /// Number of scans when the format says so up front, else 0.
  [[nodiscard]] virtual std::size_t scan_count() const = 0;
  /// Fraction of the input consumed so far, 0..1 (for progress bars).
  [[nodiscard]] virtual double progress() const = 0;
  /// The sensor origin of every scan, in order, when the input states them
  /// before its points (ScanGraph and KITTI / TUM poses, a PCD viewpoint,
  /// the given origin of a single-scan file); empty when it does not. Lets a
  /// caller check them all before inserting anything.
  [[nodiscard]] virtual std::vector<Vec3f> origins() const { return {}; }
  /// What the reader noticed but did not refuse (e.g. TUM association rows
  /// whose images are missing), one sentence each naming the file.
  [[nodiscard]] virtual std::vector<std::string> warnings() const { return {}; }
};

/// A pinhole depth camera (TUM RGB-D and other depth images): pixel (u, v)
/// with raw depth value d lies at z = d / depth_scale metres in front of the
/// camera, x = (u - cx) z / fx to the right, y = (v - cy) z / fy down (the
/// optical frame). Defaults: the TUM fr2 Kinect, depth in 1/5000 m.
struct DepthCamera {
  double fx = 580.8;
  double fy = 581.8;
  double cx = 308.8;
  double cy = 253.0;
  double depth_scale = 5000.0;  ///< raw depth units per metre
};

struct ScanSourceOptions {
  std::string format;  ///< "graph", "xyz", "ply", "pcd", "kitti", "tum", "rosbag"; empty: chosen by the name
  Vec3f origin{};      ///< sensor origin for formats that carry none (xyz, ply, pcd without viewpoint, lone .bin)
  /// kitti: the poses file (KITTI odometry: 12 numbers per line, the 3x4
  /// row-major pose of camera 0 in the world, one line per scan).
  std::filesystem::path poses;
  /// kitti: calib.txt whose "Tr:" line maps velodyne to camera 0 (also
  /// "Tr_velo_to_cam:", or "R:" + "T:" lines); empty: identity, i.e. the
  /// poses are velodyne poses.
  std::filesystem::path calibration;
  /// tum: the association file when opening a folder (relative paths are
  /// taken relative to the folder); empty: the folder's one *assoc*.txt.
  std::filesystem::path association;
  DepthCamera depth_camera;  ///< tum: intrinsics and depth scale
  /// rosbag: the PointCloud2 topics to read; empty: every PointCloud2 topic.
  std::vector<std::string> topics;
  /// rosbag: the map frame the clouds are moved into with the bag's TF.
  std::string frame = "map";
};

/// Opens a file of one format (what register_scan_format() adds).
using ScanSourceOpener =
    std::function<std::unique_ptr<ScanSource>(const std::filesystem::path&, const ScanSourceOptions&)>;

/// Makes open_scan_source() read format `name` (lower case) with `open`,
/// replacing the reader it had, and adds `extensions` (with the dot, any
/// case) to those scan_format_for() knows for it: for readers that live
/// outside umbra_io, as ROS's .bag reader does. Register at start-up, before
/// other threads open files. Throws std::invalid_argument for an empty or
/// not lower-case name or an empty opener.
void register_scan_format(const std::string& name, const std::vector<std::string>& extensions,
                          ScanSourceOpener open);

/// Opens `path`; throws std::runtime_error / FormatError as described above.
std::unique_ptr<ScanSource> open_scan_source(const std::filesystem::path& path,
                                             const ScanSourceOptions& options = {});

/// The format name open_scan_source would use for `path`, or throws
/// std::invalid_argument listing the known extensions. By name (after
/// removing a trailing .bz2, any case): .graph graph; .xyz .dat .txt xyz;
/// .ply ply; .pcd pcd; .bin kitti; .bag rosbag. Otherwise an existing folder holding
/// depth/ and rgb/ is tum, one holding .bin files is kitti. A known
/// `format` wins over all of this.
std::string scan_format_for(const std::filesystem::path& path, const std::string& format = "");

}  // namespace umbra
