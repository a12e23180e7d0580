// Tests of the native map file (.umb): exact round trips, validation of every
// malformed input, atomic saving, header-only reading.
//
// Malformed files are made two ways: by damaging a file save_map wrote
// (truncation, bit flips), and by building files from scratch with an
// independent encoder written here from docs/map-format.md (its own CRC-32,
// zstd frames made of raw blocks), so that a file can be wrong in one
// precise way while both checksums are valid. Cost: a few seconds with
// asserts on; the largest map has ~260k voxels, the bit-flip and truncation
// sweeps load a ~300-byte file a few thousand times.
#include "support/map_internals.hpp"
#include "umbra/io/map_file.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "support/test_support.hpp"

namespace umbra {
namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;

// --- files and little-endian fields -------------------------------------------

using test::read_bytes;
using test::write_bytes;

void put_le(Bytes& b, std::size_t at, std::uint64_t v, int size) {
  for (int i = 0; i < size; ++i) b[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
}
std::uint64_t get_le(const Bytes& b, std::size_t at, int size) {
  std::uint64_t v = 0;
  for (int i = size - 1; i >= 0; --i) v = (v << 8) | b[at + i];
  return v;
}
void append_le(Bytes& b, std::uint64_t v, int size) {
  b.resize(b.size() + size);
  put_le(b, b.size() - size, v, size);
}

/// CRC-32 as the spec defines it (reflected polynomial 0xEDB88320, initial
/// and final XOR 0xFFFFFFFF), written bit by bit so it is independent of zlib.
std::uint32_t reference_crc32(const std::uint8_t* data, std::size_t size) {
  std::uint32_t crc = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

// Header layout from docs/map-format.md.
constexpr std::size_t kHeader = 124;
constexpr std::size_t kAtVersion = 8, kAtFlags = 12, kAtResolution = 16, kAtDepth = 24, kAtReserved = 28,
                      kAtOccupied = 32, kAtFree = 40, kAtPHit = 48, kAtClampMax = 72, kAtInner = 80,
                      kAtChildless = 88, kAtStructure = 96, kAtStructureCompressed = 104, kAtValuesCompressed = 112,
                      kAtHeaderCrc = 120;

/// Recomputes both checksums after a test changed some bytes on purpose.
void reseal(Bytes& file) {
  put_le(file, kAtHeaderCrc, reference_crc32(file.data(), kAtHeaderCrc), 4);
  put_le(file, file.size() - 4, reference_crc32(file.data(), file.size() - 4), 4);
}

// --- an independent encoder -------------------------------------------------------

/// A zstd frame (RFC 8878) of raw blocks: content stored as is.
Bytes raw_zstd_frame(const Bytes& content) {
  Bytes frame = {0x28, 0xB5, 0x2F, 0xFD};  // magic 0xFD2FB528
  frame.push_back(0xA0);                   // 4-byte content size, single segment, no checksum
  append_le(frame, content.size(), 4);
  std::size_t pos = 0;
  do {
    const std::size_t n = std::min<std::size_t>(content.size() - pos, 128 * 1024);
    const bool last = pos + n == content.size();
    append_le(frame, (last ? 1u : 0u) | (n << 3), 3);  // block type 0 = raw
    frame.insert(frame.end(), content.begin() + static_cast<std::ptrdiff_t>(pos),
                 content.begin() + static_cast<std::ptrdiff_t>(pos + n));
    pos += n;
  } while (pos < content.size());
  return frame;
}

Bytes float_bytes(const std::vector<float>& values) {
  Bytes b;
  for (const float v : values) append_le(b, std::bit_cast<std::uint32_t>(v), 4);
  return b;
}

struct FileParts {
  MapConfig config;
  std::uint32_t flags = 0;
  std::uint64_t inner_nodes = 0;
  Bytes structure;             ///< decompressed child masks
  std::vector<float> values;   ///< childless nodes' log-odds
  Bytes structure_frame;       ///< default: raw_zstd_frame(structure)
  Bytes values_frame;          ///< default: raw_zstd_frame(float_bytes(values))
};

Bytes make_file(const FileParts& p) {
  const Bytes sframe = p.structure_frame.empty() ? raw_zstd_frame(p.structure) : p.structure_frame;
  const Bytes vframe = p.values_frame.empty() ? raw_zstd_frame(float_bytes(p.values)) : p.values_frame;
  Bytes f = {'U', 'M', 'B', 'R', 'A', 'M', 'A', 'P'};
  append_le(f, 1, 4);
  append_le(f, p.flags, 4);
  append_le(f, std::bit_cast<std::uint64_t>(p.config.resolution), 8);
  append_le(f, static_cast<std::uint64_t>(p.config.depth_levels), 4);
  append_le(f, 0, 4);
  for (const double v : {p.config.thresholds.occupied, p.config.thresholds.free, p.config.sensor.p_hit,
                         p.config.sensor.p_miss, p.config.sensor.clamp_min, p.config.sensor.clamp_max}) {
    append_le(f, std::bit_cast<std::uint64_t>(v), 8);
  }
  append_le(f, p.inner_nodes, 8);
  append_le(f, 7 * p.inner_nodes + 1, 8);
  append_le(f, p.structure.size(), 8);
  append_le(f, sframe.size(), 8);
  append_le(f, vframe.size(), 8);
  append_le(f, 0, 4);  // header CRC, set by reseal
  EXPECT_EQ(f.size(), kHeader);
  f.insert(f.end(), sframe.begin(), sframe.end());
  f.insert(f.end(), vframe.begin(), vframe.end());
  append_le(f, 0, 4);
  reseal(f);
  return f;
}

MapConfig depth_config(int depth_levels) {
  MapConfig config;
  config.resolution = 0.1;
  config.depth_levels = depth_levels;
  return config;
}

// --- comparing maps ------------------------------------------------------------

struct Leaf {
  Key key;
  int depth;
  std::uint32_t bits;
  friend bool operator==(const Leaf&, const Leaf&) = default;
};

std::vector<Leaf> leaves(const OccupancyMap& map) {
  std::vector<Leaf> out;
  map.for_each_leaf([&](const Node& l) { out.push_back({l.key, l.depth, std::bit_cast<std::uint32_t>(l.log_odds)}); });
  return out;
}

/// Every node in depth-first order: children or not, all-same, value bits, indicators.
std::vector<std::uint64_t> shape(const OccupancyTree& tree) {
  std::vector<std::uint64_t> out;
  auto walk = [&](auto& self, NodeRef node) -> void {
    out.push_back(std::uint64_t{std::bit_cast<std::uint32_t>(tree.log_odds(node))} << 8 |
                  (tree.has_children(node) ? 1u : 0u) | (tree.all_children_same(node) ? 2u : 0u) |
                  (tree.contains_free(node) ? 4u : 0u) | (tree.contains_unknown(node) ? 8u : 0u));
    if (!tree.has_children(node)) return;
    for (unsigned slot = 0; slot < 8; ++slot) self(self, tree.child(node, slot));
  };
  walk(walk, tree.root());
  return out;
}

/// Every node's color and weight in depth-first order (empty without color).
std::vector<std::uint32_t> colors(const OccupancyTree& tree) {
  std::vector<std::uint32_t> out;
  if (!tree.has_color()) return out;
  auto walk = [&](auto& self, NodeRef node) -> void {
    const Rgb rgb = tree.color(node).value_or(Rgb{});
    out.push_back(std::uint32_t{rgb.r} << 24 | std::uint32_t{rgb.g} << 16 | std::uint32_t{rgb.b} << 8 |
                  tree.color_weight(node));
    if (!tree.has_children(node)) return;
    for (unsigned slot = 0; slot < 8; ++slot) self(self, tree.child(node, slot));
  };
  walk(walk, tree.root());
  return out;
}

void expect_same_config(const MapConfig& a, const MapConfig& b) {
  EXPECT_EQ(std::bit_cast<std::uint64_t>(a.resolution), std::bit_cast<std::uint64_t>(b.resolution));
  EXPECT_EQ(a.depth_levels, b.depth_levels);
  EXPECT_EQ(a.sensor, b.sensor);
  EXPECT_EQ(a.thresholds, b.thresholds);
  EXPECT_EQ(a.color, b.color);
}

void expect_same_map(const OccupancyMap& saved, const OccupancyMap& loaded) {
  expect_same_config(saved.config(), loaded.config());
  EXPECT_EQ(saved.auto_prune(), loaded.auto_prune());
  const NodeCounts a = saved.node_counts();
  const NodeCounts b = loaded.node_counts();
  EXPECT_EQ(a.inner, b.inner);
  EXPECT_EQ(a.inner_leaf, b.inner_leaf);
  EXPECT_EQ(a.leaf, b.leaf);
  EXPECT_TRUE(leaves(saved) == leaves(loaded)) << "childless nodes differ";
  EXPECT_TRUE(shape(test::tree_of(saved)) == shape(test::tree_of(loaded))) << "tree shape, inner values or indicators differ";
  EXPECT_TRUE(colors(test::tree_of(saved)) == colors(test::tree_of(loaded))) << "colors differ";
  EXPECT_EQ(test::check_invariants(loaded), "");
}

std::size_t count_all_same(const OccupancyTree& tree) {
  std::size_t n = 0;
  for (const std::uint64_t node : shape(tree)) n += (node & 2u) != 0;
  return n;
}

// --- loading errors ----------------------------------------------------------------

/// Loads `bytes` from a file and returns the FormatError message ("" and a failure if none).
std::string load_error(const Bytes& bytes, const fs::path& path) {
  write_bytes(path, bytes);
  try {
    (void)load_map(path);
  } catch (const FormatError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected a FormatError, got another exception: " << e.what();
    return e.what();
  }
  ADD_FAILURE() << "expected a FormatError, the file loaded";
  return "";
}

std::string info_error(const fs::path& path) {
  try {
    (void)read_map_info(path);
  } catch (const FormatError& e) {
    return e.what();
  }
  return "";
}

/// Expects `part` in `text`; evaluates each once.
#define EXPECT_CONTAINS(text, part)                                                       \
  do {                                                                                    \
    const std::string contains_text_ = (text);                                            \
    EXPECT_NE(contains_text_.find(part), std::string::npos) << "message: " << contains_text_; \
  } while (0)

// --- maps to save ------------------------------------------------------------------

MapConfig unusual_config(int depth_levels) {
  MapConfig config;
  config.resolution = depth_levels <= 2 ? 0.5 : 0.037;
  config.depth_levels = depth_levels;
  config.sensor = SensorModel{0.75, 0.35, 0.12, 0.97};
  config.thresholds = Thresholds{0.6, 0.4};
  return config;
}

/// A random map: single-voxel updates and sets clustered near the centre,
/// two uniform blocks (which become inner leaves when pruned, or equal
/// siblings when not), and a few point clouds when the map is big enough.
OccupancyMap random_map(const MapConfig& config, bool auto_prune, unsigned seed) {
  OccupancyMap map(config);
  map.set_auto_prune(auto_prune);
  std::mt19937 rng(seed);
  const std::uint32_t keys = 1u << config.depth_levels;
  const std::uint32_t span = std::min<std::uint32_t>(keys, 24);
  const std::uint32_t low = keys / 2 - span / 2;
  std::uniform_int_distribution<std::uint32_t> pick(0, span - 1);
  auto random_key = [&] { return Key{low + pick(rng), low + pick(rng), low + pick(rng)}; };
  const float min = config.sensor.clamp_min_log_odds();
  const float max = config.sensor.clamp_max_log_odds();
  std::uniform_real_distribution<float> any_value(min, max);
  for (int i = 0; i < 400; ++i) {
    const int kind = static_cast<int>(rng() % 4);
    if (kind == 0) map.update_hit(map.grid().center(random_key()));
    if (kind == 1) map.update_miss(map.grid().center(random_key()));
    if (kind == 2) map.update_log_odds(random_key(), any_value(rng) * 0.5f);
    if (kind == 3) map.set_log_odds(random_key(), any_value(rng));
  }
  // A uniform depth-1 block (eight voxels) in the corner, far from the
  // scans' rays, and a uniform depth-2 block beside it when the map is big enough.
  for (const int block_depth : {1, 2}) {
    if (block_depth == 2 && config.depth_levels < 3) continue;
    const std::uint32_t side = 1u << block_depth;
    const std::uint32_t base_x = block_depth == 1 ? 0 : 4;
    const float value = any_value(rng);
    for (std::uint32_t x = 0; x < side; ++x)
      for (std::uint32_t y = 0; y < side; ++y)
        for (std::uint32_t z = 0; z < side; ++z) map.set_log_odds(Key{base_x + x, y, z}, value);
  }
  if (config.depth_levels >= 5) {
    const double radius = std::min(3.0, 0.6 * map.grid().half_extent());
    std::normal_distribution<float> gauss(0.0f, 1.0f);
    for (int scan = 0; scan < 3; ++scan) {
      std::vector<Vec3f> points;
      for (int i = 0; i < 300; ++i) {
        Vec3f p{gauss(rng), gauss(rng), gauss(rng)};
        const float norm = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z) + 1e-6f;
        const float r = static_cast<float>(radius) * (0.7f + 0.3f * static_cast<float>(i % 7) / 7.0f);
        points.push_back({p.x / norm * r, p.y / norm * r, p.z / norm * r});
      }
      map.insert_point_cloud({0.05f * static_cast<float>(scan), 0.0f, 0.0f}, points);
    }
  }
  return map;
}

/// Clears the test-only fault hook when a test ends, even a failing one.
struct FaultHookGuard {
  ~FaultHookGuard() { detail::set_map_file_fault_for_testing({}); }
};

// ===================================================================================

TEST(MapFile, RoundTripIsExactAcrossDepthsAndConfigurations) {
  const fs::path dir = test::scratch_dir();
  unsigned seed = 1;
  for (const int depth_levels : {1, 2, 5, 16, 21}) {
    for (const bool auto_prune : {true, false}) {
      SCOPED_TRACE("depth levels " + std::to_string(depth_levels) + (auto_prune ? ", pruned" : ", unpruned"));
      const OccupancyMap saved = random_map(unusual_config(depth_levels), auto_prune, seed++);
      ASSERT_EQ(test::check_invariants(saved), "");
      // The test means something only if the maps have structure to lose.
      if (!auto_prune) {
        EXPECT_GT(count_all_same(test::tree_of(saved)), 0u) << "no unpruned equal siblings to preserve";
      }
      if (depth_levels >= 2) {
        EXPECT_GT(saved.node_counts().inner, 1u);
      }

      const fs::path path = dir / ("map-" + std::to_string(depth_levels) + (auto_prune ? "p" : "u") + ".umb");
      save_map(saved, path);
      const OccupancyMap loaded = load_map(path);
      expect_same_map(saved, loaded);

      const MapFileInfo info = read_map_info(path);
      expect_same_config(saved.config(), info.config);
      EXPECT_EQ(info.version, kMapFileVersion);
      EXPECT_EQ(info.auto_prune, auto_prune);
      EXPECT_EQ(info.inner_nodes, saved.node_counts().inner);
      EXPECT_EQ(info.childless_nodes, saved.node_counts().inner_leaf + saved.node_counts().leaf);
      EXPECT_EQ(info.file_bytes, fs::file_size(path));

      // Saving the loaded map gives the same bytes: nothing was normalised away.
      save_map(loaded, dir / "again.umb");
      EXPECT_TRUE(read_bytes(path) == read_bytes(dir / "again.umb"));
    }
  }
}

TEST(MapFile, EmptyAndSingleNodeMapsRoundTrip) {
  const fs::path dir = test::scratch_dir();
  for (int depth_levels = 1; depth_levels <= kMaxDepthLevels; ++depth_levels) {
    SCOPED_TRACE("depth levels " + std::to_string(depth_levels));
    const OccupancyMap empty(depth_config(depth_levels));
    save_map(empty, dir / "empty.umb");
    const OccupancyMap loaded = load_map(dir / "empty.umb");
    expect_same_map(empty, loaded);
    EXPECT_EQ(loaded.node_counts().total(), 1u);
    const MapFileInfo info = read_map_info(dir / "empty.umb");
    EXPECT_EQ(info.inner_nodes, 0u);
    EXPECT_EQ(info.childless_nodes, 1u);
    EXPECT_EQ(info.structure_bytes, 1u);
  }
  // A childless root that is not unknown: a depth-1 map whose eight voxels were pruned into it.
  OccupancyMap full(depth_config(1));
  for (std::uint32_t code = 0; code < 8; ++code) full.set_log_odds(morton::decode(code), 1.25f);
  ASSERT_EQ(full.node_counts().total(), 1u);
  save_map(full, dir / "full.umb");
  expect_same_map(full, load_map(dir / "full.umb"));
}

TEST(MapFile, LoadedMapKeepsUpdatingAndPruning) {
  const fs::path dir = test::scratch_dir();
  save_map(random_map(unusual_config(16), true, 77), dir / "map.umb");
  OccupancyMap map = load_map(dir / "map.umb");
  const std::size_t before = map.node_counts().total();
  // Eight equal voxels far from everything: expanded, then pruned back at once.
  const Key base{1000, 2000, 3000};
  for (std::uint32_t code = 0; code < 8; ++code) {
    const Key k = morton::decode(code);
    map.set_log_odds(Key{base.x + k.x, base.y + k.y, base.z + k.z}, 2.0f);
  }
  EXPECT_EQ(test::check_invariants(map), "");
  EXPECT_GT(map.node_counts().total(), before);  // the path down to the new inner leaf
  EXPECT_EQ(map.node(base, 0).depth, 1);         // the eight voxels are one inner leaf
}

TEST(MapFile, WorkedExampleFromTheSpecLoads) {
  // docs/map-format.md, "Worked example": depth_levels 2, the root has
  // children, its child 0 has eight leaf children, its children 1..7 are
  // inner leaves (the last one free).
  const float hit = logit(0.7);
  const float miss = logit(0.4);
  FileParts p;
  p.config = depth_config(2);
  p.inner_nodes = 2;
  p.structure = {0x01, 0x01};
  p.values = {hit, miss, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, miss};
  // The hex dump printed in the spec, byte for byte.
  const Bytes spec_dump = {
      0x55, 0x4d, 0x42, 0x52, 0x41, 0x4d, 0x41, 0x50, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
      0x9a, 0x99, 0x99, 0x99, 0x99, 0x99, 0xb9, 0x3f, 0x02, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xe0, 0x3f, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xe0, 0x3f,
      0x66, 0x66, 0x66, 0x66, 0x66, 0x66, 0xe6, 0x3f, 0x9a, 0x99, 0x99, 0x99, 0x99, 0x99, 0xd9, 0x3f,
      0x32, 0xe6, 0xae, 0x25, 0xe4, 0x83, 0xbe, 0x3f, 0xdf, 0x4f, 0x8d, 0x97, 0x6e, 0x12, 0xef, 0x3f,
      0x02, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x0f, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
      0x02, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x0e, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
      0x48, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xab, 0x12, 0x49, 0x68, 0x28, 0xb5, 0x2f, 0xfd,
      0xa0, 0x02, 0x00, 0x00, 0x00, 0x11, 0x00, 0x00, 0x01, 0x01, 0x28, 0xb5, 0x2f, 0xfd, 0xa0, 0x3c,
      0x00, 0x00, 0x00, 0xe1, 0x01, 0x00, 0x83, 0xe8, 0x58, 0x3f, 0x1f, 0x99, 0xcf, 0xbe, 0x00, 0x00,
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1f, 0x99,
      0xcf, 0xbe, 0x0d, 0x0e, 0x71, 0xb5,
  };
  EXPECT_TRUE(make_file(p) == spec_dump) << "this test's encoder and the spec's dump disagree";
  const fs::path path = test::scratch_dir() / "example.umb";
  write_bytes(path, spec_dump);
  const OccupancyMap map = load_map(path);
  EXPECT_EQ(test::check_invariants(map), "");
  const std::vector<Leaf> got = leaves(map);
  ASSERT_EQ(got.size(), 15u);
  for (std::uint32_t i = 0; i < 8; ++i) {
    EXPECT_EQ(got[i].key, morton::decode(i));
    EXPECT_EQ(got[i].depth, 0);
  }
  for (std::uint32_t i = 1; i < 8; ++i) {
    EXPECT_EQ(got[7 + i].key, morton::decode(std::uint64_t{i} << 3));
    EXPECT_EQ(got[7 + i].depth, 1);
  }
  EXPECT_EQ(got[0].bits, std::bit_cast<std::uint32_t>(hit));
  EXPECT_EQ(got[1].bits, std::bit_cast<std::uint32_t>(miss));
  EXPECT_EQ(got[14].bits, std::bit_cast<std::uint32_t>(miss));
  EXPECT_EQ(map.state(map.grid().center(Key{0, 0, 0}), 0), OccupancyState::occupied);
  EXPECT_EQ(map.log_odds(map.grid().center(Key{0, 0, 0}), 2), hit);  // root = max of the voxels
  EXPECT_TRUE(map.auto_prune());
}

TEST(MapFile, EveryTruncationIsAFormatError) {
  const fs::path dir = test::scratch_dir();
  OccupancyMap map(unusual_config(3));
  map.set_log_odds(Key{1, 2, 3}, 1.0f);
  map.set_log_odds(Key{5, 6, 7}, -1.0f);
  save_map(map, dir / "map.umb");
  const Bytes whole = read_bytes(dir / "map.umb");
  ASSERT_GT(whole.size(), kHeader + 4);
  for (std::size_t n = 0; n < whole.size(); ++n) {
    SCOPED_TRACE("first " + std::to_string(n) + " bytes");
    const Bytes part(whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(n));
    const std::string message = load_error(part, dir / "cut.umb");
    EXPECT_EQ(info_error(dir / "cut.umb"), message);
    if (n < kHeader) {
      EXPECT_CONTAINS(message, "truncated: header needs 124 bytes, file has " + std::to_string(n));
    } else {
      EXPECT_CONTAINS(message, "truncated: header declares " + std::to_string(whole.size()) + " bytes, file has " +
                                   std::to_string(n));
    }
  }
  Bytes longer = whole;
  longer.push_back(0);
  EXPECT_CONTAINS(load_error(longer, dir / "long.umb"), "1 trailing bytes");
}

TEST(MapFile, EveryFlippedBitIsAFormatError) {
  const fs::path dir = test::scratch_dir();
  OccupancyMap map(unusual_config(4));
  map.set_log_odds(Key{1, 2, 3}, 1.0f);
  map.update_miss(map.grid().center(Key{9, 9, 9}));
  save_map(map, dir / "map.umb");
  const Bytes good = read_bytes(dir / "map.umb");
  for (std::size_t byte = 0; byte < good.size(); ++byte) {
    for (int bit = 0; bit < 8; ++bit) {
      SCOPED_TRACE("byte " + std::to_string(byte) + " bit " + std::to_string(bit));
      Bytes bad = good;
      bad[byte] = static_cast<std::uint8_t>(bad[byte] ^ (1u << bit));
      const std::string message = load_error(bad, dir / "bad.umb");
      if (byte < 8) {
        EXPECT_CONTAINS(message, "byte 0: bad magic: expected 'UMBRAMAP', found '");
      } else if (byte < 12) {
        EXPECT_CONTAINS(message, "byte 8: unsupported format version");
      } else if (byte < kHeader) {
        EXPECT_CONTAINS(message, "byte 120: header checksum mismatch: stored 0x");
      } else {  // the body or the file checksum
        EXPECT_CONTAINS(message, "byte " + std::to_string(good.size() - 4) + ": checksum mismatch: stored 0x");
      }
      // read_map_info catches the same header damage and does not look at the body.
      if (byte < kHeader) {
        EXPECT_EQ(info_error(dir / "bad.umb"), message);
      } else {
        EXPECT_EQ(info_error(dir / "bad.umb"), "");
      }
    }
  }
}

TEST(MapFile, WrongMagicSaysWhatItFound) {
  const fs::path dir = test::scratch_dir();
  const std::string octomap = "# Octomap OcTree binary file\nid OcTree\n";
  const std::string message = load_error(Bytes(octomap.begin(), octomap.end()), dir / "map.bt");
  EXPECT_CONTAINS(message, "map.bt: byte 0: bad magic: expected 'UMBRAMAP', found '# Octoma'");
  EXPECT_CONTAINS(load_error(Bytes{0x00, 0xFF, 'U'}, dir / "bin.umb"), "found '\\x00\\xffU'");
}

TEST(MapFile, NewerVersionIsRefusedEvenWithValidChecksums) {
  const fs::path dir = test::scratch_dir();
  save_map(random_map(unusual_config(5), true, 3), dir / "map.umb");
  Bytes file = read_bytes(dir / "map.umb");
  put_le(file, kAtVersion, 2, 4);
  reseal(file);
  const std::string message = load_error(file, dir / "v2.umb");
  EXPECT_CONTAINS(message, "byte 8: unsupported format version 2 (this build reads version 1)");
  EXPECT_EQ(info_error(dir / "v2.umb"), message);
}

TEST(MapFile, EveryHeaderFieldIsValidated) {
  const fs::path dir = test::scratch_dir();
  save_map(random_map(unusual_config(16), true, 5), dir / "map.umb");
  const Bytes good = read_bytes(dir / "map.umb");
  const std::uint64_t inner = get_le(good, kAtInner, 8);
  auto f64 = [](double v) { return std::bit_cast<std::uint64_t>(v); };
  struct Case {
    std::size_t offset;
    std::uint64_t value;
    int size;
    std::size_t error_offset;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {kAtFlags, 4, 4, kAtFlags, "unsupported flags 0x00000004 (this build knows 0x00000003)"},
      {kAtResolution, f64(std::nan("")), 8, kAtResolution,
       "resolution must be a number of metres in [0.0001, 1000] (0.1 mm to 1 km), got nan"},
      {kAtResolution, f64(0.0), 8, kAtResolution, "resolution must be a number of metres in [0.0001, 1000]"},
      {kAtResolution, f64(-0.05), 8, kAtResolution, "got -0.05"},
      {kAtResolution, f64(INFINITY), 8, kAtResolution, "got inf"},
      {kAtResolution, f64(1e-300), 8, kAtResolution, "got 1e-300"},
      {kAtResolution, f64(1e300), 8, kAtResolution, "got 1e+300"},
      {kAtResolution, f64(9.9e-5), 8, kAtResolution, "got 9.9e-05"},
      {kAtResolution, f64(1000.5), 8, kAtResolution, "got 1000.5"},
      {kAtDepth, 0, 4, kAtDepth, "depth levels must be in [1, 21], found 0"},
      {kAtDepth, 22, 4, kAtDepth, "depth levels must be in [1, 21], found 22"},
      {kAtReserved, 1, 4, kAtReserved, "reserved field must be 0, found 0x00000001"},
      {kAtOccupied, f64(1.5), 8, kAtOccupied, "invalid thresholds: occupied threshold"},
      {kAtFree, f64(0.7), 8, kAtOccupied, "invalid thresholds: free threshold"},
      {kAtPHit, f64(0.3), 8, kAtPHit, "invalid sensor model: sensor model p_hit"},
      {kAtClampMax, f64(1.0), 8, kAtPHit, "invalid sensor model: sensor model clamp_max"},
      {kAtInner, std::uint64_t{1} << 62, 8, kAtInner, "is more than a tree of 16 depth levels can hold"},
      {kAtChildless, 7 * inner, 8, kAtChildless, "does not match the inner node count"},
      {kAtStructure, inner + 2, 8, kAtStructure, "is impossible for"},
      {kAtStructure, 0, 8, kAtStructure, "is impossible for"},
      {kAtStructureCompressed, get_le(good, kAtStructureCompressed, 8) + 1, 8, good.size(),
       "truncated: header declares " + std::to_string(good.size() + 1)},
      {kAtValuesCompressed, get_le(good, kAtValuesCompressed, 8) - 1, 8, good.size() - 1, "1 trailing bytes"},
      {kAtValuesCompressed, std::uint64_t{1} << 60, 8, kAtValuesCompressed, "impossibly large"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE("field at byte " + std::to_string(c.offset) + ": " + c.expected);
    Bytes bad = good;
    put_le(bad, c.offset, c.value, c.size);
    reseal(bad);
    const std::string message = load_error(bad, dir / "bad.umb");
    EXPECT_CONTAINS(message, "bad.umb: byte " + std::to_string(c.error_offset) + ": ");
    EXPECT_CONTAINS(message, c.expected);
    EXPECT_EQ(info_error(dir / "bad.umb"), message);
  }
}

TEST(MapFile, BodyErrorsAreReportedEvenWithValidChecksums) {
  const fs::path dir = test::scratch_dir();
  const float hit = logit(0.7);
  auto leaf_map = [&](std::vector<float> values, std::uint32_t flags = 0) {
    FileParts p;
    p.config = depth_config(1);
    p.flags = flags;
    p.inner_nodes = 1;
    p.structure = {0x01};
    p.values = std::move(values);
    return p;
  };
  const std::string structure_at = "byte 124: structure stream: ";
  {
    SCOPED_TRACE("the frame holds fewer mask bytes than declared");
    FileParts p;
    p.config = depth_config(2);
    p.inner_nodes = 2;
    p.structure = {0x01, 0x01};
    p.values = std::vector<float>(15, 0.0f);
    p.structure_frame = raw_zstd_frame({0x01});
    const std::string m = load_error(make_file(p), dir / "a.umb");
    EXPECT_CONTAINS(m, structure_at + "node structure ends early: the node at depth 2, key (0, 0, 0) has children");
    EXPECT_CONTAINS(m, "its zstd frame ends after 1 of the 2 bytes the header declares");
  }
  {
    SCOPED_TRACE("the tree needs more masks than declared");
    FileParts p;
    p.config = depth_config(3);
    p.inner_nodes = 2;
    p.structure = {0x01, 0x01};  // the root's child 0 (depth 2) has children: it needs a mask too
    p.values = std::vector<float>(15, 0.0f);
    EXPECT_CONTAINS(load_error(make_file(p), dir / "b.umb"),
                    "node structure ends early: the node at depth 2, key (0, 0, 0) has children and needs a child "
                    "mask, but all 2 bytes the header declares are used");
  }
  {
    SCOPED_TRACE("bad root byte");
    FileParts p = leaf_map(std::vector<float>(8, 0.0f));
    p.structure = {0x03};
    EXPECT_CONTAINS(load_error(make_file(p), dir / "c.umb"), structure_at + "node structure: the root byte must be 0");
  }
  {
    SCOPED_TRACE("more inner nodes than declared");
    FileParts p;
    p.config = depth_config(2);
    p.inner_nodes = 2;
    p.structure = {0x01, 0xFF};
    p.values = std::vector<float>(15, 0.0f);
    p.values[0] = hit;
    EXPECT_CONTAINS(load_error(make_file(p), dir / "d.umb"),
                    structure_at + "node structure describes more than the 2 inner nodes the header declares");
  }
  {
    SCOPED_TRACE("fewer inner nodes than declared");
    FileParts p;
    p.config = depth_config(2);
    p.inner_nodes = 2;
    p.structure = {0x01, 0x00};
    p.values = std::vector<float>(15, 0.0f);
    p.values[0] = hit;
    EXPECT_CONTAINS(load_error(make_file(p), dir / "e.umb"),
                    structure_at + "node structure describes 1 inner nodes, the header declares 2");
  }
  {
    SCOPED_TRACE("unused mask bytes");
    FileParts p;
    p.config = depth_config(3);
    p.inner_nodes = 3;
    p.structure = {0x01, 0x01, 0x01, 0x00};
    p.values = std::vector<float>(22, 0.0f);
    p.values[0] = hit;
    EXPECT_CONTAINS(load_error(make_file(p), dir / "f.umb"),
                    structure_at + "node structure has unused bytes after the tree ends: 1 of its 4 declared bytes");
  }
  {
    SCOPED_TRACE("structure frame longer than declared");
    FileParts p = leaf_map(std::vector<float>(8, 0.0f));
    p.values[0] = hit;
    p.structure_frame = raw_zstd_frame({0x01, 0x00});
    EXPECT_CONTAINS(load_error(make_file(p), dir / "g.umb"),
                    structure_at + "holds more than the 1 bytes the header declares");
  }
  {
    SCOPED_TRACE("bytes after the structure frame");
    FileParts p = leaf_map(std::vector<float>(8, 0.0f));
    p.values[0] = hit;
    p.structure_frame = raw_zstd_frame({0x01});
    p.structure_frame.push_back(0x42);
    EXPECT_CONTAINS(load_error(make_file(p), dir / "h.umb"), structure_at + "1 bytes follow the end of its zstd frame");
  }
  {
    SCOPED_TRACE("not a zstd frame");
    FileParts p = leaf_map(std::vector<float>(8, 0.0f));
    p.values[0] = hit;
    p.structure_frame = {'n', 'o', 't', ' ', 'z', 's', 't', 'd'};
    EXPECT_CONTAINS(load_error(make_file(p), dir / "i.umb"), structure_at + "zstd error: ");
  }
  {
    SCOPED_TRACE("truncated zstd frame");
    FileParts p = leaf_map(std::vector<float>(8, 0.0f));
    p.values[0] = hit;
    p.values_frame = raw_zstd_frame(float_bytes(p.values));
    p.values_frame.resize(p.values_frame.size() - 5);
    EXPECT_CONTAINS(load_error(make_file(p), dir / "j.umb"), "values stream: ");
  }
  const std::size_t values_at = kHeader + raw_zstd_frame({0x01}).size();
  const std::string values_prefix = "byte " + std::to_string(values_at) + ": values stream: ";
  {
    SCOPED_TRACE("too few values");
    FileParts p = leaf_map(std::vector<float>(8, 0.0f));
    p.values[0] = hit;
    p.values_frame = raw_zstd_frame(float_bytes(std::vector<float>(7, 0.0f)));
    EXPECT_CONTAINS(load_error(make_file(p), dir / "k.umb"),
                    values_prefix + "ends early at the children of the node at depth 1, key (0, 0, 0): its zstd "
                                    "frame ends after 28 of the 32 bytes the header declares");
  }
  {
    SCOPED_TRACE("too many values");
    FileParts p = leaf_map(std::vector<float>(8, 0.0f));
    p.values[0] = hit;
    p.values_frame = raw_zstd_frame(float_bytes(std::vector<float>(9, 0.0f)));
    EXPECT_CONTAINS(load_error(make_file(p), dir / "l.umb"),
                    values_prefix + "holds more than the 32 bytes the header declares");
  }
  {
    SCOPED_TRACE("NaN, infinity, outside the clamping range");
    std::vector<float> values(8, 0.0f);
    values[1] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_CONTAINS(load_error(make_file(leaf_map(values)), dir / "m.umb"),
                    values_prefix + "log-odds value nan at the node at depth 0, key (1, 0, 0)");
    values[1] = -std::numeric_limits<float>::infinity();
    EXPECT_CONTAINS(load_error(make_file(leaf_map(values)), dir / "m.umb"),
                    values_prefix + "log-odds value -inf at the node at depth 0, key (1, 0, 0)");
    values[1] = 0.0f;
    values[7] = 3.6f;  // clamp_max 0.971 is 3.5066 in log-odds
    EXPECT_CONTAINS(load_error(make_file(leaf_map(values)), dir / "m.umb"),
                    "log-odds value 3.5999999 (bits 0x40666666) at the node at depth 0, key (1, 1, 1) is outside the "
                    "sensor model's clamping range [-2.00002789, 3.51103067]");
    FileParts inner_leaf;
    inner_leaf.config = depth_config(2);
    inner_leaf.structure = {0x00};
    inner_leaf.values = {std::numeric_limits<float>::quiet_NaN()};
    EXPECT_CONTAINS(load_error(make_file(inner_leaf), dir / "m.umb"), "log-odds value nan at the node at depth 2");
  }
  {
    SCOPED_TRACE("equal childless siblings in a file marked pruned");
    const std::vector<float> same(8, hit);
    EXPECT_CONTAINS(load_error(make_file(leaf_map(same)), dir / "n.umb"),
                    values_prefix + "the node at depth 1, key (0, 0, 0) has eight equal childless children");
    FileParts deeper;  // the same one level up: eight equal inner leaves at depth 1
    deeper.config = depth_config(2);
    deeper.inner_nodes = 1;
    deeper.structure = {0x01, 0x00};
    deeper.values = std::vector<float>(8, hit);
    EXPECT_CONTAINS(load_error(make_file(deeper), dir / "n.umb"), "the node at depth 2, key (0, 0, 0) has eight equal");
    // Marked unpruned (flag bit 0), the same bytes are a valid map with auto-pruning off.
    write_bytes(dir / "o.umb", make_file(leaf_map(same, 1)));
    const OccupancyMap map = load_map(dir / "o.umb");
    EXPECT_FALSE(map.auto_prune());
    EXPECT_TRUE(test::tree_of(map).all_children_same(test::tree_of(map).root()));
    EXPECT_EQ(test::check_invariants(map), "");
  }
}

TEST(MapFile, AbsurdDeclaredSizesAreRejectedWithoutAllocating) {
  const fs::path dir = test::scratch_dir();
  save_map(random_map(unusual_config(16), true, 9), dir / "map.umb");
  const Bytes good = read_bytes(dir / "map.umb");
  // A consistent set of counts (S - 1 <= I <= 9 (S - 1), C = 7 I + 1) that
  // would need terabytes, in a file of a few kilobytes.
  Bytes bad = good;
  const std::uint64_t huge = std::uint64_t{1} << 40;
  put_le(bad, kAtInner, huge, 8);
  put_le(bad, kAtChildless, 7 * huge + 1, 8);
  put_le(bad, kAtStructure, huge, 8);
  reseal(bad);
  // A frame whose own header claims 2^40 bytes of content in one segment
  // (which would make zstd allocate a 1 TiB window), in an otherwise valid file.
  FileParts p;
  p.config = depth_config(1);
  p.inner_nodes = 1;
  p.structure = {0x01};
  p.values = std::vector<float>(8, 0.0f);
  p.values[0] = 1.0f;
  p.structure_frame = {0x28, 0xB5, 0x2F, 0xFD, 0xE0};  // 8-byte content size, single segment
  append_le(p.structure_frame, huge, 8);
  append_le(p.structure_frame, 1u | (1u << 3), 3);  // last raw block of 1 byte
  p.structure_frame.push_back(0x01);

  // Counts that pass every header check, including the zstd expansion bound
  // (2 GiB of masks from 64 KiB, 56 GiB of values from 1.8 MB), while the
  // frames hold far less: only streaming decoding stays within the limit.
  FileParts big;
  big.config = depth_config(16);
  const std::uint64_t claimed = std::uint64_t{1} << 31;
  big.inner_nodes = claimed;
  big.structure = Bytes(65537, 0xFF);
  big.structure[0] = 0x01;
  std::vector<float> values(460'000, 0.0f);
  for (std::size_t i = 0; i < values.size(); i += 8) values[i] = 1.0f;
  big.values_frame = raw_zstd_frame(float_bytes(values));
  Bytes lying = make_file(big);
  put_le(lying, kAtStructure, claimed, 8);
  reseal(lying);

  std::string counts_message;
  std::string frame_message;
  std::string lying_message;
  {
#if defined(__SANITIZE_ADDRESS__)
    const bool limited = false;  // AddressSanitizer reserves terabytes of address space itself
#else
    const test::AddressSpaceCap limit(std::uint64_t{1} << 30);
    const bool limited = limit.active();
#endif
    counts_message = load_error(bad, dir / "counts.umb");
    frame_message = load_error(make_file(p), dir / "frame.umb");
    // Without a memory limit, so that the decoder itself meets the lie.
    const test::MemoryLimitScope unlimited(UINT64_MAX);
    lying_message = load_error(lying, dir / "lying.umb");
    if (!limited) std::cerr << "note: address-space limit not applied; only the error messages are checked\n";
  }
  EXPECT_CONTAINS(counts_message, "byte 96: structure stream declares 1099511627776 bytes, but its");
  EXPECT_CONTAINS(counts_message, "compressed bytes can expand to at most");
  EXPECT_CONTAINS(frame_message, "byte 124: structure stream: zstd error: ");
  EXPECT_CONTAINS(lying_message, "ends early");
}

TEST(MapFile, FailedSaveLeavesTheOldFileAndNoTemporary) {
  const FaultHookGuard guard;
  const fs::path dir = test::scratch_dir();
  const fs::path path = dir / "map.umb";
  const OccupancyMap old_map = random_map(unusual_config(16), true, 11);
  const OccupancyMap new_map = random_map(unusual_config(16), false, 12);
  save_map(old_map, path);
  const Bytes old_bytes = read_bytes(path);

  int calls = 0;
  detail::set_map_file_fault_for_testing([&] {
    ++calls;
    // The temporary file exists and holds the header at this point.
    std::size_t temporaries = 0;
    for (const auto& entry : fs::directory_iterator(dir)) temporaries += entry.path() != path;
    EXPECT_EQ(temporaries, 1u);
    throw std::runtime_error("injected fault");
  });
  EXPECT_THROW(
      {
        try {
          save_map(new_map, path);
        } catch (const std::runtime_error& e) {
          EXPECT_STREQ(e.what(), "injected fault");
          throw;
        }
      },
      std::runtime_error);
  EXPECT_EQ(calls, 1);
  EXPECT_TRUE(read_bytes(path) == old_bytes) << "the old file was changed";
  auto listing = [&] {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename().string());
    return names;
  };
  EXPECT_EQ(listing(), std::vector<std::string>{"map.umb"});

  // A failed save of a new name leaves nothing at all.
  EXPECT_THROW(save_map(new_map, dir / "new.umb"), std::runtime_error);
  EXPECT_FALSE(fs::exists(dir / "new.umb"));
  EXPECT_EQ(listing(), std::vector<std::string>{"map.umb"});

  // Without the fault the new map replaces the old one.
  detail::set_map_file_fault_for_testing({});
  save_map(new_map, path);
  expect_same_map(new_map, load_map(path));
  EXPECT_EQ(listing(), std::vector<std::string>{"map.umb"});
}

TEST(MapFile, IoErrorsNameThePathAndTheReason) {
  const fs::path dir = test::scratch_dir();
  const OccupancyMap map(depth_config(16));
  const fs::path missing = dir / "no-such-folder" / "map.umb";
  try {
    save_map(map, missing);
    ADD_FAILURE() << "saving into a missing folder succeeded";
  } catch (const FormatError& e) {
    ADD_FAILURE() << "an I/O error reported as a format error: " << e.what();
  } catch (const std::runtime_error& e) {
    EXPECT_CONTAINS(e.what(), missing.string());
    EXPECT_CONTAINS(e.what(), "No such file or directory");
  }
  EXPECT_FALSE(fs::exists(dir / "no-such-folder"));
  for (auto* read : {+[](const fs::path& p) { (void)load_map(p); }, +[](const fs::path& p) { (void)read_map_info(p); }}) {
    try {
      read(missing);
      ADD_FAILURE() << "reading a missing file succeeded";
    } catch (const FormatError& e) {
      ADD_FAILURE() << "an I/O error reported as a format error: " << e.what();
    } catch (const std::runtime_error& e) {
      EXPECT_CONTAINS(e.what(), missing.string());
      EXPECT_CONTAINS(e.what(), "No such file or directory");
    }
  }
  EXPECT_THROW((void)load_map(dir), std::runtime_error);  // a folder, not a map
}

TEST(MapFile, SaveRefusesValuesOutsideTheClampingRange) {
  // The map API keeps every value inside the clamping range (a narrower
  // range clamps the stored values); the low-level tree API does not, and a
  // file with such a value could not be loaded, so save_map refuses before
  // creating anything.
  const fs::path dir = test::scratch_dir();
  OccupancyMap map(depth_config(16));
  map.set_log_odds(Key{100, 100, 100}, 3.0f);
  map.set_sensor_model(SensorModel{0.7, 0.4, 0.2, 0.9});  // clamp_max 0.9 = 2.197 in log-odds
  EXPECT_EQ(map.node(Key{100, 100, 100}).log_odds, map.sensor_model().clamp_max_log_odds());
  save_map(map, dir / "narrowed.umb");
  EXPECT_EQ(load_map(dir / "narrowed.umb").node(Key{100, 100, 100}).log_odds, map.sensor_model().clamp_max_log_odds());
  fs::remove(dir / "narrowed.umb");

  detail::MapAccess::build(map, [](detail::TreeBuilder& tree) {
    NodeRef node = tree.root();
    while (tree.has_children(node)) {
      node = tree.child(node, morton::slot(morton::encode({100, 100, 100}), node.depth - 1));
    }
    tree.set_childless_value(node, 3.0f);
  });
  try {
    save_map(map, dir / "map.umb");
    ADD_FAILURE() << "saved a map its own loader would reject";
  } catch (const std::invalid_argument& e) {
    EXPECT_CONTAINS(e.what(), "log-odds value 3 (bits 0x40400000) at the node at depth 0, key (100, 100, 100)");
  }
  EXPECT_TRUE(fs::is_empty(dir));
}

TEST(MapFile, ReadMapInfoReadsTheHeaderOfALargeFileWithoutTheBody) {
  const fs::path dir = test::scratch_dir();
  MapConfig config = unusual_config(16);
  OccupancyMap map(config);
  std::mt19937 rng(21);
  const float min = config.sensor.clamp_min_log_odds();
  const float max = config.sensor.clamp_max_log_odds();
  std::uniform_real_distribution<float> value(min, max);
  for (std::uint32_t x = 0; x < 64; ++x)
    for (std::uint32_t y = 0; y < 64; ++y)
      for (std::uint32_t z = 0; z < 64; ++z) map.set_log_odds(Key{30000 + x, 30000 + y, 30000 + z}, value(rng));
  const fs::path path = dir / "large.umb";
  save_map(map, path);
  ASSERT_GT(fs::file_size(path), 500'000u);

  // Damage the middle of the body: only load_map, which reads it, notices.
  Bytes bytes = read_bytes(path);
  bytes[bytes.size() / 2] ^= 0x10;
  write_bytes(path, bytes);
  const MapFileInfo info = read_map_info(path);
  expect_same_config(info.config, config);
  EXPECT_TRUE(info.auto_prune);
  EXPECT_EQ(info.inner_nodes, map.node_counts().inner);
  EXPECT_EQ(info.childless_nodes, map.node_counts().inner_leaf + map.node_counts().leaf);
  EXPECT_EQ(info.file_bytes, bytes.size());
  EXPECT_EQ(kHeader + info.structure_compressed_bytes + info.values_compressed_bytes + 4, bytes.size());
  EXPECT_CONTAINS(load_error(bytes, path), "checksum mismatch");
}

}  // namespace
}  // namespace umbra

namespace umbra {
namespace {

OccupancyMap colored_map(int depth_levels, bool auto_prune, std::uint32_t seed) {
  MapConfig config = depth_config(depth_levels);
  config.color = true;
  OccupancyMap map(config);
  map.set_auto_prune(auto_prune);
  std::mt19937 rng(seed);
  const float h = std::min(static_cast<float>(map.grid().half_extent()) * 0.9f, 3.0f);
  std::uniform_real_distribution<float> coordinate(-h, h);
  const Rgb palette[] = {{255, 0, 0}, {0, 0, 255}, {7, 8, 9}};
  for (int scan = 0; scan < 3; ++scan) {
    std::vector<Vec3f> points;
    std::vector<Rgb> rgb;
    for (int i = 0; i < 200; ++i) {
      points.push_back({coordinate(rng), coordinate(rng), coordinate(rng)});
      rgb.push_back(palette[rng() % 3]);
    }
    map.insert_point_cloud({0, 0, 0}, points, rgb);
  }
  return map;
}

TEST(MapFile, ColoredMapsRoundTripExactly) {
  const fs::path dir = test::scratch_dir();
  for (const int depth_levels : {1, 3, 8, 16}) {
    for (const bool auto_prune : {true, false}) {
      SCOPED_TRACE("depth levels " + std::to_string(depth_levels) + (auto_prune ? " pruned" : " unpruned"));
      const OccupancyMap map = colored_map(depth_levels, auto_prune, static_cast<std::uint32_t>(depth_levels));
      ASSERT_TRUE(map.has_color());
      const fs::path path = dir / "colored.umb";
      save_map(map, path);
      const OccupancyMap loaded = load_map(path);
      EXPECT_TRUE(loaded.has_color());
      EXPECT_TRUE(read_map_info(path).config.color);
      expect_same_map(map, loaded);
      if (depth_levels == 8) {
        EXPECT_GT(colors(test::tree_of(map)).size(), 100u);
      }
    }
  }
}

/// A colored map whose values and color streams are several MiB each, so
/// that saving with helper threads cuts them into several 1 MiB zstd jobs:
/// a 100^3 block of voxels with random values and colors.
OccupancyMap large_colored_map() {
  MapConfig config = depth_config(8);
  config.color = true;
  OccupancyMap map(config);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> value(config.sensor.clamp_min_log_odds(), config.sensor.clamp_max_log_odds());
  for (std::uint32_t x = 0; x < 100; ++x) {
    for (std::uint32_t y = 0; y < 100; ++y) {
      for (std::uint32_t z = 0; z < 100; ++z) {
        map.set_log_odds(Key{x, y, z}, value(rng));
        if (rng() % 2 == 0) map.set_color(Key{x, y, z}, Rgb{static_cast<std::uint8_t>(x), 7, static_cast<std::uint8_t>(z)});
      }
    }
  }
  return map;
}

TEST(MapFile, SavingWithAnyNumberOfThreadsWritesTheSameBytes) {
  const fs::path dir = test::scratch_dir();
  const OccupancyMap map = large_colored_map();
  const MapFileInfo one_job = [&] {
    save_map(map, dir / "t1.umb", MapSaveOptions{1});
    return read_map_info(dir / "t1.umb");
  }();
  // Several jobs per stream, or the threaded path is not tested.
  ASSERT_GT(4 * one_job.childless_nodes, 3u << 20);
  for (const unsigned threads : {0u, 1u, 2u, 3u, 16u}) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    const fs::path path = dir / ("t" + std::to_string(threads) + ".umb");
    save_map(map, path, MapSaveOptions{threads});
    expect_same_map(map, load_map(path));
    // The same bytes as with one thread: a file does not change with the thread count.
    EXPECT_TRUE(read_bytes(path) == read_bytes(dir / "t1.umb"));
  }
}

TEST(MapFile, TooManySaveThreadsAreRefusedBeforeAnyFileExists) {
  const fs::path path = test::scratch_dir() / "threads.umb";
  const OccupancyMap map(depth_config(4));
  try {
    save_map(map, path, MapSaveOptions{max_threads() + 1});
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("threads must be at most " + std::to_string(max_threads())),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("got " + std::to_string(max_threads() + 1)), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(path));
  EXPECT_NO_THROW(save_map(map, path, MapSaveOptions{max_threads()}));
}

TEST(MapFile, EveryTruncationOfAColoredFileIsReported) {
  const fs::path dir = test::scratch_dir();
  const OccupancyMap map = colored_map(3, true, 5);
  save_map(map, dir / "whole.umb");
  const Bytes whole = read_bytes(dir / "whole.umb");
  for (std::size_t length = 0; length < whole.size(); ++length) {
    const std::string message = load_error(Bytes(whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(length)),
                                           dir / "cut.umb");
    ASSERT_FALSE(message.empty()) << "length " << length;
  }
}

}  // namespace
}  // namespace umbra
