// Reader for PCD files (.pcd): DATA ascii, binary and binary_compressed.
//
// Opening parses the header line by line, checks the field table (x, y, z
// present with COUNT 1; SIZE 1/2/4/8; TYPE I/U/F), the point count
// (POINTS against WIDTH x HEIGHT) and the data size against the file size;
// for binary_compressed it also reads the two uint32 sizes after the header
// and checks that the uncompressed size is exactly POINTS x the record size
// and no more than LZF can produce from the compressed bytes. next() reads
// ascii lines in place (from_chars), binary records through one 1 MiB
// buffer, or the compressed block (at most the file size) decompressed with
// liblzf (Debian liblzf-dev, the LZF library PCL itself uses) into one buffer
// of the validated size, from which the columns are gathered.
// Cost: one pass over the file, O(points) output, no per-point allocation.
// The viewpoint convention is documented in pcd_file.hpp.
#include <algorithm>
#include <cerrno>
#include <atomic>
#include <bit>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <lzf.h>

#include "reader_support.hpp"
#include "umbra/io/format_error.hpp"
#include "umbra/io/pcd_file.hpp"
#include "umbra/io/scan_source.hpp"

namespace umbra {
namespace {

using detail::ByteReader;
using detail::InputFile;
using detail::LineReader;
using detail::Pose;
using detail::quote;
using detail::ScalarKind;
using detail::ScalarType;
using detail::Tokens;

constexpr std::uint64_t kMaxPointBytes = std::uint64_t{1} << 24;  // larger records are not point clouds

/// No valid LZF stream expands more than 88 times (a 3-byte back reference
/// yields at most 264 bytes): a larger declared size is refused before allocating.
constexpr std::uint64_t kLzfMaxExpansion = 88;

/// Decompresses `input` into exactly `output.size()` bytes with liblzf;
/// what is wrong when it cannot (liblzf checks every run and back reference
/// against both buffers), else empty. Both sizes come from uint32 fields.
std::string lzf_decompress_exactly(std::span<const unsigned char> input, std::span<unsigned char> output) {
  const std::string declared = std::to_string(output.size());
  if (input.empty()) return output.empty() ? std::string() : "no compressed bytes for " + declared + " declared bytes";
  errno = 0;
  const unsigned produced = ::lzf_decompress(input.data(), static_cast<unsigned>(input.size()), output.data(),
                                             static_cast<unsigned>(output.size()));
  if (produced == 0) {
    return errno == E2BIG ? "it decompresses to more than the declared " + declared + " bytes"
                          : std::string("a run or back reference leaves the data (liblzf: invalid stream)");
  }
  if (produced != output.size()) {
    return "it decompresses to " + std::to_string(produced) + " bytes, not the declared " + declared;
  }
  return {};
}

enum class PcdEncoding { ascii, binary, binary_compressed };

struct PcdField {
  std::string name;
  ScalarType type;
  std::uint64_t count = 1;
  std::uint64_t offset = 0;       // byte offset within a record
  std::uint64_t first_token = 0;  // token index within an ascii line
};

/// Which fields umbra uses, as indices into the field table.
struct FieldRoles {
  std::size_t x = 0;
  std::size_t y = 0;
  std::size_t z = 0;
  std::optional<std::size_t> color;
};

Rgb unpack_color(std::uint32_t bits) {
  return {static_cast<std::uint8_t>(bits >> 16), static_cast<std::uint8_t>(bits >> 8), static_cast<std::uint8_t>(bits)};
}

class PcdReader final : public detail::SingleScanSource {
 public:
  PcdReader(const std::filesystem::path& path, Vec3f origin)
      : file_(path), display_name_(path.filename().string()), origin_(origin) {
    if (detail::has_bz2_suffix(path)) {
      throw FormatError(file_.name(), "compressed .bz2 PCD files are not supported; decompress it first (bunzip2)");
    }
    lines_ = std::make_unique<LineReader>(file_, 0);
    parse_header();
    check_sizes();
    // binary_compressed holds the compressed and the decompressed data besides the points.
    const std::uint64_t buffers =
        encoding_ == PcdEncoding::binary_compressed ? compressed_bytes_ + point_count_ * record_bytes_ : 0;
    detail::require_point_memory(file_.name(), "reading its " + std::to_string(point_count_) + " points",
                                    point_count_, roles_.color.has_value(), buffers);
  }

