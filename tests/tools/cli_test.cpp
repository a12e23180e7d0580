// The `umbra` program end to end: demo, build, info, their errors, and the
// README's quick-start demo command.
#include <array>
#include <cstdio>
#include <fstream>
#include <regex>
#include <tuple>
#include <sstream>

#include <gtest/gtest.h>

#include "support/cli_commands.hpp"
#include "support/test_support.hpp"
#include "umbra/io/map_file.hpp"
#include "umbra/io/scan_graph.hpp"
#include "umbra/map/decay.hpp"
#include "umbra/map/map_statistics.hpp"
#include "umbra/sim/moving_scene.hpp"

namespace umbra {
namespace {

using test::CommandResult;
CommandResult run(const std::string& command) { return test::run_command(command); }

using test::cli;
using test::quoted;

/// A small room seen from its centre: 6 walls sampled on a grid.
std::vector<Vec3f> room_scan() {
  std::vector<Vec3f> points;
  for (int i = -20; i <= 20; ++i) {
    for (int j = -20; j <= 20; ++j) {
      const float a = static_cast<float>(i) * 0.1f;
      const float b = static_cast<float>(j) * 0.1f;
      points.push_back({2.05f, a, b});
      points.push_back({-2.05f, a, b});
      points.push_back({a, 2.05f, b});
      points.push_back({a, -2.05f, b});
      points.push_back({a, b, 2.05f});
      points.push_back({a, b, -2.05f});
    }
  }
  return points;
}

void write_xyz(const std::filesystem::path& path, const std::vector<Vec3f>& points) {
  std::ofstream out(path);
  out.precision(9);
  for (const Vec3f& p : points) out << p.x << ' ' << p.y << ' ' << p.z << '\n';
}

TEST(Cli, DemoWritesAMapAndAPicture) {
  const auto dir = test::scratch_dir();
  const CommandResult demo = run(cli() + " demo -o " + quoted(dir / "out"));
  ASSERT_EQ(demo.exit_code, 0) << demo.output;
  EXPECT_NE(demo.output.find("occupied voxels"), std::string::npos) << demo.output;
  ASSERT_TRUE(std::filesystem::exists(dir / "out" / "demo.png"));
  const OccupancyMap map = load_map(dir / "out" / "demo.umb");
  const MapStatistics stats = compute_statistics(map);
  EXPECT_GT(stats.occupied_voxels, 10000u);
  EXPECT_GT(stats.free_voxels, 100000u);
}

TEST(Cli, BuildFromXyzMatchesTheLibrary) {
  const auto dir = test::scratch_dir();
  const std::vector<Vec3f> points = room_scan();
  write_xyz(dir / "room.xyz", points);
  const CommandResult build = run(cli() + " build " + quoted(dir / "room.xyz") + " -o " + quoted(dir / "room.umb") +
                        " --res 0.1 --integrator discrete --origin 0.05,0.05,0.05");
  ASSERT_EQ(build.exit_code, 0) << build.output;
  EXPECT_NE(build.output.find("insert ms"), std::string::npos) << build.output;

  OccupancyMap expected(0.1);
  InsertOptions options;
  options.integrator = IntegratorKind::discrete;
  expected.insert_point_cloud({0.05f, 0.05f, 0.05f}, points, options);
  const OccupancyMap built = load_map(dir / "room.umb");
  std::vector<std::pair<std::uint64_t, float>> a;
  std::vector<std::pair<std::uint64_t, float>> b;
  expected.for_each_leaf([&](const Node& l) { a.emplace_back(morton::encode(l.key) * 32 + l.depth, l.log_odds); });
  built.for_each_leaf([&](const Node& l) { b.emplace_back(morton::encode(l.key) * 32 + l.depth, l.log_odds); });
  EXPECT_EQ(a, b);
}

TEST(Cli, BuildFromAScanGraphAndInfoAsJson) {
  const auto dir = test::scratch_dir();
  Scan first;
  first.origin = {0.0f, 0.0f, 0.0f};
  first.points = room_scan();
  Scan second = first;
  second.origin = {0.5f, 0.0f, 0.0f};
  write_scan_graph(dir / "two.graph", {first, second});
  const CommandResult build = run(cli() + " build " + quoted(dir / "two.graph") + " -o " + quoted(dir / "two.umb") + " --res 0.05");
  ASSERT_EQ(build.exit_code, 0) << build.output;
  const CommandResult info = run(cli() + " info --json " + quoted(dir / "two.umb"));
  ASSERT_EQ(info.exit_code, 0) << info.output;
  for (const char* key : {"\"resolution\": 0.05", "\"depth_levels\": 16", "\"nodes\"", "\"memory_bytes\"",
                          "\"occupied_voxels\"", "\"free_voxels\"", "\"occupied_volume_m3\"", "\"free_volume_m3\""}) {
    EXPECT_NE(info.output.find(key), std::string::npos) << key << " missing in " << info.output;
  }
  const MapStatistics stats = compute_statistics(load_map(dir / "two.umb"));
  std::smatch match;
  ASSERT_TRUE(std::regex_search(info.output, match, std::regex("\"occupied_voxels\": ([0-9]+)")));
  EXPECT_EQ(std::stoull(match[1]), stats.occupied_voxels);
  EXPECT_GT(stats.occupied_voxels, 0u);
  const CommandResult text = run(cli() + " info " + quoted(dir / "two.umb"));
  EXPECT_EQ(text.exit_code, 0);
  EXPECT_NE(text.output.find("known space"), std::string::npos) << text.output;
}

/// Every leaf of a map as (code * 32 + depth, log-odds), for comparing maps.
std::vector<std::pair<std::uint64_t, float>> leaves_of(const OccupancyMap& map) {
  std::vector<std::pair<std::uint64_t, float>> leaves;
  map.for_each_leaf([&](const Node& l) { leaves.emplace_back(morton::encode(l.key) * 32 + l.depth, l.log_odds); });
  return leaves;
}

TEST(Cli, BuildWithDecayMatchesTheLibrary) {
  const auto dir = test::scratch_dir();
  // The whole room, then 2 s later only its +x wall from elsewhere: the rest decays for 2 s.
  Scan first;
  first.origin = {0.0f, 0.0f, 0.0f};
  first.points = room_scan();
  Scan second;
  second.origin = {0.5f, 0.0f, 0.0f};
  for (const Vec3f& p : first.points) {
    if (p.x > 2.0f) second.points.push_back(p);
  }
  write_scan_graph(dir / "two.graph", {first, second});
  const std::string build = cli() + " build " + quoted(dir / "two.graph") + " --res 0.1 --integrator discrete";
  const CommandResult decayed = run(build + " -o " + quoted(dir / "decayed.umb") +
                                    " --decay-occupied 0.5 --decay-free 0.25 --scan-period 2");
  ASSERT_EQ(decayed.exit_code, 0) << decayed.output;
  EXPECT_NE(decayed.output.find("decay toward unknown: 0.5"), std::string::npos) << decayed.output;

  OccupancyMap expected(0.1);
  DecayRates rates;
  rates.occupied_per_second = 0.5;
  rates.free_per_second = 0.25;
  expected.set_decay(rates);
  InsertOptions options;
  options.integrator = IntegratorKind::discrete;
  options.stamp = 0.0;
  expected.insert_point_cloud(first.origin, first.points, options);
  options.stamp = 2.0;
  expected.insert_point_cloud(second.origin, second.points, options);
  EXPECT_EQ(leaves_of(load_map(dir / "decayed.umb")), leaves_of(expected));

  // Without decay the map differs (the options did something).
  ASSERT_EQ(run(build + " -o " + quoted(dir / "kept.umb")).exit_code, 0);
  EXPECT_NE(leaves_of(load_map(dir / "kept.umb")), leaves_of(expected));

  // A ScanGraph carries no times: decay without --scan-period is a usage error naming the input.
  const CommandResult untimed = run(build + " -o " + quoted(dir / "no.umb") + " --decay-free 0.25");
  EXPECT_EQ(untimed.exit_code, 2) << untimed.output;
  EXPECT_NE(untimed.output.find("two.graph (graph) does not carry it"), std::string::npos) << untimed.output;
  EXPECT_NE(untimed.output.find("--scan-period"), std::string::npos) << untimed.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "no.umb"));
}

