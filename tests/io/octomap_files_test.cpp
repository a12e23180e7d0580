// Tests of the OctoMap files (.bt, .ot) against the real liboctomap 1.9.7.
//
// Both directions are checked leaf by leaf: maps umbra writes are read by
// liboctomap and must hold the same leaves (key, depth, float log-odds,
// color), and — after liboctomap recomputes its inner nodes (.ot) or
// converts and prunes (.bt) — liboctomap must write back the very bytes
// umbra wrote; trees liboctomap builds from simulated scans (OcTree,
// ColorOcTree, OcTreeStamped, unpruned, empty) are read by umbra with the
// same leaves and written back byte for byte. Then the real geb079.bt,
// exact round trips, every truncation and bit flip of small files, bad and
// hostile headers and trees, and the depth rule. Cost: about 3 s in the
// Release test build (30 s under ASan), mostly liboctomap inserting the
// simulated scans and the 1.5 MB streaming test.
#include "support/map_internals.hpp"
#include "umbra/io/octomap_files.hpp"

#include <gtest/gtest.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>
#include <octomap/OcTreeStamped.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "support/test_support.hpp"
#include "umbra/io/map_formats.hpp"
#include "umbra/sim/lidar.hpp"
#include "umbra/sim/scene.hpp"

namespace umbra {
namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;

// --- bytes and files ----------------------------------------------------------------

using test::read_bytes;
using test::write_bytes;

Bytes to_bytes(const std::string& text) { return Bytes(text.begin(), text.end()); }
std::string to_text(const Bytes& bytes) { return std::string(bytes.begin(), bytes.end()); }

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

/// The FormatError message decoding `bytes` gives; a test failure if it decodes.
std::string decode_error(const Bytes& bytes, const std::string& name = "bad.ot") {
  try {
    (void)decode_octomap(bytes, name);
  } catch (const FormatError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected a FormatError, but the file was read";
  return "";
}

// --- leaves, both sides ---------------------------------------------------------------

/// A childless node OctoMap has: where it starts, its umbra depth, value, color.
struct Leaf {
  std::uint64_t code = 0;  // Morton code of its first finest voxel
  int depth = 0;           // umbra depth (0 = finest)
  float value = 0.0f;
  std::optional<Rgb> color;
  friend bool operator==(const Leaf&, const Leaf&) = default;
  friend bool operator<(const Leaf& a, const Leaf& b) { return std::tie(a.code, a.depth) < std::tie(b.code, b.depth); }
};

std::ostream& operator<<(std::ostream& out, const Leaf& leaf) {
  const Key key = morton::decode(leaf.code);
  out << "{key (" << key.x << ", " << key.y << ", " << key.z << "), depth " << leaf.depth << ", value "
      << leaf.value;
  if (leaf.color) out << ", rgb " << int(leaf.color->r) << " " << int(leaf.color->g) << " " << int(leaf.color->b);
  return out << "}";
}

/// umbra's known childless nodes (value != 0): OctoMap's leaves (white is "no color" there).
std::vector<Leaf> umbra_leaves(const OccupancyMap& map) {
  std::vector<Leaf> leaves;
  map.for_each_leaf([&](const Node& leaf) {
    if (leaf.log_odds == 0.0f) return;
    const bool white = leaf.color == Rgb{255, 255, 255};
    leaves.push_back({morton::encode(leaf.key), leaf.depth, leaf.log_odds, white ? std::nullopt : leaf.color});
  });
  std::sort(leaves.begin(), leaves.end());
  return leaves;
}

/// Every childless node of an umbra map, unknown ones too (for exact round trips).
std::vector<Leaf> all_umbra_leaves(const OccupancyMap& map) {
  std::vector<Leaf> leaves;
  map.for_each_leaf([&](const Node& leaf) {
    leaves.push_back({morton::encode(leaf.key), leaf.depth, leaf.log_odds, leaf.color});
  });
  return leaves;
}

template <typename Tree>
std::vector<Leaf> octomap_leaves(const Tree& tree) {
  std::vector<Leaf> leaves;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const int depth = 16 - static_cast<int>(it.getDepth());
    const std::uint32_t mask = ~((std::uint32_t{1} << depth) - 1u);
    const octomap::OcTreeKey k = it.getKey();  // the key of the node's centre voxel
    const Key first{k[0] & mask, k[1] & mask, k[2] & mask};
    Leaf leaf{morton::encode(first), depth, it->getLogOdds(), std::nullopt};
    if constexpr (std::is_same_v<Tree, octomap::ColorOcTree>) {
      if (it->isColorSet()) leaf.color = Rgb{it->getColor().r, it->getColor().g, it->getColor().b};
    }
    leaves.push_back(leaf);
  }
  std::sort(leaves.begin(), leaves.end());
  return leaves;
}

void expect_same_leaves(const std::vector<Leaf>& expected, const std::vector<Leaf>& actual) {
  ASSERT_EQ(expected.size(), actual.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    ASSERT_EQ(expected[i], actual[i]) << "leaf " << i << " of " << expected.size();
  }
}

// --- liboctomap in memory ---------------------------------------------------------------

template <typename Tree>
Bytes octomap_ot_bytes(const Tree& tree) {
  std::ostringstream out;
  EXPECT_TRUE(tree.write(out));
  return to_bytes(out.str());
}

Bytes octomap_bt_bytes(octomap::AbstractOccupancyOcTree& tree) {
  std::ostringstream out;
  EXPECT_TRUE(tree.writeBinary(out));  // converts to maximum likelihood and prunes first
  return to_bytes(out.str());
}

/// liboctomap's reading of .ot bytes (any registered tree type); null if it refuses.
std::unique_ptr<octomap::AbstractOcTree> octomap_read_ot(const Bytes& bytes) {
  std::istringstream in(to_text(bytes));
  return std::unique_ptr<octomap::AbstractOcTree>(octomap::AbstractOcTree::read(in));
}

std::unique_ptr<octomap::OcTree> octomap_read_bt(const Bytes& bytes) {
  auto tree = std::make_unique<octomap::OcTree>(0.1);
  std::istringstream in(to_text(bytes));
  EXPECT_TRUE(tree->readBinary(in));
  return tree;
}

// --- maps to test with -------------------------------------------------------------------

/// Scans of umbra's simulated office from a few poses along its corridor.
struct SimulatedScan {
  Vec3f origin;
  std::vector<Vec3f> points;
};

std::vector<SimulatedScan> office_scans(int count) {
  static const sim::Scene scene = sim::make_demo_scene();
  const std::vector<sim::SensorPose> path = sim::demo_path();
  sim::LidarModel lidar;
  lidar.rings = 12;
  lidar.azimuth_steps = 240;
  lidar.max_range = 12.0;
  std::vector<SimulatedScan> scans;
  for (int i = 0; i < count && i < static_cast<int>(path.size()); ++i) {
    const sim::SensorPose& pose = path[static_cast<std::size_t>(i) * 2];
    scans.push_back({Vec3f(pose.position), sim::simulate_scan(scene, pose, lidar)});
  }
  return scans;
}

Rgb color_of(const Vec3f& p) {
  // A color that varies over the scene and is never white.
  auto channel = [](float v) { return static_cast<std::uint8_t>(static_cast<int>(std::floor(v * 37.0f)) & 0xFE); };
  return {channel(p.x), channel(p.y), channel(p.z + 3.0f)};
}

template <typename Tree>
void insert_into_octomap(Tree& tree, const std::vector<SimulatedScan>& scans, bool lazy = false) {
  for (const SimulatedScan& scan : scans) {
    octomap::Pointcloud cloud;
    for (const Vec3f& p : scan.points) cloud.push_back(p.x, p.y, p.z);
    tree.insertPointCloud(cloud, octomap::point3d(scan.origin.x, scan.origin.y, scan.origin.z), 10.0, lazy);
  }
}

/// A random umbra map: observed voxels in a few clusters (some with color),
/// some solid blocks that prune into inner leaves, values from real hit/miss sequences.
OccupancyMap random_map(std::uint32_t seed, bool color, bool auto_prune = true, double resolution = 0.1) {
  MapConfig config;
  config.resolution = resolution;
  config.color = color;
  OccupancyMap map(config);
  map.set_auto_prune(auto_prune);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> offset(-20, 20);
  std::uniform_int_distribution<int> updates(1, 6);
  std::uniform_int_distribution<int> coin(0, 1);
  std::uniform_int_distribution<int> byte(0, 254);  // never 255: white means "no color" in OctoMap
  const std::uint32_t centre = map.grid().key_offset();
  for (int cluster = 0; cluster < 4; ++cluster) {
    const Key base{centre + static_cast<std::uint32_t>(offset(rng) * 50), centre - 700u + static_cast<std::uint32_t>(cluster * 300),
                   centre + static_cast<std::uint32_t>(offset(rng))};
    for (int i = 0; i < 400; ++i) {
      const Key key{base.x + static_cast<std::uint32_t>(offset(rng) + 20), base.y + static_cast<std::uint32_t>(offset(rng) + 20),
                    base.z + static_cast<std::uint32_t>(offset(rng) + 20)};
      for (int u = updates(rng); u > 0; --u) {
        map.update_log_odds(key, coin(rng) ? map.sensor_model().hit_log_odds() : map.sensor_model().miss_log_odds());
      }
      if (color && coin(rng)) {
        map.set_color(key, Rgb{static_cast<std::uint8_t>(byte(rng)), static_cast<std::uint8_t>(byte(rng)),
                               static_cast<std::uint8_t>(byte(rng))});
      }
    }
  }
  // Solid 8x8x8 and 16x16x16 blocks: pruned into inner leaves of depth 3 and 4.
  for (int block = 0; block < 3; ++block) {
    const std::uint32_t size = block == 0 ? 16u : 8u;
    const Key corner{(centre + 256u * static_cast<std::uint32_t>(block)) & ~(size - 1u), (centre + 512u) & ~(size - 1u),
                     centre & ~(size - 1u)};
    const float value = block == 1 ? map.sensor_model().clamp_min_log_odds() : map.sensor_model().clamp_max_log_odds();
    for (std::uint32_t x = 0; x < size; ++x) {
      for (std::uint32_t y = 0; y < size; ++y) {
        for (std::uint32_t z = 0; z < size; ++z) map.set_log_odds(Key{corner.x + x, corner.y + y, corner.z + z}, value);
      }
    }
  }
  return map;
}

// --- umbra writes, liboctomap reads ----------------------------------------------------------

void check_ot_read_by_octomap(const OccupancyMap& map) {
  const Bytes bytes = encode_octomap(map, OctoMapFormat::ot);
  const auto tree = octomap_read_ot(bytes);
  ASSERT_NE(tree, nullptr) << "liboctomap refused the file";
  if (map.has_color()) {
    auto* color_tree = dynamic_cast<octomap::ColorOcTree*>(tree.get());
    ASSERT_NE(color_tree, nullptr) << tree->getTreeType();
    expect_same_leaves(umbra_leaves(map), octomap_leaves(*color_tree));
    // Inner values and colors are what liboctomap computes itself.
    color_tree->updateInnerOccupancy();
    EXPECT_EQ(octomap_ot_bytes(*color_tree), bytes);
  } else {
    auto* plain_tree = dynamic_cast<octomap::OcTree*>(tree.get());
    ASSERT_NE(plain_tree, nullptr) << tree->getTreeType();
    expect_same_leaves(umbra_leaves(map), octomap_leaves(*plain_tree));
    plain_tree->updateInnerOccupancy();
    EXPECT_EQ(octomap_ot_bytes(*plain_tree), bytes);
  }
  EXPECT_EQ(tree->getResolution(), map.resolution());
}

/// Finest voxels of occupied and free space in OctoMap's tree (pruned leaves count whole).
std::pair<std::uint64_t, std::uint64_t> octomap_voxels(const octomap::OcTree& tree) {
  std::uint64_t occupied = 0;
  std::uint64_t free = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const std::uint64_t voxels = std::uint64_t{1} << (3 * (16 - it.getDepth()));
    (tree.isNodeOccupied(*it) ? occupied : free) += voxels;
  }
  return {occupied, free};
}

