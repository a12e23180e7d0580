// `umbra merge` run as a user would: the saved map equals the library's
// OccupancyMap::merge of the same inputs (checked voxel by voxel against
// brute force in tests/map/map_merge_test.cpp), node for node, for .umb and
// .bt inputs, offsets and transforms. Bad input: exit code 2 for options, 1
// for files, each message naming the value or the file; nothing is written.
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "support/cli_commands.hpp"
#include "support/test_support.hpp"
#include "umbra/io/map_file.hpp"
#include "umbra/io/map_formats.hpp"
#include "umbra/io/spill_file.hpp"
#include "umbra/map/moving_window.hpp"

namespace umbra {
namespace {

namespace fs = std::filesystem;
using test::CommandResult;
using test::contains;
using test::quoted;
using test::run;

/// A room's walls seen from `origin` (10 cm voxels).
OccupancyMap room(Vec3f origin, double resolution = 0.1) {
  OccupancyMap map(resolution);
  std::vector<Vec3f> points;
  for (int i = -15; i <= 15; ++i) {
    for (int j = -15; j <= 15; ++j) {
      const float a = static_cast<float>(i) * 0.1f + 0.03f;
      const float b = static_cast<float>(j) * 0.1f + 0.03f;
      points.push_back({1.63f, a, b});
      points.push_back({a, -1.47f, b});
    }
  }
  map.insert_point_cloud(origin, points);
  return map;
}

std::vector<std::pair<std::uint64_t, float>> leaves(const OccupancyMap& map) {
  std::vector<std::pair<std::uint64_t, float>> out;
  map.for_each_leaf([&](const Node& n) { out.emplace_back(n.code() * 32 + std::uint64_t(n.depth), n.log_odds); });
  return out;
}

TEST(MergeCli, WritesTheLibrarysMerge) {
  const fs::path dir = test::scratch_dir();
  const OccupancyMap a = room({0.0f, 0.0f, 0.0f});
  const OccupancyMap b = room({0.4f, 0.3f, 0.1f});
  const OccupancyMap c = room({-0.3f, 0.2f, 0.0f});
  save_map(a, dir / "a.umb");
  save_map(b, dir / "b.umb");
  save_any_map(c, dir / "c.bt");
  const OccupancyMap c_read = load_any_map(dir / "c.bt");

  const auto merged_by_cli = [&](const std::string& options) {
    const CommandResult r = run("merge " + quoted(dir / "a.umb") + " " + quoted(dir / "b.umb") + " " +
                                quoted(dir / "c.bt") + " -o " + quoted(dir / "abc.umb") + options);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(contains(r.output, "added " + (dir / "b.umb").string())) << r.output;
    return load_map(dir / "abc.umb");
  };
  OccupancyMap expected = a;
  expected.merge(b);
  expected.merge(c_read);
  EXPECT_EQ(leaves(merged_by_cli("")), leaves(expected));

  expected = a;
  expected.merge(b, VoxelOffset{3, -2, 1});
  expected.merge(c_read, VoxelOffset{3, -2, 1});
  EXPECT_EQ(leaves(merged_by_cli(" --offset 3 -2 1")), leaves(expected));

  const Pose turn = Pose::from_translation_quaternion(0.05, 0.0, 0.0, 0.9961946980917455, 0, 0, 0.08715574274765817);
  expected = a;
  expected.merge(b, turn);
  expected.merge(c_read, turn);
  EXPECT_EQ(leaves(merged_by_cli(" --transform 0.05 0 0 0.9961946980917455 0 0 0.08715574274765817")),
            leaves(expected));
}

TEST(MergeCli, PutsAMovingWindowsRunBackTogether) {
  // A run on a map that keeps 1 m around the sensor, what left spilled to
  // run.umbs: `umbra merge run.umbs final.umb` is the library's load_spill
  // plus the final window.
  const fs::path dir = test::scratch_dir();
  OccupancyMap map(0.1);
  MovingWindow window;
  window.half_extent = 1.0;
  window.spill = spill_to_file(dir / "run.umbs");
  map.set_moving_window(window);
  for (int stop = 0; stop < 4; ++stop) {
    const Vec3f origin{2.5f * static_cast<float>(stop), 0.0f, 0.0f};
    std::vector<Vec3f> points;
    for (int i = -8; i <= 8; ++i) {
      for (int j = -8; j <= 8; ++j) {
        const float a = static_cast<float>(i) * 0.1f + 0.03f;
        const float b = static_cast<float>(j) * 0.1f + 0.03f;
        points.push_back(origin + Vec3f{0.83f, a, b});
        points.push_back(origin + Vec3f{a, -0.77f, b});
      }
    }
    map.insert_point_cloud(origin, points);
  }
  save_map(map, dir / "final.umb");
  std::size_t pieces = 0;
  (void)for_each_spill_piece(dir / "run.umbs", [&](OccupancyMap&&) { ++pieces; });
  EXPECT_GE(pieces, 2u);

  const CommandResult r = run("merge " + quoted(dir / "run.umbs") + " " + quoted(dir / "final.umb") + " -o " +
                              quoted(dir / "whole.umb"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  OccupancyMap expected = load_spill(dir / "run.umbs");
  expected.merge(load_map(dir / "final.umb"));
  const OccupancyMap whole = load_map(dir / "whole.umb");
  EXPECT_EQ(leaves(whole), leaves(expected));
  EXPECT_GT(leaves(whole).size(), leaves(load_map(dir / "final.umb")).size());

  // A damaged spill file: exit code 1, the file named, nothing written.
  fs::resize_file(dir / "run.umbs", fs::file_size(dir / "run.umbs") - 5);
  const CommandResult bad = run("merge " + quoted(dir / "run.umbs") + " " + quoted(dir / "final.umb") + " -o " +
                                quoted(dir / "bad.umb"));
  EXPECT_EQ(bad.exit_code, 1) << bad.output;
  EXPECT_TRUE(contains(bad.output, (dir / "run.umbs").string())) << bad.output;
  EXPECT_FALSE(fs::exists(dir / "bad.umb"));
}

TEST(MergeCli, BadInputNamesTheFileOrOptionAndWritesNothing) {
  const fs::path dir = test::scratch_dir();
  save_map(room({0.0f, 0.0f, 0.0f}), dir / "a.umb");
  save_map(room({0.0f, 0.0f, 0.0f}, 0.05), dir / "fine.umb");
  const std::string out = " -o " + quoted(dir / "out.umb");

  const CommandResult grids = run("merge " + quoted(dir / "a.umb") + " " + quoted(dir / "fine.umb") + out);
  EXPECT_EQ(grids.exit_code, 1) << grids.output;
  EXPECT_TRUE(contains(grids.output, (dir / "fine.umb").string() + ": cannot be merged")) << grids.output;
  EXPECT_TRUE(contains(grids.output, "this map 0.1 m, the other 0.05 m")) << grids.output;

  const CommandResult outside = run("merge " + quoted(dir / "a.umb") + " " + quoted(dir / "a.umb") + out +
                                    " --offset 40000 0 0");
  EXPECT_EQ(outside.exit_code, 1) << outside.output;
  EXPECT_TRUE(contains(outside.output, "lands outside this map")) << outside.output;

  const CommandResult one = run("merge " + quoted(dir / "a.umb") + out);
  EXPECT_EQ(one.exit_code, 2) << one.output;
  const CommandResult both = run("merge " + quoted(dir / "a.umb") + " " + quoted(dir / "a.umb") + out +
                                 " --offset 1 0 0 --transform 0 0 0 1 0 0 0");
  EXPECT_EQ(both.exit_code, 2) << both.output;
  const CommandResult zero = run("merge " + quoted(dir / "a.umb") + " " + quoted(dir / "a.umb") + out +
                                 " --transform 0 0 0 0 0 0 0");
  EXPECT_EQ(zero.exit_code, 2) << zero.output;
  EXPECT_TRUE(contains(zero.output, "--transform")) << zero.output;
  EXPECT_FALSE(fs::exists(dir / "out.umb"));
}

}  // namespace
}  // namespace umbra