TEST(Cli, MovingDemoForgetsWhatItNoLongerSees) {
  const auto dir = test::scratch_dir();
  const CommandResult demo = run(cli() + " demo --moving -o " + quoted(dir));
  ASSERT_EQ(demo.exit_code, 0) << demo.output;
  for (const char* name : {"moving-t03", "moving-t07", "moving-t14"}) {
    EXPECT_TRUE(std::filesystem::exists(dir / (std::string(name) + ".png"))) << name;
  }
  const OccupancyMap early = load_map(dir / "moving-t03.umb");
  const OccupancyMap middle = load_map(dir / "moving-t07.umb");
  const OccupancyMap late = load_map(dir / "moving-t14.umb");
  // The corridor's west end, behind the sensor once it is in the meeting
  // room (from 9 s): seen free at 3 s, unknown again at 14 s.
  const Vec3d west{2.0, 6.0, 1.2};
  EXPECT_EQ(early.state(west), OccupancyState::free);
  EXPECT_EQ(late.state(west), OccupancyState::unknown);
  // A wall beside the corridor, seen at 3 s, out of view from 7 s on: an
  // obstacle faded to unknown (occupied log-odds <= 3.5 at 1.0 a second).
  const Vec3d wall{6.0, 5.025, 1.225};
  EXPECT_EQ(early.state(wall), OccupancyState::occupied);
  EXPECT_EQ(middle.state(wall), OccupancyState::unknown);
  EXPECT_EQ(late.state(wall), OccupancyState::unknown);
  // The sliding door's west edge: occupied while closed (3 s), seen free
  // once it has slid open (7 s): re-observed, not merely forgotten.
  const sim::MovingScene scene = sim::make_demo_moving_scene();
  const Vec3d door{9.575, 6.925, 1.225};
  ASSERT_TRUE(scene.at(3.0).is_inside_solid(door));
  ASSERT_FALSE(scene.at(7.0).is_inside_solid(door));
  EXPECT_EQ(early.state(door), OccupancyState::occupied);
  EXPECT_EQ(middle.state(door), OccupancyState::free);
}

