// Reader for PLY files (.ply): ascii, binary little-endian and big-endian.
//
// Opening parses the header (line by line, with line numbers in every
// error), checks that the vertex element has scalar x, y and z properties
// and that every element's declared count fits in the bytes after the
// header (binary: count x the element's minimum record size; ascii: count x
// the shortest possible line), so no count can cause an allocation larger
// than the file. next() then walks all elements in file order through one
// 1 MiB buffer: vertex records are decoded at precomputed offsets (records
// with list properties are walked property by property), other elements are
// skipped (binary: fixed-size ones in one seek, ones with lists instance by
// instance) and ascii lines are split in place and parsed with from_chars.
// Cost: one pass over the file, O(vertices) output, no per-point allocation.
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "reader_support.hpp"
#include "umbra/io/format_error.hpp"
#include "umbra/io/ply_file.hpp"
#include "umbra/io/scan_source.hpp"

namespace umbra {
namespace {

using detail::ByteReader;
using detail::InputFile;
using detail::LineReader;
using detail::quote;
using detail::ScalarKind;
using detail::ScalarType;
using detail::Tokens;

enum class PlyEncoding { ascii, binary_little_endian, binary_big_endian };

/// What a vertex property is used for.
enum class Role : std::uint8_t { none, x, y, z, red, green, blue };

struct PlyProperty {
  std::string name;
  ScalarType type;  // for lists: the item type
  bool is_list = false;
  ScalarType count_type;  // lists only
  Role role = Role::none;
  std::size_t offset = 0;  // byte offset in a record without lists
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::uint64_t header_line = 0;
  std::vector<PlyProperty> properties;
  bool has_lists = false;
  std::uint64_t min_record_bytes = 0;  // scalars + list counts (binary)
  std::uint64_t min_tokens = 0;        // scalars + list counts (ascii)
};

std::optional<ScalarType> scalar_type_named(std::string_view name) {
  struct Named {
    std::string_view name;
    ScalarType type;
  };
  static constexpr std::array<Named, 16> kTypes{{
      {"char", {ScalarKind::signed_integer, 1}},    {"int8", {ScalarKind::signed_integer, 1}},
      {"uchar", {ScalarKind::unsigned_integer, 1}}, {"uint8", {ScalarKind::unsigned_integer, 1}},
      {"short", {ScalarKind::signed_integer, 2}},   {"int16", {ScalarKind::signed_integer, 2}},
      {"ushort", {ScalarKind::unsigned_integer, 2}}, {"uint16", {ScalarKind::unsigned_integer, 2}},
      {"int", {ScalarKind::signed_integer, 4}},     {"int32", {ScalarKind::signed_integer, 4}},
      {"uint", {ScalarKind::unsigned_integer, 4}},  {"uint32", {ScalarKind::unsigned_integer, 4}},
      {"float", {ScalarKind::floating_point, 4}},   {"float32", {ScalarKind::floating_point, 4}},
      {"double", {ScalarKind::floating_point, 8}},  {"float64", {ScalarKind::floating_point, 8}},
  }};
  for (const Named& entry : kTypes) {
    if (entry.name == name) return entry.type;
  }
  return std::nullopt;
}

constexpr const char* kTypeList =
    "char uchar short ushort int uint float double, or int8 uint8 int16 uint16 int32 uint32 float32 float64";

Role role_named(std::string_view name) {
  if (name == "x") return Role::x;
  if (name == "y") return Role::y;
  if (name == "z") return Role::z;
  if (name == "red" || name == "diffuse_red") return Role::red;
  if (name == "green" || name == "diffuse_green") return Role::green;
  if (name == "blue" || name == "diffuse_blue") return Role::blue;
  return Role::none;
}

std::uint8_t color_channel(double value, ScalarType type) {
  double channel = value;
  if (type.kind == ScalarKind::floating_point) {
    channel = std::round(value * 255.0);
  } else if (type.kind == ScalarKind::unsigned_integer && type.bytes == 2) {
    channel = std::round(value / 257.0);
  }
  if (!(channel >= 0.0)) return 0;  // also NaN
  return static_cast<std::uint8_t>(std::min(channel, 255.0));
}

class PlyReader final : public detail::SingleScanSource {
 public:
  PlyReader(const std::filesystem::path& path, Vec3f origin)
      : file_(path), display_name_(path.filename().string()), origin_(origin) {
    if (detail::has_bz2_suffix(path)) {
      throw FormatError(file_.name(), "compressed PLY files are not supported; decompress it first (bunzip2)");
    }
    lines_ = std::make_unique<LineReader>(file_, 0);
    parse_header();
    const std::uint64_t count = elements_[vertex_element_].count;
    detail::require_point_memory(file_.name(), "reading its " + std::to_string(count) + " vertices", count,
                                    has_colors_);
  }

