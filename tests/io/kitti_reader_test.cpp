// Tests of the KITTI velodyne reader (kitti_sequence.hpp).
//
// .bin scans with poses and calibration checked against the transforms
// computed here in double; errors naming the file and line.
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
// KITTI
// =================================================================================

/// Writes a velodyne .bin file (float32 x y z reflectance).
void write_bin(const fs::path& path, const std::vector<std::array<float, 4>>& points) {
  Bytes bytes;
  for (const auto& p : points) bytes.put(p[0]).put(p[1]).put(p[2]).put(p[3]);
  write_file(path, bytes.str());
}

struct KittiFixture {
  fs::path folder;
  fs::path poses;
  fs::path calibration;
  std::vector<std::vector<std::array<float, 4>>> scans;
  std::vector<Matrix34> camera_poses;
  Matrix34 velodyne_to_camera;
};

KittiFixture kitti_fixture(const fs::path& dir) {
  KittiFixture fixture;
  fixture.folder = dir / "sequences" / "04" / "velodyne";
  fs::create_directories(fixture.folder);
  fixture.scans = {{{1, 2, 3, 0.5f}, {-4, 0.25f, 10, 0}},
                   {{5, 0, 0, 1}, {0, 5, 0, 1}, {0, 0, 5, 1}},
                   {{1, 1, 1, 0}}};
  for (std::size_t i = 0; i < fixture.scans.size(); ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "%06zu.bin", i);
    write_bin(fixture.folder / name, fixture.scans[i]);
  }
  write_file(fixture.folder / "README.txt", "not a scan");
  fixture.camera_poses = {Matrix34{}, Matrix34::rotation_z(0.3, 1, -2, 0.5), Matrix34::rotation_z(-1.2, 10, 20, 30)};
  fixture.poses = dir / "poses" / "04.txt";
  fs::create_directories(fixture.poses.parent_path());
  std::string poses;
  for (const Matrix34& pose : fixture.camera_poses) poses += pose.text() + "\n";
  write_file(fixture.poses, poses);
  // Velodyne x forward, y left, z up -> camera x right, y down, z forward, plus an offset.
  fixture.velodyne_to_camera = {{0, -1, 0, -0.004, 0, 0, -1, -0.076, 1, 0, 0, -0.27}};
  fixture.calibration = dir / "sequences" / "04" / "calib.txt";
  write_file(fixture.calibration,
             "P0: 7.0e+02 0 6.0e+02 0 0 7.0e+02 1.8e+02 0 0 0 1 0\n"
             "P1: 7.0e+02 0 6.0e+02 -3.8e+02 0 7.0e+02 1.8e+02 0 0 0 1 0\n"
             "Tr: " + fixture.velodyne_to_camera.text() + "\n");
  return fixture;
}

std::array<double, 3> kitti_expected(const KittiFixture& fixture, std::size_t scan, std::size_t point, bool calibrated) {
  const auto& p = fixture.scans[scan][point];
  std::array<double, 3> sensor{p[0], p[1], p[2]};
  if (calibrated) sensor = fixture.velodyne_to_camera.apply(sensor[0], sensor[1], sensor[2]);
  return fixture.camera_poses[scan].apply(sensor[0], sensor[1], sensor[2]);
}

