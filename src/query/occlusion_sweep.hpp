// OcclusionSweep: proves that every ray walk from the sensor to a box of
// targets meets an occupied voxel, so that the information gain can skip a
// whole node behind a wall without looking at its voxels.
//
// Why it works. A walk steps one voxel at a time along an axis, each axis
// always in the same direction (the sign of the ray's direction there), so
// a walk from the sensor to a target beyond layer k (the voxels with key k
// along an axis a, in the direction the walk goes) passes through layer k,
// entering it from layer k - 1 through the face between them and moving
// within it from voxel to face neighbour. Every voxel a walk visits lies
// within the walk's rounding margin of its segment, so within the margin of
// the cone from the sensor over the target box. The sweep follows the
// layers across the cone and keeps, per layer, the voxels a walk could have
// reached without meeting an occupied voxel: a free or unknown voxel of the
// layer's part of the cone that lies next to a reachable voxel of the layer
// before, or to a reachable voxel of its own layer that a walk could step
// from (where all the cone's directions agree in sign along an axis, only
// from that side). When a layer has no
// reachable voxel, no walk gets past it: the targets are hidden. Taking a
// layer as wholly reachable only weakens the proof, never falsifies it, so
// the sweep starts with the layer before the nearest obstacle in the cone
// (read from the ViewImage) taken as wholly reachable instead of walking
// from the sensor through empty layers. It proves only (an answer "no" means "not
// proven"), it allows more paths than walks take (the cone's bounding
// rectangle per layer; both directions along an axis the cone straddles),
// and it gives up after a few layers or on wide cones, leaving those
// targets to smaller nodes. Voxels outside the bitmap count as open.
//
// Layout: one row of up to 64 voxels per 64-bit mask (b axis, x where it
// can), rows along the c axis; two layers (the one before and the current)
// are kept. Cost: O(rows x layers swept) word operations when rows run
// along x (read from the OccupiedBitmap a row at a time), O(voxels) bit
// reads otherwise.
#pragma once

#include <array>
#include <cstdint>

#include "query/occupied_bitmap.hpp"
#include "umbra/core/aabb.hpp"
#include "umbra/core/grid.hpp"

namespace umbra::detail {

class OcclusionSweep {
 public:
  /// Layers swept beyond the first that may hold an obstacle before giving up.
  static constexpr int kMaxLayers = 6;
  /// Widest cross-section swept, in voxels, along each of the two other axes.
  static constexpr int kMaxWidth = 64;

  struct Pose {
    const OccupiedBitmap* occupied;  // the occupied voxels around the cone
    const Grid* grid;
    Vec3d apex;      // the walks' (float) origin
    Key apex_key;
    double margin;   // how far a walk strays from its segment
  };

  /// Whether every walk from the apex to a point of `targets` surely meets
  /// an occupied voxel. `obstacle_free`: no obstacle lies nearer than this
  /// to the apex in the cone over `targets` (where the sweep starts; any
  /// value is safe, a good one makes the proof succeed).
  bool hidden(const Pose& pose, const Aabb& targets, double obstacle_free);

 private:
  struct Layer {
    std::int64_t b0 = 0, b1 = -1, c0 = 0, c1 = -1;  // inclusive key ranges
    std::array<std::uint64_t, kMaxWidth> reach{};   // per c row, bit (b - b0)
  };
};

}  // namespace umbra::detail