void check_bt_read_by_octomap(const OccupancyMap& map) {
  const Bytes bytes = encode_octomap(map, OctoMapFormat::bt);
  const auto tree = octomap_read_bt(bytes);
  // Every known umbra leaf is known to liboctomap with the same class (merged nodes may be coarser) ...
  std::uint64_t occupied = 0;
  std::uint64_t free = 0;
  const auto& thresholds = test::log_odds_thresholds(map);
  map.for_each_leaf([&](const Node& leaf) {
    if (leaf.log_odds == 0.0f) return;
    const octomap::OcTreeNode* node = tree->search(octomap::OcTreeKey(leaf.key.x, leaf.key.y, leaf.key.z));
    ASSERT_NE(node, nullptr) << "leaf at depth " << leaf.depth << " missing";
    const bool occupied_here = thresholds.is_occupied(leaf.log_odds);
    EXPECT_EQ(tree->isNodeOccupied(node), occupied_here);
    EXPECT_EQ(node->getLogOdds(), occupied_here ? tree->getClampingThresMaxLog() : tree->getClampingThresMinLog());
    (occupied_here ? occupied : free) += std::uint64_t{1} << (3 * leaf.depth);
  });
  // ... and liboctomap knows nothing more.
  const auto [octomap_occupied, octomap_free] = octomap_voxels(*tree);
  EXPECT_EQ(octomap_occupied, occupied);
  EXPECT_EQ(octomap_free, free);
  // The file is in liboctomap's canonical form: maximum likelihood, pruned.
  EXPECT_EQ(octomap_bt_bytes(*tree), bytes);
}

TEST(OctoMapWrite, RandomMapsAreReadByLiboctomapWithTheSameLeaves) {
  for (std::uint32_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const OccupancyMap plain = random_map(seed, false);
    check_ot_read_by_octomap(plain);
    check_bt_read_by_octomap(plain);
    const OccupancyMap colored = random_map(seed + 10, true);
    check_ot_read_by_octomap(colored);
    check_bt_read_by_octomap(colored);
    const OccupancyMap unpruned = random_map(seed + 20, true, false);
    check_ot_read_by_octomap(unpruned);
    check_bt_read_by_octomap(unpruned);
  }
}

TEST(OctoMapWrite, SimulatedOfficeIsReadByLiboctomapWithTheSameLeaves) {
  MapConfig config;
  config.resolution = 0.1;
  config.color = true;
  OccupancyMap map(config);
  InsertOptions options;
  options.max_range = 10.0;
  for (const SimulatedScan& scan : office_scans(3)) {
    std::vector<Rgb> colors;
    for (const Vec3f& p : scan.points) colors.push_back(color_of(p));
    map.insert_point_cloud(scan.origin, scan.points, colors, options);
  }
  ASSERT_GT(umbra_leaves(map).size(), 10000u);
  check_ot_read_by_octomap(map);
  check_bt_read_by_octomap(map);
}

