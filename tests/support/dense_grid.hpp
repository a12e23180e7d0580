// DenseGrid: the test oracle. A plain 3D array of log-odds, one float per
// finest voxel, with the scan rules of docs/design.md (Semantics) written out the obvious
// way: a literal key-based copy of OctoMap's ray walk, std::set to
// de-duplicate, the occupied set subtracted from the free set, then add and
// clamp. Nothing here shares code with the library except the Key struct,
// so a bug in the optimised tree, batch or Morton ray walker shows up as a
// difference. Only for small maps (depth_levels <= 7: at most 2M voxels).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "umbra/core/color.hpp"
#include "umbra/core/morton.hpp"
#include "umbra/core/vec3.hpp"

namespace umbra::test {

/// OctoMap's computeRayKeys written out key by key, for grids of any depth
/// (DenseGrid uses it; tests of large maps use it alone).
class OctoMapRays {
 public:
  OctoMapRays(double resolution, int depth_levels);
  /// The voxels computeRayKeys visits from origin to end (end voxel
  /// excluded); false when either end is outside the grid.
  bool ray_keys(Vec3f origin, Vec3f end, std::vector<Key>& keys) const;
  /// OctoMap's coordToKeyChecked.
  bool key_of(Vec3f point, Key& key) const;
  /// OctoMap's keyToCoord along one axis.
  [[nodiscard]] double centre(std::uint32_t k) const;

 private:
  double resolution_;
  std::int64_t offset_;
  std::int64_t size_;
};

struct DenseScanOptions {
  bool discrete = false;
  double max_range = -1.0;
};

class DenseGrid {
 public:
  DenseGrid(double resolution, int depth_levels, float clamp_min, float clamp_max);

  [[nodiscard]] std::uint32_t size() const { return size_; }
  [[nodiscard]] float at(Key key) const { return values_[index(key)]; }
  /// Every voxel's log-odds, x fastest, then y, then z.
  [[nodiscard]] std::span<const float> values() const { return values_; }
  void add(Key key, float delta);
  void set(Key key, float value);

  /// The voxels OctoMap's computeRayKeys visits from origin to end (end voxel
  /// excluded); false when either end is outside the grid.
  [[nodiscard]] bool ray_keys(Vec3f origin, Vec3f end, std::vector<Key>& keys) const {
    return rays_.ray_keys(origin, end, keys);
  }
  /// OctoMap's insertPointCloud on this grid; with `colors` (one per point),
  /// every point that gives a hit also blends its color into its voxel.
  void insert_scan(Vec3f origin, std::span<const Vec3f> points, const DenseScanOptions& options,
                   float hit, float miss, std::span<const Rgb> colors = {});

  /// A voxel's color: running average of its samples, weight = samples
  /// (saturating at 255, then each new sample weighs 1/256); weight 0: none.
  struct Color {
    Rgb rgb;
    std::uint8_t weight = 0;
  };
  [[nodiscard]] Color color_at(Key key) const { return colors_[index(key)]; }
  void blend(Key key, Rgb sample);
  /// A coarser node's color: the rounded average of its colored children
  /// (recursively), or none.
  [[nodiscard]] Color node_color(Key key, int depth) const;

  /// Brute-force summaries of the depth-`depth` node containing `key`.
  [[nodiscard]] float max_in_node(Key key, int depth) const;
  [[nodiscard]] bool any_in_node(Key key, int depth, float free_below, float occupied_above, bool want_free) const;

 private:
  [[nodiscard]] std::size_t index(Key key) const {
    return (std::size_t{key.z} * size_ + key.y) * size_ + key.x;
  }
  [[nodiscard]] bool key_of(Vec3f point, Key& key) const { return rays_.key_of(point, key); }
  [[nodiscard]] double centre(std::uint32_t k) const { return rays_.centre(k); }

  OctoMapRays rays_;
  double resolution_;
  int depth_levels_;
  std::uint32_t size_;
  std::int64_t offset_;
  float clamp_min_;
  float clamp_max_;
  std::vector<float> values_;
  std::vector<Color> colors_;
};

}  // namespace umbra::test
