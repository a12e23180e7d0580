// Tests of the default cuts of views (render_cuts.hpp) on a room written
// voxel by voxel (support/room_map.hpp), whose ceiling, floor and middle are
// known by construction, and of what a top view of it shows once cut.
#include "umbra/io/render_cuts.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "support/room_map.hpp"
#include "umbra/io/map_render.hpp"
#include "umbra/io/topdown_image.hpp"

namespace umbra {
namespace {

using test::closed_room_map;
using test::room_voxel;

Rgb pixel_at(const MapPicture& picture, Vec3d p) {
  const auto [x, y] = picture.camera.pixel(p);
  return picture.image.at(static_cast<int>(std::floor(x)), static_cast<int>(std::floor(y)));
}

TEST(RenderCuts, FindTheRoomsCeilingAndFloor) {
  const OccupancyMap room = closed_room_map();
  const auto ceiling = find_ceiling(room);
  ASSERT_TRUE(ceiling.has_value());
  EXPECT_NEAR(ceiling->underside_z, 2.4, 1e-9);  // the bottom of layer k = 24
  EXPECT_NEAR(ceiling->max_z, 2.35, 1e-9);       // the centre of layer k = 23
  const auto floor = find_floor(room);
  ASSERT_TRUE(floor.has_value());
  EXPECT_NEAR(floor->top_z, 0.1, 1e-9);  // the top of layer k = 0
  EXPECT_NEAR(floor->min_z, 0.15, 1e-9);
  // At depth 1 (20 cm layers) the ceiling is layer 12 (z 2.4 to 2.6).
  const auto coarse = find_ceiling(room, 1);
  ASSERT_TRUE(coarse.has_value());
  EXPECT_NEAR(coarse->underside_z, 2.4, 1e-9);
  EXPECT_NEAR(coarse->max_z, 2.3, 1e-9);
}

TEST(RenderCuts, AnOpenRoomOrAFewLintelsHaveNoCeiling) {
  OccupancyMap open = closed_room_map(false);
  EXPECT_FALSE(find_ceiling(open).has_value());
  EXPECT_TRUE(find_floor(open).has_value());
  // A lintel of ten voxels over free space: far under 1% of the occupied cells.
  for (int i = 10; i < 20; ++i) {
    open.set_log_odds(room_voxel(i, 15, 21), 2.0f);
    open.set_log_odds(room_voxel(i, 15, 20), -2.0f);
  }
  EXPECT_FALSE(find_ceiling(open).has_value());
  EXPECT_FALSE(find_ceiling(OccupancyMap(0.1)).has_value());
  EXPECT_FALSE(find_floor(OccupancyMap(0.1)).has_value());
  EXPECT_THROW((void)find_ceiling(open, 17), std::invalid_argument);
}

TEST(RenderCuts, MiddleSectionIsTheCentreOfTheMiddleLayer) {
  const OccupancyMap room = closed_room_map();
  // Occupied j from 0 to 29: the middle key is j = 14, its centre y = 1.45.
  EXPECT_NEAR(*middle_section(room, RenderView::front), 1.45, 1e-9);
  EXPECT_NEAR(*middle_section(room, RenderView::side), 1.95, 1e-9);  // i from 0 to 39: i = 19
  EXPECT_NEAR(*middle_section(room, RenderView::front, 2), 1.4, 1e-9);  // the 0.4 m layer 1.2..1.6
  EXPECT_FALSE(middle_section(OccupancyMap(0.1), RenderView::front).has_value());
  EXPECT_THROW((void)middle_section(room, RenderView::top), std::invalid_argument);
}

TEST(RenderCuts, TopViewOfTheRoomCutAtItsCeilingShowsTheFloorAndTheTable) {
  const OccupancyMap room = closed_room_map();
  RenderOptions options;
  options.view = RenderView::top;
  options.width = 300;
  const Vec3d floor_point = room_voxel(30, 20, 0) + Vec3d{0, 0, 0.05};  // on the floor's top face
  const Vec3d table_point = room_voxel(15, 12, 7) + Vec3d{0, 0, 0.05};
  const MapPicture uncut = render_map(room, options);
  // Top faces: 0.5 + 0.5 n.l with n = z and l = unit((0, 0, 1) + 0.8 (0, 1, 0) - 0.4 (1, 0, 0)) (map_render.hpp).
  const double shade = 0.5 + 0.5 / std::sqrt(1 + 0.64 + 0.16);
  auto shaded = [&](Rgb c) {
    return Rgb{static_cast<std::uint8_t>(std::lround(c.r * shade)), static_cast<std::uint8_t>(std::lround(c.g * shade)),
               static_cast<std::uint8_t>(std::lround(c.b * shade))};
  };
  EXPECT_EQ(pixel_at(uncut, floor_point), shaded(height_ramp(1.0))) << "without a cut the ceiling hides the room";

  options.max_z = find_ceiling(room)->max_z;
  const MapPicture cut = render_map(room, options);
  // Heights from the floor (centre 0.05) to the walls' highest kept layer (centre 2.35).
  EXPECT_NEAR(cut.ramp_low, 0.05, 1e-9);
  EXPECT_NEAR(cut.ramp_high, 2.35, 1e-9);
  EXPECT_EQ(pixel_at(cut, floor_point), shaded(height_ramp(0.0)));
  EXPECT_EQ(pixel_at(cut, table_point), shaded(height_ramp((0.75 - 0.05) / 2.3)));
  // The floor color fills the room's inside less the table.
  std::size_t floor_pixels = 0;
  for (int row = 0; row < cut.image.height; ++row) {
    for (int column = 0; column < cut.image.width; ++column) floor_pixels += cut.image.at(column, row) == shaded(height_ramp(0.0));
  }
  const double pixels_per_m2 = 1.0 / (cut.camera.metres_per_pixel * cut.camera.metres_per_pixel);
  EXPECT_NEAR(double(floor_pixels), (3.8 * 2.8 - 0.5) * pixels_per_m2, 0.03 * 3.8 * 2.8 * pixels_per_m2);

  // Colored by state and cut at the floor too: free floor space between the walls.
  options.color = RenderColor::state;
  options.min_z = find_floor(room)->min_z;
  const MapPicture state = render_map(room, options);
  EXPECT_EQ(pixel_at(state, floor_point), options.free_color);
  EXPECT_EQ(pixel_at(state, table_point), shaded(options.occupied_color));
  EXPECT_EQ(pixel_at(state, room_voxel(0, 15, 10) + Vec3d{0, 0, 1.2}), shaded(options.occupied_color)) << "a wall";
}

}  // namespace
}  // namespace umbra
