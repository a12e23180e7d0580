// OctoMap's full tree (.ot): decoder and encoder of the data after the header.
//
// Layout (liboctomap's readNodesRecurs/writeNodesRecurs): depth first from
// the root, every node is its data — the float log-odds, little-endian,
// then in a ColorOcTree the color r, g, b — and a byte whose bit i says
// that child i exists; the existing children follow in child order.
// OcTreeStamped nodes have the OcTree layout (liboctomap 1.9.7 does not
// store the timestamp).
//
// Reading: leaves keep their float bits (a leaf of exactly 0 is unknown in
// umbra; -0 is stored as 0); children that do not exist stay unknown; inner
// values and colors in the file are checked to be finite numbers and
// otherwise not used (umbra recomputes them). A color of white (255, 255,
// 255) is "no color", as in liboctomap. Log-odds beyond the sensor model's
// clamping range widen the map's clamping range (see octomap_files.hpp).
// Writing: a node whose subtree is entirely 0 is left out; an inner node
// gets the maximum of the children written and the truncating average of
// their set colors (white if none), as liboctomap's updateInnerOccupancy.
//
// Cost: one depth-first pass either way, recursion at most 17 deep, no
// per-node allocation (the output grows amortised; a left-out subtree's
// bytes are dropped by shrinking it back).
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <optional>

#include "map/map_access.hpp"
#include "octomap_format.hpp"
#include "umbra/core/memory_limit.hpp"

namespace umbra::detail {
namespace {

constexpr Rgb kNoColor{255, 255, 255};

std::size_t node_bytes(bool color) { return color ? 8 : 5; }

float get_float(const std::uint8_t* p) {
  std::uint32_t bits = 0;
  for (int i = 3; i >= 0; --i) bits = (bits << 8) | p[i];
  return std::bit_cast<float>(bits);
}

void put_float(std::uint8_t* p, float value) {
  const auto bits = std::bit_cast<std::uint32_t>(value);
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(bits >> (8 * i));
}

/// A clamping probability whose log-odds (as the map computes them, rounded to
/// float) reach past `value`: at least it for the upper end, at most it for
/// the lower end. Nothing when no probability in (0, 1) does.
std::optional<double> clamp_probability_covering(float value, bool upper) {
  // Computed on the side that keeps precision: p for negative log-odds, 1 - p for positive ones.
  const double v = value;
  double p = v < 0 ? std::exp(v) / (1.0 + std::exp(v)) : 1.0 / (1.0 + std::exp(-v));
  for (int step = 0; step < 64; ++step) {
    if (!(p > 0.0 && p < 1.0)) return std::nullopt;
    const float reached = logit(p);
    if (upper ? reached >= value : reached <= value) return p;
    p = std::nextafter(p, upper ? 1.0 : 0.0);
  }
  return std::nullopt;
}

/// The nodes whose child mask (the last byte of each fixed-size record) is not 0, counted
/// on an input of its own from where `in` is.
std::uint64_t count_parents(const ByteReader& in, std::uint64_t nodes, std::size_t record_bytes) {
  ByteReader records(in, in.offset());
  std::array<std::uint8_t, 8> record{};
  std::uint64_t parents = 0;
  for (std::uint64_t node = 0; node < nodes && records.read(record.data(), record_bytes); ++node) {
    parents += record[record_bytes - 1] != 0 ? 1 : 0;
  }
  return parents;
}

class OtDecoder {
 public:
  OtDecoder(ByteReader& in, const std::string& name, detail::TreeBuilder& tree, bool color)
      : in_(in), name_(name), tree_(tree), color_(color), node_bytes_(node_bytes(color)) {}

  void run(std::uint64_t declared_nodes) {
    if (declared_nodes > 0) decode(tree_.root(), 0);
    if (in_.remaining() != 0) {
      fail(in_.offset(), "the tree ends here, after " + std::to_string(nodes_) + " nodes, but size says " +
                             std::to_string(declared_nodes) + " (" + std::to_string(in_.remaining()) +
                             " bytes are left)");
    }
  }

