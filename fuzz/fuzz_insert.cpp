// libFuzzer target: point insertion (OccupancyMap::insert_point_cloud) with
// hostile coordinates.
//
// Input: byte 0 the integrator (bits 0-1: simple, discrete, fast, fast),
// a bounding box (bit 2), two threads (bit 3), the clear depth (bits 4-6:
// automatic, 0..5); byte 1 the fine steps (bits 0-1: 0, 1, 2, 5), max_range
// (bits 2-4: none, 0, 1e-30, 0.05, 0.3, 1, 3, 1e30), the resolution (bits
// 5-6: 0.1, 0.5, 0.05, 0.37); byte 2 the number of scans (1-3). Then per
// scan a sensor origin, a point count (1-24) and the points; then, with bit
// 2, the box's two corners. Every coordinate is one kind byte and its
// payload, biased to what breaks ray walks: exactly 0 or -0, tiny values
// (1e-23, 1e-29, denormals: rays whose float squared length underflows),
// voxel and coarse-node borders with and without a hair's offset, the
// sensor's own coordinate (rays along faces and edges), huge values (1e19,
// 3e38, inf), and raw float bits (NaN too). Past the end of the input every
// byte reads 0. The map has 5 depth levels (32 voxels a side), so the dense
// reference is small and a scan easily leaves the map.
//
// Crashes (the rule): any exception but the std::invalid_argument /
// std::out_of_range of a refused scan (a sensor origin outside the map or
// not finite), after which the map must be unchanged; a failed
// UMBRA_ASSERT; a sanitizer report; and, after each scan:
//  - the tree's invariants;
//  - simple and discrete without a box: every voxel's log-odds bit for bit
//    those of the dense-grid reference (tests/support/dense_grid.cpp:
//    OctoMap's insertPointCloud written out plainly, with umbra's rule for
//    rays whose float squared length underflows);
//  - with a box: no voxel outside the box's voxels changed;
//  - every changed voxel lies near some ray: within 2 voxel diagonals of
//    its segment (simple, discrete), within three coarse-node diagonals
//    (fast, which clears whole coarse nodes around a group of rays; not
//    checked for fast with a box, whose clipped rays of one group may
//    begin far apart).
// Cost per input: up to three insertions into a 32^3 map and a few passes
// over its 32,768 voxels after each; the maps (one per resolution) are kept
// between inputs and cleared at the end of each (docs/fuzzing.md).
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <optional>
#include <span>
#include <stdexcept>
#include <vector>

#include "fuzz_support.hpp"
#include "support/dense_grid.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace {

using namespace umbra;
using umbra::fuzz::require;

constexpr int kDepthLevels = 5;  // 32 voxels a side: a dense reference of 32,768 voxels

// The checks' loops over every voxel are left out of the coverage
// instrumentation: their branches say nothing about the library, and
// tracing them was most of the time per input.
#define UMBRA_FUZZ_NO_COVERAGE __attribute__((no_sanitize("coverage")))

