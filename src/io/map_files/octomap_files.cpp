// OctoMap files: the public functions, the byte input, and the text header
// both formats share (the trees themselves are in octomap_bt.cpp and
// octomap_ot.cpp).
//
// The header is parsed the way liboctomap parses it — whitespace-separated
// tokens, `#` starts a comment up to the end of the line, unknown keywords
// are skipped with the rest of their line, `data` ends the header and the
// tree starts after the end of that line — but stricter about values: `res`
// and `size` must be whole numbers (no trailing text), `res` finite and > 0,
// and `id`, `res` and `size` must all be present. Cost: one pass over the
// header bytes; tokens longer than 64 bytes are not stored. Files are read
// through a 1 MiB buffer, never whole.
#include "umbra/io/octomap_files.hpp"

#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "umbra/io/file_saving.hpp"
#include "core/memory_budget.hpp"
#include "map/map_access.hpp"
#include "octomap_format.hpp"

namespace umbra {
namespace detail {
namespace {

namespace fs = std::filesystem;

/// Longest header token that is kept (longer keywords are unknown, longer values wrong).
constexpr std::size_t kMaxTokenBytes = 64;
/// The second and third lines liboctomap writes.
constexpr std::string_view kCommentLines =
    "# (feel free to add / change comments, but leave the first line as it is!)\n#\n";

bool is_space(int c) { return c == ' ' || c == '\t' || c == '\n' || c == '\v' || c == '\f' || c == '\r'; }

/// Reads the header token by token, counting lines.
class HeaderLexer {
 public:
  HeaderLexer(ByteReader& in, const std::string& name) : in_(in), name_(name) {}

  /// Skips whitespace; false at the end of the input.
  bool skip_space() {
    for (int c = in_.peek(); c >= 0; c = in_.peek()) {
      if (!is_space(c)) return true;
      if (c == '\n') ++line_;
      in_.get();
    }
    return false;
  }
  /// The next token (call after skip_space() returned true); `too_long` when it had more than 64 bytes.
  std::string token(bool& too_long) {
    std::string text;
    too_long = false;
    for (int c = in_.peek(); c >= 0 && !is_space(c); c = in_.peek()) {
      if (text.size() < kMaxTokenBytes) {
        text += static_cast<char>(c);
      } else {
        too_long = true;
      }
      in_.get();
    }
    return text;
  }
  /// Consumes the rest of the line, its '\n' included.
  void skip_line() {
    for (int c = in_.get(); c >= 0; c = in_.get()) {
      if (c == '\n') {
        ++line_;
        return;
      }
    }
  }
  /// The value after a keyword (on the same or a later line, as liboctomap allows).
  std::string value(const char* keyword) {
    if (!skip_space()) fail("the header ends after '" + std::string(keyword) + "' without its value");
    bool too_long = false;
    std::string text = token(too_long);
    if (too_long) fail("the value of '" + std::string(keyword) + "' is longer than 64 bytes: " + quote_bytes(text) + "...");
    return text;
  }

  [[nodiscard]] std::uint64_t line() const { return line_; }
  [[noreturn]] void fail(const std::string& message) const { fail_at(line_, message); }
  [[noreturn]] void fail_at(std::uint64_t line, const std::string& message) const {
    throw FormatError::at_line(name_, line, message);
  }

