// ROS depth images to umbra: a sensor_msgs/Image of depths with its
// sensor_msgs/CameraInfo (and, optionally, a color image registered to it)
// become what OccupancyMap::insert_depth_image takes: a DepthImage, a
// PinholeCamera and one color per pixel.
//
// Depth encodings (REP 118): 16UC1, unsigned millimetres, 0 = no reading;
// 32FC1, float metres, NaN (or 0, a negative value, infinity) = no reading.
// Rows may be padded (`step` longer than a row); data in the other byte
// order than this machine's (`is_bigendian`) is swapped.
//
// Intrinsics, as image_geometry (and so depth_image_proc) reads them: from
// P, the projection of the rectified image, when its fx and fy are set,
// else from K; then moved by the region of interest's offset and divided by
// the binning, so that they describe the image as it arrives (roi.width x
// roi.height, or width x height without a region, divided by the binning).
// The image must be rectified: the distortion D is not applied.
//
// Color encodings: rgb8, bgr8, rgba8, bgra8 (alpha ignored), the same size
// as the depth image (registered to it, pixel for pixel, as a driver's
// aligned or registered depth is).
//
// Errors throw umbra::FormatError "NAME: what is wrong" naming the image
// (e.g. "depth image in frame 'camera' at 12.300000"): another encoding, no
// pixels, a step shorter than a row, data shorter than its rows, an image
// of another size than its CameraInfo (or its color image) describes, a
// CameraInfo without a calibration (fx or fy not finite and > 0).
//
// Cost: one copy of the pixels (into vectors kept by the caller, so that no
// frame allocates once they have grown).
#pragma once

#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <cstdint>
#include <string>
#include <vector>

#include "umbra/core/color.hpp"
#include "umbra/integrate/depth_image.hpp"

namespace umbra::ros_io {

/// One depth image copied out of its message: either raw millimetres or metres.
struct DecodedDepthImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint16_t> millimetres;  ///< 16UC1 (empty for 32FC1)
  std::vector<float> metres;               ///< 32FC1 (empty for 16UC1)

  /// A view of the pixels (valid while this object is unchanged).
  [[nodiscard]] DepthImage view() const;
};

/// Decodes a 16UC1 or 32FC1 image into `out` (its vectors are reused).
void decode_depth_image(const sensor_msgs::Image& image, DecodedDepthImage& out, const std::string& name);

/// The intrinsics `info` gives an image of width x height pixels; throws if
/// `info` describes another size or no calibration.
PinholeCamera camera_of(const sensor_msgs::CameraInfo& info, int width, int height, const std::string& name);

/// Decodes an rgb8 / bgr8 / rgba8 / bgra8 image of width x height pixels
/// into one color per pixel, row by row (`colors` is reused).
void decode_color_image(const sensor_msgs::Image& image, int width, int height, std::vector<Rgb>& colors,
                        const std::string& name);

}  // namespace umbra::ros_io
