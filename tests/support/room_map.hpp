// A closed room written voxel by voxel, the indoor map the render tests cut:
// 4 x 3 x 2.5 m at 10 cm (voxels i in [0, 40), j in [0, 30), k in [0, 25)),
// occupied floor (k = 0), ceiling (k = 24) and walls, a table top at
// k = 7 over i in [10, 20), j in [10, 15), and free space everywhere else
// inside, as a sensor in the room would leave it. Outside is unknown.
#pragma once

#include "umbra/core/vec3.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra::test {

inline constexpr double kRoomResolution = 0.1;

/// Centre of room voxel (i, j, k).
inline Vec3d room_voxel(int i, int j, int k) {
  return {(i + 0.5) * kRoomResolution, (j + 0.5) * kRoomResolution, (k + 0.5) * kRoomResolution};
}

inline bool room_table(int i, int j, int k) { return k == 7 && i >= 10 && i < 20 && j >= 10 && j < 15; }

/// The room above; without `ceiling` its top layer is left unknown (an open box).
inline OccupancyMap closed_room_map(bool ceiling = true) {
  OccupancyMap map(kRoomResolution);
  for (int i = 0; i < 40; ++i) {
    for (int j = 0; j < 30; ++j) {
      for (int k = 0; k < 25; ++k) {
        const bool shell = i == 0 || i == 39 || j == 0 || j == 29 || k == 0 || k == 24;
        if (k == 24 && !ceiling && !(i == 0 || i == 39 || j == 0 || j == 29)) continue;
        map.set_log_odds(room_voxel(i, j, k), shell || room_table(i, j, k) ? 2.0f : -2.0f);
      }
    }
  }
  return map;
}

}  // namespace umbra::test