 private:
  ByteReader& in_;
  const std::string& name_;
  std::uint64_t line_ = 2;  // the first line is read before the lexer starts
};

/// Reads the first line and says which format it announces.
OctoMapFormat read_first_line(ByteReader& in, const std::string& name) {
  std::string start;
  const std::size_t longest = std::max(kBtFirstLine.size(), kOtFirstLine.size());
  for (int c = in.peek(); c >= 0 && c != '\n' && start.size() < longest; c = in.peek()) {
    start += static_cast<char>(c);
    in.get();
  }
  OctoMapFormat format;
  if (start.starts_with(kBtFirstLine)) {
    format = OctoMapFormat::bt;
  } else if (start.starts_with(kOtFirstLine)) {
    format = OctoMapFormat::ot;
  } else {
    throw FormatError::at_line(name, 1,
                               "not an OctoMap file: the first line must start with '" + std::string(kBtFirstLine) +
                                   "' (.bt) or '" + std::string(kOtFirstLine) + "' (.ot), found " +
                                   (in.size() == 0 ? std::string("an empty file") : quote_bytes(start, 40)));
  }
  for (int c = in.get(); c >= 0 && c != '\n'; c = in.get()) {
  }
  return format;
}

double parse_resolution(HeaderLexer& lexer, const std::string& text) {
  std::string_view digits = text;
  if (digits.size() > 1 && digits[0] == '+' && digits[1] != '-') digits.remove_prefix(1);  // as istream accepts
  double value = 0.0;
  const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (error != std::errc() || end != digits.data() + digits.size()) {
    lexer.fail("res must be a number (the voxel edge in metres), found " + quote_bytes(text));
  }
  if (!(value >= kMinResolution && value <= kMaxResolution)) {  // NaN fails this
    lexer.fail("res must be the voxel edge in metres, in [0.0001, 1000] (0.1 mm to 1 km), found " + quote_bytes(text));
  }
  return value;
}

std::uint64_t parse_size(HeaderLexer& lexer, const std::string& text) {
  std::uint64_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error == std::errc::result_out_of_range) lexer.fail("size " + quote_bytes(text) + " is too large");
  if (error != std::errc() || end != text.data() + text.size()) {
    lexer.fail("size must be a whole number >= 0 (the number of nodes), found " + quote_bytes(text));
  }
  return value;
}

}  // namespace

// --- header -------------------------------------------------------------------

Header parse_header(ByteReader& in, const std::string& name) {
  Header header;
  header.format = read_first_line(in, name);
  header.file_bytes = in.size();
  HeaderLexer lexer(in, name);
  std::string id;
  std::uint64_t id_line = 0;
  bool have_res = false;
  bool have_size = false;
  std::uint64_t data_line = 0;
  for (;;) {
    if (!lexer.skip_space()) {
      lexer.fail("the header ends without a 'data' line (the line after which the tree starts)");
    }
    const std::uint64_t line = lexer.line();
    bool too_long = false;
    const std::string token = lexer.token(too_long);
    if (too_long || token.starts_with('#')) {
      lexer.skip_line();  // a comment, or a keyword no one knows
    } else if (token == "data") {
      data_line = line;
      lexer.skip_line();
      break;
    } else if (token == "id") {
      id = lexer.value("id");
      id_line = line;
    } else if (token == "res") {
      header.resolution = parse_resolution(lexer, lexer.value("res"));
      have_res = true;
    } else if (token == "size") {
      header.nodes = parse_size(lexer, lexer.value("size"));
      header.size_line = line;
      have_size = true;
    } else {
      lexer.skip_line();  // liboctomap skips unknown keywords (with a warning) too
    }
  }
  if (id.empty()) lexer.fail_at(data_line, "the header has no 'id' line (the tree type, e.g. 'id OcTree')");
  if (!have_res) lexer.fail_at(data_line, "the header has no 'res' line (the voxel edge in metres)");
  if (!have_size) lexer.fail_at(data_line, "the header has no 'size' line (the number of nodes)");

  if (id == "1") id = "OcTree";  // the legacy id liboctomap still accepts
  if (const std::string problem = unreadable_tree_type(id); !problem.empty()) lexer.fail_at(id_line, problem);
  header.color = id == "ColorOcTree" && header.format == OctoMapFormat::ot;  // a .bt file carries no color
  header.tree_type = id;
  header.data_offset = in.offset();
  return header;
}

std::string unreadable_tree_type(const std::string& id) {
  if (id == "OcTree" || id == "OcTreeStamped" || id == "ColorOcTree") return "";
  if (id == "OcTreeBase" || id == "CountingOcTree") {
    return "tree type " + quote_bytes(id) +
           " is a CountingOcTree (liboctomap registers it as 'OcTreeBase'): it counts hits, it holds no occupancy; "
           "umbra reads the occupancy trees OcTree, OcTreeStamped and ColorOcTree";
  }
  return "unknown tree type " + quote_bytes(id) +
         ": umbra reads the occupancy trees liboctomap 1.9.7 knows: OcTree, OcTreeStamped, ColorOcTree (and the "
         "legacy id '1', an OcTree)";
}

std::uint64_t count_tree_nodes(const Header& header, std::span<const std::uint8_t> data, const std::string& name) {
  if (header.format == OctoMapFormat::ot) {
    const std::size_t node_bytes = header.color ? 8 : 5;
    if (data.size() % node_bytes != 0) {
      throw FormatError::at_byte(name, data.size() - data.size() % node_bytes,
                                 "the tree data ends inside a node: " + std::to_string(data.size()) +
                                     " bytes are not a whole number of " + std::to_string(node_bytes) + "-byte " +
                                     header.tree_type + " nodes (truncated data?)");
    }
    return data.size() / node_bytes;
  }
  if (data.size() % 2 != 0) {
    throw FormatError::at_byte(name, data.size() - 1,
                               "the .bt tree data has an odd number of bytes (" + std::to_string(data.size()) +
                                   "): every node with children takes 2 (truncated data?)");
  }
  if (data.empty()) return 0;
  // Every node but the root appears once as a non-zero 2-bit code in its parent's pair.
  std::uint64_t nodes = 1;
  for (const std::uint8_t byte : data) {
    for (unsigned shift = 0; shift < 8; shift += 2) nodes += ((byte >> shift) & 3u) != 0 ? 1 : 0;
  }
  return nodes;
}

std::string resolution_text(double resolution) {
  char text[64];
  // What `std::ostream << double` writes with its default precision (%g, 6 digits).
  std::snprintf(text, sizeof text, "%g", resolution);
  double back = 0.0;
  const std::string_view short_text(text);
  const auto parsed = std::from_chars(short_text.data(), short_text.data() + short_text.size(), back);
  if (parsed.ec == std::errc() && back == resolution) return text;
  const auto written = std::to_chars(text, text + sizeof text, resolution);  // shortest exact form
  return std::string(text, written.ptr);
}

std::string header_text(OctoMapFormat format, std::string_view id, std::uint64_t size, double resolution) {
  std::string text(format == OctoMapFormat::bt ? kBtFirstLine : kOtFirstLine);
  text += '\n';
  text += kCommentLines;
  text += "id ";
  text += id;
  text += "\nsize " + std::to_string(size) + "\nres " + resolution_text(resolution) + "\ndata\n";
  return text;
}

// --- size against the file length ---------------------------------------------------

void check_declared_size(const Header& header, const std::string& name) {
  const std::uint64_t data_bytes = header.file_bytes - header.data_offset;
  const std::uint64_t nodes = header.nodes;
  auto fail = [&](const std::string& message) -> FormatError {
    return FormatError::at_line(name, header.size_line, message);
  };
  if (header.format == OctoMapFormat::ot) {
    // Every node is its data (4 bytes of log-odds, 3 of color in a ColorOcTree) and a child mask byte.
    const std::uint64_t node_bytes = header.color ? 8 : 5;
    if (data_bytes % node_bytes == 0 && data_bytes / node_bytes == nodes) return;
    throw fail("size says " + std::to_string(nodes) + " nodes of " + std::to_string(node_bytes) + " bytes (" +
               header.tree_type + "), but " + std::to_string(data_bytes) +
               " bytes follow the header (the file is truncated, has trailing bytes, or the size is wrong)");
  }
  // .bt: every node with children takes 2 bytes (the root's come first) and has 1 to 8 children.
  const std::uint64_t with_children = data_bytes / 2;
  if (nodes == 0 && data_bytes == 0) return;
  if (nodes == 0) {
    throw fail("size is 0 (an empty tree), but " + std::to_string(data_bytes) + " bytes follow the header");
  }
  if (data_bytes == 0) {
    throw fail("size says " + std::to_string(nodes) + " nodes, but no bytes follow the header");
  }
  const std::uint64_t most = with_children > (UINT64_MAX - 1) / 8 ? UINT64_MAX : 8 * with_children + 1;
  if (nodes < with_children || nodes > most) {
    throw fail("size says " + std::to_string(nodes) + " nodes, but the " + std::to_string(data_bytes) +
               " bytes after the header describe " + std::to_string(with_children) +
               " nodes with children, so between " + std::to_string(with_children) + " and " + std::to_string(most) +
               " nodes (the file is truncated, has trailing bytes, or the size is wrong)");
  }
}

// --- memory ---------------------------------------------------------------------------

std::uint64_t tree_bytes(const Header& header, std::uint64_t parents) {
  const std::uint64_t group = sizeof(OccupancyTree::InnerGroup) + (header.color ? sizeof(OccupancyTree::ColorGroup) : 0);
  return parents > UINT64_MAX / group ? UINT64_MAX : parents * group;
}

void require_tree_memory(const Header& header, const std::string& name, std::uint64_t parents) {
  detail::require_memory(name,
                         "loading this OctoMap tree (" + std::to_string(header.nodes) + " nodes, " +
                             std::to_string(parents) + " with children)",
                         tree_bytes(header, parents));
}

// --- helpers --------------------------------------------------------------------

void require_octomap_depth(const OccupancyMap& map, const std::string& what) {
  if (map.depth_levels() == kOctoMapDepthLevels) return;
  throw std::invalid_argument(what + ": OctoMap files always hold a tree of 16 depth levels (their keys and the "
                              "map's extent depend on it), and this map has " +
                              std::to_string(map.depth_levels()) +
                              "; only maps made with depth_levels = 16 can be written as .bt or .ot");
}

OccupancyMap new_map(const Header& header, const std::string& name, const SensorModel& sensor, bool color) {
  MapConfig config;
  config.resolution = header.resolution;
  config.depth_levels = kOctoMapDepthLevels;
  config.sensor = sensor;
  config.color = color;
  try {
    return OccupancyMap(config);
  } catch (const std::invalid_argument& e) {
    throw FormatError(name, std::string("cannot make a map of this file's resolution: ") + e.what());
  }
}

}  // namespace detail

