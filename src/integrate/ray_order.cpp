#include "integrate/ray_order.hpp"

#include <cstddef>
#include <cstdint>

#include "core/radix_sort.hpp"

namespace umbra {

std::vector<PreparedRay> rays_in_end_order(const std::vector<std::vector<PreparedRay>>& parts, int key_bits) {
  struct Moved {
    std::uint64_t code;
    std::size_t index;  // in the scan's rays
    const PreparedRay* ray;
  };
  std::vector<Moved> moved;
  std::size_t count = 0;
  for (const std::vector<PreparedRay>& part : parts) {
    for (const PreparedRay& ray : part) {
      if (!ray.hit) moved.push_back({ray.end_code, count, &ray});
      ++count;
    }
  }
  radix_sort(moved, key_bits, [](const Moved& m) { return m.code; });
  std::vector<PreparedRay> rays;
  rays.reserve(count);
  std::size_t next = 0;  // in `moved`
  std::size_t index = 0;
  for (const std::vector<PreparedRay>& part : parts) {
    for (const PreparedRay& ray : part) {
      if (ray.hit) {
        while (next < moved.size() &&
               (moved[next].code < ray.end_code || (moved[next].code == ray.end_code && moved[next].index < index))) {
          rays.push_back(*moved[next++].ray);
        }
        rays.push_back(ray);
      }
      ++index;
    }
  }
  while (next < moved.size()) rays.push_back(*moved[next++].ray);
  return rays;
}

}  // namespace umbra
