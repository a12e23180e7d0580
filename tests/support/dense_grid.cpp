#include "support/dense_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <tuple>

namespace umbra::test {

DenseGrid::DenseGrid(double resolution, int depth_levels, float clamp_min, float clamp_max)
    : rays_(resolution, depth_levels),
      resolution_(resolution),
      depth_levels_(depth_levels),
      size_(1u << depth_levels),
      offset_(std::int64_t{1} << (depth_levels - 1)),
      clamp_min_(clamp_min),
      clamp_max_(clamp_max),
      values_(std::size_t{size_} * size_ * size_, 0.0f),
      colors_(values_.size()) {}

void DenseGrid::blend(Key key, Rgb sample) {
  Color& c = colors_[index(key)];
  if (c.weight == 0) {
    c = {sample, 1};
    return;
  }
  const unsigned n = c.weight;
  auto mix = [n](unsigned old, unsigned add) { return static_cast<std::uint8_t>((old * n + add + (n + 1) / 2) / (n + 1)); };
  c.rgb = {mix(c.rgb.r, sample.r), mix(c.rgb.g, sample.g), mix(c.rgb.b, sample.b)};
  if (c.weight < 255) ++c.weight;
}

DenseGrid::Color DenseGrid::node_color(Key key, int depth) const {
  if (depth == 0) return color_at(key);
  const Key base{(key.x >> depth) << depth, (key.y >> depth) << depth, (key.z >> depth) << depth};
  const std::uint32_t half = 1u << (depth - 1);
  unsigned r = 0;
  unsigned g = 0;
  unsigned b = 0;
  unsigned n = 0;
  for (std::uint32_t i = 0; i < 8; ++i) {
    const Color c = node_color({base.x + (i & 1) * half, base.y + (i >> 1 & 1) * half, base.z + (i >> 2 & 1) * half},
                               depth - 1);
    if (c.weight == 0) continue;
    r += c.rgb.r;
    g += c.rgb.g;
    b += c.rgb.b;
    ++n;
  }
  if (n == 0) return {};
  auto mean = [n](unsigned sum) { return static_cast<std::uint8_t>((sum + n / 2) / n); };
  return {Rgb{mean(r), mean(g), mean(b)}, 1};
}

void DenseGrid::add(Key key, float delta) {
  float& v = values_[index(key)];
  v += delta;
  if (v < clamp_min_) v = clamp_min_;
  if (v > clamp_max_) v = clamp_max_;
}

void DenseGrid::set(Key key, float value) {
  values_[index(key)] = std::min(std::max(value, clamp_min_), clamp_max_) + 0.0f;
}

OctoMapRays::OctoMapRays(double resolution, int depth_levels)
    : resolution_(resolution),
      offset_(std::int64_t{1} << (depth_levels - 1)),
      size_(std::int64_t{1} << depth_levels) {}

bool OctoMapRays::key_of(Vec3f point, Key& key) const {
  for (int axis = 0; axis < 3; ++axis) {
    const double scaled = std::floor((1.0 / resolution_) * static_cast<double>(point[axis]));
    if (!(scaled >= -static_cast<double>(offset_) && scaled < static_cast<double>(offset_))) return false;
    key[axis] = static_cast<std::uint32_t>(static_cast<std::int64_t>(scaled) + offset_);
  }
  return true;
}

double OctoMapRays::centre(std::uint32_t k) const {
  return (static_cast<double>(static_cast<std::int64_t>(k) - offset_) + 0.5) * resolution_;
}

bool OctoMapRays::ray_keys(Vec3f origin, Vec3f end, std::vector<Key>& keys) const {
  keys.clear();
  Key key_origin;
  Key key_end;
  if (!key_of(origin, key_origin) || !key_of(end, key_end)) return false;
  if (key_origin == key_end) return true;
  keys.push_back(key_origin);

  // OctoMap's computeRayKeys, step by step.
  float dx = end.x - origin.x;
  float dy = end.y - origin.y;
  float dz = end.z - origin.z;
  const float squared = dx * dx + dy * dy + dz * dz;
  auto length = static_cast<float>(std::sqrt(static_cast<double>(squared)));
  if (length == 0.0f) {
    // The squared length underflowed float (every component below about
    // 2.6e-23): OctoMap divides by zero here and walks on until its key
    // buffer overflows. umbra's rule instead (docs/octomap-agreement.md):
    // the same walk with the direction and length computed in double.
    const double ex = static_cast<double>(end.x) - static_cast<double>(origin.x);
    const double ey = static_cast<double>(end.y) - static_cast<double>(origin.y);
    const double ez = static_cast<double>(end.z) - static_cast<double>(origin.z);
    const double norm = std::sqrt(ex * ex + ey * ey + ez * ez);
    dx = static_cast<float>(ex / norm);
    dy = static_cast<float>(ey / norm);
    dz = static_cast<float>(ez / norm);
    length = static_cast<float>(norm);
  } else {
    dx /= length;
    dy /= length;
    dz /= length;
  }
  const float direction[3] = {dx, dy, dz};
  int step[3];
  double t_max[3];
  double t_delta[3];
  std::int64_t current[3] = {key_origin.x, key_origin.y, key_origin.z};
  for (int i = 0; i < 3; ++i) {
    if (direction[i] > 0.0) {
      step[i] = 1;
    } else if (direction[i] < 0.0) {
      step[i] = -1;
    } else {
      step[i] = 0;
    }
    if (step[i] != 0) {
      double border = centre(static_cast<std::uint32_t>(current[i]));
      border += static_cast<float>(step[i] * resolution_ * 0.5);
      t_max[i] = (border - origin[i]) / direction[i];
      t_delta[i] = resolution_ / std::fabs(direction[i]);
    } else {
      t_max[i] = std::numeric_limits<double>::max();
      t_delta[i] = std::numeric_limits<double>::max();
    }
  }
  for (;;) {
    int dim;
    if (t_max[0] < t_max[1]) {
      dim = t_max[0] < t_max[2] ? 0 : 2;
    } else {
      dim = t_max[1] < t_max[2] ? 1 : 2;
    }
    current[dim] += step[dim];
    t_max[dim] += t_delta[dim];
    if (current[dim] < 0 || current[dim] >= size_) return true;
    const Key k{static_cast<std::uint32_t>(current[0]), static_cast<std::uint32_t>(current[1]),
                static_cast<std::uint32_t>(current[2])};
    if (k == key_end) return true;
    if (std::min(std::min(t_max[0], t_max[1]), t_max[2]) > length) return true;
    keys.push_back(k);
  }
}

void DenseGrid::insert_scan(Vec3f origin, std::span<const Vec3f> points, const DenseScanOptions& options,
                            float hit, float miss, std::span<const Rgb> colors) {
  using Triple = std::tuple<std::uint32_t, std::uint32_t, std::uint32_t>;
  auto triple = [](Key k) { return Triple{k.x, k.y, k.z}; };
  std::vector<Vec3f> ends;
  if (options.discrete) {
    std::set<Triple> seen;
    for (const Vec3f& p : points) {
      Key k;
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || !key_of(p, k)) continue;
      if (seen.insert(triple(k)).second) {
        ends.push_back({static_cast<float>(centre(k.x)), static_cast<float>(centre(k.y)),
                        static_cast<float>(centre(k.z))});
      }
    }
  } else {
    ends.assign(points.begin(), points.end());
  }
  std::set<Triple> free_cells;
  std::set<Triple> occupied_cells;
  std::vector<Key> keys;
  for (const Vec3f& p : ends) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    const float ox = p.x - origin.x;
    const float oy = p.y - origin.y;
    const float oz = p.z - origin.z;
    const double range = std::sqrt(static_cast<double>(ox * ox + oy * oy + oz * oz));
    if (options.max_range <= 0.0 || range <= options.max_range) {
      if (ray_keys(origin, p, keys)) {
        for (const Key& k : keys) free_cells.insert(triple(k));
      }
      Key k;
      if (key_of(p, k)) occupied_cells.insert(triple(k));
    } else {
      const auto length = static_cast<float>(range);
      const float m = static_cast<float>(options.max_range);
      Vec3f direction{ox / length, oy / length, oz / length};
      if (std::isinf(range)) {
        // A point beyond about 1.8e19 m: OctoMap's direction is zero (it
        // divides by an infinite length) and its ray updates nothing; umbra
        // cuts the ray along the double direction (docs/octomap-agreement.md).
        const double ex = static_cast<double>(p.x) - static_cast<double>(origin.x);
        const double ey = static_cast<double>(p.y) - static_cast<double>(origin.y);
        const double ez = static_cast<double>(p.z) - static_cast<double>(origin.z);
        const double norm = std::sqrt(ex * ex + ey * ey + ez * ez);
        direction = {static_cast<float>(ex / norm), static_cast<float>(ey / norm), static_cast<float>(ez / norm)};
      }
      const Vec3f end{origin.x + direction.x * m, origin.y + direction.y * m, origin.z + direction.z * m};
      if (ray_keys(origin, end, keys)) {
        for (const Key& k : keys) free_cells.insert(triple(k));
      }
    }
  }
  for (const Triple& t : occupied_cells) free_cells.erase(t);
  for (const Triple& t : free_cells) add(Key{std::get<0>(t), std::get<1>(t), std::get<2>(t)}, miss);
  for (const Triple& t : occupied_cells) add(Key{std::get<0>(t), std::get<1>(t), std::get<2>(t)}, hit);
  // Colors: each point whose ray ends in a hit, in scan order.
  for (std::size_t i = 0; i < colors.size(); ++i) {
    const Vec3f& p = points[i];
    Key k;
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || !key_of(p, k)) continue;
    const Vec3f end = options.discrete ? Vec3f{static_cast<float>(centre(k.x)), static_cast<float>(centre(k.y)),
                                               static_cast<float>(centre(k.z))}
                                       : p;
    const float ox = end.x - origin.x;
    const float oy = end.y - origin.y;
    const float oz = end.z - origin.z;
    const double range = std::sqrt(static_cast<double>(ox * ox + oy * oy + oz * oz));
    if (options.max_range > 0.0 && range > options.max_range) continue;
    blend(k, colors[i]);
  }
}

