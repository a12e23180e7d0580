// MovingScene: a scene whose obstacles move, for maps that must forget.
//
// A still Scene (scene.hpp) plus objects that move with time: people
// walking back and forth along a segment (vertical cylinders) and sliding
// doors that open (boxes moved by an offset over an interval). at(t) is the
// plain Scene of that moment, which the simulated sensors take as they are;
// a sequence of depth images or scans at increasing times then shows
// obstacles appearing, moving on and leaving space behind that the sensor
// sees free again (the decay and merging of docs/design.md are tested and
// shown with it).
//
// Time is in seconds from 0; positions are exact functions of it, so the
// same time gives the same scene (tests compare against them).
#pragma once

#include <vector>

#include "umbra/sim/scene.hpp"

namespace umbra::sim {

/// A person: a vertical cylinder of `radius` from the floor (`from.z`) up
/// to `height`, walking from `from` to `to` at `speed` m/s, then back, and
/// so on (only x and y of `to` are used).
struct Walker {
  Vec3d from;
  Vec3d to;
  double speed = 1.2;
  double radius = 0.25;
  double height = 1.75;
};

/// A door that slides open: the box `closed` until `open_start`, moved by
/// `offset` at `open_end` and after, linearly in between.
struct SlidingDoor {
  Box closed;
  Vec3d offset;
  double open_start = 0.0;
  double open_end = 1.0;
};

class MovingScene {
 public:
  explicit MovingScene(Scene still = {});

  /// Throws std::invalid_argument for non-finite values, a speed, radius or
  /// height <= 0, from == to (in x and y), or open_end < open_start.
  void add_walker(const Walker& walker);
  void add_door(const SlidingDoor& door);

  [[nodiscard]] const Scene& still() const { return still_; }
  [[nodiscard]] const std::vector<Walker>& walkers() const { return walkers_; }
  [[nodiscard]] const std::vector<SlidingDoor>& doors() const { return doors_; }

  /// Where walker `index`'s axis stands at `time` (its foot point). Throws
  /// std::out_of_range for a bad index, std::invalid_argument for a
  /// negative or non-finite time.
  [[nodiscard]] Vec3d walker_position(std::size_t index, double time) const;
  /// Door `index`'s box at `time` (throws as walker_position).
  [[nodiscard]] Box door_box(std::size_t index, double time) const;

  /// The still scene with every moving object where it is at `time`.
  [[nodiscard]] Scene at(double time) const;

 private:
  Scene still_;
  std::vector<Walker> walkers_;
  std::vector<SlidingDoor> doors_;
};

/// make_demo_scene() with a person walking along the corridor (from x = 4
/// to x = 12 at y = 6.0) and the door of the middle north room (x in [9.5,
/// 10.5] at y = 7) closed by a sliding door that opens between 4 s and 6 s.
MovingScene make_demo_moving_scene();

}  // namespace umbra::sim
