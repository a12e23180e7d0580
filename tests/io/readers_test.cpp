// Tests for the PLY, PCD, KITTI and TUM RGB-D readers and LZF as liblzf decodes it.
//
// Every fixture is generated here: PLY files in all three encodings (with and
// without colours, extra vertex properties, list properties, elements before
// and after the vertices), PCD files as ascii, binary and binary_compressed
// (compressed with liblzf), KITTI .bin files with poses and calibration, and a tiny TUM
// sequence whose 16-bit depth PNGs are written by the minimal PNG encoder
// below (stored deflate blocks, no libpng). Malformed input: every
// truncation of a binary PLY and of binary / compressed PCD files, bad
// headers, hostile counts (under a lowered address-space limit, so a reader
// that allocated what a header claims would fail with bad_alloc), corrupt
// LZF streams. Real data (skipped when absent): the ten TUM fr2/pioneer_slam2
// frames.
#include <gtest/gtest.h>
#include <lzf.h>


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

namespace umbra {
namespace {

namespace fs = std::filesystem;

// --- helpers -------------------------------------------------------------------

/// Builds binary fixtures field by field in either byte order.
class Bytes {
 public:
  explicit Bytes(bool big_endian = false) : big_endian_(big_endian) {}

  Bytes& text(std::string_view characters) {
    bytes_.append(characters);
    return *this;
  }

  template <typename T>
  Bytes& put(T value) {
    static_assert(std::is_arithmetic_v<T>);
    using Bits = std::conditional_t<sizeof(T) == 1, std::uint8_t,
                                    std::conditional_t<sizeof(T) == 2, std::uint16_t,
                                                       std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>>;
    const auto bits = std::bit_cast<Bits>(value);
    for (std::size_t i = 0; i < sizeof(T); ++i) {
      const std::size_t byte = big_endian_ ? sizeof(T) - 1 - i : i;
      bytes_.push_back(static_cast<char>(static_cast<std::uint64_t>(bits) >> (8 * byte)));
    }
    return *this;
  }

  [[nodiscard]] const std::string& str() const { return bytes_; }
  [[nodiscard]] std::size_t size() const { return bytes_.size(); }

 private:
  bool big_endian_;
  std::string bytes_;
};

using test::read_all;
using test::write_file;

/// what() of the FormatError that opening and reading `path` throws, or a
/// test failure (and "") when it throws nothing or something else.
std::string format_error_of(const fs::path& path, const ScanSourceOptions& options = {}) {
  try {
    read_all(path, options);
  } catch (const FormatError& error) {
    return error.what();
  } catch (const std::exception& error) {
    ADD_FAILURE() << path << ": expected FormatError, got " << error.what();
    return "";
  }
  ADD_FAILURE() << path << ": expected FormatError, but it was read";
  return "";
}

bool contains(const std::string& text, std::string_view part) { return text.find(part) != std::string::npos; }

using test::AddressSpaceCap;

/// Shortest text that reads back as exactly `value`.
std::string float_text(float value) {
  char buffer[64];
  const auto [end, status] = std::to_chars(buffer, buffer + sizeof buffer, value);
  EXPECT_EQ(status, std::errc());
  return std::string(buffer, end);
}

/// A 3x4 transform applied in double (the tests' own arithmetic).
struct Matrix34 {
  std::array<double, 12> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  [[nodiscard]] std::array<double, 3> apply(double x, double y, double z) const {
    return {m[0] * x + m[1] * y + m[2] * z + m[3], m[4] * x + m[5] * y + m[6] * z + m[7],
            m[8] * x + m[9] * y + m[10] * z + m[11]};
  }
  [[nodiscard]] std::string text() const {
    std::ostringstream out;
    out.precision(17);
    for (std::size_t i = 0; i < 12; ++i) out << (i == 0 ? "" : " ") << m[i];
    return out.str();
  }
  /// Rotation about z by `angle` radians, then translation.
  static Matrix34 rotation_z(double angle, double tx, double ty, double tz) {
    const double c = std::cos(angle);
    const double s = std::sin(angle);
    return {{c, -s, 0, tx, s, c, 0, ty, 0, 0, 1, tz}};
  }
  /// From a unit quaternion (w, x, y, z) and a translation.
  static Matrix34 from_quaternion(double w, double x, double y, double z, double tx, double ty, double tz) {
    const double n = std::sqrt(w * w + x * x + y * y + z * z);
    w /= n;
    x /= n;
    y /= n;
    z /= n;
    return {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y), tx,  //
             2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x), ty,  //
             2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y), tz}};
  }
};