// --- public functions -------------------------------------------------------------

namespace {

OccupancyMap decode(detail::ByteReader& in, const std::string& name, const SensorModel& sensor) {
  sensor.validate();
  const detail::Header header = detail::parse_header(in, name);
  // The decoders check the tree's need against the memory limit first; this names an allocation that fails anyway.
  return detail::naming_bad_alloc(name, "loading the OctoMap tree (" + std::to_string(header.nodes) + " nodes)", 0, [&] {
    return header.format == OctoMapFormat::bt ? detail::decode_bt(in, header, name, sensor)
                                              : detail::decode_ot(in, header, name, sensor);
  });
}

struct EncodedFile {
  std::string header;
  detail::EncodedTree tree;
};

const char* tree_id(const OccupancyMap& map, OctoMapFormat format) {
  return format == OctoMapFormat::ot && map.has_color() ? "ColorOcTree" : "OcTree";
}

EncodedFile encode(const OccupancyMap& map, OctoMapFormat format, const std::string& what) {
  detail::require_octomap_depth(map, what);
  EncodedFile file;
  file.tree = format == OctoMapFormat::bt ? detail::encode_bt(map) : detail::encode_ot(map);
  file.header = detail::header_text(format, tree_id(map, format), file.tree.nodes, map.resolution());
  return file;
}

}  // namespace