  [[nodiscard]] std::vector<Vec3f> origins() const override { return {origin_}; }

 private:
  [[nodiscard]] std::uint64_t input_bytes() const override { return file_.size(); }
  [[nodiscard]] std::uint64_t bytes_consumed() const override { return consumed_.load(std::memory_order_relaxed); }

  void read_scan(Scan& scan) override {
    scan.origin = origin_;
    scan.points.clear();
    scan.colors.clear();
    scan.stamp.reset();  // this format carries no times
    scan.name = display_name_;
    // Safe: the count was checked against the file size when it was opened.
    scan.points.reserve(static_cast<std::size_t>(elements_[vertex_element_].count));
    if (has_colors_) scan.colors.reserve(static_cast<std::size_t>(elements_[vertex_element_].count));
    if (encoding_ == PlyEncoding::ascii) {
      read_ascii(scan);
    } else {
      read_binary(scan);
    }
  }

  // --- header ---

  [[noreturn]] void header_error(const std::string& message) const {
    throw FormatError::at_line(file_.name(), lines_->line_number(), message);
  }

  void parse_header() {
    std::string_view line;
    if (!lines_->next(line) || line != "ply") {
      throw FormatError::at_line(file_.name(), 1,
                                 "not a PLY file: the first line must be 'ply', found " +
                                     (lines_->line_number() == 0 ? std::string("an empty file") : quote(line)));
    }
    bool have_format = false;
    while (true) {
      if (!lines_->next(line)) {
        throw FormatError::at_line(file_.name(), lines_->line_number(),
                                   "the PLY header ends without an 'end_header' line (truncated file?)");
      }
      Tokens tokens(line);
      const std::string_view keyword = tokens.next();
      if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
      if (keyword == "end_header") break;
      if (keyword == "format") {
        if (have_format) header_error("a second 'format' line");
        const std::string_view encoding = tokens.next();
        const std::string_view version = tokens.next();
        if (encoding == "ascii") {
          encoding_ = PlyEncoding::ascii;
        } else if (encoding == "binary_little_endian") {
          encoding_ = PlyEncoding::binary_little_endian;
        } else if (encoding == "binary_big_endian") {
          encoding_ = PlyEncoding::binary_big_endian;
        } else {
          header_error("unknown PLY format " + quote(encoding) +
                       "; expected ascii, binary_little_endian or binary_big_endian");
        }
        if (version != "1.0" || !tokens.at_end()) {
          header_error("expected 'format " + std::string(encoding) + " 1.0', found " + quote(line));
        }
        have_format = true;
      } else if (keyword == "element") {
        if (!have_format) header_error("'element' before the 'format' line");
        PlyElement element;
        element.name = std::string(tokens.next());
        const std::string_view count = tokens.next();
        if (element.name.empty() || !detail::parse_unsigned(count, element.count) || !tokens.at_end()) {
          header_error("expected 'element NAME COUNT' with a non-negative integer count, found " + quote(line));
        }
        element.header_line = lines_->line_number();
        elements_.push_back(std::move(element));
      } else if (keyword == "property") {
        if (elements_.empty()) header_error("'property' before any 'element' line");
        elements_.back().properties.push_back(parse_property(tokens, line));
      } else {
        header_error("unknown PLY header line " + quote(line));
      }
    }
    if (!have_format) header_error("the PLY header has no 'format' line");
    data_offset_ = lines_->offset();
    consumed_.store(data_offset_, std::memory_order_relaxed);
    check_vertex_element();
    check_counts();
  }

