// ROS depth images to umbra (ros/src/image_message.hpp): the pixels of
// 16UC1 and 32FC1 images, padded rows and either byte order; the
// intrinsics of a CameraInfo (P, else K; region of interest and binning as
// image_geometry applies them); color images of each encoding; and an
// error naming the image for every malformed message.
#include <cmath>
#include <cstring>
#include <limits>

#include "image_message.hpp"
#include "umbra/io/format_error.hpp"

#include <gtest/gtest.h>

namespace umbra::test {
namespace {

using ros_io::camera_of;
using ros_io::decode_color_image;
using ros_io::decode_depth_image;
using ros_io::DecodedDepthImage;

const std::string kName = "depth image in frame 'camera' at 12.500000";

/// An image of `width` x `height` pixels of `bytes` bytes each, rows padded to `step`, pixel (u, v) written by
/// `write(u, v, bytes_of_the_pixel)`.
template <typename Write>
sensor_msgs::Image image_of(const std::string& encoding, std::uint32_t width, std::uint32_t height,
                            std::uint32_t bytes, std::uint32_t step, bool big_endian, const Write& write) {
  sensor_msgs::Image image;
  image.encoding = encoding;
  image.width = width;
  image.height = height;
  image.step = step;
  image.is_bigendian = big_endian ? 1 : 0;
  image.data.assign(std::size_t{step} * height, 0xEE);  // padding: a value no test pixel holds
  for (std::uint32_t v = 0; v < height; ++v) {
    for (std::uint32_t u = 0; u < width; ++u) write(u, v, image.data.data() + v * step + u * bytes);
  }
  return image;
}

/// The bytes of `value` in the requested order.
template <typename T>
void put(T value, bool big_endian, std::uint8_t* out) {
  std::uint8_t bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));  // this machine's order (little-endian on every machine umbra targets)
  for (std::size_t i = 0; i < sizeof(T); ++i) out[i] = bytes[big_endian ? sizeof(T) - 1 - i : i];
}

std::string error_of(const std::function<void()>& call) {
  try {
    call();
  } catch (const FormatError& e) {
    return e.what();
  }
  return "no error";
}

TEST(ImageMessage, MillimetreImagesInEitherByteOrderWithPaddedRows) {
  for (const bool big_endian : {false, true}) {
    // 5 x 3 pixels of 2 bytes in rows of 14 bytes: 4 bytes of padding per row.
    const auto image = image_of("16UC1", 5, 3, 2, 14, big_endian, [&](std::uint32_t u, std::uint32_t v, std::uint8_t* p) {
      put<std::uint16_t>(static_cast<std::uint16_t>(u == 1 && v == 2 ? 0 : 1000 + 300 * v + u), big_endian, p);
    });
    DecodedDepthImage decoded;
    decode_depth_image(image, decoded, kName);
    ASSERT_EQ(decoded.width, 5);
    ASSERT_EQ(decoded.height, 3);
    EXPECT_TRUE(decoded.metres.empty());
    const DepthImage view = decoded.view();
    ASSERT_TRUE(view.is_raw());
    EXPECT_EQ(view.metres_per_unit(), 1.0 / 1000.0);  // REP 118: millimetres
    for (std::uint32_t v = 0; v < 3; ++v) {
      for (std::uint32_t u = 0; u < 5; ++u) {
        const std::size_t index = v * 5 + u;
        const std::uint16_t want = static_cast<std::uint16_t>(u == 1 && v == 2 ? 0 : 1000 + 300 * v + u);
        EXPECT_EQ(view.raw_depths()[index], want) << "pixel " << u << ", " << v << (big_endian ? " big-endian" : "");
        EXPECT_DOUBLE_EQ(view.depth(index), want / 1000.0);  // the library multiplies by 1 / 1000
      }
    }
  }
}

