// Tests of the PLY reader (ply_file.hpp).
//
// Fixtures in all three encodings (with and without colors, extra vertex
// properties, list properties, elements before and after the vertices);
// every truncation of a binary file, bad headers, hostile counts under a
// lowered address-space limit.
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
// PLY
// =================================================================================

struct PlyVertex {
  double x;
  float y;
  std::int16_t z;
  std::array<float, 3> normal;
  std::array<std::uint8_t, 4> rgba;
  float intensity;
};

const std::vector<PlyVertex>& ply_vertices() {
  static const std::vector<PlyVertex> vertices{
      {1.25, -2.5f, 3, {0, 0, 1}, {255, 0, 10, 200}, 0.5f},
      {0.5, 1e-3f, -7, {0, 1, 0}, {1, 2, 3, 255}, 0.25f},
      {-100.125, 42.0f, 0, {1, 0, 0}, {90, 128, 254, 0}, 100.0f},
  };
  return vertices;
}

enum class PlyFormat { ascii, little, big };

/// A PLY file with an element before the vertices (with a list), vertices
/// with normals, colors (optional), alpha and intensity, and faces after.
std::string rich_ply(PlyFormat format, bool colors) {
  std::string header = "ply\n";
  header += format == PlyFormat::ascii ? "format ascii 1.0\n"
                                       : (format == PlyFormat::little ? "format binary_little_endian 1.0\n"
                                                                      : "format binary_big_endian 1.0\n");
  header +=
      "comment written by umbra's reader tests\n"
      "obj_info anything\n"
      "element camera 1\n"
      "property list uchar float parameters\n"
      "property uchar id\n"
      "element vertex 3\n"
      "property double x\n"
      "property float y\n"
      "property short z\n"
      "property float nx\n"
      "property float ny\n"
      "property float nz\n";
  if (colors) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  header +=
      "property uchar alpha\n"
      "property float intensity\n"
      "element face 2\n"
      "property list uchar int vertex_indices\n"
      "property uchar flags\n"
      "end_header\n";
  if (format == PlyFormat::ascii) {
    std::string body = "2 1.5 2.5 7\n";
    for (const PlyVertex& v : ply_vertices()) {
      std::ostringstream line;
      line.precision(17);
      line << v.x << ' ' << float_text(v.y) << ' ' << v.z << ' ' << v.normal[0] << ' ' << v.normal[1] << ' '
           << v.normal[2] << ' ';
      if (colors) line << int{v.rgba[0]} << ' ' << int{v.rgba[1]} << ' ' << int{v.rgba[2]} << ' ';
      line << int{v.rgba[3]} << ' ' << float_text(v.intensity) << '\n';
      body += line.str();
    }
    body += "3 0 1 2 1\n4 0 1 2 0 2\n";
    return header + body;
  }
  Bytes body(format == PlyFormat::big);
  body.put(std::uint8_t{2}).put(1.5f).put(2.5f).put(std::uint8_t{7});
  for (const PlyVertex& v : ply_vertices()) {
    body.put(v.x).put(v.y).put(v.z).put(v.normal[0]).put(v.normal[1]).put(v.normal[2]);
    if (colors) body.put(v.rgba[0]).put(v.rgba[1]).put(v.rgba[2]);
    body.put(v.rgba[3]).put(v.intensity);
  }
  body.put(std::uint8_t{3}).put(std::int32_t{0}).put(std::int32_t{1}).put(std::int32_t{2}).put(std::uint8_t{1});
  body.put(std::uint8_t{4}).put(std::int32_t{0}).put(std::int32_t{1}).put(std::int32_t{2}).put(std::int32_t{0});
  body.put(std::uint8_t{2});
  return header + body.str();
}