TEST(OctoMapWrite, EdgeCasesOfTheRoot) {
  OccupancyMap map(0.2);
  // All unknown: an empty tree, as liboctomap writes one.
  octomap::OcTree empty(0.2);
  EXPECT_EQ(encode_octomap(map, OctoMapFormat::ot), octomap_ot_bytes(empty));
  EXPECT_EQ(encode_octomap(map, OctoMapFormat::bt), octomap_bt_bytes(empty));
  // A single voxel.
  map.update_hit(Vec3d{0.3, -0.5, 1.0});
  check_ot_read_by_octomap(map);
  check_bt_read_by_octomap(map);
  // The whole map one value: the root is childless in umbra.
  for (const float value : {map.sensor_model().clamp_min_log_odds(), map.sensor_model().clamp_max_log_odds()}) {
    map.clear();
    detail::MapAccess::build(map, [&](detail::TreeBuilder& tree) { tree.set_childless_value(tree.root(), value); });
    check_ot_read_by_octomap(map);
    check_bt_read_by_octomap(map);
    const OccupancyMap back = decode_octomap(encode_octomap(map, OctoMapFormat::bt));
    EXPECT_EQ(back.state({1.0, 2.0, 3.0}), map.state({1.0, 2.0, 3.0}));
    EXPECT_EQ(back.state({-1000.0, 2.0, 3.0}), map.state({-1000.0, 2.0, 3.0}));
  }
  // Eight equal children of the root (auto-pruning off): liboctomap never merges them into the root.
  for (const float value : {map.sensor_model().clamp_min_log_odds(), map.sensor_model().clamp_max_log_odds()}) {
    OccupancyMap split(0.2);
    split.set_auto_prune(false);
    detail::MapAccess::build(split, [&](detail::TreeBuilder& tree) {
      tree.subdivide(tree.root());
      for (unsigned slot = 0; slot < 8; ++slot) tree.set_childless_value(tree.child(tree.root(), slot), value);
    });
    check_ot_read_by_octomap(split);
    check_bt_read_by_octomap(split);
    EXPECT_TRUE(contains(to_text(encode_octomap(split, OctoMapFormat::bt)), "size 9\n"));
  }
}

TEST(OctoMapWrite, WhiteIsNoColorAndInnerColorsTruncate) {
  MapConfig config;
  config.resolution = 0.1;
  config.color = true;
  OccupancyMap map(config);
  const Key a{32768, 32768, 32768};
  const Key b{32769, 32768, 32768};
  const Key c{32768, 32769, 32768};
  for (const Key& key : {a, b, c}) map.update_log_odds(key, 0.85f);
  map.set_color(a, Rgb{10, 20, 31});
  map.set_color(b, Rgb{11, 20, 30});
  map.set_color(c, Rgb{255, 255, 255});  // white: "no color" to OctoMap, left out of averages
  check_ot_read_by_octomap(map);
  const auto tree = octomap_read_ot(encode_octomap(map, OctoMapFormat::ot));
  auto* color_tree = dynamic_cast<octomap::ColorOcTree*>(tree.get());
  ASSERT_NE(color_tree, nullptr);
  const octomap::ColorOcTreeNode::Color root = color_tree->getRoot()->getColor();
  EXPECT_EQ(std::tuple(int(root.r), int(root.g), int(root.b)), std::tuple(10, 20, 30));  // truncating average
  const OccupancyMap back = decode_octomap(encode_octomap(map, OctoMapFormat::ot));
  EXPECT_EQ(back.color(c), std::nullopt);
  EXPECT_EQ(back.color(a), (Rgb{10, 20, 31}));
}

TEST(OctoMapWrite, OtherDepthLevelsAreRefusedBeforeAnyFileIsMade) {
  const auto dir = test::scratch_dir();
  OccupancyMap map(0.1, 12);
  map.update_hit(Vec3d{0.0, 0.0, 0.0});
  for (const OctoMapFormat format : {OctoMapFormat::bt, OctoMapFormat::ot}) {
    const fs::path path = dir / (std::string("map.") + to_string(format));
    try {
      save_octomap(map, path, format);
      ADD_FAILURE() << "a 12-level map was written";
    } catch (const std::invalid_argument& e) {
      EXPECT_TRUE(contains(e.what(), "16 depth levels")) << e.what();
      EXPECT_TRUE(contains(e.what(), "has 12")) << e.what();
    }
    EXPECT_FALSE(fs::exists(path));
    EXPECT_THROW((void)encode_octomap(map, format), std::invalid_argument);
  }
  EXPECT_TRUE(fs::is_empty(dir));
}

TEST(OctoMapWrite, SavingReplacesAtomicallyAndKeepsTheOldFileOnFailure) {
  const auto dir = test::scratch_dir();
  const OccupancyMap map = random_map(7, false);
  const fs::path path = dir / "map.ot";
  save_octomap(map, path, OctoMapFormat::ot);
  EXPECT_EQ(read_bytes(path), encode_octomap(map, OctoMapFormat::ot));
  // A failing save (a 12-level map) leaves the old file as it was, and no temporary file.
  OccupancyMap deep(0.1, 12);
  EXPECT_THROW(save_any_map(deep, path), std::invalid_argument);
  EXPECT_EQ(read_bytes(path), encode_octomap(map, OctoMapFormat::ot));
  // A folder that does not exist: an error naming the target.
  try {
    save_octomap(map, dir / "missing" / "map.bt", OctoMapFormat::bt);
    ADD_FAILURE() << "saved into a missing folder";
  } catch (const std::runtime_error& e) {
    EXPECT_TRUE(contains(e.what(), "missing/map.bt")) << e.what();
  }
  // Replacing: the new content, nothing else left in the folder.
  const OccupancyMap other = random_map(8, false);
  save_any_map(other, path);
  EXPECT_EQ(read_bytes(path), encode_octomap(other, OctoMapFormat::ot));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

// --- liboctomap writes, umbra reads -----------------------------------------------------------

TEST(OctoMapRead, LiboctomapOcTreeFromSimulatedScans) {
  octomap::OcTree tree(0.1);
  insert_into_octomap(tree, office_scans(3));
  ASSERT_GT(tree.getNumLeafNodes(), 10000u);
  // .ot: the same leaves, and written back byte for byte.
  const Bytes ot = octomap_ot_bytes(tree);
  const OccupancyMap from_ot = decode_octomap(ot, "office.ot");
  EXPECT_EQ(from_ot.resolution(), 0.1);
  EXPECT_FALSE(from_ot.has_color());
  EXPECT_EQ(test::check_invariants(from_ot), "");
  expect_same_leaves(octomap_leaves(tree), umbra_leaves(from_ot));
  EXPECT_EQ(encode_octomap(from_ot, OctoMapFormat::ot), ot);
  // .bt: liboctomap converts to maximum likelihood; umbra reads what liboctomap reads back.
  const Bytes bt = octomap_bt_bytes(tree);
  const OccupancyMap from_bt = decode_octomap(bt, "office.bt");
  EXPECT_EQ(test::check_invariants(from_bt), "");
  expect_same_leaves(octomap_leaves(*octomap_read_bt(bt)), umbra_leaves(from_bt));
  EXPECT_EQ(encode_octomap(from_bt, OctoMapFormat::bt), bt);
  // Every voxel's state agrees with liboctomap's own tree.
  for (const Leaf& leaf : umbra_leaves(from_ot)) {
    const Key key = morton::decode(leaf.code);
    const octomap::OcTreeNode* node = tree.search(octomap::OcTreeKey(key.x, key.y, key.z));
    ASSERT_NE(node, nullptr);
    EXPECT_EQ(tree.isNodeOccupied(node), test::log_odds_thresholds(from_ot).is_occupied(leaf.value));
  }
}

TEST(OctoMapRead, LiboctomapColorOcTree) {
  octomap::ColorOcTree tree(0.1);
  const auto scans = office_scans(2);
  insert_into_octomap(tree, scans);
  for (const SimulatedScan& scan : scans) {
    for (const Vec3f& p : scan.points) {
      const Rgb rgb = color_of(p);
      tree.integrateNodeColor(p.x, p.y, p.z, rgb.r, rgb.g, rgb.b);
    }
  }
  tree.updateInnerOccupancy();
  const Bytes ot = octomap_ot_bytes(tree);
  ASSERT_TRUE(contains(to_text(Bytes(ot.begin(), ot.begin() + 120)), "id ColorOcTree"));
  const OccupancyMap map = decode_octomap(ot, "office-color.ot");
  ASSERT_TRUE(map.has_color());
  EXPECT_EQ(test::check_invariants(map), "");
  const std::vector<Leaf> leaves = umbra_leaves(map);
  EXPECT_GT(std::count_if(leaves.begin(), leaves.end(), [](const Leaf& l) { return l.color.has_value(); }), 1000);
  expect_same_leaves(octomap_leaves(tree), leaves);
  EXPECT_EQ(encode_octomap(map, OctoMapFormat::ot), ot);
}

TEST(OctoMapRead, LiboctomapOcTreeStampedHasTheOcTreeLayout) {
  octomap::OcTreeStamped tree(0.2);
  insert_into_octomap(tree, office_scans(1));
  const Bytes ot = octomap_ot_bytes(tree);
  const OccupancyMap map = decode_octomap(ot, "stamped.ot");
  std::vector<Leaf> expected;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const int depth = 16 - static_cast<int>(it.getDepth());
    const std::uint32_t mask = ~((std::uint32_t{1} << depth) - 1u);
    const Key first{it.getKey()[0] & mask, it.getKey()[1] & mask, it.getKey()[2] & mask};
    expected.push_back({morton::encode(first), depth, it->getLogOdds(), std::nullopt});
  }
  std::sort(expected.begin(), expected.end());
  expect_same_leaves(expected, umbra_leaves(map));
  // Written back as an OcTree: the same bytes but for the id line.
  std::string text = to_text(ot);
  text.replace(text.find("id OcTreeStamped"), 16, "id OcTree");
  EXPECT_EQ(to_text(encode_octomap(map, OctoMapFormat::ot)), text);
}

