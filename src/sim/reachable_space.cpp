#include "umbra/sim/reachable_space.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace umbra::sim {

namespace {

constexpr std::uint8_t kClear = 0;
constexpr std::uint8_t kBlocked = 1;
constexpr std::uint8_t kReached = 2;

[[noreturn]] void bad(const std::string& what) { throw std::invalid_argument("ReachableSpace: " + what); }

/// Lattice index of the first cell whose centre is >= c, and of the last one whose centre is <= c.
std::int64_t first_centre_at_or_above(double c, double size) { return std::int64_t(std::ceil(c / size - 0.5)); }
std::int64_t last_centre_at_or_below(double c, double size) { return std::int64_t(std::floor(c / size - 0.5)); }

}  // namespace

ReachableSpace::ReachableSpace(const Scene& scene, const Box& region, double cell_size, double robot_radius,
                               Vec3d start)
    : cell_size_(cell_size) {
  if (!std::isfinite(cell_size) || !(cell_size > 0.0)) bad("cell_size must be finite and > 0");
  if (!std::isfinite(robot_radius) || !(robot_radius >= 0.0)) bad("robot_radius must be finite and >= 0");
  if (!region.min.is_finite() || !region.max.is_finite()) bad("the region must be finite");
  Index3 last{};
  double cells = 1.0;
  for (std::size_t a = 0; a < 3; ++a) {
    first_[a] = first_centre_at_or_above(region.min[a], cell_size);
    last[a] = last_centre_at_or_below(region.max[a], cell_size);
    size_[a] = last[a] - first_[a] + 1;
    if (size_[a] <= 0) bad("the region holds no cell centre (min > max, or thinner than a cell)");
    cells *= double(size_[a]);
  }
  if (cells > double(std::numeric_limits<std::int32_t>::max())) {
    std::ostringstream out;
    out << "the region holds " << cells << " cells, more than 2^31: use larger cells";
    bad(out.str());
  }
  const auto local = [&](std::int64_t i, std::int64_t j, std::int64_t k) {
    return std::size_t(i + size_[0] * (j + size_[1] * k));
  };

  // Block every cell whose centre is within the radius of (or inside) a primitive.
  std::vector<std::uint8_t> cell(std::size_t(cells), kClear);
  const auto rasterise = [&](const auto& primitive) {
    const Box b = bounds_of(primitive);
    Index3 lo{};
    Index3 hi{};
    for (std::size_t a = 0; a < 3; ++a) {
      lo[a] = std::max(first_[a], first_centre_at_or_above(b.min[a] - robot_radius, cell_size));
      hi[a] = std::min(last[a], last_centre_at_or_below(b.max[a] + robot_radius, cell_size));
      if (lo[a] > hi[a]) return;
    }
    for (std::int64_t k = lo[2]; k <= hi[2]; ++k) {
      for (std::int64_t j = lo[1]; j <= hi[1]; ++j) {
        for (std::int64_t i = lo[0]; i <= hi[0]; ++i) {
          std::uint8_t& c = cell[local(i - first_[0], j - first_[1], k - first_[2])];
          if (c == kBlocked) continue;
          const Vec3d centre{(double(i) + 0.5) * cell_size, (double(j) + 0.5) * cell_size,
                             (double(k) + 0.5) * cell_size};
          const double d = distance_to_solid(primitive, centre);
          if (d < robot_radius || d == 0.0) c = kBlocked;
        }
      }
    }
  };
  for (const Box& box : scene.boxes()) rasterise(box);
  for (const Cylinder& cylinder : scene.cylinders()) rasterise(cylinder);
  for (const Pipe& pipe : scene.pipes()) rasterise(pipe);
  clear_cells_ = std::size_t(std::count(cell.begin(), cell.end(), kClear));

  // Flood fill from the start's cell through faces.
  Index3 s{};
  for (std::size_t a = 0; a < 3; ++a) {
    s[a] = std::int64_t(std::floor(start[a] / cell_size)) - first_[a];
    if (!std::isfinite(start[a]) || s[a] < 0 || s[a] >= size_[a]) bad("the start lies outside the region");
  }
  if (cell[local(s[0], s[1], s[2])] != kClear) {
    bad("the start's cell is not clear: its centre is within robot_radius of a solid");
  }
  std::vector<Index3> pending{s};
  cell[local(s[0], s[1], s[2])] = kReached;
  while (!pending.empty()) {
    const Index3 c = pending.back();
    pending.pop_back();
    ++reachable_cells_;
    for (std::size_t a = 0; a < 3; ++a) {
      for (const std::int64_t step : {-1, 1}) {
        Index3 n = c;
        n[a] += step;
        if (n[a] < 0 || n[a] >= size_[a]) continue;
        std::uint8_t& v = cell[local(n[0], n[1], n[2])];
        if (v != kClear) continue;
        v = kReached;
        pending.push_back(n);
      }
    }
  }

  // Summed-volume table of the reached cells.
  const std::int64_t px = size_[0] + 1;
  const std::int64_t py = size_[1] + 1;
  prefix_.assign(std::size_t(px * py * (size_[2] + 1)), 0);
  const auto at = [&](std::int64_t i, std::int64_t j, std::int64_t k) -> std::uint32_t& {
    return prefix_[std::size_t(i + px * (j + py * k))];
  };
  for (std::int64_t k = 0; k < size_[2]; ++k) {
    for (std::int64_t j = 0; j < size_[1]; ++j) {
      for (std::int64_t i = 0; i < size_[0]; ++i) {
        const std::uint32_t v = cell[local(i, j, k)] == kReached ? 1 : 0;
        at(i + 1, j + 1, k + 1) = v + at(i, j + 1, k + 1) + at(i + 1, j, k + 1) + at(i + 1, j + 1, k) -
                                  at(i, j, k + 1) - at(i, j + 1, k) - at(i + 1, j, k) + at(i, j, k);
      }
    }
  }
}

