// Internal helpers shared by the point-cloud readers (ScanGraph, xyz, PLY,
// PCD, KITTI, TUM; not installed). Their files are read through
// common/byte_input.hpp (InputFile, ByteReader, LineReader) and their
// messages quote with common/message_text.hpp; both come with this header.
// FileHandle closes a stdio file (for streams that cannot be read by offset,
// such as pipes, and for writing). The number parsers wrap std::from_chars;
// the scalar loaders decode little- or big-endian integers and IEEE floats of
// 1, 2, 4 or 8 bytes; Pose is a rigid (or affine) 3x4 transform kept in
// double and applied to float points with one rounding per coordinate.
// SingleScanSource is the ScanSource side of a reader whose file is one scan.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "byte_input.hpp"
#include "message_text.hpp"
#include "umbra/core/pose.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/io/scan_source.hpp"

namespace umbra::detail {

/// `text` with the ASCII letters in lower case.
std::string to_lower(std::string text);

/// True when the file name ends in ".bz2" (any case).
bool has_bz2_suffix(const std::filesystem::path& path);

/// A stdio file that is closed when the handle goes.
struct FileCloser {
  void operator()(std::FILE* file) const { std::fclose(file); }
};
using FileHandle = std::unique_ptr<std::FILE, FileCloser>;

/// Whitespace-separated tokens of one line.
class Tokens {
 public:
  explicit Tokens(std::string_view line) : line_(line) {}
  /// The next token; empty at the end of the line.
  std::string_view next() {
    while (position_ < line_.size() && is_space(line_[position_])) ++position_;
    const std::size_t start = position_;
    while (position_ < line_.size() && !is_space(line_[position_])) ++position_;
    return line_.substr(start, position_ - start);
  }
  /// True when only whitespace is left.
  bool at_end() {
    while (position_ < line_.size() && is_space(line_[position_])) ++position_;
    return position_ == line_.size();
  }
  /// Number of tokens left (does not consume them).
  [[nodiscard]] std::size_t count_left() const;

  static bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

 private:
  std::string_view line_;
  std::size_t position_ = 0;
};

/// Parses a whole token as a float (decimal or scientific, optional '+',
/// "nan", "inf"); values beyond float range become +-inf as strtof would.
bool parse_float(std::string_view token, float& value);
/// The same for double.
bool parse_double(std::string_view token, double& value);
/// A whole token as a non-negative decimal integer.
bool parse_unsigned(std::string_view token, std::uint64_t& value);
/// A whole token as a decimal integer with optional sign.
bool parse_signed(std::string_view token, std::int64_t& value);

/// The numeric types of the binary point formats.
enum class ScalarKind : std::uint8_t { signed_integer, unsigned_integer, floating_point };

struct ScalarType {
  ScalarKind kind = ScalarKind::floating_point;
  std::uint8_t bytes = 4;  ///< 1, 2, 4 or 8 (floating point: 4 or 8)
};

/// The raw bits of a `bytes`-byte field (1..8), little- or big-endian.
inline std::uint64_t load_bits(const unsigned char* data, std::size_t bytes, bool big_endian) {
  std::uint64_t bits = 0;
  if (big_endian) {
    for (std::size_t i = 0; i < bytes; ++i) bits = (bits << 8) | data[i];
  } else {
    for (std::size_t i = bytes; i-- > 0;) bits = (bits << 8) | data[i];
  }
  return bits;
}

/// The value of a binary scalar as double (exact for every type but 64-bit integers).
double load_scalar(const unsigned char* data, ScalarType type, bool big_endian);

/// The value of a text token of the given type, as double; false when the
/// token is not a number of that kind (integers must be integers in range).
bool parse_scalar(std::string_view token, ScalarType type, double& value);

/// The rigid (or affine) 3x4 transform of the readers: the public umbra::Pose.
using umbra::Pose;

/// Bytes the points of a scan take in a Scan: 12 a point, 15 with color.
std::uint64_t point_bytes(std::uint64_t points, bool color);

/// Throws MemoryLimitError "FILE: WHAT needs ..." unless `points` points
/// (with colors when `color`) plus `extra_bytes` fit the memory limit.
void require_point_memory(const std::string& file, const std::string& what, std::uint64_t points, bool color,
                          std::uint64_t extra_bytes = 0);

/// Makes room for more points in a scan whose count is not known in advance
/// (capacity doubled, at least 64 Ki points), after checking the new
/// capacity against the memory limit.
void grow_points(Scan& scan, bool color, const std::string& file);

/// Wraps a reader so that a std::bad_alloc from its next() comes out as a
/// MemoryLimitError naming `file` and the points read; `make()` constructs
/// the reader, with the same treatment.
std::unique_ptr<ScanSource> naming_bad_alloc(const std::filesystem::path& file,
                                             const std::function<std::unique_ptr<ScanSource>()>& make);

/// The ScanSource side of a reader whose file holds exactly one scan (xyz,
/// PLY, PCD): next() calls read_scan() once and then returns false; an
/// exception read_scan() throws is kept and thrown again by every later
/// call. progress() is 1 once the scan is read, before that bytes_consumed()
/// / input_bytes(), or 0 while the input size is 0 or unknown.
class SingleScanSource : public ScanSource {
 public:
  bool next(Scan& scan) final;
  [[nodiscard]] std::size_t scan_count() const final { return 1; }
  [[nodiscard]] double progress() const final;

 protected:
  /// Fills `scan` (reusing its buffers) with the file's one scan.
  virtual void read_scan(Scan& scan) = 0;
  /// The size of the input in bytes; 0 when unknown.
  [[nodiscard]] virtual std::uint64_t input_bytes() const = 0;
  /// How many bytes of the input read_scan() has consumed; called from other
  /// threads (for progress bars) while it runs.
  [[nodiscard]] virtual std::uint64_t bytes_consumed() const = 0;

 private:
  std::atomic<bool> done_{false};
  std::exception_ptr error_;
};

}  // namespace umbra::detail
