// Internal helpers shared by the point-cloud readers (ScanGraph, xyz, PLY,
// PCD, KITTI, TUM; not installed).
//
// InputFile opens a regular file (std::runtime_error "cannot open FILE:
// reason" otherwise) and reads at offsets with pread; ByteReader streams its
// bytes through one reusable buffer and hands out pointers to whole records
// (no per-record allocation, a file that ends early is reported by a null
// pointer so the caller can name what was expected at which byte offset);
// LineReader splits text into lines without copying them and counts them.
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

#include "umbra/core/pose.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/io/scan_source.hpp"

namespace umbra::io_detail {

/// The system's text for an errno value, e.g. "No such file or directory".
std::string errno_text(int error);

/// What quote() shows of bytes 0x80 to 0xff (parts of UTF-8 characters).
enum class HighBytes : std::uint8_t { replace, keep };

/// `text` quoted for an error message, at most 80 characters: control bytes
/// and DEL shown as '?', and so are bytes from 0x80 on unless `high_bytes` is keep.
std::string quote(std::string_view text, HighBytes high_bytes = HighBytes::replace);

/// `text` with the ASCII letters in lower case.
std::string to_lower(std::string text);

/// True when the file name ends in ".bz2" (any case).
bool has_bz2_suffix(const std::filesystem::path& path);

/// Throws std::runtime_error("cannot open FILE: it is a directory") when
/// `path` names a folder (checked without opening it, so that an unreadable
/// folder is named as a folder, and before fopen, which opens folders).
void reject_directory(const std::filesystem::path& path);

/// A stdio file that is closed when the handle goes.
struct FileCloser {
  void operator()(std::FILE* file) const { std::fclose(file); }
};
using FileHandle = std::unique_ptr<std::FILE, FileCloser>;

/// A regular file opened for reading (binary), with its size fixed at open.
class InputFile {
 public:
  /// Throws std::runtime_error("cannot open FILE: reason") for a missing file,
  /// a directory or anything else that is not a readable regular file; for
  /// the last, a non-empty `format` adds why: "not a regular file (FORMAT
  /// files are read with seeks)".
  explicit InputFile(const std::filesystem::path& path, std::string_view format = {});
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;
  ~InputFile();

  [[nodiscard]] const std::string& name() const { return name_; }
  [[nodiscard]] std::uint64_t size() const { return size_; }

  /// Reads up to `capacity` bytes at `offset`; fewer only at the end of the
  /// file. Throws std::runtime_error when the system reports an error.
  std::size_t read_at(std::uint64_t offset, void* out, std::size_t capacity);

 private:
  std::string name_;
  int descriptor_ = -1;
  std::uint64_t size_ = 0;
};

/// Sequential binary reading through one buffer.
class ByteReader {
 public:
  ByteReader(InputFile& file, std::uint64_t offset, std::size_t buffer_bytes = std::size_t{1} << 20);

  /// The next `count` bytes, contiguous, valid until the next call; null when
  /// the file ends before them (the position is then unchanged).
  const unsigned char* take(std::size_t count) {
    if (end_ - begin_ < count && !fill(count)) return nullptr;
    const unsigned char* bytes = buffer_.data() + begin_;
    begin_ += count;
    return bytes;
  }

  /// Skips `count` bytes; false (position unchanged) when the file is shorter.
  bool skip(std::uint64_t count);

  /// File offset of the next byte take() returns.
  [[nodiscard]] std::uint64_t offset() const { return buffer_end_offset_ - (end_ - begin_); }
  /// Bytes left in the file after offset().
  [[nodiscard]] std::uint64_t remaining() const { return file_.size() - offset(); }

 private:
  bool fill(std::size_t count);

  InputFile& file_;
  std::vector<unsigned char> buffer_;
  std::size_t begin_ = 0;                // next unread byte in buffer_
  std::size_t end_ = 0;                  // one past the last valid byte in buffer_
  std::uint64_t buffer_end_offset_ = 0;  // file offset of buffer_[end_]
};

/// Splits a file (from some offset on) into lines.
class LineReader {
 public:
  /// Reads from `offset`; the first line returned gets number `first_line`.
  /// Lines longer than `max_line_bytes` are a FormatError ("is this a text file?").
  LineReader(InputFile& file, std::uint64_t offset, std::uint64_t first_line = 1,
             std::size_t max_line_bytes = std::size_t{1} << 20);

  /// The next line without its '\n' and trailing '\r'; false at the end of
  /// the file. The view stays valid until the next call.
  bool next(std::string_view& line);

  /// The next line that holds more than whitespace (Tokens::is_space), skipping
  /// blank ones; false when only blank lines are left.
  bool next_non_blank(std::string_view& line);

  /// Number of the line last returned (0 before the first).
  [[nodiscard]] std::uint64_t line_number() const { return line_number_; }
  /// File offset just past the line last returned (its '\n' included).
  [[nodiscard]] std::uint64_t offset() const { return buffer_end_offset_ - (end_ - begin_); }

 private:
  InputFile& file_;
  std::size_t max_line_bytes_;
  std::vector<char> buffer_;
  std::size_t begin_ = 0;
  std::size_t end_ = 0;
  std::uint64_t buffer_end_offset_ = 0;
  std::uint64_t line_number_ = 0;
  bool at_end_ = false;
};

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

/// Bytes the points of a scan take in a Scan: 12 a point, 15 with colour.
std::uint64_t point_bytes(std::uint64_t points, bool colour);

/// Throws MemoryLimitError "FILE: WHAT needs ..." unless `points` points
/// (with colours when `colour`) plus `extra_bytes` fit the memory limit.
void require_point_memory(const std::string& file, const std::string& what, std::uint64_t points, bool colour,
                          std::uint64_t extra_bytes = 0);

/// Makes room for more points in a scan whose count is not known in advance
/// (capacity doubled, at least 64 Ki points), after checking the new
/// capacity against the memory limit.
void grow_points(Scan& scan, bool colour, const std::string& file);

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

}  // namespace umbra::io_detail