void expect_near_point(Vec3f actual, const std::array<double, 3>& expected, double tolerance, const std::string& what) {
  EXPECT_NEAR(actual.x, expected[0], tolerance) << what;
  EXPECT_NEAR(actual.y, expected[1], tolerance) << what;
  EXPECT_NEAR(actual.z, expected[2], tolerance) << what;
}

// --- LZF through liblzf, the library the PCD reader decodes with ---------------------

std::vector<unsigned char> compress_lzf(std::span<const unsigned char> input) {
  std::vector<unsigned char> out(input.size() + input.size() / 16 + 64);  // LZF expands by at most 1/32
  const unsigned size = ::lzf_compress(input.data(), static_cast<unsigned>(input.size()), out.data(),
                                       static_cast<unsigned>(out.size()));
  EXPECT_TRUE(size > 0 || input.empty());
  out.resize(size);
  return out;
}

std::vector<unsigned char> bytes_of(std::string_view text) { return {text.begin(), text.end()}; }

/// What liblzf makes of `input`, given room for exactly `size` bytes; fewer
/// (or none) when it refuses the stream.
std::vector<unsigned char> decompress(const std::vector<unsigned char>& input, std::size_t size) {
  std::vector<unsigned char> output(size);
  if (input.empty()) return {};
  output.resize(::lzf_decompress(input.data(), static_cast<unsigned>(input.size()), output.data(),
                                 static_cast<unsigned>(output.size())));
  return output;
}

// --- a minimal PNG encoder for greyscale test images (stored deflate blocks) -----

std::uint32_t crc32_of(std::string_view bytes) {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> entries{};
    for (std::uint32_t n = 0; n < 256; ++n) {
      std::uint32_t c = n;
      for (int k = 0; k < 8; ++k) c = (c & 1) != 0 ? 0xedb88320U ^ (c >> 1) : c >> 1;
      entries[n] = c;
    }
    return entries;
  }();
  std::uint32_t crc = 0xffffffffU;
  for (const char byte : bytes) crc = table[(crc ^ static_cast<unsigned char>(byte)) & 0xff] ^ (crc >> 8);
  return crc ^ 0xffffffffU;
}

void append_chunk(Bytes& png, std::string_view type, const std::string& data) {
  png.put(static_cast<std::uint32_t>(data.size()));
  const std::string typed = std::string(type) + data;
  png.text(typed);
  png.put(crc32_of(typed));
}

/// A greyscale PNG with `bit_depth` 8 or 16; `samples` row-major.
void write_grey_png(const fs::path& path, std::uint32_t width, std::uint32_t height,
                    const std::vector<std::uint16_t>& samples, int bit_depth = 16) {
  Bytes png(true);  // PNG integers are big-endian
  png.text("\x89PNG\r\n\x1a\n");
  Bytes header(true);
  header.put(width).put(height).put(static_cast<std::uint8_t>(bit_depth)).put(std::uint8_t{0});  // greyscale
  header.put(std::uint8_t{0}).put(std::uint8_t{0}).put(std::uint8_t{0});
  append_chunk(png, "IHDR", header.str());
  std::string raw;
  for (std::uint32_t row = 0; row < height; ++row) {
    raw.push_back('\0');  // filter: none
    for (std::uint32_t column = 0; column < width; ++column) {
      const std::uint16_t sample = samples[row * width + column];
      if (bit_depth == 16) raw.push_back(static_cast<char>(sample >> 8));
      raw.push_back(static_cast<char>(sample & 0xff));
    }
  }
  Bytes zlib(true);
  zlib.put(std::uint8_t{0x78}).put(std::uint8_t{0x01});
  std::size_t offset = 0;
  do {
    const std::size_t block = std::min<std::size_t>(65535, raw.size() - offset);
    const bool last = offset + block == raw.size();
    zlib.put(static_cast<std::uint8_t>(last ? 1 : 0));
    Bytes lengths(false);  // deflate lengths are little-endian
    lengths.put(static_cast<std::uint16_t>(block)).put(static_cast<std::uint16_t>(~block & 0xffff));
    zlib.text(lengths.str()).text(std::string_view(raw).substr(offset, block));
    offset += block;
  } while (offset < raw.size());
  std::uint32_t a = 1;
  std::uint32_t b = 0;
  for (const char byte : raw) {
    a = (a + static_cast<unsigned char>(byte)) % 65521;
    b = (b + a) % 65521;
  }
  zlib.put((b << 16) | a);
  append_chunk(png, "IDAT", zlib.str());
  append_chunk(png, "IEND", "");
  write_file(path, png.str());
}

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
/// with normals, colours (optional), alpha and intensity, and faces after.
std::string rich_ply(PlyFormat format, bool colours) {
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
  if (colours) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
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
      if (colours) line << int{v.rgba[0]} << ' ' << int{v.rgba[1]} << ' ' << int{v.rgba[2]} << ' ';
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
    if (colours) body.put(v.rgba[0]).put(v.rgba[1]).put(v.rgba[2]);
    body.put(v.rgba[3]).put(v.intensity);
  }
  body.put(std::uint8_t{3}).put(std::int32_t{0}).put(std::int32_t{1}).put(std::int32_t{2}).put(std::uint8_t{1});
  body.put(std::uint8_t{4}).put(std::int32_t{0}).put(std::int32_t{1}).put(std::int32_t{2}).put(std::int32_t{0});
  body.put(std::uint8_t{2});
  return header + body.str();
}

