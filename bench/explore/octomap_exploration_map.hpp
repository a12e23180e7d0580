// The explorer's map on OctoMap (liboctomap 1.9), written as its users write
// exploration code (nbvplanner's volumetric_mapping and its like), for the
// side-by-side study. Every call takes one std::mutex between the mapping
// and the planning thread (OcTree is not safe to read while it is written):
//
//   collision of a node:  the keys of the ball's bounding cube, each voxel
//                         whose cube meets the ball looked up with search();
//                         not stored (unknown) or occupied blocks
//   collision of an edge: lines parallel to the segment at every offset of a
//                         resolution-spaced grid within the radius,
//                         computeRayKeys() + search() along each (the box
//                         sweep of volumetric_mapping, kept to the ball)
//   gain of a view:       the keys of the frustum's bounding box, voxel by
//                         voxel: centre in the frustum (Frustum::contains,
//                         the definition umbra uses) and unknown, then
//                         computeRayKeys() from the sensor and search() for
//                         an occupied voxel on the way
//   inserting an image:   insertPointCloud(..., discretize = true), the
//                         fastest of OctoMap's own insertions
//   coverage:             the free leaves of begin_leafs()
//
// Cost: a gain is one search() per voxel of the frustum's box plus a ray of
// searches per unknown voxel; an edge check a ray of searches per offset.
#pragma once

#include <octomap/OcTree.h>

#include "exploration_map.hpp"
#include "sim_clock.hpp"

namespace umbra::explore {

class OctomapExplorationMap final : public ExplorationMap {
 public:
  explicit OctomapExplorationMap(double resolution);

  [[nodiscard]] std::string name() const override { return "octomap"; }
  [[nodiscard]] double resolution() const override { return tree_.getResolution(); }
  void assume_free(const Sphere& ball) override;
  void insert(Vec3f origin, std::span<const Vec3f> points, double max_range) override;
  [[nodiscard]] bool is_free(const Sphere& ball) const override;
  [[nodiscard]] bool is_free(const Capsule& path) const override;
  [[nodiscard]] double gain(const Frustum& view) const override;
  void for_each_free_node(FunctionRef<void(Vec3d min, Vec3d max)> visit) const override;
  [[nodiscard]] std::size_t memory_bytes() const override;

  /// The tree itself (to save it when exploring is over).
  [[nodiscard]] const octomap::OcTree& tree() const { return tree_; }

 private:
  /// Unknown (not stored) or occupied.
  [[nodiscard]] bool blocks(const octomap::OcTreeKey& key) const;
  /// Whether the ray's voxels (computeRayKeys plus the end voxel) are all known free.
  [[nodiscard]] bool line_free(const octomap::point3d& from, const octomap::point3d& to) const;

  octomap::OcTree tree_;
  mutable SimMutex mutex_;
  mutable octomap::KeyRay ray_;  ///< scratch, used under mutex_
  octomap::Pointcloud cloud_;    ///< scratch of insert(), under mutex_
};

}  // namespace umbra::explore
