#include "umbra/sim/industrial_scene.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <initializer_list>
#include <random>
#include <vector>

namespace umbra::sim {

namespace {

// The fixed frame of the building (see the header).
constexpr double kWidth = 40.0;   // x
constexpr double kDepth = 30.0;   // y
constexpr double kHeight = 12.0;  // z
constexpr double kWall = 0.3;
constexpr double kLevel = 6.0;    // top of the floors between the levels
constexpr double kSlab = 0.2;     // their thickness
constexpr double kSplitX = 14.0;  // wall between hall A and halls B, C: x in [14, 14.3]
constexpr double kSplitY = 16.0;  // wall between halls B and C: y in [16, 16.3]
constexpr double kMezzanineY = 10.0;  // hall A's mezzanine covers y < 10
constexpr double kGalleryY = 18.5;    // hall C's gallery covers y < 18.5

/// Uniform numbers from std::mt19937, whose bits the standard fixes; the
/// mapping to doubles is ours, so a seed gives the same scene everywhere.
class Dice {
 public:
  explicit Dice(std::uint32_t seed) : engine_(seed) {}
  double uniform(double low, double high) { return low + (high - low) * (double(engine_()) / 4294967296.0); }
  int integer(int low, int high) { return low + int(engine_() % std::uint32_t(high - low + 1)); }
  bool chance(double p) { return uniform(0.0, 1.0) < p; }

 private:
  std::mt19937 engine_;
};

/// An opening in a wall or a floor: [from, to] along the wall, [low, high] across it.
struct Opening {
  double from;
  double to;
  double low;
  double high;
};

/// A wall (or floor) as boxes around rectangular openings. `along` is the
/// axis the openings are ordered on, `across` the other axis in the wall's
/// plane, `normal` the thickness axis; openings must not overlap along.
void add_with_openings(Scene& scene, int along, int across, Vec3d min, Vec3d max, std::vector<Opening> openings) {
  std::sort(openings.begin(), openings.end(), [](const Opening& a, const Opening& b) { return a.from < b.from; });
  auto add_part = [&](double a0, double a1, double c0, double c1) {
    if (a1 - a0 <= 1e-9 || c1 - c0 <= 1e-9) return;
    Vec3d low = min;
    Vec3d high = max;
    low[std::size_t(along)] = a0;
    high[std::size_t(along)] = a1;
    low[std::size_t(across)] = c0;
    high[std::size_t(across)] = c1;
    scene.add_box({low, high});
  };
  const double across_min = min[std::size_t(across)];
  const double across_max = max[std::size_t(across)];
  double start = min[std::size_t(along)];
  for (const Opening& o : openings) {
    add_part(start, o.from, across_min, across_max);
    add_part(o.from, o.to, across_min, o.low);
    add_part(o.from, o.to, o.high, across_max);
    start = o.to;
  }
  add_part(start, max[std::size_t(along)], across_min, across_max);
}

bool overlaps(const Box& a, const Box& b) {
  return a.min.x < b.max.x && b.min.x < a.max.x && a.min.y < b.max.y && b.min.y < a.max.y && a.min.z < b.max.z &&
         b.min.z < a.max.z;
}

Box grown(const Box& box, double margin) {
  const Vec3d m{margin, margin, margin};
  return {box.min - m, box.max + m};
}

/// A straight flight of solid steps rising from (x0..x1, y_low_end) to
/// `top` at the other end: `steps` blocks from the floor up, each one step higher.
void add_stair(Scene& scene, double x0, double x1, double y_from, double y_to, double floor, double top, int steps) {
  const double run = (y_to - y_from) / steps;  // signed: the stair may rise towards -y
  for (int i = 0; i < steps; ++i) {
    const double a = y_from + run * i;
    const double b = a + run;
    scene.add_box({{x0, std::min(a, b), floor}, {x1, std::max(a, b), floor + (top - floor) * (i + 1) / steps}});
  }
}

/// A railing along x or y: posts every `spacing` metres, a top and a middle rail.
void add_railing(Scene& scene, bool along_x, double from, double to, double at, double floor, double spacing) {
  constexpr double post = 0.06;
  constexpr double height = 1.0;
  auto box = [&](double a0, double a1, double c0, double c1, double z0, double z1) {
    if (along_x) {
      scene.add_box({{a0, c0, z0}, {a1, c1, z1}});
    } else {
      scene.add_box({{c0, a0, z0}, {c1, a1, z1}});
    }
  };
  const int posts = std::max(1, int(std::round((to - from) / spacing)));
  for (int i = 0; i <= posts; ++i) {
    const double p = std::clamp(from + (to - from) * i / posts, from, to - post);
    box(p, p + post, at - post / 2, at + post / 2, floor, floor + height);
  }
  box(from, to, at - 0.03, at + 0.03, floor + height - 0.05, floor + height);
  box(from, to, at - 0.02, at + 0.02, floor + 0.5 * height - 0.02, floor + 0.5 * height + 0.02);
}

/// Places clutter: keeps a list of the solid blocks placed and of the zones
/// kept free (doors, stairs, hatches, the start), and rejects a candidate
/// that comes within `spacing` of either, so that passages stay open.
class Layout {
 public:
  Layout(Scene& scene, Dice& dice) : scene_(scene), dice_(dice) {}

