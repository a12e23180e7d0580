// Internal helpers shared by the point-cloud readers: file access by offset
// (pread), a buffered byte reader, a line splitter, number parsing with
// std::from_chars, binary scalar decoding, 3x4 poses and the single-scan
// ScanSource base.
//
// Cost model: every read goes through one buffer per reader (1 MiB by
// default for bytes, growing only for lines longer than the buffer up to a
// limit), so a reader's memory is independent of the file size; parsing
// never allocates per token or per record.
#include "reader_support.hpp"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <system_error>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/memory_budget.hpp"
#include "umbra/io/format_error.hpp"

namespace umbra::io_detail {

namespace {
constexpr std::size_t kQuotedTextChars = 80;
constexpr std::size_t kLineChunkBytes = 256 * 1024;
}  // namespace

std::string errno_text(int error) { return std::generic_category().message(error); }

std::string quote(std::string_view text, HighBytes high_bytes) {
  std::string quoted = "'";
  for (std::size_t i = 0; i < text.size() && i < kQuotedTextChars; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    const bool shown = c >= 0x20 && c != 0x7f && (c < 0x80 || high_bytes == HighBytes::keep);
    quoted += shown ? static_cast<char>(c) : '?';
  }
  if (text.size() > kQuotedTextChars) quoted += "...";
  quoted += "'";
  return quoted;
}

std::string to_lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

bool has_bz2_suffix(const std::filesystem::path& path) {
  return to_lower(path.filename().string()).ends_with(".bz2");
}

void reject_directory(const std::filesystem::path& path) {
  std::error_code ignored;
  if (std::filesystem::is_directory(path, ignored)) {
    throw std::runtime_error("cannot open " + path.string() + ": it is a directory");
  }
}

// --- InputFile ---------------------------------------------------------------

InputFile::InputFile(const std::filesystem::path& path, std::string_view format) : name_(path.string()) {
  descriptor_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (descriptor_ < 0) throw std::runtime_error("cannot open " + name_ + ": " + errno_text(errno));
  struct stat info {};
  if (::fstat(descriptor_, &info) != 0) {
    const int error = errno;
    ::close(descriptor_);
    throw std::runtime_error("cannot open " + name_ + ": " + errno_text(error));
  }
  if (S_ISDIR(info.st_mode)) {
    ::close(descriptor_);
    throw std::runtime_error("cannot open " + name_ + ": it is a directory");
  }
  if (!S_ISREG(info.st_mode)) {
    ::close(descriptor_);
    std::string reason = "not a regular file";
    if (!format.empty()) reason += " (" + std::string(format) + " files are read with seeks)";
    throw std::runtime_error("cannot open " + name_ + ": " + reason);
  }
  size_ = static_cast<std::uint64_t>(info.st_size);
}

InputFile::~InputFile() {
  if (descriptor_ >= 0) ::close(descriptor_);
}

std::size_t InputFile::read_at(std::uint64_t offset, void* out, std::size_t capacity) {
  auto* bytes = static_cast<unsigned char*>(out);
  std::size_t done = 0;
  while (done < capacity) {
    const ::ssize_t got = ::pread(descriptor_, bytes + done, capacity - done, static_cast<off_t>(offset + done));
    if (got < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error("cannot read " + name_ + ": " + errno_text(errno));
    }
    if (got == 0) break;
    done += static_cast<std::size_t>(got);
  }
  return done;
}

// --- ByteReader --------------------------------------------------------------

ByteReader::ByteReader(InputFile& file, std::uint64_t offset, std::size_t buffer_bytes)
    : file_(file), buffer_(std::max<std::size_t>(buffer_bytes, 64)), buffer_end_offset_(offset) {}

bool ByteReader::fill(std::size_t count) {
  const std::size_t have = end_ - begin_;
  if (count - have > file_.size() - std::min(file_.size(), buffer_end_offset_)) return false;
  if (begin_ > 0) {
    std::memmove(buffer_.data(), buffer_.data() + begin_, have);
    begin_ = 0;
    end_ = have;
  }
  if (count > buffer_.size()) buffer_.resize(count);  // bounded by the file size (checked above)
  while (end_ < count) {
    const std::size_t got = file_.read_at(buffer_end_offset_, buffer_.data() + end_, buffer_.size() - end_);
    if (got == 0) return false;  // the file shrank after it was opened
    end_ += got;
    buffer_end_offset_ += got;
  }
  return true;
}

bool ByteReader::skip(std::uint64_t count) {
  const std::uint64_t have = end_ - begin_;
  if (count <= have) {
    begin_ += static_cast<std::size_t>(count);
    return true;
  }
  if (count > remaining()) return false;
  buffer_end_offset_ += count - have;
  begin_ = end_ = 0;
  return true;
}

// --- LineReader --------------------------------------------------------------

LineReader::LineReader(InputFile& file, std::uint64_t offset, std::uint64_t first_line, std::size_t max_line_bytes)
    : file_(file),
      max_line_bytes_(max_line_bytes),
      buffer_(std::min(kLineChunkBytes, max_line_bytes + 1)),
      buffer_end_offset_(offset),
      line_number_(first_line - 1) {}

bool LineReader::next(std::string_view& line) {
  std::size_t searched = begin_;  // bytes before this have no '\n'
  while (true) {
    const auto* newline = static_cast<const char*>(std::memchr(buffer_.data() + searched, '\n', end_ - searched));
    if (newline != nullptr || (at_end_ && end_ > begin_)) {
      const std::size_t line_end = newline != nullptr ? static_cast<std::size_t>(newline - buffer_.data()) : end_;
      if (line_end - begin_ > max_line_bytes_) break;  // reported below
      line = std::string_view(buffer_.data() + begin_, line_end - begin_);
      while (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      begin_ = newline != nullptr ? line_end + 1 : line_end;
      ++line_number_;
      return true;
    }
    if (at_end_) return false;
    searched = end_;
    if (end_ - begin_ > max_line_bytes_) break;
    // Keep the unfinished line, make room, read more.
    if (begin_ > 0) {
      std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
      end_ -= begin_;
      searched -= begin_;
      begin_ = 0;
    }
    if (end_ == buffer_.size()) buffer_.resize(std::min(buffer_.size() * 2, max_line_bytes_ + 2));
    const std::size_t got = file_.read_at(buffer_end_offset_, buffer_.data() + end_, buffer_.size() - end_);
    if (got == 0) at_end_ = true;
    end_ += got;
    buffer_end_offset_ += got;
  }
  throw FormatError::at_line(file_.name(), line_number_ + 1,
                             "line longer than " + std::to_string(max_line_bytes_) +
                                 " bytes; is this really a text file? It starts " +
                                 quote({buffer_.data() + begin_, std::min<std::size_t>(end_ - begin_, 80)}));
}

bool LineReader::next_non_blank(std::string_view& line) {
  while (next(line)) {
    if (!Tokens(line).at_end()) return true;
  }
  return false;
}

std::size_t Tokens::count_left() const {
  std::size_t count = 0;
  bool in_token = false;
  for (std::size_t i = position_; i < line_.size(); ++i) {
    const bool space = is_space(line_[i]);
    if (!space && !in_token) ++count;
    in_token = !space;
  }
  return count;
}

// --- numbers -----------------------------------------------------------------

namespace {

template <typename Float>
bool parse_floating(std::string_view token, Float& value) {
  const char* first = token.data();
  const char* const last = first + token.size();
  if (token.size() > 1 && *first == '+' && first[1] != '+' && first[1] != '-') ++first;
  if (first == last) return false;
  const auto [end, status] = std::from_chars(first, last, value);
  if (end != last) return false;
  if (status == std::errc()) return true;
  if (status != std::errc::result_out_of_range) return false;
  // Out of range: overflow to +-inf, underflow to +-0 (as strtof/strtod).
  long double wide = 0.0L;
  const auto [wide_end, wide_status] = std::from_chars(first, last, wide);
  if (wide_end != last || wide_status != std::errc()) {
    const bool negative = *first == '-';
    // Decide overflow/underflow by the exponent sign: "1e999" vs "1e-999".
    const std::string_view digits(first, static_cast<std::size_t>(last - first));
    const std::size_t e = digits.find_first_of("eE");
    const bool underflow = e != std::string_view::npos && e + 1 < digits.size() && digits[e + 1] == '-';
    value = underflow ? (negative ? -Float(0) : Float(0))
                      : (negative ? -std::numeric_limits<Float>::infinity() : std::numeric_limits<Float>::infinity());
    return true;
  }
  value = static_cast<Float>(wide);
  return true;
}

}  // namespace

bool parse_float(std::string_view token, float& value) { return parse_floating(token, value); }
bool parse_double(std::string_view token, double& value) { return parse_floating(token, value); }

namespace {

/// A whole token as a decimal integer; an optional '+' (from_chars takes '-'
/// only for signed types).
template <typename Integer>
bool parse_integer(std::string_view token, Integer& value) {
  const char* first = token.data();
  const char* const last = first + token.size();
  if (first != last && *first == '+') ++first;
  if (first == last) return false;
  const auto [end, status] = std::from_chars(first, last, value);
  return status == std::errc() && end == last;
}

}  // namespace

bool parse_unsigned(std::string_view token, std::uint64_t& value) { return parse_integer(token, value); }
bool parse_signed(std::string_view token, std::int64_t& value) { return parse_integer(token, value); }

double load_scalar(const unsigned char* data, ScalarType type, bool big_endian) {
  const std::uint64_t bits = load_bits(data, type.bytes, big_endian);
  switch (type.kind) {
    case ScalarKind::floating_point:
      if (type.bytes == 4) return static_cast<double>(std::bit_cast<float>(static_cast<std::uint32_t>(bits)));
      return std::bit_cast<double>(bits);
    case ScalarKind::unsigned_integer:
      return static_cast<double>(bits);
    case ScalarKind::signed_integer: {
      const unsigned shift = 64U - 8U * type.bytes;
      return static_cast<double>(static_cast<std::int64_t>(bits << shift) >> shift);
    }
  }
  return 0.0;
}

bool parse_scalar(std::string_view token, ScalarType type, double& value) {
  switch (type.kind) {
    case ScalarKind::floating_point:
      return parse_double(token, value);
    case ScalarKind::unsigned_integer: {
      std::uint64_t integer = 0;
      if (!parse_unsigned(token, integer)) return false;
      if (type.bytes < 8 && integer >> (8U * type.bytes) != 0) return false;
      value = static_cast<double>(integer);
      return true;
    }
    case ScalarKind::signed_integer: {
      std::int64_t integer = 0;
      if (!parse_signed(token, integer)) return false;
      if (type.bytes < 8) {
        const std::int64_t limit = std::int64_t{1} << (8U * type.bytes - 1);
        if (integer < -limit || integer >= limit) return false;
      }
      value = static_cast<double>(integer);
      return true;
    }
  }
  return false;
}

// --- SingleScanSource --------------------------------------------------------

std::uint64_t point_bytes(std::uint64_t points, bool colour) {
  const std::uint64_t each = sizeof(Vec3f) + (colour ? sizeof(Rgb) : 0);
  return points > UINT64_MAX / each ? UINT64_MAX : points * each;
}

void require_point_memory(const std::string& file, const std::string& what, std::uint64_t points, bool colour,
                          std::uint64_t extra_bytes) {
  const std::uint64_t bytes = point_bytes(points, colour);
  detail::require_memory(file, what, bytes > UINT64_MAX - extra_bytes ? UINT64_MAX : bytes + extra_bytes);
}

void grow_points(Scan& scan, bool colour, const std::string& file) {
  const std::size_t capacity = std::max<std::size_t>(std::size_t{1} << 16, 2 * scan.points.capacity());
  require_point_memory(file,
                       "making room for " + std::to_string(capacity) + " points (" +
                           std::to_string(scan.points.size()) + " read so far; the file does not say how many follow)",
                       capacity, colour);
  scan.points.reserve(capacity);
  if (colour) scan.colors.reserve(capacity);
}

namespace {

/// Passes everything on to the reader it holds, naming the file when memory runs out.
class MemoryNamingSource final : public ScanSource {
 public:
  MemoryNamingSource(std::string file, std::unique_ptr<ScanSource> reader)
      : file_(std::move(file)), reader_(std::move(reader)) {}
  bool next(Scan& scan) override {
    try {
      return reader_->next(scan);
    } catch (const MemoryLimitError&) {
      throw;
    } catch (const std::bad_alloc&) {
      detail::throw_out_of_memory(file_, "reading a scan (" + std::to_string(scan.points.size()) + " points so far)",
                                  point_bytes(scan.points.capacity(), !scan.colors.empty()));
    }
  }
  [[nodiscard]] std::size_t scan_count() const override { return reader_->scan_count(); }
  [[nodiscard]] double progress() const override { return reader_->progress(); }
  [[nodiscard]] std::vector<Vec3f> origins() const override { return reader_->origins(); }
  [[nodiscard]] std::vector<std::string> warnings() const override { return reader_->warnings(); }

 private:
  std::string file_;
  std::unique_ptr<ScanSource> reader_;
};

}  // namespace

std::unique_ptr<ScanSource> naming_bad_alloc(const std::filesystem::path& file,
                                             const std::function<std::unique_ptr<ScanSource>()>& make) {
  const std::string name = file.string();
  return std::make_unique<MemoryNamingSource>(name, detail::naming_bad_alloc(name, "opening it", 0, make));
}

bool SingleScanSource::next(Scan& scan) {
  if (error_) std::rethrow_exception(error_);
  if (done_) return false;
  try {
    read_scan(scan);
  } catch (...) {
    error_ = std::current_exception();
    throw;
  }
  done_ = true;
  return true;
}

double SingleScanSource::progress() const {
  if (done_) return 1.0;
  const std::uint64_t total = input_bytes();
  if (total == 0) return 0.0;
  return static_cast<double>(bytes_consumed()) / static_cast<double>(total);
}

}  // namespace umbra::io_detail
