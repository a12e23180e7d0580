// `umbra render` and `umbra view` run as a user would: the PNG is the
// library's picture, bad options are usage errors (exit code 2) that name
// the problem, and the HTML page is self-contained with layers that decode
// (base64, zlib, the codes and columns of tools/viewer_data.hpp, read here with code
// of the test's own) to exactly the nodes the library's queries yield.
#include <zlib.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <regex>
#include <sstream>
#include <cmath>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "support/cli_commands.hpp"
#include "support/test_support.hpp"
#include "umbra/io/map_file.hpp"
#include "umbra/io/map_render.hpp"
#include "umbra/io/png_writer.hpp"
#include "umbra/map/map_statistics.hpp"
#include "umbra/query/predicate.hpp"
#include "umbra/sim/lidar.hpp"
#include "umbra/sim/scene.hpp"
#include "support/demo_maps.hpp"
#include "support/room_map.hpp"
#include "umbra/io/topdown_image.hpp"

namespace umbra {
namespace {

using test::CommandResult;

using test::cli;
using test::quoted;

/// The demo building at 20 cm, with color, saved as DIR/building.umb.
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
                                              " --width 300 --color rgb --depth 1 --max-z none");
  ASSERT_EQ(iso.exit_code, 0) << iso.output;
  EXPECT_NE(iso.output.find("300 x"), std::string::npos) << iso.output;
  RenderOptions options;
  options.width = 300;
  options.color = RenderColor::rgb;
  options.depth = 1;
  options.annotate = true;
  EXPECT_EQ(read_png(dir / "iso.png").rgb, render_map(map, options).image.rgb);

  // --bare: the drawing alone.
  const CommandResult bare = test::run_command(cli() + " render " + quoted(map_path) + " -o " +
                                               quoted(dir / "bare.png") + " --width 120 --max-z none --bare");
  ASSERT_EQ(bare.exit_code, 0) << bare.output;
  RenderOptions bare_options;
  bare_options.width = 120;
  EXPECT_EQ(read_png(dir / "bare.png").rgb, render_map(map, bare_options).image.rgb);

  // A slice is seen along its axis and colored by state unless told otherwise.
  const CommandResult slice = test::run_command(cli() + " render " + quoted(map_path) + " -o " +
                                                quoted(dir / "slice.png") + " --slice y=6.1 --width 300");
  ASSERT_EQ(slice.exit_code, 0) << slice.output;
  RenderOptions slice_options;
  slice_options.width = 300;
  slice_options.slice = RenderSlice{1, 6.1};
  slice_options.view = RenderView::front;
  slice_options.color = RenderColor::state;
  slice_options.annotate = true;
  EXPECT_EQ(read_png(dir / "slice.png").rgb, render_map(map, slice_options).image.rgb);
}

TEST(RenderCli, DefaultsCutTheCeilingFromAboveAndTheNearHalfFromTheFront) {
  const auto dir = test::scratch_dir();
  const OccupancyMap room = test::closed_room_map();
  save_map(room, dir / "room.umb");
  const std::string render = cli() + " render " + quoted(dir / "room.umb") + " --width 300 ";

  // A top view cuts the ceiling: the floor shows (its height color at the room's middle).
  const CommandResult top = test::run_command(render + "-o " + quoted(dir / "top.png") + " --view top");
  ASSERT_EQ(top.exit_code, 0) << top.output;
  EXPECT_NE(top.output.find("ceiling found at 2.400 m"), std::string::npos) << top.output;
  RenderOptions options;
  options.view = RenderView::top;
  options.width = 300;
  options.annotate = true;
  options.max_z = 2.35;
  const MapPicture expected = render_map(room, options);
  const Image written = read_png(dir / "top.png");
  EXPECT_EQ(written.rgb, expected.image.rgb);
  const auto [x, y] = expected.camera.pixel(test::room_voxel(30, 20, 0));
  const double top_shade = 0.5 + 0.5 / std::sqrt(1.8);  // map_render.hpp's light on a top face
  const Rgb floor = height_ramp(0.0);
  const Rgb shaded_floor{static_cast<std::uint8_t>(std::lround(floor.r * top_shade)),
                         static_cast<std::uint8_t>(std::lround(floor.g * top_shade)),
                         static_cast<std::uint8_t>(std::lround(floor.b * top_shade))};
  EXPECT_EQ(written.at(int(x), int(y)), shaded_floor) << "the room's floor, not its ceiling";

  // --max-z none keeps the ceiling: the same pixel is the ceiling's.
  const CommandResult uncut =
      test::run_command(render + "-o " + quoted(dir / "uncut.png") + " --view top --max-z none");
  ASSERT_EQ(uncut.exit_code, 0) << uncut.output;
  EXPECT_NE(read_png(dir / "uncut.png").at(int(x), int(y)), shaded_floor);

  // A front view: cut through the middle (y >= 1.45), colored by distance.
  const CommandResult front = test::run_command(render + "-o " + quoted(dir / "front.png") + " --view front");
  ASSERT_EQ(front.exit_code, 0) << front.output;
  EXPECT_NE(front.output.find("y >= 1.450 m"), std::string::npos) << front.output;
  RenderOptions front_options;
  front_options.view = RenderView::front;
  front_options.color = RenderColor::depth;
  front_options.section = 1.45;
  front_options.width = 300;
  front_options.annotate = true;
  EXPECT_EQ(read_png(dir / "front.png").rgb, render_map(room, front_options).image.rgb);
}

