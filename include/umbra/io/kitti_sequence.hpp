// KITTI velodyne scans (.bin) with KITTI odometry poses: a sequence of scans.
//
// A KITTI velodyne file holds one scan as float32 x, y, z, reflectance per
// point (little-endian, 16 bytes per point, sensor frame; reflectance is
// ignored). The odometry benchmark's poses file (dataset/poses/NN.txt) has
// one line per scan with 12 numbers, the row-major 3x4 pose P of the left
// camera (camera 0) in the world frame (the first camera pose), and the
// sequence's calib.txt has a "Tr:" line, the 3x4 transform from the
// velodyne frame to camera 0. umbra maps a point p of scan i to the world as
// P_i Tr p, and the scan's sensor origin is P_i Tr (0, 0, 0), the velodyne's
// position. Tr is used only when a calibration file is given; without one it
// is the identity, i.e. the poses are taken to be velodyne poses already (as
// LiDAR odometry tools such as KISS-ICP write them): with the official KITTI
// poses, give calib.txt, or the map comes out rotated. Scan i uses pose line
// number(name) + 1 when every scan file is named by a number (000000.bin,
// 000001.bin, ...; so a folder holding only some of the scans still matches
// its poses), else line i + 1 of the name-sorted list. Files are read one at
// a time when next() reaches them, through a fixed-size buffer; the poses
// and the calibration are parsed (and checked) when the source is opened.
#pragma once

#include <filesystem>
#include <memory>
#include <vector>

#include "umbra/core/vec3.hpp"
#include "umbra/io/scan_source.hpp"

namespace umbra {

struct KittiOptions {
  std::filesystem::path poses;        ///< KITTI odometry poses file; empty: no poses (one scan only)
  std::filesystem::path calibration;  ///< calib.txt with "Tr:" (or "Tr_velo_to_cam:", or "R:" + "T:"); empty: identity
  Vec3f origin{};                     ///< sensor origin of a lone scan without poses
};

/// Opens a folder of KITTI .bin files (name order) or one .bin file. A
/// folder needs `options.poses` (std::invalid_argument otherwise, since
/// scans without poses would all sit on top of each other); one file without
/// poses is one scan in its sensor frame with origin `options.origin`.
/// Throws std::runtime_error("cannot open PATH: reason") for a missing path,
/// a folder without .bin files, or an unreadable poses/calibration file, and
/// FormatError (file and line) for a malformed poses or calibration file
/// (also a pose or transform whose 3x3 part is singular, |determinant| <
/// 1e-6, such as all zeros: it would collapse the scan) or when a scan has
/// no pose line. Bad .bin files throw FormatError (byte
/// offset) from next(). open_scan_source() calls this for the "kitti" format.
std::unique_ptr<ScanSource> open_kitti_velodyne(const std::filesystem::path& folder_or_file,
                                                const KittiOptions& options = {});

/// The same for an explicit list of .bin files, read in the order given.
std::unique_ptr<ScanSource> open_kitti_scans(std::vector<std::filesystem::path> scan_files,
                                             const KittiOptions& options = {});

}  // namespace umbra