TEST(OctoMapRead, UnprunedTreesComeBackUnchangedWithAutoPruningOff) {
  octomap::OcTree tree(0.2);
  insert_into_octomap(tree, office_scans(1));
  tree.expand();  // every leaf split down to the finest depth: groups of eight equal leaves
  const Bytes ot = octomap_ot_bytes(tree);
  const OccupancyMap map = decode_octomap(ot, "unpruned.ot");
  EXPECT_FALSE(map.auto_prune());
  EXPECT_EQ(test::check_invariants(map), "");
  expect_same_leaves(octomap_leaves(tree), umbra_leaves(map));
  EXPECT_EQ(encode_octomap(map, OctoMapFormat::ot), ot);
  // A pruned file keeps auto-pruning on.
  tree.prune();
  EXPECT_TRUE(decode_octomap(octomap_ot_bytes(tree)).auto_prune());
}

TEST(OctoMapRead, EmptyTreesOfEveryKind) {
  octomap::OcTree plain(0.05);
  octomap::ColorOcTree colored(0.25);
  octomap::OcTreeStamped stamped(0.125);
  for (const Bytes& bytes : {octomap_ot_bytes(plain), octomap_ot_bytes(colored), octomap_ot_bytes(stamped),
                             octomap_bt_bytes(plain), octomap_bt_bytes(colored)}) {
    SCOPED_TRACE(to_text(bytes));
    const OccupancyMap map = decode_octomap(bytes);
    EXPECT_TRUE(umbra_leaves(map).empty());
    EXPECT_EQ(map.node_counts().total(), 1u);
    EXPECT_EQ(map.depth_levels(), 16);
  }
  EXPECT_EQ(decode_octomap(octomap_ot_bytes(colored)).resolution(), 0.25);
  EXPECT_TRUE(decode_octomap(octomap_ot_bytes(colored)).has_color());
  EXPECT_FALSE(decode_octomap(octomap_bt_bytes(colored)).has_color());  // a .bt carries no color
  EXPECT_EQ(encode_octomap(decode_octomap(octomap_ot_bytes(plain)), OctoMapFormat::ot), octomap_ot_bytes(plain));
  EXPECT_EQ(encode_octomap(decode_octomap(octomap_ot_bytes(colored)), OctoMapFormat::ot), octomap_ot_bytes(colored));
  EXPECT_EQ(encode_octomap(decode_octomap(octomap_bt_bytes(plain)), OctoMapFormat::bt), octomap_bt_bytes(plain));
}

TEST(OctoMapRead, InfoReadsTheHeaderAndChecksTheSize) {
  const auto dir = test::scratch_dir();
  octomap::ColorOcTree tree(0.1);
  tree.updateNode(octomap::point3d(1.0f, 2.0f, 3.0f), true);
  write_bytes(dir / "a.ot", octomap_ot_bytes(tree));
  const OctoMapFileInfo info = read_octomap_info(dir / "a.ot");
  EXPECT_EQ(info.format, OctoMapFormat::ot);
  EXPECT_EQ(info.tree_type, "ColorOcTree");
  EXPECT_TRUE(info.color);
  EXPECT_EQ(info.resolution, 0.1);
  EXPECT_EQ(info.nodes, tree.size());
  EXPECT_EQ(info.file_bytes, fs::file_size(dir / "a.ot"));
  EXPECT_EQ(info.file_bytes - info.data_offset, 8 * tree.size());
  Bytes cut = octomap_ot_bytes(tree);
  cut.pop_back();
  write_bytes(dir / "cut.ot", cut);
  EXPECT_THROW((void)read_octomap_info(dir / "cut.ot"), FormatError);
}

TEST(OctoMapRead, FilesLargerThanTheReadBufferAreStreamed) {
  // A 64^3 block of distinct values: ~1.5 MB of .ot, more than the 1 MiB read buffer.
  OccupancyMap map(0.05);
  const std::uint32_t base = map.grid().key_offset() - 32u;
  for (std::uint32_t x = 0; x < 64; ++x) {
    for (std::uint32_t y = 0; y < 64; ++y) {
      for (std::uint32_t z = 0; z < 64; ++z) {
        map.set_log_odds(Key{base + x, base + y, base + z}, -1.5f + 0.001f * static_cast<float>((x * 7 + y * 3 + z) % 3000));
      }
    }
  }
  const auto dir = test::scratch_dir();
  save_octomap(map, dir / "large.ot", OctoMapFormat::ot);
  ASSERT_GT(fs::file_size(dir / "large.ot"), std::uintmax_t{1} << 20);
  const OccupancyMap loaded = load_octomap(dir / "large.ot");
  expect_same_leaves(umbra_leaves(map), umbra_leaves(loaded));
  EXPECT_EQ(encode_octomap(loaded, OctoMapFormat::ot), read_bytes(dir / "large.ot"));
  // Cut inside the second buffer: still a clean error with the offset.
  Bytes cut = read_bytes(dir / "large.ot");
  cut.resize(cut.size() - 3);
  write_bytes(dir / "cut.ot", cut);
  try {
    (void)load_octomap(dir / "cut.ot");
    ADD_FAILURE() << "read";
  } catch (const FormatError& e) {
    EXPECT_TRUE(contains(e.what(), "cut.ot:5: size says")) << e.what();
  }
}