  void keep_free(const Box& zone) { kept_free_.push_back(zone); }

  /// True (and the footprint recorded) when `block` fits.
  bool claim(const Box& block, double spacing) {
    const Box wide = grown(block, spacing);
    for (const Box& zone : kept_free_) {
      if (overlaps(wide, zone)) return false;
    }
    for (const Box& taken : claimed_) {
      if (overlaps(wide, taken)) return false;
    }
    claimed_.push_back(block);
    return true;
  }

  /// Up to `count` items on a floor area (x0..x1, y0..y1 at height floor,
  /// below ceiling), each tried a few times at random places.
  void scatter(int count, double x0, double x1, double y0, double y1, double floor, double ceiling) {
    for (int i = 0; i < count; ++i) {
      for (int attempt = 0; attempt < 20; ++attempt) {
        if (place_item(x0, x1, y0, y1, floor, ceiling)) break;
      }
    }
  }

  /// Shelving against a wall: uprights and shelves, `length` along x or y.
  void shelving(bool along_x, double from, double length, double wall_side, double depth_sign, double floor,
                double height) {
    const double depth = 0.6;
    const double c0 = depth_sign > 0 ? wall_side : wall_side - depth;
    const double c1 = c0 + depth;
    const Box block = along_x ? Box{{from, c0, floor}, {from + length, c1, floor + height}}
                              : Box{{c0, from, floor}, {c1, from + length, floor + height}};
    if (!claim(block, 0.5)) return;
    auto box = [&](double a0, double a1, double d0, double d1, double z0, double z1) {
      if (along_x) {
        scene_.add_box({{a0, d0, z0}, {a1, d1, z1}});
      } else {
        scene_.add_box({{d0, a0, z0}, {d1, a1, z1}});
      }
    };
    const int bays = std::max(1, int(length / 1.8));
    for (int i = 0; i <= bays; ++i) {
      const double a = std::min(from + length * i / bays, from + length - 0.08);
      box(a, a + 0.08, c0, c0 + 0.08, floor, floor + height);
      box(a, a + 0.08, c1 - 0.08, c1, floor, floor + height);
    }
    for (double z = floor + 0.15; z < floor + height - 0.2; z += dice_.uniform(0.7, 1.1)) {
      box(from, from + length, c0, c1, z, z + 0.04);
      // Goods on the shelf: a few boxes.
      for (double a = from + 0.1; a < from + length - 0.6; a += dice_.uniform(0.5, 1.2)) {
        if (dice_.chance(0.6)) {
          const double w = dice_.uniform(0.3, 0.5);
          box(a, a + w, c0 + 0.05, c1 - 0.05, z + 0.04, z + 0.04 + dice_.uniform(0.2, 0.5));
        }
      }
    }
  }