  PlyProperty parse_property(Tokens& tokens, std::string_view line) {
    PlyProperty property;
    std::string_view type_name = tokens.next();
    if (type_name == "list") {
      property.is_list = true;
      const std::string_view count_type_name = tokens.next();
      const auto count_type = scalar_type_named(count_type_name);
      if (!count_type || count_type->kind == ScalarKind::floating_point) {
        header_error("list count type " + quote(count_type_name) +
                     " is not an integer type (char uchar short ushort int uint ...), in " + quote(line));
      }
      property.count_type = *count_type;
      type_name = tokens.next();
    }
    const auto type = scalar_type_named(type_name);
    if (!type) header_error("unknown property type " + quote(type_name) + " (PLY types: " + kTypeList + "), in " + quote(line));
    property.type = *type;
    property.name = std::string(tokens.next());
    if (property.name.empty() || !tokens.at_end()) {
      header_error("expected 'property TYPE NAME' or 'property list COUNT_TYPE TYPE NAME', found " + quote(line));
    }
    return property;
  }

  void check_vertex_element() {
    const auto vertex = std::find_if(elements_.begin(), elements_.end(),
                                     [](const PlyElement& element) { return element.name == "vertex"; });
    if (vertex == elements_.end()) {
      throw FormatError(file_.name(), "the PLY header declares no 'vertex' element, so there are no points");
    }
    vertex_element_ = static_cast<std::size_t>(vertex - elements_.begin());
    std::array<const PlyProperty*, 7>& by_role = vertex_roles_;
    for (PlyProperty& property : vertex->properties) {
      const Role role = role_named(property.name);
      if (role == Role::none) continue;
      const auto index = static_cast<std::size_t>(role);
      if (by_role[index] != nullptr) {
        // Two sources for one channel (e.g. red and diffuse_red): use the first.
        if (role == Role::x || role == Role::y || role == Role::z || property.name == by_role[index]->name) {
          throw FormatError::at_line(file_.name(), vertex->header_line,
                                     "the vertex element has two '" + property.name + "' properties");
        }
        continue;
      }
      if (property.is_list) {
        throw FormatError::at_line(file_.name(), vertex->header_line,
                                   "the vertex property '" + property.name + "' is a list, expected a number");
      }
      property.role = role;
      by_role[index] = &property;
    }
    for (const Role role : {Role::x, Role::y, Role::z}) {
      if (by_role[static_cast<std::size_t>(role)] == nullptr) {
        const char* names[] = {"", "x", "y", "z"};
        throw FormatError::at_line(file_.name(), vertex->header_line,
                                   std::string("the vertex element (declared here) has no '") +
                                       names[static_cast<std::size_t>(role)] + "' property");
      }
    }
    const int color_channels = (by_role[4] != nullptr) + (by_role[5] != nullptr) + (by_role[6] != nullptr);
    if (color_channels != 0 && color_channels != 3) {
      throw FormatError::at_line(file_.name(), vertex->header_line,
                                 "the vertex element has only some of the color properties red, green, blue");
    }
    has_colors_ = color_channels == 3;
  }