// --- the real map ---------------------------------------------------------------------------

TEST(OctoMapGeb079, ReadCountsAndByteIdenticalRewrite) {
  UMBRA_REQUIRE_SHARED_DATA(path, "octomap/geb079.bt");
  const Bytes original = read_bytes(path);
  const OccupancyMap map = load_octomap(path);
  EXPECT_EQ(map.resolution(), 0.08);
  EXPECT_EQ(map.depth_levels(), 16);
  EXPECT_TRUE(map.auto_prune());
  EXPECT_EQ(test::check_invariants(map), "");
  // Leaves counted as OctoMap counts them (a merged node is one leaf), volumes in full.
  std::uint64_t occupied = 0;
  std::uint64_t free = 0;
  double occupied_volume = 0.0;
  double free_volume = 0.0;
  map.for_each_leaf([&](const Node& leaf) {
    const double edge = map.grid().node_size(leaf.depth);
    if (leaf.state == OccupancyState::occupied) {
      ++occupied;
      occupied_volume += edge * edge * edge;
    } else if (leaf.state == OccupancyState::free) {
      ++free;
      free_volume += edge * edge * edge;
    }
  });
  EXPECT_EQ(occupied + free, 428144u);
  EXPECT_EQ(occupied, 143729u);
  EXPECT_EQ(free, 284415u);
  EXPECT_NEAR(occupied_volume, 95.0646, 5e-5);
  EXPECT_NEAR(free_volume, 486.7886, 5e-5);
  // Written again: byte for byte the input, through the file writer too.
  EXPECT_EQ(encode_octomap(map, OctoMapFormat::bt), original);
  const auto dir = test::scratch_dir();
  save_any_map(map, dir / "geb079.bt");
  EXPECT_EQ(read_bytes(dir / "geb079.bt"), original);
  const OctoMapFileInfo info = read_octomap_info(path);
  EXPECT_EQ(info.tree_type, "OcTree");
  EXPECT_EQ(info.nodes, 532566u);
}

TEST(OctoMapGeb079, SameLeavesAsLiboctomapAlsoThroughOt) {
  UMBRA_REQUIRE_SHARED_DATA(path, "octomap/geb079.bt");
  octomap::OcTree tree(0.1);
  ASSERT_TRUE(tree.readBinary(path.string()));
  const OccupancyMap map = load_octomap(path);
  expect_same_leaves(octomap_leaves(tree), umbra_leaves(map));
  EXPECT_EQ(encode_octomap(map, OctoMapFormat::ot), octomap_ot_bytes(tree));  // liboctomap's own .bt -> .ot
  // As .ot, read by liboctomap: the same leaves again; converted back to .bt by liboctomap: the original.
  const auto from_ot = octomap_read_ot(encode_octomap(map, OctoMapFormat::ot));
  auto* ot_tree = dynamic_cast<octomap::OcTree*>(from_ot.get());
  ASSERT_NE(ot_tree, nullptr);
  expect_same_leaves(umbra_leaves(map), octomap_leaves(*ot_tree));
  EXPECT_EQ(octomap_bt_bytes(*ot_tree), read_bytes(path));
}

// --- round trips ------------------------------------------------------------------------------

void expect_exact_round_trip(const OccupancyMap& map) {
  const OccupancyMap back = decode_octomap(encode_octomap(map, OctoMapFormat::ot));
  EXPECT_EQ(test::check_invariants(back), "");
  EXPECT_EQ(back.resolution(), map.resolution());
  EXPECT_EQ(back.has_color(), map.has_color());
  const std::vector<Leaf> expected = all_umbra_leaves(map);
  const std::vector<Leaf> actual = all_umbra_leaves(back);
  ASSERT_EQ(expected.size(), actual.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    ASSERT_EQ(std::bit_cast<std::uint32_t>(expected[i].value), std::bit_cast<std::uint32_t>(actual[i].value))
        << expected[i];
    ASSERT_EQ(expected[i], actual[i]);
  }
  // Nothing changes on a second trip.
  EXPECT_EQ(encode_octomap(back, OctoMapFormat::ot), encode_octomap(map, OctoMapFormat::ot));
}

TEST(OctoMapRoundTrip, OtKeepsLogOddsAndColorsExactly) {
  for (std::uint32_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    expect_exact_round_trip(random_map(seed, false));
    expect_exact_round_trip(random_map(seed, true));
    expect_exact_round_trip(random_map(seed, true, true, 0.123456789));  // a resolution %g would round
  }
  OccupancyMap single(0.1);
  single.update_miss(Vec3d{0.0, 0.0, 0.0});
  expect_exact_round_trip(single);
  expect_exact_round_trip(OccupancyMap(0.1));
}

TEST(OctoMapRoundTrip, ValuesBeyondTheDefaultClampingWidenTheLoadedRange) {
  SensorModel wide;
  wide.clamp_min = 0.01;
  wide.clamp_max = 0.999;
  OccupancyMap map(0.1, 16, wide);
  for (int i = 0; i < 12; ++i) map.update_hit(Vec3d{0.05, 0.05, 0.05});
  for (int i = 0; i < 12; ++i) map.update_miss(Vec3d{0.15, 0.05, 0.05});
  ASSERT_EQ(map.log_odds({0.05, 0.05, 0.05}), wide.clamp_max_log_odds());
  ASSERT_EQ(map.log_odds({0.15, 0.05, 0.05}), wide.clamp_min_log_odds());
  const OccupancyMap back = decode_octomap(encode_octomap(map, OctoMapFormat::ot));
  EXPECT_EQ(back.log_odds({0.05, 0.05, 0.05}), wide.clamp_max_log_odds());
  EXPECT_EQ(back.log_odds({0.15, 0.05, 0.05}), wide.clamp_min_log_odds());
  EXPECT_GT(back.sensor_model().clamp_max, SensorModel{}.clamp_max);
  EXPECT_LT(back.sensor_model().clamp_min, SensorModel{}.clamp_min);
  EXPECT_LE(back.sensor_model().clamp_max_log_odds() - wide.clamp_max_log_odds(), 1e-5f);
  EXPECT_EQ(back.sensor_model().p_hit, SensorModel{}.p_hit);
  EXPECT_EQ(test::check_invariants(back), "");
  // The sensor model passed in is the one the map gets (and .bt leaves take its clamping values).
  const OccupancyMap with_model = decode_octomap(encode_octomap(map, OctoMapFormat::ot), "x.ot", wide);
  EXPECT_EQ(with_model.sensor_model(), wide);
  const OccupancyMap bt = decode_octomap(encode_octomap(map, OctoMapFormat::bt), "x.bt", wide);
  EXPECT_EQ(bt.log_odds({0.15, 0.05, 0.05}), wide.clamp_min_log_odds());
}