 private:
  bool place_item(double x0, double x1, double y0, double y1, double floor, double ceiling) {
    const int kind = dice_.integer(0, 9);
    if (kind <= 4) {  // a crate, sometimes with a smaller one on top
      const double sx = dice_.uniform(0.6, 1.6);
      const double sy = dice_.uniform(0.6, 1.6);
      const double h = dice_.uniform(0.5, 1.4);
      const double x = dice_.uniform(x0, x1 - sx);
      const double y = dice_.uniform(y0, y1 - sy);
      const Box crate{{x, y, floor}, {x + sx, y + sy, floor + h}};
      if (!claim(crate, 0.9)) return false;
      scene_.add_box(crate);
      if (dice_.chance(0.4)) {
        const double inset = dice_.uniform(0.05, 0.2);
        scene_.add_box({{x + inset, y + inset, floor + h}, {x + sx - inset, y + sy - inset, floor + h + dice_.uniform(0.3, 0.8)}});
      }
      return true;
    }
    if (kind <= 6) {  // a machine: a block on a plinth, a motor (a horizontal pipe), a vertical exhaust
      const double sx = dice_.uniform(1.5, 3.5);
      const double sy = dice_.uniform(1.2, 2.5);
      const double h = dice_.uniform(1.2, std::min(3.0, ceiling - floor - 2.0));
      const double x = dice_.uniform(x0, x1 - sx);
      const double y = dice_.uniform(y0, y1 - sy);
      const Box block{{x, y, floor}, {x + sx, y + sy, floor + h + 0.6}};
      if (!claim(block, 1.0)) return false;
      scene_.add_box({{x, y, floor}, {x + sx, y + sy, floor + 0.2}});
      scene_.add_box({{x + 0.1, y + 0.1, floor + 0.2}, {x + sx - 0.1, y + sy - 0.1, floor + h}});
      const double r = std::min(0.35, 0.25 * sy);
      scene_.add_pipe({{x + 0.3, y + sy / 2, floor + h + r}, {x + sx - 0.3, y + sy / 2, floor + h + r}, r});
      const double ex = x + dice_.uniform(0.3, sx - 0.3);
      const double ey = y + dice_.uniform(0.3, sy - 0.3);
      scene_.add_pipe({{ex, ey, floor + h}, {ex, ey, ceiling - 0.3}, dice_.uniform(0.08, 0.15)});
      return true;
    }
    if (kind <= 8) {  // a pump: a vertical cylinder with pipe stubs
      const double r = dice_.uniform(0.3, 0.5);
      const double x = dice_.uniform(x0 + r, x1 - r);
      const double y = dice_.uniform(y0 + r, y1 - r);
      const double h = dice_.uniform(0.8, 1.4);
      const Box block{{x - r - 0.6, y - r - 0.6, floor}, {x + r + 0.6, y + r + 0.6, floor + h}};
      if (!claim(block, 0.8)) return false;
      scene_.add_cylinder({x, y, r, floor, floor + h});
      scene_.add_pipe({{x - r - 0.5, y, floor + 0.4}, {x + r + 0.5, y, floor + 0.4}, 0.1});
      scene_.add_pipe({{x, y - r - 0.5, floor + h - 0.3}, {x, y + r + 0.5, floor + h - 0.3}, 0.08});
      return true;
    }
    // A cabinet bank: a row of tall narrow boxes.
    const int n = dice_.integer(2, 5);
    const double w = 0.8;
    const double d = 0.6;
    const double h = dice_.uniform(1.8, 2.2);
    const double x = dice_.uniform(x0, x1 - n * w);
    const double y = dice_.uniform(y0, y1 - d);
    const Box block{{x, y, floor}, {x + n * w, y + d, floor + h}};
    if (!claim(block, 0.9)) return false;
    for (int i = 0; i < n; ++i) scene_.add_box({{x + i * w + 0.01, y, floor}, {x + (i + 1) * w - 0.01, y + d, floor + h}});
    return true;
  }

