// The one way umbra's file code reads bytes: every point-cloud reader and
// every map-file format (.umb, .bt, .ot) opens its file as an InputFile and
// streams it through a ByteReader (binary) or a LineReader (text). Not
// installed.
//
// InputFile opens a regular file (std::runtime_error "cannot open FILE:
// reason" otherwise) and reads at offsets with pread, retrying on EINTR; its
// size is fixed when it is opened, so a file that grows meanwhile is read as
// it was and one that shrinks reads as truncated. ByteReader streams bytes
// from an InputFile through one reusable buffer, or straight from memory,
// and hands out pointers to whole records (no per-record allocation; a file
// that ends early is reported by a null pointer or false so the caller can
// name what was expected at which byte offset). LineReader splits text into
// lines without copying them and counts them.
//
// Cost model: one pread per buffer (1 MiB by default); take(), get(), peek()
// and read() are inline and only call out of line to refill.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace umbra::detail {

/// Throws std::runtime_error("cannot open FILE: it is a directory") when
/// `path` names a folder (checked without opening it, so that an unreadable
/// folder is named as a folder, and before fopen, which opens folders).
void reject_directory(const std::filesystem::path& path);

/// A regular file opened for reading (binary), with its size fixed at open.
class InputFile {
 public:
  /// Throws std::runtime_error("cannot open FILE: reason") for a missing file,
  /// a directory or anything else that is not a readable regular file; for
  /// the last, a non-empty `format` adds why: "not a regular file (FORMAT
  /// files are read with seeks)". A non-empty `kind` names the file as
  /// "KIND 'FILE'" in these messages (map files: "cannot open map file 'a.bt': ...").
  explicit InputFile(const std::filesystem::path& path, std::string_view format = {}, std::string_view kind = {});
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;
  ~InputFile();

  [[nodiscard]] const std::string& name() const { return name_; }
  [[nodiscard]] std::uint64_t size() const { return size_; }

  /// Reads up to `capacity` bytes at `offset`; fewer only at the end of the
  /// file. Throws std::runtime_error("cannot read FILE: reason") when the
  /// system reports an error. Safe to call from several threads at once.
  std::size_t read_at(std::uint64_t offset, void* out, std::size_t capacity) const;

 private:
  std::string name_;
  std::string named_;  // name_ as the messages of this class give it
  int descriptor_ = -1;
  std::uint64_t size_ = 0;
};

/// Sequential binary reading, from a file through one buffer or from memory.
class ByteReader {
 public:
  /// Reads `file` from `offset` on; the file must outlive the reader.
  ByteReader(const InputFile& file, std::uint64_t offset, std::size_t buffer_bytes = std::size_t{1} << 20);
  /// Reads bytes in memory; they must outlive the reader.
  explicit ByteReader(std::span<const std::uint8_t> bytes);
  /// A second, independent reader over the same file or memory, from `offset` on.
  ByteReader(const ByteReader& source, std::uint64_t offset);
  ByteReader(const ByteReader&) = delete;
  ByteReader& operator=(const ByteReader&) = delete;

  /// The next `count` bytes, contiguous, valid until the next call; null when
  /// the input ends before them (the position is then unchanged).
  const unsigned char* take(std::size_t count) {
    if (end_ - begin_ < count && !fill(count)) return nullptr;
    const unsigned char* bytes = data_ + begin_;
    begin_ += count;
    return bytes;
  }
  /// The next byte, or -1 at the end.
  int get() {
    if (begin_ == end_ && !fill(1)) return -1;
    return data_[begin_++];
  }
  /// The next byte without consuming it, or -1 at the end.
  int peek() {
    if (begin_ == end_ && !fill(1)) return -1;
    return data_[begin_];
  }
  /// The next `count` bytes into `out`; false when fewer remain (the reader
  /// is then at the end of its input).
  bool read(void* out, std::size_t count) {
    const unsigned char* bytes = take(count);
    if (bytes == nullptr) {
      skip(remaining());
      return false;
    }
    std::memcpy(out, bytes, count);
    return true;
  }

  /// Skips `count` bytes; false (position unchanged) when the input is shorter.
  bool skip(std::uint64_t count);

  /// Total bytes of the input (the file's size when it was opened).
  [[nodiscard]] std::uint64_t size() const { return size_; }
  /// Offset of the next byte take() returns.
  [[nodiscard]] std::uint64_t offset() const { return buffer_end_offset_ - (end_ - begin_); }
  /// Bytes left after offset().
  [[nodiscard]] std::uint64_t remaining() const { return size_ - offset(); }

 private:
  bool fill(std::size_t count);

  const InputFile* file_ = nullptr;    // null: the bytes are in memory, all of them in data_
  const unsigned char* data_ = nullptr;  // buffer_.data(), or the bytes in memory
  std::vector<unsigned char> buffer_;
  std::size_t buffer_bytes_ = 0;         // what the buffer grows to when the file is long enough
  std::size_t begin_ = 0;                // next unread byte in data_
  std::size_t end_ = 0;                  // one past the last valid byte in data_
  std::uint64_t buffer_end_offset_ = 0;  // offset of data_[end_]
  std::uint64_t size_ = 0;
};

/// Splits a file (from some offset on) into lines.
class LineReader {
 public:
  /// Reads from `offset`; the first line returned gets number `first_line`.
  /// Lines longer than `max_line_bytes` are a FormatError ("is this a text file?").
  LineReader(const InputFile& file, std::uint64_t offset, std::uint64_t first_line = 1,
             std::size_t max_line_bytes = std::size_t{1} << 20);

  /// The next line without its '\n' and trailing '\r'; false at the end of
  /// the file. The view stays valid until the next call.
  bool next(std::string_view& line);

  /// The next line that holds more than whitespace (' ', '\t', '\r', '\v',
  /// '\f'), skipping blank ones; false when only blank lines are left.
  bool next_non_blank(std::string_view& line);

  /// Number of the line last returned (0 before the first).
  [[nodiscard]] std::uint64_t line_number() const { return line_number_; }
  /// File offset just past the line last returned (its '\n' included).
  [[nodiscard]] std::uint64_t offset() const { return buffer_end_offset_ - (end_ - begin_); }

 private:
  const InputFile& file_;
  std::size_t max_line_bytes_;
  std::vector<char> buffer_;
  std::size_t begin_ = 0;
  std::size_t end_ = 0;
  std::uint64_t buffer_end_offset_ = 0;
  std::uint64_t line_number_ = 0;
  bool at_end_ = false;
};

}  // namespace umbra::detail