  [[nodiscard]] std::vector<Vec3f> origins() const override {
    return {viewpoint_.is_identity() ? origin_ : viewpoint_.translation()};
  }

 private:
  [[nodiscard]] std::uint64_t input_bytes() const override { return file_.size(); }
  [[nodiscard]] std::uint64_t bytes_consumed() const override { return consumed_.load(std::memory_order_relaxed); }

  // --- header ---

  [[noreturn]] void header_error(const std::string& message) const {
    throw FormatError::at_line(file_.name(), lines_->line_number(), message);
  }

  /// The remaining tokens of a header line as unsigned integers (at least one).
  std::vector<std::uint64_t> unsigned_values(Tokens& tokens, std::string_view keyword, std::string_view line) const {
    std::vector<std::uint64_t> values;
    for (std::string_view token = tokens.next(); !token.empty(); token = tokens.next()) {
      std::uint64_t value = 0;
      if (!detail::parse_unsigned(token, value)) {
        header_error(std::string(keyword) + ": " + quote(token) + " is not a non-negative integer, in " + quote(line));
      }
      values.push_back(value);
    }
    if (values.empty()) header_error(std::string(keyword) + " without values");
    return values;
  }

  std::uint64_t single_value(Tokens& tokens, std::string_view keyword, std::string_view line) const {
    const std::vector<std::uint64_t> values = unsigned_values(tokens, keyword, line);
    if (values.size() != 1) header_error(std::string(keyword) + " takes one value, found " + quote(line));
    return values[0];
  }

