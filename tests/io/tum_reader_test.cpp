// Tests of the TUM RGB-D reader (tum_sequence.hpp).
//
// A tiny sequence whose 16-bit depth PNGs come from the minimal encoder in
// reader_test_support.hpp, back-projected against hand-computed points; the
// real fr2/pioneer_slam2 frames when ../shared/data has them.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <random>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "support/test_support.hpp"
#include "umbra/io/format_error.hpp"
#include "umbra/io/kitti_sequence.hpp"
#include "umbra/io/pcd_file.hpp"
#include "umbra/io/ply_file.hpp"
#include "umbra/io/png_writer.hpp"
#include "umbra/io/scan_source.hpp"
#include "umbra/io/tum_sequence.hpp"
#include "reader_test_support.hpp"

namespace umbra {
namespace {

using namespace reader_test;  // NOLINT(google-build-using-namespace): the fixtures of every reader test

// =================================================================================
// TUM RGB-D
// =================================================================================

struct TumFixture {
  fs::path folder;
  fs::path association;
  DepthCamera camera{2.0, 4.0, 1.5, 1.0, 1000.0};
  std::uint32_t width = 4;
  std::uint32_t height = 3;
  std::vector<std::vector<std::uint16_t>> depths;
  std::vector<Image> colors;
  std::vector<Matrix34> poses;          // of the frames on disk
  std::vector<std::array<double, 3>> origins;
};

TumFixture tum_fixture(const fs::path& dir) {
  TumFixture fixture;
  fixture.folder = dir / "rgbd_dataset_test";
  fs::create_directories(fixture.folder / "depth");
  fs::create_directories(fixture.folder / "rgb");
  fixture.depths = {{0, 1000, 2000, 0, 500, 0, 65535, 3000, 1, 2, 0, 0}, {7, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 4000}};
  for (std::size_t frame = 0; frame < 2; ++frame) {
    Image color(4, 3);
    for (int row = 0; row < 3; ++row) {
      for (int column = 0; column < 4; ++column) {
        color.set(column, row,
                   {static_cast<std::uint8_t>(10 * column + 1), static_cast<std::uint8_t>(50 * row + 2),
                    static_cast<std::uint8_t>(100 * frame + 3)});
      }
    }
    fixture.colors.push_back(color);
  }
  write_grey_png(fixture.folder / "depth" / "1.001.png", 4, 3, fixture.depths[0]);
  write_png(fixture.colors[0], fixture.folder / "rgb" / "1.000.png");
  write_grey_png(fixture.folder / "depth" / "3.001.png", 4, 3, fixture.depths[1]);
  write_png(fixture.colors[1], fixture.folder / "rgb" / "3.000.png");
  write_png(fixture.colors[1], fixture.folder / "rgb" / "4.000.png");  // its depth image is missing
  const double half = std::sqrt(0.5);
  fixture.poses = {Matrix34::from_quaternion(1, 0, 0, 0, 1, 2, 3), Matrix34::from_quaternion(half, 0, 0, half, -1, 0.5, 2)};
  fixture.origins = {{1, 2, 3}, {-1, 0.5, 2}};
  fixture.association = fixture.folder / "my_association.txt";
  write_file(fixture.association,
             "# association of rgb,depth,groundtruth\n"
             "# rgb depth tx ty tz qx qy qz qw\n"
             "rgb/1.000.png depth/1.001.png 1 2 3 0 0 0 1 \n"
             "rgb/2.000.png depth/2.001.png 0 0 0 0 0 0 1\n"
             "\n"
             "rgb/3.000.png depth/3.001.png -1 0.5 2 0 0 " + std::to_string(half) + " " + std::to_string(half) + "\n"
             "rgb/4.000.png depth/4.001.png 0 0 0 0 0 0 1\n");
  return fixture;
}

void expect_tum_frames(const std::vector<Scan>& scans, const TumFixture& fixture) {
  ASSERT_EQ(scans.size(), 2u);
  for (std::size_t frame = 0; frame < 2; ++frame) {
    const Scan& scan = scans[frame];
    const std::string what = scan.name;
    expect_near_point(scan.origin, fixture.origins[frame], 1e-6, what + " origin");
    EXPECT_TRUE(contains(scan.name, frame == 0 ? "depth/1.001.png" : "depth/3.001.png")) << scan.name;
    EXPECT_TRUE(contains(scan.name, "frame " + std::to_string(frame + 1) + " of 2")) << scan.name;
    // TUM names images by their time: the depth image's name is the scan's stamp.
    ASSERT_TRUE(scan.stamp.has_value()) << what;
    EXPECT_DOUBLE_EQ(*scan.stamp, frame == 0 ? 1.001 : 3.001) << what;
    ASSERT_EQ(scan.colors.size(), scan.points.size()) << what;
    std::size_t k = 0;
    for (std::uint32_t v = 0; v < fixture.height; ++v) {
      for (std::uint32_t u = 0; u < fixture.width; ++u) {
        const std::uint16_t raw = fixture.depths[frame][v * fixture.width + u];
        if (raw == 0) continue;
        ASSERT_LT(k, scan.points.size()) << what;
        const double z = raw / fixture.camera.depth_scale;
        const double x = (u - fixture.camera.cx) * z / fixture.camera.fx;
        const double y = (v - fixture.camera.cy) * z / fixture.camera.fy;
        expect_near_point(scan.points[k], fixture.poses[frame].apply(x, y, z), 1e-4,
                          what + " pixel " + std::to_string(u) + "," + std::to_string(v));
        EXPECT_EQ(scan.colors[k], fixture.colors[frame].at(static_cast<int>(u), static_cast<int>(v))) << what;
        ++k;
      }
    }
    EXPECT_EQ(k, scan.points.size()) << what;
  }
}

TEST(TumReader, FramesOnDiskAreBackProjected) {
  const TumFixture fixture = tum_fixture(test::scratch_dir());
  ScanSourceOptions options;
  options.depth_camera = fixture.camera;
  // The folder (format detected), the folder with an explicit format, the file with format "tum".
  EXPECT_EQ(scan_format_for(fixture.folder), "tum");
  const auto source = open_scan_source(fixture.folder, options);
  EXPECT_EQ(source->scan_count(), 2u);
  EXPECT_EQ(source->progress(), 0.0);
  const std::vector<Scan> scans = read_all(*source);
  EXPECT_EQ(source->progress(), 1.0);
  expect_tum_frames(scans, fixture);
  // The rows whose images are missing (lines 4 and 6) are skipped with a warning naming the first one.
  const std::vector<std::string> warnings = source->warnings();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_TRUE(contains(warnings[0], "my_association.txt: 2 of its 4 rows were skipped because their images are "
                                    "missing (the first is line 4 of " + fixture.association.string() + ": " +
                                    (fixture.folder / "depth" / "2.001.png").string() + " does not exist)"))
      << warnings[0];
  // The origins are known before any image is decoded.
  const std::vector<Vec3f> origins = open_scan_source(fixture.folder, options)->origins();
  ASSERT_EQ(origins.size(), 2u);
  for (std::size_t frame = 0; frame < 2; ++frame) expect_near_point(origins[frame], fixture.origins[frame], 1e-6, "origin");
  options.format = "tum";
  expect_tum_frames(read_all(fixture.folder, options), fixture);
  expect_tum_frames(read_all(fixture.association, options), fixture);
  expect_tum_frames(read_all(*open_tum_sequence(fixture.association, fixture.camera)), fixture);
  // The default camera is the fr2 Kinect.
  const DepthCamera fr2;
  EXPECT_EQ(fr2.fx, 580.8);
  EXPECT_EQ(fr2.fy, 581.8);
  EXPECT_EQ(fr2.cx, 308.8);
  EXPECT_EQ(fr2.cy, 253.0);
  EXPECT_EQ(fr2.depth_scale, 5000.0);
}

TEST(TumReader, ImagesNotNamedByTheirTimeGiveNoStamp) {
  const TumFixture fixture = tum_fixture(test::scratch_dir());
  fs::copy_file(fixture.folder / "depth" / "1.001.png", fixture.folder / "depth" / "first.png");
  write_file(fixture.association, "rgb/1.000.png depth/first.png 1 2 3 0 0 0 1\nrgb/1.000.png depth/1.001.png 1 2 3 0 0 0 1\n");
  ScanSourceOptions options;
  options.depth_camera = fixture.camera;
  const std::vector<Scan> scans = read_all(fixture.folder, options);
  ASSERT_EQ(scans.size(), 2u);
  EXPECT_FALSE(scans[0].stamp.has_value()) << *scans[0].stamp;
  ASSERT_TRUE(scans[1].stamp.has_value());
  EXPECT_DOUBLE_EQ(*scans[1].stamp, 1.001);
}

TEST(TumReader, AssociationDiscoveryAndErrors) {
  const fs::path dir = test::scratch_dir();
  TumFixture fixture = tum_fixture(dir);
  EXPECT_EQ(find_tum_association(fixture.folder), fixture.association);
  EXPECT_EQ(find_tum_association(fixture.folder, "other.txt"), fixture.folder / "other.txt");
  write_file(fixture.folder / "associations.txt", "");
  EXPECT_THROW((void)find_tum_association(fixture.folder), std::runtime_error);
  ScanSourceOptions options;
  options.association = "associations.txt";  // empty: no frames, which is an error naming the file
  const std::string empty = format_error_of(fixture.folder, options);
  EXPECT_TRUE(contains(empty, "associations.txt: the association file lists no frames")) << empty;
  fs::remove(fixture.folder / "associations.txt");
  fs::remove(fixture.association);
  try {
    (void)find_tum_association(fixture.folder);
    ADD_FAILURE() << "expected runtime_error";
  } catch (const std::runtime_error& error) {
    EXPECT_TRUE(contains(error.what(), "no association file")) << error.what();
  }

  // Malformed rows: the line is named.
  fixture = tum_fixture(dir / "again");
  const fs::path association = fixture.association;
  options = {};
  options.format = "tum";
  write_file(association, "# header\nrgb/1.000.png depth/1.001.png 1 2 3 0 0 0\n");
  std::string message = format_error_of(association, options);
  EXPECT_TRUE(contains(message, association.string() + ":2:")) << message;
  write_file(association, "rgb/1.000.png depth/1.001.png 1 2 3 0 0 0 zero\n");
  EXPECT_TRUE(contains(format_error_of(association, options), ":1:"));
  write_file(association, "rgb/1.000.png depth/1.001.png 1 2 3 0 0 0 0\n");
  EXPECT_TRUE(contains(format_error_of(association, options), "bad pose"));
  // An 8-bit depth image, a corrupt one, a color image of another size.
  write_file(association, "rgb/1.000.png depth/1.001.png 1 2 3 0 0 0 1\n");
  write_grey_png(fixture.folder / "depth" / "1.001.png", 4, 3, fixture.depths[0], 8);
  message = format_error_of(association, options);
  EXPECT_TRUE(contains(message, "16-bit greyscale")) << message;
  write_file(fixture.folder / "depth" / "1.001.png", "\x89PNG\r\n\x1a\nnot really");
  message = format_error_of(association, options);
  EXPECT_TRUE(contains(message, "corrupt PNG")) << message;
  write_grey_png(fixture.folder / "depth" / "1.001.png", 2, 3, {1, 2, 3, 4, 5, 6});
  message = format_error_of(association, options);
  EXPECT_TRUE(contains(message, "the color image is 4 x 3")) << message;
  // A bad camera.
  options.depth_camera.fx = 0;
  EXPECT_THROW((void)open_scan_source(association, options), std::invalid_argument);
  // Rows, but none with both images on disk: an error naming the first missing image.
  options = {};
  options.format = "tum";
  write_file(association, "rgb/2.000.png depth/2.001.png 0 0 0 0 0 0 1\nrgb/4.000.png depth/4.001.png 0 0 0 0 0 0 1\n");
  message = format_error_of(association, options);
  EXPECT_TRUE(contains(message, "none of its 2 rows has both images on disk (the first is line 1 of")) << message;
  EXPECT_TRUE(contains(message, "2.001.png does not exist")) << message;
}

/// A PNG that is only a header (and a stub of image data): enough for a
/// reader to learn the size it declares, nothing to decode.
void write_png_header_only(const fs::path& path, std::uint32_t width, std::uint32_t height, std::uint8_t bit_depth,
                           std::uint8_t color_type) {
  Bytes png(true);
  png.text("\x89PNG\r\n\x1a\n");
  Bytes header(true);
  header.put(width).put(height).put(bit_depth).put(color_type);
  header.put(std::uint8_t{0}).put(std::uint8_t{0}).put(std::uint8_t{0});
  append_chunk(png, "IHDR", header.str());
  append_chunk(png, "IDAT", std::string("\x78\x01", 2));
  append_chunk(png, "IEND", "");
  write_file(path, png.str());
}

// The bomb: a few hundred bytes of PNG declaring 8192 x 8192 pixels,
// which would take 1.25 GiB to decode and back-project (20 bytes a pixel).
// With a 256 MiB limit it is refused from the header, before any pixel is
// allocated (an address-space cap of 64 MiB would turn any large allocation
// into "out of memory" instead of "needs").
TEST(TumReader, AFrameDeclaringHugeImagesIsRefusedBeforeDecoding) {
  const fs::path dir = test::scratch_dir();
  fs::create_directories(dir / "depth");
  fs::create_directories(dir / "rgb");
  write_png_header_only(dir / "depth" / "1.png", 8192, 8192, 16, 0);
  write_png_header_only(dir / "rgb" / "1.png", 8192, 8192, 8, 2);
  write_file(dir / "assoc.txt", "rgb/1.png depth/1.png 0 0 0 0 0 0 1\n");
  const test::MemoryLimitScope limit(std::uint64_t{256} << 20);
  ScanSourceOptions options;
  options.format = "tum";
  const auto source = open_scan_source(dir / "assoc.txt", options);
  Scan scan;
  std::string message;
  {
    const test::AddressSpaceCap cap(std::uint64_t{64} << 20);
    try {
      source->next(scan);
      ADD_FAILURE() << "the frame was read";
    } catch (const MemoryLimitError& error) {
      message = error.what();
    }
  }
  EXPECT_TRUE(contains(message, (dir / "depth" / "1.png").string() + ": a frame of 8192 x 8192 pixels (both images, "
                                "the scan's copy of them and its points) needs 1.8 GiB (1946157056 bytes), more than the memory limit of "
                                "256.0 MiB (268435456 bytes)"))
      << message;
  EXPECT_EQ(scan.points.capacity(), 0u);
}


TEST(TumRealData, TenPioneerSlam2Frames) {
  // (The macro's variable must be called `path`: it also spells std::filesystem::path.)
  UMBRA_REQUIRE_SHARED_DATA(path, "tum_fr2_pioneer_slam2/my_association.txt");
  const fs::path& association = path;
  // The rows whose images are on disk, parsed independently.
  struct Row {
    std::string depth;
    std::array<float, 3> translation;
  };
  std::vector<Row> expected;
  std::ifstream in(association);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string rgb;
    std::string depth;
    double t[3];
    fields >> rgb >> depth >> t[0] >> t[1] >> t[2];
    if (fs::exists(association.parent_path() / rgb) && fs::exists(association.parent_path() / depth)) {
      expected.push_back({depth, {static_cast<float>(t[0]), static_cast<float>(t[1]), static_cast<float>(t[2])}});
    }
  }
  ASSERT_EQ(expected.size(), 10u);