  /// Every element's count against the bytes after the header.
  void check_counts() {
    std::uint64_t offset = data_offset_;
    for (PlyElement& element : elements_) {
      std::size_t record_offset = 0;
      for (PlyProperty& property : element.properties) {
        property.offset = record_offset;
        if (property.is_list) {
          element.has_lists = true;
          element.min_record_bytes += property.count_type.bytes;
        } else {
          element.min_record_bytes += property.type.bytes;
          record_offset += property.type.bytes;
        }
        ++element.min_tokens;
      }
      const std::uint64_t remaining = file_.size() - std::min(file_.size(), offset);
      if (encoding_ == PlyEncoding::ascii) {
        // Each instance is a line of min_tokens tokens: at least 2 bytes per
        // token with the separators and line break (one less on the last line).
        const std::uint64_t line_bytes = 2 * element.min_tokens;
        if (line_bytes != 0 && element.count > (remaining + 1) / line_bytes) {
          throw FormatError::at_line(
              file_.name(), element.header_line,
              "element '" + element.name + "' declares " + std::to_string(element.count) + " instances of " +
                  std::to_string(element.min_tokens) + " values, which need at least " +
                  std::to_string(line_bytes) + " bytes per line, but only " + std::to_string(remaining) +
                  " bytes follow the header (and the elements before it) (truncated file or wrong count)");
        }
        // Ascii elements take at least a line each; later elements start after them.
        offset += element.count * line_bytes;
      } else {
        if (element.min_record_bytes != 0 && element.count > remaining / element.min_record_bytes) {
          throw FormatError::at_byte(
              file_.name(), offset,
              "element '" + element.name + "' (header line " + std::to_string(element.header_line) +
                  ") declares " + std::to_string(element.count) + " instances of at least " +
                  std::to_string(element.min_record_bytes) + " bytes, which need " +
                  (element.count > UINT64_MAX / element.min_record_bytes
                       ? std::string("more than 2^64")
                       : std::to_string(element.count * element.min_record_bytes)) +
                  " bytes, but only " + std::to_string(remaining) +
                  " bytes remain in the file (truncated file or wrong count)");
        }
        offset += element.count * element.min_record_bytes;
      }
    }
  }

  // --- binary data ---

  [[noreturn]] void truncated(const ByteReader& reader, const PlyElement& element, std::uint64_t instance,
                              const std::string& what) const {
    throw FormatError::at_byte(file_.name(), reader.offset(),
                               "truncated file: element '" + element.name + "' instance " + std::to_string(instance) +
                                   " of " + std::to_string(element.count) + ": expected " + what +
                                   ", but the file ends");
  }

  void read_binary(Scan& scan) {
    const bool big_endian = encoding_ == PlyEncoding::binary_big_endian;
    ByteReader reader(file_, data_offset_);
    constexpr std::uint64_t kProgressStride = 4096;
    for (std::size_t index = 0; index < elements_.size(); ++index) {
      const PlyElement& element = elements_[index];
      if (index == vertex_element_) {
        read_binary_vertices(reader, element, big_endian, scan);
      } else if (!element.has_lists) {
        if (!reader.skip(element.count * element.min_record_bytes)) {  // checked product, see check_counts
          const std::uint64_t complete = reader.remaining() / element.min_record_bytes;
          reader.skip(complete * element.min_record_bytes);
          truncated(reader, element, complete, std::to_string(element.min_record_bytes) + " bytes");
        }
      } else {
        for (std::uint64_t instance = 0; instance < element.count; ++instance) {
          skip_binary_instance(reader, element, instance, big_endian);
          if (instance % kProgressStride == 0) consumed_.store(reader.offset(), std::memory_order_relaxed);
        }
      }
      consumed_.store(reader.offset(), std::memory_order_relaxed);
    }
  }