void expect_rich_ply_scan(const Scan& scan, bool colours, const std::string& what) {
  ASSERT_EQ(scan.points.size(), 3u) << what;
  for (std::size_t i = 0; i < 3; ++i) {
    const PlyVertex& v = ply_vertices()[i];
    EXPECT_EQ(scan.points[i], (Vec3f{static_cast<float>(v.x), v.y, static_cast<float>(v.z)})) << what << " vertex " << i;
  }
  if (colours) {
    ASSERT_EQ(scan.colors.size(), 3u) << what;
    for (std::size_t i = 0; i < 3; ++i) {
      const PlyVertex& v = ply_vertices()[i];
      EXPECT_EQ(scan.colors[i], (Rgb{v.rgba[0], v.rgba[1], v.rgba[2]})) << what << " vertex " << i;
    }
  } else {
    EXPECT_TRUE(scan.colors.empty()) << what;
  }
}

TEST(PlyReader, EveryEncodingWithAndWithoutColours) {
  const fs::path dir = test::scratch_dir();
  for (const PlyFormat format : {PlyFormat::ascii, PlyFormat::little, PlyFormat::big}) {
    for (const bool colours : {true, false}) {
      const std::string what = "format " + std::to_string(static_cast<int>(format)) + (colours ? " rgb" : " plain");
      const fs::path path = dir / ("cloud" + std::to_string(static_cast<int>(format)) + (colours ? "c" : "") + ".ply");
      write_file(path, rich_ply(format, colours));
      ScanSourceOptions options;
      options.origin = {0.5f, -1, 2};
      const auto source = open_scan_source(path, options);
      EXPECT_EQ(source->scan_count(), 1u);
      EXPECT_LT(source->progress(), 1.0);
      Scan scan;
      ASSERT_TRUE(source->next(scan)) << what;
      expect_rich_ply_scan(scan, colours, what);
      EXPECT_EQ(scan.origin, (Vec3f{0.5f, -1, 2})) << what;
      EXPECT_EQ(scan.name, path.filename().string());
      EXPECT_FALSE(source->next(scan));
      EXPECT_EQ(source->progress(), 1.0);
    }
  }
}

TEST(PlyReader, EveryScalarTypeListsInsideVerticesAndCrLf) {
  const fs::path dir = test::scratch_dir();
  // x as char, y as ushort, z as uint, a list between them, float colours.
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
       "some of the colour"},
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