TEST(OctoMapRoundTrip, BtKeepsEveryVoxelsClass) {
  const OccupancyMap map = random_map(5, true);
  const OccupancyMap back = decode_octomap(encode_octomap(map, OctoMapFormat::bt));
  EXPECT_FALSE(back.has_color());
  EXPECT_EQ(test::check_invariants(back), "");
  map.for_each_leaf([&](const Node& leaf) {
    const Node node = back.node(leaf.key, leaf.depth);
    EXPECT_EQ(test::log_odds_thresholds(back).classify(node.log_odds), leaf.state);
    if (leaf.state == OccupancyState::unknown) return;
    EXPECT_EQ(node.log_odds, leaf.state == OccupancyState::occupied ? back.sensor_model().clamp_max_log_odds()
                                                                   : back.sensor_model().clamp_min_log_odds());
  });
  EXPECT_EQ(encode_octomap(back, OctoMapFormat::bt), encode_octomap(map, OctoMapFormat::bt));
}

TEST(OctoMapRoundTrip, AnyMapFormatByExtension) {
  const auto dir = test::scratch_dir();
  const OccupancyMap map = random_map(3, true);
  for (const char* name : {"m.umb", "m.BT", "m.ot"}) {
    save_any_map(map, dir / name);
    const OccupancyMap back = load_any_map(dir / name);
    EXPECT_EQ(umbra_leaves(back).size(), umbra_leaves(map).size()) << name;
  }
  EXPECT_EQ(map_file_format_for("a/b.Umb"), MapFileFormat::umb);
  EXPECT_EQ(map_file_format("x.xyz"), std::nullopt);
  try {
    save_any_map(map, dir / "m.octomap");
    ADD_FAILURE() << "saved with an unknown extension";
  } catch (const std::invalid_argument& e) {
    EXPECT_TRUE(contains(e.what(), "'.octomap'")) << e.what();
    EXPECT_TRUE(contains(e.what(), ".umb")) << e.what();
  }
  EXPECT_THROW((void)load_any_map(dir / "m"), std::invalid_argument);
  // .bt and .ot are told apart by their content, whatever the extension says.
  fs::copy_file(dir / "m.ot", dir / "really-ot.bt");
  EXPECT_TRUE(load_any_map(dir / "really-ot.bt").has_color());
}

// --- malformed files ---------------------------------------------------------------------------

std::string quote_for_test(const std::string& text) {
  std::string out;
  for (const char c : text) out += c == '\n' ? std::string("\\n") : std::string(1, c);
  return "'" + out + "'";
}

std::string header(const std::string& first_line, const std::string& id, const std::string& size,
                   const std::string& res) {
  return first_line + "\n# comment\n#\nid " + id + "\nsize " + size + "\nres " + res + "\ndata\n";
}
const std::string kBt = "# Octomap OcTree binary file";
const std::string kOt = "# Octomap OcTree file";

Bytes with_data(const std::string& head, const Bytes& data) {
  Bytes bytes = to_bytes(head);
  bytes.insert(bytes.end(), data.begin(), data.end());
  return bytes;
}

/// One ot node: float log-odds, optional color, child mask.
void append_ot_node(Bytes& out, float value, std::uint8_t mask, const Rgb* rgb = nullptr) {
  const auto bits = std::bit_cast<std::uint32_t>(value);
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(bits >> (8 * i)));
  if (rgb != nullptr) {
    out.push_back(rgb->r);
    out.push_back(rgb->g);
    out.push_back(rgb->b);
  }
  out.push_back(mask);
}

/// Small files of each kind, written by umbra (and checked against liboctomap above).
std::vector<std::pair<std::string, Bytes>> small_files() {
  OccupancyMap plain(0.1);
  MapConfig config;
  config.resolution = 0.1;
  config.color = true;
  OccupancyMap colored(config);
  for (const Vec3d& p : {Vec3d{0.05, 0.05, 0.05}, Vec3d{-0.35, 0.05, 0.15}, Vec3d{0.05, 0.25, -0.05}}) {
    plain.update_hit(p);
    plain.update_miss(p + Vec3d{0.1, 0.0, 0.0});
    colored.update_hit(p);
    colored.add_color(p, Rgb{1, 2, 3});
  }
  return {{"small.bt", encode_octomap(plain, OctoMapFormat::bt)},
          {"small.ot", encode_octomap(plain, OctoMapFormat::ot)},
          {"small-color.ot", encode_octomap(colored, OctoMapFormat::ot)}};
}

TEST(OctoMapMalformed, EveryTruncationAndTrailingByteIsAFormatError) {
  for (const auto& [name, bytes] : small_files()) {
    SCOPED_TRACE(name);
    ASSERT_NO_THROW((void)decode_octomap(bytes, name));
    for (std::size_t size = 0; size < bytes.size(); ++size) {
      const std::string message = decode_error(Bytes(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(size)), name);
      ASSERT_TRUE(message.starts_with(name + ":")) << "cut at " << size << ": " << message;
    }
    Bytes longer = bytes;
    longer.push_back(0);
    EXPECT_TRUE(contains(decode_error(longer, name), "size says")) << decode_error(longer, name);
  }
}

TEST(OctoMapMalformed, EveryBitFlipIsReadOrRefusedCleanly) {
  for (const auto& [name, bytes] : small_files()) {
    SCOPED_TRACE(name);
    int refused = 0;
    for (std::size_t i = 0; i < bytes.size(); ++i) {
      for (int bit = 0; bit < 8; ++bit) {
        Bytes flipped = bytes;
        flipped[i] = static_cast<std::uint8_t>(flipped[i] ^ (1u << bit));
        try {
          const OccupancyMap map = decode_octomap(flipped, name);
          ASSERT_EQ(test::check_invariants(map), "") << "byte " << i << " bit " << bit;
        } catch (const FormatError&) {
          ++refused;
        }
      }
    }
    EXPECT_GT(refused, 0);
  }
}

TEST(OctoMapMalformed, BadHeadersNameTheLineAndTheProblem) {
  const Bytes root_only = {0, 0};
  struct Case {
    std::string text;
    std::string expected;  // part of the message
  };
  const std::vector<Case> cases = {
      {"", "bad.bt:1: not an OctoMap file"},
      {"UMBRAMAP........", "bad.bt:1: not an OctoMap file"},
      {"# Octomap OcTree binary\nid OcTree\n", "bad.bt:1: not an OctoMap file"},
      {kBt + "\nid OcTree\nsize 1\nres 0.1\n", "bad.bt:5: the header ends without a 'data' line"},
      {kBt + "\nid OcTree\nsize 1\nres 0.1\ndat\n", "bad.bt:6: the header ends without a 'data' line"},
      {kBt + "\nsize 1\nres 0.1\ndata\n", "bad.bt:4: the header has no 'id' line"},
      {kBt + "\nid OcTree\nres 0.1\ndata\n", "no 'size' line"},
      {kBt + "\nid OcTree\nsize 1\ndata\n", "no 'res' line"},
      {header(kBt, "FancyTree", "1", "0.1"), "bad.bt:4: unknown tree type 'FancyTree'"},
      {header(kBt, "CountingOcTree", "1", "0.1"), "CountingOcTree"},
      {header(kOt, "OcTreeBase", "1", "0.1"), "it counts hits"},
      {header(kBt, "OcTree", "many", "0.1"), "bad.bt:5: size must be a whole number"},
      {header(kBt, "OcTree", "-3", "0.1"), "bad.bt:5: size must be a whole number"},
      {header(kBt, "OcTree", "3.5", "0.1"), "size must be a whole number"},
      {header(kBt, "OcTree", "18446744073709551616", "0.1"), "is too large"},
      {header(kBt, "OcTree", "1", "abc"), "bad.bt:6: res must be a number"},
      {header(kBt, "OcTree", "1", "0.1m"), "res must be a number"},
      {header(kBt, "OcTree", "1", "0"), "res must be the voxel edge in metres, in [0.0001, 1000] (0.1 mm to 1 km), found '0'"},
      {header(kBt, "OcTree", "1", "-0.1"), "res must be the voxel edge in metres, in [0.0001, 1000]"},
      {header(kBt, "OcTree", "1", "nan"), "res must be the voxel edge in metres, in [0.0001, 1000]"},
      {header(kBt, "OcTree", "1", "inf"), "res must be the voxel edge in metres, in [0.0001, 1000]"},
      {header(kBt, "OcTree", "1", "1e-320"), "res must be the voxel edge in metres, in [0.0001, 1000]"},
      {header(kBt, "OcTree", "1", "1e-300"), "found '1e-300'"},
      {header(kBt, "OcTree", "1", "1e300"), "found '1e300'"},
      {header(kBt, "OcTree", "1", "0.00009"), "found '0.00009'"},
      {header(kBt, "OcTree", "1", "1000.001"), "found '1000.001'"},
      {kBt + "\nid " + std::string(100, 'x') + "\n", "longer than 64 bytes"},
  };
  for (const Case& c : cases) {
    const std::string message = decode_error(with_data(c.text, root_only), "bad.bt");
    EXPECT_TRUE(contains(message, c.expected)) << "header " << quote_for_test(c.text) << "\n  gave: " << message;
  }
  const std::string cut = decode_error(to_bytes(kBt + "\nid OcTree\nsize 1\nres"), "cut.bt");
  EXPECT_TRUE(contains(cut, "cut.bt:4: the header ends after 'res' without its value")) << cut;
}

