// Tests of the top-down map picture and the PNG reader/writer.
#include "umbra/io/topdown_image.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "support/test_support.hpp"
#include "umbra/io/png_writer.hpp"
#include "umbra/map/occupancy_map.hpp"
#include "umbra/sim/lidar.hpp"
#include "umbra/sim/scene.hpp"
#include "support/demo_maps.hpp"

namespace umbra {
namespace {

namespace fs = std::filesystem;

constexpr double kResolution = 0.1;
constexpr float kFree = -1.0f;
constexpr float kOccupied = 2.0f;

/// Centre of the voxel with indices (i, j, k) counted from the map origin.
Vec3d voxel(int i, int j, int k) {
  return {(i + 0.5) * kResolution, (j + 0.5) * kResolution, (k + 0.5) * kResolution};
}

void set_node(OccupancyMap& map, int i0, int j0, int k0, float log_odds) {
  // The 8 voxels of the depth-1 node whose first voxel is (i0, j0, k0) (all even).
  for (int di = 0; di < 2; ++di) {
    for (int dj = 0; dj < 2; ++dj) {
      for (int dk = 0; dk < 2; ++dk) map.set_log_odds(voxel(i0 + di, j0 + dj, k0 + dk), log_odds);
    }
  }
}

/// A hand-made map over voxel columns i in [0, 7], j in [0, 1]:
///  A  (0..1, 0..1)      a free depth-1 node (8 equal voxels, pruned into one leaf)
///  B  (3, 0)            one occupied voxel at k = 0 (z 0.05, the lowest top)
///  C  (3, 1)            one occupied voxel at k = 10 (z 1.05, the highest top)
///  E  (4, 0)            free at k = 0 under an occupied voxel at k = 5 (z 0.55)
///  F  (6..7, 0..1)      an occupied depth-1 node at k = 2..3 (top z 0.35)
/// Columns (2, *), (5, *) and (4, 1) stay unknown.
OccupancyMap hand_made_map() {
  OccupancyMap map(kResolution);
  set_node(map, 0, 0, 0, kFree);
  map.set_log_odds(voxel(3, 0, 0), kOccupied);
  map.set_log_odds(voxel(3, 1, 10), kOccupied);
  map.set_log_odds(voxel(4, 0, 0), kFree);
  map.update_hit(voxel(4, 0, 5));
  set_node(map, 6, 0, 2, kOccupied);
  return map;
}

const Rgb kFreeGrey = TopdownOptions{}.free_color;
const Rgb kUnknownDark = TopdownOptions{}.unknown_color;

std::string text(Rgb c) {
  return "(" + std::to_string(c.r) + ", " + std::to_string(c.g) + ", " + std::to_string(c.b) + ")";
}

TEST(TopdownImage, HandMadeMapHasThePrunedNodesItIsMeantToHave) {
  const OccupancyMap map = hand_made_map();
  int depth_one_leaves = 0;
  map.for_each_leaf([&](const Node& leaf) {
    if (leaf.depth == 1 && leaf.state != OccupancyState::unknown) ++depth_one_leaves;
  });
  EXPECT_EQ(depth_one_leaves, 2);  // A and F: the renderer must handle inner leaves
}

TEST(TopdownImage, RampEndsAreTheDocumentedColors) {
  EXPECT_EQ(height_ramp(0.0), (Rgb{48, 64, 200}));
  EXPECT_EQ(height_ramp(0.5), (Rgb{60, 180, 75}));
  EXPECT_EQ(height_ramp(1.0), (Rgb{215, 48, 39}));
  EXPECT_EQ(height_ramp(-3.0), height_ramp(0.0));
  EXPECT_EQ(height_ramp(7.0), height_ramp(1.0));
  EXPECT_EQ(height_ramp(0.125), (Rgb{24, 117, 205}));  // half way from blue to cyan
}

TEST(TopdownImage, HandPlacedVoxelsGiveExpectedPixels) {
  const OccupancyMap map = hand_made_map();
  const Image image = render_topdown(map);  // margin 2
  ASSERT_EQ(image.width, 8 + 4);
  ASSERT_EQ(image.height, 2 + 4);
  EXPECT_EQ(image.depth, 0);
  EXPECT_DOUBLE_EQ(image.metres_per_pixel, kResolution);
  EXPECT_NEAR(image.left_x, -0.2, 1e-12);
  EXPECT_NEAR(image.top_y, 0.4, 1e-12);

  // Column i, row j of the map -> pixel: x to the right, y up (row 0 north).
  auto at = [&](int i, int j) { return image.at(i + 2, (1 - j) + 2); };
  const Rgb low = height_ramp(0.0);   // B, z 0.05
  const Rgb high = height_ramp(1.0);  // C, z 1.05
  EXPECT_NE(low, high);
  EXPECT_EQ(at(3, 0), low) << text(at(3, 0));
  EXPECT_EQ(at(3, 1), high) << text(at(3, 1));
  EXPECT_EQ(at(4, 0), height_ramp((0.55 - 0.05) / 1.0));  // E: occupied wins over free
  EXPECT_EQ(at(4, 0), (Rgb{60, 180, 75}));
  for (int i : {6, 7}) {
    for (int j : {0, 1}) EXPECT_EQ(at(i, j), height_ramp((0.35 - 0.05) / 1.0)) << i << "," << j;
  }
  for (int i : {0, 1}) {
    for (int j : {0, 1}) EXPECT_EQ(at(i, j), kFreeGrey) << i << "," << j;
  }
  for (const auto& [i, j] :
       std::vector<std::pair<int, int>>{{2, 0}, {2, 1}, {5, 0}, {5, 1}, {4, 1}}) {
    EXPECT_EQ(at(i, j), kUnknownDark) << i << "," << j;
  }
  // The margin is unknown all round.
  for (int column = 0; column < image.width; ++column) {
    EXPECT_EQ(image.at(column, 0), kUnknownDark);
    EXPECT_EQ(image.at(column, image.height - 1), kUnknownDark);
  }
  for (int row = 0; row < image.height; ++row) {
    EXPECT_EQ(image.at(0, row), kUnknownDark);
    EXPECT_EQ(image.at(image.width - 1, row), kUnknownDark);
  }
}

TEST(TopdownImage, FixedRampEndsAndCustomColors) {
  const OccupancyMap map = hand_made_map();
  TopdownOptions options;
  options.margin_pixels = 0;
  options.ramp_low_z = 0.05;
  options.ramp_high_z = 2.05;
  options.free_color = {1, 2, 3};
  options.unknown_color = {4, 5, 6};
  const Image image = render_topdown(map, options);
  ASSERT_EQ(image.width, 8);
  ASSERT_EQ(image.height, 2);
  EXPECT_EQ(image.at(3, 1), height_ramp(0.0));  // B
  EXPECT_EQ(image.at(3, 0), height_ramp(0.5));  // C: (1.05 - 0.05) / 2
  EXPECT_EQ(image.at(0, 0), (Rgb{1, 2, 3}));
  EXPECT_EQ(image.at(2, 0), (Rgb{4, 5, 6}));
}

TEST(TopdownImage, CoarserDepthWhenTooLarge) {
  const OccupancyMap map = hand_made_map();
  TopdownOptions options;
  options.margin_pixels = 1;
  options.max_pixels_per_side = 6;  // 8 + 2 columns do not fit; 4 + 2 nodes of depth 1 do
  const Image image = render_topdown(map, options);
  EXPECT_EQ(image.depth, 1);
  EXPECT_DOUBLE_EQ(image.metres_per_pixel, 2 * kResolution);
  ASSERT_EQ(image.width, 6);
  ASSERT_EQ(image.height, 3);
  EXPECT_NEAR(image.left_x, -0.2, 1e-12);
  EXPECT_NEAR(image.top_y, 0.4, 1e-12);
  // Node columns: 0 = A (free), 1 = B, C and unknown (top C), 2 = E (top 0.55),
  // 3 = F (top 0.35, the lowest top now).
  EXPECT_EQ(image.at(1, 1), kFreeGrey);
  EXPECT_EQ(image.at(2, 1), height_ramp(1.0));
  EXPECT_EQ(image.at(3, 1), height_ramp((0.55 - 0.35) / (1.05 - 0.35)));
  EXPECT_EQ(image.at(4, 1), height_ramp(0.0));
  EXPECT_EQ(image.at(0, 1), kUnknownDark);
  EXPECT_EQ(image.at(1, 0), kUnknownDark);

  options.max_pixels_per_side = 3;  // everything in one pixel: the root's children merge
  const Image tiny = render_topdown(map, options);
  EXPECT_EQ(tiny.width, 3);
  EXPECT_EQ(tiny.height, 3);
  EXPECT_EQ(tiny.at(1, 1), height_ramp(0.0));  // one occupied pixel: low == high gives t = 0
}

TEST(TopdownImage, HeightWindowIgnoresVoxelsOutsideIt) {
  const OccupancyMap map = hand_made_map();
  TopdownOptions options;
  options.margin_pixels = 0;
  options.max_z = 0.9;  // drops C (z 1.05)
  const Image image = render_topdown(map, options);
  ASSERT_EQ(image.width, 8);
  EXPECT_EQ(image.at(3, 0), kUnknownDark);      // C's column had nothing else
  EXPECT_EQ(image.at(4, 1), height_ramp(1.0));  // E is now the highest top

  options.min_z = 0.3;  // keeps only voxels at k = 3: F's upper half
  options.max_z = 0.4;
  const Image slice = render_topdown(map, options);
  // Only F (k = 2..3, centres 0.25 and 0.35) remains: F's top within the window is 0.35.
  EXPECT_EQ(slice.width, 2);
  EXPECT_EQ(slice.height, 2);
  EXPECT_NEAR(slice.left_x, 0.6, 1e-12);

  options.min_z = 5.0;
  options.max_z = 6.0;
  try {
    (void)render_topdown(map, options);
    ADD_FAILURE() << "an empty window was accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("no known voxel"), std::string::npos) << error.what();
  }
}

TEST(TopdownImage, EmptyMapIsRejected) {
  const OccupancyMap map(0.1);
  EXPECT_THROW((void)render_topdown(map), std::invalid_argument);
}

TEST(TopdownImage, BadOptionsAreNamed) {
  const OccupancyMap map = hand_made_map();
  auto expect_named = [&](const TopdownOptions& options, const std::string& field) {
    try {
      (void)render_topdown(map, options);
      ADD_FAILURE() << "accepted a bad " << field;
    } catch (const std::invalid_argument& error) {
      EXPECT_NE(std::string(error.what()).find(field), std::string::npos) << error.what();
    }
  };
  TopdownOptions options;
  options.margin_pixels = -1;
  expect_named(options, "margin_pixels");
  options = {};
  options.max_pixels_per_side = 4;  // less than 2 * 2 + 1
  expect_named(options, "max_pixels_per_side");
  options = {};
  options.min_z = 1.0;
  options.max_z = 0.0;
  expect_named(options, "max_z");
  options = {};
  options.ramp_low_z = 1.0;
  options.ramp_high_z = 1.0;
  expect_named(options, "ramp_high_z");
}

/// A slow reference: the color of one pixel of a depth-0 picture from
/// per-voxel state() queries.
Rgb reference_pixel(const OccupancyMap& map, const Image& image, const TopdownOptions& options,
                    int column, int row) {
  const double x = image.left_x + (column + 0.5) * image.metres_per_pixel;
  const double y = image.top_y - (row + 0.5) * image.metres_per_pixel;
  bool any_free = false;
  const double res = map.resolution();
  // Voxel k (counted from the map origin) has its centre at (k + 0.5) * res.
  for (auto k = std::int64_t(std::floor(*options.max_z / res));
       k >= std::int64_t(std::floor(*options.min_z / res)) - 1; --k) {
    const double centre = (double(k) + 0.5) * res;
    if (centre > *options.max_z || centre < *options.min_z) continue;
    const OccupancyState state = map.state({x, y, centre});
    if (state == OccupancyState::occupied) {
      return height_ramp((centre - *options.ramp_low_z) /
                         (*options.ramp_high_z - *options.ramp_low_z));
    }
    any_free = any_free || state == OccupancyState::free;
  }
  return any_free ? options.free_color : options.unknown_color;
}

TEST(TopdownImage, DemoSceneMapMatchesPerVoxelReference) {
  MapConfig config;
  config.resolution = kResolution;
  const OccupancyMap map = test::demo_lidar_map(config);
  TopdownOptions options;
  // Window limits between voxel centres, so that no centre lies on a limit.
  options.min_z = -0.22;  // the top of the floor slab
  options.max_z = 2.78;   // below the ceiling
  options.ramp_low_z = 0.0;
  options.ramp_high_z = 2.8;
  const Image image = render_topdown(map, options);
  EXPECT_EQ(image.depth, 0);
  // The building (20 m x 12 m at 0.1 m) fits inside the picture, margins included.
  EXPECT_LE(image.width, 200 + 4 + 2);
  EXPECT_LE(image.height, 120 + 4 + 2);
  EXPECT_GE(image.width, 100);

  std::size_t mismatches = 0;
  for (int row = 0; row < image.height; ++row) {
    for (int column = 0; column < image.width; ++column) {
      const Rgb expected = reference_pixel(map, image, options, column, row);
      if (image.at(column, row) != expected && ++mismatches < 5) {
        ADD_FAILURE() << "pixel (" << column << ", " << row << ") is "
                      << text(image.at(column, row)) << ", expected " << text(expected);
      }
    }
  }
  EXPECT_EQ(mismatches, 0u);

  // A picture with all three kinds of column and walls of many heights.
  std::size_t free = 0;
  std::size_t unknown = 0;
  std::vector<Rgb> occupied_colors;
  for (int row = 0; row < image.height; ++row) {
    for (int column = 0; column < image.width; ++column) {
      const Rgb c = image.at(column, row);
      if (c == options.free_color) {
        ++free;
      } else if (c == options.unknown_color) {
        ++unknown;
      } else if (std::find(occupied_colors.begin(), occupied_colors.end(), c) ==
                 occupied_colors.end()) {
        occupied_colors.push_back(c);
      }
    }
  }
  EXPECT_GT(free, 0u);
  EXPECT_GT(unknown, std::size_t(2 * (image.width + image.height)));  // at least the margin
  EXPECT_GE(occupied_colors.size(), 10u);

  // Kept in the scratch folder for a human look.
  write_png(image, umbra::test::scratch_dir() / "demo_topdown.png");
}

// --- PNG ---------------------------------------------------------------------

Image gradient_image(int width, int height) {
  Image image(width, height);
  for (int row = 0; row < height; ++row) {
    for (int column = 0; column < width; ++column) {
      image.set(
          column, row,
          {std::uint8_t(column * 7), std::uint8_t(row * 11), std::uint8_t((column * row) ^ 0x5a)});
    }
  }
  return image;
}

/// Incompressible content, so that its PNG file is large.
Image noise_image(int width, int height) {
  Image image(width, height);
  std::uint32_t state = 12345;
  for (auto& byte : image.rgb) {
    state = state * 1664525u + 1013904223u;
    byte = std::uint8_t(state >> 24);
  }
  return image;
}

std::vector<fs::path> files_in(const fs::path& folder) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(folder)) files.push_back(entry.path().filename());
  return files;
}