  [[nodiscard]] bool has_mergeable_children() const { return mergeable_; }
  /// Smallest and largest leaf log-odds other than 0 and where they are; nothing without such leaves.
  [[nodiscard]] std::optional<float> lowest() const { return lowest_; }
  [[nodiscard]] std::optional<float> highest() const { return highest_; }
  [[nodiscard]] std::uint64_t lowest_offset() const { return lowest_offset_; }
  [[nodiscard]] std::uint64_t highest_offset() const { return highest_offset_; }

 private:
  void decode(NodeRef node, std::uint64_t code) {
    const std::uint64_t at = in_.offset();
    std::array<std::uint8_t, 8> bytes{};
    if (!in_.read(bytes.data(), node_bytes_)) {
      fail(in_.size(), "the file ends inside the tree, in " + octomap_node(node.depth, code) + ", after " +
                           std::to_string(nodes_) + " nodes (the file is truncated or its size is wrong)");
    }
    ++nodes_;
    float value = get_float(bytes.data());
    if (!std::isfinite(value)) {
      fail(at, "the log-odds of " + octomap_node(node.depth, code) + " is " + float_text(value) +
                   ", not a finite number");
    }
    const std::uint8_t mask = bytes[node_bytes_ - 1];
    if (mask == 0) {
      if (value == 0.0f) value = 0.0f;  // -0 too: unknown
      else note_extremes(value, at);
      tree_.set_childless_value(node, value);
      if (color_) {
        const Rgb rgb{bytes[4], bytes[5], bytes[6]};
        if (rgb != kNoColor) tree_.set_childless_color(node, rgb, 1);
      }
      return;
    }
    if (node.depth == 0) {
      fail(at + node_bytes_ - 1, octomap_node(node.depth, code) + " is at the finest depth (OctoMap depth 16), which "
                                     "has no children, but its child mask is " + std::to_string(mask));
    }
    tree_.subdivide(node);
    const int child_depth = node.depth - 1;
    for (unsigned slot = 0; slot < 8; ++slot) {
      if ((mask >> slot & 1u) == 0) continue;
      decode(tree_.child(node, slot), code | (std::uint64_t{slot} << (3 * child_depth)));
    }
    mergeable_ |= children_equal_and_childless(node);
  }

  [[nodiscard]] bool children_equal_and_childless(NodeRef node) const {
    const NodeRef first = tree_.child(node, 0);
    if (tree_.has_children(first)) return false;
    for (unsigned slot = 1; slot < 8; ++slot) {
      const NodeRef other = tree_.child(node, slot);
      if (tree_.has_children(other) || tree_.log_odds(other) != tree_.log_odds(first) ||
          tree_.color(other) != tree_.color(first) || tree_.color_weight(other) != tree_.color_weight(first)) {
        return false;
      }
    }
    return true;
  }

  void note_extremes(float value, std::uint64_t offset) {
    if (!lowest_ || value < *lowest_) {
      lowest_ = value;
      lowest_offset_ = offset;
    }
    if (!highest_ || value > *highest_) {
      highest_ = value;
      highest_offset_ = offset;
    }
  }

  [[noreturn]] void fail(std::uint64_t offset, const std::string& message) const {
    throw FormatError::at_byte(name_, offset, message);
  }

  ByteReader& in_;
  const std::string& name_;
  detail::TreeBuilder& tree_;
  bool color_;
  std::size_t node_bytes_;
  std::uint64_t nodes_ = 0;
  bool mergeable_ = false;
  std::optional<float> lowest_;
  std::optional<float> highest_;
  std::uint64_t lowest_offset_ = 0;
  std::uint64_t highest_offset_ = 0;
};

class OtEncoder {
 public:
  explicit OtEncoder(const OccupancyTree& tree) : tree_(tree), color_(tree.has_color()), node_bytes_(node_bytes(color_)) {}

  EncodedTree run() {
    encode(tree_.root());
    return std::move(out_);
  }

 private:
  /// What a written node contributes to its parent.
  struct Written {
    bool exists = false;
    float value = 0.0f;
    Rgb rgb = kNoColor;
  };

