// Tests of the PCD reader (pcd_file.hpp) and of LZF as liblzf decodes it.
//
// Fixtures as ascii, binary and binary_compressed (LZF from liblzf; the
// LZF tests pin the stream format on hand-made streams); every truncation,
// bad headers and data, corrupt compressed sizes and streams.
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
// LZF
// =================================================================================

TEST(LzfDecoder, LiteralRuns) {
  EXPECT_EQ(decompress({2, 'a', 'b', 'c'}, 3), bytes_of("abc"));
  EXPECT_EQ(decompress({0, 'a', 1, 'b', 'c'}, 3), bytes_of("abc"));
  std::vector<unsigned char> input{31};
  for (int i = 0; i < 32; ++i) input.push_back(static_cast<unsigned char>('A' + i));
  EXPECT_EQ(decompress(input, 32).back(), 'A' + 31);
  EXPECT_TRUE(decompress({}, 0).empty());
}

TEST(LzfDecoder, BackReferences) {
  // "abc" then 3 bytes from 3 back: length code 1, distance code 2.
  EXPECT_EQ(decompress({2, 'a', 'b', 'c', 0x20, 2}, 6), bytes_of("abcabc"));
  // Length code 6 = 8 bytes, the longest short form.
  EXPECT_EQ(decompress({3, 'w', 'x', 'y', 'z', 0xc0, 3}, 12), bytes_of("wxyzwxyzwxyz"));
  // Extended length: code 7 + 255 + 2 = 264 bytes of one repeated byte (overlapping, distance 1).
  const std::vector<unsigned char> run = decompress({0, 'q', 0xe0, 255, 0}, 265);
  EXPECT_TRUE(std::all_of(run.begin(), run.end(), [](unsigned char c) { return c == 'q'; }));
  // Overlapping copy of a two-byte pattern: distance 2, length 7.
  EXPECT_EQ(decompress({1, 'a', 'b', 0xa0, 1}, 9), bytes_of("ababababa"));
  // The farthest reference: 8192 bytes back (distance code 8191 = 31 << 8 | 255).
  std::vector<unsigned char> far;
  std::vector<unsigned char> expected;
  for (int i = 0; i < 8192; i += 32) {
    far.push_back(31);
    for (int k = 0; k < 32; ++k) {
      far.push_back(static_cast<unsigned char>((i + k) * 7));
      expected.push_back(static_cast<unsigned char>((i + k) * 7));
    }
  }
  far.insert(far.end(), {0x3f, 0xff});  // length 3, distance 8192
  expected.insert(expected.end(), expected.begin(), expected.begin() + 3);
  EXPECT_EQ(decompress(far, expected.size()), expected);
}

TEST(LzfDecoder, RoundTripsWithTheTestCompressor) {
  std::mt19937 random(7);
  for (const std::size_t size : {1u, 2u, 3u, 31u, 32u, 33u, 300u, 5000u, 20000u}) {
    for (int kind = 0; kind < 3; ++kind) {
      std::vector<unsigned char> data(size);
      for (std::size_t i = 0; i < size; ++i) {
        data[i] = kind == 0 ? static_cast<unsigned char>(random())               // incompressible
                  : kind == 1 ? static_cast<unsigned char>(i % 5 == 0 ? 'x' : 'y')  // repetitive
                              : static_cast<unsigned char>((i / 300) + (random() % 4 == 0 ? 1 : 0));
      }
      const std::vector<unsigned char> compressed = compress_lzf(data);
      EXPECT_EQ(decompress(compressed, size), data) << size << " kind " << kind;
      if (kind == 1 && size >= 300) {
        EXPECT_LT(compressed.size(), size / 10) << size;
      }
    }
  }
}