TEST(TopdownPng, WriteThenReadGivesTheSamePixels) {
  const fs::path folder = umbra::test::scratch_dir();
  const Image picture = render_topdown(hand_made_map());
  write_png(picture, folder / "map.png");
  const Image back = read_png(folder / "map.png");
  EXPECT_EQ(back.width, picture.width);
  EXPECT_EQ(back.height, picture.height);
  EXPECT_EQ(back.rgb, picture.rgb);

  const Image gradient = gradient_image(37, 23);
  write_png(gradient, folder / "gradient.png");
  const Image gradient_back = read_png(folder / "gradient.png");
  EXPECT_EQ(gradient_back.width, 37);
  EXPECT_EQ(gradient_back.height, 23);
  EXPECT_EQ(gradient_back.rgb, gradient.rgb);
  // Only the two pictures: no temporary files left behind.
  EXPECT_EQ(files_in(folder).size(), 2u);

  // Overwriting an existing file replaces it.
  write_png(picture, folder / "gradient.png");
  EXPECT_EQ(read_png(folder / "gradient.png").rgb, picture.rgb);
  EXPECT_EQ(files_in(folder).size(), 2u);
}

TEST(TopdownPng, MissingFolderThrowsWithThePathAndLeavesNothing) {
  const fs::path folder = umbra::test::scratch_dir();
  const fs::path target = folder / "no_such_folder" / "map.png";
  try {
    write_png(gradient_image(4, 4), target);
    ADD_FAILURE() << "wrote into a missing folder";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find(target.string()), std::string::npos) << error.what();
  }
  EXPECT_FALSE(fs::exists(folder / "no_such_folder"));
  EXPECT_TRUE(files_in(folder).empty());
}