TEST(RenderCli, StateViewShowsFreeAndUnknownSpaceNotJustRed) {
  const auto dir = test::scratch_dir();
  const auto map_path = building_map(dir);
  const CommandResult top = test::run_command(cli() + " render " + quoted(map_path) + " -o " +
                                              quoted(dir / "state.png") + " --view top --color state --bare");
  ASSERT_EQ(top.exit_code, 0) << top.output;
  EXPECT_NE(top.output.find("floor found"), std::string::npos) << top.output;
  const Image picture = read_png(dir / "state.png");
  const RenderOptions colors;
  std::size_t free = 0;
  std::size_t unknown = 0;
  std::size_t red = 0;
  for (int row = 0; row < picture.height; ++row) {
    for (int column = 0; column < picture.width; ++column) {
      const Rgb c = picture.at(column, row);
      free += c == colors.free_color ? 1 : 0;
      unknown += c == colors.unknown_color ? 1 : 0;
      red += c.r > 2 * c.g && c.r > 2 * c.b ? 1 : 0;
    }
  }
  const double pixels = double(picture.width) * picture.height;
  EXPECT_GT(free, 0.2 * pixels) << "free floor space between the walls";
  EXPECT_GT(unknown, 0.02 * pixels) << "unknown space around the building";
  EXPECT_GT(red, 0.02 * pixels) << "walls";
}

TEST(RenderCli, SliceOutsideTheMapFailsNamingTheValueAndTheExtent) {
  const auto dir = test::scratch_dir();
  const auto map_path = building_map(dir);
  const OccupancyMap map = load_map(map_path);
  const MapStatistics stats = compute_statistics(map);
  for (const std::string value : {"100", "-7", "250.5"}) {
    const CommandResult result = test::run_command(cli() + " render " + quoted(map_path) + " -o " +
                                                   quoted(dir / "slice.png") + " --slice z=" + value);
    EXPECT_EQ(result.exit_code, 1) << result.output;
    std::ostringstream extent;
    extent << "spans z from " << stats.known_min.z << " to " << stats.known_max.z << " m";
    EXPECT_NE(result.output.find("z = " + value + " m"), std::string::npos) << result.output;
    EXPECT_NE(result.output.find(extent.str()), std::string::npos) << extent.str() << ": " << result.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "slice.png"));
  }
}