// liblzf refuses what the hand-written decoder it replaced refused: nothing
// is read or written past either buffer, and the PCD reader turns a refusal
// (or a short output) into a FormatError at the compressed block (Pcd tests).
TEST(LzfDecoder, CorruptInputIsRefused) {
  struct Case {
    std::vector<unsigned char> input;
    std::size_t output_size;
    std::string what;
  };
  const std::vector<Case> cases{
      {{5, 'a', 'b'}, 6, "literal run past the input"},
      {{2, 'a', 'b', 'c'}, 2, "literal run past the output"},
      {{0, 'a', 0x20, 5}, 4, "reference before the start"},
      {{0, 'a', 0xe0}, 40, "extended length missing"},
      {{0, 'a', 0x20}, 4, "distance missing"},
      {{0, 'a', 0x20, 0}, 3, "reference past the output"},
      {{2, 'a', 'b', 'c'}, 5, "output shorter than expected"},
      {{0x20, 0}, 3, "reference first"},
  };
  for (const Case& c : cases) {
    EXPECT_LT(decompress(c.input, c.output_size).size(), c.output_size) << c.what;
  }
  // Random garbage never crashes or writes outside the buffer.
  std::mt19937 random(11);
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<unsigned char> input(random() % 64);
    for (unsigned char& byte : input) byte = static_cast<unsigned char>(random());
    (void)decompress(input, random() % 200);
  }
}

// =================================================================================
// PCD
// =================================================================================

/// Points of the mixed-type PCD fixture: x float, y double, z float,
/// intensity uint16, normal float x3, rgb float bits.
struct PcdPoint {
  float x;
  double y;
  float z;
  std::uint16_t intensity;
  std::array<float, 3> normal;
  std::uint32_t rgb;
};

const std::vector<PcdPoint>& pcd_points() {
  static const std::vector<PcdPoint> points{
      {1.5f, -2.25, 3.0f, 100, {0, 0, 1}, 0x00ff8040},
      {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN(),
       std::numeric_limits<float>::quiet_NaN(), 0, {0, 0, 0}, 0},
      {-0.125f, 1e-3, 250.75f, 65535, {1, 0, 0}, 0xff0a141e},  // alpha byte set, as PCL writes it
  };
  return points;
}

enum class PcdData { ascii, binary, compressed };

std::string pcd_file(PcdData data, bool colors, const std::string& viewpoint = "0 0 0 1 0 0 0") {
  std::string header = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n";
  header += colors ? "FIELDS x y z intensity normal rgb\nSIZE 4 8 4 2 4 4\nTYPE F F F U F F\nCOUNT 1 1 1 1 3 1\n"
                    : "FIELDS x y z intensity normal\nSIZE 4 8 4 2 4\nTYPE F F F U F\nCOUNT 1 1 1 1 3\n";
  header += "WIDTH 3\nHEIGHT 1\nVIEWPOINT " + viewpoint + "\nPOINTS 3\n";
  const std::vector<PcdPoint>& points = pcd_points();
  if (data == PcdData::ascii) {
    std::string body = "DATA ascii\n";
    for (std::size_t i = 0; i < points.size(); ++i) {
      const PcdPoint& p = points[i];
      std::ostringstream line;
      line.precision(17);
      line << float_text(p.x) << ' ' << p.y << ' ' << float_text(p.z) << ' ' << p.intensity << ' ' << p.normal[0]
           << ' ' << p.normal[1] << ' ' << p.normal[2];
      // Point 0 as PCL >= 1.8 writes rgb (the bits as an integer), point 2
      // as older PCL did (the float whose bits hold the color).
      if (colors) line << ' ' << (i == 2 ? float_text(std::bit_cast<float>(p.rgb)) : std::to_string(p.rgb));
      body += line.str() + "\n";
    }
    return header + body;
  }
  // Cells[field][point] as little-endian bytes.
  std::vector<std::vector<std::string>> cells(colors ? 6 : 5);
  for (const PcdPoint& p : points) {
    cells[0].push_back(Bytes().put(p.x).str());
    cells[1].push_back(Bytes().put(p.y).str());
    cells[2].push_back(Bytes().put(p.z).str());
    cells[3].push_back(Bytes().put(p.intensity).str());
    cells[4].push_back(Bytes().put(p.normal[0]).put(p.normal[1]).put(p.normal[2]).str());
    if (colors) cells[5].push_back(Bytes().put(p.rgb).str());
  }
  std::string payload;
  if (data == PcdData::binary) {
    for (std::size_t point = 0; point < points.size(); ++point) {
      for (const auto& field : cells) payload += field[point];
    }
    return header + "DATA binary\n" + payload;
  }
  for (const auto& field : cells) {
    for (const std::string& cell : field) payload += cell;
  }
  const std::vector<unsigned char> compressed = compress_lzf(bytes_of(payload));
  Bytes sizes;
  sizes.put(static_cast<std::uint32_t>(compressed.size())).put(static_cast<std::uint32_t>(payload.size()));
  return header + "DATA binary_compressed\n" + sizes.str() + std::string(compressed.begin(), compressed.end());
}

