// `umbra crop`, `umbra compare` and `umbra export` (issue 23, point 9), run
// as a user would. References: crop and compare give what the library's
// crop_map and compare_maps give (each checked voxel by voxel against brute
// force in tests/map/), plus a voxel-by-voxel check here of what a cropped
// file holds; export's PLY files are read back with umbra's own PLY reader
// and compared with the occupied voxels found one key at a time, the
// mesh's triangles checked to face outwards. Bad input: exit code 2 for
// options, 1 for files, each message naming the value or the file.
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "support/cli_commands.hpp"
#include "support/test_support.hpp"
#include "umbra/io/map_file.hpp"
#include "umbra/io/map_formats.hpp"
#include "umbra/io/ply_file.hpp"
#include "umbra/map/map_agreement.hpp"
#include "umbra/map/map_crop.hpp"
#include "umbra/map/map_statistics.hpp"

namespace umbra {
namespace {

namespace fs = std::filesystem;
using test::CommandResult;

using test::cli;
using test::quoted;
using test::contains;
using test::run;

/// A colored room (4 m, 10 cm voxels) seen from two places, with a pruned
/// occupied 2 x 2 x 2 block (one depth-1 node) and a voxel without color.
OccupancyMap room_map(IntegratorKind integrator = IntegratorKind::simple) {
  MapConfig config;
  config.resolution = 0.1;
  config.color = true;
  OccupancyMap map(config);
  std::vector<Vec3f> points;
  std::vector<Rgb> colors;
  for (int i = -19; i <= 19; ++i) {
    for (int j = -19; j <= 19; ++j) {
      const float a = static_cast<float>(i) * 0.1f + 0.03f;
      const float b = static_cast<float>(j) * 0.1f + 0.03f;
      for (const Vec3f p : {Vec3f{2.03f, a, b}, Vec3f{-1.97f, a, b}, Vec3f{a, 2.03f, b}, Vec3f{a, -1.97f, b},
                            Vec3f{a, b, 1.53f}}) {
        points.push_back(p);
        colors.push_back({static_cast<std::uint8_t>(100 + i), static_cast<std::uint8_t>(100 + j), 7});
      }
    }
  }
  InsertOptions options;
  options.integrator = integrator;
  map.insert_point_cloud({0.0f, 0.0f, 0.0f}, points, colors, options);
  map.insert_point_cloud({0.5f, 0.3f, 0.2f}, points, colors, options);
  const float high = map.sensor_model().clamp_max_log_odds();
  // The block: the depth-1 node at keys (k, k, k) with k even, all 8 voxels at the clamping maximum.
  const Key base = map.grid().key({-1.05, -1.05, -1.05});
  const Key even{base.x & ~1u, base.y & ~1u, base.z & ~1u};
  for (unsigned slot = 0; slot < 8; ++slot) {
    map.set_log_odds(Key{even.x + (slot & 1u), even.y + ((slot >> 1) & 1u), even.z + ((slot >> 2) & 1u)}, high);
  }
  return map;
}

/// Every finest key in the block of keys around the known space.
template <typename Visit>
void for_each_key_near_known_space(const OccupancyMap& map, Visit&& visit) {
  const MapStatistics stats = compute_statistics(map);
  const Key lo = map.grid().key(stats.known_min + Vec3d{0.01, 0.01, 0.01});
  const Key hi = map.grid().key(stats.known_max - Vec3d{0.01, 0.01, 0.01});
  for (std::uint32_t z = lo.z; z <= hi.z; ++z) {
    for (std::uint32_t y = lo.y; y <= hi.y; ++y) {
      for (std::uint32_t x = lo.x; x <= hi.x; ++x) visit(Key{x, y, z});
    }
  }
}

std::vector<std::pair<std::uint64_t, float>> leaves(const OccupancyMap& map) {
  std::vector<std::pair<std::uint64_t, float>> out;
  map.for_each_leaf([&](const Node& n) { out.emplace_back(n.code() * 32 + static_cast<std::uint64_t>(n.depth), n.log_odds); });
  return out;
}

std::vector<std::string> temporaries_in(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (contains(entry.path().filename().string(), ".tmp-")) names.push_back(entry.path().filename().string());
  }
  return names;
}

// --- crop --------------------------------------------------------------------------------

TEST(CropCli, KeepsTheVoxelsInTheBoxAndNothingElse) {
  const fs::path dir = test::scratch_dir();
  const OccupancyMap map = room_map();
  save_map(map, dir / "room.umb");
  const std::string box = "-1.23,-0.5,-1.1,0.71,2.5,0.4";
  const CommandResult crop = run("crop " + quoted(dir / "room.umb") + " -o " + quoted(dir / "cut.umb") + " --bbox " + box);
  ASSERT_EQ(crop.exit_code, 0) << crop.output;
  EXPECT_TRUE(contains(crop.output, "kept the voxels from (-1.3, -0.5, -1.1) to (0.8, 2.6, 0.5) m")) << crop.output;
  const OccupancyMap cut = load_map(dir / "cut.umb");
  const VoxelBox keep = voxel_box(map.grid(), Aabb{{-1.23, -0.5, -1.1}, {0.71, 2.5, 0.4}});
  // Voxel by voxel: the source's value and color inside, unknown outside.
  std::size_t kept = 0;
  for_each_key_near_known_space(map, [&](Key key) {
    const Node before = map.node(key);
    const Node after = cut.node(key);
    if (keep.contains(key)) {
      ASSERT_EQ(after.log_odds, before.log_odds);
      ASSERT_EQ(after.color, before.color);
      kept += before.state == OccupancyState::occupied ? 1 : 0;
    } else {
      ASSERT_EQ(after.state, OccupancyState::unknown);
    }
  });
  EXPECT_GT(kept, 100u);
  // The library's crop, node for node.
  EXPECT_EQ(leaves(cut), leaves(crop_map(map, keep)));
  EXPECT_TRUE(temporaries_in(dir).empty());
}

TEST(CropCli, ReadsAndWritesOctoMapFiles) {
  const fs::path dir = test::scratch_dir();
  const OccupancyMap map = room_map();
  save_map(map, dir / "room.umb");
  ASSERT_EQ(run("convert " + quoted(dir / "room.umb") + " " + quoted(dir / "room.ot")).exit_code, 0);
  const std::string box = " --bbox -1,-1,-1,1,1,1";
  ASSERT_EQ(run("crop " + quoted(dir / "room.umb") + " -o " + quoted(dir / "cut.umb") + box).exit_code, 0);
  // .ot in, .ot out: the same voxels as the .umb crop (.ot keeps every value and color).
  const CommandResult ot = run("crop " + quoted(dir / "room.ot") + " -o " + quoted(dir / "cut.ot") + box);
  ASSERT_EQ(ot.exit_code, 0) << ot.output;
  EXPECT_EQ(leaves(load_any_map(dir / "cut.ot")), leaves(load_map(dir / "cut.umb")));
  // .bt out: what convert makes of the cropped map, byte for byte, with the note on what .bt drops.
  const CommandResult bt = run("crop " + quoted(dir / "room.umb") + " -o " + quoted(dir / "cut.bt") + box);
  ASSERT_EQ(bt.exit_code, 0) << bt.output;
  EXPECT_TRUE(contains(bt.output, "note: .bt keeps only free / occupied")) << bt.output;
  ASSERT_EQ(run("convert " + quoted(dir / "cut.umb") + " " + quoted(dir / "converted.bt")).exit_code, 0);
  EXPECT_EQ(test::read_bytes(dir / "cut.bt"), test::read_bytes(dir / "converted.bt"));
}

TEST(CropCli, BadInputIsNamed) {
  const fs::path dir = test::scratch_dir();
  save_map(room_map(), dir / "room.umb");
  save_map(OccupancyMap(0.1, 18), dir / "deep.umb");
  const std::string in = "crop " + quoted(dir / "room.umb") + " -o " + quoted(dir / "out.umb");
  struct Case {
    std::string arguments;
    int exit_code;
    std::string words;
  };
  const std::vector<Case> cases = {
      {in + " --bbox 1,2,3", 2, "--bbox: expects 6 numbers separated by commas, got '1,2,3'"},
      {in + " --bbox 1,2,3,0,5,6", 2, "with each min <= its max, got '1,2,3,0,5,6'"},
      {in + " --bbox 0,0,0,1,1,nan", 2, "finite numbers"},
      {in, 2, "--bbox is required"},
      {"crop " + quoted(dir / "room.umb") + " -o " + quoted(dir / "out.png") + " --bbox 0,0,0,1,1,1", 2,
       "unknown map file extension '.png'"},
      {in + " --bbox 5000,0,0,5001,1,1", 1, "lies outside the map, which spans [-3276.8, 3276.8)"},
      {"crop " + quoted(dir / "deep.umb") + " -o " + quoted(dir / "out.bt") + " --bbox 0,0,0,1,1,1", 1,
       "OctoMap files (.bt) hold 16 depth levels, this map has 18"},
      {"crop " + quoted(dir / "room.umb") + " -o " + quoted(dir / "no" / "out.umb") + " --bbox 0,0,0,1,1,1", 1,
       (dir / "no").string()},
  };
  for (const Case& c : cases) {
    const CommandResult result = run(c.arguments);
    EXPECT_EQ(result.exit_code, c.exit_code) << c.arguments << "\n" << result.output;
    EXPECT_TRUE(contains(result.output, c.words)) << c.arguments << "\n" << result.output;
  }
  EXPECT_FALSE(fs::exists(dir / "out.umb"));
  EXPECT_FALSE(fs::exists(dir / "out.bt"));
  EXPECT_TRUE(temporaries_in(dir).empty());
}

// --- compare -------------------------------------------------------------------------------

/// The unsigned number after "key": in a JSON text.
std::uint64_t json_count(const std::string& json, const std::string& path_regex) {
  std::smatch match;
  if (!std::regex_search(json, match, std::regex(path_regex + "([0-9]+)"))) return ~std::uint64_t{0};
  return std::stoull(match[1]);
}
double json_number(const std::string& json, const std::string& key) {
  std::smatch match;
  if (!std::regex_search(json, match, std::regex("\"" + key + "\": ([0-9.eE+-]+)"))) return -1.0;
  return std::stod(match[1]);
}

void expect_json_is(const std::string& json, const MapAgreement& a) {
  const char* names[] = {"unknown", "free", "occupied"};
  for (int r = 0; r < 3; ++r) {
    for (int o = 0; o < 3; ++o) {
      const std::string path = "\"" + std::string(names[r]) + "\": \\{[^}]*\"" + names[o] + "\": ";
      EXPECT_EQ(json_count(json, path), a.voxels[r][o]) << names[r] << " / " << names[o] << "\n" << json;
    }
  }
  EXPECT_DOUBLE_EQ(json_number(json, "occupied_recall"), a.recall());
  EXPECT_DOUBLE_EQ(json_number(json, "occupied_precision"), a.precision());
  EXPECT_DOUBLE_EQ(json_number(json, "free_agreement"), a.free_agreement());
  EXPECT_DOUBLE_EQ(json_number(json, "free_left_unknown"), a.free_left_unknown());
}

TEST(CompareCli, GivesTheLibrarysAgreement) {
  const fs::path dir = test::scratch_dir();
  const OccupancyMap simple = room_map(IntegratorKind::simple);
  const OccupancyMap fast = room_map(IntegratorKind::fast);
  save_map(simple, dir / "simple.umb");
  save_map(fast, dir / "fast.umb");
  const MapAgreement whole = compare_maps(simple, fast);
  ASSERT_GT(whole.count(OccupancyState::free, OccupancyState::unknown) +
                whole.count(OccupancyState::unknown, OccupancyState::free),
            0u)
      << "the two maps should differ somewhere";
  const CommandResult json = run("compare " + quoted(dir / "simple.umb") + " " + quoted(dir / "fast.umb") + " --json");
  ASSERT_EQ(json.exit_code, 0) << json.output;
  expect_json_is(json.output, whole);
  EXPECT_TRUE(contains(json.output, "\"box_keys\": null")) << json.output;

  const Aabb box{{-1.0, -0.5, -1.5}, {2.5, 1.0, 1.0}};
  const MapAgreement inside = compare_maps(simple, fast, voxel_box(simple.grid(), box));
  const CommandResult boxed = run("compare " + quoted(dir / "simple.umb") + " " + quoted(dir / "fast.umb") +
                                  " --json --bbox -1,-0.5,-1.5,2.5,1,1");
  ASSERT_EQ(boxed.exit_code, 0) << boxed.output;
  expect_json_is(boxed.output, inside);

  const CommandResult text = run("compare " + quoted(dir / "simple.umb") + " " + quoted(dir / "fast.umb"));
  ASSERT_EQ(text.exit_code, 0) << text.output;
  char recall[64];
  std::snprintf(recall, sizeof recall, "occupied recall     %8.4f %%", 100.0 * whole.recall());
  EXPECT_TRUE(contains(text.output, recall)) << text.output;
  EXPECT_TRUE(contains(text.output, "A free ")) << text.output;
}

TEST(CompareCli, AMapAgainstItselfAndAgainstItsCrop) {
  const fs::path dir = test::scratch_dir();
  const OccupancyMap map = room_map();
  save_map(map, dir / "room.umb");
  ASSERT_EQ(run("crop " + quoted(dir / "room.umb") + " -o " + quoted(dir / "cut.umb") + " --bbox -1,-1,-1,1,1,1").exit_code, 0);
  const CommandResult self = run("compare " + quoted(dir / "room.umb") + " " + quoted(dir / "room.umb") + " --json");
  EXPECT_EQ(json_number(self.output, "occupied_recall"), 1.0) << self.output;
  EXPECT_EQ(json_number(self.output, "free_agreement"), 1.0) << self.output;
  // Inside the crop's box the two agree completely; outside it the crop knows nothing.
  const CommandResult inside = run("compare " + quoted(dir / "room.umb") + " " + quoted(dir / "cut.umb") +
                                   " --json --bbox -1,-1,-1,1,1,1");
  EXPECT_EQ(json_number(inside.output, "occupied_recall"), 1.0) << inside.output;
  EXPECT_EQ(json_number(inside.output, "free_agreement"), 1.0) << inside.output;
  const CommandResult whole = run("compare " + quoted(dir / "room.umb") + " " + quoted(dir / "cut.umb") + " --json");
  EXPECT_LT(json_number(whole.output, "occupied_recall"), 1.0) << whole.output;
  EXPECT_EQ(json_number(whole.output, "occupied_precision"), 1.0) << whole.output;
}

TEST(CompareCli, BadInputIsNamed) {
  const fs::path dir = test::scratch_dir();
  save_map(room_map(), dir / "a.umb");
  save_map(OccupancyMap(0.05), dir / "fine.umb");
  const CommandResult grids = run("compare " + quoted(dir / "a.umb") + " " + quoted(dir / "fine.umb"));
  EXPECT_EQ(grids.exit_code, 1) << grids.output;
  EXPECT_TRUE(contains(grids.output, "the maps have different voxels: 0.1")) << grids.output;
  const CommandResult box = run("compare " + quoted(dir / "a.umb") + " " + quoted(dir / "a.umb") + " --bbox 1,2");
  EXPECT_EQ(box.exit_code, 2) << box.output;
  EXPECT_TRUE(contains(box.output, "--bbox: expects 6 numbers")) << box.output;
  const CommandResult name = run("compare " + quoted(dir / "a.umb") + " " + quoted(dir / "b.txt"));
  EXPECT_EQ(name.exit_code, 2) << name.output;
  EXPECT_TRUE(contains(name.output, "unknown map file extension '.txt'")) << name.output;
}

// --- export -------------------------------------------------------------------------------

struct Point {
  Vec3f p;
  Rgb rgb;
  friend bool operator<(const Point& a, const Point& b) {
    return std::tie(a.p.x, a.p.y, a.p.z, a.rgb.r, a.rgb.g, a.rgb.b) < std::tie(b.p.x, b.p.y, b.p.z, b.rgb.r, b.rgb.g, b.rgb.b);
  }
  friend bool operator==(const Point& a, const Point& b) { return !(a < b) && !(b < a); }
};

/// The vertices of a PLY file as umbra's reader gives them.
std::vector<Point> read_ply_points(const fs::path& path) {
  Scan scan;
  const auto source = open_ply_file(path);
  EXPECT_TRUE(source->next(scan)) << path;
  std::vector<Point> points;
  for (std::size_t i = 0; i < scan.points.size(); ++i) {
    points.push_back({scan.points[i], scan.colors.empty() ? Rgb{} : scan.colors[i]});
  }
  return points;
}

TEST(ExportCli, PointsAreTheOccupiedVoxelCentresAndReadBack) {
  const fs::path dir = test::scratch_dir();
  const OccupancyMap map = room_map();
  ASSERT_LT(map.count(pred::leaf() && pred::occupied() && pred::min_depth(1)), 100u);
  ASSERT_GT(map.count(pred::leaf() && pred::occupied() && pred::min_depth(1)), 0u) << "no pruned occupied node";
  save_map(map, dir / "room.umb");
  // Brute force: every occupied voxel near the known space, one key at a time.
  std::vector<Point> expected;
  std::vector<Point> expected_colored;
  for_each_key_near_known_space(map, [&](Key key) {
    const Node node = map.node(key);
    if (node.state != OccupancyState::occupied) return;
    expected.push_back({map.grid().center_f(key), Rgb{}});
    expected_colored.push_back({map.grid().center_f(key), node.color.value_or(Rgb{128, 128, 128})});
  });
  std::sort(expected.begin(), expected.end());
  std::sort(expected_colored.begin(), expected_colored.end());

  const CommandResult plain = run("export " + quoted(dir / "room.umb") + " -o " + quoted(dir / "room.ply"));
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  EXPECT_TRUE(contains(plain.output, "wrote " + (dir / "room.ply").string() + ": " + std::to_string(expected.size()) +
                                         " points"))
      << plain.output;
  std::vector<Point> got = read_ply_points(dir / "room.ply");
  std::sort(got.begin(), got.end());
  EXPECT_EQ(got, expected);

  const CommandResult colored =
      run("export " + quoted(dir / "room.umb") + " -o " + quoted(dir / "colored.ply") + " --color");
  ASSERT_EQ(colored.exit_code, 0) << colored.output;
  EXPECT_TRUE(contains(colored.output, "have no color sample; they are grey")) << colored.output;
  got = read_ply_points(dir / "colored.ply");
  std::sort(got.begin(), got.end());
  EXPECT_EQ(got, expected_colored);
  const std::vector<std::uint8_t> bytes = test::read_bytes(dir / "colored.ply");
  const std::string head(bytes.begin(), bytes.begin() + 64);
  EXPECT_TRUE(head.starts_with("ply\nformat binary_little_endian 1.0\n")) << head;
}

TEST(ExportCli, AMeshOfOutwardFacingCubes) {
  const fs::path dir = test::scratch_dir();
  const OccupancyMap map = room_map();
  save_map(map, dir / "room.umb");
  std::vector<Node> cubes;  // the occupied childless nodes, in the order export walks them
  map.for_each_leaf([&](const Node& n) {
    if (n.state == OccupancyState::occupied) cubes.push_back(n);
  });
  const CommandResult mesh = run("export " + quoted(dir / "room.umb") + " -o " + quoted(dir / "mesh.ply") + " --mesh --color");
  ASSERT_EQ(mesh.exit_code, 0) << mesh.output;
  // The vertices through umbra's reader (it also checks the face list that follows them).
  const std::vector<Point> vertices = read_ply_points(dir / "mesh.ply");
  ASSERT_EQ(vertices.size(), 8 * cubes.size());
  // The faces, read here: 12 triangles per cube, each facing away from its cube's centre.
  const std::vector<std::uint8_t> bytes = test::read_bytes(dir / "mesh.ply");
  const std::string text(bytes.begin(), bytes.end());
  const std::size_t body = text.find("end_header\n") + 11;
  EXPECT_TRUE(contains(text.substr(0, body), "element face " + std::to_string(12 * cubes.size()) +
                                                 "\nproperty list uchar int vertex_indices\n"));
  std::size_t at = body + vertices.size() * 15;
  ASSERT_EQ(bytes.size(), at + 12 * cubes.size() * 13);
  for (std::size_t cube = 0; cube < cubes.size(); ++cube) {
    Vec3f low = vertices[8 * cube].p;
    Vec3f high = low;
    for (int c = 0; c < 8; ++c) {
      const Vec3f v = vertices[8 * cube + static_cast<std::size_t>(c)].p;
      low = {std::min(low.x, v.x), std::min(low.y, v.y), std::min(low.z, v.z)};
      high = {std::max(high.x, v.x), std::max(high.y, v.y), std::max(high.z, v.z)};
      EXPECT_EQ(vertices[8 * cube + static_cast<std::size_t>(c)].rgb, cubes[cube].color.value_or(Rgb{128, 128, 128}));
    }
    // The cube is the node: its corners and its size.
    EXPECT_NEAR(low.x, cubes[cube].min_corner().x, 1e-5);
    EXPECT_NEAR(high.z, cubes[cube].max_corner().z, 1e-5);
    EXPECT_NEAR(high.y - low.y, cubes[cube].size, 1e-5);
    const Vec3f centre{(low.x + high.x) / 2, (low.y + high.y) / 2, (low.z + high.z) / 2};
    for (int t = 0; t < 12; ++t) {
      ASSERT_EQ(bytes[at], 3u);
      std::array<Vec3f, 3> corner;
      for (int k = 0; k < 3; ++k) {
        std::int32_t index = 0;
        std::memcpy(&index, &bytes[at + 1 + 4 * static_cast<std::size_t>(k)], 4);
        ASSERT_GE(index, static_cast<std::int32_t>(8 * cube));
        ASSERT_LT(index, static_cast<std::int32_t>(8 * cube + 8));
        corner[static_cast<std::size_t>(k)] = vertices[static_cast<std::size_t>(index)].p;
      }
      at += 13;
      const Vec3f u = corner[1] - corner[0];
      const Vec3f v = corner[2] - corner[0];
      const Vec3f normal{u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
      const Vec3f middle{(corner[0].x + corner[1].x + corner[2].x) / 3 - centre.x,
                         (corner[0].y + corner[1].y + corner[2].y) / 3 - centre.y,
                         (corner[0].z + corner[1].z + corner[2].z) / 3 - centre.z};
      EXPECT_GT(normal.x * middle.x + normal.y * middle.y + normal.z * middle.z, 0.0f) << "cube " << cube << " triangle " << t;
    }
  }
}

TEST(ExportCli, BadInputIsNamed) {
  const fs::path dir = test::scratch_dir();
  OccupancyMap plain(0.1);
  plain.set_log_odds(Vec3d{0.05, 0.05, 0.05}, 2.0f);
  save_map(plain, dir / "plain.umb");
  const CommandResult color = run("export " + quoted(dir / "plain.umb") + " -o " + quoted(dir / "p.ply") + " --color");
  EXPECT_EQ(color.exit_code, 1) << color.output;
  EXPECT_TRUE(contains(color.output, (dir / "plain.umb").string() + ": the map has no colors")) << color.output;
  const CommandResult name = run("export " + quoted(dir / "plain.umb") + " -o " + quoted(dir / "p.obj"));
  EXPECT_EQ(name.exit_code, 2) << name.output;
  EXPECT_TRUE(contains(name.output, "name the output .ply")) << name.output;
  const CommandResult folder = run("export " + quoted(dir / "plain.umb") + " -o " + quoted(dir / "no" / "p.ply"));
  EXPECT_EQ(folder.exit_code, 1) << folder.output;
  EXPECT_TRUE(contains(folder.output, (dir / "no").string())) << folder.output;
  const CommandResult memory = run("export " + quoted(dir / "plain.umb") + " -o " + quoted(dir / "p.ply") +
                                   " --max-memory 1");
  EXPECT_EQ(memory.exit_code, 1) << memory.output;
  EXPECT_FALSE(fs::exists(dir / "p.ply"));
  EXPECT_TRUE(temporaries_in(dir).empty());
}

}  // namespace
}  // namespace umbra
