#include "core/voxel_codes.hpp"

#include <optional>

namespace umbra {

void voxel_codes(const Grid& grid, std::span<const Vec3f> points, std::uint64_t* codes) {
  static const bool avx2 = detail::voxel_codes_avx2_available();  // the CPU does not change
  if (avx2) {
    detail::voxel_codes_avx2(grid, points, codes);
  } else {
    detail::voxel_codes_scalar(grid, points, codes);
  }
}

namespace detail {

void voxel_codes_scalar(const Grid& grid, std::span<const Vec3f> points, std::uint64_t* codes) {
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3f& p = points[i];
    if (!p.is_finite()) {
      codes[i] = kNonFiniteCode;
    } else if (const std::optional<Key> key = grid.key_checked(p)) {
      codes[i] = morton::encode(*key);
    } else {
      codes[i] = kOutsideCode;
    }
  }
}

}  // namespace detail
}  // namespace umbra
