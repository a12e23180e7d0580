// Test-local helpers of the point-cloud reader tests (ply_reader_test.cpp,
// pcd_reader_test.cpp, kitti_reader_test.cpp, tum_reader_test.cpp): a
// binary fixture builder, the FormatError a file gives, 3x4 transforms in
// double, LZF through liblzf (the library the PCD reader decodes with) and a
// minimal PNG encoder for greyscale test images (stored deflate blocks, no
// libpng, so that the TUM reader's libpng decoding is checked against an
// independent writer).
#pragma once

#include <gtest/gtest.h>
#include <lzf.h>

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "support/test_support.hpp"
#include "umbra/io/format_error.hpp"
#include "umbra/io/scan_source.hpp"

namespace umbra::reader_test {

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
inline std::string format_error_of(const fs::path& path, const ScanSourceOptions& options = {}) {
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

inline bool contains(const std::string& text, std::string_view part) { return text.find(part) != std::string::npos; }

using test::AddressSpaceCap;

/// Shortest text that reads back as exactly `value`.
inline std::string float_text(float value) {
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

inline void expect_near_point(Vec3f actual, const std::array<double, 3>& expected, double tolerance, const std::string& what) {
  EXPECT_NEAR(actual.x, expected[0], tolerance) << what;
  EXPECT_NEAR(actual.y, expected[1], tolerance) << what;
  EXPECT_NEAR(actual.z, expected[2], tolerance) << what;
}

// --- LZF through liblzf, the library the PCD reader decodes with ---------------------

inline std::vector<unsigned char> compress_lzf(std::span<const unsigned char> input) {
  std::vector<unsigned char> out(input.size() + input.size() / 16 + 64);  // LZF expands by at most 1/32
  const unsigned size = ::lzf_compress(input.data(), static_cast<unsigned>(input.size()), out.data(),
                                       static_cast<unsigned>(out.size()));
  EXPECT_TRUE(size > 0 || input.empty());
  out.resize(size);
  return out;
}

inline std::vector<unsigned char> bytes_of(std::string_view text) { return {text.begin(), text.end()}; }

/// What liblzf makes of `input`, given room for exactly `size` bytes; fewer
/// (or none) when it refuses the stream.
inline std::vector<unsigned char> decompress(const std::vector<unsigned char>& input, std::size_t size) {
  std::vector<unsigned char> output(size);
  if (input.empty()) return {};
  output.resize(::lzf_decompress(input.data(), static_cast<unsigned>(input.size()), output.data(),
                                 static_cast<unsigned>(output.size())));
  return output;
}

// --- a minimal PNG encoder for greyscale test images (stored deflate blocks) -----

inline std::uint32_t crc32_of(std::string_view bytes) {
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

inline void append_chunk(Bytes& png, std::string_view type, const std::string& data) {
  png.put(static_cast<std::uint32_t>(data.size()));
  const std::string typed = std::string(type) + data;
  png.text(typed);
  png.put(crc32_of(typed));
}

/// A greyscale PNG with `bit_depth` 8 or 16; `samples` row-major.
inline void write_grey_png(const fs::path& path, std::uint32_t width, std::uint32_t height,
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


}  // namespace umbra::reader_test
