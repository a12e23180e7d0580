// Reader for ASCII point files: "x y z" or "x y z r g b" per line, plain or bz2.
//
// The file is read in large chunks (decompressed on the fly with libbz2's
// streaming API when the name ends in .bz2) and split into lines without
// copying them; numbers are parsed with std::from_chars, so OctoMap's 88,206
// point scan.dat.bz2 loads in a small fraction of a second. Every problem is
// reported with the file name, and for text problems the line number and the
// offending text. A file is one scan whose sensor origin the caller gives.
// The file is read as a stream (stdio), not by offset, so pipes work too.
#include <algorithm>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <bzlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include "reader_support.hpp"
#include "umbra/io/format_error.hpp"
#include "umbra/io/scan_source.hpp"
#include "umbra/io/xyz_file.hpp"

namespace umbra {
namespace {

using detail::errno_text;
using detail::FileHandle;
using detail::Tokens;

constexpr std::size_t kRawChunkBytes = 256 * 1024;   // compressed input per read
constexpr std::size_t kTextChunkBytes = 256 * 1024;  // initial text buffer
constexpr std::size_t kMaxLineBytes = 1024 * 1024;   // longer lines mean "not a text file"

/// The bytes of a file, decompressed when it is bz2. read() returns 0 only at
/// the real end of the data; truncated or corrupt bz2 data throws FormatError.
class TextInput {
 public:
  TextInput(FileHandle file, bool compressed, std::string file_name)
      : file_(std::move(file)), compressed_(compressed), file_name_(std::move(file_name)) {
    if (compressed_) {
      raw_.resize(kRawChunkBytes);
      start_stream();
    }
  }
  TextInput(const TextInput&) = delete;
  TextInput& operator=(const TextInput&) = delete;
  ~TextInput() {
    if (stream_active_) BZ2_bzDecompressEnd(&stream_);
  }

  /// Fills up to `capacity` bytes of `out`; returns how many (0: end of data).
  std::size_t read(char* out, std::size_t capacity) {
    return compressed_ ? read_compressed(out, capacity) : read_raw(out, capacity);
  }

  /// Bytes of the file (compressed bytes for bz2) read so far.
  [[nodiscard]] std::uint64_t raw_bytes_read() const { return raw_bytes_read_.load(std::memory_order_relaxed); }

 private:
  std::size_t read_raw(char* out, std::size_t capacity) {
    const std::size_t got = std::fread(out, 1, capacity, file_.get());
    if (got == 0 && std::ferror(file_.get())) {
      throw std::runtime_error("cannot read " + file_name_ + ": " + errno_text(errno));
    }
    raw_bytes_read_.fetch_add(got, std::memory_order_relaxed);
    return got;
  }

  void start_stream() {
    stream_ = bz_stream{};
    const int status = BZ2_bzDecompressInit(&stream_, 0, 0);
    if (status != BZ_OK) {
      throw std::runtime_error("cannot decompress " + file_name_ + ": libbz2 initialisation failed (" +
                               std::to_string(status) + ")");
    }
    stream_active_ = true;
  }

  std::string where() const {
    return "after " + std::to_string(raw_bytes_read() - stream_.avail_in) + " compressed bytes";
  }

  std::size_t read_compressed(char* out, std::size_t capacity) {
    while (true) {
      if (stream_.avail_in == 0 && !raw_end_) {
        const std::size_t got = read_raw(raw_.data(), raw_.size());
        if (got == 0) raw_end_ = true;
        stream_.next_in = raw_.data();
        stream_.avail_in = static_cast<unsigned>(got);
      }
      if (stream_ended_) {
        if (stream_.avail_in == 0) return 0;  // end of the file after a complete stream
        // More data after a complete stream: bzip2 allows concatenated streams.
        BZ2_bzDecompressEnd(&stream_);
        stream_active_ = false;
        char* const next_in = stream_.next_in;
        const unsigned avail_in = stream_.avail_in;
        start_stream();
        stream_.next_in = next_in;
        stream_.avail_in = avail_in;
        stream_ended_ = false;
        ++completed_streams_;
      }
      if (stream_.avail_in == 0) {
        throw FormatError(file_name_, raw_bytes_read() == 0
                                          ? "empty file, not bz2 data"
                                          : "truncated bz2 data: the compressed stream ends " +
                                                where() + " without its end-of-stream marker");
      }
      const unsigned avail_in_before = stream_.avail_in;
      stream_.next_out = out;
      stream_.avail_out = static_cast<unsigned>(std::min<std::size_t>(capacity, 1U << 30));
      const unsigned avail_out_before = stream_.avail_out;
      const int status = BZ2_bzDecompress(&stream_);
      const std::size_t produced = avail_out_before - stream_.avail_out;
      if (status == BZ_STREAM_END) {
        stream_ended_ = true;
      } else if (status == BZ_DATA_ERROR_MAGIC) {
        throw FormatError(file_name_, completed_streams_ == 0
                                          ? "not bz2 data (the file does not start with the bz2 signature \"BZh\")"
                                          : "unexpected non-bz2 data " + where() +
                                                ", after the end of the compressed stream");
      } else if (status == BZ_DATA_ERROR) {
        throw FormatError(file_name_, "corrupt bz2 data (integrity check failed) " + where());
      } else if (status == BZ_MEM_ERROR) {
        throw std::bad_alloc();  // named with the file by the reader's wrapper
      } else if (status != BZ_OK) {
        throw std::runtime_error("cannot decompress " + file_name_ + ": libbz2 error " + std::to_string(status));
      } else if (produced == 0 && stream_.avail_in == avail_in_before) {
        throw std::runtime_error("cannot decompress " + file_name_ + ": libbz2 made no progress " + where());
      }
      if (produced > 0) return produced;
    }
  }

