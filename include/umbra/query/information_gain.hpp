// Information gain of a sensor pose: how much unknown space a sensor placed
// there would see (docs/design.md, Semantics), the quantity exploration planners rank
// candidate poses by.
//
//   umbra::Frustum view = umbra::Frustum::from_degrees({1, 2, 1.2}, 30, -10, 115, 60, 0.0, 6.5);
//   umbra::GainResult gain = map.information_gain(view);                        // exact
//   umbra::GainResult quick = map.information_gain(view, {.method = umbra::GainMethod::fast});
//   std::vector<umbra::GainResult> all = map.information_gain(std::span(views), {.threads = 2});
//
// The gain counts the unknown finest voxels whose centre c lies in the
// frustum (Frustum::contains) and is visible from its origin o: no occupied
// voxel lies on the ray o -> c, the ray's voxels being those OctoMap's
// computeRayKeys(o, c) visits (float o and c; the voxel of o included, the
// voxel of c not). Free and unknown voxels never block; states use the
// map's thresholds. A sensor inside an occupied voxel sees nothing. Voxels
// outside the map are not counted (a frustum may reach beyond the map).
//
// Methods (docs/design.md, "Information gain", has how and why):
//   exact: that count, voxel for voxel. The speed comes from the tree and
//          from a depth image of the obstacles: unknown nodes that surely
//          see no obstacle are counted whole, nodes surely behind obstacles
//          are skipped whole, and only the rest is decided ray by ray.
//   fast:  the same, except that a node of at most 2^fast_depth voxels per
//          edge that is not surely visible or hidden is decided by the rays
//          to its two opposite corner voxels when they agree (counted whole
//          or skipped), and split when they do not. It errs only where both
//          corners agree and the inside does not. Measured error against
//          exact on the benchmark poses: docs/benchmarks.md ("Information
//          gain").
//
// Long ranges: voxels beyond the map are not counted, so a range longer
// than the distance to the map's farthest corner counts what that distance
// does. The work grows with the range's square or faster (the centres along
// the frustum's boundary, and along the edges of the shadows of obstacles
// in it, are decided one by one: about 10^10 of them at 900 m on a 2 cm
// map), so one pose may take at most GainOptions::max_steps steps (2^28 by
// default, 10 to 30 s of one core); beyond that it throws
// std::invalid_argument naming max_range, the resolution and the limit
// rather than running for hours. The exact method keeps a bitmap of the
// occupied voxels in view (their bounding box, one bit a voxel); above
// umbra::memory_limit() it throws umbra::MemoryLimitError naming max_range
// and the box. Nothing else grows with the range: the image is at most
// 400,000 pixels.
//
// Cost: one query takes the map for reading for one pose; a batch takes it
// pose by pose, so a writer never waits for a whole batch. Queries are const
// and share nothing: each call (each thread of a batch) has its own scratch
// memory.
#pragma once

#include <cstdint>

namespace umbra {

enum class GainMethod : unsigned char {
  exact,  ///< the count of the definition
  fast,   ///< an approximation: small undecided nodes decided by their corner voxels
};

/// GainOptions::max_steps's default: 10 to 30 seconds of one core.
inline constexpr std::uint64_t kDefaultMaxGainSteps = std::uint64_t{1} << 28;

struct GainOptions {
  GainMethod method = GainMethod::exact;
  /// fast only: nodes of up to 2^fast_depth voxels per edge are decided by
  /// their corners (0 makes fast exact). In [0, depth_levels].
  int fast_depth = 2;
  /// Batch form only: poses answered in parallel by this many threads,
  /// including the caller; 0 means all hardware threads.
  unsigned threads = 1;
  /// The most work one pose may take, in steps (a node or a voxel decided,
  /// a block of up to 64 centres counted, a ray walked plus one per 8 of
  /// its voxels; about 10 to 20 million a second). A pose that needs more
  /// throws std::invalid_argument naming its max_range (see the file
  /// comment, "Long ranges"). 0: no limit.
  std::uint64_t max_steps = kDefaultMaxGainSteps;
};

struct GainResult {
  /// Visible unknown finest voxels in the frustum.
  std::uint64_t unknown_voxels = 0;
  /// Their volume, unknown_voxels * resolution^3, in cubic metres.
  double volume = 0.0;
  /// Sum over those voxels of the binary entropy of their occupancy
  /// probability p, -p log2 p - (1 - p) log2 (1 - p), in bits: a voxel never
  /// observed (p = 0.5) weighs 1, one already nearly decided less. Equals
  /// unknown_voxels with the default thresholds (only p = 0.5 is unknown).
  double entropy_bits = 0.0;
};

}  // namespace umbra
