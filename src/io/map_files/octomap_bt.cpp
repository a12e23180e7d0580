// OctoMap's binary tree (.bt): decoder and encoder of the data after the header.
//
// Layout (liboctomap's readBinaryNode/writeBinaryNode): depth first from the
// root, every node that has children is two bytes, children 0-3 in the
// first and 4-7 in the second, two bits per child from the low bits up:
// 0 absent, 1 free leaf, 2 occupied leaf, 3 has children. The bytes of a
// node's children that have children follow in child order. The root is
// the first pair; a root pair of 0 0 is a root without children, which
// liboctomap reads as one occupied leaf covering the whole map.
//
// Reading: free leaves get the clamping minimum, occupied leaves the
// clamping maximum, absent children stay unknown (0); a pair that marks a
// child at the finest depth as having children, or a node with children
// whose pair is 0 0, is an error (liboctomap would silently make the latter
// a free leaf of log-odds -3.4e38). Writing does what liboctomap's
// writeBinary does (toMaxLikelihood, prune, write): every childless node is
// free, occupied or unknown by the map's thresholds (unknown is left out),
// and eight equal leaf children merge into their parent, bottom up, except
// into the root (liboctomap never prunes the root).
//
// Cost: one depth-first pass either way, recursion at most 16 deep, no
// per-node allocation (the output grows amortised; a merged subtree's bytes
// are dropped by shrinking it back).
#include <array>
#include <bit>

#include "map/map_access.hpp"
#include "octomap_format.hpp"

namespace umbra::detail {
namespace {

enum ChildCode : std::uint8_t { kAbsent = 0, kFree = 1, kOccupied = 2, kHasChildren = 3 };

std::array<std::uint8_t, 8> child_codes(std::uint8_t low, std::uint8_t high) {
  std::array<std::uint8_t, 8> codes{};
  for (unsigned i = 0; i < 4; ++i) {
    codes[i] = static_cast<std::uint8_t>((low >> (2 * i)) & 3u);
    codes[i + 4] = static_cast<std::uint8_t>((high >> (2 * i)) & 3u);
  }
  return codes;
}

class BtDecoder {
 public:
  BtDecoder(ByteReader& in, const std::string& name, detail::TreeBuilder& tree, LogOddsRange range)
      : in_(in), name_(name), tree_(tree), free_value_(range.min), occupied_value_(range.max) {}

  void run(std::uint64_t declared_nodes) {
    if (declared_nodes == 0) return;  // an empty tree (check_declared_size saw no data)
    const NodeRef root = tree_.root();
    const std::array<std::uint8_t, 2> pair = read_pair(root, 0);
    nodes_ = 1;
    if (pair[0] == 0 && pair[1] == 0) {
      tree_.set_childless_value(root, occupied_value_);  // liboctomap's value for a childless root
    } else {
      tree_.subdivide(root);
      decode_children(root, 0, pair, in_.offset() - 2);
    }
    if (in_.remaining() != 0) {
      fail(in_.offset(), "the tree ends here, after " + std::to_string(nodes_) + " nodes, but " +
                             std::to_string(in_.remaining()) + " more bytes follow (size says " +
                             std::to_string(declared_nodes) + " nodes)");
    }
    if (nodes_ != declared_nodes) {
      fail(in_.offset(), "the tree has " + std::to_string(nodes_) + " nodes, but size says " +
                             std::to_string(declared_nodes));
    }
  }

  /// True when some node has eight equal leaf children (liboctomap would have merged them, except under the root).
  [[nodiscard]] bool has_mergeable_children() const { return mergeable_; }

 private:
  std::array<std::uint8_t, 2> read_pair(NodeRef node, std::uint64_t code) {
    std::array<std::uint8_t, 2> pair{};
    if (!in_.read(pair.data(), 2)) {
      fail(in_.size(), "the file ends inside the tree: " + octomap_node(node.depth, code) +
                           " has children and needs 2 bytes describing them (the file is truncated)");
    }
    return pair;
  }

  void decode_children(NodeRef node, std::uint64_t code, const std::array<std::uint8_t, 2>& pair,
                       std::uint64_t pair_offset) {
    const int child_depth = node.depth - 1;
    const std::array<std::uint8_t, 8> codes = child_codes(pair[0], pair[1]);
    for (unsigned slot = 0; slot < 8; ++slot) {
      const NodeRef child = tree_.child(node, slot);
      switch (codes[slot]) {
        case kFree:
          tree_.set_childless_value(child, free_value_);
          break;
        case kOccupied:
          tree_.set_childless_value(child, occupied_value_);
          break;
        case kHasChildren:
          if (child_depth == 0) {
            fail(pair_offset + slot / 4, "child " + std::to_string(slot) + " of " + octomap_node(node.depth, code) +
                                             " is marked as having children (bits 11), but it is at the finest "
                                             "depth (OctoMap depth 16), which has no children");
          }
          break;
        default:
          continue;  // absent: stays unknown
      }
      ++nodes_;
    }
    bool all_same_leaf = codes[0] == kFree || codes[0] == kOccupied;
    for (const std::uint8_t c : codes) all_same_leaf &= c == codes[0];
    mergeable_ |= all_same_leaf;
    for (unsigned slot = 0; slot < 8; ++slot) {
      if (codes[slot] != kHasChildren) continue;
      const NodeRef child = tree_.child(node, slot);
      const std::uint64_t child_code = code | (std::uint64_t{slot} << (3 * child_depth));
      const std::uint64_t offset = in_.offset();
      const std::array<std::uint8_t, 2> child_pair = read_pair(child, child_code);
      if (child_pair[0] == 0 && child_pair[1] == 0) {
        fail(offset, octomap_node(child.depth, child_code) +
                         " is marked as having children (bits 11), but its own two bytes are 0 0 (no children)");
      }
      tree_.subdivide(child);
      decode_children(child, child_code, child_pair, offset);
    }
  }