  void skip_binary_instance(ByteReader& reader, const PlyElement& element, std::uint64_t instance,
                            bool big_endian) const {
    for (const PlyProperty& property : element.properties) {
      if (!property.is_list) {
        if (!reader.skip(property.type.bytes)) truncated(reader, element, instance, "property '" + property.name + "'");
        continue;
      }
      const unsigned char* count_bytes = reader.take(property.count_type.bytes);
      if (count_bytes == nullptr) truncated(reader, element, instance, "the length of list '" + property.name + "'");
      const double length = detail::load_scalar(count_bytes, property.count_type, big_endian);
      if (length < 0) {
        throw FormatError::at_byte(file_.name(), reader.offset() - property.count_type.bytes,
                                   "element '" + element.name + "' instance " + std::to_string(instance) +
                                       ": list '" + property.name + "' has the negative length " +
                                       std::to_string(static_cast<std::int64_t>(length)));
      }
      if (!reader.skip(static_cast<std::uint64_t>(length) * property.type.bytes)) {
        truncated(reader, element, instance, std::to_string(static_cast<std::uint64_t>(length)) +
                                                 " items of list '" + property.name + "'");
      }
    }
  }

  void read_binary_vertices(ByteReader& reader, const PlyElement& element, bool big_endian, Scan& scan) {
    const auto record_bytes = static_cast<std::size_t>(element.min_record_bytes);
    std::array<double, 7> values{};
    for (std::uint64_t instance = 0; instance < element.count; ++instance) {
      if (element.has_lists) {
        read_vertex_with_lists(reader, element, instance, big_endian, values);
      } else {
        const unsigned char* record = reader.take(record_bytes);
        if (record == nullptr) truncated(reader, element, instance, std::to_string(record_bytes) + " bytes");
        for (std::size_t role = 1; role < (has_colors_ ? 7U : 4U); ++role) {
          const PlyProperty& property = *vertex_roles_[role];
          values[role] = detail::load_scalar(record + property.offset, property.type, big_endian);
        }
      }
      scan.points.push_back({static_cast<float>(values[1]), static_cast<float>(values[2]), static_cast<float>(values[3])});
      if (has_colors_) push_color(values, scan);
      if (instance % 65536 == 0) consumed_.store(reader.offset(), std::memory_order_relaxed);
    }
  }

  /// Walks one vertex record that has list properties, property by property.
  void read_vertex_with_lists(ByteReader& reader, const PlyElement& element, std::uint64_t instance,
                              bool big_endian, std::array<double, 7>& values) const {
    for (const PlyProperty& property : element.properties) {
      if (property.is_list) {
        const unsigned char* count_bytes = reader.take(property.count_type.bytes);
        if (count_bytes == nullptr) truncated(reader, element, instance, "the length of list '" + property.name + "'");
        const double length = detail::load_scalar(count_bytes, property.count_type, big_endian);
        if (length < 0) {
          throw FormatError::at_byte(file_.name(), reader.offset() - property.count_type.bytes,
                                     "vertex " + std::to_string(instance) + ": list '" + property.name +
                                         "' has a negative length");
        }
        if (!reader.skip(static_cast<std::uint64_t>(length) * property.type.bytes)) {
          truncated(reader, element, instance, "the items of list '" + property.name + "'");
        }
        continue;
      }
      const unsigned char* bytes = reader.take(property.type.bytes);
      if (bytes == nullptr) truncated(reader, element, instance, "property '" + property.name + "'");
      if (property.role != Role::none) {
        values[static_cast<std::size_t>(property.role)] = detail::load_scalar(bytes, property.type, big_endian);
      }
    }
  }

  void push_color(const std::array<double, 7>& values, Scan& scan) const {
    scan.colors.push_back({color_channel(values[4], vertex_roles_[4]->type),
                           color_channel(values[5], vertex_roles_[5]->type),
                           color_channel(values[6], vertex_roles_[6]->type)});
  }

  // --- ascii data ---

  /// The next non-blank line, or a FormatError naming the missing instance.
  std::string_view next_data_line(const PlyElement& element, std::uint64_t instance) {
    std::string_view line;
    if (lines_->next_non_blank(line)) return line;
    throw FormatError::at_line(file_.name(), lines_->line_number() + 1,
                               "truncated file: the file ends before element '" + element.name + "' instance " +
                                   std::to_string(instance) + " of " + std::to_string(element.count));
  }