/// The input as a stream of bytes that reads 0 past its end.
class Input {
 public:
  Input(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  std::uint8_t byte() { return at_ < size_ ? data_[at_++] : 0; }
  float raw_float() {
    std::uint32_t bits = 0;
    for (int i = 0; i < 4; ++i) bits = bits << 8 | byte();
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t at_ = 0;
};

constexpr std::array<float, 10> kTiny = {1e-23f, 1e-29f, 2.5e-23f, 3e-23f, 1e-22f, 1e-20f, 1e-40f,
                                         std::numeric_limits<float>::denorm_min(),
                                         std::numeric_limits<float>::min(), 1e-16f};
constexpr std::array<float, 8> kHuge = {1e19f, 2e19f, 1e30f, 3e38f, std::numeric_limits<float>::max(),
                                        std::numeric_limits<float>::infinity(), 5000.0f, 1e9f};

/// One coordinate, biased to what breaks ray walks; `sensor` is the scan's
/// sensor coordinate on this axis (0 while decoding the sensor itself).
float coordinate(Input& in, double resolution, float sensor) {
  const std::uint8_t kind = in.byte();
  const std::uint8_t payload = in.byte();
  const float sign = (payload & 0x80) != 0 ? -1.0f : 1.0f;
  const auto r = static_cast<float>(resolution);
  // -16..15 voxels (the map), or twice that (the map and beyond)
  const float voxels = static_cast<float>((static_cast<int>(payload & 0x1f) - 16) * ((payload & 0x20) != 0 ? 2 : 1));
  switch (kind % 10) {
    case 0: return sign * 0.0f;
    case 1: return sign * kTiny[payload % kTiny.size()];
    case 2: return voxels * r;                                              // a voxel border
    case 3: return voxels * r + sign * kTiny[(payload >> 3) % kTiny.size()];  // a hair from one
    case 4: return voxels * r * static_cast<float>(1 << (1 + kind / 10 % 3));  // a coarse-node border
    case 5: return static_cast<float>(static_cast<std::int8_t>(payload)) / 128.0f * 1.1f * 16.0f * r;
    case 6: return sign * kHuge[payload % kHuge.size()];
    case 7: return in.raw_float();
    case 8: return sensor;                // along a face through the sensor
    default: return sensor + voxels * r;  // along a face a whole number of voxels away
  }
}

Vec3f point(Input& in, double resolution, Vec3f sensor) {
  Vec3f p;
  for (std::size_t axis = 0; axis < 3; ++axis) p[axis] = coordinate(in, resolution, sensor[axis]);
  return p;
}

/// A leaf of the map: what read_voxel_values needs of it.
struct Leaf {
  Key key;
  int depth;
  float log_odds;
};

/// `leaves` written out voxel by voxel into `values` (x fastest, `n` a side).
UMBRA_FUZZ_NO_COVERAGE void fill_voxel_values(const std::vector<Leaf>& leaves, std::uint32_t n,
                                              std::vector<float>& values) {
  values.resize(std::size_t{n} * n * n);
  for (const Leaf& leaf : leaves) {
    const std::uint32_t edge = 1u << leaf.depth;
    for (std::uint32_t z = 0; z < edge; ++z) {
      for (std::uint32_t y = 0; y < edge; ++y) {
        float* row = &values[(std::size_t{leaf.key.z + z} * n + leaf.key.y + y) * n + leaf.key.x];
        std::fill(row, row + edge, leaf.log_odds);
      }
    }
  }
}

/// Every finest voxel's log-odds (x fastest), read leaf by leaf into `values`.
void read_voxel_values(const OccupancyMap& map, std::vector<float>& values) {
  static std::vector<Leaf> leaves;
  leaves.clear();
  // Only collected here: the library's thunk that calls this visitor is
  // compiled with coverage tracing, and writing the voxels out in it was
  // the largest part of an input's time.
  map.for_each_leaf([](const Node& leaf) { leaves.push_back({leaf.key, leaf.depth, leaf.log_odds}); });
  fill_voxel_values(leaves, map.grid().keys_per_axis(), values);
}

/// Distance from `p` to the segment a-b.
UMBRA_FUZZ_NO_COVERAGE double distance_to_segment(Vec3d p, Vec3d a, Vec3d b) {
  const Vec3d d = b - a;
  const double length_squared = d.dot(d);
  const double t = length_squared > 0.0 ? std::clamp((p - a).dot(d) / length_squared, 0.0, 1.0) : 0.0;
  return (p - (a + d * t)).norm();
}

/// The same bits (log-odds compared bit for bit: -0 is not 0).
UMBRA_FUZZ_NO_COVERAGE bool same_bits(std::span<const float> a, std::span<const float> b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size_bytes()) == 0;
}

/// After a scan: where a voxel changed from `before` to `after`, it lies
/// inside `box_keys` (when given) and, when `allowed` is finite, within
/// `allowed` metres of one of `segments`. Rows of voxels that did not
/// change are skipped whole.
UMBRA_FUZZ_NO_COVERAGE void require_changes_near_rays(const Grid& grid, const std::vector<float>& before,
                                                      const std::vector<float>& after,
                                                      const std::optional<std::pair<Key, Key>>& box_keys,
                                                      const std::vector<std::pair<Vec3d, Vec3d>>& segments,
                                                      double allowed) {
  const std::uint32_t n = grid.keys_per_axis();
  for (std::uint32_t z = 0; z < n; ++z) {
    for (std::uint32_t y = 0; y < n; ++y) {
      const std::size_t row = (std::size_t{z} * n + y) * n;
      if (same_bits({&before[row], n}, {&after[row], n})) continue;
      for (std::uint32_t x = 0; x < n; ++x) {
        if (std::bit_cast<std::uint32_t>(before[row + x]) == std::bit_cast<std::uint32_t>(after[row + x])) continue;
        if (box_keys) {
          const auto& [low, high] = *box_keys;
          require(x >= low.x && y >= low.y && z >= low.z && x <= high.x && y <= high.y && z <= high.z,
                  "with a box, only the voxels it covers change");
        }
        if (!std::isfinite(allowed)) continue;
        const Vec3d centre = grid.center({x, y, z});
        bool near = false;
        for (const auto& [a, b] : segments) near = near || distance_to_segment(centre, a, b) <= allowed;
        require(near, "every changed voxel lies near a ray");
      }
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Input in(data, size);
  const std::uint8_t settings = in.byte();
  const std::uint8_t more = in.byte();
  const int scans = 1 + in.byte() % 3;
  constexpr std::array<IntegratorKind, 4> kKinds = {IntegratorKind::simple, IntegratorKind::discrete,
                                                    IntegratorKind::fast, IntegratorKind::fast};
  constexpr std::array<int, 4> kFineSteps = {0, 1, 2, 5};
  constexpr std::array<double, 8> kMaxRanges = {-1.0, 0.0, 1e-30, 0.05, 0.3, 1.0, 3.0, 1e30};
  constexpr std::array<double, 4> kResolutions = {0.1, 0.5, 0.05, 0.37};
  InsertOptions options;
  options.integrator = kKinds[settings & 3];
  options.threads = (settings & 8) != 0 ? 2 : 1;
  options.clear_depth = std::min((settings >> 4 & 7) - 1, kDepthLevels);  // -1 (automatic) .. the map's depth
  options.fine_steps = kFineSteps[more & 3];
  options.max_range = kMaxRanges[more >> 2 & 7];
  const double resolution = kResolutions[more >> 5 & 3];
  const bool with_box = (settings & 4) != 0;

  const SensorModel sensor;
  // One map per resolution, cleared at the end of every input: a new map
  // started two worker threads and allocated the integrator's buffers
  // afresh (pages AddressSanitizer then handed back to the system) for
  // every input. Cleared at the end, not the start, so that an input frees
  // what it allocated and libFuzzer's leak check after each input stays
  // quiet unless something leaks. That clearing leaves nothing behind is
  // checked below: the map reads all unknown before the first scan.
  static std::array<std::optional<OccupancyMap>, kResolutions.size()> maps;
  std::optional<OccupancyMap>& kept_map = maps[more >> 5 & 3];
  if (!kept_map) kept_map.emplace(resolution, kDepthLevels, sensor);
  OccupancyMap& map = *kept_map;
  struct ClearAtEnd {
    OccupancyMap& map;
    ~ClearAtEnd() {
      map.clear();
      map.set_bounding_box(std::nullopt);
    }
  } clear_at_end{map};
  // A fresh reference, copied from an empty one kept per resolution (its
  // construction's fresh pages were a good part of an input's time).
  static std::array<std::optional<test::DenseGrid>, kResolutions.size()> empty_references;
  static std::optional<test::DenseGrid> reference_copy;
  std::optional<test::DenseGrid>& empty = empty_references[more >> 5 & 3];
  if (!empty) empty.emplace(resolution, kDepthLevels, sensor.clamp_min_log_odds(), sensor.clamp_max_log_odds());
  if (reference_copy) {
    *reference_copy = *empty;
  } else {
    reference_copy = *empty;
  }
  test::DenseGrid& reference = *reference_copy;
  const bool exact = options.integrator != IntegratorKind::fast;

  struct ScanInput {
    Vec3f origin;
    std::vector<Vec3f> points;
  };
  std::vector<ScanInput> inputs(static_cast<std::size_t>(scans));
  for (ScanInput& scan : inputs) {
    scan.origin = point(in, resolution, {0, 0, 0});
    const int count = 1 + in.byte() % 24;
    for (int i = 0; i < count; ++i) scan.points.push_back(point(in, resolution, scan.origin));
  }
  std::optional<Aabb> box;
  if (with_box) {
    const Vec3f a = point(in, resolution, {0, 0, 0});
    const Vec3f b = point(in, resolution, {0, 0, 0});
    if (a.is_finite() && b.is_finite()) {
      box = Aabb{{std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)},
                 {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}};
      map.set_bounding_box(box);
    }
  }
  // The voxels the box covers, as the integrator counts them (its faces' voxels included).
  std::optional<std::pair<Key, Key>> box_keys;
  if (box) {
    const double inside = map.grid().half_extent() - 0.5 * resolution;
    const auto clamp = [inside](Vec3d p) {
      return Vec3d{std::clamp(p.x, -inside, inside), std::clamp(p.y, -inside, inside), std::clamp(p.z, -inside, inside)};
    };
    box_keys = std::pair{map.key(clamp(box->min)), map.key(clamp(box->max))};
  }

  // Kept between inputs: fresh pages for every input were a good part of its time.
  static std::vector<float> before;
  static std::vector<float> after;
  static std::vector<float> now;
  read_voxel_values(map, before);
  require(same_bits(before, reference.values()), "a cleared map is unknown everywhere");
  for (const ScanInput& scan : inputs) {
    try {
      map.insert_point_cloud(scan.origin, scan.points, options);
    } catch (const std::invalid_argument& e) {
      if (scan.origin.is_finite()) std::fprintf(stderr, "refused: %s\n", e.what());
      require(!scan.origin.is_finite(), "only a non-finite sensor origin is refused as an invalid argument");
      read_voxel_values(map, now);
      require(now == before, "a refused scan changes nothing");
      continue;
    } catch (const std::out_of_range&) {
      require(!map.grid().key_checked(scan.origin), "only a sensor origin outside the map is refused as out of range");
      read_voxel_values(map, now);
      require(now == before, "a refused scan changes nothing");
      continue;
    }
    require(fuzz::invariants_hold(map), "the tree's invariants hold after a scan");
    read_voxel_values(map, after);

    if (exact && !box) {
      reference.insert_scan(scan.origin, scan.points, {options.integrator == IntegratorKind::discrete, options.max_range},
                            sensor.hit_log_odds(), sensor.miss_log_odds());
      require(same_bits(reference.values(), after), "simple / discrete: every voxel as in the dense-grid reference");
    }

    // The rays' segments: origin to point, cut at max_range.
    static std::vector<std::pair<Vec3d, Vec3d>> segments;
    segments.clear();
    const Vec3d origin(scan.origin);
    for (const Vec3f& p : scan.points) {
      if (!p.is_finite()) continue;
      Vec3d end(p);
      const double range = (end - origin).norm();
      if (options.max_range > 0.0 && range > options.max_range) end = origin + (end - origin) * (options.max_range / range);
      segments.emplace_back(origin, end);
    }
    const int coarse = options.integrator == IntegratorKind::fast ? options.resolved_clear_depth(map.grid()) : 0;
    double allowed = exact ? 2.0 * std::sqrt(3.0) * resolution
                           : 3.0 * std::sqrt(3.0) * map.grid().node_size(coarse) + std::sqrt(3.0) * resolution;
    if (!exact && box) allowed = std::numeric_limits<double>::infinity();
    require_changes_near_rays(map.grid(), before, after, box_keys, segments, allowed);
    std::swap(before, after);
  }
  return 0;
}