TEST(RenderCli, WritesPngOnlyAndSaysSo) {
  const auto dir = test::scratch_dir();
  const auto map_path = building_map(dir);
  for (const std::string name : {"out.jpg", "out.jpeg", "out", "out.png.gif"}) {
    const CommandResult result = test::run_command(cli() + " render " + quoted(map_path) + " -o " + quoted(dir / name));
    EXPECT_EQ(result.exit_code, 2) << name << ": " << result.output;
    EXPECT_NE(result.output.find(".png"), std::string::npos) << result.output;
    EXPECT_NE(result.output.find("PNG pictures only"), std::string::npos) << result.output;
    EXPECT_FALSE(std::filesystem::exists(dir / name));
  }
  const CommandResult upper = test::run_command(cli() + " render " + quoted(map_path) + " -o " + quoted(dir / "a.PNG"));
  EXPECT_EQ(upper.exit_code, 0) << upper.output;
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
      {"--width 100", "--bare"},
      {"--depth 40", "--depth"},
      {"--slice z=1 --view iso", "view"},
      {"--slice z=1 --max-z 2", "for views"},
      {"--slice z=1 --color depth", "flat"},
      {"--max-z high", "--max-z"},
      {"--min-z low", "--min-z"},
      {"--section 1 --view top", "--section"},
      {"--section somewhere --view front", "--section"},
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
  EXPECT_NE(rgb.output.find("no color"), std::string::npos) << rgb.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.png"));

  const CommandResult missing = test::run_command(cli() + " render " + quoted(dir / "nothing.umb") + " -o x.png");
  EXPECT_EQ(missing.exit_code, 1) << missing.output;  // an input failure, as for the other commands
  EXPECT_NE(missing.output.find("nothing.umb"), std::string::npos) << missing.output;
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

/// A box in finest voxels from the known space's lowest corner, clipped to
/// the known space as the page clips it, with its color when the layer has colors.
using Box = std::tuple<std::int64_t, std::int64_t, std::int64_t, std::int64_t, std::int64_t, std::int64_t,
                       std::uint32_t>;

/// 8-bit color as the page shows it: 5-6-5 bits, the high bits repeated below.
std::uint32_t as_shown(Rgb c) {
  const std::uint32_t r = c.r >> 3;
  const std::uint32_t g = c.g >> 2;
  const std::uint32_t b = c.b >> 3;
  return (((r << 3) | (r >> 2)) << 16) | (((g << 2) | (g >> 4)) << 8) | ((b << 3) | (b >> 2));
}

/// Bits 0, 3, 6, ... of a code (the test's own, not umbra's morton::decode).
std::uint32_t every_third_bit(std::uint64_t code) {
  std::uint32_t value = 0;
  for (int bit = 0; bit < 21; ++bit) value |= std::uint32_t((code >> (3 * bit)) & 1u) << bit;
  return value;
}

struct PageGeometry {
  std::array<std::int64_t, 3> origin{};  ///< finest key of the known space's lowest corner
  std::array<std::int64_t, 3> size{};    ///< the known space in finest voxels
};

/// One box clipped as the page clips every node (coarse nodes of any state
/// and unknown nodes reach beyond the known space).
Box box_of(const std::array<std::int64_t, 3>& key, std::int64_t edge, const PageGeometry& page, std::uint32_t rgb) {
  std::array<std::int64_t, 6> box{};
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const std::int64_t first = std::max<std::int64_t>(key[axis] - page.origin[axis], 0);
    const std::int64_t end = std::min(key[axis] - page.origin[axis] + edge, page.size[axis]);
    box[axis] = first;
    box[axis + 3] = end - first;
  }
  return {box[0], box[1], box[2], box[3], box[4], box[5], rgb};
}