TEST(OctoMapMalformed, HeadersLiboctomapAcceptsAreAccepted) {
  const Bytes root_only = {0, 0};
  for (const std::string& text : {
           header(kBt, "1", "1", "0.1"),                                      // the legacy id
           header(kBt, "OcTreeStamped", "1", "+0.1"),                         // a sign, as istream reads it
           kBt + " extra text\r\n#\r\nid OcTree\r\nsize 1\r\nres 0.1\r\ndata\r\n",  // CRLF, text after the first line
           kBt + "\nfoo bar baz\n# a comment with data in it\nid\n OcTree size 1 res 0.1\ndata trailing words\n",
       }) {
    SCOPED_TRACE(text);
    const OccupancyMap map = decode_octomap(with_data(text, root_only), "ok.bt");
    EXPECT_EQ(map.resolution(), 0.1);
    // A root without children: liboctomap makes it one occupied leaf.
    EXPECT_EQ(map.state({123.0, -45.0, 6.0}), OccupancyState::occupied);
  }
}

TEST(OctoMapMalformed, SizesThatLieAreRefusedBeforeReadingTheTree) {
  test::AddressSpaceCap cap(256u << 20);  // a reader allocating what the header claims fails here
  const Bytes bt = small_files()[0].second;
  const Bytes ot = small_files()[1].second;
  const std::string bt_text = to_text(bt);
  const std::string ot_text = to_text(ot);
  const std::size_t bt_data = bt_text.find("data\n") + 5;
  const std::size_t ot_data = ot_text.find("data\n") + 5;
  const Bytes bt_tree(bt.begin() + static_cast<std::ptrdiff_t>(bt_data), bt.end());
  const Bytes ot_tree(ot.begin() + static_cast<std::ptrdiff_t>(ot_data), ot.end());
  const std::uint64_t ot_nodes = ot_tree.size() / 5;
  for (const char* size : {"0", "1", "1000000", "1152921504606846976", "18446744073709551615"}) {
    SCOPED_TRACE(size);
    EXPECT_TRUE(contains(decode_error(with_data(header(kBt, "OcTree", size, "0.1"), bt_tree), "lie.bt"), "lie.bt:5: size"));
    EXPECT_TRUE(contains(decode_error(with_data(header(kOt, "OcTree", size, "0.1"), ot_tree), "lie.ot"), "lie.ot:5: size"));
  }
  // Plausible for the length, but not the tree: found while reading, at a byte.
  const std::string wrong = decode_error(with_data(header(kOt, "ColorOcTree", std::to_string(ot_tree.size() / 8), "0.1"),
                                                   Bytes(ot_tree.begin(), ot_tree.begin() + static_cast<std::ptrdiff_t>(ot_tree.size() / 8 * 8))));
  EXPECT_TRUE(contains(wrong, ": byte ")) << wrong;
  EXPECT_NO_THROW((void)decode_octomap(with_data(header(kOt, "OcTree", std::to_string(ot_nodes), "0.1"), ot_tree)));
  // A .bt whose size is possible for its length but does not match the tree.
  const std::size_t size_at = bt_text.find("size ") + 5;
  const std::uint64_t nodes = std::stoull(bt_text.substr(size_at, bt_text.find('\n', size_at) - size_at));
  const std::string mismatch =
      decode_error(with_data(header(kBt, "OcTree", std::to_string(nodes + 1), "0.1"), bt_tree), "m.bt");
  EXPECT_TRUE(contains(mismatch, "but size says " + std::to_string(nodes + 1))) << mismatch;
}

TEST(OctoMapMalformed, HostileTreesAreRefused) {
  // .bt: a chain of "child 0 has children" deeper than 16 levels.
  for (const int pairs : {16, 17, 1000}) {
    Bytes chain;
    for (int i = 0; i < pairs; ++i) {
      chain.push_back(0x03);
      chain.push_back(0x00);
    }
    const std::string message =
        decode_error(with_data(header(kBt, "OcTree", std::to_string(pairs + 1), "0.1"), chain), "deep.bt");
    EXPECT_TRUE(contains(message, "finest depth")) << message;
    EXPECT_TRUE(contains(message, "deep.bt: byte ")) << message;
  }
  // .bt: a child marked as having children whose own bytes say it has none.
  EXPECT_TRUE(contains(decode_error(with_data(header(kBt, "OcTree", "2", "0.1"), {0x03, 0x00, 0x00, 0x00})),
                       "its own two bytes are 0 0"));
  // .ot: a chain of nodes with one child each, deeper than 16 levels.
  for (const int nodes : {17, 18, 1000}) {
    Bytes chain;
    for (int i = 0; i < nodes; ++i) append_ot_node(chain, 0.5f, 0x01);
    const std::string message =
        decode_error(with_data(header(kOt, "OcTree", std::to_string(nodes), "0.1"), chain), "deep.ot");
    EXPECT_TRUE(contains(message, "finest depth")) << message;
  }
  // .ot: values that are not numbers, or too extreme for any clamping range.
  for (const float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
    Bytes root;
    append_ot_node(root, bad, 0x00);
    EXPECT_TRUE(contains(decode_error(with_data(header(kOt, "OcTree", "1", "0.1"), root)), "not a finite number"));
    Bytes inner;
    append_ot_node(inner, bad, 0x01);
    append_ot_node(inner, 1.0f, 0x00);
    EXPECT_TRUE(contains(decode_error(with_data(header(kOt, "OcTree", "2", "0.1"), inner)), "not a finite number"));
  }
  for (const float extreme : {100.0f, -1000.0f, -std::numeric_limits<float>::max()}) {
    Bytes tree;
    append_ot_node(tree, extreme, 0x01);
    append_ot_node(tree, extreme, 0x00);
    const std::string message = decode_error(with_data(header(kOt, "OcTree", "2", "0.1"), tree));
    EXPECT_TRUE(contains(message, "clamping probability")) << message;
  }
  // -200 is what liboctomap 1.9.7 leaves in nodes of malformed .bt files: still representable.
  Bytes low;
  append_ot_node(low, -200.0f, 0x01);
  append_ot_node(low, -200.0f, 0x00);
  EXPECT_EQ(decode_octomap(with_data(header(kOt, "OcTree", "2", "0.1"), low)).log_odds({-1.0, -1.0, -1.0}, 15), -200.0f);
}