  Scene& scene_;
  Dice& dice_;
  std::vector<Box> kept_free_;
  std::vector<Box> claimed_;
};

/// A straight pipe with a flange (a short, wider piece) every 3 m or so.
void flanged_pipe(Scene& scene, Vec3d a, Vec3d b, double radius) {
  scene.add_pipe({a, b, radius});
  const Vec3d ab = b - a;
  const double length = ab.norm();
  const int flanges = int(length / 3.0);
  for (int i = 1; i <= flanges; ++i) {
    const double t = double(i) / (flanges + 1);
    const Vec3d half = ab * (0.03 / length);
    scene.add_pipe({a + ab * t - half, a + ab * t + half, radius + 0.04});
  }
}

/// Horizontal pipes along a wall at random heights between z0 and z1, and
/// vertical ones from floor to ceiling; `along_x` walls run along x at
/// y = at (pipes offset by `side` metres into the room).
void wall_pipes(Scene& scene, Dice& dice, bool along_x, double from, double to, double at, double side, double z0,
                double z1, int count) {
  for (int i = 0; i < count; ++i) {
    const double r = dice.uniform(0.05, 0.2);
    const double z = dice.uniform(z0 + r, z1 - r);
    const double off = at + side * (r + dice.uniform(0.1, 0.3));
    if (along_x) {
      flanged_pipe(scene, {from, off, z}, {to, off, z}, r);
    } else {
      flanged_pipe(scene, {off, from, z}, {off, to, z}, r);
    }
  }
  const int vertical = count / 2;
  for (int i = 0; i < vertical; ++i) {
    const double r = dice.uniform(0.05, 0.15);
    const double a = dice.uniform(from + 0.5, to - 0.5);
    const double off = at + side * (r + 0.05);
    const Vec3d low = along_x ? Vec3d{a, off, z0} : Vec3d{off, a, z0};
    const Vec3d high = along_x ? Vec3d{a, off, z1} : Vec3d{off, a, z1};
    flanged_pipe(scene, low, high, r);
  }
}

/// A cable tray under a ceiling: a thin open box along x or y, with hangers.
void cable_tray(Scene& scene, bool along_x, double from, double to, double at, double z, double ceiling) {
  auto box = [&](double a0, double a1, double c0, double c1, double z0, double z1) {
    if (along_x) {
      scene.add_box({{a0, c0, z0}, {a1, c1, z1}});
    } else {
      scene.add_box({{c0, a0, z0}, {c1, a1, z1}});
    }
  };
  box(from, to, at - 0.3, at + 0.3, z, z + 0.03);
  box(from, to, at - 0.3, at - 0.28, z, z + 0.1);
  box(from, to, at + 0.28, at + 0.3, z, z + 0.1);
  for (double a = from; a < to - 0.05; a += 2.0) {
    box(a, a + 0.04, at - 0.3, at - 0.26, z + 0.03, ceiling);
    box(a, a + 0.04, at + 0.26, at + 0.3, z + 0.03, ceiling);
  }
}

}  // namespace

IndustrialPlant make_industrial_scene(std::uint32_t seed) {
  IndustrialPlant plant;
  Scene& scene = plant.scene;
  Dice dice(seed);
  Layout layout(scene, dice);
  plant.start = {7.0, 15.0, 1.5};
  plant.interior = {{kWall, kWall, 0.0}, {kWidth - kWall, kDepth - kWall, kHeight}};
  const double east_x0 = kSplitX + kWall;
  const double north_y0 = kSplitY + kWall;

  // Shell.
  scene.add_box({{0, 0, -kWall}, {kWidth, kDepth, 0}});
  scene.add_box({{0, 0, kHeight}, {kWidth, kDepth, kHeight + kWall}});
  scene.add_box({{0, 0, 0}, {kWidth, kWall, kHeight}});
  scene.add_box({{0, kDepth - kWall, 0}, {kWidth, kDepth, kHeight}});
  scene.add_box({{0, kWall, 0}, {kWall, kDepth - kWall, kHeight}});
  scene.add_box({{kWidth - kWall, kWall, 0}, {kWidth, kDepth - kWall, kHeight}});

  // Inner walls and their doors (2.5 m wide; the door zones, 2.5 m deep on
  // both sides, are kept free of clutter).
  const std::vector<Opening> west_doors{{3.0, 5.5, kLevel, kLevel + 3.0},   // A mezzanine <-> B upper floor
                                        {12.0, 14.5, 0.0, 3.5},             // A <-> B ground
                                        {21.0, 24.5, 0.0, 4.0}};            // A <-> C ground (a gate)
  add_with_openings(scene, 1, 2, {kSplitX, kWall, 0}, {kSplitX + kWall, kDepth - kWall, kHeight}, west_doors);
  for (const Opening& d : west_doors) {
    layout.keep_free({{kSplitX - 2.5, d.from - 0.5, d.low}, {kSplitX + kWall + 2.5, d.to + 0.5, d.high + 0.5}});
  }
  const std::vector<Opening> north_doors{{24.0, 26.5, 0.0, 3.5},           // B <-> C ground
                                         {31.0, 33.5, kLevel, kLevel + 3.0}};  // B upper <-> C gallery
  add_with_openings(scene, 0, 2, {east_x0, kSplitY, 0}, {kWidth - kWall, kSplitY + kWall, kHeight}, north_doors);
  for (const Opening& d : north_doors) {
    layout.keep_free({{d.from - 0.5, kSplitY - 2.5, d.low}, {d.to + 0.5, kSplitY + kWall + 2.5, d.high + 0.5}});
  }

  // Hall A: the mezzanine (y < 10) at 6 m, its stair along the west wall
  // rising southwards from y = 18 to its edge, its railing, and its columns.
  scene.add_box({{kWall, kWall, kLevel - kSlab}, {kSplitX, kMezzanineY, kLevel}});
  add_stair(scene, 0.5, 1.9, 18.0, kMezzanineY, 0.0, kLevel - kSlab, 20);
  layout.keep_free({{kWall, kMezzanineY - 1.0, 0.0}, {3.0, 19.0, kHeight}});
  add_railing(scene, true, 2.2, kSplitX, kMezzanineY - 0.05, kLevel, 1.2);
  for (const double x : {4.5, 9.0, 12.5}) scene.add_cylinder({x, kMezzanineY - 0.4, 0.2, 0.0, kLevel - kSlab});

  // Hall B: the floor between the levels, with a hatch and a stairwell (and its stair).
  const std::vector<Opening> floor_holes{{22.0, 25.5, 6.0, 9.5}, {34.0, 36.5, 3.0, 11.0}};
  add_with_openings(scene, 0, 1, {east_x0, kWall, kLevel - kSlab}, {kWidth - kWall, kSplitY, kLevel}, floor_holes);
  add_stair(scene, 34.2, 36.3, 11.0, 3.0, 0.0, kLevel - kSlab, 20);
  for (const Opening& h : floor_holes) {
    layout.keep_free({{h.from - 1.0, h.low - 1.0, 0.0}, {h.to + 1.0, h.high + 1.0, kHeight}});
  }
  for (const double x : {20.0, 29.0}) {
    for (const double y : {5.0, 11.0}) scene.add_cylinder({x, y, 0.25, 0.0, kLevel - kSlab});
  }

  // Hall C: the gallery at 6 m along the south wall, with its railing.
  scene.add_box({{east_x0, north_y0, kLevel - kSlab}, {kWidth - kWall, kGalleryY, kLevel}});
  add_railing(scene, true, east_x0, kWidth - kWall, kGalleryY - 0.05, kLevel, 1.5);

  // The start stays clear.
  layout.keep_free({plant.start - Vec3d{2.5, 2.5, 1.5}, plant.start + Vec3d{2.5, 2.5, 2.5}});

  // Hall A: a turbine (a horizontal drum on a plinth) in its north part, and
  // a generator behind it.
  {
    const double y = dice.uniform(22.5, 25.5);
    const double r = dice.uniform(1.1, 1.5);
    const Box plinth{{3.5, y - r - 0.3, 0.0}, {11.0, y + r + 0.3, 0.8}};
    layout.claim({plinth.min, {plinth.max.x, plinth.max.y, 0.8 + 2 * r}}, 0.0);
    scene.add_box(plinth);
    scene.add_pipe({{4.5, y, 0.8 + r}, {8.5, y, 0.8 + r}, r});
    scene.add_box({{8.8, y - 0.9, 0.8}, {10.8, y + 0.9, 0.8 + 1.8}});
    scene.add_pipe({{6.5, y, 0.8 + 2 * r}, {6.5, y, kHeight - 0.2}, 0.35});  // steam pipe to the roof
  }
  layout.shelving(false, 20.0, 8.0, kWall, 1.0, 0.0, 3.5);                               // west wall, north
  layout.shelving(true, 3.0, 9.0, kDepth - kWall, -1.0, 0.0, 4.0);                       // north wall
  layout.scatter(10, 3.0, kSplitX - 0.5, 0.8, kMezzanineY - 1.0, 0.0, kLevel - kSlab);   // under the mezzanine
  layout.scatter(8, 3.0, kSplitX - 0.5, kMezzanineY + 1.0, kDepth - 0.8, 0.0, kHeight);  // the high part
  layout.scatter(8, 0.8, kSplitX - 0.5, 0.8, kMezzanineY - 1.2, kLevel, kHeight);        // on the mezzanine
  wall_pipes(scene, dice, true, kWall, kSplitX, kDepth - kWall, -1.0, 4.5, kHeight - 0.5, 6);
  wall_pipes(scene, dice, false, kMezzanineY + 0.5, kDepth - kWall, kSplitX, -1.0, 4.0, kHeight - 0.5, 5);
  wall_pipes(scene, dice, true, kWall, kSplitX, kWall, 1.0, kLevel + 2.5, kHeight - 0.3, 4);
  cable_tray(scene, false, 1.0, kDepth - 1.0, 11.0, kHeight - 0.8, kHeight);

  // Hall B, both levels.
  layout.shelving(true, 16.0, 5.0, kWall, 1.0, 0.0, 3.0);
  layout.shelving(true, 27.0, 6.0, kWall, 1.0, kLevel, 3.0);
  layout.shelving(false, 12.0, 3.5, kWidth - kWall, -1.0, 0.0, 3.0);
  layout.scatter(22, east_x0 + 0.5, kWidth - 0.8, 0.8, kSplitY - 0.5, 0.0, kLevel - kSlab);
  layout.scatter(18, east_x0 + 0.5, kWidth - 0.8, 0.8, kSplitY - 0.5, kLevel, kHeight);
  wall_pipes(scene, dice, true, east_x0, kWidth - kWall, kWall, 1.0, 3.2, kLevel - kSlab - 0.2, 6);
  wall_pipes(scene, dice, true, east_x0, kWidth - kWall, kWall, 1.0, kLevel + 3.2, kHeight - 0.3, 5);
  wall_pipes(scene, dice, false, kWall + 0.5, kSplitY - 0.5, kWidth - kWall, -1.0, 3.5, kLevel - kSlab - 0.2, 5);
  cable_tray(scene, true, east_x0 + 1.0, kWidth - 1.0, 13.5, kLevel - kSlab - 0.6, kLevel - kSlab);
  cable_tray(scene, true, east_x0 + 1.0, kWidth - 1.0, 2.0, kHeight - 0.7, kHeight);

  // Hall C: tanks in two rows north of the gallery, pipes between them and
  // to the walls, a pipe rack along the north wall, clutter in between.
  std::vector<Cylinder> tanks;
  for (int i = 0; i < 40 && tanks.size() < 6; ++i) {
    const double r = dice.uniform(1.2, 2.0);
    const double x = dice.uniform(east_x0 + r + 1.0, kWidth - kWall - r - 1.0);
    const double y = dice.uniform(kGalleryY + r + 1.5, kDepth - kWall - r - 3.5);
    const double h = dice.uniform(4.5, 9.5);
    const Box block{{x - r, y - r, 0.0}, {x + r, y + r, h}};
    if (!layout.claim(block, 1.5)) continue;
    tanks.push_back({x, y, r, 0.0, h});
    scene.add_cylinder(tanks.back());
    scene.add_cylinder({x, y, r * 0.3, h, h + 0.6});  // a dome nozzle
  }
  for (std::size_t i = 0; i + 1 < tanks.size(); ++i) {
    const Cylinder& a = tanks[i];
    const Cylinder& b = tanks[i + 1];
    const double z = dice.uniform(1.5, std::min(a.z_max, b.z_max) - 0.5);
    scene.add_pipe({{a.center_x, a.center_y, z}, {b.center_x, b.center_y, z}, dice.uniform(0.1, 0.25)});
    const double up = std::min(a.z_max + 1.5, kHeight - 0.6);
    scene.add_pipe({{a.center_x, a.center_y, a.z_max}, {a.center_x, a.center_y, up}, 0.12});
    scene.add_pipe({{a.center_x, a.center_y, up}, {a.center_x, kDepth - 0.6, up}, 0.12});
  }
  {
    // Pipe rack: posts every 4 m along x at y = 28.2, a beam at 5 m, six pipes on it.
    const double y = kDepth - 1.5;
    for (double x = east_x0 + 1.0; x < kWidth - 1.0; x += 4.0) {
      scene.add_box({{x, y - 0.6, 0.0}, {x + 0.2, y - 0.4, 5.0}});
      scene.add_box({{x, y + 0.4, 0.0}, {x + 0.2, y + 0.6, 5.0}});
      scene.add_box({{x, y - 0.6, 5.0}, {x + 0.2, y + 0.6, 5.2}});
    }
    layout.claim({{east_x0, y - 0.7, 0.0}, {kWidth - kWall, kDepth - kWall, kHeight}}, 0.0);
    for (int i = 0; i < 6; ++i) {
      const double r = dice.uniform(0.08, 0.18);
      const double py = y - 0.5 + 0.2 * i;
      flanged_pipe(scene, {east_x0, py, 5.2 + r}, {kWidth - kWall, py, 5.2 + r}, r);
    }
  }
  layout.scatter(14, east_x0 + 0.5, kWidth - 0.8, kGalleryY + 0.5, kDepth - 2.5, 0.0, kHeight);
  layout.scatter(4, east_x0 + 0.5, kWidth - 0.8, north_y0 + 0.3, kGalleryY - 0.3, kLevel, kHeight);
  wall_pipes(scene, dice, false, north_y0, kDepth - kWall, kWidth - kWall, -1.0, 1.0, kHeight - 0.5, 6);
  wall_pipes(scene, dice, false, north_y0 + 2.5, kDepth - kWall, east_x0, 1.0, kLevel, kHeight - 0.5, 4);
  cable_tray(scene, true, east_x0 + 1.0, kWidth - 1.0, 24.0, kHeight - 0.7, kHeight);
  return plant;
}

}  // namespace umbra::sim