TEST(Cli, BadInputGivesAClearErrorAndNoMap) {
  const auto dir = test::scratch_dir();
  {
    std::ofstream bad(dir / "bad.xyz");
    bad << "1 2 3\n4 five 6\n";
  }
  const CommandResult malformed = run(cli() + " build " + quoted(dir / "bad.xyz") + " -o " + quoted(dir / "bad.umb"));
  EXPECT_EQ(malformed.exit_code, 1);
  EXPECT_NE(malformed.output.find("bad.xyz:2"), std::string::npos) << malformed.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.umb"));

  const CommandResult missing = run(cli() + " build " + quoted(dir / "nothing.xyz") + " -o " + quoted(dir / "x.umb"));
  EXPECT_EQ(missing.exit_code, 1) << missing.output;  // an input failure, not bad usage
  EXPECT_NE(missing.output.find("nothing.xyz"), std::string::npos) << missing.output;

  write_xyz(dir / "ok.xyz", room_scan());
  const CommandResult origin = run(cli() + " build " + quoted(dir / "ok.xyz") + " -o " + quoted(dir / "ok.umb") + " --origin 1,2");
  EXPECT_EQ(origin.exit_code, 2);
  EXPECT_NE(origin.output.find("--origin"), std::string::npos) << origin.output;

  const CommandResult format = run(cli() + " build " + quoted(dir / "ok.xyz") + " -o " + quoted(dir / "ok.map"));
  EXPECT_EQ(format.exit_code, 2);
  EXPECT_NE(format.output.find("ok.map"), std::string::npos) << format.output;

  const CommandResult outside = run(cli() + " build " + quoted(dir / "ok.xyz") + " -o " + quoted(dir / "small.umb") +
                          " --depth-levels 4 --res 0.1");
  EXPECT_EQ(outside.exit_code, 0) << outside.output;
  EXPECT_NE(outside.output.find("outside the map"), std::string::npos) << outside.output;

  {
    std::ofstream junk(dir / "junk.umb");
    junk << "not a map";
  }
  const CommandResult info = run(cli() + " info " + quoted(dir / "junk.umb"));
  EXPECT_EQ(info.exit_code, 1);
  EXPECT_NE(info.output.find("junk.umb"), std::string::npos) << info.output;
}