  [[noreturn]] void fail(std::uint64_t offset, const std::string& message) const {
    throw FormatError::at_byte(name_, offset, message);
  }

  ByteReader& in_;
  const std::string& name_;
  detail::TreeBuilder& tree_;
  float free_value_;
  float occupied_value_;
  std::uint64_t nodes_ = 0;
  bool mergeable_ = false;
};

class BtEncoder {
 public:
  explicit BtEncoder(const OccupancyTree& tree) : tree_(tree), thresholds_(tree.thresholds()) {}

  EncodedTree run() {
    const NodeRef root = tree_.root();
    if (!tree_.has_children(root)) {
      // One value for the whole map. A childless root is read back as occupied by liboctomap, so a free
      // map is written the way liboctomap would hold it: a root with eight free children.
      switch (leaf_code(tree_.log_odds(root))) {
        case kOccupied:
          out_.bytes = {0, 0};
          out_.nodes = 1;
          break;
        case kFree:
          out_.bytes = {0x55, 0x55};
          out_.nodes = 9;
          break;
        default:
          break;  // all unknown: an empty tree
      }
      return std::move(out_);
    }
    if (encode(root, true) == kHasChildren) ++out_.nodes;
    return std::move(out_);
  }

 private:
  [[nodiscard]] std::uint8_t leaf_code(float value) const {
    if (thresholds_.is_occupied(value)) return kOccupied;
    if (thresholds_.is_free(value)) return kFree;
    return kAbsent;
  }

  /// Appends the subtree's bytes (if it keeps children) and returns its code in its parent's pair.
  std::uint8_t encode(NodeRef node, bool is_root) {
    if (!tree_.has_children(node)) return leaf_code(tree_.log_odds(node));
    const std::size_t at = out_.bytes.size();
    const std::uint64_t nodes_before = out_.nodes;
    out_.bytes.push_back(0);
    out_.bytes.push_back(0);
    std::array<std::uint8_t, 8> codes{};
    for (unsigned slot = 0; slot < 8; ++slot) codes[slot] = encode(tree_.child(node, slot), false);
    bool all_same = true;
    for (const std::uint8_t c : codes) all_same &= c == codes[0];
    // Merge eight equal leaves (or drop eight unknown children), as prune() after toMaxLikelihood() would.
    if (all_same && codes[0] != kHasChildren && (!is_root || codes[0] == kAbsent)) {
      out_.bytes.resize(at);
      out_.nodes = nodes_before;
      return codes[0];
    }
    std::uint8_t low = 0;
    std::uint8_t high = 0;
    for (unsigned i = 0; i < 4; ++i) {
      low = static_cast<std::uint8_t>(low | (codes[i] << (2 * i)));
      high = static_cast<std::uint8_t>(high | (codes[i + 4] << (2 * i)));
    }
    out_.bytes[at] = low;
    out_.bytes[at + 1] = high;
    for (const std::uint8_t c : codes) out_.nodes += c != kAbsent ? 1 : 0;
    return kHasChildren;
  }

  const OccupancyTree& tree_;
  LogOddsThresholds thresholds_;
  EncodedTree out_;
};

}  // namespace

OccupancyMap decode_bt(ByteReader& in, const Header& header, const std::string& name, const SensorModel& sensor) {
  check_declared_size(header, name);
  // Every node with children is 2 bytes of the data, and gets a group of eight children.
  require_tree_memory(header, name, (header.file_bytes - header.data_offset) / 2);
  OccupancyMap map = new_map(header, name, sensor, false);
  bool mergeable = false;
  detail::MapAccess::build(map, [&](detail::TreeBuilder& builder) {
    BtDecoder decoder(in, name, builder, LogOddsRange::from(sensor));
    decoder.run(header.nodes);
    mergeable = decoder.has_mergeable_children();
  });
  // Keep unmerged equal siblings as they are (so the file is written back unchanged).
  if (mergeable) map.set_auto_prune(false);
  return map;
}

EncodedTree encode_bt(const OccupancyMap& map) {
  return detail::MapAccess::read(map, [](const OccupancyTree& tree) { return BtEncoder(tree).run(); });
}

}  // namespace umbra::detail
