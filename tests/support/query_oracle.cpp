#include "support/query_oracle.hpp"

#include <algorithm>

namespace umbra::test {

OccupancyMap random_map(const RandomMapSpec& spec) {
  OccupancyMap map(spec.resolution, spec.depth_levels);
  map.set_auto_prune(spec.auto_prune);
  std::mt19937 rng(spec.seed);
  const SensorModel sensor = map.sensor_model();
  const std::uint32_t size = 1u << spec.depth_levels;
  // Values that matter: clamped ends (they prune), values near the default
  // thresholds, exactly 0 (unknown), ordinary hits and misses.
  const std::vector<float> values = {sensor.clamp_min_log_odds(), sensor.clamp_max_log_odds(), -0.4055f, 0.8473f,
                                     0.0f, 0.05f, -0.05f, 1.7f, -1.2f, 0.3f};
  auto pick_value = [&] { return values[std::uniform_int_distribution<std::size_t>(0, values.size() - 1)(rng)]; };

  // Uniform aligned blocks: they become pruned nodes (or all-same nodes
  // with automatic pruning off).
  std::uint64_t covered = 0;
  const std::uint64_t total = std::uint64_t{size} * size * size;
  for (int attempt = 0; attempt < 200 && covered < spec.block_fill * double(total); ++attempt) {
    const int block_depth = std::uniform_int_distribution<int>(1, std::max(1, spec.depth_levels - 2))(rng);
    const std::uint32_t edge = 1u << block_depth;
    std::uniform_int_distribution<std::uint32_t> start(0, size / edge - 1);
    const Key base{start(rng) * edge, start(rng) * edge, start(rng) * edge};
    const float value = pick_value();
    for (std::uint32_t z = 0; z < edge; ++z) {
      for (std::uint32_t y = 0; y < edge; ++y) {
        for (std::uint32_t x = 0; x < edge; ++x) map.set_log_odds(Key{base.x + x, base.y + y, base.z + z}, value);
      }
    }
    covered += std::uint64_t{edge} * edge * edge;
  }
  std::uniform_int_distribution<std::uint32_t> coordinate(0, size - 1);
  for (int i = 0; i < spec.scattered_voxels; ++i) {
    map.set_log_odds(Key{coordinate(rng), coordinate(rng), coordinate(rng)}, pick_value());
  }
  // A few scans of random rays (inside the map's extent).
  const double half = map.grid().half_extent() * 0.95;
  std::uniform_real_distribution<float> anywhere(static_cast<float>(-half), static_cast<float>(half));
  for (int scan = 0; scan < spec.scans; ++scan) {
    const Vec3f origin{anywhere(rng) * 0.3f, anywhere(rng) * 0.3f, anywhere(rng) * 0.3f};
    std::vector<Vec3f> points(200);
    for (Vec3f& p : points) p = {anywhere(rng), anywhere(rng), anywhere(rng)};
    InsertOptions options;
    options.integrator = IntegratorKind::discrete;
    map.insert_point_cloud(origin, points, options);
  }
  return map;
}

DenseValues::DenseValues(const OccupancyMap& map)
    : size_(map.grid().keys_per_axis()), values_(std::size_t{size_} * size_ * size_) {
  for (std::uint32_t z = 0; z < size_; ++z) {
    for (std::uint32_t y = 0; y < size_; ++y) {
      for (std::uint32_t x = 0; x < size_; ++x) values_[index({x, y, z})] = map.node(Key{x, y, z}, 0).log_odds;
    }
  }
}

DenseValues::Summary DenseValues::summarize(Key base, int depth, const LogOddsThresholds& thresholds) const {
  const std::uint32_t edge = 1u << depth;
  Summary s{at(base), false, false, true};
  for (std::uint32_t z = 0; z < edge; ++z) {
    for (std::uint32_t y = 0; y < edge; ++y) {
      for (std::uint32_t x = 0; x < edge; ++x) {
        const float v = at({base.x + x, base.y + y, base.z + z});
        s.max = std::max(s.max, v);
        s.any_free |= thresholds.is_free(v);
        s.any_unknown |= thresholds.is_unknown(v);
        s.all_equal &= v == at(base);
      }
    }
  }
  return s;
}

Key child_key(Key key, int depth, unsigned slot) {
  const std::uint32_t half = 1u << (depth - 1);
  return {key.x + ((slot & 1u) ? half : 0u), key.y + ((slot & 2u) ? half : 0u), key.z + ((slot & 4u) ? half : 0u)};
}

namespace {

void enumerate(const OccupancyMap& map, Key key, int depth, int query_depth, std::vector<OracleNode>& out) {
  const Node node = map.node(key, depth);
  bool leaf = depth <= query_depth || !node.has_children;
  if (!leaf && !map.auto_prune()) {
    // Eight childless children of one value (and color) act as one leaf.
    bool same = true;
    const Node first = map.node(child_key(key, depth, 0), depth - 1);
    for (unsigned slot = 0; slot < 8 && same; ++slot) {
      const Node child = map.node(child_key(key, depth, slot), depth - 1);
      same = !child.has_children && child.log_odds == first.log_odds && child.color == first.color;
    }
    leaf = same;
  }
  out.push_back({key, depth, leaf});
  if (leaf) return;
  for (unsigned slot = 0; slot < 8; ++slot) enumerate(map, child_key(key, depth, slot), depth - 1, query_depth, out);
}

}  // namespace

std::vector<OracleNode> enumerate_nodes(const OccupancyMap& map, int query_depth) {
  std::vector<OracleNode> out;
  enumerate(map, Key{}, map.depth_levels(), query_depth, out);
  return out;
}

}  // namespace umbra::test
