// Tests for the point-cloud readers behind umbra::open_scan_source.
//
// ScanGraph: write/read round trips, hand-built files with rotations, every
// truncation of a small file, wrong count prefixes, hostile counts (checked
// with an allocation probe: this file replaces the global operator new with a
// pass-through that can record the largest request while a test watches).
// xyz: plain, colors, comments, CRLF, bad lines with their line numbers,
// bz2 compressed (made here with libbz2), truncated/corrupt bz2. Factory:
// format detection and open errors. Shared data (skipped when absent):
// OctoMap's scan.dat.bz2 and spherical_scan.graph, the 3DTK ScanGraph.
#include <gtest/gtest.h>

#include <bzlib.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <limits>
#include <new>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "support/test_support.hpp"
#include "umbra/io/format_error.hpp"
#include "umbra/io/scan_graph.hpp"
#include "umbra/io/scan_source.hpp"
#include "umbra/io/xyz_file.hpp"

// --- allocation probe -------------------------------------------------------
// AddressSanitizer brings its own operator new (with checks worth keeping), so
// the probe is compiled only without it; the tests then skip that one check.
#if defined(__SANITIZE_ADDRESS__)
#define UMBRA_ALLOCATION_PROBE 0
#else
#define UMBRA_ALLOCATION_PROBE 1
namespace {
std::atomic<bool> g_watch_allocations{false};
std::atomic<std::size_t> g_largest_allocation{0};
}  // namespace

void* operator new(std::size_t size) {
  if (g_watch_allocations.load(std::memory_order_relaxed)) {
    std::size_t largest = g_largest_allocation.load(std::memory_order_relaxed);
    while (size > largest && !g_largest_allocation.compare_exchange_weak(largest, size)) {
    }
  }
  if (void* memory = std::malloc(size == 0 ? 1 : size)) return memory;
  throw std::bad_alloc();
}
// GCC 12 warns about free() on memory from operator new once these are
// inlined into new-expressions, although this malloc/free pair matches.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void operator delete(void* memory) noexcept { std::free(memory); }
void operator delete(void* memory, std::size_t) noexcept { std::free(memory); }
#pragma GCC diagnostic pop
#endif

namespace umbra {
namespace {

namespace fs = std::filesystem;

// --- helpers ---------------------------------------------------------------

/// Builds ScanGraph bytes field by field (little-endian).
class GraphBytes {
 public:
  GraphBytes& u32(std::uint32_t value) {
    for (int i = 0; i < 4; ++i) bytes_.push_back(static_cast<char>(value >> (8 * i)));
    return *this;
  }
  GraphBytes& i32(std::int32_t value) { return u32(static_cast<std::uint32_t>(value)); }
  GraphBytes& f64(double value) {
    const auto bits = std::bit_cast<std::uint64_t>(value);
    for (int i = 0; i < 8; ++i) bytes_.push_back(static_cast<char>(bits >> (8 * i)));
    return *this;
  }
  GraphBytes& point(double x, double y, double z) { return i32(3).f64(x).f64(y).f64(z); }
  /// Translation and quaternion (w, x, y, z) with their count prefixes.
  GraphBytes& pose(Vec3d t, double w, double x, double y, double z) {
    return i32(3).f64(t.x).f64(t.y).f64(t.z).i32(4).f64(w).f64(x).f64(y).f64(z);
  }
  [[nodiscard]] const std::string& bytes() const { return bytes_; }
  [[nodiscard]] std::size_t size() const { return bytes_.size(); }