  FileHandle file_;
  bool compressed_ = false;
  std::string file_name_;
  std::vector<char> raw_;
  bz_stream stream_{};
  bool stream_active_ = false;
  bool stream_ended_ = false;
  bool raw_end_ = false;
  int completed_streams_ = 0;
  std::atomic<std::uint64_t> raw_bytes_read_{0};
};

/// `text` quoted for an error message; unlike the binary formats' readers,
/// this one shows bytes from 0x80 on as they are (UTF-8 text stays legible).
std::string quote(std::string_view text) {
  return detail::quote(text, {.unprintable = detail::Unprintable::question_mark_keep_utf8});
}

/// Parses a whole token as a float: decimal or scientific, optional sign
/// (including '+'), "nan" and "inf". Values beyond float range become +-inf
/// or are flushed towards 0, as strtof would; beyond double range is an error
/// (where detail::parse_float, used by PLY and PCD, gives +-inf or 0).
bool parse_coordinate(std::string_view token, float& value) {
  const char* first = token.data();
  const char* const last = first + token.size();
  if (token.size() > 1 && *first == '+' && first[1] != '+' && first[1] != '-') ++first;
  const auto [end, status] = std::from_chars(first, last, value);
  if (end != last) return false;
  if (status == std::errc()) return true;
  if (status != std::errc::result_out_of_range) return false;
  double wide = 0.0;
  const auto [wide_end, wide_status] = std::from_chars(first, last, wide);
  if (wide_end != last || wide_status != std::errc()) return false;
  value = static_cast<float>(wide);
  return true;
}

/// A whole token as an integer 0..255, digits only (no sign).
bool parse_color_channel(std::string_view token, std::uint8_t& value) {
  unsigned channel = 0;
  const auto [end, status] = std::from_chars(token.data(), token.data() + token.size(), channel);
  if (status != std::errc() || end != token.data() + token.size() || channel > 255) return false;
  value = static_cast<std::uint8_t>(channel);
  return true;
}

class XyzReader final : public detail::SingleScanSource {
 public:
  XyzReader(const std::filesystem::path& path, Vec3f origin)
      : file_name_(path.string()), display_name_(path.filename().string()), origin_(origin) {
    detail::reject_directory(path);
    FileHandle file(std::fopen(path.c_str(), "rb"));
    if (!file) throw std::runtime_error("cannot open " + file_name_ + ": " + errno_text(errno));
    struct stat info {};
    if (::fstat(::fileno(file.get()), &info) == 0 && S_ISREG(info.st_mode)) {
      file_size_ = static_cast<std::uint64_t>(info.st_size);
    }
    const bool compressed = detail::has_bz2_suffix(path);
    if (compressed) check_bz2_signature(file.get());
    input_ = std::make_unique<TextInput>(std::move(file), compressed, file_name_);
  }

  [[nodiscard]] std::vector<Vec3f> origins() const override { return {origin_}; }

 private:
  /// A .bz2 name on a regular file that is not bz2 data is refused at open
  /// (so a build checks it before inserting anything), not after reading;
  /// for a pipe the decompressor says so when reading.
  void check_bz2_signature(std::FILE* file) const {
    struct stat info {};
    if (::fstat(::fileno(file), &info) != 0 || !S_ISREG(info.st_mode)) return;
    char signature[3] = {};
    const ssize_t got = ::pread(::fileno(file), signature, sizeof signature, 0);  // leaves the stream where it is
    if (got == 0) throw FormatError(file_name_, "empty file, not bz2 data");
    if (got == static_cast<ssize_t>(sizeof signature) && std::memcmp(signature, "BZh", 3) != 0) {
      throw FormatError(file_name_, "not bz2 data (the file does not start with the bz2 signature \"BZh\")");
    }
  }