  void parse_header() {
    std::vector<std::string> names;
    std::vector<std::uint64_t> sizes;
    std::vector<char> types;
    std::vector<std::uint64_t> counts;
    std::optional<std::uint64_t> width;
    std::optional<std::uint64_t> height;
    std::optional<std::uint64_t> points;
    std::uint64_t fields_line = 0;
    std::uint64_t sizes_line = 0;
    std::uint64_t types_line = 0;
    std::uint64_t counts_line = 0;
    std::uint64_t points_line = 0;
    std::string_view line;
    while (true) {
      if (!lines_->next(line)) {
        throw FormatError::at_line(file_.name(), lines_->line_number(),
                                   lines_->line_number() == 0
                                       ? std::string("empty file, not a PCD file")
                                       : "the PCD header ends without a DATA line (truncated file?)");
      }
      Tokens tokens(line);
      const std::string_view keyword = tokens.next();
      if (keyword.empty() || keyword.front() == '#') continue;
      const auto once = [&](bool seen) {
        if (seen) header_error("a second " + std::string(keyword) + " line");
      };
      if (keyword == "VERSION") {
        continue;  // 0.7 and the older versions differ only in which lines are optional
      } else if (keyword == "FIELDS" || keyword == "COLUMNS") {
        once(fields_line != 0);
        fields_line = lines_->line_number();
        for (std::string_view token = tokens.next(); !token.empty(); token = tokens.next()) names.emplace_back(token);
        if (names.empty()) header_error("FIELDS without field names");
      } else if (keyword == "SIZE") {
        once(sizes_line != 0);
        sizes_line = lines_->line_number();
        sizes = unsigned_values(tokens, keyword, line);
      } else if (keyword == "TYPE") {
        once(types_line != 0);
        types_line = lines_->line_number();
        for (std::string_view token = tokens.next(); !token.empty(); token = tokens.next()) {
          if (token != "I" && token != "U" && token != "F") {
            header_error("TYPE " + quote(token) + " is not I (signed), U (unsigned) or F (floating point)");
          }
          types.push_back(token[0]);
        }
        if (types.empty()) header_error("TYPE without values");
      } else if (keyword == "COUNT") {
        once(counts_line != 0);
        counts_line = lines_->line_number();
        counts = unsigned_values(tokens, keyword, line);
      } else if (keyword == "WIDTH") {
        once(width.has_value());
        width = single_value(tokens, keyword, line);
      } else if (keyword == "HEIGHT") {
        once(height.has_value());
        height = single_value(tokens, keyword, line);
      } else if (keyword == "POINTS") {
        once(points.has_value());
        points_line = lines_->line_number();
        points = single_value(tokens, keyword, line);
      } else if (keyword == "VIEWPOINT") {
        parse_viewpoint(tokens, line);
      } else if (keyword == "DATA") {
        const std::string_view encoding = tokens.next();
        if (encoding == "ascii") {
          encoding_ = PcdEncoding::ascii;
        } else if (encoding == "binary") {
          encoding_ = PcdEncoding::binary;
        } else if (encoding == "binary_compressed") {
          encoding_ = PcdEncoding::binary_compressed;
        } else {
          header_error("unknown DATA encoding " + quote(encoding) + "; expected ascii, binary or binary_compressed");
        }
        if (!tokens.at_end()) header_error("unexpected text after the DATA encoding: " + quote(line));
        break;
      } else {
        header_error("not a PCD header line: " + quote(line));
      }
    }
    data_line_ = lines_->line_number();
    data_offset_ = lines_->offset();
    consumed_.store(data_offset_, std::memory_order_relaxed);

    // The field table.
    if (fields_line == 0) header_error("the PCD header has no FIELDS line");
    const auto check_length = [&](std::size_t length, std::uint64_t at_line, const char* what) {
      if (at_line != 0 && length != names.size()) {
        throw FormatError::at_line(file_.name(), at_line,
                                   std::string(what) + " has " + std::to_string(length) + " values but FIELDS (line " +
                                       std::to_string(fields_line) + ") names " + std::to_string(names.size()) +
                                       " fields");
      }
    };
    check_length(sizes.size(), sizes_line, "SIZE");
    check_length(types.size(), types_line, "TYPE");
    check_length(counts.size(), counts_line, "COUNT");
    std::uint64_t record_bytes = 0;
    std::uint64_t tokens = 0;
    for (std::size_t i = 0; i < names.size(); ++i) {
      PcdField field;
      field.name = names[i];
      const std::uint64_t size = sizes_line != 0 ? sizes[i] : 4;  // PCL's defaults: 4-byte floats, one each
      const char type = types_line != 0 ? types[i] : 'F';
      field.count = counts_line != 0 ? counts[i] : 1;
      if (size != 1 && size != 2 && size != 4 && size != 8) {
        throw FormatError::at_line(file_.name(), sizes_line,
                                   "field '" + field.name + "' has SIZE " + std::to_string(size) +
                                       "; PCD sizes are 1, 2, 4 or 8 bytes");
      }
      if (type == 'F' && size != 4 && size != 8) {
        throw FormatError::at_line(file_.name(), sizes_line,
                                   "field '" + field.name + "' is TYPE F with SIZE " + std::to_string(size) +
                                       "; floating-point fields have 4 or 8 bytes");
      }
      if (field.count == 0 || field.count > kMaxPointBytes) {
        throw FormatError::at_line(file_.name(), counts_line,
                                   "field '" + field.name + "' has COUNT " + std::to_string(field.count) +
                                       "; expected 1 to " + std::to_string(kMaxPointBytes));
      }
      field.type = {type == 'F' ? ScalarKind::floating_point
                                : (type == 'U' ? ScalarKind::unsigned_integer : ScalarKind::signed_integer),
                    static_cast<std::uint8_t>(size)};
      field.offset = record_bytes;
      field.first_token = tokens;
      record_bytes += size * field.count;
      tokens += field.count;
      if (record_bytes > kMaxPointBytes) {
        throw FormatError::at_line(file_.name(), counts_line != 0 ? counts_line : fields_line,
                                   "a point of more than " + std::to_string(kMaxPointBytes) +
                                       " bytes is not a point cloud");
      }
      fields_.push_back(std::move(field));
    }
    record_bytes_ = record_bytes;
    tokens_per_point_ = tokens;
    find_roles(fields_line);

    // The point count.
    if (width && !height) height = 1;
    if (!points && !width) header_error("the PCD header has neither POINTS nor WIDTH, so the point count is unknown");
    if (width && *height != 0 && *width > UINT64_MAX / *height) header_error("WIDTH x HEIGHT overflows");
    if (width && points && *width * *height != *points) {
      throw FormatError::at_line(file_.name(), points_line,
                                 "POINTS " + std::to_string(*points) + " differs from WIDTH x HEIGHT = " +
                                     std::to_string(*width) + " x " + std::to_string(*height));
    }
    point_count_ = points ? *points : *width * *height;
  }