TEST(KittiReader, FolderWithPosesAndCalibration) {
  const KittiFixture fixture = kitti_fixture(test::scratch_dir());
  for (const bool calibrated : {true, false}) {
    ScanSourceOptions options;
    options.poses = fixture.poses;
    if (calibrated) options.calibration = fixture.calibration;
    EXPECT_EQ(scan_format_for(fixture.folder), "kitti");
    const auto source = open_scan_source(fixture.folder, options);
    ASSERT_EQ(source->scan_count(), 3u);
    EXPECT_EQ(source->progress(), 0.0);
    Scan scan;
    for (std::size_t i = 0; i < 3; ++i) {
      ASSERT_TRUE(source->next(scan));
      const std::string what = scan.name + (calibrated ? " calibrated" : " uncalibrated");
      EXPECT_TRUE(contains(scan.name, "00000" + std::to_string(i) + ".bin")) << scan.name;
      EXPECT_TRUE(contains(scan.name, "pose line " + std::to_string(i + 1))) << scan.name;
      ASSERT_EQ(scan.points.size(), fixture.scans[i].size()) << what;
      EXPECT_TRUE(scan.colors.empty());
      for (std::size_t k = 0; k < scan.points.size(); ++k) {
        expect_near_point(scan.points[k], kitti_expected(fixture, i, k, calibrated), 1e-5,
                          what + " point " + std::to_string(k));
      }
      const Matrix34 sensor_pose = fixture.camera_poses[i];
      const std::array<double, 3> origin = calibrated ? sensor_pose.apply(fixture.velodyne_to_camera.m[3],
                                                                          fixture.velodyne_to_camera.m[7],
                                                                          fixture.velodyne_to_camera.m[11])
                                                      : sensor_pose.apply(0, 0, 0);
      expect_near_point(scan.origin, origin, 1e-5, what + " origin");
      EXPECT_NEAR(source->progress(), static_cast<double>(i + 1) / 3.0, 1e-12);
    }
    EXPECT_FALSE(source->next(scan));
  }
}

TEST(KittiReader, SubsetsListsLoneFilesAndRawCalibration) {
  const fs::path dir = test::scratch_dir();
  const KittiFixture fixture = kitti_fixture(dir);
  KittiOptions options;
  options.poses = fixture.poses;
  options.calibration = fixture.calibration;
  // A lone numbered scan with poses uses the pose of its number.
  std::vector<Scan> scans = read_all(*open_kitti_velodyne(fixture.folder / "000002.bin", options));
  ASSERT_EQ(scans.size(), 1u);
  expect_near_point(scans[0].points[0], kitti_expected(fixture, 2, 0, true), 1e-5, "lone scan 2");
  // A list of files in the caller's order.
  scans = read_all(*open_kitti_scans({fixture.folder / "000001.bin", fixture.folder / "000000.bin"}, options));
  ASSERT_EQ(scans.size(), 2u);
  expect_near_point(scans[0].points[1], kitti_expected(fixture, 1, 1, true), 1e-5, "list scan 1");
  expect_near_point(scans[1].points[1], kitti_expected(fixture, 0, 1, true), 1e-5, "list scan 0");
  // Raw-data calibration (calib_velo_to_cam.txt: R and T).
  const fs::path raw = dir / "calib_velo_to_cam.txt";
  const auto& m = fixture.velodyne_to_camera.m;
  std::ostringstream text;
  text.precision(17);
  text << "calib_time: 15-Mar-2012 11:37:16\nR: " << m[0] << ' ' << m[1] << ' ' << m[2] << ' ' << m[4] << ' ' << m[5]
       << ' ' << m[6] << ' ' << m[8] << ' ' << m[9] << ' ' << m[10] << "\nT: " << m[3] << ' ' << m[7] << ' ' << m[11]
       << "\ndelta_f: 0 0\n";
  write_file(raw, text.str());
  options.calibration = raw;
  scans = read_all(*open_kitti_velodyne(fixture.folder, options));
  ASSERT_EQ(scans.size(), 3u);
  expect_near_point(scans[1].points[2], kitti_expected(fixture, 1, 2, true), 1e-5, "raw calibration");
  // One file without poses: sensor frame, the caller's origin.
  ScanSourceOptions lone;
  lone.origin = {1, 2, 3};
  scans = read_all(fixture.folder / "000001.bin", lone);
  ASSERT_EQ(scans.size(), 1u);
  EXPECT_EQ(scans[0].origin, (Vec3f{1, 2, 3}));
  EXPECT_EQ(scans[0].points[1], (Vec3f{0, 5, 0}));
}

