// ROS depth images to umbra: see image_message.hpp.
#include "image_message.hpp"

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include "umbra/io/format_error.hpp"

namespace umbra::ros_io {
namespace {

std::string size_text(std::uint64_t width, std::uint64_t height) {
  return std::to_string(width) + " x " + std::to_string(height);
}

/// Checks that the image's rows of `bytes_per_pixel`-byte pixels lie inside its data.
void check_layout(const sensor_msgs::Image& image, std::uint32_t bytes_per_pixel, const std::string& what,
                  const std::string& name) {
  if (image.width == 0 || image.height == 0) {
    throw FormatError(name, what + " has no pixels (" + size_text(image.width, image.height) + ")");
  }
  // int: the library's image sizes; a message (at most 4 GiB) cannot hold more rows or columns anyway.
  if (image.width > std::uint32_t(std::numeric_limits<int>::max()) ||
      image.height > std::uint32_t(std::numeric_limits<int>::max())) {
    throw FormatError(name, what + " of " + size_text(image.width, image.height) + " pixels is too large");
  }
  const std::uint64_t row_bytes = std::uint64_t{image.width} * bytes_per_pixel;
  if (image.step < row_bytes) {
    throw FormatError(name, what + " (" + image.encoding + ", " + size_text(image.width, image.height) +
                                ") has step " + std::to_string(image.step) + ", shorter than a row of " +
                                std::to_string(row_bytes) + " bytes");
  }
  const std::uint64_t needed = std::uint64_t{image.step} * image.height;
  if (image.data.size() < needed) {
    throw FormatError(name, what + " (" + image.encoding + ", " + size_text(image.width, image.height) +
                                ") holds " + std::to_string(image.data.size()) + " bytes of data, but " +
                                std::to_string(image.height) + " rows of step " + std::to_string(image.step) +
                                " need " + std::to_string(needed));
  }
}

/// Whether the message's bytes are in the other order than this machine's.
bool swapped(const sensor_msgs::Image& image) {
  return (image.is_bigendian != 0) != (std::endian::native == std::endian::big);
}

/// Copies the pixels of a checked image, row by row, as T (2 or 4 bytes), swapping the bytes if asked.
template <typename T>
void copy_pixels(const sensor_msgs::Image& image, bool swap, std::vector<T>& out) {
  static_assert(sizeof(T) == 2 || sizeof(T) == 4);
  out.resize(std::size_t{image.width} * image.height);
  const std::size_t row_bytes = std::size_t{image.width} * sizeof(T);
  for (std::size_t row = 0; row < image.height; ++row) {
    std::memcpy(out.data() + row * image.width, image.data.data() + row * image.step, row_bytes);
  }
  if (!swap) return;
  for (T& value : out) {
    using Bits = std::conditional_t<sizeof(T) == 2, std::uint16_t, std::uint32_t>;
    Bits bits;
    std::memcpy(&bits, &value, sizeof bits);
    Bits reversed = 0;
    for (std::size_t byte = 0; byte < sizeof bits; ++byte) {
      reversed = static_cast<Bits>((reversed << 8) | ((bits >> (8 * byte)) & 0xFFu));
    }
    std::memcpy(&value, &reversed, sizeof value);
  }
}

bool calibrated(double focal_length) { return std::isfinite(focal_length) && focal_length > 0.0; }

}  // namespace

DepthImage DecodedDepthImage::view() const {
  // sensor_msgs/Image's 16UC1 depths are millimetres (REP 118).
  return millimetres.empty() ? DepthImage::metres(metres, width, height)
                             : DepthImage::raw(millimetres, width, height, 1000.0);
}

void decode_depth_image(const sensor_msgs::Image& image, DecodedDepthImage& out, const std::string& name) {
  const bool millimetres = image.encoding == "16UC1";
  if (!millimetres && image.encoding != "32FC1") {
    throw FormatError(name, "depth image has encoding '" + image.encoding +
                                "'; umbra reads 16UC1 (millimetres) and 32FC1 (metres)");
  }
  check_layout(image, millimetres ? 2 : 4, "depth image", name);
  out.width = static_cast<int>(image.width);
  out.height = static_cast<int>(image.height);
  if (millimetres) {
    copy_pixels(image, swapped(image), out.millimetres);
    out.metres.clear();
  } else {
    copy_pixels(image, swapped(image), out.metres);
    out.millimetres.clear();
  }
}

PinholeCamera camera_of(const sensor_msgs::CameraInfo& info, int width, int height, const std::string& name) {
  // P's intrinsics (the rectified image's) where set, else K's: image_geometry's choice.
  const bool projection = calibrated(info.P[0]) && calibrated(info.P[5]);
  PinholeCamera camera;
  camera.fx = projection ? info.P[0] : info.K[0];
  camera.cx = projection ? info.P[2] : info.K[2];
  camera.fy = projection ? info.P[5] : info.K[4];
  camera.cy = projection ? info.P[6] : info.K[5];
  if (!calibrated(camera.fx) || !calibrated(camera.fy) || !std::isfinite(camera.cx) || !std::isfinite(camera.cy)) {
    throw FormatError(name, "its CameraInfo has no calibration (fx " + std::to_string(camera.fx) + ", fy " +
                                std::to_string(camera.fy) + " from " + (projection ? "P" : "K") +
                                "; both must be > 0)");
  }
  // A region of interest and binning change the image the intrinsics describe (image_geometry's rule).
  const std::uint32_t binning_x = std::max<std::uint32_t>(info.binning_x, 1);
  const std::uint32_t binning_y = std::max<std::uint32_t>(info.binning_y, 1);
  const bool region = info.roi.width != 0 && info.roi.height != 0;
  camera.cx = (camera.cx - (region ? info.roi.x_offset : 0)) / binning_x;
  camera.cy = (camera.cy - (region ? info.roi.y_offset : 0)) / binning_y;
  camera.fx /= binning_x;
  camera.fy /= binning_y;
  const std::uint64_t expected_width = (region ? info.roi.width : info.width) / binning_x;
  const std::uint64_t expected_height = (region ? info.roi.height : info.height) / binning_y;
  if (std::uint64_t(width) != expected_width || std::uint64_t(height) != expected_height) {
    std::string described = size_text(expected_width, expected_height);
    if (region || binning_x > 1 || binning_y > 1) {
      described += " (" + size_text(info.width, info.height) +
                   (region ? ", region of interest " + size_text(info.roi.width, info.roi.height) : std::string()) +
                   (binning_x > 1 || binning_y > 1 ? ", binning " + size_text(binning_x, binning_y) : std::string()) +
                   ")";
    }
    throw FormatError(name, "depth image is " + size_text(std::uint64_t(width), std::uint64_t(height)) +
                                " pixels, but its CameraInfo describes " + described);
  }
  return camera;
}

void decode_color_image(const sensor_msgs::Image& image, int width, int height, std::vector<Rgb>& colors,
                        const std::string& name) {
  const std::string& encoding = image.encoding;
  const bool rgb = encoding == "rgb8" || encoding == "rgba8";
  const bool bgr = encoding == "bgr8" || encoding == "bgra8";
  if (!rgb && !bgr) {
    throw FormatError(name, "color image has encoding '" + encoding + "'; umbra reads rgb8, bgr8, rgba8 and bgra8");
  }
  const std::uint32_t channels = encoding.size() == 5 ? 4 : 3;  // "rgba8", "bgra8"
  check_layout(image, channels, "color image", name);
  if (image.width != std::uint32_t(width) || image.height != std::uint32_t(height)) {
    throw FormatError(name, "color image is " + size_text(image.width, image.height) +
                                " pixels, the depth image " + size_text(std::uint64_t(width), std::uint64_t(height)) +
                                "; umbra needs a color image registered to the depth image, pixel for pixel");
  }
  colors.resize(std::size_t{image.width} * image.height);
  std::size_t index = 0;
  for (std::size_t row = 0; row < image.height; ++row) {
    const std::uint8_t* pixel = image.data.data() + row * image.step;
    for (std::size_t column = 0; column < image.width; ++column, pixel += channels) {
      colors[index++] = rgb ? Rgb{pixel[0], pixel[1], pixel[2]} : Rgb{pixel[2], pixel[1], pixel[0]};
    }
  }
}

}  // namespace umbra::ros_io
