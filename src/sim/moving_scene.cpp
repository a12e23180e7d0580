#include "umbra/sim/moving_scene.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace umbra::sim {

namespace {

bool finite(Vec3d v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

void check_time(double time) {
  if (!(std::isfinite(time) && time >= 0.0)) {
    throw std::invalid_argument("MovingScene: the time must be finite and >= 0, got " + std::to_string(time));
  }
}

}  // namespace

MovingScene::MovingScene(Scene still) : still_(std::move(still)) {}

void MovingScene::add_walker(const Walker& walker) {
  const double dx = walker.to.x - walker.from.x;
  const double dy = walker.to.y - walker.from.y;
  if (!finite(walker.from) || !finite(walker.to) || !(walker.speed > 0.0) || !(walker.radius > 0.0) ||
      !(walker.height > 0.0) || !std::isfinite(walker.speed) || !std::isfinite(walker.radius) ||
      !std::isfinite(walker.height)) {
    throw std::invalid_argument("MovingScene::add_walker: finite ends, and speed, radius and height > 0 expected");
  }
  if (dx == 0.0 && dy == 0.0) throw std::invalid_argument("MovingScene::add_walker: from and to are the same point");
  walkers_.push_back(walker);
}

void MovingScene::add_door(const SlidingDoor& door) {
  if (!finite(door.closed.min) || !finite(door.closed.max) || !finite(door.offset) ||
      !std::isfinite(door.open_start) || !std::isfinite(door.open_end) || !(door.open_end >= door.open_start)) {
    throw std::invalid_argument("MovingScene::add_door: finite values and open_end >= open_start expected");
  }
  Scene check;
  check.add_box(door.closed);  // min < max on every axis, or its message
  doors_.push_back(door);
}

Vec3d MovingScene::walker_position(std::size_t index, double time) const {
  check_time(time);
  const Walker& w = walkers_.at(index);
  const Vec3d along{w.to.x - w.from.x, w.to.y - w.from.y, 0.0};
  const double length = std::hypot(along.x, along.y);
  // Back and forth: the distance walked folded into [0, length].
  const double walked = std::fmod(time * w.speed, 2.0 * length);
  const double from_start = walked <= length ? walked : 2.0 * length - walked;
  return w.from + along * (from_start / length);
}

Box MovingScene::door_box(std::size_t index, double time) const {
  check_time(time);
  const SlidingDoor& d = doors_.at(index);
  double share = 1.0;  // of the offset
  if (time <= d.open_start) {
    share = 0.0;
  } else if (time < d.open_end) {
    share = (time - d.open_start) / (d.open_end - d.open_start);
  }
  return {d.closed.min + d.offset * share, d.closed.max + d.offset * share};
}

Scene MovingScene::at(double time) const {
  check_time(time);
  Scene scene = still_;
  for (std::size_t i = 0; i < walkers_.size(); ++i) {
    const Vec3d foot = walker_position(i, time);
    scene.add_cylinder({foot.x, foot.y, walkers_[i].radius, foot.z, foot.z + walkers_[i].height});
  }
  for (std::size_t i = 0; i < doors_.size(); ++i) scene.add_box(door_box(i, time));
  return scene;
}

MovingScene make_demo_moving_scene() {
  MovingScene scene(make_demo_scene());
  // Along the south side of the corridor (y in [5, 7]), 0.35 m from the
  // demo path's sensor at y = 6, from the east end of the path's stretch to the west.
  scene.add_walker({{13.0, 5.4, 0.0}, {5.0, 5.4, 0.0}, 1.2, 0.25, 1.75});
  // The middle north room's door gap (x in [9.5, 10.5]), closed on the
  // corridor side of the wall, slides east along the wall.
  scene.add_door({{{9.5, 6.9, 0.0}, {10.5, 7.0, 2.1}}, {1.05, 0.0, 0.0}, 4.0, 6.0});
  return scene;
}

}  // namespace umbra::sim