  const auto start = std::chrono::steady_clock::now();
  const auto source = open_scan_source(association.parent_path());  // the folder: format "tum"
  ASSERT_EQ(source->scan_count(), 10u);
  Scan scan;
  std::size_t frame = 0;
  std::size_t total = 0;
  while (source->next(scan)) {
    ASSERT_LT(frame, expected.size());
    std::cout << "[ info     ] " << scan.name << ": " << scan.points.size() << " points\n";
    EXPECT_TRUE(contains(scan.name, expected[frame].depth)) << scan.name;
    EXPECT_EQ(scan.origin, (Vec3f{expected[frame].translation[0], expected[frame].translation[1],
                                  expected[frame].translation[2]}));
    EXPECT_GT(scan.points.size(), 100000u);
    EXPECT_LE(scan.points.size(), 640u * 480u);
    ASSERT_EQ(scan.colors.size(), scan.points.size());
    std::size_t colored = 0;
    double farthest = 0;
    for (std::size_t i = 0; i < scan.points.size(); ++i) {
      colored += scan.colors[i] != Rgb{0, 0, 0};
      farthest = std::max(farthest, static_cast<double>((scan.points[i] - scan.origin).norm()));
    }
    EXPECT_GT(colored, scan.points.size() / 2);
    EXPECT_LT(farthest, 16.0);  // 65535 / 5000 m at the image corner
    // The pose convention and the intrinsics put the hall's floor (much of
    // every frame) level at the motion-capture frame's z = 0 (measured:
    // 5th percentile of z 0.04 to 0.08 m in every frame, median 0.09 to
    // 0.23 m); a wrong quaternion order or frame would tilt or lift it.
    std::vector<float> heights(scan.points.size());
    std::transform(scan.points.begin(), scan.points.end(), heights.begin(), [](Vec3f p) { return p.z; });
    const auto low = heights.begin() + static_cast<std::ptrdiff_t>(heights.size() / 20);
    std::nth_element(heights.begin(), low, heights.end());
    EXPECT_GT(*low, 0.0f) << scan.name;
    EXPECT_LT(*low, 0.15f) << scan.name;
    const auto middle = heights.begin() + static_cast<std::ptrdiff_t>(heights.size() / 2);
    std::nth_element(heights.begin(), middle, heights.end());
    EXPECT_LT(*middle, 0.5f) << scan.name;
    total += scan.points.size();
    ++frame;
  }
  EXPECT_EQ(frame, 10u);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "[ info     ] " << total << " points in " << seconds << " s\n";
}


}  // namespace
}  // namespace umbra
