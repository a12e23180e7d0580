#include "field/brick_sites.hpp"

#include <stdexcept>
#include <string>

#include "tree/occupancy_tree.hpp"

namespace umbra::detail {
namespace {

class BrickReader {
 public:
  BrickReader(const OccupancyTree& tree, const FieldLayout& layout, BrickBits& bits)
      : tree_(tree), thresholds_(tree.thresholds()), depth_(layout.depth()), bits_(bits) {}

  /// Fills the cells of node `ref` (at `depth`, its first cell at `cell`
  /// within the brick, per axis).
  void fill(NodeRef ref, int depth, std::array<int, 3> cell) {
    if (depth == depth_ || !tree_.has_children(ref)) {
      const float value = tree_.log_odds(ref);
      const bool occupied = thresholds_.is_occupied(value);
      const bool unknown = tree_.contains_unknown(ref);
      if (occupied || tree_.contains_free(ref)) bits_.known = true;
      const int cells = 1 << (depth - depth_);
      for (int z = cell[2]; z < cell[2] + cells; ++z) {
        for (int y = cell[1]; y < cell[1] + cells; ++y) {
          for (int x = cell[0]; x < cell[0] + cells; ++x) {
            const int i = x + 8 * y + 64 * z;
            const std::uint64_t bit = std::uint64_t{1} << (i & 63);
            if (occupied) bits_.occupied[std::size_t(i >> 6)] |= bit;
            if (unknown) bits_.unknown[std::size_t(i >> 6)] |= bit;
          }
        }
      }
      return;
    }
    const int half = 1 << (depth - 1 - depth_);
    for (unsigned slot = 0; slot < 8; ++slot) {
      fill(tree_.child(ref, slot), depth - 1,
           {cell[0] + ((slot & 1u) ? half : 0), cell[1] + ((slot & 2u) ? half : 0),
            cell[2] + ((slot & 4u) ? half : 0)});
    }
  }

 private:
  const OccupancyTree& tree_;
  LogOddsThresholds thresholds_;
  int depth_;
  BrickBits& bits_;
};

}  // namespace

BrickBits read_brick(const OccupancyTree& tree, const FieldLayout& layout, BrickIndex brick,
                     const std::optional<CellBox>& box) {
  BrickBits bits;
  const int brick_depth = layout.depth() + 3;
  const int shift = brick_depth;
  const Key key{brick.x << shift, brick.y << shift, brick.z << shift};
  const NodeSummary found = tree.find(morton::encode(key), brick_depth);
  // A childless node found above the brick's depth covers the whole brick:
  // fill() gives every cell its value, which holds for every voxel it covers.
  BrickReader reader(tree, layout, bits);
  reader.fill(found.node, brick_depth, {0, 0, 0});
  if (box) {
    const std::uint32_t first[3] = {brick.x * 8, brick.y * 8, brick.z * 8};
    for (int i = 0; i < kBrickVolume; ++i) {
      if (!box->contains(first[0] + std::uint32_t(i & 7), first[1] + std::uint32_t((i >> 3) & 7),
                         first[2] + std::uint32_t(i >> 6))) {
        const std::uint64_t clear = ~(std::uint64_t{1} << (i & 63));
        bits.occupied[std::size_t(i >> 6)] &= clear;
        bits.unknown[std::size_t(i >> 6)] &= clear;
      }
    }
  }
  return bits;
}

namespace {

class KnownBricks {
 public:
  KnownBricks(const OccupancyTree& tree, const FieldLayout& layout, std::size_t limit,
              FunctionRef<void(BrickIndex)> visit)
      : tree_(tree), thresholds_(tree.thresholds()), brick_depth_(layout.depth() + 3), limit_(limit), visit_(visit) {}

  void walk(NodeRef ref, int depth, Key key) {
    if (!tree_.contains_free(ref) && !thresholds_.is_occupied(tree_.log_odds(ref))) return;  // all unknown
    if (depth == brick_depth_ || !tree_.has_children(ref)) {
      const std::uint32_t per_axis = 1u << (depth - brick_depth_);
      count_ += std::size_t(per_axis) * per_axis * per_axis;
      if (count_ > limit_) {
        throw std::length_error("the known space spans more than " + std::to_string(limit_) +
                                " bricks of the distance field: give the field a box (DistanceFieldOptions::box)");
      }
      const BrickIndex first{key.x >> brick_depth_, key.y >> brick_depth_, key.z >> brick_depth_};
      for (std::uint32_t z = 0; z < per_axis; ++z) {
        for (std::uint32_t y = 0; y < per_axis; ++y) {
          for (std::uint32_t x = 0; x < per_axis; ++x) visit_(BrickIndex{first.x + x, first.y + y, first.z + z});
        }
      }
      return;
    }
    const std::uint32_t half = 1u << (depth - 1);
    for (unsigned slot = 0; slot < 8; ++slot) {
      walk(tree_.child(ref, slot), depth - 1,
           Key{key.x + ((slot & 1u) ? half : 0), key.y + ((slot & 2u) ? half : 0), key.z + ((slot & 4u) ? half : 0)});
    }
  }

 private:
  const OccupancyTree& tree_;
  LogOddsThresholds thresholds_;
  int brick_depth_;
  std::size_t limit_;
  FunctionRef<void(BrickIndex)> visit_;
  std::size_t count_ = 0;
};

}  // namespace

void for_each_known_brick(const OccupancyTree& tree, const FieldLayout& layout, std::size_t limit,
                          FunctionRef<void(BrickIndex)> visit) {
  KnownBricks walker(tree, layout, limit, visit);
  walker.walk(tree.root(), tree.depth_levels(), Key{});
}

}  // namespace umbra::detail
