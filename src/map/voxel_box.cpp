// VoxelBox (umbra/map/voxel_box.hpp).
#include "umbra/map/voxel_box.hpp"

#include <algorithm>
#include <sstream>
#include <stdexcept>

namespace umbra {

std::uint64_t VoxelBox::voxels_inside(Key corner, int depth) const {
  const std::int64_t side = std::int64_t{1} << depth;
  std::uint64_t inside = 1;
  for (int axis = 0; axis < 3; ++axis) {
    const std::int64_t begin = std::max<std::int64_t>(corner[axis], lo[axis]);
    const std::int64_t end = std::min<std::int64_t>(std::int64_t{corner[axis]} + side, std::int64_t{hi[axis]} + 1);
    if (end <= begin) return 0;
    inside *= static_cast<std::uint64_t>(end - begin);
  }
  return inside;
}

VoxelBox voxel_box(const Grid& grid, const Aabb& box) {
  box.validate();
  const double half = grid.half_extent();
  for (int axis = 0; axis < 3; ++axis) {
    if (box.max[axis] < -half || box.min[axis] >= half) {
      std::ostringstream text;
      text << "the box (" << box.min.x << ", " << box.min.y << ", " << box.min.z << ") to (" << box.max.x << ", "
           << box.max.y << ", " << box.max.z << ") lies outside the map, which spans [" << -half << ", " << half
           << ") m on every axis";
      throw std::out_of_range(text.str());
    }
  }
  // Corners past the map are moved onto the centre of its outermost voxels.
  const double inside = half - 0.5 * grid.resolution();
  const auto clamp = [inside](Vec3d p) {
    return Vec3d{std::clamp(p.x, -inside, inside), std::clamp(p.y, -inside, inside), std::clamp(p.z, -inside, inside)};
  };
  return {grid.key(clamp(box.min)), grid.key(clamp(box.max))};
}

}  // namespace umbra