void expect_pcd_points(const Scan& scan, bool colors, const std::string& what) {
  ASSERT_EQ(scan.points.size(), 3u) << what;
  EXPECT_EQ(scan.points[0], (Vec3f{1.5f, -2.25f, 3.0f})) << what;
  EXPECT_TRUE(std::isnan(scan.points[1].x) && std::isnan(scan.points[1].y) && std::isnan(scan.points[1].z)) << what;
  EXPECT_EQ(scan.points[2], (Vec3f{-0.125f, 1e-3f, 250.75f})) << what;
  if (colors) {
    ASSERT_EQ(scan.colors.size(), 3u) << what;
    EXPECT_EQ(scan.colors[0], (Rgb{0xff, 0x80, 0x40})) << what;
    EXPECT_EQ(scan.colors[2], (Rgb{0x0a, 0x14, 0x1e})) << what;
  } else {
    EXPECT_TRUE(scan.colors.empty()) << what;
  }
}

TEST(PcdReader, AsciiBinaryAndCompressedWithAndWithoutColors) {
  const fs::path dir = test::scratch_dir();
  for (const PcdData data : {PcdData::ascii, PcdData::binary, PcdData::compressed}) {
    for (const bool colors : {true, false}) {
      const std::string what = "data " + std::to_string(static_cast<int>(data)) + (colors ? " rgb" : "");
      const fs::path path = dir / ("cloud" + std::to_string(static_cast<int>(data)) + (colors ? "c" : "") + ".pcd");
      write_file(path, pcd_file(data, colors));
      ScanSourceOptions options;
      options.origin = {7, 8, 9};
      const auto source = open_scan_source(path, options);
      EXPECT_EQ(source->scan_count(), 1u);
      Scan scan;
      ASSERT_TRUE(source->next(scan)) << what;
      expect_pcd_points(scan, colors, what);
      EXPECT_EQ(scan.origin, (Vec3f{7, 8, 9})) << what << ": an identity viewpoint leaves the origin to the caller";
      EXPECT_EQ(scan.name, path.filename().string());
      EXPECT_FALSE(source->next(scan));
      EXPECT_EQ(source->progress(), 1.0);
    }
  }
}

TEST(PcdReader, ViewpointIsTheSensorPose) {
  const fs::path dir = test::scratch_dir();
  // 90 degrees about z: (x, y, z) -> (-y, x, z), then + (10, 20, 30).
  const double half = std::sqrt(0.5);
  const std::string viewpoint = "10 20 30 " + std::to_string(half) + " 0 0 " + std::to_string(half);
  for (const PcdData data : {PcdData::ascii, PcdData::binary, PcdData::compressed}) {
    const fs::path path = dir / ("view" + std::to_string(static_cast<int>(data)) + ".pcd");
    write_file(path, pcd_file(data, true, viewpoint));
    ScanSourceOptions options;
    options.origin = {7, 8, 9};
    const std::vector<Scan> scans = read_all(path, options);
    ASSERT_EQ(scans.size(), 1u);
    const Scan& scan = scans[0];
    EXPECT_EQ(scan.origin, (Vec3f{10, 20, 30}));
    ASSERT_EQ(scan.points.size(), 3u);
    expect_near_point(scan.points[0], {10 + 2.25, 20 + 1.5, 30 + 3.0}, 1e-4, "point 0");
    EXPECT_TRUE(std::isnan(scan.points[1].x));
    expect_near_point(scan.points[2], {10 - 1e-3, 20 - 0.125, 30 + 250.75}, 1e-4, "point 2");
    EXPECT_EQ(scan.colors.size(), 3u);
  }
}

