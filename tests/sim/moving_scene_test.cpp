// MovingScene: people and doors where their motion puts them at a time,
// and a map of a depth camera watching a person walk away, whose voxels the
// camera then sees free again.
#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

#include "umbra/map/occupancy_map.hpp"
#include "umbra/sim/depth_camera.hpp"
#include "umbra/sim/moving_scene.hpp"

namespace umbra::sim {
namespace {

TEST(MovingScene, WalkersGoBackAndForthAndDoorsSlideOpen) {
  const MovingScene scene = make_demo_moving_scene();
  ASSERT_EQ(scene.walkers().size(), 1u);
  ASSERT_EQ(scene.doors().size(), 1u);
  const Walker& w = scene.walkers()[0];
  const double length = std::hypot(w.to.x - w.from.x, w.to.y - w.from.y);
  const double there = length / w.speed;  // seconds to walk it once
  for (const double t : {0.0, 0.3 * there, there, 1.6 * there, 2.0 * there, 7.25 * there}) {
    // Folded by hand: t mod 2 there, then back from `to` in the second half.
    const double phase = std::fmod(t, 2.0 * there) / there;
    const double share = phase <= 1.0 ? phase : 2.0 - phase;
    const Vec3d want = w.from + (w.to - w.from) * share;
    const Vec3d got = scene.walker_position(0, t);
    EXPECT_NEAR(got.x, want.x, 1e-9) << "t " << t;
    EXPECT_NEAR(got.y, want.y, 1e-9) << "t " << t;
    // The scene of that moment holds the person there (and the still scene does not).
    const Scene now = scene.at(t);
    EXPECT_TRUE(now.is_inside_solid({got.x, got.y, 1.0})) << "t " << t;
    EXPECT_TRUE(now.is_inside_solid({got.x + 0.9 * w.radius, got.y, 1.7})) << "t " << t;
    EXPECT_FALSE(now.is_inside_solid({got.x + 1.1 * w.radius, got.y, 1.0})) << "t " << t;
    EXPECT_FALSE(now.is_inside_solid({got.x, got.y, w.height + 0.05})) << "t " << t;
    EXPECT_FALSE(scene.still().is_inside_solid({got.x, got.y, 1.0})) << "t " << t;
  }
  // The door: closed until it starts to open, half way in the middle, open after.
  const SlidingDoor& d = scene.doors()[0];
  const Vec3d middle = (d.closed.min + d.closed.max) * 0.5;
  EXPECT_TRUE(scene.at(d.open_start).is_inside_solid(middle));
  EXPECT_FALSE(scene.at(d.open_end + 1.0).is_inside_solid(middle));
  EXPECT_TRUE(scene.at(d.open_end + 1.0).is_inside_solid(middle + d.offset));
  const Box half = scene.door_box(0, 0.5 * (d.open_start + d.open_end));
  EXPECT_NEAR(half.min.x, d.closed.min.x + 0.5 * d.offset.x, 1e-12);
  EXPECT_NEAR(half.max.x, d.closed.max.x + 0.5 * d.offset.x, 1e-12);
}

TEST(MovingScene, BadObjectsAndTimesAreRefused) {
  MovingScene scene;
  EXPECT_THROW(scene.add_walker({{1, 1, 0}, {1, 1, 0}}), std::invalid_argument);            // nowhere to walk
  EXPECT_THROW(scene.add_walker({{0, 0, 0}, {1, 0, 0}, 0.0}), std::invalid_argument);       // no speed
  EXPECT_THROW(scene.add_walker({{0, 0, 0}, {1, 0, 0}, 1.0, -0.1}), std::invalid_argument);  // no radius
  EXPECT_THROW(scene.add_walker({{0, 0, NAN}, {1, 0, 0}}), std::invalid_argument);
  EXPECT_THROW(scene.add_door({{{0, 0, 0}, {1, 1, 1}}, {1, 0, 0}, 2.0, 1.0}), std::invalid_argument);  // ends first
  EXPECT_THROW(scene.add_door({{{0, 0, 0}, {0, 1, 1}}, {1, 0, 0}, 0.0, 1.0}), std::invalid_argument);  // flat box
  scene.add_walker({{0, 0, 0}, {1, 0, 0}});
  EXPECT_THROW((void)scene.at(-1.0), std::invalid_argument);
  EXPECT_THROW((void)scene.walker_position(1, 0.0), std::out_of_range);
  EXPECT_TRUE(scene.at(0.0).is_inside_solid({0.0, 0.0, 1.0}));
}

TEST(MovingScene, APersonWhoWalksOnIsSeenFreeAgain) {
  // A camera at the west end of the corridor looks east; a person crosses
  // the corridor 3 m ahead of it and walks on to its north side.
  MovingScene scene(make_demo_scene());
  scene.add_walker({{4.0, 5.35, 0.0}, {4.0, 6.65, 0.0}, 0.325, 0.25, 1.75});  // 4 s to cross
  const CameraPose camera{{1.0, 6.0, 1.2}, 0.0, 0.0};
  const DepthCameraModel model;
  OccupancyMap map(0.05);
  InsertOptions options;
  options.integrator = IntegratorKind::projective;
  options.max_range = model.max_range;
  const auto look = [&](double time) {
    const SimulatedDepthImage frame = simulate_depth_frame(scene.at(time), camera, model);
    map.insert_depth_image(frame.view(), frame.camera, frame.pose, {}, options);
  };
  // The side of the person that faces the camera, where it stands at first.
  const Vec3d face{4.0 - 0.25 + 0.01, 5.35, 1.2};
  for (const double t : {0.0, 0.02, 0.04}) look(t);
  EXPECT_EQ(map.state(face), OccupancyState::occupied);
  // Four seconds later the person stands on the corridor's far side, and the
  // camera sees the corridor behind where it stood: free after enough misses.
  for (int i = 0; i < 8; ++i) look(3.9 + 0.01 * i);
  EXPECT_EQ(map.state(face), OccupancyState::free);
  // And where the person stands now is occupied.
  const Vec3d now = scene.walker_position(0, 3.97);
  EXPECT_EQ(map.state({now.x - 0.25 + 0.01, now.y, 1.2}), OccupancyState::occupied);
}

}  // namespace
}  // namespace umbra::sim