 private:
  std::string bytes_;
};

using test::read_all;
using test::write_file;

/// what() of the FormatError that reading `path` completely throws, or a
/// test failure when it throws nothing or something else.
std::string format_error_of(const fs::path& path, const ScanSourceOptions& options = {}) {
  try {
    read_all(path, options);
  } catch (const FormatError& error) {
    EXPECT_EQ(error.file(), path.string());
    return error.what();
  } catch (const std::exception& error) {
    ADD_FAILURE() << path << ": expected a FormatError, got: " << error.what();
    return {};
  }
  ADD_FAILURE() << path << ": expected a FormatError, but it was read without error";
  return {};
}

/// `text` compressed with libbz2 (linked by tests/io/CMakeLists.txt).
std::string bz2_compress(const std::string& text) {
  std::vector<char> out(text.size() + text.size() / 100 + 601);
  auto out_size = static_cast<unsigned>(out.size());
  std::string input = text;  // the libbz2 API takes a non-const pointer
  const int status =
      BZ2_bzBuffToBuffCompress(out.data(), &out_size, input.data(), static_cast<unsigned>(input.size()), 9, 0, 0);
  EXPECT_EQ(status, BZ_OK);
  return {out.data(), out_size};
}

void expect_near(Vec3f actual, Vec3f expected, float tolerance, const std::string& what) {
  EXPECT_NEAR(actual.x, expected.x, tolerance) << what;
  EXPECT_NEAR(actual.y, expected.y, tolerance) << what;
  EXPECT_NEAR(actual.z, expected.z, tolerance) << what;
}

/// A small valid graph: scan 0 with two points, scan 1 with one point, one edge.
GraphBytes small_graph() {
  GraphBytes graph;
  graph.u32(2);
  graph.u32(2).point(1, 2, 3).point(-1, 0.5, 0).pose({0, 0, 0}, 1, 0, 0, 0).u32(0);
  graph.u32(1).point(4, 5, 6).pose({1, 1, 1}, 1, 0, 0, 0).u32(1);
  graph.u32(1).u32(0).u32(1).pose({1, 1, 1}, 1, 0, 0, 0).f64(1.0);
  return graph;
}

// --- ScanGraph ---------------------------------------------------------------

TEST(ScanGraph, WriteThenReadGivesTheSameScans) {
  const fs::path dir = test::scratch_dir();
  std::mt19937 random(42);
  std::uniform_real_distribution<float> coordinate(-30.0f, 30.0f);
  std::vector<Scan> scans(3);
  scans[0].origin = {0, 0, 0};
  scans[1].origin = {10.5f, -3.25f, 1.0f};
  scans[2].origin = {1000.0f, 2000.0f, -50.0f};
  for (std::size_t s = 0; s < scans.size(); ++s) {
    for (std::size_t i = 0; i < 1000 * (s + 1); ++i) {
      scans[s].points.push_back(scans[s].origin + Vec3f{coordinate(random), coordinate(random), coordinate(random)});
    }
  }
  scans[1].points.clear();  // an empty scan is valid too
  scans[2].colors.assign(scans[2].points.size(), Rgb{1, 2, 3});  // not stored by the format

  const fs::path path = dir / "round trip.graph";
  write_scan_graph(path, scans);
  // Written under a temporary name and renamed: nothing else is left behind.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);

  auto source = open_scan_source(path);
  EXPECT_EQ(source->scan_count(), 3u);
  EXPECT_EQ(source->progress(), 0.0);
  Scan scan;
  for (std::size_t s = 0; s < scans.size(); ++s) {
    ASSERT_TRUE(source->next(scan)) << "scan " << s;
    EXPECT_EQ(scan.origin, scans[s].origin);
    EXPECT_EQ(scan.name, "round trip.graph scan " + std::to_string(s));
    EXPECT_TRUE(scan.colors.empty());
    ASSERT_EQ(scan.points.size(), scans[s].points.size());
    for (std::size_t i = 0; i < scan.points.size(); ++i) {
      const Vec3f expected = scans[s].points[i];
      const float scale = std::max({1.0f, std::abs(expected.x), std::abs(expected.y), std::abs(expected.z),
                                    std::abs(scans[s].origin.x), std::abs(scans[s].origin.y),
                                    std::abs(scans[s].origin.z)});
      expect_near(scan.points[i], expected, 2 * std::numeric_limits<float>::epsilon() * scale,
                  "scan " + std::to_string(s) + " point " + std::to_string(i));
    }
    EXPECT_GT(source->progress(), 0.0);
  }
  EXPECT_FALSE(source->next(scan));
  EXPECT_EQ(source->progress(), 1.0);
}

TEST(ScanGraph, WriterRejectsNonFiniteOriginAndLeavesNoFile) {
  const fs::path dir = test::scratch_dir();
  std::vector<Scan> scans(1);
  scans[0].origin = {0, std::numeric_limits<float>::quiet_NaN(), 0};
  EXPECT_THROW(write_scan_graph(dir / "bad.graph", scans), std::invalid_argument);
  EXPECT_TRUE(fs::is_empty(dir));
  EXPECT_THROW(write_scan_graph(dir / "missing folder" / "x.graph", {}), std::runtime_error);
}

TEST(ScanGraph, PosesRotateAndTranslatePoints) {
  const fs::path path = test::scratch_dir() / "rotated.graph";
  const double c = std::sqrt(0.5);
  GraphBytes graph;
  graph.u32(3);
  // 90 degrees about z, then translated by (1, 2, 3).
  graph.u32(4).point(1, 0, 0).point(0, 1, 0).point(0, 0, 1).point(2, -1, 0.5);
  graph.pose({1, 2, 3}, c, 0, 0, c).u32(7);
  // 180 degrees about x, given as a non-unit quaternion (the reader normalises).
  graph.u32(1).point(1, 2, 3).pose({0, 0, 0}, 0, 2.5, 0, 0).u32(8);
  // Identity: each coordinate is rounded to float, then the float translation
  // is added in float, exactly as OctoMap does.
  graph.u32(1).point(0.1, 1.1, 1.3).pose({12.34, 0.2, 5.55}, 1, 0, 0, 0).u32(2);
  graph.u32(0);
  write_file(path, graph.bytes());

  const std::vector<Scan> scans = read_all(path);
  ASSERT_EQ(scans.size(), 3u);
  EXPECT_EQ(scans[0].origin, (Vec3f{1, 2, 3}));
  ASSERT_EQ(scans[0].points.size(), 4u);
  const float tolerance = 1e-6f;
  expect_near(scans[0].points[0], {1, 3, 3}, tolerance, "x axis -> y axis");
  expect_near(scans[0].points[1], {0, 2, 3}, tolerance, "y axis -> -x axis");
  expect_near(scans[0].points[2], {1, 2, 4}, tolerance, "z axis unchanged");
  expect_near(scans[0].points[3], {2, 4, 3.5f}, tolerance, "general point");
  EXPECT_EQ(scans[0].name, "rotated.graph scan 0 (id 7)");

  ASSERT_EQ(scans[1].points.size(), 1u);
  expect_near(scans[1].points[0], {1, -2, -3}, tolerance, "180 degrees about x");

  ASSERT_EQ(scans[2].points.size(), 1u);
  const Vec3f exact{static_cast<float>(0.1) + static_cast<float>(12.34),
                    static_cast<float>(1.1) + static_cast<float>(0.2),
                    static_cast<float>(1.3) + static_cast<float>(5.55)};
  // The values are chosen so that adding in double would round differently.
  ASSERT_NE(exact.x, static_cast<float>(0.1 + 12.34));
  ASSERT_NE(exact.y, static_cast<float>(1.1 + 0.2));
  ASSERT_NE(exact.z, static_cast<float>(1.3 + 5.55));
  EXPECT_EQ(scans[2].points[0], exact);
  EXPECT_EQ(scans[2].origin, (Vec3f{12.34f, 0.2f, 5.55f}));
}

TEST(ScanGraph, EveryTruncationIsAFormatErrorWithAByteOffset) {
  const fs::path dir = test::scratch_dir();
  const std::string whole = small_graph().bytes();
  const fs::path valid = dir / "valid.graph";
  write_file(valid, whole);
  const std::vector<Scan> scans = read_all(valid);
  ASSERT_EQ(scans.size(), 2u);
  EXPECT_EQ(scans[1].points[0], (Vec3f{5, 6, 7}));

  for (std::size_t cut = 0; cut < whole.size(); ++cut) {
    const fs::path path = dir / ("cut" + std::to_string(cut) + ".graph");
    write_file(path, whole.substr(0, cut));
    const std::string message = format_error_of(path);
    EXPECT_NE(message.find(path.string() + ": byte "), std::string::npos) << "cut at " << cut << ": " << message;
    fs::remove(path);
  }
  // Trailing data after the edges is reported too.
  const fs::path longer = dir / "longer.graph";
  write_file(longer, whole + "x");
  EXPECT_NE(format_error_of(longer).find("trailing"), std::string::npos);
}

TEST(ScanGraph, WrongCountPrefixesAreReportedWhereTheyAre) {
  const fs::path dir = test::scratch_dir();
  struct Case {
    std::size_t offset;  // of the int32 to corrupt
    std::int32_t value;
    std::string expected;
  };
  // small_graph(): node count at 0, scan 0 point count at 4, its points at 8
  // and 36, its pose at 64 (quaternion count at 92).
  const std::vector<Case> cases = {
      {8, 2, "byte 8: scan 0 point 0: expected the element count 3 (int32) before its coordinates, found 2"},
      {36, -1, "byte 36: scan 0 point 1: expected the element count 3"},
      {64, 2, "byte 64: scan 0 pose: expected the translation's element count 3 (int32), found 2"},
      {92, 3, "byte 92: scan 0 pose: expected the quaternion's element count 4 (int32), found 3"},
  };
  for (const Case& c : cases) {
    std::string bytes = small_graph().bytes();
    for (int i = 0; i < 4; ++i) bytes[c.offset + i] = static_cast<char>(static_cast<std::uint32_t>(c.value) >> (8 * i));
    const fs::path path = dir / ("prefix" + std::to_string(c.offset) + ".graph");
    write_file(path, bytes);
    const std::string message = format_error_of(path);
    EXPECT_NE(message.find(c.expected), std::string::npos) << message;
  }
}

TEST(ScanGraph, InvalidPosesAreRejected) {
  const fs::path dir = test::scratch_dir();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  struct Case {
    Vec3d translation;
    double w, x, y, z;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {{nan, 0, 0}, 1, 0, 0, 0, "byte 40: scan 0 pose: translation x is"},
      {{0, 0, 1e300}, 1, 0, 0, 0, "byte 56: scan 0 pose: translation z is"},
      {{0, 0, 0}, 1, inf, 0, 0, "byte 76: scan 0 pose: quaternion x is inf"},
      {{0, 0, 0}, 0, 0, 0, 0, "byte 64: scan 0 pose: the rotation quaternion is (0, 0, 0, 0)"},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const Case& c = cases[i];
    GraphBytes graph;
    graph.u32(1).u32(1).point(1, 2, 3).pose(c.translation, c.w, c.x, c.y, c.z).u32(0).u32(0);
    const fs::path path = dir / ("pose" + std::to_string(i) + ".graph");
    write_file(path, graph.bytes());
    const std::string message = format_error_of(path);
    EXPECT_NE(message.find(c.expected), std::string::npos) << message;
  }
}

TEST(ScanGraph, HugeCountsAreRejectedWithoutAllocating) {
  const fs::path dir = test::scratch_dir();
  GraphBytes huge_points;
  huge_points.u32(1).u32(4'000'000'000u).point(1, 2, 3).pose({0, 0, 0}, 1, 0, 0, 0).u32(0).u32(0);
  GraphBytes huge_scans;
  huge_scans.u32(4'000'000'000u).u32(0).pose({0, 0, 0}, 1, 0, 0, 0).u32(0).u32(0);
  const fs::path points_path = dir / "huge points.graph";
  const fs::path scans_path = dir / "huge scans.graph";
  write_file(points_path, huge_points.bytes());
  write_file(scans_path, huge_scans.bytes());

#if UMBRA_ALLOCATION_PROBE
  g_largest_allocation = 0;
  g_watch_allocations = true;
#endif
  const std::string points_message = format_error_of(points_path);
  const std::string scans_message = format_error_of(scans_path);
#if UMBRA_ALLOCATION_PROBE
  g_watch_allocations = false;
  EXPECT_LT(g_largest_allocation.load(), std::size_t{1} << 20) << "largest single allocation in bytes";
#endif
  EXPECT_NE(points_message.find("byte 4: scan 0 declares 4000000000 points"), std::string::npos) << points_message;
  EXPECT_NE(scans_message.find("byte 0: the file declares 4000000000 scans"), std::string::npos) << scans_message;
}

TEST(ScanGraph, CompressedGraphIsRejectedWithAHint) {
  const fs::path dir = test::scratch_dir();
  const fs::path path = dir / "small.graph.bz2";
  write_file(path, bz2_compress(small_graph().bytes()));
  EXPECT_NE(format_error_of(path).find("decompress"), std::string::npos);
  // Also when the name does not say so.
  const fs::path renamed = dir / "small.graph";
  fs::rename(path, renamed);
  EXPECT_NE(format_error_of(renamed).find("bz2-compressed"), std::string::npos);
}

TEST(ScanGraph, Real3dtkRegisteredGraph) {
  UMBRA_REQUIRE_SHARED_DATA(path, "3dtk/3dtk_registered.graph");
  auto source = open_scan_source(path);
  ASSERT_EQ(source->scan_count(), 3u);
  // The README's 81,360 points per scan are before the invalid ranges
  // (< 0.48 m, >= 32.76 m) were dropped; these are the counts in the file.
  const std::vector<std::size_t> expected_counts = {77690, 77910, 77584};
  const std::vector<Vec3f> expected_origins = {
      {0.0f, -0.0f, 0.0f}, {1.56796f, 0.036331f, -0.0908315f}, {3.37786f, 0.0805008f, -0.156539f}};
  Scan scan;
  for (std::size_t s = 0; s < 3; ++s) {
    ASSERT_TRUE(source->next(scan));
    std::cout << "[ info     ] " << scan.name << ": " << scan.points.size() << " points, origin ("
              << scan.origin.x << ", " << scan.origin.y << ", " << scan.origin.z << ")\n";
    EXPECT_EQ(scan.points.size(), expected_counts[s]);
    EXPECT_EQ(scan.origin, expected_origins[s]);
    // Rotations are identity, so every range (|point - origin|) stays inside
    // the scanner's valid interval.
    float closest = std::numeric_limits<float>::max();
    float farthest = 0.0f;
    for (const Vec3f& point : scan.points) {
      const float range = (point - scan.origin).norm();
      closest = std::min(closest, range);
      farthest = std::max(farthest, range);
    }
    EXPECT_GT(closest, 0.479f);
    EXPECT_LT(closest, 0.5f);
    EXPECT_LT(farthest, 32.761f);
    EXPECT_GT(farthest, 32.7f);
  }
  EXPECT_FALSE(source->next(scan));
  EXPECT_EQ(source->progress(), 1.0);
}

TEST(ScanGraph, RealOctomapSphericalScan) {
  UMBRA_REQUIRE_SHARED_DATA(path, "octomap/spherical_scan.graph");
  const std::vector<Scan> scans = read_all(path);
  ASSERT_EQ(scans.size(), 1u);
  std::cout << "[ info     ] spherical_scan.graph: " << scans[0].points.size() << " points\n";
  EXPECT_EQ(scans[0].points.size(), 10201u);
  EXPECT_EQ(scans[0].origin, (Vec3f{1.0f, 0.0f, -0.5f}));
  for (const Vec3f& point : scans[0].points) ASSERT_TRUE(point.is_finite());
}

// --- xyz ---------------------------------------------------------------------

TEST(Xyz, PlainPointsWithTheGivenOrigin) {
  const fs::path path = test::scratch_dir() / "points.xyz";
  write_file(path, "1 2 3\n-4.5 5e-1 +6\n  7\t8   9  \n");
  ScanSourceOptions options;
  options.origin = {0.5f, 0.25f, 2.0f};
  auto source = open_scan_source(path, options);
  EXPECT_EQ(source->scan_count(), 1u);
  EXPECT_EQ(source->progress(), 0.0);
  Scan scan;
  scan.colors.push_back({});  // stale contents are replaced
  ASSERT_TRUE(source->next(scan));
  EXPECT_EQ(scan.origin, options.origin);
  EXPECT_EQ(scan.name, "points.xyz");
  EXPECT_TRUE(scan.colors.empty());
  const std::vector<Vec3f> expected = {{1, 2, 3}, {-4.5f, 0.5f, 6}, {7, 8, 9}};
  EXPECT_EQ(scan.points, expected);
  EXPECT_EQ(source->progress(), 1.0);
  EXPECT_FALSE(source->next(scan));
}

TEST(Xyz, NumbersAreRoundedToFloatLikeStrtof) {
  const fs::path path = test::scratch_dir() / "precise.dat";
  write_file(path, "0.1 -4.82982 1e-50\n3.4028236e38 1e39 -1e400000\n");
  // 1e400000 does not even fit in a double.
  EXPECT_NE(format_error_of(path).find(":2: '-1e400000' is not a number"), std::string::npos);
  write_file(path, "0.1 -4.82982 1e-50\n3.4028234e38 1e39 -1e39\n");
  const std::vector<Scan> scans = read_all(path);
  ASSERT_EQ(scans.size(), 1u);
  ASSERT_EQ(scans[0].points.size(), 2u);
  EXPECT_EQ(scans[0].points[0], (Vec3f{std::strtof("0.1", nullptr), std::strtof("-4.82982", nullptr), 0.0f}));
  EXPECT_EQ(scans[0].points[1].x, std::numeric_limits<float>::max());
  EXPECT_EQ(scans[0].points[1].y, std::numeric_limits<float>::infinity());
  EXPECT_EQ(scans[0].points[1].z, -std::numeric_limits<float>::infinity());
}

TEST(Xyz, ColorsAreRead) {
  const fs::path path = test::scratch_dir() / "colored.txt";
  write_file(path, "1 2 3 255 0 17\n4 5 6 0 128 255\n");
  const std::vector<Scan> scans = read_all(path);
  ASSERT_EQ(scans.size(), 1u);
  ASSERT_EQ(scans[0].points.size(), 2u);
  const std::vector<Rgb> expected = {{255, 0, 17}, {0, 128, 255}};
  EXPECT_EQ(scans[0].colors, expected);
  EXPECT_EQ(scans[0].points[1], (Vec3f{4, 5, 6}));
}

TEST(Xyz, CommentsAndBlankLinesAreSkipped) {
  const fs::path path = test::scratch_dir() / "commented.xyz";
  write_file(path, "# header\n\n   \n1 2 3\n  # indented comment 1 2 3\n\t\n4 5 6");  // no final newline
  const std::vector<Scan> scans = read_all(path);
  ASSERT_EQ(scans.size(), 1u);
  const std::vector<Vec3f> expected = {{1, 2, 3}, {4, 5, 6}};
  EXPECT_EQ(scans[0].points, expected);
}

TEST(Xyz, CrlfLineEndings) {
  const fs::path path = test::scratch_dir() / "windows.xyz";
  write_file(path, "# made on Windows\r\n1 2 3\r\n\r\n4 5 6\r\n");
  const std::vector<Scan> scans = read_all(path);
  ASSERT_EQ(scans.size(), 1u);
  const std::vector<Vec3f> expected = {{1, 2, 3}, {4, 5, 6}};
  EXPECT_EQ(scans[0].points, expected);
  // ... and a bad CRLF line is quoted without its carriage return.
  write_file(path, "1 2 3\r\n1 2\r\n");
  EXPECT_NE(format_error_of(path).find(":2: expected 3 numbers (x y z) or 6 (x y z r g b), found 2: '1 2'"),
            std::string::npos);
}

TEST(Xyz, NanAndInfinityArePassedThrough) {
  const fs::path path = test::scratch_dir() / "gaps.xyz";
  write_file(path, "nan 1 2\n1 inf -inf\n1 2 3\n");
  const std::vector<Scan> scans = read_all(path);
  ASSERT_EQ(scans.size(), 1u);
  ASSERT_EQ(scans[0].points.size(), 3u);
  EXPECT_TRUE(std::isnan(scans[0].points[0].x));
  EXPECT_EQ(scans[0].points[1].y, std::numeric_limits<float>::infinity());
  EXPECT_EQ(scans[0].points[1].z, -std::numeric_limits<float>::infinity());
  EXPECT_EQ(scans[0].points[2], (Vec3f{1, 2, 3}));
}

TEST(Xyz, BadLinesAreReportedWithLineNumberAndText) {
  const fs::path dir = test::scratch_dir();
  struct Case {
    std::string contents;
    std::string expected;
  };
  const std::string long_line = "1 2 " + std::string(200, '7');
  const std::vector<Case> cases = {
      {"1 2 3\n# fine\n\n1.0 abc 2\n", ":4: 'abc' is not a number, in '1.0 abc 2'"},
      {"1 2 3\n1 2\n", ":2: expected 3 numbers (x y z) or 6 (x y z r g b), found 2: '1 2'"},
      {"1 2 3 4\n", ":1: expected 3 numbers (x y z) or 6 (x y z r g b), found 4: '1 2 3 4'"},
      {"1 2 3 4 5 6 7 8\n", ":1: expected 3 numbers (x y z) or 6 (x y z r g b), found 8"},
      {"1 2 3x\n", ":1: '3x' is not a number"},
      {"1,2,3\n", ":1: expected 3 numbers (x y z) or 6 (x y z r g b), found 1: '1,2,3'"},
      {"1 2 3 # comment\n", ":1: expected 3 numbers (x y z) or 6 (x y z r g b), found 5"},
      {"1 2 3 # a comment\n", ":1: color value '#' is not an integer 0..255"},
      {"1 2 3 255 0 256\n", ":1: color value '256' is not an integer 0..255, in '1 2 3 255 0 256'"},
      {"1 2 3 255 0 0.5\n", ":1: color value '0.5' is not an integer 0..255"},
      {"\n\n" + long_line + " 4\n", ":3: expected 3 numbers (x y z) or 6 (x y z r g b), found 4: '" +
                                        long_line.substr(0, 80) + "...'"},
      {"1 2 \x01\x02\n", ":1: '\?\?' is not a number"},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const fs::path path = dir / ("bad" + std::to_string(i) + ".xyz");
    write_file(path, cases[i].contents);
    const std::string message = format_error_of(path);
    EXPECT_NE(message.find(path.string() + cases[i].expected), std::string::npos)
        << "case " << i << ": " << message;
  }
}

TEST(Xyz, MixingColoredAndPlainLinesIsRejected) {
  const fs::path dir = test::scratch_dir();
  write_file(dir / "a.xyz", "# x y z r g b\n1 2 3 4 5 6\n1 2 3\n");
  EXPECT_NE(format_error_of(dir / "a.xyz").find(":3: this line has no color (x y z) but line 2 has one"),
            std::string::npos);
  write_file(dir / "b.xyz", "1 2 3\n\n1 2 3 4 5 6\n");
  EXPECT_NE(format_error_of(dir / "b.xyz").find(":3: this line has a color (x y z r g b) but line 1 has none"),
            std::string::npos);
}

TEST(Xyz, ErrorsAreRepeatedOnTheNextCall) {
  const fs::path path = test::scratch_dir() / "bad.xyz";
  write_file(path, "1 2\n");
  auto source = open_scan_source(path);
  Scan scan;
  EXPECT_THROW(source->next(scan), FormatError);
  EXPECT_THROW(source->next(scan), FormatError);
}

/// Many lines (more than the reader's buffers), every float written exactly.
std::string many_points_text(std::vector<Vec3f>& points) {
  std::mt19937 random(7);
  std::uniform_real_distribution<float> coordinate(-100.0f, 100.0f);
  std::string text = "# generated\n";
  char line[128];
  for (int i = 0; i < 60000; ++i) {
    const Vec3f point{coordinate(random), coordinate(random), coordinate(random)};
    points.push_back(point);
    std::snprintf(line, sizeof line, "%.9g %.9g %.9g\n", static_cast<double>(point.x),
                  static_cast<double>(point.y), static_cast<double>(point.z));
    text += line;
  }
  return text;
}

TEST(Xyz, Bz2ReadsTheSameAsPlain) {
  const fs::path dir = test::scratch_dir();
  std::vector<Vec3f> points;
  const std::string text = many_points_text(points);
  ASSERT_GT(text.size(), 1u << 20);  // crosses buffer boundaries
  write_file(dir / "many.dat", text);
  write_file(dir / "many.dat.BZ2", bz2_compress(text));

  const std::vector<Scan> plain = read_all(dir / "many.dat");
  auto source = open_scan_source(dir / "many.dat.BZ2");
  EXPECT_EQ(source->progress(), 0.0);
  const std::vector<Scan> compressed = read_all(*source);
  EXPECT_EQ(source->progress(), 1.0);
  ASSERT_EQ(plain.size(), 1u);
  ASSERT_EQ(compressed.size(), 1u);
  EXPECT_EQ(plain[0].points, points);
  EXPECT_EQ(compressed[0].points, points);

  // Concatenated bz2 streams (as pbzip2 writes) are one file.
  const std::string half_one = text.substr(0, text.size() / 2);
  write_file(dir / "two streams.xyz.bz2", bz2_compress(half_one) + bz2_compress(text.substr(half_one.size())));
  const std::vector<Scan> two_streams = read_all(dir / "two streams.xyz.bz2");
  ASSERT_EQ(two_streams.size(), 1u);
  EXPECT_EQ(two_streams[0].points, points);
}

TEST(Xyz, TruncatedOrCorruptBz2IsAFormatError) {
  const fs::path dir = test::scratch_dir();
  std::vector<Vec3f> points;
  const std::string compressed = bz2_compress(many_points_text(points));
  const fs::path path = dir / "broken.xyz.bz2";
  for (const std::size_t cut : {std::size_t{0}, std::size_t{3}, std::size_t{20}, compressed.size() / 2,
                                compressed.size() - 1}) {
    write_file(path, compressed.substr(0, cut));
    const std::string message = format_error_of(path);
    EXPECT_NE(message.find(cut == 0 ? "empty file" : "truncated bz2 data"), std::string::npos)
        << "cut at " << cut << ": " << message;
  }
  std::string corrupt = compressed;
  corrupt[corrupt.size() / 3] = static_cast<char>(corrupt[corrupt.size() / 3] ^ 0x55);
  write_file(path, corrupt);
  EXPECT_NE(format_error_of(path).find(path.string()), std::string::npos);

  write_file(path, "1 2 3\n");
  EXPECT_NE(format_error_of(path).find("not bz2 data"), std::string::npos);
  write_file(path, compressed + "garbage");
  EXPECT_NE(format_error_of(path).find("unexpected non-bz2 data"), std::string::npos);
}

// --- the factory -----------------------------------------------------------------

TEST(ScanSource, FormatComesFromTheExtension) {
  EXPECT_EQ(scan_format_for("run.graph"), "graph");
  EXPECT_EQ(scan_format_for("dir.with.dots/RUN.Graph"), "graph");
  EXPECT_EQ(scan_format_for("run.graph.bz2"), "graph");
  EXPECT_EQ(scan_format_for("a.xyz"), "xyz");
  EXPECT_EQ(scan_format_for("scan.dat.bz2"), "xyz");
  EXPECT_EQ(scan_format_for("SCAN.TXT.BZ2"), "xyz");
  EXPECT_EQ(scan_format_for("points.txt"), "xyz");
  // An explicit known format wins.
  EXPECT_EQ(scan_format_for("points.graph", "xyz"), "xyz");
  EXPECT_EQ(scan_format_for("points.pts", "graph"), "graph");
  for (const char* name : {"cloud.las", "scan.bz2", "noextension", "graph", "x.graph.gz"}) {
    try {
      (void)scan_format_for(name);
      ADD_FAILURE() << name << ": expected std::invalid_argument";
    } catch (const std::invalid_argument& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find(name), std::string::npos) << message;
      for (const char* extension : {".graph", ".xyz", ".dat", ".txt", ".bz2"}) {
        EXPECT_NE(message.find(extension), std::string::npos) << message;
      }
    }
  }
  EXPECT_THROW((void)scan_format_for("a.xyz", "las"), std::invalid_argument);
}

TEST(ScanSource, MissingFilesAreRuntimeErrorsNamingTheFile) {
  const fs::path dir = test::scratch_dir();
  fs::create_directory(dir / "folder.graph");
  fs::create_directory(dir / "folder.xyz");
  fs::create_directory(dir / "folder.graph.bz2");
  for (const fs::path& path : {dir / "missing.graph", dir / "missing.xyz", dir / "missing.dat.bz2",
                               dir / "missing.graph.bz2", dir / "folder.graph", dir / "folder.xyz",
                               dir / "folder.graph.bz2"}) {
    try {
      (void)open_scan_source(path);
      ADD_FAILURE() << path << ": expected std::runtime_error";
    } catch (const FormatError& error) {
      ADD_FAILURE() << path << ": expected a plain std::runtime_error, got FormatError " << error.what();
    } catch (const std::runtime_error& error) {
      EXPECT_EQ(std::string(error.what()).rfind("cannot open " + path.string() + ": ", 0), 0u) << error.what();
    }
  }
}

TEST(ScanSource, ExplicitFormatAndOptions) {
  const fs::path dir = test::scratch_dir();
  write_file(dir / "cloud.pts", "1 2 3\n");
  ScanSourceOptions options;
  options.format = "xyz";
  options.origin = {9, 8, 7};
  const std::vector<Scan> scans = read_all(dir / "cloud.pts", options);
  ASSERT_EQ(scans.size(), 1u);
  EXPECT_EQ(scans[0].origin, (Vec3f{9, 8, 7}));

  // A ScanGraph carries its own poses: the option's origin does not apply.
  write_file(dir / "graph.bin", small_graph().bytes());
  options.format = "graph";
  const std::vector<Scan> graph_scans = read_all(dir / "graph.bin", options);
  ASSERT_EQ(graph_scans.size(), 2u);
  EXPECT_EQ(graph_scans[1].origin, (Vec3f{1, 1, 1}));

  // The wrong explicit format gives a FormatError, not garbage.
  options.format = "xyz";
  EXPECT_FALSE(format_error_of(dir / "graph.bin", options).empty());
}

// A reader from outside umbra_io (as ros/ adds .bag): its extension becomes
// known, open_scan_source hands it the path and the options, and the
// built-in formats are untouched.
TEST(ScanSource, RegisteredFormatsAreOpenedByTheirReader) {
  EXPECT_THROW((void)scan_format_for("cloud.regtest"), std::invalid_argument);
  std::filesystem::path opened;
  register_scan_format("regtest", {".RegTest"}, [&](const fs::path& path, const ScanSourceOptions& options) {
    opened = path;
    ScanSourceOptions xyz = options;
    xyz.format = "xyz";
    return open_scan_source(path, xyz);
  });
  EXPECT_EQ(scan_format_for("cloud.regtest"), "regtest");
  EXPECT_EQ(scan_format_for("cloud.xyz", "regtest"), "regtest");
  EXPECT_EQ(scan_format_for("cloud.xyz"), "xyz");
  const fs::path dir = test::scratch_dir();
  write_file(dir / "cloud.regtest", "1 2 3\n");
  ScanSourceOptions options;
  options.origin = {4, 5, 6};
  const std::vector<Scan> scans = read_all(dir / "cloud.regtest", options);
  EXPECT_EQ(opened, dir / "cloud.regtest");
  ASSERT_EQ(scans.size(), 1u);
  EXPECT_EQ(scans[0].origin, (Vec3f{4, 5, 6}));
  EXPECT_EQ(scans[0].points, (std::vector<Vec3f>{{1, 2, 3}}));
  EXPECT_THROW(register_scan_format("RegTest", {}, [](const fs::path&, const ScanSourceOptions&) {
                 return std::unique_ptr<ScanSource>();
               }), std::invalid_argument);
  EXPECT_THROW(register_scan_format("other", {}, nullptr), std::invalid_argument);
}

TEST(ScanSource, RealOctomapScanDat) {
  UMBRA_REQUIRE_SHARED_DATA(path, "octomap/scan.dat.bz2");
  auto source = open_scan_source(path);
  Scan scan;
  ASSERT_TRUE(source->next(scan));
  EXPECT_EQ(scan.points.size(), 88206u);
  EXPECT_EQ(scan.origin, (Vec3f{0, 0, 0}));
  EXPECT_TRUE(scan.colors.empty());
  EXPECT_EQ(scan.points.front(), (Vec3f{-0.0434742f, -4.82982f, 0.499645f}));
  EXPECT_EQ(scan.points.back(), (Vec3f{0.130896f, 3.58f, 0.432014f}));
  EXPECT_FALSE(source->next(scan));
  EXPECT_EQ(source->progress(), 1.0);
  // (Its reading speed is measured by the benchmarks, never timed in a test.)
}

}  // namespace
}  // namespace umbra
