#include "integrate/color_samples.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "core/assert.hpp"
#include "core/radix_sort.hpp"
#include "core/voxel_codes.hpp"
#include "ray/ray_direction.hpp"

namespace umbra {
namespace {

/// A point that falls in a voxel of the map (inside the box).
struct Sample {
  std::uint64_t code;
  std::uint32_t point;
};

/// The samples of points [begin, end), in scan order.
std::vector<Sample> samples_of(const Grid& grid, std::span<const Vec3f> points, std::span<const std::uint64_t> known_codes,
                               std::size_t begin, std::size_t end, const std::optional<KeyBox>& box) {
  std::vector<Sample> samples;
  samples.reserve(end - begin);
  constexpr std::size_t kBlock = 1024;
  std::array<std::uint64_t, kBlock> codes;
  for (std::size_t block = begin; block < end; block += kBlock) {
    const std::size_t size = std::min(kBlock, end - block);
    const std::uint64_t* block_codes = known_codes.data() + block;
    if (known_codes.empty()) {
      voxel_codes(grid, points.subspan(block, size), codes.data());
      block_codes = codes.data();
    }
    for (std::size_t j = 0; j < size; ++j) {
      const std::uint64_t code = block_codes[j];
      if (code >= kOutsideCode || (box && !box->contains(morton::decode(code)))) continue;
      samples.push_back({code, static_cast<std::uint32_t>(block + j)});
    }
  }
  return samples;
}

/// The first sample of a voxel at or after `i` (or the end).
std::size_t voxel_start(std::span<const Sample> sorted, std::size_t i) {
  while (i > 0 && i < sorted.size() && sorted[i - 1].code == sorted[i].code) ++i;
  return i;
}

}  // namespace

std::vector<OccupancyTree::ColorSample> color_samples(const Grid& grid, Vec3f origin, std::span<const Vec3f> points,
                                                      std::span<const Rgb> colors, const InsertOptions& options,
                                                      const std::optional<KeyBox>& box, ThreadPool* pool,
                                                      std::span<const std::uint64_t> codes) {
  UMBRA_ASSERT(codes.empty() || codes.size() == points.size());
  if (points.size() > UINT32_MAX) {
    throw std::invalid_argument("too many points in one scan: " + std::to_string(points.size()));
  }
  const std::size_t parts = pool != nullptr ? pool->size() : 1;

  // 1. The samples of contiguous parts of the scan, sorted as one list.
  std::vector<std::vector<Sample>> found(parts);
  for_each_part(pool, parts, [&](std::size_t p) {
    found[p] = samples_of(grid, points, codes, points.size() * p / parts, points.size() * (p + 1) / parts, box);
  });
  const std::vector<Sample> sorted =
      parallel_radix_sort(found, 3 * grid.depth_levels(), [](const Sample& s) { return s.code; }, pool);

  // 2. The samples that give a hit, decided over parts of the sorted list
  //    that begin at a voxel's first sample (the fast integrator decides a
  //    voxel by its first point), then laid end to end.
  const bool limited = options.max_range > 0.0;
  std::vector<std::vector<OccupancyTree::ColorSample>> kept(parts);
  for_each_part(pool, parts, [&](std::size_t p) {
    const std::size_t begin = voxel_start(sorted, sorted.size() * p / parts);
    const std::size_t end = voxel_start(sorted, sorted.size() * (p + 1) / parts);
    std::vector<OccupancyTree::ColorSample> hits;
    hits.reserve(end - begin);
    bool voxel_hit = true;
    for (std::size_t i = begin; i < end; ++i) {
      const Sample& sample = sorted[i];
      const bool first_of_voxel = i == 0 || sorted[i - 1].code != sample.code;
      if (options.integrator == IntegratorKind::simple || first_of_voxel) {
        const Vec3f end_point = options.integrator == IntegratorKind::discrete
                                    ? grid.center_f(morton::decode(sample.code))
                                    : points[sample.point];
        voxel_hit = !limited || octomap_norm(end_point - origin) <= options.max_range;
      }
      if (voxel_hit) hits.push_back({sample.code, colors[sample.point]});
    }
    kept[p] = std::move(hits);
  });
  if (parts == 1) return std::move(kept[0]);
  std::vector<std::size_t> first(parts + 1, 0);
  for (std::size_t p = 0; p < parts; ++p) first[p + 1] = first[p] + kept[p].size();
  std::vector<OccupancyTree::ColorSample> hits(first[parts]);
  for_each_part(pool, parts, [&](std::size_t p) {
    std::copy(kept[p].begin(), kept[p].end(), hits.begin() + static_cast<std::ptrdiff_t>(first[p]));
  });
  return hits;
}

}  // namespace umbra