double ReachableSpace::volume() const { return double(reachable_cells_) * cell_size_ * cell_size_ * cell_size_; }

std::uint32_t ReachableSpace::prefix(std::int64_t i, std::int64_t j, std::int64_t k) const {
  return prefix_[std::size_t(i + (size_[0] + 1) * (j + (size_[1] + 1) * k))];
}

bool ReachableSpace::reachable(Vec3d point) const {
  Index3 c{};
  for (std::size_t a = 0; a < 3; ++a) {
    if (!std::isfinite(point[a])) return false;
    c[a] = std::int64_t(std::floor(point[a] / cell_size_)) - first_[a];
    if (c[a] < 0 || c[a] >= size_[a]) return false;
  }
  return count_cells(c, {c[0] + 1, c[1] + 1, c[2] + 1}) == 1;
}

std::size_t ReachableSpace::count_in(Vec3d min, Vec3d max) const {
  // Box corners are usually cell boundaries (a map node's cube): a half
  // cell away from the nearest centre, so rounding cannot flip the answer.
  Index3 lo{};
  Index3 hi{};
  for (std::size_t a = 0; a < 3; ++a) {
    lo[a] = std::max<std::int64_t>(0, first_centre_at_or_above(min[a], cell_size_) - first_[a]);
    hi[a] = std::min<std::int64_t>(size_[a], last_centre_at_or_below(max[a], cell_size_) - first_[a] + 1);
    if (lo[a] >= hi[a]) return 0;
  }
  return count_cells(lo, hi);
}

std::size_t ReachableSpace::count_cells(const Index3& lo, const Index3& hi) const {
  const std::int64_t sum = std::int64_t(prefix(hi[0], hi[1], hi[2])) - prefix(lo[0], hi[1], hi[2]) -
                           prefix(hi[0], lo[1], hi[2]) - prefix(hi[0], hi[1], lo[2]) + prefix(lo[0], lo[1], hi[2]) +
                           prefix(lo[0], hi[1], lo[2]) + prefix(hi[0], lo[1], lo[2]) - prefix(lo[0], lo[1], lo[2]);
  return std::size_t(sum);
}

}  // namespace umbra::sim