TEST(Cli, BuildWithTheFastIntegratorThreadsBoxAndColor) {
  const auto dir = test::scratch_dir();
  const std::vector<Vec3f> points = room_scan();
  {
    std::ofstream out(dir / "room.xyz");
    out.precision(9);
    for (std::size_t i = 0; i < points.size(); ++i) {
      out << points[i].x << ' ' << points[i].y << ' ' << points[i].z << ' ' << (i % 256) << " 10 200\n";
    }
  }
  const CommandResult fast = run(cli() + " build " + quoted(dir / "room.xyz") + " -o " + quoted(dir / "fast.umb") +
                                 " --res 0.05 --integrator fast --clear-depth 2 --fine-steps 1 --threads 2 --color");
  ASSERT_EQ(fast.exit_code, 0) << fast.output;
  EXPECT_NE(fast.output.find("clear depth 2"), std::string::npos) << fast.output;

  MapConfig config;
  config.resolution = 0.05;
  config.color = true;
  OccupancyMap expected(config);
  InsertOptions options;
  options.integrator = IntegratorKind::fast;
  options.clear_depth = 2;
  options.fine_steps = 1;
  std::vector<Rgb> colors;
  for (std::size_t i = 0; i < points.size(); ++i) colors.push_back({static_cast<std::uint8_t>(i % 256), 10, 200});
  expected.insert_point_cloud({0, 0, 0}, points, colors, options);
  const OccupancyMap built = load_map(dir / "fast.umb");
  ASSERT_TRUE(built.has_color());
  std::vector<std::tuple<std::uint64_t, float, std::optional<Rgb>>> a;
  std::vector<std::tuple<std::uint64_t, float, std::optional<Rgb>>> b;
  expected.for_each_leaf([&](const Node& l) { a.emplace_back(morton::encode(l.key) * 32 + l.depth, l.log_odds, l.color); });
  built.for_each_leaf([&](const Node& l) { b.emplace_back(morton::encode(l.key) * 32 + l.depth, l.log_odds, l.color); });
  EXPECT_TRUE(a == b);

  const CommandResult boxed = run(cli() + " build " + quoted(dir / "room.xyz") + " -o " + quoted(dir / "box.umb") +
                                  " --res 0.05 --bbox -1,-1,-1,1,1,1");
  ASSERT_EQ(boxed.exit_code, 0) << boxed.output;
  const MapStatistics stats = compute_statistics(load_map(dir / "box.umb"));
  ASSERT_TRUE(stats.has_known_space);
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_GE(stats.known_min[axis], -1.05);
    EXPECT_LE(stats.known_max[axis], 1.05);
  }
  EXPECT_EQ(stats.occupied_voxels, 0u) << "every wall lies outside the box";
  EXPECT_GT(stats.free_voxels, 1000u) << "rays to the walls still clear the box";

  const CommandResult bad = run(cli() + " build " + quoted(dir / "room.xyz") + " -o " + quoted(dir / "bad.umb") +
                                " --bbox 1,2,3,4,5");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.output.find("--bbox"), std::string::npos) << bad.output;
}