  void parse_viewpoint(Tokens& tokens, std::string_view line) {
    double values[7];
    std::size_t count = 0;
    for (std::string_view token = tokens.next(); !token.empty(); token = tokens.next()) {
      if (count == 7 || !detail::parse_double(token, values[count])) {
        header_error("VIEWPOINT expects 7 numbers (tx ty tz qw qx qy qz), found " + quote(line));
      }
      ++count;
    }
    if (count != 7) header_error("VIEWPOINT expects 7 numbers (tx ty tz qw qx qy qz), found " + quote(line));
    try {
      viewpoint_ = Pose::from_translation_quaternion(values[0], values[1], values[2], values[3], values[4], values[5],
                                                     values[6]);
    } catch (const std::invalid_argument& error) {
      header_error(std::string("VIEWPOINT: ") + error.what());
    }
  }

  void find_roles(std::uint64_t fields_line) {
    const auto find = [&](std::string_view name) -> std::optional<std::size_t> {
      for (std::size_t i = 0; i < fields_.size(); ++i) {
        if (fields_[i].name == name) return i;
      }
      return std::nullopt;
    };
    const auto required = [&](const char* name) {
      const auto index = find(name);
      if (!index) {
        throw FormatError::at_line(file_.name(), fields_line, std::string("the PCD file has no '") + name + "' field");
      }
      if (fields_[*index].count != 1) {
        throw FormatError::at_line(file_.name(), fields_line,
                                   std::string("field '") + name + "' has COUNT " +
                                       std::to_string(fields_[*index].count) + ", expected 1");
      }
      return *index;
    };
    roles_.x = required("x");
    roles_.y = required("y");
    roles_.z = required("z");
    roles_.color = find("rgb");
    if (!roles_.color) roles_.color = find("rgba");
    if (roles_.color) {
      const PcdField& color = fields_[*roles_.color];
      if (color.type.bytes != 4 || color.count != 1) {
        throw FormatError::at_line(file_.name(), fields_line,
                                   "field '" + color.name +
                                       "' must be one packed 4-byte value (SIZE 4, COUNT 1), found SIZE " +
                                       std::to_string(color.type.bytes) + " COUNT " + std::to_string(color.count));
      }
    }
  }