  Written encode(NodeRef node) {
    if (!tree_.has_children(node)) {
      const float value = tree_.log_odds(node);
      if (value == 0.0f) return {};  // unknown: OctoMap has no such node
      const Rgb rgb = tree_.color(node).value_or(kNoColor);
      put_node(out_.bytes.size(), value, rgb, 0, true);
      return {true, value, rgb};
    }
    const std::size_t at = out_.bytes.size();
    const std::uint64_t nodes_before = out_.nodes;
    out_.bytes.resize(at + node_bytes_);
    std::uint8_t mask = 0;
    float max = -std::numeric_limits<float>::max();  // liboctomap's getMaxChildLogOdds starts here
    unsigned r = 0;
    unsigned g = 0;
    unsigned b = 0;
    unsigned colored = 0;
    for (unsigned slot = 0; slot < 8; ++slot) {
      const Written child = encode(tree_.child(node, slot));
      if (!child.exists) continue;
      mask = static_cast<std::uint8_t>(mask | (1u << slot));
      if (child.value > max) max = child.value;
      if (child.rgb != kNoColor) {
        r += child.rgb.r;
        g += child.rgb.g;
        b += child.rgb.b;
        ++colored;
      }
    }
    if (mask == 0) {  // nothing below is known
      out_.bytes.resize(at);
      out_.nodes = nodes_before;
      return {};
    }
    const Rgb rgb = colored == 0 ? kNoColor
                                 : Rgb{static_cast<std::uint8_t>(r / colored), static_cast<std::uint8_t>(g / colored),
                                       static_cast<std::uint8_t>(b / colored)};
    put_node(at, max, rgb, mask, false);
    return {true, max, rgb};
  }

  void put_node(std::size_t at, float value, Rgb rgb, std::uint8_t mask, bool append) {
    if (append) out_.bytes.resize(at + node_bytes_);
    std::uint8_t* p = &out_.bytes[at];
    put_float(p, value);
    if (color_) {
      p[4] = rgb.r;
      p[5] = rgb.g;
      p[6] = rgb.b;
    }
    p[node_bytes_ - 1] = mask;
    ++out_.nodes;
  }

  const OccupancyTree& tree_;
  bool color_;
  std::size_t node_bytes_;
  EncodedTree out_;
};

}  // namespace

OccupancyMap decode_ot(ByteReader& in, const Header& header, const std::string& name, const SensorModel& sensor) {
  check_declared_size(header, name);
  // A node with children gets a group of eight. Every node may have children as far as the size says; when
  // that bound is above the limit, count them (the records have a fixed size and end with the child mask).
  if (const std::uint64_t bound = header.nodes > 0 ? header.nodes - 1 : 0; tree_bytes(header, bound) > memory_limit()) {
    require_tree_memory(header, name, count_parents(in, header.nodes, node_bytes(header.color)));
  }
  OccupancyMap map = new_map(header, name, sensor, header.color);
  std::optional<OtDecoder> decoder;
  detail::MapAccess::build(map, [&](detail::TreeBuilder& builder) {
    decoder.emplace(in, name, builder, header.color);
    decoder->run(header.nodes);
  });
  if (decoder->has_mergeable_children()) map.set_auto_prune(false);

  // Values beyond the clamping range: widen the range so that every value stays as it is.
  const LogOddsRange range = LogOddsRange::from(sensor);
  SensorModel widened = sensor;
  if (decoder->lowest() && *decoder->lowest() < range.min) {
    const auto p = clamp_probability_covering(*decoder->lowest(), false);
    if (!p) {
      throw FormatError::at_byte(name, decoder->lowest_offset(),
                                 "log-odds " + float_text(*decoder->lowest()) +
                                     " is too low for any clamping probability > 0 (umbra keeps every value "
                                     "inside its sensor model's clamping range)");
    }
    widened.clamp_min = *p;
  }
  if (decoder->highest() && *decoder->highest() > range.max) {
    const auto p = clamp_probability_covering(*decoder->highest(), true);
    if (!p) {
      throw FormatError::at_byte(name, decoder->highest_offset(),
                                 "log-odds " + float_text(*decoder->highest()) +
                                     " is too high for any clamping probability < 1 (umbra keeps every value "
                                     "inside its sensor model's clamping range)");
    }
    widened.clamp_max = *p;
  }
  if (!(widened == sensor)) map.set_sensor_model(widened);
  return map;
}

EncodedTree encode_ot(const OccupancyMap& map) {
  return detail::MapAccess::read(map, [](const OccupancyTree& tree) { return OtEncoder(tree).run(); });
}

}  // namespace umbra::detail