float DenseGrid::max_in_node(Key key, int depth) const {
  const std::uint32_t n = 1u << depth;
  const Key base{(key.x >> depth) << depth, (key.y >> depth) << depth, (key.z >> depth) << depth};
  float best = -std::numeric_limits<float>::infinity();
  for (std::uint32_t z = 0; z < n; ++z)
    for (std::uint32_t y = 0; y < n; ++y)
      for (std::uint32_t x = 0; x < n; ++x) best = std::max(best, at({base.x + x, base.y + y, base.z + z}));
  return best;
}

bool DenseGrid::any_in_node(Key key, int depth, float free_below, float occupied_above, bool want_free) const {
  const std::uint32_t n = 1u << depth;
  const Key base{(key.x >> depth) << depth, (key.y >> depth) << depth, (key.z >> depth) << depth};
  for (std::uint32_t z = 0; z < n; ++z) {
    for (std::uint32_t y = 0; y < n; ++y) {
      for (std::uint32_t x = 0; x < n; ++x) {
        const float v = at({base.x + x, base.y + y, base.z + z});
        const bool is_free = v < free_below;
        const bool is_unknown = !is_free && !(v > occupied_above);
        if (want_free ? is_free : is_unknown) return true;
      }
    }
  }
  return false;
}

}  // namespace umbra::test
