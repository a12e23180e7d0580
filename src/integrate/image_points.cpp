#include "integrate/image_points.hpp"

#include <algorithm>
#include <array>
#include <bit>

#include "core/radix_sort.hpp"
#include "core/thread_pool.hpp"
#include "core/voxel_codes.hpp"
#include "integrate/image_row_codes.hpp"
#include "integrate/row_candidates.hpp"

namespace umbra {

namespace {

/// Calls depth_of(index) for each pixel of rows [row_begin, row_end): one
/// loop per kind of image, so that the pixel loop does not ask which.
template <typename Work>
void for_each_depth(const DepthImage& depth, const Work& work) {
  if (depth.is_raw()) {
    const std::span<const std::uint16_t> raw = depth.raw_depths();
    const double scale = depth.metres_per_unit();
    work([&](std::size_t i) { return raw[i] * scale; });
  } else {
    work([&](std::size_t i) { return depth.depth(i); });
  }
}

}  // namespace

std::size_t count_readings(const DepthImage& depth, int row_begin, int row_end) {
  const std::size_t begin = std::size_t(row_begin) * std::size_t(depth.width());
  const std::size_t end = std::size_t(row_end) * std::size_t(depth.width());
  std::size_t count = 0;
  for_each_depth(depth, [&](auto&& depth_of) {
    for (std::size_t i = begin; i < end; ++i) count += static_cast<std::size_t>(depth_of(i) != 0.0);
  });
  return count;
}

std::size_t back_project_rows(const DepthImage& depth, const PinholeCamera& camera, const Pose& pose, int row_begin,
                              int row_end, Vec3f* points, std::uint32_t* pixels) {
  const int width = depth.width();
  // A row's x factors, (u - cx) / fx, on the stack for the usual widths.
  std::array<double, 2048> small_factors;
  std::vector<double> large_factors;
  double* column_factor = small_factors.data();
  if (width > static_cast<int>(small_factors.size())) {
    large_factors.resize(static_cast<std::size_t>(width));
    column_factor = large_factors.data();
  }
  for (int u = 0; u < width; ++u) column_factor[u] = (u - camera.cx) / camera.fx;
  std::size_t out = 0;
  for_each_depth(depth, [&](auto&& depth_of) {
    std::size_t index = std::size_t(row_begin) * std::size_t(width);
    for (int v = row_begin; v < row_end; ++v) {
      const double row_factor = (v - camera.cy) / camera.fy;
      for (int u = 0; u < width; ++u, ++index) {
        const double z = depth_of(index);
        if (z == 0.0) continue;
        points[out] = pose.apply(column_factor[u] * z, row_factor * z, z);
        if (pixels != nullptr) pixels[out] = static_cast<std::uint32_t>(index);
        ++out;
      }
    }
  });
  return out;
}

void ImagePoints::build(const Grid& grid, const DepthImage& depth, const PinholeCamera& camera, const Pose& pose,
                        std::span<const Rgb> colors, ThreadPool* pool, FunctionRef<void()> alongside,
                        bool voxels_only) {
  voxels_only = voxels_only && colors.empty();
  const int height = depth.height();
  // Two bands per worker balance rows of unequal counts; at least 16 rows a
  // band. One band without a pool: for_each_voxel then reads its voxels
  // directly instead of merging bands.
  const int band_count = pool != nullptr ? std::max(1, std::min(2 * static_cast<int>(pool->size()), height / 16)) : 1;
  bands_.resize(static_cast<std::size_t>(band_count));
  for (int b = 0; b < band_count; ++b) {
    Band& band = bands_[static_cast<std::size_t>(b)];
    band.row_begin = static_cast<int>(std::int64_t{height} * b / band_count);
    band.row_end = static_cast<int>(std::int64_t{height} * (b + 1) / band_count);
  }
  points_kept_ = !voxels_only;
  if (voxels_only) {
    points_.clear();
    pixels_.clear();
    codes_.clear();
    colors_.clear();
    // Each band back-projects its rows a few at a time and keeps their voxels.
    for_each_part(pool, bands_.size() + 1, [&](std::size_t task) {
      if (task == 0) {
        alongside();
      } else {
        find_voxels_streamed(grid, depth, camera, pose, bands_[task - 1]);
      }
    });
    sum_band_counts();
    return;
  }
  // 1. Each band's readings, then where its points begin.
  for_each_part(pool, bands_.size(),
                [&](std::size_t b) { bands_[b].count = count_readings(depth, bands_[b].row_begin, bands_[b].row_end); });
  std::size_t total = 0;
  for (Band& band : bands_) {
    band.first = total;
    total += band.count;
  }
  // Room for every pixel (as the frames to come may need): resizing to each
  // frame's count let the capacity grow to twice the largest.
  points_.reserve(depth.pixel_count());
  pixels_.reserve(depth.pixel_count());
  if (!colors.empty()) {
    codes_.reserve(depth.pixel_count());
    colors_.reserve(depth.pixel_count());
  }
  points_.resize(total);
  pixels_.resize(total);
  // The codes are kept for the colors only (2.5 MB for a Kinect frame).
  codes_.resize(colors.empty() ? 0 : total);
  colors_.resize(colors.empty() ? 0 : total);

  // 2. The bands' points, codes, colors and candidate voxels, with
  //    `alongside` as the first task (it starts first).
  const auto band_work = [&](std::size_t task) {
    if (task == 0) {
      alongside();
      return;
    }
    Band& band = bands_[task - 1];
    back_project_rows(depth, camera, pose, band.row_begin, band.row_end, points_.data() + band.first,
                      pixels_.data() + band.first);
    if (!colors.empty()) {
      for (std::size_t i = band.first; i < band.first + band.count; ++i) colors_[i] = colors[pixels_[i]];
    }
    find_voxels(grid, depth.width(), band);
  };
  for_each_part(pool, bands_.size() + 1, band_work);
  sum_band_counts();
}

void ImagePoints::keep_points(const DepthImage& depth, const PinholeCamera& camera, const Pose& pose) {
  if (points_kept_) return;
  const std::size_t total = count_readings(depth, 0, depth.height());
  points_.resize(total);
  pixels_.resize(total);
  back_project_rows(depth, camera, pose, 0, depth.height(), points_.data(), pixels_.data());
  points_kept_ = true;
}

void ImagePoints::sum_band_counts() {
  non_finite_ = 0;
  out_of_bounds_ = 0;
  for (const Band& band : bands_) {
    non_finite_ += band.non_finite;
    out_of_bounds_ += band.out_of_bounds;
  }
}

void ImagePoints::for_each_voxel(FunctionRef<void(std::uint64_t)> visit) const {
  for_each_voxel_in(0, ~std::uint64_t{0}, visit);
}

void ImagePoints::for_each_voxel_in(std::uint64_t first, std::uint64_t end,
                                    FunctionRef<void(std::uint64_t)> visit) const {
  // A brick's voxels once, though several bands may hand it over.
  BrickVoxels pending{0, 0};
  const auto flush = [&] {
    for (std::uint64_t rest = pending.voxels; rest != 0; rest &= rest - 1) {
      visit(pending.brick | static_cast<std::uint64_t>(std::countr_zero(rest)));
    }
  };
  for_each_brick_in(first, end, [&](BrickVoxels bricks) {
    if (bricks.brick != pending.brick) {
      flush();
      pending = {bricks.brick, 0};
    }
    pending.voxels |= bricks.voxels;
  });
  flush();
}

void ImagePoints::for_each_brick_in(std::uint64_t first, std::uint64_t end,
                                    FunctionRef<void(BrickVoxels)> visit) const {
  if (first >= end) return;
  constexpr std::uint64_t kBrickCodes = 64;
  // Each band's bricks that hold codes in [first, end): a contiguous run of
  // its sorted list; the first and last may hold codes outside it too.
  const std::uint64_t first_brick = first & ~(kBrickCodes - 1);
  const auto run = [&](const std::vector<BrickVoxels>& list) {
    const auto before = [](const BrickVoxels& b, std::uint64_t brick) { return b.brick < brick; };
    const auto begin = std::lower_bound(list.begin(), list.end(), first_brick, before);
    return std::pair{static_cast<std::size_t>(begin - list.begin()),
                     static_cast<std::size_t>(std::lower_bound(begin, list.end(), end, before) - list.begin())};
  };
  // The voxels of `bricks` in [first, end).
  const auto in_range = [&](BrickVoxels bricks) {
    if (bricks.brick < first) bricks.voxels &= ~std::uint64_t{0} << (first - bricks.brick);
    if (end - bricks.brick < kBrickCodes) bricks.voxels &= (std::uint64_t{1} << (end - bricks.brick)) - 1;
    return bricks;
  };
  // The bands' runs merged a stretch at a time (one band: its run): the
  // band with the lowest head hands over all its bricks up to the lowest
  // head of the others. The bands are strips of the image, so within a
  // subtree one band's bricks come in long stretches, and most bricks cost
  // a comparison or two. (A heap of the heads cost about 50 instructions a
  // code: 3.5% of the instructions of a TUM frame at 2 cm on two threads,
  // callgrind, and most of what two threads did more than one.)
  struct Run {
    const BrickVoxels* next;
    const BrickVoxels* stop;
  };
  std::array<Run, 64> small_runs;  // on the stack for up to 32 workers
  std::vector<Run> large_runs;
  Run* runs = small_runs.data();
  if (bands_.size() > small_runs.size()) {
    large_runs.resize(bands_.size());
    runs = large_runs.data();
  }
  std::size_t open = 0;  // runs[0, open) hold bricks
  for (const Band& band : bands_) {
    const auto [begin, stop] = run(band.candidates);
    if (begin < stop) runs[open++] = {band.candidates.data() + begin, band.candidates.data() + stop};
  }
  while (open > 0) {
    if (open == 1) {  // the last run (or the one band's) needs no comparisons
      for (const BrickVoxels* next = runs[0].next; next != runs[0].stop; ++next) visit(in_range(*next));
      return;
    }
    std::size_t lowest = 0;
    std::uint64_t bound = ~std::uint64_t{0};  // the lowest head of the other runs
    for (std::size_t r = 1; r < open; ++r) {
      if (runs[r].next->brick < runs[lowest].next->brick) {
        bound = runs[lowest].next->brick;
        lowest = r;
      } else {
        bound = std::min(bound, runs[r].next->brick);
      }
    }
    Run& stretch = runs[lowest];
    for (; stretch.next != stretch.stop && stretch.next->brick <= bound; ++stretch.next) visit(in_range(*stretch.next));
    if (stretch.next == stretch.stop) runs[lowest] = runs[--open];
  }
}

void ImagePoints::find_voxels(const Grid& grid, int width, Band& band) {
  VoxelScan scan = start_scan(width, band);
  add_candidates(grid, width, std::span<const Vec3f>(points_.data() + band.first, band.count),
                 pixels_.data() + band.first, codes_.empty() ? nullptr : codes_.data() + band.first, band, scan);
  finish_candidates(grid, band, scan);
}

void ImagePoints::find_voxels_streamed(const Grid& grid, const DepthImage& depth, const PinholeCamera& camera,
                                       const Pose& pose, Band& band) {
  // Row by row: the codes of every pixel of the row (image_row_codes:
  // those of back_project_rows' points bit for bit, four pixels at a time
  // in registers, kNoReadingCode for a pixel without a reading), and the
  // pixels with a reading added as add_candidates adds them. No point
  // is stored, compacted or given a pixel index (a TUM frame at 2 cm:
  // back-projection, codes and candidates were 16% of a steady frame, about
  // 6 ns a pixel).
  const int width = depth.width();
  const auto columns = static_cast<std::size_t>(width);
  band.row_factors.resize(columns);
  band.row_points.resize(columns);
  band.row_codes.resize(columns);
  double* const column_factor = band.row_factors.data();
  for (int u = 0; u < width; ++u) column_factor[u] = (u - camera.cx) / camera.fx;
  Vec3f* const points = band.row_points.data();
  std::uint64_t* const codes = band.row_codes.data();
  VoxelScan scan = start_scan(width, band);
  std::uint64_t* const above = band.above.data();
  for (int v = band.row_begin; v < band.row_end; ++v) {
    image_row_codes(grid, depth, column_factor, (v - camera.cy) / camera.fy, pose, v, points, codes);
    // add_candidates' rule (see there), the pixels without a reading
    // passed over: they neither keep a code nor stand beside one
    // (row_candidates.hpp). The kept codes are compacted in place.
    RowCandidateCounts counts;
    const std::size_t n = keep_row_candidates(codes, above, columns, counts);
    scan.non_finite += counts.non_finite;
    scan.outside += counts.outside;
    append_candidates(band, codes, n);
  }
  finish_candidates(grid, band, scan);
}

ImagePoints::VoxelScan ImagePoints::start_scan(int width, Band& band) {
  band.candidates.clear();
  band.above.assign(static_cast<std::size_t>(width), kNonFiniteCode);
  return VoxelScan{kNonFiniteCode, ~std::uint32_t{0},
                   static_cast<std::uint32_t>(band.row_begin) * static_cast<std::uint32_t>(width)};
}

void ImagePoints::add_candidates(const Grid& grid, int width, std::span<const Vec3f> points,
                                 const std::uint32_t* pixels, std::uint64_t* codes_out, Band& band, VoxelScan& scan) {
  std::array<std::uint64_t, 1024> block_codes;  // when the codes are not kept
  std::array<std::uint64_t, 1024> kept;         // a block's candidates, appended at its end
  // A voxel holds many neighbouring pixels: a code equal to its left or upper
  // neighbour's is dropped before sorting (a TUM frame at 2 cm keeps a
  // tenth). Any repeat dropped is one already kept: only the first
  // occurrence of a code reaches the candidates without a twin before it.
  // Without branches: whether a pixel's code is kept is unpredictable
  // (voxel borders, pixels without readings), and the branches were most of
  // this loop's time (a TUM frame at 2 cm: 11 ns a pixel with them).
  std::uint64_t left = scan.left;
  std::uint32_t left_pixel = scan.left_pixel;
  std::uint32_t row_start = scan.row_start;
  std::size_t non_finite = 0;
  std::size_t outside = 0;
  std::uint64_t* const above = band.above.data();
  constexpr std::size_t kBlock = block_codes.size();  // codes computed a block at a time stay in cache for the loop
  for (std::size_t block = 0; block < points.size(); block += kBlock) {
    const std::size_t size = std::min(kBlock, points.size() - block);
    std::uint64_t* const codes = codes_out == nullptr ? block_codes.data() : codes_out + block;
    voxel_codes(grid, points.subspan(block, size), codes);
    std::size_t n = 0;
    for (std::size_t j = 0; j < size; ++j) {
      const std::uint64_t code = codes[j];
      const std::uint32_t pixel = pixels[block + j];
      while (pixel - row_start >= static_cast<std::uint32_t>(width)) row_start += static_cast<std::uint32_t>(width);
      const std::size_t column = pixel - row_start;
      const bool beside = pixel == left_pixel + 1 && column != 0;
      left_pixel = pixel;
      const bool repeat = (beside & (code == left)) | (code == above[column]);
      kept[n] = code;
      n += static_cast<std::size_t>(code < kOutsideCode && !repeat);
      non_finite += static_cast<std::size_t>(code == kNonFiniteCode);
      outside += static_cast<std::size_t>(code == kOutsideCode);
      left = code;
      above[column] = code;
    }
    append_candidates(band, kept.data(), n);
  }
  scan.left = left;
  scan.left_pixel = left_pixel;
  scan.row_start = row_start;
  scan.non_finite += non_finite;
  scan.outside += outside;
}

void ImagePoints::append_candidates(Band& band, const std::uint64_t* codes, std::size_t n) {
  // Codes of one brick in a row (a brick is several pixels wide) join its record.
  std::vector<BrickVoxels>& list = band.candidates;
  for (std::size_t i = 0; i < n; ++i) {
    const BrickVoxels voxel{codes[i] & ~std::uint64_t{63}, std::uint64_t{1} << (codes[i] & 63)};
    if (!list.empty() && list.back().brick == voxel.brick) {
      list.back().voxels |= voxel.voxels;
    } else {
      list.push_back(voxel);
    }
  }
}

void ImagePoints::finish_candidates(const Grid& grid, Band& band, const VoxelScan& scan) {
  band.non_finite = scan.non_finite;
  band.out_of_bounds = scan.outside;
  std::vector<BrickVoxels>& list = band.candidates;
  radix_sort(list, 3 * grid.depth_levels() - 6, [](const BrickVoxels& b) { return b.brick >> 6; }, band.sort_scratch);
  // One record a brick: its records' voxels together.
  std::size_t kept = 0;
  for (std::size_t i = 0; i < list.size(); ++i) {
    if (kept > 0 && list[kept - 1].brick == list[i].brick) {
      list[kept - 1].voxels |= list[i].voxels;
    } else {
      list[kept++] = list[i];
    }
  }
  list.resize(kept);
}

std::size_t ImagePoints::memory_bytes() const {
  std::size_t bytes = points_.capacity() * sizeof(Vec3f) + pixels_.capacity() * sizeof(std::uint32_t) +
                      colors_.capacity() * sizeof(Rgb) + codes_.capacity() * sizeof(std::uint64_t) +
                      bands_.capacity() * sizeof(Band);
  for (const Band& band : bands_) {
    bytes += band.row_factors.capacity() * sizeof(double) + band.row_points.capacity() * sizeof(Vec3f) +
             band.row_codes.capacity() * sizeof(std::uint64_t);
    bytes += (band.candidates.capacity() + band.sort_scratch.records.capacity()) * sizeof(BrickVoxels) +
             band.above.capacity() * sizeof(std::uint64_t) + band.sort_scratch.counts.capacity() * sizeof(std::uint32_t);
  }
  return bytes;
}

}  // namespace umbra