TEST(PcdReader, OlderHeadersAndOrganisedClouds) {
  const fs::path dir = test::scratch_dir();
  // No VERSION, COUNT, WIDTH/HEIGHT or VIEWPOINT; COLUMNS instead of FIELDS;
  // SIZE and TYPE default to 4-byte floats.
  const fs::path old = dir / "old.pcd";
  write_file(old, "COLUMNS x y z\nPOINTS 2\nDATA ascii\n1 2 3\n4 5 6\n");
  std::vector<Scan> scans = read_all(old);
  ASSERT_EQ(scans.size(), 1u);
  ASSERT_EQ(scans[0].points.size(), 2u);
  EXPECT_EQ(scans[0].points[1], (Vec3f{4, 5, 6}));
  // Integer coordinates, an organised 2 x 2 cloud without POINTS, rgba as U.
  const fs::path organised = dir / "organised.pcd";
  Bytes bytes;
  bytes.text("VERSION .7\nFIELDS rgba z y x\nSIZE 4 2 1 8\nTYPE U I U I\nWIDTH 2\nHEIGHT 2\nDATA binary\n");
  for (std::int16_t i = 0; i < 4; ++i) {
    bytes.put(static_cast<std::uint32_t>(0x11223300U + static_cast<std::uint32_t>(i)))
        .put(static_cast<std::int16_t>(-i))
        .put(static_cast<std::uint8_t>(i * 2))
        .put(static_cast<std::int64_t>(-1000 * i));
  }
  write_file(organised, bytes.str());
  scans = read_all(organised);
  ASSERT_EQ(scans[0].points.size(), 4u);
  EXPECT_EQ(scans[0].points[3], (Vec3f{-3000, 6, -3}));
  EXPECT_EQ(scans[0].colors[3], (Rgb{0x22, 0x33, 0x03}));
}

TEST(PcdReader, EveryTruncationOfBinaryAndCompressedFilesIsAFormatError) {
  const fs::path dir = test::scratch_dir();
  const fs::path path = dir / "cut.pcd";
  for (const PcdData data : {PcdData::binary, PcdData::compressed}) {
    const std::string full = pcd_file(data, true);
    const std::size_t data_line = full.find("DATA ");
    const std::size_t data_offset = full.find('\n', data_line) + 1;
    for (std::size_t size = 0; size < full.size(); ++size) {
      write_file(path, std::string_view(full).substr(0, size));
      const std::string message = format_error_of(path);
      EXPECT_TRUE(contains(message, path.string())) << size << ": " << message;
      if (size + 1 >= data_offset) {  // the whole DATA line is there (its newline may not be)
        EXPECT_TRUE(contains(message, path.string() + ": byte ")) << size << ": " << message;
      } else if (!contains(full.substr(0, size), "DATA binary")) {
        // Header errors name the line (a cut "DATA binary_compressed" can read as
        // "DATA binary", whose missing data is then reported by byte offset).
        EXPECT_FALSE(contains(message, ": byte ")) << size << ": " << message;
      }
    }
  }
}