/// The README's quick start is exactly two commands; the first runs the demo.
std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// The fenced block that follows `marker` in the README (its first fence line excluded).
std::string readme_block_after(const std::string& readme, const std::string& marker) {
  const auto at = readme.find(marker);
  if (at == std::string::npos) return {};
  const auto open = readme.find("```", at);
  const auto body = readme.find('\n', open) + 1;
  const auto close = readme.find("```", body);
  return readme.substr(body, close - body);
}

TEST(Readme, QuotedExamplesAreTheExampleFiles) {
  const std::string readme = read_text(test::source_dir() / "README.md");
  for (const std::string example : {"query_map.cpp", "readers_while_inserting.cpp"}) {
    const std::string quoted_text = readme_block_after(readme, "whole of `examples/" + example + "`");
    ASSERT_FALSE(quoted_text.empty()) << "README does not quote examples/" << example;
    EXPECT_EQ(quoted_text, read_text(test::source_dir() / "examples" / example))
        << "README's quote of examples/" << example << " differs from the file (the file is built and run)";
  }
}

TEST(Readme, QueryCommandsRunAsWritten) {
  const std::string readme = read_text(test::source_dir() / "README.md");
  const std::string block = readme_block_after(readme, "The same from the command line");
  ASSERT_NE(block.find("umbra query"), std::string::npos);
  // The commands name build/tools/umbra: run them where build/ is this build.
  const auto dir = test::scratch_dir();
  std::filesystem::create_directory_symlink(UMBRA_BUILD_DIR, dir / "build");
  std::istringstream lines(block);
  int commands = 0;
  for (std::string line; std::getline(lines, line);) {
    const std::string command = line.substr(0, line.find("   #"));
    if (command.empty()) continue;
    const CommandResult r = run("cd " + quoted(dir) + " && " + command);
    EXPECT_EQ(r.exit_code, 0) << command << "\n" << r.output;
    ++commands;
  }
  EXPECT_GE(commands, 5);
}

TEST(Readme, QuickStartDemoCommandWorks) {
  std::ifstream readme(test::source_dir() / "README.md");
  ASSERT_TRUE(readme) << "README.md is missing";
  std::stringstream text;
  text << readme.rdbuf();
  const std::string content = text.str();
  const auto start = content.find("## Quick start");
  ASSERT_NE(start, std::string::npos) << "README needs a '## Quick start' section";
  const auto block = content.find("```", start);
  const auto block_end = content.find("```", block + 3);
  ASSERT_NE(block_end, std::string::npos);
  std::vector<std::string> commands;
  std::istringstream lines(content.substr(block + 3, block_end - block - 3));
  std::string line;
  while (std::getline(lines, line)) {
    if (line.empty() || line == "sh" || line == "bash") continue;
    std::string command = line.substr(0, line.find('#'));
    command.erase(command.find_last_not_of(' ') + 1);
    commands.push_back(command);
  }
  ASSERT_EQ(commands.size(), 2u) << "the quick start is exactly two commands";
  EXPECT_EQ(commands[0], "./scripts/demo.sh");
  EXPECT_EQ(commands[1], "./scripts/test.sh");
  // CI runs the second command exactly.
  std::ifstream ci(test::source_dir() / ".ci" / "run");
  std::stringstream ci_text;
  ci_text << ci.rdbuf();
  EXPECT_NE(ci_text.str().find("\n" + commands[1] + "\n"), std::string::npos) << ".ci/run must call " << commands[1];

  const auto dir = test::scratch_dir();
  const CommandResult demo = run("cd " + quoted(test::source_dir()) + " && UMBRA_BUILD_DIR=" + quoted(UMBRA_BUILD_DIR) +
                       " UMBRA_DEMO_OUTPUT=" + quoted(dir) + " " + commands[0]);
  ASSERT_EQ(demo.exit_code, 0) << demo.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "demo.umb"));
  EXPECT_TRUE(std::filesystem::exists(dir / "demo.png"));
}

}  // namespace
}  // namespace umbra
