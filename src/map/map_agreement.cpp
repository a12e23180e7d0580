// compare_maps (umbra/map/map_agreement.hpp): both trees walked at once.
#include "umbra/map/map_agreement.hpp"

#include <functional>
#include <sstream>
#include <stdexcept>

#include "map/map_access.hpp"

namespace umbra {
namespace {

class AgreementWalk {
 public:
  AgreementWalk(const OccupancyTree& reference, const OccupancyTree& other, const std::optional<VoxelBox>& region,
                MapAgreement& result)
      : reference_(reference), other_(other), region_(region), result_(result) {}

  /// The node of each tree covering the depth-`depth` node whose first voxel
  /// is `first` (a childless node stands for each of its parts).
  void walk(NodeRef reference, NodeRef other, std::uint64_t first, int depth) {
    std::uint64_t voxels = std::uint64_t{1} << (3 * depth);
    if (region_) {
      voxels = region_->voxels_inside(morton::decode(first), depth);
      if (voxels == 0) return;
    }
    const bool reference_split = reference_.has_children(reference);
    const bool other_split = other_.has_children(other);
    if (!reference_split && !other_split) {
      result_.voxels[state(reference_, reference)][state(other_, other)] += voxels;
      return;
    }
    for (unsigned slot = 0; slot < 8; ++slot) {
      walk(reference_split ? reference_.child(reference, slot) : reference,
           other_split ? other_.child(other, slot) : other, first + (std::uint64_t{slot} << (3 * (depth - 1))),
           depth - 1);
    }
  }

 private:
  static int state(const OccupancyTree& tree, NodeRef node) {
    return static_cast<int>(tree.thresholds().classify(tree.log_odds(node)));  // by that map's own thresholds
  }

  const OccupancyTree& reference_;
  const OccupancyTree& other_;
  const std::optional<VoxelBox>& region_;
  MapAgreement& result_;
};

}  // namespace

MapAgreement compare_maps(const OccupancyMap& reference, const OccupancyMap& other,
                          const std::optional<VoxelBox>& region) {
  if (reference.resolution() != other.resolution() || reference.depth_levels() != other.depth_levels()) {
    std::ostringstream text;
    text.precision(17);
    text << "the maps have different voxels: " << reference.resolution() << " m and " << reference.depth_levels()
         << " depth levels against " << other.resolution() << " m and " << other.depth_levels()
         << " depth levels; only maps of the same grid can be compared";
    throw std::invalid_argument(text.str());
  }
  MapAgreement result;
  const auto compare = [&](const OccupancyTree& a, const OccupancyTree& b) {
    AgreementWalk(a, b, region, result).walk(a.root(), b.root(), 0, reference.depth_levels());
  };
  if (&reference == &other) {
    detail::MapAccess::read(reference, [&](const OccupancyTree& tree) { compare(tree, tree); });
    return result;
  }
  // Held in address order, so that compare_maps(a, b) and compare_maps(b, a)
  // on two threads never each hold one map while a writer waits on the other.
  const bool reference_first = std::less<const OccupancyMap*>()(&reference, &other);
  const OccupancyMap& first = reference_first ? reference : other;
  const OccupancyMap& second = reference_first ? other : reference;
  detail::MapAccess::read(first, [&](const OccupancyTree& first_tree) {
    detail::MapAccess::read(second, [&](const OccupancyTree& second_tree) {
      if (reference_first) {
        compare(first_tree, second_tree);
      } else {
        compare(second_tree, first_tree);
      }
    });
  });
  return result;
}

}  // namespace umbra
