// A procedural industrial plant: the world of the exploration study
// (docs/exploration.md), in the spirit of the power plant of the UFOMap
// paper's case study.
//
// The building spans x in [0, 40], y in [0, 30], z in [0, 12] (0.3 m outer
// walls, a floor slab below z = 0 and a roof above z = 12) and holds three
// connected halls:
//  - hall A, the west third (x < 14): full height, with a mezzanine at 6 m
//    over its southern part (y < 10), reached by a stair along the west wall
//    and open to the north over a railing;
//  - hall B, south-east (x > 14.3, y < 16): two storeys, the floor between
//    them at 6 m with a hatch and a stairwell;
//  - hall C, north-east (x > 14.3, y > 16.3): full height, with tanks
//    (vertical cylinders), a pipe rack, and a gallery at 6 m along its south
//    wall.
// Doors (2.5 m wide) join A and B and B and C on both levels, and A and C on
// the ground. Every hall holds seeded clutter: machines, crates, shelving,
// cabinets, horizontal and vertical pipes, cable trays, railings with posts.
// The layout of the halls, doors and openings is fixed; the seed places the
// clutter, tanks and pipes (never in the doors, stairwells or hatches, or at
// the start), so every seed gives a building explorable by a flying robot of
// radius 0.3 m from `start`. Same seed, same scene, with every compiler (the
// numbers come from std::mt19937 bits through our own mapping).
//
// Cost: about 900 primitives (a third of them pipes), built in about two
// milliseconds.
#pragma once

#include <cstdint>

#include "umbra/core/vec3.hpp"
#include "umbra/sim/scene.hpp"

namespace umbra::sim {

struct IndustrialPlant {
  Scene scene;
  /// Where a robot starts: hall A, on the ground level, 1.5 m up, at least
  /// 1.5 m from every surface.
  Vec3d start;
  /// The inside of the building (between the walls, floor and roof): where
  /// a robot may fly.
  Box interior;
};

IndustrialPlant make_industrial_scene(std::uint32_t seed = 1);

}  // namespace umbra::sim