void expect_rich_ply_scan(const Scan& scan, bool colors, const std::string& what) {
  ASSERT_EQ(scan.points.size(), 3u) << what;
  for (std::size_t i = 0; i < 3; ++i) {
    const PlyVertex& v = ply_vertices()[i];
    EXPECT_EQ(scan.points[i], (Vec3f{static_cast<float>(v.x), v.y, static_cast<float>(v.z)})) << what << " vertex " << i;
  }
  if (colors) {
    ASSERT_EQ(scan.colors.size(), 3u) << what;
    for (std::size_t i = 0; i < 3; ++i) {
      const PlyVertex& v = ply_vertices()[i];
      EXPECT_EQ(scan.colors[i], (Rgb{v.rgba[0], v.rgba[1], v.rgba[2]})) << what << " vertex " << i;
    }
  } else {
    EXPECT_TRUE(scan.colors.empty()) << what;
  }
}

TEST(PlyReader, EveryEncodingWithAndWithoutColors) {
  const fs::path dir = test::scratch_dir();
  for (const PlyFormat format : {PlyFormat::ascii, PlyFormat::little, PlyFormat::big}) {
    for (const bool colors : {true, false}) {
      const std::string what = "format " + std::to_string(static_cast<int>(format)) + (colors ? " rgb" : " plain");
      const fs::path path = dir / ("cloud" + std::to_string(static_cast<int>(format)) + (colors ? "c" : "") + ".ply");
      write_file(path, rich_ply(format, colors));
      ScanSourceOptions options;
      options.origin = {0.5f, -1, 2};
      const auto source = open_scan_source(path, options);
      EXPECT_EQ(source->scan_count(), 1u);
      EXPECT_LT(source->progress(), 1.0);
      Scan scan;
      ASSERT_TRUE(source->next(scan)) << what;
      expect_rich_ply_scan(scan, colors, what);
      EXPECT_EQ(scan.origin, (Vec3f{0.5f, -1, 2})) << what;
      EXPECT_EQ(scan.name, path.filename().string());
      EXPECT_FALSE(source->next(scan));
      EXPECT_EQ(source->progress(), 1.0);
    }
  }
}

