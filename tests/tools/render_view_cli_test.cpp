// `umbra render` and `umbra view` run as a user would: the PNG is the
// library's picture, bad options are usage errors (exit code 2) that name
// the problem, and the HTML page is self-contained with layers that decode
// (base64, zlib, the columns of tools/viewer_data.hpp, read here with code
// of the test's own) to exactly the nodes the library's queries yield.
#include <zlib.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "support/test_support.hpp"
#include "umbra/io/map_file.hpp"
#include "umbra/io/map_render.hpp"
#include "umbra/io/png_writer.hpp"
#include "umbra/map/map_statistics.hpp"
#include "umbra/query/predicate.hpp"
#include "umbra/sim/lidar.hpp"
#include "umbra/sim/scene.hpp"
#include "support/demo_maps.hpp"

namespace umbra {
namespace {

using test::CommandResult;

std::string cli() { return UMBRA_CLI_PATH; }
std::string quoted(const std::filesystem::path& path) { return "'" + path.string() + "'"; }

/// The demo building at 20 cm, with colour, saved as DIR/building.umb.
std::filesystem::path building_map(const std::filesystem::path& dir) {
  MapConfig config;
  config.resolution = 0.2;
  config.color = true;
  const OccupancyMap map = test::demo_lidar_map(config, [](std::size_t i, Vec3f) {
    return i % 3 == 0 ? Rgb{250, 5, 90} : Rgb{10, 200, 30};
  });
  const auto path = dir / "building.umb";
  save_map(map, path);
  return path;
}

TEST(RenderCli, WritesThePictureTheLibraryDraws) {
  const auto dir = test::scratch_dir();
  const auto map_path = building_map(dir);
  const OccupancyMap map = load_map(map_path);

  const CommandResult iso = test::run_command(cli() + " render " + quoted(map_path) + " -o " + quoted(dir / "iso.png") +
                                              " --width 300 --color rgb --depth 1");
  ASSERT_EQ(iso.exit_code, 0) << iso.output;
  EXPECT_NE(iso.output.find("300 x"), std::string::npos) << iso.output;
  RenderOptions options;
  options.width = 300;
  options.color = RenderColor::rgb;
  options.depth = 1;
  EXPECT_EQ(read_png(dir / "iso.png").rgb, render_map(map, options).image.rgb);

  // A slice is seen along its axis and coloured by state unless told otherwise.
  const CommandResult slice = test::run_command(cli() + " render " + quoted(map_path) + " -o " +
                                                quoted(dir / "slice.png") + " --slice y=6.1 --width 200");
  ASSERT_EQ(slice.exit_code, 0) << slice.output;
  RenderOptions slice_options;
  slice_options.width = 200;
  slice_options.slice = RenderSlice{1, 6.1};
  slice_options.view = RenderView::front;
  slice_options.color = RenderColor::state;
  EXPECT_EQ(read_png(dir / "slice.png").rgb, render_map(map, slice_options).image.rgb);
}

TEST(RenderCli, BadOptionsAreUsageErrorsThatNameTheProblem) {
  const auto dir = test::scratch_dir();
  const auto map_path = building_map(dir);
  OccupancyMap plain(0.1);
  plain.set_log_odds(Vec3d{0.05, 0.05, 0.05}, 2.0f);
  save_map(plain, dir / "plain.umb");
  const std::string render = cli() + " render " + quoted(map_path) + " -o " + quoted(dir / "out.png") + " ";
  const std::vector<std::pair<std::string, std::string>> cases{
      {"--view diagonal", "--view"},
      {"--color pink", "--color"},
      {"--slice q=1", "AXIS=METRES"},
      {"--slice z=abc", "AXIS=METRES"},
      {"--slice z=", "AXIS=METRES"},
      {"--width 5", "--width"},
      {"--depth 40", "--depth"},
      {"--slice z=1 --view iso", "view"},
      {"--slice z=1e9", "outside the map"},
      {"--depth 17", "depth levels"},
  };
  for (const auto& [options, words] : cases) {
    const CommandResult result = test::run_command(render + options);
    EXPECT_EQ(result.exit_code, 2) << options << ": " << result.output;
    EXPECT_NE(result.output.find(words), std::string::npos) << options << ": " << result.output;
  }
  const CommandResult rgb = test::run_command(cli() + " render " + quoted(dir / "plain.umb") + " -o " +
                                              quoted(dir / "out.png") + " --color rgb");
  EXPECT_EQ(rgb.exit_code, 2) << rgb.output;
  EXPECT_NE(rgb.output.find("no colour"), std::string::npos) << rgb.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.png"));

  const CommandResult missing = test::run_command(cli() + " render " + quoted(dir / "nothing.umb") + " -o x.png");
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  const CommandResult no_folder = test::run_command(cli() + " render " + quoted(map_path) + " -o " +
                                                    quoted(dir / "no" / "such" / "folder.png"));
  EXPECT_EQ(no_folder.exit_code, 1) << no_folder.output;
  EXPECT_NE(no_folder.output.find("folder.png"), std::string::npos) << no_folder.output;

  save_map(OccupancyMap(0.1), dir / "empty.umb");
  const CommandResult empty = test::run_command(cli() + " render " + quoted(dir / "empty.umb") + " -o " +
                                                quoted(dir / "empty.png"));
  EXPECT_EQ(empty.exit_code, 1) << empty.output;
  EXPECT_NE(empty.output.find("no occupied node"), std::string::npos) << empty.output;
}

// --- umbra view --------------------------------------------------------------------

/// RFC 4648 base64, written here rather than shared with the tool.
std::vector<std::uint8_t> from_base64(const std::string& text) {
  std::vector<std::uint8_t> out;
  std::uint32_t bits = 0;
  int count = 0;
  for (const char c : text) {
    int value = -1;
    if (c >= 'A' && c <= 'Z') value = c - 'A';
    if (c >= 'a' && c <= 'z') value = c - 'a' + 26;
    if (c >= '0' && c <= '9') value = c - '0' + 52;
    if (c == '+') value = 62;
    if (c == '/') value = 63;
    if (value < 0) continue;  // padding
    bits = (bits << 6) | std::uint32_t(value);
    count += 6;
    if (count >= 8) {
      count -= 8;
      out.push_back(static_cast<std::uint8_t>(bits >> count));
    }
  }
  return out;
}

/// A box in finest voxels, with its colour when the layer has colours.
using Box = std::tuple<std::uint32_t, std::uint32_t, std::uint32_t, std::uint32_t, std::uint32_t, std::uint32_t,
                       std::uint32_t>;

std::vector<Box> decode_layer(const std::string& base64, std::size_t count, int key_bytes, bool colours) {
  const std::vector<std::uint8_t> packed = from_base64(base64);
  std::vector<std::uint8_t> raw(count * (6 * std::size_t(key_bytes) + (colours ? 3 : 0)));
  uLongf size = raw.size();
  EXPECT_EQ(uncompress(raw.data(), &size, packed.data(), packed.size()), Z_OK);
  EXPECT_EQ(size, raw.size());
  auto column = [&](int c, std::size_t i) {
    std::uint32_t value = 0;
    for (int b = 0; b < key_bytes; ++b) value |= std::uint32_t(raw[(c * count + i) * key_bytes + b]) << (8 * b);
    return value;
  };
  std::vector<Box> boxes;
  for (std::size_t i = 0; i < count; ++i) {
    std::uint32_t rgb = 0;
    if (colours) {
      const std::size_t base = 6 * count * key_bytes;
      rgb = (std::uint32_t(raw[base + i]) << 16) | (std::uint32_t(raw[base + count + i]) << 8) | raw[base + 2 * count + i];
    }
    boxes.emplace_back(column(0, i), column(1, i), column(2, i), column(3, i), column(4, i), column(5, i), rgb);
  }
  std::sort(boxes.begin(), boxes.end());
  return boxes;
}

TEST(ViewCli, PageIsSelfContainedAndItsLayersAreTheLibrarysNodes) {
  const auto dir = test::scratch_dir();
  const auto map_path = building_map(dir);
  const CommandResult view = test::run_command(cli() + " view " + quoted(map_path) + " -o " + quoted(dir / "map.html"));
  if (view.exit_code == 1 && view.output.find("built without the browser viewer") != std::string::npos) {
    GTEST_SKIP() << "this umbra has no viewer page (node/npm were missing at configure time): " << view.output;
  }
  ASSERT_EQ(view.exit_code, 0) << view.output;
  const std::vector<std::uint8_t> bytes = test::read_bytes(dir / "map.html");
  const std::string page(bytes.begin(), bytes.end());
  EXPECT_EQ(page.find("<script src"), std::string::npos) << "the page loads a script from elsewhere";
  EXPECT_EQ(page.find("<link"), std::string::npos) << "the page loads a style sheet from elsewhere";
  EXPECT_NE(page.find("Three.js Authors"), std::string::npos) << "three.js and its licence notice are inside";

  // The numbers: key_bytes and the known space's size in voxels.
  std::smatch found;
  ASSERT_TRUE(std::regex_search(page, found, std::regex(R"re("keyBytes": (\d), "size": \[(\d+), (\d+), (\d+)\])re")));
  const int key_bytes = std::stoi(found[1]);
  const OccupancyMap map = load_map(map_path);
  const MapStatistics stats = compute_statistics(map);
  const Key origin = map.key(stats.known_min + Vec3d{0.1, 0.1, 0.1});
  const Key end = map.key(stats.known_max - Vec3d{0.1, 0.1, 0.1});
  EXPECT_EQ(std::stoul(found[2]), end.x - origin.x + 1);
  EXPECT_EQ(std::stoul(found[4]), end.z - origin.z + 1);

  // Every layer the page lists, against the library's nodes.
  const std::regex layer_entry(R"re(\{"depth": (\d+), "state": "(\w+)", "count": (\d+)(, "id": "(layer-\d+)")?\})re");
  std::size_t layers = 0;
  std::set<int> depths;
  for (auto it = std::sregex_iterator(page.begin(), page.end(), layer_entry); it != std::sregex_iterator(); ++it) {
    const int depth = std::stoi((*it)[1]);
    const std::string state = (*it)[2];
    const std::size_t count = std::stoul((*it)[3]);
    const std::string id = (*it)[5];
    depths.insert(depth);
    Predicate predicate = pred::leaf() && (state == "occupied" ? pred::occupied() : state == "free" ? pred::free() : pred::unknown());
    if (state == "unknown") predicate = predicate && pred::intersects(Aabb{stats.known_min + Vec3d{0.1, 0.1, 0.1}, stats.known_max - Vec3d{0.1, 0.1, 0.1}});
    ASSERT_EQ(count, map.count(predicate, depth)) << state << " at depth " << depth;
    ASSERT_FALSE(id.empty()) << "the default budget holds every layer of this small map";
    const std::string open = "id=\"" + id + "\">";
    const std::size_t begin = page.find(open);
    ASSERT_NE(begin, std::string::npos) << id;
    const std::string base64 = page.substr(begin + open.size(), page.find('<', begin + open.size()) - begin - open.size());
    const bool colours = state == "occupied";
    const std::vector<Box> decoded = decode_layer(base64, count, key_bytes, colours);

    std::vector<Box> expected;
    for (const Node& node : map.query(predicate, depth)) {
      std::array<std::uint32_t, 6> box{};
      for (int axis = 0; axis < 3; ++axis) {
        const std::uint32_t low = std::max(node.key[axis], origin[axis]);
        const std::uint32_t high = std::min(node.key[axis] + (1u << node.depth), end[axis] + 1);
        box[std::size_t(axis)] = low - origin[axis];
        box[std::size_t(axis) + 3] = high - low;
      }
      std::uint32_t rgb = 0;
      if (colours) {
        const Rgb c = node.color.value_or(Rgb{150, 150, 150});
        rgb = (std::uint32_t(c.r) << 16) | (std::uint32_t(c.g) << 8) | c.b;
      }
      expected.emplace_back(box[0], box[1], box[2], box[3], box[4], box[5], rgb);
    }
    std::sort(expected.begin(), expected.end());
    EXPECT_EQ(decoded, expected) << state << " at depth " << depth;
    ++layers;
  }
  EXPECT_EQ(depths.size(), 8u);  // the finest depth and seven coarser
  EXPECT_EQ(layers, 3 * depths.size());
}

TEST(ViewCli, UsageErrors) {
  const auto dir = test::scratch_dir();
  const auto map_path = building_map(dir);
  const CommandResult nowhere = test::run_command(cli() + " view " + quoted(map_path));
  EXPECT_EQ(nowhere.exit_code, 2) << nowhere.output;
  EXPECT_NE(nowhere.output.find("-o FILE.html"), std::string::npos) << nowhere.output;
  const CommandResult budget = test::run_command(cli() + " view " + quoted(map_path) + " -o x.html --budget 0");
  EXPECT_EQ(budget.exit_code, 2) << budget.output;
  const CommandResult port = test::run_command(cli() + " view " + quoted(map_path) + " --serve --port 70000");
  EXPECT_EQ(port.exit_code, 2) << port.output;
}

}  // namespace
}  // namespace umbra