  /// The declared data against the bytes after the header.
  void check_sizes() {
    const std::uint64_t remaining = file_.size() - data_offset_;
    if (encoding_ == PcdEncoding::ascii) {
      const std::uint64_t line_bytes = 2 * tokens_per_point_;  // "v v\n": 2 bytes per value at least
      if (point_count_ > (remaining + 1) / line_bytes) {
        throw FormatError::at_line(file_.name(), data_line_ + 1,
                                   "the header declares " + std::to_string(point_count_) + " points of " +
                                       std::to_string(tokens_per_point_) + " values, which need at least " +
                                       std::to_string(line_bytes) + " bytes per line, but only " +
                                       std::to_string(remaining) + " bytes follow (truncated file or wrong count)");
      }
      return;
    }
    if (encoding_ == PcdEncoding::binary) {
      if (point_count_ > remaining / record_bytes_) {
        throw FormatError::at_byte(file_.name(), data_offset_,
                                   "truncated file: the header declares " + std::to_string(point_count_) +
                                       " points of " + std::to_string(record_bytes_) + " bytes, which need " +
                                       size_text(point_count_, record_bytes_) + " bytes, but only " +
                                       std::to_string(remaining) + " bytes follow the header");
      }
      return;
    }
    // binary_compressed: uint32 compressed size, uint32 uncompressed size, the LZF data.
    unsigned char sizes[8];
    if (file_.read_at(data_offset_, sizes, 8) != 8) {
      throw FormatError::at_byte(file_.name(), data_offset_,
                                 "truncated file: expected the compressed and uncompressed sizes (2 x uint32, 8 bytes) "
                                 "after the header, but only " +
                                     std::to_string(remaining) + " bytes follow");
    }
    compressed_bytes_ = detail::load_bits(sizes, 4, false);
    const std::uint64_t uncompressed_bytes = detail::load_bits(sizes + 4, 4, false);
    if (compressed_bytes_ > remaining - 8) {
      throw FormatError::at_byte(file_.name(), data_offset_,
                                 "truncated file: the compressed data is declared as " +
                                     std::to_string(compressed_bytes_) + " bytes, but only " +
                                     std::to_string(remaining - 8) + " bytes follow the sizes");
    }
    if (point_count_ > UINT64_MAX / record_bytes_ || uncompressed_bytes != point_count_ * record_bytes_) {
      throw FormatError::at_byte(file_.name(), data_offset_ + 4,
                                 "the uncompressed size is declared as " + std::to_string(uncompressed_bytes) +
                                     " bytes, but " + std::to_string(point_count_) + " points of " +
                                     std::to_string(record_bytes_) + " bytes need " +
                                     size_text(point_count_, record_bytes_));
    }
    if (uncompressed_bytes > kLzfMaxExpansion * compressed_bytes_) {
      throw FormatError::at_byte(file_.name(), data_offset_,
                                 "the uncompressed size " + std::to_string(uncompressed_bytes) +
                                     " bytes is more than LZF can produce from " + std::to_string(compressed_bytes_) +
                                     " compressed bytes (corrupt sizes)");
    }
  }

  static std::string size_text(std::uint64_t count, std::uint64_t each) {
    return count > UINT64_MAX / each ? std::string("more than 2^64") : std::to_string(count * each);
  }

  // --- data ---

  void read_scan(Scan& scan) override {
    const bool transform = !viewpoint_.is_identity();
    scan.origin = transform ? viewpoint_.translation() : origin_;
    scan.points.clear();
    scan.colors.clear();
    scan.stamp.reset();  // this format carries no times
    scan.name = display_name_;
    // Safe: the count was checked against the file size when it was opened.
    scan.points.reserve(static_cast<std::size_t>(point_count_));
    if (roles_.color) scan.colors.reserve(static_cast<std::size_t>(point_count_));
    switch (encoding_) {
      case PcdEncoding::ascii:
        read_ascii(scan);
        break;
      case PcdEncoding::binary:
        read_binary(scan);
        break;
      case PcdEncoding::binary_compressed:
        read_compressed(scan);
        break;
    }
    if (transform) {
      for (Vec3f& point : scan.points) point = viewpoint_.apply(point);
    }
  }

  [[nodiscard]] float coordinate(const unsigned char* bytes, std::size_t field) const {
    return static_cast<float>(detail::load_scalar(bytes, fields_[field].type, false));
  }