std::string pcd_file(PcdData data, bool colours, const std::string& viewpoint = "0 0 0 1 0 0 0") {
  std::string header = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n";
  header += colours ? "FIELDS x y z intensity normal rgb\nSIZE 4 8 4 2 4 4\nTYPE F F F U F F\nCOUNT 1 1 1 1 3 1\n"
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
      // as older PCL did (the float whose bits hold the colour).
      if (colours) line << ' ' << (i == 2 ? float_text(std::bit_cast<float>(p.rgb)) : std::to_string(p.rgb));
      body += line.str() + "\n";
    }
    return header + body;
  }
  // Cells[field][point] as little-endian bytes.
  std::vector<std::vector<std::string>> cells(colours ? 6 : 5);
  for (const PcdPoint& p : points) {
    cells[0].push_back(Bytes().put(p.x).str());
    cells[1].push_back(Bytes().put(p.y).str());
    cells[2].push_back(Bytes().put(p.z).str());
    cells[3].push_back(Bytes().put(p.intensity).str());
    cells[4].push_back(Bytes().put(p.normal[0]).put(p.normal[1]).put(p.normal[2]).str());
    if (colours) cells[5].push_back(Bytes().put(p.rgb).str());
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

void expect_pcd_points(const Scan& scan, bool colours, const std::string& what) {
  ASSERT_EQ(scan.points.size(), 3u) << what;
  EXPECT_EQ(scan.points[0], (Vec3f{1.5f, -2.25f, 3.0f})) << what;
  EXPECT_TRUE(std::isnan(scan.points[1].x) && std::isnan(scan.points[1].y) && std::isnan(scan.points[1].z)) << what;
  EXPECT_EQ(scan.points[2], (Vec3f{-0.125f, 1e-3f, 250.75f})) << what;
  if (colours) {
    ASSERT_EQ(scan.colors.size(), 3u) << what;
    EXPECT_EQ(scan.colors[0], (Rgb{0xff, 0x80, 0x40})) << what;
    EXPECT_EQ(scan.colors[2], (Rgb{0x0a, 0x14, 0x1e})) << what;
  } else {
    EXPECT_TRUE(scan.colors.empty()) << what;
  }
}

TEST(PcdReader, AsciiBinaryAndCompressedWithAndWithoutColours) {
  const fs::path dir = test::scratch_dir();
  for (const PcdData data : {PcdData::ascii, PcdData::binary, PcdData::compressed}) {
    for (const bool colours : {true, false}) {
      const std::string what = "data " + std::to_string(static_cast<int>(data)) + (colours ? " rgb" : "");
      const fs::path path = dir / ("cloud" + std::to_string(static_cast<int>(data)) + (colours ? "c" : "") + ".pcd");
      write_file(path, pcd_file(data, colours));
      ScanSourceOptions options;
      options.origin = {7, 8, 9};
      const auto source = open_scan_source(path, options);
      EXPECT_EQ(source->scan_count(), 1u);
      Scan scan;
      ASSERT_TRUE(source->next(scan)) << what;
      expect_pcd_points(scan, colours, what);
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
  std::vector<Image> colours;
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
    Image colour(4, 3);
    for (int row = 0; row < 3; ++row) {
      for (int column = 0; column < 4; ++column) {
        colour.set(column, row,
                   {static_cast<std::uint8_t>(10 * column + 1), static_cast<std::uint8_t>(50 * row + 2),
                    static_cast<std::uint8_t>(100 * frame + 3)});
      }
    }
    fixture.colours.push_back(colour);
  }
  write_grey_png(fixture.folder / "depth" / "1.001.png", 4, 3, fixture.depths[0]);
  write_png(fixture.colours[0], fixture.folder / "rgb" / "1.000.png");
  write_grey_png(fixture.folder / "depth" / "3.001.png", 4, 3, fixture.depths[1]);
  write_png(fixture.colours[1], fixture.folder / "rgb" / "3.000.png");
  write_png(fixture.colours[1], fixture.folder / "rgb" / "4.000.png");  // its depth image is missing
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
        EXPECT_EQ(scan.colors[k], fixture.colours[frame].at(static_cast<int>(u), static_cast<int>(v))) << what;
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
  // An 8-bit depth image, a corrupt one, a colour image of another size.
  write_file(association, "rgb/1.000.png depth/1.001.png 1 2 3 0 0 0 1\n");
  write_grey_png(fixture.folder / "depth" / "1.001.png", 4, 3, fixture.depths[0], 8);
  message = format_error_of(association, options);
  EXPECT_TRUE(contains(message, "16-bit greyscale")) << message;
  write_file(fixture.folder / "depth" / "1.001.png", "\x89PNG\r\n\x1a\nnot really");
  message = format_error_of(association, options);
  EXPECT_TRUE(contains(message, "corrupt PNG")) << message;
  write_grey_png(fixture.folder / "depth" / "1.001.png", 2, 3, {1, 2, 3, 4, 5, 6});
  message = format_error_of(association, options);
  EXPECT_TRUE(contains(message, "the colour image is 4 x 3")) << message;
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
                           std::uint8_t colour_type) {
  Bytes png(true);
  png.text("\x89PNG\r\n\x1a\n");
  Bytes header(true);
  header.put(width).put(height).put(bit_depth).put(colour_type);
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
    std::size_t coloured = 0;
    double farthest = 0;
    for (std::size_t i = 0; i < scan.points.size(); ++i) {
      coloured += scan.colors[i] != Rgb{0, 0, 0};
      farthest = std::max(farthest, static_cast<double>((scan.points[i] - scan.origin).norm()));
    }
    EXPECT_GT(coloured, scan.points.size() / 2);
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