TEST(KittiReader, ErrorsNameTheFileAndPlace) {
  const fs::path dir = test::scratch_dir();
  const KittiFixture fixture = kitti_fixture(dir);
  // A folder without poses is a usage error.
  EXPECT_THROW((void)open_scan_source(fixture.folder), std::invalid_argument);
  ScanSourceOptions options;
  options.poses = fixture.poses;
  // A .bin file whose size is not a multiple of 16.
  const fs::path odd = dir / "odd";
  fs::create_directories(odd);
  write_file(odd / "000000.bin", std::string(37, '\0'));
  std::string message = format_error_of(odd, options);
  EXPECT_TRUE(contains(message, (odd / "000000.bin").string() + ": byte 32")) << message;
  // A bad poses line.
  const fs::path bad_poses = dir / "bad_poses.txt";
  write_file(bad_poses, Matrix34{}.text() + "\n1 0 0 0 0 1 0 0 0 0 1\n");
  options.poses = bad_poses;
  message = format_error_of(fixture.folder, options);
  EXPECT_TRUE(contains(message, bad_poses.string() + ":2:")) << message;
  EXPECT_TRUE(contains(message, "12 finite numbers")) << message;
  // Too few poses for the scans.
  const fs::path short_poses = dir / "short_poses.txt";
  write_file(short_poses, Matrix34{}.text() + "\n" + Matrix34{}.text() + "\n\n");
  options.poses = short_poses;
  message = format_error_of(fixture.folder, options);
  EXPECT_TRUE(contains(message, "needs line 3")) << message;
  // A calibration without Tr.
  options.poses = fixture.poses;
  options.calibration = dir / "no_tr.txt";
  write_file(options.calibration, "P0: 1 0 0 0 0 1 0 0 0 0 1 0\n");
  message = format_error_of(fixture.folder, options);
  EXPECT_TRUE(contains(message, "Tr:")) << message;
  // Missing things are runtime errors naming them.
  options.calibration = dir / "missing_calib.txt";
  try {
    (void)open_scan_source(fixture.folder, options);
    ADD_FAILURE() << "expected runtime_error";
  } catch (const std::runtime_error& error) {
    EXPECT_TRUE(contains(error.what(), "cannot open " + options.calibration.string())) << error.what();
  }
  try {
    (void)open_scan_source(dir / "nothing.bin");
    ADD_FAILURE() << "expected runtime_error";
  } catch (const std::runtime_error& error) {
    EXPECT_TRUE(contains(error.what(), "cannot open " + (dir / "nothing.bin").string())) << error.what();
  }
}

// A pose (or calibration) whose 3x3 part is singular would collapse every
// point of its scan onto a plane, a line or the translation: refused with
// the line, as the other readers refuse a zero quaternion.
TEST(KittiReader, SingularPosesAreRefusedWithTheirLine) {
  const fs::path dir = test::scratch_dir();
  const KittiFixture fixture = kitti_fixture(dir);
  ScanSourceOptions options;
  options.poses = dir / "zero_poses.txt";
  write_file(options.poses, Matrix34{}.text() + "\n0 0 0 0 0 0 0 0 0 0 0 0\n" + Matrix34{}.text() + "\n");
  std::string message = format_error_of(fixture.folder, options);
  EXPECT_TRUE(contains(message, options.poses.string() + ":2: the 3x3 rotation part has determinant 0")) << message;
  // Flat: a rotation with its last row zeroed squashes the scan onto a plane.
  write_file(options.poses, Matrix34{}.text() + "\n" + Matrix34{}.text() + "\n1 0 0 5 0 1 0 6 0 0 0 7\n");
  message = format_error_of(fixture.folder, options);
  EXPECT_TRUE(contains(message, options.poses.string() + ":3:")) << message;
  // A scaled (affine) pose is still a pose.
  write_file(options.poses, Matrix34{}.text() + "\n" + Matrix34{}.text() + "\n0.5 0 0 5 0 0.5 0 6 0 0 0.5 7\n");
  const std::vector<Scan> scans = read_all(fixture.folder, options);
  ASSERT_EQ(scans.size(), 3u);
  EXPECT_EQ(scans[2].points[0], (Vec3f{5.5f, 6.5f, 7.5f}));
  // The calibration's transform too.
  options.poses = fixture.poses;
  options.calibration = dir / "zero_calib.txt";
  write_file(options.calibration, "Tr: 0 0 0 1 0 0 0 2 0 0 0 3\n");
  message = format_error_of(fixture.folder, options);
  EXPECT_TRUE(contains(message, options.calibration.string() + ":1:")) << message;
  EXPECT_TRUE(contains(message, "determinant 0")) << message;
}


}  // namespace
}  // namespace umbra
