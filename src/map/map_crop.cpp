// crop_map (umbra/map/map_crop.hpp): the source tree copied into a new one
// through the file readers' TreeBuilder, node by node, cut at the box; and
// copy_voxels (map_copy.hpp), the copy itself, which the moving window also
// uses for what leaves its box.
#include "umbra/map/map_crop.hpp"

#include <stdexcept>

#include "map/map_access.hpp"
#include "map/map_copy.hpp"

namespace umbra {
namespace {

class CropCopy {
 public:
  CropCopy(const OccupancyTree& from, detail::TreeBuilder& to, detail::VoxelsKept keep)
      : from_(from), to_(to), keep_(keep) {}

  /// Copies the part in the box of the depth-`depth` region whose first
  /// voxel is `first`: `source` is the source's node there (or the childless
  /// node above it), `target` the new tree's node there, still as made
  /// (unknown, childless).
  void copy(NodeRef source, NodeRef target, std::uint64_t first, int depth) {
    const std::uint64_t inside = keep_(morton::decode(first), depth);
    if (inside == 0) return;
    const bool whole = inside == std::uint64_t{1} << (3 * depth);
    const bool source_split = from_.has_children(source);
    if (!source_split) {
      if (is_blank(source)) return;  // unknown and uncolored: what the new tree holds already
      copied_any_ = true;
      if (whole) {
        to_.set_childless_value(target, from_.log_odds(source));
        if (from_.has_color()) {
          to_.set_childless_color(target, from_.color(source).value_or(Rgb{}), from_.color_weight(source));
        }
        return;
      }
    }
    // Children in the source, or a childless source node the box cuts: the
    // new node gets children, each copied (a childless source stands for each).
    to_.subdivide(target);
    for (unsigned slot = 0; slot < 8; ++slot) {
      copy(source_split ? from_.child(source, slot) : source, to_.child(target, slot),
           first + (std::uint64_t{slot} << (3 * (depth - 1))), depth - 1);
    }
  }

  /// Whether some copied voxel was known or colored.
  [[nodiscard]] bool copied_any() const { return copied_any_; }

 private:
  [[nodiscard]] bool is_blank(NodeRef node) const {
    return from_.log_odds(node) == 0.0f && from_.color_weight(node) == 0;
  }
  const OccupancyTree& from_;
  detail::TreeBuilder& to_;
  detail::VoxelsKept keep_;
  bool copied_any_ = false;
};

}  // namespace

namespace detail {

bool copy_voxels(const OccupancyTree& from, OccupancyMap& into, VoxelsKept kept) {
  bool copied_any = false;
  MapAccess::build(into, [&](TreeBuilder& to) {
    CropCopy copy(from, to, kept);
    copy.copy(from.root(), to.root(), 0, from.depth_levels());
    copied_any = copy.copied_any();
  });
  return copied_any;
}

}  // namespace detail

OccupancyMap crop_map(const OccupancyMap& map, const VoxelBox& keep) {
  const std::uint32_t keys = map.grid().keys_per_axis();
  for (int axis = 0; axis < 3; ++axis) {
    if (keep.lo[axis] > keep.hi[axis] || keep.hi[axis] >= keys) {
      throw std::out_of_range("crop_map: the voxel box is empty or reaches outside the map");
    }
  }
  OccupancyMap cropped(map.config());
  cropped.set_bounding_box(map.bounding_box());
  const bool prune = map.auto_prune();
  if (!prune) cropped.set_auto_prune(false);
  detail::MapAccess::read(map, [&](const OccupancyTree& from) {
    (void)detail::copy_voxels(from, cropped, [&](Key corner, int depth) { return keep.voxels_inside(corner, depth); });
  });
  // The cut may leave eight equal childless siblings (say, all unknown):
  // merged, as the source's own updates would have.
  if (prune) cropped.prune();
  return cropped;
}

}  // namespace umbra
