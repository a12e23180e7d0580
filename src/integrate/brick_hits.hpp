// The discrete integrator's hits for a stream of end voxels, a brick (the
// 4x4x4 voxels of a depth-2 node, UpdateBatch's finest group) at a time.
//
// A hit goes to every end voxel whose centre lies within max_range of the
// origin (octomap_norm_exceeds). Per voxel that is a Morton decode, the
// centre, the range test and a descent of the batch: about 250 instructions
// a voxel on the TUM frames at 2 cm (callgrind, 13% of a frame's
// insertion). The voxels of a depth image's surface come in sorted order and
// mostly share bricks, so they are collected into one brick's bit mask, the
// range is decided once for the whole brick where it lies clearly inside
// (or clearly beyond) max_range, and the mask is handed over in one descent
// (UpdateBatch::add_hits_in_brick). Only bricks that straddle the range's
// sphere test their voxels one by one. The hits, the counts and the batch
// are the per-voxel path's exactly.
#pragma once

#include <cstdint>

#include "umbra/core/grid.hpp"
#include "umbra/core/vec3.hpp"

namespace umbra {

struct InsertStats;
class UpdateBatch;

/// Voxels of one brick: bit i of `voxels` stands for the voxel whose code
/// is brick + i (`brick`: the brick's first code, a multiple of 64).
struct BrickVoxels {
  std::uint64_t brick;
  std::uint64_t voxels;
};

class BrickHits {
 public:
  /// Hits from `origin` into `batch` (max_range <= 0: no range), counted in
  /// stats.hits and stats.truncated. No box: a box clips each voxel's ray.
  BrickHits(const Grid& grid, Vec3f origin, double max_range, UpdateBatch& batch, InsertStats& stats);
  BrickHits(const BrickHits&) = delete;
  BrickHits& operator=(const BrickHits&) = delete;
  /// The caller hands over the last brick with flush(): the destructor does
  /// not, since the batch may allocate and a destructor must not throw (nor
  /// retry after an exception left a brick half handed over).
  ~BrickHits() = default;

  /// The end voxel `code`. Voxels of one brick given one after another are
  /// handed over together (any order works; sorted codes are cheapest).
  void add(std::uint64_t code) { add({code & ~std::uint64_t{63}, std::uint64_t{1} << (code & 63)}); }
  /// Several end voxels of one brick.
  void add(BrickVoxels voxels) {
    if (voxels.brick != brick_) {
      flush();
      brick_ = voxels.brick;
    }
    voxels_ |= voxels.voxels;
  }

  /// Hands over the collected brick now.
  void flush();

 private:
  /// Which of the brick's voxels lie within max_range.
  [[nodiscard]] std::uint64_t in_range(std::uint64_t voxels) const;

  const Grid& grid_;
  Vec3f origin_;
  double max_range_;
  UpdateBatch& batch_;
  InsertStats& stats_;
  std::uint64_t brick_ = 0;   // the first code of the collected brick
  std::uint64_t voxels_ = 0;  // its end voxels, bit i: code brick_ + i
};

}  // namespace umbra