TEST(TopdownPng, BadImagesAreRejectedAndTheOldFileSurvives) {
  const fs::path folder = umbra::test::scratch_dir();
  const fs::path target = folder / "map.png";
  const Image original = gradient_image(5, 3);
  write_png(original, target);

  Image wrong_size = gradient_image(5, 3);
  wrong_size.rgb.pop_back();
  EXPECT_THROW(write_png(wrong_size, target), std::invalid_argument);
  EXPECT_THROW(write_png(Image{}, target), std::invalid_argument);
  EXPECT_THROW(Image(0, 3), std::invalid_argument);
  EXPECT_THROW((void)original.at(5, 0), std::out_of_range);
  EXPECT_EQ(read_png(target).rgb, original.rgb);
  EXPECT_EQ(files_in(folder).size(), 1u);
}

/// Lowers this process's file size limit (and ignores SIGXFSZ, so writes past
/// it fail with EFBIG instead of killing the process) until destroyed.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    ::getrlimit(RLIMIT_FSIZE, &saved_);
    previous_handler_ = std::signal(SIGXFSZ, SIG_IGN);
    rlimit lowered = saved_;
    lowered.rlim_cur = bytes;
    ok_ = ::setrlimit(RLIMIT_FSIZE, &lowered) == 0;
  }
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;
  ~FileSizeLimit() {
    ::setrlimit(RLIMIT_FSIZE, &saved_);
    std::signal(SIGXFSZ, previous_handler_);
  }
  [[nodiscard]] bool ok() const { return ok_; }

 private:
  rlimit saved_{};
  void (*previous_handler_)(int) = nullptr;
  bool ok_ = false;
};