TEST(ImageMessage, MetreImagesKeepNaNAsNoReading) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (const bool big_endian : {false, true}) {
    const auto image = image_of("32FC1", 4, 2, 4, 20, big_endian, [&](std::uint32_t u, std::uint32_t v, std::uint8_t* p) {
      put<float>(u == 3 ? nan : 0.5f + 0.25f * static_cast<float>(u + 4 * v), big_endian, p);
    });
    DecodedDepthImage decoded;
    decoded.millimetres.assign(3, 7);  // left from an earlier 16UC1 image: must go
    decode_depth_image(image, decoded, kName);
    EXPECT_TRUE(decoded.millimetres.empty());
    const DepthImage view = decoded.view();
    ASSERT_FALSE(view.is_raw());
    for (std::uint32_t v = 0; v < 2; ++v) {
      for (std::uint32_t u = 0; u < 4; ++u) {
        const std::size_t index = v * 4 + u;
        if (u == 3) {
          EXPECT_TRUE(std::isnan(view.metre_depths()[index]));
          EXPECT_EQ(view.depth(index), 0.0);  // no reading
        } else {
          EXPECT_EQ(view.metre_depths()[index], 0.5f + 0.25f * static_cast<float>(index));
        }
      }
    }
  }
}

TEST(ImageMessage, MalformedDepthImagesNameTheImageAndTheProblem) {
  const auto plain = [](std::uint32_t, std::uint32_t, std::uint8_t* p) { put<std::uint16_t>(1500, false, p); };
  DecodedDepthImage decoded;
  const auto decode = [&](const sensor_msgs::Image& image) {
    return error_of([&] { decode_depth_image(image, decoded, kName); });
  };
  EXPECT_EQ(decode(image_of("mono8", 4, 3, 1, 4, false, plain)),
            kName + ": depth image has encoding 'mono8'; umbra reads 16UC1 (millimetres) and 32FC1 (metres)");
  EXPECT_EQ(decode(image_of("16UC1", 0, 3, 2, 0, false, plain)), kName + ": depth image has no pixels (0 x 3)");
  EXPECT_EQ(decode(image_of("16UC1", 4, 3, 2, 7, false, plain)),
            kName + ": depth image (16UC1, 4 x 3) has step 7, shorter than a row of 8 bytes");
  auto short_data = image_of("32FC1", 4, 3, 4, 16, false, plain);
  short_data.data.resize(47);
  EXPECT_EQ(decode(short_data), kName + ": depth image (32FC1, 4 x 3) holds 47 bytes of data, but 3 rows of step 16 "
                                        "need 48");
  // A step whose rows overflow 32 bits is checked in 64.
  auto huge_step = image_of("16UC1", 4, 3, 2, 8, false, plain);
  huge_step.step = 0xFFFFFFF0u;
  EXPECT_NE(decode(huge_step).find("holds 24 bytes of data, but 3 rows of step 4294967280 need 12884901840"),
            std::string::npos);
}

sensor_msgs::CameraInfo info_of(std::uint32_t width, std::uint32_t height) {
  sensor_msgs::CameraInfo info;
  info.width = width;
  info.height = height;
  info.K = {500.0, 0.0, 319.5, 0.0, 510.0, 239.5, 0.0, 0.0, 1.0};
  return info;
}

TEST(ImageMessage, IntrinsicsFromPElseK) {
  sensor_msgs::CameraInfo info = info_of(640, 480);
  // Only K (P all zero): K's.
  PinholeCamera camera = camera_of(info, 640, 480, kName);
  EXPECT_EQ(camera.fx, 500.0);
  EXPECT_EQ(camera.fy, 510.0);
  EXPECT_EQ(camera.cx, 319.5);
  EXPECT_EQ(camera.cy, 239.5);
  // P set (the rectified image's): P's, its Tx ignored.
  info.P = {490.0, 0.0, 321.0, -12.0, 0.0, 495.0, 241.0, 0.0, 0.0, 0.0, 1.0, 0.0};
  camera = camera_of(info, 640, 480, kName);
  EXPECT_EQ(camera.fx, 490.0);
  EXPECT_EQ(camera.fy, 495.0);
  EXPECT_EQ(camera.cx, 321.0);
  EXPECT_EQ(camera.cy, 241.0);
  // A region of interest moves the principal point; binning scales everything (image_geometry's rule).
  info.roi.x_offset = 100;
  info.roi.y_offset = 40;
  info.roi.width = 320;
  info.roi.height = 200;
  info.binning_x = 2;
  info.binning_y = 4;
  camera = camera_of(info, 160, 50, kName);
  EXPECT_EQ(camera.fx, 245.0);
  EXPECT_EQ(camera.fy, 123.75);
  EXPECT_EQ(camera.cx, (321.0 - 100.0) / 2.0);
  EXPECT_EQ(camera.cy, (241.0 - 40.0) / 4.0);
}