  [[nodiscard]] std::uint64_t input_bytes() const override { return file_size_; }
  // Capped: a file that grows while being read still ends at 1.
  [[nodiscard]] std::uint64_t bytes_consumed() const override {
    return std::min(input_->raw_bytes_read(), file_size_);
  }

  void read_scan(Scan& scan) override {
    scan.origin = origin_;
    scan.points.clear();
    scan.colors.clear();
    scan.stamp.reset();  // this format carries no times
    scan.name = display_name_;

    std::vector<char> text(kTextChunkBytes);
    std::size_t begin = 0;  // first unparsed byte
    std::size_t end = 0;    // one past the last valid byte
    std::uint64_t line_number = 0;
    bool at_end = false;
    while (!at_end) {
      // Keep the unfinished line, make room, read more.
      if (begin > 0) {
        std::memmove(text.data(), text.data() + begin, end - begin);
        end -= begin;
        begin = 0;
      }
      if (end == text.size()) {
        if (text.size() >= kMaxLineBytes) {
          throw FormatError::at_line(file_name_, line_number + 1,
                                     "line longer than " + std::to_string(kMaxLineBytes) +
                                         " bytes; is this really a text point file? It starts " +
                                         quote({text.data(), end}));
        }
        text.resize(text.size() * 2);
      }
      const std::size_t got = input_->read(text.data() + end, text.size() - end);
      at_end = got == 0;
      end += got;

      while (begin < end) {
        const auto* newline = static_cast<const char*>(std::memchr(text.data() + begin, '\n', end - begin));
        if (newline == nullptr) {
          if (!at_end) break;
          newline = text.data() + end;  // last line without a line break
        }
        const auto line_end = static_cast<std::size_t>(newline - text.data());
        parse_line({text.data() + begin, line_end - begin}, ++line_number, scan);
        begin = std::min(line_end + 1, end);
      }
    }
  }

  void parse_line(std::string_view line, std::uint64_t line_number, Scan& scan) {
    while (!line.empty() && line.back() == '\r') line.remove_suffix(1);

    std::string_view tokens[7];
    std::size_t token_count = 0;
    Tokens splitter(line);
    for (std::string_view token = splitter.next(); !token.empty(); token = splitter.next()) {
      if (token_count == 0 && token.front() == '#') return;  // comment
      if (token_count < 7) tokens[token_count] = token;
      ++token_count;
    }
    if (token_count == 0) return;  // blank line

    if (token_count != 3 && token_count != 6) {
      throw FormatError::at_line(file_name_, line_number,
                                 "expected 3 numbers (x y z) or 6 (x y z r g b), found " +
                                     std::to_string(token_count) + ": " + quote(line));
    }
    const bool has_color = token_count == 6;
    if (!color_line_kind_) {
      color_line_kind_ = has_color;
      first_point_line_ = line_number;
    } else if (*color_line_kind_ != has_color) {
      throw FormatError::at_line(
          file_name_, line_number,
          std::string(has_color ? "this line has a color (x y z r g b) but line "
                                 : "this line has no color (x y z) but line ") +
              std::to_string(first_point_line_) + (has_color ? " has none" : " has one") +
              "; either every line has r g b or none does: " + quote(line));
    }

    Vec3f point;
    for (std::size_t axis = 0; axis < 3; ++axis) {
      if (!parse_coordinate(tokens[axis], point[axis])) {
        throw FormatError::at_line(file_name_, line_number,
                                   quote(tokens[axis]) + " is not a number, in " + quote(line));
      }
    }
    // Grown here, checked against the memory limit: the file does not say how many points follow.
    if (scan.points.size() == scan.points.capacity()) detail::grow_points(scan, has_color, file_name_);
    scan.points.push_back(point);
    if (has_color) {
      Rgb color;
      std::uint8_t* channels[3] = {&color.r, &color.g, &color.b};
      for (std::size_t channel = 0; channel < 3; ++channel) {
        if (!parse_color_channel(tokens[3 + channel], *channels[channel])) {
          throw FormatError::at_line(file_name_, line_number,
                                     "color value " + quote(tokens[3 + channel]) +
                                         " is not an integer 0..255, in " + quote(line));
        }
      }
      scan.colors.push_back(color);
    }
  }

  std::string file_name_;
  std::string display_name_;
  Vec3f origin_;
  std::uint64_t file_size_ = 0;  // 0 when unknown (pipes)
  std::unique_ptr<TextInput> input_;
  std::optional<bool> color_line_kind_;  // set by the first point line: true = with colors
  std::uint64_t first_point_line_ = 0;
};

}  // namespace

std::unique_ptr<ScanSource> open_xyz_file(const std::filesystem::path& path, Vec3f origin) {
  return detail::naming_bad_alloc(path, [&] { return std::make_unique<XyzReader>(path, origin); });
}

}  // namespace umbra