  [[noreturn]] void ascii_error(const std::string& message, std::string_view line) const {
    throw FormatError::at_line(file_.name(), lines_->line_number(), message + ", in " + quote(line));
  }

  void read_ascii(Scan& scan) {
    constexpr std::uint64_t kProgressStride = 4096;
    for (std::size_t index = 0; index < elements_.size(); ++index) {
      const PlyElement& element = elements_[index];
      const bool is_vertex = index == vertex_element_;
      if (element.properties.empty()) continue;  // instances without data take no line
      for (std::uint64_t instance = 0; instance < element.count; ++instance) {
        const std::string_view line = next_data_line(element, instance);
        Tokens tokens(line);
        std::array<double, 7> values{};
        std::array<float, 4> coordinates{};
        for (const PlyProperty& property : element.properties) {
          if (property.is_list) {
            const std::string_view count_token = tokens.next();
            double length = 0;
            if (count_token.empty()) ascii_error("too few values for element '" + element.name + "'", line);
            if (!detail::parse_scalar(count_token, property.count_type, length) || length < 0) {
              ascii_error("the length of list '" + property.name + "' is " + quote(count_token) +
                              ", not a non-negative integer",
                          line);
            }
            for (auto item = static_cast<std::uint64_t>(length); item > 0; --item) {
              if (tokens.next().empty()) {
                ascii_error("list '" + property.name + "' declares " + std::to_string(static_cast<std::uint64_t>(length)) +
                                " items but the line ends early",
                            line);
              }
            }
            continue;
          }
          const std::string_view token = tokens.next();
          if (token.empty()) ascii_error("too few values for element '" + element.name + "'", line);
          if (!is_vertex || property.role == Role::none) continue;
          const auto role = static_cast<std::size_t>(property.role);
          bool ok = false;
          if (role <= 3 && property.type.kind == ScalarKind::floating_point && property.type.bytes == 4) {
            ok = detail::parse_float(token, coordinates[role]);
            values[role] = coordinates[role];
          } else {
            ok = detail::parse_scalar(token, property.type, values[role]);
            if (role <= 3) coordinates[role] = static_cast<float>(values[role]);
          }
          if (!ok) ascii_error("property '" + property.name + "' is " + quote(token) + ", not a number of its type", line);
        }
        if (!tokens.at_end()) {
          ascii_error("more values than element '" + element.name + "' has properties (" +
                          std::to_string(tokens.count_left()) + " left over)",
                      line);
        }
        if (is_vertex) {
          scan.points.push_back({coordinates[1], coordinates[2], coordinates[3]});
          if (has_colors_) push_color(values, scan);
        }
        if (instance % kProgressStride == 0) consumed_.store(lines_->offset(), std::memory_order_relaxed);
      }
    }
    std::string_view line;
    if (lines_->next_non_blank(line)) {
      throw FormatError::at_line(file_.name(), lines_->line_number(),
                                 "unexpected data after the last element (do the header counts match?): " +
                                     quote(line));
    }
  }

  InputFile file_;
  std::string display_name_;
  Vec3f origin_;
  std::unique_ptr<LineReader> lines_;  // the header, then the ascii data
  PlyEncoding encoding_ = PlyEncoding::ascii;
  std::vector<PlyElement> elements_;
  std::size_t vertex_element_ = 0;
  std::array<const PlyProperty*, 7> vertex_roles_{};  // by Role; points into elements_ (fixed after the header)
  bool has_colors_ = false;
  std::uint64_t data_offset_ = 0;
  std::atomic<std::uint64_t> consumed_{0};  // file offset reached, for progress()
};

}  // namespace

std::unique_ptr<ScanSource> open_ply_file(const std::filesystem::path& path, Vec3f origin) {
  return detail::naming_bad_alloc(path, [&] { return std::make_unique<PlyReader>(path, origin); });
}

}  // namespace umbra