TEST(PcdReader, BadHeadersAndDataAreReportedClearly) {
  const fs::path dir = test::scratch_dir();
  struct Case {
    std::string text;
    std::string words;
  };
  const std::string xyz = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";
  const std::vector<Case> cases{
      {"", "empty file"},
      {"ply\nformat ascii 1.0\n", "not a PCD header line"},
      {"FIELDS x y\nSIZE 4 4\nTYPE F F\nPOINTS 1\nDATA ascii\n1 2\n", "no 'z' field"},
      {"FIELDS x y z\nSIZE 4 4 3\nPOINTS 1\nDATA ascii\n1 2 3\n", "SIZE 3"},
      {"FIELDS x y z\nTYPE F F D\nPOINTS 1\nDATA ascii\n1 2 3\n", "TYPE 'D'"},
      {"FIELDS x y z\nSIZE 4 4 2\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n", "TYPE F with SIZE 2"},
      {"FIELDS x y z\nSIZE 4 4\nPOINTS 1\nDATA ascii\n1 2 3\n", "SIZE has 2 values"},
      {xyz + "WIDTH 2\nHEIGHT 1\nPOINTS 3\nDATA ascii\n", "differs from WIDTH x HEIGHT"},
      {xyz + "DATA ascii\n1 2 3\n", "neither POINTS nor WIDTH"},
      {xyz + "POINTS 1\nDATA zipped\n", "unknown DATA encoding"},
      {xyz + "POINTS 1\n", "without a DATA line"},
      {xyz + "VIEWPOINT 0 0 0 1 0 0\nPOINTS 1\nDATA ascii\n1 2 3\n", "VIEWPOINT expects 7 numbers"},
      {xyz + "VIEWPOINT 0 0 0 0 0 0 0\nPOINTS 1\nDATA ascii\n1 2 3\n", "quaternion"},
      {"FIELDS x y z\nCOUNT 1 2 1\nPOINTS 1\nDATA ascii\n1 2 3 4\n", "'y' has COUNT 2"},
      {"FIELDS x y z rgb\nSIZE 4 4 4 2\nTYPE F F F U\nPOINTS 1\nDATA ascii\n1 2 3 4\n", "packed 4-byte"},
      {xyz + "POINTS 2\nDATA ascii\n1.0 2.0 3.0\n1.0 2.0\n", ":8: expected 3 values per point, found 2"},
      {xyz + "POINTS 1\nDATA ascii\n1 2 zz\n", ":7: field 'z' is 'zz'"},
      {xyz + "POINTS 1\nDATA ascii\n1 2 3\n4 5 6\n", ":8: more data"},
      {xyz + "POINTS 2\nDATA ascii\n1 2 3\n\n\n\n\n\n", "truncated file: the file ends after 1 of 2"},
      {xyz + "POINTS 5000000000\nDATA ascii\n" + std::string(1000, '1'), "declares 5000000000 points"},
      {xyz + "POINTS 5000000000\nDATA binary\n" + std::string(1000, '1'), "declares 5000000000 points"},
      {xyz + "FIELDS a\nPOINTS 1\nDATA ascii\n", "second FIELDS"},
  };
  AddressSpaceCap cap(256u << 20);
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const fs::path path = dir / ("bad" + std::to_string(i) + ".pcd");
    write_file(path, cases[i].text);
    const std::string message = format_error_of(path);
    EXPECT_TRUE(contains(message, cases[i].words)) << "case " << i << ": " << message;
    EXPECT_TRUE(contains(message, path.string())) << message;
  }
}

TEST(PcdReader, CompressedSizesAndCorruptDataAreChecked) {
  const fs::path dir = test::scratch_dir();
  const std::string header = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1000\nHEIGHT 1\nPOINTS 1000\n"
                             "DATA binary_compressed\n";
  const std::string payload(12000, '\0');
  const std::vector<unsigned char> compressed = compress_lzf(bytes_of(payload));
  const auto file = [&](std::uint32_t compressed_size, std::uint32_t uncompressed_size,
                        const std::vector<unsigned char>& data) {
    Bytes bytes;
    bytes.text(header).put(compressed_size).put(uncompressed_size);
    return bytes.str() + std::string(data.begin(), data.end());
  };
  const fs::path path = dir / "sizes.pcd";
  AddressSpaceCap cap(256u << 20);

  write_file(path, file(static_cast<std::uint32_t>(compressed.size()), 12000, compressed));
  std::vector<Scan> scans = read_all(path);
  ASSERT_EQ(scans[0].points.size(), 1000u);
  EXPECT_EQ(scans[0].points[999], (Vec3f{0, 0, 0}));

  write_file(path, file(static_cast<std::uint32_t>(compressed.size()), 4000000000U, compressed));
  EXPECT_TRUE(contains(format_error_of(path), "uncompressed size is declared as 4000000000")) << format_error_of(path);
  write_file(path, file(4000000000U, 12000, compressed));
  EXPECT_TRUE(contains(format_error_of(path), "compressed data is declared as 4000000000"));
  // 12000 bytes cannot come from 100 compressed bytes.
  std::vector<unsigned char> short_data(100, 0);
  write_file(path, file(100, 12000, short_data));
  EXPECT_TRUE(contains(format_error_of(path), "more than LZF can produce")) << format_error_of(path);
  // Corrupt stream: a reference before the start, at compressed byte 0.
  std::vector<unsigned char> corrupt = compressed;
  corrupt[0] = 0x20;
  write_file(path, file(static_cast<std::uint32_t>(corrupt.size()), 12000, corrupt));
  const std::size_t data_offset = header.size() + 8;
  const std::string message = format_error_of(path);
  EXPECT_TRUE(contains(message, "byte " + std::to_string(data_offset) + ": corrupt LZF data")) << message;
}


}  // namespace
}  // namespace umbra
