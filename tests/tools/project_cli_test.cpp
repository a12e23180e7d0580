// `umbra project`, run as a user would: the PGM and YAML it writes are read
// back here the way map_server reads them (P5 header, first row the highest
// y; occupancy (255 - pixel) / 255 against the YAML's thresholds, trinary
// mode) and compared cell by cell with project_to_grid on the same map
// (itself checked against brute force in tests/query/navigation_grid_test.cpp);
// a second reference is written out here from dense voxel values for one
// band. Bad input: exit code 2 for options, 1 for files, each message naming
// the value or the file, and nothing written.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/cli_commands.hpp"
#include "support/query_oracle.hpp"
#include "support/test_support.hpp"
#include "umbra/io/map_file.hpp"
#include "umbra/query/navigation_grid.hpp"

namespace umbra {
namespace {

namespace fs = std::filesystem;
using test::contains;
using test::quoted;
using test::run;

struct Pgm {
  std::uint32_t width = 0, height = 0;
  std::vector<std::uint8_t> pixels;  // row-major, as stored (first row at the top)
};

/// A binary PGM as map_server's image loader sees it; failures fail the test.
Pgm read_pgm(const fs::path& path) {
  const std::vector<std::uint8_t> bytes = test::read_bytes(path);
  std::size_t at = 0;
  // Header tokens (magic, width, height, maxval), skipping '#' comments, then one whitespace byte.
  auto token = [&] {
    std::string t;
    while (at < bytes.size()) {
      const char c = static_cast<char>(bytes[at]);
      if (c == '#' && t.empty()) {
        while (at < bytes.size() && bytes[at] != '\n') ++at;
      } else if (std::isspace(static_cast<unsigned char>(c))) {
        if (!t.empty()) break;
        ++at;
      } else {
        t += c;
        ++at;
      }
    }
    return t;
  };
  Pgm pgm;
  EXPECT_EQ(token(), "P5");
  pgm.width = static_cast<std::uint32_t>(std::stoul(token()));
  pgm.height = static_cast<std::uint32_t>(std::stoul(token()));
  EXPECT_EQ(token(), "255");
  ++at;  // the single whitespace byte before the pixels
  EXPECT_EQ(bytes.size() - at, std::size_t{pgm.width} * pgm.height) << "pixel bytes after the header";
  pgm.pixels.assign(bytes.begin() + static_cast<std::ptrdiff_t>(std::min(at, bytes.size())), bytes.end());
  return pgm;
}

/// "key: value" lines of a flat YAML file.
std::map<std::string, std::string> read_yaml(const fs::path& path) {
  const std::vector<std::uint8_t> bytes = test::read_bytes(path);
  std::istringstream in(std::string(bytes.begin(), bytes.end()));
  std::map<std::string, std::string> fields;
  for (std::string line; std::getline(in, line);) {
    const std::size_t colon = line.find(": ");
    if (colon != std::string::npos) fields[line.substr(0, colon)] = line.substr(colon + 2);
  }
  return fields;
}

/// The grid map_server would build from the two files (trinary mode, negate 0).
NavigationGrid load_like_map_server(const fs::path& yaml_path) {
  auto fields = read_yaml(yaml_path);
  EXPECT_EQ(fields["mode"], "trinary");
  EXPECT_EQ(fields["negate"], "0");
  const double occupied_thresh = std::stod(fields["occupied_thresh"]);
  const double free_thresh = std::stod(fields["free_thresh"]);
  std::string image = fields["image"];
  if (image.size() >= 2 && image.front() == '"') image = image.substr(1, image.size() - 2);
  const Pgm pgm = read_pgm(yaml_path.parent_path() / image);
  NavigationGrid grid;
  grid.resolution = std::stod(fields["resolution"]);
  double yaw = -1.0;
  EXPECT_EQ(std::sscanf(fields["origin"].c_str(), "[%lf, %lf, %lf]", &grid.origin_x, &grid.origin_y, &yaw), 3)
      << fields["origin"];
  EXPECT_EQ(yaw, 0.0);
  grid.width = pgm.width;
  grid.height = pgm.height;
  for (std::uint32_t y = 0; y < pgm.height; ++y) {
    for (std::uint32_t x = 0; x < pgm.width; ++x) {
      const std::uint8_t pixel = pgm.pixels[std::size_t{pgm.height - 1 - y} * pgm.width + x];
      const double occupancy = (255.0 - pixel) / 255.0;
      grid.cells.push_back(occupancy > occupied_thresh ? GridCell::occupied
                           : occupancy < free_thresh   ? GridCell::free
                                                       : GridCell::unknown);
    }
  }
  return grid;
}

/// A random map (0.125 m voxels, 64^3) saved as .umb.
fs::path saved_random_map(const fs::path& dir, OccupancyMap* keep = nullptr) {
  test::RandomMapSpec spec;
  spec.depth_levels = 6;
  spec.resolution = 0.125;
  spec.seed = 25;
  const OccupancyMap map = test::random_map(spec);
  const fs::path path = dir / "random.umb";
  save_map(map, path);
  if (keep) *keep = map;
  return path;
}

TEST(ProjectCli, WritesFilesMapServerReadsBackAsTheProjection) {
  const fs::path dir = test::scratch_dir();
  OccupancyMap map(0.125, 6);
  const fs::path input = saved_random_map(dir, &map);
  for (const auto& [rule, depth] : {std::pair{ProjectionRule::all_known, 0}, std::pair{ProjectionRule::any_free, 1}}) {
    const fs::path pgm = dir / ("grid " + std::to_string(depth) + ".pgm");  // a space in the name
    const test::CommandResult r = run("project " + quoted(input) + " -o " + quoted(pgm) +
                                      " --z-min -0.3 --z-max 0.55 --depth " + std::to_string(depth) + " --rule " +
                                      std::string(to_string(rule)));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(contains(r.output, "wrote ")) << r.output;
    const fs::path yaml = dir / ("grid " + std::to_string(depth) + ".yaml");
    ASSERT_TRUE(fs::exists(yaml));
    const NavigationGrid want = project_to_grid(map, {-0.3, 0.55, depth, rule});
    ASSERT_FALSE(want.empty());
    const NavigationGrid got = load_like_map_server(yaml);
    EXPECT_EQ(got.resolution, want.resolution);
    EXPECT_NEAR(got.origin_x, want.origin_x, 1e-9);
    EXPECT_NEAR(got.origin_y, want.origin_y, 1e-9);
    ASSERT_EQ(got.width, want.width);
    ASSERT_EQ(got.height, want.height);
    EXPECT_TRUE(got.cells == want.cells) << "the files do not read back as the projection";
    int kinds[3] = {0, 0, 0};
    for (const GridCell c : got.cells) ++kinds[c == GridCell::occupied ? 0 : c == GridCell::free ? 1 : 2];
    EXPECT_GT(kinds[0], 0);
    EXPECT_GT(kinds[1], 0);
    EXPECT_GT(kinds[2], 0);
  }
  // Only the finished files remain (no temporary files beside them).
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 5u);
}

TEST(ProjectCli, OneVoxelRowAgainstDenseValues) {
  // A band inside one voxel row: the picture's pixels are that row's voxels,
  // occupied 0, free 254, unknown 205, the first row the highest y.
  const fs::path dir = test::scratch_dir();
  OccupancyMap map(0.125, 6);
  const fs::path input = saved_random_map(dir, &map);
  const test::DenseValues dense(map);
  const LogOddsThresholds t = LogOddsThresholds::from(map.thresholds());
  const test::CommandResult r = run("project " + quoted(input) + " -o " + quoted(dir / "row.pgm") +
                                    " --z-min 0.26 --z-max 0.3");  // row 0.25 .. 0.375: key 34
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // The extent: the voxel columns whose row-34 voxel is known.
  std::uint32_t x0 = 64, y0 = 64, x1 = 0, y1 = 0;
  for (std::uint32_t y = 0; y < 64; ++y) {
    for (std::uint32_t x = 0; x < 64; ++x) {
      if (!t.is_unknown(dense.at({x, y, 34}))) {
        x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
      }
    }
  }
  ASSERT_LE(x0, x1);
  const Pgm pgm = read_pgm(dir / "row.pgm");
  ASSERT_EQ(pgm.width, x1 - x0 + 1);
  ASSERT_EQ(pgm.height, y1 - y0 + 1);
  for (std::uint32_t y = y0; y <= y1; ++y) {
    for (std::uint32_t x = x0; x <= x1; ++x) {
      const float v = dense.at({x, y, 34});
      const std::uint8_t want = t.is_occupied(v) ? 0 : t.is_free(v) ? 254 : 205;
      ASSERT_EQ(pgm.pixels[std::size_t{y1 - y} * pgm.width + (x - x0)], want) << "voxel column " << x << ", " << y;
    }
  }
  const auto yaml = read_yaml(dir / "row.yaml");
  double origin_x = 0, origin_y = 0, yaw = 1;
  ASSERT_EQ(std::sscanf(yaml.at("origin").c_str(), "[%lf, %lf, %lf]", &origin_x, &origin_y, &yaw), 3);
  EXPECT_EQ(origin_x, (int(x0) - 32) * 0.125);  // the lower-left corner of the lowest known column
  EXPECT_EQ(origin_y, (int(y0) - 32) * 0.125);
  EXPECT_EQ(yaml.at("resolution"), "0.125");
  EXPECT_EQ(yaml.at("image"), "\"row.pgm\"");
}

TEST(ProjectCli, BadArgumentsAreNamedAndWriteNothing) {
  const fs::path dir = test::scratch_dir();
  const fs::path input = saved_random_map(dir);
  const std::string out = " -o " + quoted(dir / "out.pgm");
  struct Case {
    std::string arguments;
    int exit_code;
    std::string message;
  };
  const std::vector<Case> cases = {
      {quoted(input) + out + " --z-min 1 --z-max 1", 2, "z_min must be below z_max, got z_min 1 and z_max 1"},
      {quoted(input) + out + " --z-min 1 --z-max 0.5", 2, "z_min must be below z_max, got z_min 1 and z_max 0.5"},
      {quoted(input) + out + " --z-min 0 --z-max 1 --rule most_free", 2,
       "unknown projection rule 'most_free' (the rules: all_known, any_free)"},
      {quoted(input) + out + " --z-min nan --z-max 1", 2, "--z-min"},
      {quoted(input) + out + " --z-max 1", 2, "--z-min is required"},
      {quoted(input) + " -o " + quoted(dir / "out.png") + " --z-min 0 --z-max 1", 2,
       "a navigation grid's picture must be a .pgm file, got"},
      {quoted(input) + " -o " + quoted(dir / "missing" / "out.pgm") + " --z-min 0 --z-max 1", 1, "missing/out.pgm"},
      {quoted(dir / "absent.umb") + out + " --z-min 0 --z-max 1", 1, "absent.umb"},
      {quoted(input) + out + " --z-min 0 --z-max 1 --depth 7", 2, "--depth 7 is outside [0, 6]"},
      {quoted(input) + out + " --z-min 5 --z-max 6", 2, "lies outside the map, which spans z from -4 to 4"},
  };
  for (const Case& c : cases) {
    const test::CommandResult r = run("project " + c.arguments);
    EXPECT_EQ(r.exit_code, c.exit_code) << c.arguments << "\n" << r.output;
    EXPECT_TRUE(contains(r.output, c.message)) << c.arguments << "\n" << r.output;
  }
  // Nothing known in the band: an error naming the map and the heights.
  OccupancyMap small(0.125, 6);
  small.update_hit({0.0, 0.0, 0.0});
  save_map(small, dir / "small.umb");
  const test::CommandResult r = run("project " + quoted(dir / "small.umb") + out + " --z-min 1 --z-max 2");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_TRUE(contains(r.output, "small.umb has no known voxel between z 1 and 2 m")) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out.pgm"));
  EXPECT_FALSE(fs::exists(dir / "out.yaml"));
}

// The README's example (section "Navigation grid") on the shared geb079.bt prints what the README quotes.
TEST(ProjectCli, ReadmeExampleOnGeb079PrintsWhatTheReadmeQuotes) {
  const auto geb079 = test::shared_data("octomap/geb079.bt");
  if (!geb079) GTEST_SKIP() << "../shared/data/octomap/geb079.bt is not present";
  const fs::path dir = test::scratch_dir();
  const test::CommandResult r =
      run("project " + quoted(*geb079) + " -o " + quoted(dir / "geb079.pgm") + " --z-min 0.1 --z-max 1.8 --rule any_free");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string first_line = r.output.substr(0, r.output.find('\n'));
  const std::vector<std::uint8_t> readme = test::read_bytes(test::source_dir() / "README.md");
  EXPECT_TRUE(contains(std::string(readme.begin(), readme.end()), "# " + first_line))
      << "README does not quote the output line: " << first_line;
}

}  // namespace
}  // namespace umbra
