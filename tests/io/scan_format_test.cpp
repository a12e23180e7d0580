// Tests of how open_scan_source and scan_format_for tell the formats apart.
//
// By name, extension and folder contents (scan_source.hpp).
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
// open_scan_source / scan_format_for
// =================================================================================

TEST(ScanSourceFormats, NamesExtensionsAndFolders) {
  const fs::path dir = test::scratch_dir();
  EXPECT_EQ(scan_format_for("cloud.ply"), "ply");
  EXPECT_EQ(scan_format_for("CLOUD.PLY"), "ply");
  EXPECT_EQ(scan_format_for("cloud.pcd"), "pcd");
  EXPECT_EQ(scan_format_for("000000.bin"), "kitti");
  EXPECT_EQ(scan_format_for("a.txt"), "xyz");
  EXPECT_EQ(scan_format_for("my_association.txt", "tum"), "tum");
  for (const char* format : {"ply", "pcd", "kitti", "tum", "graph", "xyz", "PCD"}) {
    EXPECT_EQ(scan_format_for("x.unknown", format), [&] {
      std::string lower = format;
      std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
      return lower;
    }()) << format;
  }
  try {
    (void)scan_format_for("x.las");
    ADD_FAILURE() << "expected invalid_argument";
  } catch (const std::invalid_argument& error) {
    for (const char* part : {".ply", ".pcd", ".bin", "depth/", "tum", "kitti"}) {
      EXPECT_TRUE(contains(error.what(), part)) << error.what();
    }
  }
  fs::create_directories(dir / "empty");
  EXPECT_THROW((void)scan_format_for(dir / "empty"), std::invalid_argument);
  fs::create_directories(dir / "seq" / "depth");
  fs::create_directories(dir / "seq" / "rgb");
  EXPECT_EQ(scan_format_for(dir / "seq"), "tum");
  fs::create_directories(dir / "velo");
  write_file(dir / "velo" / "x.BIN", "");
  EXPECT_EQ(scan_format_for(dir / "velo"), "kitti");
  // Missing inputs are runtime errors naming them.
  for (const char* name : {"missing.ply", "missing.pcd", "missing.bin"}) {
    try {
      (void)open_scan_source(dir / name);
      ADD_FAILURE() << name;
    } catch (const FormatError& error) {
      ADD_FAILURE() << name << ": got FormatError " << error.what();
    } catch (const std::runtime_error& error) {
      EXPECT_EQ(std::string(error.what()).rfind("cannot open " + (dir / name).string() + ": ", 0), 0u) << error.what();
    }
  }
  ScanSourceOptions tum;
  tum.format = "tum";
  EXPECT_THROW((void)open_scan_source(dir / "missing_association.txt", tum), std::runtime_error);
}


}  // namespace
}  // namespace umbra