const char* to_string(OctoMapFormat format) { return format == OctoMapFormat::bt ? "bt" : "ot"; }

OccupancyMap load_octomap(const std::filesystem::path& path, const SensorModel& sensor) {
  const detail::InputFile file(path, {}, "map file");
  detail::ByteReader in(file, 0);
  return decode(in, path.string(), sensor);
}

OccupancyMap decode_octomap(std::span<const std::uint8_t> bytes, const std::string& name, const SensorModel& sensor) {
  detail::ByteReader in(bytes);
  return decode(in, name, sensor);
}

OctoMapFileInfo read_octomap_info(const std::filesystem::path& path) {
  const detail::InputFile file(path, {}, "map file");
  detail::ByteReader in(file, 0);
  const std::string name = path.string();
  const detail::Header header = detail::parse_header(in, name);
  detail::check_declared_size(header, name);
  OctoMapFileInfo info = header;
  return info;
}

std::vector<std::uint8_t> encode_octomap(const OccupancyMap& map, OctoMapFormat format) {
  EncodedFile file = encode(map, format, "encode_octomap");
  std::vector<std::uint8_t> bytes(file.header.begin(), file.header.end());
  bytes.insert(bytes.end(), file.tree.bytes.begin(), file.tree.bytes.end());
  return bytes;
}

OctoMapTreeData encode_octomap_tree(const OccupancyMap& map, OctoMapFormat format) {
  EncodedFile file = encode(map, format, "encode_octomap_tree");
  return {format, tree_id(map, format), map.resolution(), std::move(file.tree.bytes)};
}

OccupancyMap decode_octomap_tree(OctoMapFormat format, const std::string& id, double resolution,
                                 std::span<const std::uint8_t> data, const std::string& name,
                                 const SensorModel& sensor) {
  sensor.validate();
  detail::Header header;
  header.format = format;
  header.tree_type = id == "1" ? std::string("OcTree") : id;
  if (const std::string problem = detail::unreadable_tree_type(header.tree_type); !problem.empty()) {
    throw FormatError(name, problem);
  }
  header.color = header.tree_type == "ColorOcTree" && format == OctoMapFormat::ot;
  if (!(std::isfinite(resolution) && resolution > 0.0 && std::isfinite(1.0 / resolution))) {
    throw FormatError(name, "the resolution must be a finite number > 0 (the voxel edge in metres), got " +
                                detail::resolution_text(resolution));
  }
  header.resolution = resolution;
  header.file_bytes = data.size();
  header.data_offset = 0;
  header.nodes = detail::count_tree_nodes(header, data, name);
  detail::ByteReader in(data);
  return format == OctoMapFormat::bt ? detail::decode_bt(in, header, name, sensor)
                                     : detail::decode_ot(in, header, name, sensor);
}

void save_octomap(const OccupancyMap& map, const std::filesystem::path& path, OctoMapFormat format) {
  const EncodedFile file = encode(map, format, "cannot save '" + path.string() + "'");
  const std::span<const std::uint8_t> header(reinterpret_cast<const std::uint8_t*>(file.header.data()),
                                             file.header.size());
  write_file_atomically(path, {header, std::span<const std::uint8_t>(file.tree.bytes)}, "map");
}

}  // namespace umbra