TEST(OctoMapMalformed, FilesThatCannotBeOpened) {
  const auto dir = test::scratch_dir();
  EXPECT_THROW((void)load_octomap(dir / "missing.bt"), std::runtime_error);
  EXPECT_THROW((void)load_octomap(dir), std::runtime_error);  // a folder
  write_bytes(dir / "x.umb.bt", to_bytes("UMBRAMAP"));
  try {
    (void)load_any_map(dir / "x.umb.bt");
    ADD_FAILURE() << "read";
  } catch (const FormatError& e) {
    EXPECT_TRUE(contains(e.what(), (dir / "x.umb.bt").string() + ":1: not an OctoMap file")) << e.what();
  }
}

// --- tree data without the header (octomap_msgs/Octomap's `data`) ------------------------

/// liboctomap's writeBinaryData / writeData: the tree without the file header.
Bytes octomap_bt_data(octomap::OcTree& tree) {
  std::ostringstream out;
  EXPECT_TRUE(tree.writeBinaryData(out));
  return to_bytes(out.str());
}

template <typename Tree>
Bytes octomap_ot_data(const Tree& tree) {
  std::ostringstream out;
  EXPECT_TRUE(tree.writeData(out));
  return to_bytes(out.str());
}

/// The FormatError message decoding tree data gives; a test failure if it decodes.
std::string tree_data_error(OctoMapFormat format, const std::string& id, double resolution, const Bytes& data) {
  try {
    (void)decode_octomap_tree(format, id, resolution, data, "msg");
  } catch (const FormatError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected a FormatError, but the data was read";
  return "";
}

TEST(OctoMapTreeData, EncodedAsLiboctomapWritesItsData) {
  for (const bool color : {false, true}) {
    const OccupancyMap map = random_map(41, color);
    const OctoMapTreeData bt = encode_octomap_tree(map, OctoMapFormat::bt);
    EXPECT_EQ(bt.id, "OcTree");
    EXPECT_EQ(bt.resolution, map.resolution());
    const auto bt_tree = octomap_read_bt(encode_octomap(map, OctoMapFormat::bt));
    EXPECT_EQ(bt.data, octomap_bt_data(*bt_tree));

    const OctoMapTreeData ot = encode_octomap_tree(map, OctoMapFormat::ot);
    EXPECT_EQ(ot.id, color ? "ColorOcTree" : "OcTree");
    const auto ot_tree = octomap_read_ot(encode_octomap(map, OctoMapFormat::ot));
    ASSERT_NE(ot_tree, nullptr);
    if (color) {
      EXPECT_EQ(ot.data, octomap_ot_data(dynamic_cast<octomap::ColorOcTree&>(*ot_tree)));
    } else {
      EXPECT_EQ(ot.data, octomap_ot_data(dynamic_cast<octomap::OcTree&>(*ot_tree)));
    }
  }
  EXPECT_THROW((void)encode_octomap_tree(OccupancyMap(0.1, 15), OctoMapFormat::bt), std::invalid_argument);
}

TEST(OctoMapTreeData, DecodesLiboctomapsDataLikeItsFiles) {
  octomap::OcTree tree(0.1);
  insert_into_octomap(tree, office_scans(3));
  const OccupancyMap from_ot = decode_octomap_tree(OctoMapFormat::ot, "OcTree", 0.1, octomap_ot_data(tree));
  expect_same_leaves(octomap_leaves(tree), umbra_leaves(from_ot));
  EXPECT_EQ(from_ot.resolution(), 0.1);

  // Unpruned, not maximum likelihood: the data as a ROS node with this tree would send it.
  const Bytes bt = octomap_bt_data(tree);
  const OccupancyMap from_bt = decode_octomap_tree(OctoMapFormat::bt, "OcTree", 0.1, bt);
  octomap::OcTree read_back(0.1);  // liboctomap's own reading of that data
  std::istringstream in(to_text(bt));
  read_back.readBinaryData(in);
  expect_same_leaves(octomap_leaves(read_back), umbra_leaves(from_bt));
  EXPECT_FALSE(umbra_leaves(from_bt).empty());

  octomap::ColorOcTree color_tree(0.1);
  insert_into_octomap(color_tree, office_scans(2));
  for (auto it = color_tree.begin_leafs(), end = color_tree.end_leafs(); it != end; ++it) it->setColor(10, 20, 30);
  color_tree.updateInnerOccupancy();
  const OccupancyMap colored = decode_octomap_tree(OctoMapFormat::ot, "ColorOcTree", 0.1, octomap_ot_data(color_tree));
  EXPECT_TRUE(colored.has_color());
  expect_same_leaves(octomap_leaves(color_tree), umbra_leaves(colored));

  // An empty tree is no bytes.
  EXPECT_TRUE(umbra_leaves(decode_octomap_tree(OctoMapFormat::bt, "OcTree", 0.1, Bytes{})).empty());
  EXPECT_TRUE(encode_octomap_tree(OccupancyMap(0.1), OctoMapFormat::ot).data.empty());
}

TEST(OctoMapTreeData, BadDataIsAClearError) {
  octomap::OcTree tree(0.1);
  insert_into_octomap(tree, office_scans(1));
  const Bytes ot = octomap_ot_data(tree);
  const Bytes bt = octomap_bt_data(tree);

  std::string message = tree_data_error(OctoMapFormat::ot, "OcTree", 0.1, Bytes(ot.begin(), ot.end() - 2));
  EXPECT_TRUE(contains(message, "msg: byte " + std::to_string((ot.size() - 2) / 5 * 5))) << message;
  EXPECT_TRUE(contains(message, "not a whole number of 5-byte OcTree nodes")) << message;
  message = tree_data_error(OctoMapFormat::ot, "OcTree", 0.1, Bytes(ot.begin(), ot.end() - 5));
  EXPECT_TRUE(contains(message, "msg: byte")) << message;  // whole nodes, but the tree is cut short

  message = tree_data_error(OctoMapFormat::bt, "OcTree", 0.1, Bytes(bt.begin(), bt.end() - 1));
  EXPECT_TRUE(contains(message, "odd number of bytes")) << message;
  message = tree_data_error(OctoMapFormat::bt, "OcTree", 0.1, Bytes(bt.begin(), bt.end() - 2));
  EXPECT_TRUE(contains(message, "msg: byte")) << message;

  message = tree_data_error(OctoMapFormat::bt, "CountingOcTree", 0.1, bt);
  EXPECT_TRUE(contains(message, "CountingOcTree")) << message;
  message = tree_data_error(OctoMapFormat::ot, "OcTree\nsize 3", 0.1, ot);
  EXPECT_TRUE(contains(message, "unknown tree type")) << message;
  for (const double resolution : {0.0, -0.1, std::numeric_limits<double>::quiet_NaN(), 1e-320}) {
    message = tree_data_error(OctoMapFormat::ot, "OcTree", resolution, ot);
    EXPECT_TRUE(contains(message, "resolution must be")) << message;
  }
}

}  // namespace
}  // namespace umbra