  void read_binary(Scan& scan) {
    ByteReader reader(file_, data_offset_);
    const auto record_bytes = static_cast<std::size_t>(record_bytes_);
    const PcdField& x = fields_[roles_.x];
    const PcdField& y = fields_[roles_.y];
    const PcdField& z = fields_[roles_.z];
    for (std::uint64_t point = 0; point < point_count_; ++point) {
      const unsigned char* record = reader.take(record_bytes);
      if (record == nullptr) {
        throw FormatError::at_byte(file_.name(), reader.offset(),
                                   "truncated file: the file ends in point " + std::to_string(point) + " of " +
                                       std::to_string(point_count_));
      }
      scan.points.push_back({coordinate(record + x.offset, roles_.x), coordinate(record + y.offset, roles_.y),
                             coordinate(record + z.offset, roles_.z)});
      if (roles_.color) {
        scan.colors.push_back(unpack_color(
            static_cast<std::uint32_t>(detail::load_bits(record + fields_[*roles_.color].offset, 4, false))));
      }
      if (point % 65536 == 0) consumed_.store(reader.offset(), std::memory_order_relaxed);
    }
  }

  void read_compressed(Scan& scan) {
    const std::uint64_t compressed_offset = data_offset_ + 8;
    std::vector<unsigned char> compressed(static_cast<std::size_t>(compressed_bytes_));  // <= the file size
    if (file_.read_at(compressed_offset, compressed.data(), compressed.size()) != compressed.size()) {
      throw FormatError::at_byte(file_.name(), compressed_offset, "truncated file: the file shrank while being read");
    }
    consumed_.store(compressed_offset + compressed_bytes_, std::memory_order_relaxed);
    // <= 88 x the compressed size and exactly points x record size (checked at open).
    std::vector<unsigned char> data(static_cast<std::size_t>(point_count_ * record_bytes_));
    if (const std::string problem = lzf_decompress_exactly(compressed, data); !problem.empty()) {
      throw FormatError::at_byte(file_.name(), compressed_offset, "corrupt LZF data: " + problem);
    }
    // Column layout: field after field, each holding every point's value.
    const auto column = [&](std::size_t field) { return data.data() + point_count_ * fields_[field].offset; };
    const unsigned char* xs = column(roles_.x);
    const unsigned char* ys = column(roles_.y);
    const unsigned char* zs = column(roles_.z);
    const std::size_t x_bytes = fields_[roles_.x].type.bytes;
    const std::size_t y_bytes = fields_[roles_.y].type.bytes;
    const std::size_t z_bytes = fields_[roles_.z].type.bytes;
    for (std::uint64_t point = 0; point < point_count_; ++point) {
      scan.points.push_back({coordinate(xs + point * x_bytes, roles_.x), coordinate(ys + point * y_bytes, roles_.y),
                             coordinate(zs + point * z_bytes, roles_.z)});
    }
    if (roles_.color) {
      const unsigned char* colors = column(*roles_.color);
      for (std::uint64_t point = 0; point < point_count_; ++point) {
        scan.colors.push_back(unpack_color(static_cast<std::uint32_t>(detail::load_bits(colors + 4 * point, 4, false))));
      }
    }
  }

  [[noreturn]] void ascii_error(const std::string& message, std::string_view line) const {
    throw FormatError::at_line(file_.name(), lines_->line_number(), message + ", in " + quote(line));
  }

  /// An ascii coordinate of any PCD type, as float.
  bool parse_coordinate(std::string_view token, const PcdField& field, float& value) const {
    if (field.type.kind == ScalarKind::floating_point && field.type.bytes == 4) {
      return detail::parse_float(token, value);
    }
    double wide = 0;
    if (!detail::parse_scalar(token, field.type, wide)) return false;
    value = static_cast<float>(wide);
    return true;
  }

