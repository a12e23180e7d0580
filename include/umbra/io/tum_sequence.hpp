// TUM RGB-D sequences: depth images with poses, back-projected into scans.
//
// A TUM RGB-D benchmark sequence has depth/*.png (16-bit greyscale, raw
// value / depth_scale = metres, 0 = no reading) and rgb/*.png (8-bit color,
// same size), named by their timestamps. An association file pairs them
// with the ground-truth pose, one row per frame: "rgb_path depth_path tx ty
// tz qx qy qz qw" (paths relative to the association file's folder; the pose
// is the camera-to-world transform of the optical frame, quaternion with w
// last, as in TUM's groundtruth.txt); '#' lines are comments. Every row
// whose depth and color images both exist on disk is a scan, in file order
// (a partial copy of a sequence yields just the frames it holds). A scan is
// built from every pixel (u, v) with a non-zero depth d: camera point
// z = d / depth_scale, x = (u - cx) z / fx, y = (v - cy) z / fy (x right, y
// down, z forward), mapped to the world by the row's pose; the origin is the
// pose's translation, the color the color image's pixel (u, v). Opening
// parses and checks the whole association file (a few hundred KB for a long
// sequence) and looks up which files exist; next() decodes one frame's two
// images (libpng) into reused buffers, so memory stays at one frame. The
// scan keeps the depth image and the color image (Scan::image) for the
// projective integrator; its points are back_project() of that image.
#pragma once

#include <filesystem>
#include <memory>

#include "umbra/io/scan_source.hpp"

namespace umbra {

/// Opens the sequence described by `association_file`. Throws
/// std::invalid_argument for a camera with non-positive or non-finite focal
/// lengths or depth scale, std::runtime_error("cannot open FILE: reason")
/// when the association file cannot be opened, FormatError (file and line)
/// for a malformed row, and FormatError when no row has both its images
/// (an empty association file, or none of its images on disk); undecodable
/// images throw FormatError from next(). Rows whose images are missing are
/// skipped and counted in warnings() (the first such row named). A depth
/// image whose frame would need more than memory_limit() (29 bytes a pixel:
/// both images, the scan's copy of them and the points) throws MemoryLimitError from next() before it
/// is decoded.
std::unique_ptr<ScanSource> open_tum_sequence(const std::filesystem::path& association_file,
                                              const DepthCamera& camera = {});

/// The association file of a sequence folder: `association` when given
/// (taken relative to the folder unless absolute), else the folder's only
/// regular file whose name contains "assoc" and ends in ".txt" (any case).
/// Throws std::runtime_error naming the folder when there is none or more
/// than one. open_scan_source() uses it when the "tum" path is a folder.
std::filesystem::path find_tum_association(const std::filesystem::path& folder,
                                           const std::filesystem::path& association = {});

}  // namespace umbra
