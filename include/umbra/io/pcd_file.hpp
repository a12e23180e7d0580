// PCD point clouds (.pcd, the Point Cloud Library's format): one file, one scan.
//
// A PCD file is a text header (VERSION, FIELDS, SIZE, TYPE, COUNT, WIDTH,
// HEIGHT, VIEWPOINT, POINTS, DATA; versions 0.7 and the older headers that
// omit COUNT, WIDTH/HEIGHT, VIEWPOINT or say COLUMNS for FIELDS) followed by
// the points as text ("DATA ascii"), as packed little-endian records ("DATA
// binary") or LZF-compressed with the fields stored column by column ("DATA
// binary_compressed"). umbra reads the x, y, z fields (any PCD type, rounded
// to float; NaN points are passed through for the integrator to skip and
// count) and colors from a packed "rgb" or "rgba" field (4 bytes, float or
// integer, holding 0x00RRGGBB / 0xAARRGGBB). Other fields are skipped.
//
// Pose: PCL stores the sensor pose as VIEWPOINT tx ty tz qw qx qy qz
// (PointCloud::sensor_origin_ and sensor_orientation_) and its viewer
// (PCLVisualizer, pcl_viewer) draws the points transformed by that pose, i.e.
// the points are in the sensor frame. umbra does the same: when the
// viewpoint is not the identity (0 0 0 1 0 0 0, PCL's default), every point
// is mapped to R p + t and the scan's sensor origin is t; when it is the
// identity (or absent) the points are used as they are and the origin is the
// caller's. The header is validated when the file is opened (counts against
// the file size, and for compressed data the claimed sizes against what LZF
// can produce), so a hostile file never causes a large allocation; the data
// is read in next(). Errors are FormatError with the line (header, ascii
// data) or byte offset (binary data).
#pragma once

#include <filesystem>
#include <memory>

#include "umbra/core/vec3.hpp"
#include "umbra/io/scan_source.hpp"

namespace umbra {

/// Opens a PCD file as a source of exactly one scan; `origin` is the sensor
/// origin when the file's VIEWPOINT is the identity. Throws
/// std::runtime_error("cannot open FILE: reason") when the file cannot be
/// opened, FormatError for a bad header (here) or bad data (from next()).
/// open_scan_source() calls this for the "pcd" format.
std::unique_ptr<ScanSource> open_pcd_file(const std::filesystem::path& path, Vec3f origin = {});

}  // namespace umbra