  /// A packed color written as text: an integer (the bits, as PCL writes
  /// rgb since 1.8 and for integer fields) or a float whose bits are the color.
  bool parse_packed_color(std::string_view token, const PcdField& field, std::uint32_t& bits) const {
    const bool integer_text = token.find_first_of(".eEnNiI") == std::string_view::npos;
    if (field.type.kind == ScalarKind::floating_point && !integer_text) {
      float value = 0;
      if (!detail::parse_float(token, value)) return false;
      bits = std::bit_cast<std::uint32_t>(value);
      return true;
    }
    if (token.starts_with('-')) {
      std::int64_t value = 0;
      if (!detail::parse_signed(token, value) || value < INT32_MIN) return false;
      bits = static_cast<std::uint32_t>(value);
      return true;
    }
    std::uint64_t value = 0;
    if (!detail::parse_unsigned(token, value) || value > UINT32_MAX) return false;
    bits = static_cast<std::uint32_t>(value);
    return true;
  }

  void read_ascii(Scan& scan) {
    std::string_view line;
    std::uint64_t point = 0;
    const std::size_t wanted_fields = roles_.color ? 4 : 3;
    const std::size_t wanted[4] = {roles_.x, roles_.y, roles_.z, roles_.color.value_or(0)};
    while (point < point_count_) {
      if (!lines_->next_non_blank(line)) {
        throw FormatError::at_line(file_.name(), lines_->line_number() + 1,
                                   "truncated file: the file ends after " + std::to_string(point) + " of " +
                                       std::to_string(point_count_) + " points");
      }
      Tokens tokens(line);
      // Pick out the wanted tokens by position; count all of them.
      std::string_view values[4];
      std::uint64_t index = 0;
      for (std::string_view token = tokens.next(); !token.empty(); token = tokens.next(), ++index) {
        for (std::size_t k = 0; k < wanted_fields; ++k) {
          if (fields_[wanted[k]].first_token == index) values[k] = token;
        }
      }
      if (index != tokens_per_point_) {
        ascii_error("expected " + std::to_string(tokens_per_point_) + " values per point, found " +
                        std::to_string(index),
                    line);
      }
      Vec3f p;
      for (std::size_t axis = 0; axis < 3; ++axis) {
        if (!parse_coordinate(values[axis], fields_[wanted[axis]], p[axis])) {
          ascii_error("field '" + fields_[wanted[axis]].name + "' is " + quote(values[axis]) +
                          ", not a number of its type",
                      line);
        }
      }
      scan.points.push_back(p);
      if (roles_.color) {
        std::uint32_t bits = 0;
        if (!parse_packed_color(values[3], fields_[wanted[3]], bits)) {
          ascii_error("field '" + fields_[wanted[3]].name + "' is " + quote(values[3]) + ", not a packed color", line);
        }
        scan.colors.push_back(unpack_color(bits));
      }
      ++point;
      if (point % 4096 == 0) consumed_.store(lines_->offset(), std::memory_order_relaxed);
    }
    if (lines_->next_non_blank(line)) {
      throw FormatError::at_line(file_.name(), lines_->line_number(),
                                 "more data than the " + std::to_string(point_count_) +
                                     " points the header declares: " + quote(line));
    }
  }

  InputFile file_;
  std::string display_name_;
  Vec3f origin_;
  std::unique_ptr<LineReader> lines_;  // the header, then the ascii data
  PcdEncoding encoding_ = PcdEncoding::ascii;
  std::vector<PcdField> fields_;
  FieldRoles roles_;
  std::uint64_t record_bytes_ = 0;
  std::uint64_t tokens_per_point_ = 0;
  std::uint64_t point_count_ = 0;
  Pose viewpoint_;
  std::uint64_t data_line_ = 0;
  std::uint64_t data_offset_ = 0;
  std::uint64_t compressed_bytes_ = 0;
  std::atomic<std::uint64_t> consumed_{0};  // file offset reached, for progress()
};

}  // namespace

std::unique_ptr<ScanSource> open_pcd_file(const std::filesystem::path& path, Vec3f origin) {
  return detail::naming_bad_alloc(path, [&] { return std::make_unique<PcdReader>(path, origin); });
}

}  // namespace umbra