TEST(TopdownPng, FailedWriteLeavesTheExistingFileAndNoTemporary) {
  const fs::path folder = umbra::test::scratch_dir();
  const fs::path target = folder / "map.png";
  const Image original = gradient_image(8, 8);
  write_png(original, target);
  const auto original_size = fs::file_size(target);

  const Image big = noise_image(128, 128);  // about 48 KiB of PNG
  {
    FileSizeLimit limit(4096);  // the write fails part way through
    ASSERT_TRUE(limit.ok());
    try {
      write_png(big, target);
      ADD_FAILURE() << "the write past the file size limit succeeded";
    } catch (const std::runtime_error& error) {
      EXPECT_NE(std::string(error.what()).find(target.string()), std::string::npos) << error.what();
    }
  }
  EXPECT_EQ(fs::file_size(target), original_size);
  EXPECT_EQ(read_png(target).rgb, original.rgb);
  EXPECT_EQ(files_in(folder), std::vector<fs::path>{"map.png"});

  // With the limit gone the same write works.
  write_png(big, target);
  EXPECT_EQ(read_png(target).rgb, big.rgb);
}

TEST(TopdownPng, TargetThatIsAFolderFailsCleanly) {
  const fs::path folder = umbra::test::scratch_dir();
  const fs::path target = folder / "taken";
  fs::create_directories(target / "inside");
  EXPECT_THROW(write_png(gradient_image(4, 4), target), std::runtime_error);
  EXPECT_TRUE(fs::is_directory(target / "inside"));
  EXPECT_EQ(files_in(folder), std::vector<fs::path>{"taken"});
}

TEST(TopdownPng, ReadErrorsNameTheFile) {
  const fs::path folder = umbra::test::scratch_dir();
  auto expect_named_error = [](const fs::path& path) {
    try {
      (void)read_png(path);
      ADD_FAILURE() << "read " << path;
    } catch (const std::runtime_error& error) {
      EXPECT_NE(std::string(error.what()).find(path.string()), std::string::npos) << error.what();
    }
  };
  expect_named_error(folder / "missing.png");
  { std::ofstream(folder / "text.png") << "this is not a PNG file\n"; }
  expect_named_error(folder / "text.png");
  // A PNG cut short.
  write_png(gradient_image(30, 30), folder / "whole.png");
  {
    std::ifstream in(folder / "whole.png", std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(folder / "cut.png", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  }
  expect_named_error(folder / "cut.png");
}

}  // namespace
}  // namespace umbra