/// A layer in the format of tools/viewer_data.hpp, decoded by the test's own code.
std::vector<Box> decode_layer(const std::string& base64, std::size_t count, int depth, const PageGeometry& page,
                              bool colors) {
  const std::vector<std::uint8_t> packed = from_base64(base64);
  std::vector<std::uint8_t> raw(count * 16 + 64);
  uLongf size = raw.size();
  EXPECT_EQ(uncompress(raw.data(), &size, packed.data(), packed.size()), Z_OK);
  raw.resize(size);
  std::size_t at = 0;
  std::vector<std::uint64_t> codes;
  std::uint64_t code = 0;
  for (std::size_t i = 0; i < count; ++i) {
    std::uint64_t delta = 0;
    for (int shift = 0;; shift += 7) {
      EXPECT_LT(at, raw.size());
      if (at >= raw.size()) return {};
      delta |= std::uint64_t(raw[at] & 0x7f) << shift;
      if (raw[at++] < 0x80) break;
    }
    code += delta;
    codes.push_back(code);
  }
  EXPECT_EQ(raw.size(), at + count + (colors ? 3 * count : 0));
  if (raw.size() != at + count + (colors ? 3 * count : 0)) return {};
  std::vector<Box> boxes;
  std::array<std::uint8_t, 3> last{};
  for (std::size_t i = 0; i < count; ++i) {
    std::array<std::int64_t, 3> key{};
    for (int axis = 0; axis < 3; ++axis) key[std::size_t(axis)] = std::int64_t(every_third_bit(codes[i] >> axis)) << depth;
    std::uint32_t rgb = 0;
    if (colors) {
      std::array<std::uint32_t, 3> c{};
      for (std::size_t channel = 0; channel < 3; ++channel) {
        last[channel] = static_cast<std::uint8_t>(last[channel] + raw[at + count + channel * count + i]);
        c[channel] = last[channel];
      }
      rgb = ((((c[0] << 3) | (c[0] >> 2)) << 16) | (((c[1] << 2) | (c[1] >> 4)) << 8) | ((c[2] << 3) | (c[2] >> 2)));
    }
    boxes.push_back(box_of(key, std::int64_t{1} << (depth + raw[at + i]), page, rgb));
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

  // The numbers: the known space's lowest finest key and its size in voxels.
  std::smatch found;
  ASSERT_TRUE(std::regex_search(
      page, found,
      std::regex(R"re("format": 2, "origin": \[(\d+), (\d+), (\d+)\], "size": \[(\d+), (\d+), (\d+)\])re")));
  const OccupancyMap map = load_map(map_path);
  const MapStatistics stats = compute_statistics(map);
  const Key origin = map.key(stats.known_min + Vec3d{0.1, 0.1, 0.1});
  const Key end = map.key(stats.known_max - Vec3d{0.1, 0.1, 0.1});
  PageGeometry geometry;
  for (int axis = 0; axis < 3; ++axis) {
    geometry.origin[std::size_t(axis)] = std::stoll(found[1 + axis]);
    geometry.size[std::size_t(axis)] = std::stoll(found[4 + axis]);
    EXPECT_EQ(geometry.origin[std::size_t(axis)], origin[axis]);
    EXPECT_EQ(geometry.size[std::size_t(axis)], std::int64_t(end[axis]) - origin[axis] + 1);
  }

  // Every layer the page lists, against the library's nodes.
  const std::regex layer_entry(R"re(\{"depth": (\d+), "state": "(\w+)", "count": (\d+)(, "id": "(layer-\d+)")?\})re");
  std::size_t layers = 0;
  std::size_t layer_text = 0;
  std::size_t layer_nodes = 0;
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
    const bool colors = state == "occupied";
    const std::vector<Box> decoded = decode_layer(base64, count, depth, geometry, colors);
    layer_text += base64.size();
    layer_nodes += count;

    std::vector<Box> expected;
    for (const Node& node : map.query(predicate, depth)) {
      const std::array<std::int64_t, 3> key{node.key.x, node.key.y, node.key.z};
      const std::uint32_t rgb = colors ? as_shown(node.color.value_or(Rgb{150, 150, 150})) : 0;
      expected.push_back(box_of(key, std::int64_t{1} << node.depth, geometry, rgb));
    }
    std::sort(expected.begin(), expected.end());
    EXPECT_EQ(decoded, expected) << state << " at depth " << depth;
    ++layers;
  }
  EXPECT_EQ(depths.size(), 8u);  // the finest depth and seven coarser
  EXPECT_EQ(layers, 3 * depths.size());
  // Size: the layers' base64 text per node, over every layer. The format of
  // viewer_data.hpp (sorted code deltas, 5-6-5 colors) takes 0.89 bytes
  // here; the previous one (six 16-bit columns, 8-bit colors) took 1.78.
  EXPECT_LE(double(layer_text) / double(layer_nodes), 1.0) << layer_text << " bytes for " << layer_nodes << " nodes";
}

TEST(ViewCli, DeepMapsStartAtTheDepthTheirCodesFit) {
  // 21 depth levels: keys of 21 bits, more than the page's 17 per axis.
  const auto dir = test::scratch_dir();
  OccupancyMap deep(0.1, 21);
  deep.set_log_odds(Vec3d{0.05, 0.05, 0.05}, 2.0f);
  deep.set_log_odds(Vec3d{3.05, 1.05, 0.05}, -2.0f);
  save_map(deep, dir / "deep.umb");
  const CommandResult view = test::run_command(cli() + " view " + quoted(dir / "deep.umb") + " -o " + quoted(dir / "deep.html"));
  if (view.exit_code == 1 && view.output.find("built without the browser viewer") != std::string::npos) {
    GTEST_SKIP() << view.output;
  }
  ASSERT_EQ(view.exit_code, 0) << view.output;
  EXPECT_NE(view.output.find("a map of 21 depth levels starts at depth 4"), std::string::npos) << view.output;
  const std::vector<std::uint8_t> bytes = test::read_bytes(dir / "deep.html");
  EXPECT_NE(std::string(bytes.begin(), bytes.end()).find("\"finestDepth\": 4,"), std::string::npos);
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
