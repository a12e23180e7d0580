// `umbra convert` and `umbra info` with OctoMap files, run as a user would:
// .umb -> .bt -> .ot -> .umb keeps every voxel's class (and .umb -> .ot ->
// .umb every value and color), info reads all three formats, and bad names
// are usage errors (exit code 2) with a message; info's OctoMap node count
// is liboctomap's. Cost: a few runs of the program on a small simulated map,
// well under a second.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <memory>
#include <string>

#include <octomap/AbstractOcTree.h>
#include <octomap/OcTree.h>

#include "support/cli_commands.hpp"
#include "support/test_support.hpp"
#include "support/map_internals.hpp"
#include "umbra/io/map_file.hpp"
#include "umbra/io/map_formats.hpp"
#include "umbra/map/map_statistics.hpp"
#include "umbra/sim/lidar.hpp"
#include "umbra/sim/scene.hpp"

namespace umbra {
namespace {

namespace fs = std::filesystem;

using test::CommandResult;
CommandResult run(const std::string& command) { return test::run_command(command); }

using test::cli;
using test::quoted;
using test::contains;

/// A colored map of the simulated office from two poses, 20 cm voxels.
OccupancyMap office_map() {
  MapConfig config;
  config.resolution = 0.2;
  config.color = true;
  OccupancyMap map(config);
  const sim::Scene scene = sim::make_demo_scene();
  sim::LidarModel lidar;
  lidar.rings = 8;
  lidar.azimuth_steps = 180;
  for (const sim::SensorPose& pose : {sim::demo_path()[0], sim::demo_path()[3]}) {
    const std::vector<Vec3f> points = sim::simulate_scan(scene, pose, lidar);
    std::vector<Rgb> colors(points.size(), Rgb{200, 100, 50});
    map.insert_point_cloud(Vec3f(pose.position), points, colors);
  }
  return map;
}

TEST(OctoMapCli, ConvertChainKeepsTheMap) {
  const auto dir = test::scratch_dir();
  const OccupancyMap map = office_map();
  save_map(map, dir / "a.umb");

  const CommandResult to_bt = run(cli() + " convert " + quoted(dir / "a.umb") + " " + quoted(dir / "b.bt"));
  ASSERT_EQ(to_bt.exit_code, 0) << to_bt.output;
  EXPECT_TRUE(contains(to_bt.output, "colors are dropped")) << to_bt.output;
  const CommandResult to_ot = run(cli() + " convert " + quoted(dir / "b.bt") + " " + quoted(dir / "c.ot"));
  ASSERT_EQ(to_ot.exit_code, 0) << to_ot.output;
  const CommandResult to_umb = run(cli() + " convert " + quoted(dir / "c.ot") + " " + quoted(dir / "d.umb"));
  ASSERT_EQ(to_umb.exit_code, 0) << to_umb.output;
  EXPECT_TRUE(contains(to_umb.output, "(umb,")) << to_umb.output;

  // Through .bt every voxel keeps its class (values become the clamping limits).
  const OccupancyMap chained = load_map(dir / "d.umb");
  const MapStatistics before = compute_statistics(map);
  const MapStatistics after = compute_statistics(chained);
  EXPECT_EQ(after.occupied_voxels, before.occupied_voxels);
  EXPECT_EQ(after.free_voxels, before.free_voxels);
  map.for_each_leaf([&](const Node& leaf) {
    ASSERT_EQ(test::log_odds_thresholds(chained).classify(chained.node(leaf.key, leaf.depth).log_odds), leaf.state);
  });

  // Through .ot alone every value and color is kept.
  ASSERT_EQ(run(cli() + " convert " + quoted(dir / "a.umb") + " " + quoted(dir / "e.ot")).exit_code, 0);
  ASSERT_EQ(run(cli() + " convert " + quoted(dir / "e.ot") + " " + quoted(dir / "f.umb")).exit_code, 0);
  const OccupancyMap exact = load_map(dir / "f.umb");
  ASSERT_TRUE(exact.has_color());
  map.for_each_leaf([&](const Node& leaf) {
    const Node node = exact.node(leaf.key, leaf.depth);
    ASSERT_EQ(node.log_odds, leaf.log_odds);
    ASSERT_EQ(node.depth, leaf.depth);
    ASSERT_EQ(exact.color(leaf.key, leaf.depth), leaf.color);
  });
}

TEST(OctoMapCli, InfoReadsAllThreeFormats) {
  const auto dir = test::scratch_dir();
  const OccupancyMap map = office_map();
  save_any_map(map, dir / "x.umb");
  save_any_map(map, dir / "x.bt");
  save_any_map(map, dir / "x.ot");
  const MapStatistics expected = compute_statistics(map);
  for (const char* name : {"x.umb", "x.bt", "x.ot"}) {
    const CommandResult info = run(cli() + " info --json " + quoted(dir / name));
    ASSERT_EQ(info.exit_code, 0) << name << ": " << info.output;
    EXPECT_TRUE(contains(info.output, "\"occupied_voxels\": " + std::to_string(expected.occupied_voxels)))
        << name << ": " << info.output;
    const CommandResult text = run(cli() + " info " + quoted(dir / name));
    ASSERT_EQ(text.exit_code, 0) << text.output;
    EXPECT_TRUE(contains(text.output, "occupied")) << text.output;
  }
}

/// The "octomap_nodes" of `umbra info --json`.
std::size_t info_octomap_nodes(const fs::path& map) {
  const CommandResult info = run(cli() + " info --json " + quoted(map));
  EXPECT_EQ(info.exit_code, 0) << info.output;
  const auto at = info.output.find("\"octomap_nodes\": ");
  EXPECT_NE(at, std::string::npos) << info.output;
  return at == std::string::npos ? 0 : std::stoull(info.output.substr(at + 17));
}

// umbra's node count is larger than OctoMap's (every node with children has
// all eight); `info` gives OctoMap's too, which liboctomap itself confirms
// on the same map read from .ot and .bt (written by umbra), and on OctoMap's
// own geb079.bt.
TEST(OctoMapCli, InfoGivesLiboctomapsNodeCountAndSaysWhy) {
  const auto dir = test::scratch_dir();
  const OccupancyMap map = office_map();
  save_map(map, dir / "a.umb");
  save_any_map(map, dir / "a.ot");
  save_any_map(map, dir / "a.bt");
  const std::unique_ptr<octomap::AbstractOcTree> full(octomap::AbstractOcTree::read((dir / "a.ot").string()));
  ASSERT_NE(full, nullptr);
  octomap::OcTree binary(0.1);
  ASSERT_TRUE(binary.readBinary((dir / "a.bt").string()));
  EXPECT_EQ(info_octomap_nodes(dir / "a.umb"), full->size());
  EXPECT_EQ(info_octomap_nodes(dir / "a.ot"), full->size());
  EXPECT_EQ(info_octomap_nodes(dir / "a.bt"), binary.size());
  EXPECT_LT(full->size(), map.node_counts().total()) << "the office map should show the difference";
  const CommandResult text = run(cli() + " info " + quoted(dir / "a.umb"));
  EXPECT_TRUE(contains(text.output, "  OctoMap nodes     " + std::to_string(full->size()) +
                                        " (liboctomap's count for this map: it stores no unknown children"))
      << text.output;
  EXPECT_TRUE(contains(run(cli() + " info --help").output, "OctoMap leaves unobserved children out"));

  UMBRA_REQUIRE_SHARED_DATA(geb079, "octomap/geb079.bt");
  octomap::OcTree corridor(0.1);
  ASSERT_TRUE(corridor.readBinary(geb079.string()));
  EXPECT_EQ(info_octomap_nodes(geb079), corridor.size());
  EXPECT_EQ(corridor.size(), 532566u);  // shared/data/README.md's figure from OctoMap 1.9.7
}

TEST(OctoMapCli, BadNamesAndMapsAreErrorsWithMessages) {
  const auto dir = test::scratch_dir();
  save_map(office_map(), dir / "a.umb");
  // Unknown output extension: a usage error, before anything is read.
  const CommandResult bad_out = run(cli() + " convert " + quoted(dir / "a.umb") + " " + quoted(dir / "b.ply"));
  EXPECT_EQ(bad_out.exit_code, 2) << bad_out.output;
  EXPECT_TRUE(contains(bad_out.output, "unknown map file extension '.ply'")) << bad_out.output;
  EXPECT_FALSE(fs::exists(dir / "b.ply"));
  // Unknown input extension.
  fs::copy_file(dir / "a.umb", dir / "a.xyz");
  const CommandResult bad_in = run(cli() + " convert " + quoted(dir / "a.xyz") + " " + quoted(dir / "b.bt"));
  EXPECT_EQ(bad_in.exit_code, 2) << bad_in.output;
  EXPECT_TRUE(contains(bad_in.output, "'.xyz'")) << bad_in.output;
  // Missing input: an input failure (exit code 1) naming the file.
  const CommandResult missing = run(cli() + " convert " + quoted(dir / "none.bt") + " " + quoted(dir / "b.ot"));
  EXPECT_EQ(missing.exit_code, 1) << missing.output;
  EXPECT_TRUE(contains(missing.output, "none.bt': No such file or directory")) << missing.output;
  // A map of 12 depth levels cannot become an OctoMap file.
  OccupancyMap shallow(0.1, 12);
  shallow.update_hit(Vec3d{0.0, 0.0, 0.0});
  save_map(shallow, dir / "shallow.umb");
  const CommandResult deep = run(cli() + " convert " + quoted(dir / "shallow.umb") + " " + quoted(dir / "s.ot"));
  EXPECT_EQ(deep.exit_code, 1) << deep.output;
  EXPECT_TRUE(contains(deep.output, "16 depth levels")) << deep.output;
  EXPECT_FALSE(fs::exists(dir / "s.ot"));
  // A malformed OctoMap file: exit code 1, the file and line named.
  std::FILE* f = std::fopen((dir / "junk.bt").c_str(), "w");
  std::fputs("# Octomap OcTree binary file\nid OcTree\nsize 1\nres zero\ndata\n", f);
  std::fclose(f);
  const CommandResult junk = run(cli() + " info " + quoted(dir / "junk.bt"));
  EXPECT_EQ(junk.exit_code, 1) << junk.output;
  EXPECT_TRUE(contains(junk.output, "junk.bt:4: res must be a number")) << junk.output;
  const CommandResult unknown_info = run(cli() + " info " + quoted(dir / "a.xyz"));
  EXPECT_EQ(unknown_info.exit_code, 1) << unknown_info.output;
  EXPECT_TRUE(contains(unknown_info.output, "'.xyz'")) << unknown_info.output;
}

}  // namespace
}  // namespace umbra
