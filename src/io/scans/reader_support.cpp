// Internal helpers shared by the point-cloud readers: number parsing with
// std::from_chars, binary scalar decoding, memory checks for points and the
// single-scan ScanSource base. Cost model: parsing never allocates per token
// or per record.
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

#include "core/memory_budget.hpp"
#include "umbra/io/format_error.hpp"

namespace umbra::detail {

std::string to_lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

bool has_bz2_suffix(const std::filesystem::path& path) {
  return to_lower(path.filename().string()).ends_with(".bz2");
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

std::uint64_t point_bytes(std::uint64_t points, bool color) {
  const std::uint64_t each = sizeof(Vec3f) + (color ? sizeof(Rgb) : 0);
  return points > UINT64_MAX / each ? UINT64_MAX : points * each;
}

void require_point_memory(const std::string& file, const std::string& what, std::uint64_t points, bool color,
                          std::uint64_t extra_bytes) {
  const std::uint64_t bytes = point_bytes(points, color);
  detail::require_memory(file, what, bytes > UINT64_MAX - extra_bytes ? UINT64_MAX : bytes + extra_bytes);
}

void grow_points(Scan& scan, bool color, const std::string& file) {
  const std::size_t capacity = std::max<std::size_t>(std::size_t{1} << 16, 2 * scan.points.capacity());
  require_point_memory(file,
                       "making room for " + std::to_string(capacity) + " points (" +
                           std::to_string(scan.points.size()) + " read so far; the file does not say how many follow)",
                       capacity, color);
  scan.points.reserve(capacity);
  if (color) scan.colors.reserve(capacity);
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

}  // namespace umbra::detail