TEST(ImageMessage, CameraInfoOfAnotherSizeOrWithoutCalibrationIsAnError) {
  sensor_msgs::CameraInfo info = info_of(640, 480);
  EXPECT_EQ(error_of([&] { camera_of(info, 320, 240, kName); }),
            kName + ": depth image is 320 x 240 pixels, but its CameraInfo describes 640 x 480");
  info.binning_x = 2;
  info.binning_y = 2;
  info.roi.width = 600;
  info.roi.height = 400;
  EXPECT_EQ(error_of([&] { camera_of(info, 320, 240, kName); }),
            kName + ": depth image is 320 x 240 pixels, but its CameraInfo describes 300 x 200 (640 x 480, region of "
                    "interest 600 x 400, binning 2 x 2)");
  sensor_msgs::CameraInfo uncalibrated;  // what a driver without calibration publishes: zeros
  uncalibrated.width = 640;
  uncalibrated.height = 480;
  EXPECT_EQ(error_of([&] { camera_of(uncalibrated, 640, 480, kName); }),
            kName + ": its CameraInfo has no calibration (fx 0.000000, fy 0.000000 from K; both must be > 0)");
  info = info_of(640, 480);
  info.K[4] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(error_of([&] { camera_of(info, 640, 480, kName); }).find("has no calibration (fx 500.000000, fy nan"),
            std::string::npos);
}

TEST(ImageMessage, ColorImagesOfEachEncoding) {
  for (const std::string encoding : {"rgb8", "bgr8", "rgba8", "bgra8"}) {
    const std::uint32_t channels = encoding.size() == 5 ? 4 : 3;
    const bool bgr = encoding[0] == 'b';
    const auto image = image_of(encoding, 3, 2, channels, 3 * channels + 2, false,
                                [&](std::uint32_t u, std::uint32_t v, std::uint8_t* p) {
                                  const std::uint8_t r = static_cast<std::uint8_t>(10 * u + v);
                                  const std::uint8_t g = static_cast<std::uint8_t>(100 + u);
                                  const std::uint8_t b = static_cast<std::uint8_t>(200 + v);
                                  p[0] = bgr ? b : r;
                                  p[1] = g;
                                  p[2] = bgr ? r : b;
                                  if (channels == 4) p[3] = 7;
                                });
    std::vector<Rgb> colors;
    decode_color_image(image, 3, 2, colors, kName);
    ASSERT_EQ(colors.size(), 6u) << encoding;
    for (std::uint32_t v = 0; v < 2; ++v) {
      for (std::uint32_t u = 0; u < 3; ++u) {
        const Rgb want{static_cast<std::uint8_t>(10 * u + v), static_cast<std::uint8_t>(100 + u),
                       static_cast<std::uint8_t>(200 + v)};
        EXPECT_EQ(colors[v * 3 + u], want) << encoding << " pixel " << u << ", " << v;
      }
    }
  }
}

TEST(ImageMessage, MalformedColorImagesNameTheImageAndTheProblem) {
  const auto grey = [](std::uint32_t, std::uint32_t, std::uint8_t* p) { p[0] = p[1] = p[2] = 9; };
  std::vector<Rgb> colors;
  const auto decode = [&](const sensor_msgs::Image& image) {
    return error_of([&] { decode_color_image(image, 4, 3, colors, kName); });
  };
  EXPECT_EQ(decode(image_of("mono8", 4, 3, 3, 12, false, grey)),
            kName + ": color image has encoding 'mono8'; umbra reads rgb8, bgr8, rgba8 and bgra8");
  EXPECT_EQ(decode(image_of("rgb8", 5, 3, 3, 15, false, grey)),
            kName + ": color image is 5 x 3 pixels, the depth image 4 x 3; umbra needs a color image registered "
                    "to the depth image, pixel for pixel");
  EXPECT_EQ(decode(image_of("rgba8", 4, 3, 3, 12, false, grey)),
            kName + ": color image (rgba8, 4 x 3) has step 12, shorter than a row of 16 bytes");
}

}  // namespace
}  // namespace umbra::test
