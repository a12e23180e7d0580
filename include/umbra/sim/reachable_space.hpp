// ReachableSpace: the free space a ball-shaped robot can reach in a scene,
// the ground truth an exploration's coverage is measured against.
//
// Space is cut into cubic cells of edge `cell_size` on the lattice of a map
// of that resolution (cell i along an axis covers [i, i + 1) * cell_size, so
// cells are the finest voxels of an umbra or OctoMap map of the same
// resolution). Only cells whose centre lies in `region` count. A cell is
// clear when its centre is at least `robot_radius` from every solid of the
// scene (and so outside them); the reachable cells are the clear cells
// joined to the cell of `start` through faces (a flood fill, 6-connected).
//
// Cost: building rasterises each primitive over the cells of its bounds
// grown by the radius (a few flops per cell, no scene queries), then one
// flood fill: about a second for the 40 x 30 x 12 m plant at 10 cm. Memory:
// one byte per cell while building, then a summed-volume table of 4 bytes
// per cell, which answers count_in() for any box of cells in constant time
// (coverage of a map is one count_in() per free leaf).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "umbra/core/vec3.hpp"
#include "umbra/sim/scene.hpp"

namespace umbra::sim {

class ReachableSpace {
 public:
  /// Throws std::invalid_argument for a cell size or radius that is not
  /// finite and > 0 (radius >= 0), a region with min > max, more than 2^31
  /// cells, or a start whose cell is not clear or outside the region.
  ReachableSpace(const Scene& scene, const Box& region, double cell_size, double robot_radius, Vec3d start);

  [[nodiscard]] double cell_size() const { return cell_size_; }
  /// Reachable cells, and their volume (cells * cell_size^3).
  [[nodiscard]] std::size_t cell_count() const { return reachable_cells_; }
  [[nodiscard]] double volume() const;
  /// Clear cells in the region, reachable or not.
  [[nodiscard]] std::size_t clear_cell_count() const { return clear_cells_; }

  /// Whether the cell holding `point` is reachable (false outside the region).
  [[nodiscard]] bool reachable(Vec3d point) const;
  /// Reachable cells whose centres lie in the closed box [min, max]; for a
  /// map node, its cube (corners on cell boundaries; a corner at a cell's
  /// very centre may fall either way). Constant time.
  [[nodiscard]] std::size_t count_in(Vec3d min, Vec3d max) const;

 private:
  using Index3 = std::array<std::int64_t, 3>;
  /// Summed-volume table entry: reachable cells with local index < (i, j, k).
  [[nodiscard]] std::uint32_t prefix(std::int64_t i, std::int64_t j, std::int64_t k) const;
  /// Reachable cells with local index in [lo, hi) per axis.
  [[nodiscard]] std::size_t count_cells(const Index3& lo, const Index3& hi) const;

  double cell_size_;
  Index3 first_{};  ///< lattice index of the region's first cell per axis
  Index3 size_{};   ///< cells per axis
  std::size_t reachable_cells_ = 0;
  std::size_t clear_cells_ = 0;
  std::vector<std::uint32_t> prefix_;  ///< (size + 1) per axis, x fastest
};

}  // namespace umbra::sim