TEST(PlyReader, EveryScalarTypeListsInsideVerticesAndCrLf) {
  const fs::path dir = test::scratch_dir();
  // x as char, y as ushort, z as uint, a list between them, float colors.
  for (const bool big : {false, true}) {
    Bytes bytes(big);
    bytes.text(std::string("ply\r\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
               " 1.0\r\n"
               "element vertex 2\r\n"
               "property int8 x\r\n"
               "property list uint16 uint8 tags\r\n"
               "property uint16 y\r\n"
               "property uint32 z\r\n"
               "property float32 diffuse_red\r\n"
               "property float64 diffuse_green\r\n"
               "property ushort diffuse_blue\r\n"
               "end_header\r\n");
    bytes.put(std::int8_t{-5}).put(std::uint16_t{2}).put(std::uint8_t{9}).put(std::uint8_t{9});
    bytes.put(std::uint16_t{65535}).put(std::uint32_t{123456}).put(1.0f).put(0.5).put(std::uint16_t{65535});
    bytes.put(std::int8_t{127}).put(std::uint16_t{0});
    bytes.put(std::uint16_t{0}).put(std::uint32_t{0}).put(-0.5f).put(2.0).put(std::uint16_t{257});
    const fs::path path = dir / (big ? "types_be.ply" : "types_le.ply");
    write_file(path, bytes.str());
    const std::vector<Scan> scans = read_all(path);
    ASSERT_EQ(scans.size(), 1u);
    ASSERT_EQ(scans[0].points.size(), 2u);
    EXPECT_EQ(scans[0].points[0], (Vec3f{-5, 65535, 123456}));
    EXPECT_EQ(scans[0].points[1], (Vec3f{127, 0, 0}));
    ASSERT_EQ(scans[0].colors.size(), 2u);
    EXPECT_EQ(scans[0].colors[0], (Rgb{255, 128, 255}));  // 1.0, 0.5 (rounded up), 65535
    EXPECT_EQ(scans[0].colors[1], (Rgb{0, 255, 1}));      // clamped, clamped, 257 / 257
  }
}

TEST(PlyReader, AsciiErrorsNameTheLine) {
  const fs::path dir = test::scratch_dir();
  const std::string header = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                             "property float z\nelement face 1\nproperty list uchar int idx\nend_header\n";
  struct Case {
    std::string body;
    std::string line;  // ":N:" expected
    std::string words;
  };
  const std::vector<Case> cases{
      {"1 2 3\n1 2 x\n3 0 1 1\n", ":11:", "'x'"},
      {"1 2 3\n1 2\n3 0 1 1\n", ":11:", "too few values"},
      {"1 2 3\n1 2 3 4\n3 0 1 1\n", ":11:", "more values"},
      {"1 2 3\n1 2 3\n3 0 1\n", ":12:", "line ends early"},
      {"1 2 3\n1 2 3\n-1\n", ":12:", "list 'idx'"},
      {"1 2 3\n1 2 3\n", ":7:", "element 'face' declares 1"},  // caught by the size check at open
      {"1 2 3\n1 2 3\n\n\n\n\n", ":16:", "truncated file"},   // blank lines get past that check
      {"1 2 3\n1 2 3\n0\nextra\n", ":13:", "unexpected data"},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const fs::path path = dir / ("bad" + std::to_string(i) + ".ply");
    write_file(path, header + cases[i].body);
    const std::string message = format_error_of(path);
    EXPECT_TRUE(contains(message, path.string() + cases[i].line)) << message;
    EXPECT_TRUE(contains(message, cases[i].words)) << message;
  }
  // Blank lines between instances are fine, and so is a missing final newline.
  const fs::path good = dir / "good.ply";
  write_file(good, header + "1 2 3\n\n4 5 6\n0");
  const std::vector<Scan> scans = read_all(good);
  ASSERT_EQ(scans.size(), 1u);
  ASSERT_EQ(scans[0].points.size(), 2u);
  EXPECT_EQ(scans[0].points[1], (Vec3f{4, 5, 6}));
}

TEST(PlyReader, BadHeadersAreReportedClearly) {
  const fs::path dir = test::scratch_dir();
  const std::string vertex = "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n";
  struct Case {
    std::string text;
    std::string words;
  };
  const std::vector<Case> cases{
      {"", "not a PLY file"},
      {"PLY\nformat ascii 1.0\n", "not a PLY file"},
      {"ply\nformat binary_middle_endian 1.0\n" + vertex + "end_header\n", "unknown PLY format"},
      {"ply\nformat ascii 2.0\n" + vertex + "end_header\n", "1.0"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n", "no 'z'"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float16 x\nend_header\n", "unknown property type"},
      {"ply\nformat ascii 1.0\nproperty float x\n" + vertex + "end_header\n", "before any 'element'"},
      {"ply\nformat ascii 1.0\nelement vertex -3\n", "non-negative integer count"},
      {"ply\nformat ascii 1.0\n" + vertex, "without an 'end_header'"},
      {"ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int idx\nend_header\n3 0 1 2\n", "no 'vertex'"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
       "property uchar red\nend_header\n0 0 0 1\n",
       "some of the color"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty list float int x\nend_header\n", "not an integer type"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty list uchar float x\nproperty float y\nproperty float z\n"
       "end_header\n1 0 0 0\n",
       "is a list"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float x\nproperty float y\n"
       "property float z\nend_header\n",
       "two 'x'"},
      {"ply\nformat ascii 1.0\nwhatever\n" + vertex + "end_header\n", "unknown PLY header line"},
      {"ply\n" + vertex + "end_header\n", "before the 'format'"},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const fs::path path = dir / ("header" + std::to_string(i) + ".ply");
    write_file(path, cases[i].text);
    const std::string message = format_error_of(path);
    EXPECT_TRUE(contains(message, cases[i].words)) << "case " << i << ": " << message;
    EXPECT_TRUE(contains(message, path.string())) << message;
  }
}

TEST(PlyReader, HugeCountsFailBeforeAllocating) {
  const fs::path dir = test::scratch_dir();
  const std::string properties = "property float x\nproperty float y\nproperty float z\n";
  const std::string filler(1000, '0');
  AddressSpaceCap cap(256u << 20);
  for (const std::string format : {"binary_little_endian", "binary_big_endian", "ascii"}) {
    // 86 x 12 bytes just exceed the binary data; 501 lines of at least 6 bytes the ascii data.
    for (const std::string count : {"4000000000", "18446744073709551615", format == "ascii" ? "501" : "86"}) {
      const fs::path path = dir / ("huge_" + format + "_" + count + ".ply");
      write_file(path, "ply\nformat " + format + " 1.0\nelement vertex " + count + "\n" + properties +
                           "end_header\n" + filler);
      try {
        (void)open_ply_file(path);
        ADD_FAILURE() << path << ": expected FormatError";
      } catch (const FormatError& error) {
        const std::string message = error.what();
        EXPECT_TRUE(contains(message, "declares " + count)) << message;
        EXPECT_TRUE(contains(message, format == "ascii" ? path.string() + ":3:" : path.string() + ": byte ")) << message;
      }
    }
  }
  // A face count too large for the file after the vertices.
  const fs::path faces = dir / "faces.ply";
  Bytes bytes;
  bytes.text("ply\nformat binary_little_endian 1.0\nelement vertex 1\n" + properties +
             "element face 3000000000\nproperty list uchar int idx\nend_header\n");
  bytes.put(1.0f).put(2.0f).put(3.0f).put(std::uint8_t{0});
  write_file(faces, bytes.str());
  const std::string message = format_error_of(faces);
  EXPECT_TRUE(contains(message, "element 'face'")) << message;
}

TEST(PlyReader, EveryTruncationOfABinaryFileIsAFormatErrorWithItsPosition) {
  const fs::path dir = test::scratch_dir();
  const std::string full = rich_ply(PlyFormat::little, true);
  const std::size_t data_offset = full.find("end_header\n") + 11;
  const fs::path path = dir / "cut.ply";
  for (std::size_t size = 0; size < full.size(); ++size) {
    write_file(path, std::string_view(full).substr(0, size));
    const std::string message = format_error_of(path);
    EXPECT_TRUE(contains(message, path.string())) << size << ": " << message;
    if (size + 1 >= data_offset) {  // the whole end_header line is there (its newline may not be)
      EXPECT_TRUE(contains(message, path.string() + ": byte ")) << size << ": " << message;
    } else {
      EXPECT_TRUE(contains(message, path.string() + ":") && !contains(message, "byte ")) << size << ": " << message;
    }
  }
  // Negative list lengths in binary data.
  Bytes bytes;
  bytes.text("ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
             "property float z\nelement face 1\nproperty list char int idx\nend_header\n");
  const std::size_t count_offset = bytes.size() + 12;
  bytes.put(1.0f).put(2.0f).put(3.0f).put(std::int8_t{-1});
  write_file(path, bytes.str());
  const std::string message = format_error_of(path);
  EXPECT_TRUE(contains(message, "byte " + std::to_string(count_offset))) << message;
  EXPECT_TRUE(contains(message, "negative")) << message;
}

TEST(PlyReader, CompressedAndMissingFiles) {
  const fs::path dir = test::scratch_dir();
  write_file(dir / "cloud.ply.bz2", "BZh9");
  EXPECT_TRUE(contains(format_error_of(dir / "cloud.ply.bz2"), "decompress"));
  try {
    (void)open_scan_source(dir / "missing.ply");
    ADD_FAILURE() << "expected std::runtime_error";
  } catch (const FormatError& error) {
    ADD_FAILURE() << "expected a plain runtime_error, got " << error.what();
  } catch (const std::runtime_error& error) {
    EXPECT_EQ(std::string(error.what()).rfind("cannot open " + (dir / "missing.ply").string() + ": ", 0), 0u)
        << error.what();
  }
}


}  // namespace
}  // namespace umbra
