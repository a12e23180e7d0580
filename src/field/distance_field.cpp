// DistanceField (include/umbra/query/distance_field.hpp): bricks of 8^3
// cells in a hash map, each holding its cells' sites (brick_sites.hpp) and
// the offsets to their nearest occupied and unknown sites
// (distance_transform.hpp). A query is one hash lookup and two offsets
// turned into metres; storing offsets rather than distances gives the
// gradient exactly (the direction from the nearest site) for 6 bytes a cell.
//
// Building and updating compute aside from the bricks readers use and swap
// the results in with the field's gate closed (the map's ReadGate), so a
// reader sees whole updates only.
#include "umbra/query/distance_field.hpp"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include "field/brick_sites.hpp"
#include "field/distance_transform.hpp"
#include "map/map_access.hpp"
#include "map/read_gate.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra {

using detail::BrickBits;
using detail::BrickIndex;
using detail::BrickOffsets;
using detail::CellBox;
using detail::FieldLayout;
using detail::kBrickCells;
using detail::kChunkBricks;
using detail::SiteOffset;

void DistanceFieldOptions::validate() const {
  if (!(max_distance > 0.0) || !std::isfinite(max_distance)) {
    throw std::invalid_argument("distance field: max_distance must be positive and finite, got " +
                                std::to_string(max_distance));
  }
  if (depth < 0) throw std::invalid_argument("distance field: depth must be >= 0, got " + std::to_string(depth));
  if (box) box->validate();
}

namespace {

/// Most bricks a field without a box may hold before it asks for one (~20 GB).
constexpr std::size_t kMaxKnownBricks = std::size_t{1} << 23;

struct FieldBrick {
  BrickBits bits;
  BrickOffsets offsets;
};

using BrickMap = std::unordered_map<std::uint64_t, std::unique_ptr<FieldBrick>>;

std::string point_text(Vec3d p) {
  return "(" + std::to_string(p.x) + ", " + std::to_string(p.y) + ", " + std::to_string(p.z) + ")";
}

}  // namespace

struct DistanceField::State {
  State(const OccupancyMap& m, const DistanceFieldOptions& o)
      : map(m), options(o), grid(m.grid()), layout(m.resolution(), m.depth_levels(), o.depth, o.max_distance) {}

  const OccupancyMap& map;
  DistanceFieldOptions options;
  Grid grid;
  FieldLayout layout;
  std::optional<CellBox> box_cells;
  BrickBits absent;  // what a brick not stored holds: all unknown (no box) or nothing (outside the box)
  BrickMap bricks;
  std::shared_ptr<detail::ChangeJournal> journal;
  std::uint64_t version = 0;
  std::size_t bricks_recomputed = 0;
  std::size_t bricks_reread = 0;
  std::mutex writer;
  detail::ReadGate gate;

  void set_box(const std::optional<Aabb>& box);
  void rebuild();
  void update();
  /// Recomputes the offsets of `targets` into `staged` (bricks whose sites
  /// are already staged keep them; others copy them from the live bricks).
  void compute(const std::unordered_set<std::uint64_t>& targets, BrickMap& staged,
               const std::unordered_map<std::uint64_t, BrickBits>& new_sites, bool consult_live) const;
  [[nodiscard]] const BrickBits& sites_of(std::uint64_t brick) const {
    const auto it = bricks.find(brick);
    return it == bricks.end() ? absent : it->second->bits;
  }
  [[nodiscard]] bool in_map(std::int64_t x, std::int64_t y, std::int64_t z) const {
    const std::int64_t n = layout.bricks_per_axis();
    return x >= 0 && y >= 0 && z >= 0 && x < n && y < n && z < n;
  }
  template <typename Visit>
  void for_each_neighbour(BrickIndex b, int reach, Visit&& visit) const {
    for (int dz = -reach; dz <= reach; ++dz) {
      for (int dy = -reach; dy <= reach; ++dy) {
        for (int dx = -reach; dx <= reach; ++dx) {
          const std::int64_t x = std::int64_t(b.x) + dx, y = std::int64_t(b.y) + dy, z = std::int64_t(b.z) + dz;
          if (in_map(x, y, z)) visit(BrickIndex{std::uint32_t(x), std::uint32_t(y), std::uint32_t(z)});
        }
      }
    }
  }
  /// The bricks of the box, or nothing without one.
  template <typename Visit>
  void for_each_box_brick(Visit&& visit) const {
    for (std::uint32_t z = box_cells->min[2] / 8; z <= box_cells->max[2] / 8; ++z) {
      for (std::uint32_t y = box_cells->min[1] / 8; y <= box_cells->max[1] / 8; ++y) {
        for (std::uint32_t x = box_cells->min[0] / 8; x <= box_cells->max[0] / 8; ++x) visit(BrickIndex{x, y, z});
      }
    }
  }
  [[nodiscard]] bool brick_in_box(BrickIndex b) const {
    if (!box_cells) return true;
    const std::uint32_t v[3] = {b.x, b.y, b.z};
    for (int a = 0; a < 3; ++a) {
      if (v[a] < box_cells->min[std::size_t(a)] / 8 || v[a] > box_cells->max[std::size_t(a)] / 8) return false;
    }
    return true;
  }

  DistanceSample sample(Vec3d point, std::uint64_t& cached_key, const FieldBrick*& cached) const;
};

void DistanceField::State::set_box(const std::optional<Aabb>& box) {
  options.box = box;
  box_cells.reset();
  absent = BrickBits::all_unknown();
  if (!box) return;
  box->validate();
  const std::optional<Key> low = grid.key_checked(box->min);
  const std::optional<Key> high = grid.key_checked(box->max);
  if (!low || !high) {
    throw std::out_of_range("distance field: the box " + point_text(box->min) + " - " + point_text(box->max) +
                            " reaches outside the map, which spans [" + std::to_string(-grid.half_extent()) + ", " +
                            std::to_string(grid.half_extent()) + ") on every axis");
  }
  CellBox cells;
  for (int a = 0; a < 3; ++a) {
    cells.min[std::size_t(a)] = (*low)[a] >> layout.depth();
    cells.max[std::size_t(a)] = (*high)[a] >> layout.depth();
  }
  const std::uint64_t count = std::uint64_t(cells.max[0] / 8 - cells.min[0] / 8 + 1) *
                              (cells.max[1] / 8 - cells.min[1] / 8 + 1) * (cells.max[2] / 8 - cells.min[2] / 8 + 1);
  if (count > kMaxKnownBricks) {
    throw std::invalid_argument("distance field: the box needs " + std::to_string(count) +
                                " bricks of 8^3 cells, more than the limit of " + std::to_string(kMaxKnownBricks));
  }
  box_cells = cells;
  absent = BrickBits{};
}

void DistanceField::State::compute(const std::unordered_set<std::uint64_t>& targets, BrickMap& staged,
                                   const std::unordered_map<std::uint64_t, BrickBits>& new_sites,
                                   bool consult_live) const {
  const auto sites = [&](BrickIndex b) -> const BrickBits* {
    const std::uint64_t key = b.packed();
    if (const auto it = new_sites.find(key); it != new_sites.end()) return &it->second;
    if (!consult_live) return nullptr;
    if (const auto it = bricks.find(key); it != bricks.end()) return &it->second->bits;
    return nullptr;
  };
  std::unordered_set<std::uint64_t> chunks;
  for (const std::uint64_t key : targets) {
    const BrickIndex b = BrickIndex::unpack(key);
    chunks.insert(BrickIndex{b.x / kChunkBricks * kChunkBricks, b.y / kChunkBricks * kChunkBricks,
                             b.z / kChunkBricks * kChunkBricks}
                      .packed());
  }
  detail::ChunkTransform transform(layout);
  for (const std::uint64_t chunk : chunks) {
    transform.run(
        BrickIndex::unpack(chunk), sites, absent, [&](BrickIndex b) { return targets.contains(b.packed()); },
        [&](BrickIndex b, const BrickOffsets& offsets) {
          auto brick = std::make_unique<FieldBrick>();
          const BrickBits* bits = sites(b);
          brick->bits = bits != nullptr ? *bits : absent;
          brick->offsets = offsets;
          staged[b.packed()] = std::move(brick);
        });
  }
}

void DistanceField::State::rebuild() {
  std::unordered_map<std::uint64_t, BrickBits> new_sites;
  std::unordered_set<std::uint64_t> targets;
  detail::MapAccess::read(map, [&](const OccupancyTree& tree) {
    std::shared_ptr<detail::ChangeJournal> current = detail::MapAccess::journal(map);
    if (current != journal) {
      if (journal) journal->unsubscribe();
      current->subscribe();
      journal = std::move(current);
    }
    version = journal->version();
    if (box_cells) {
      for_each_box_brick([&](BrickIndex b) { new_sites.emplace(b.packed(), detail::read_brick(tree, layout, b, box_cells)); });
    } else {
      detail::for_each_known_brick(tree, layout, kMaxKnownBricks, [&](BrickIndex b) {
        new_sites.emplace(b.packed(), detail::read_brick(tree, layout, b, std::nullopt));
      });
    }
  });
  if (box_cells) {
    for (const auto& [key, bits] : new_sites) targets.insert(key);
  } else {
    // Without a box, the bricks within reach of known space are kept (the
    // rest are unknown with no occupied voxel within max_distance).
    for (const auto& [key, bits] : new_sites) {
      if (!bits.known) continue;
      for_each_neighbour(BrickIndex::unpack(key), layout.brick_reach(),
                         [&](BrickIndex n) { targets.insert(n.packed()); });
    }
  }
  BrickMap staged;
  compute(targets, staged, new_sites, /*consult_live=*/false);  // the live bricks are all replaced
  const std::size_t reread = new_sites.size();
  detail::ClosedGate closed(gate);
  bricks.swap(staged);
  bricks_recomputed = targets.size();
  bricks_reread = reread;
}

void DistanceField::State::update() {
  std::vector<detail::ChangeJournal::Entry> entries;
  std::unordered_map<std::uint64_t, BrickBits> new_sites;
  bool start_over = false;
  detail::MapAccess::read(map, [&](const OccupancyTree& tree) {
    if (detail::MapAccess::journal(map) != journal || !journal->changes_since(version, entries)) {
      start_over = true;
      return;
    }
    version = journal->version();
    const int brick_shift = layout.depth() + 3;
    for (const detail::ChangeJournal::Entry& entry : entries) {
      const Key key = morton::decode(entry.code);
      const std::uint32_t last = (std::uint32_t{1} << entry.depth) - 1;
      BrickIndex lo{key.x >> brick_shift, key.y >> brick_shift, key.z >> brick_shift};
      BrickIndex hi{(key.x + last) >> brick_shift, (key.y + last) >> brick_shift, (key.z + last) >> brick_shift};
      if (box_cells) {
        lo = {std::max(lo.x, box_cells->min[0] / 8), std::max(lo.y, box_cells->min[1] / 8),
              std::max(lo.z, box_cells->min[2] / 8)};
        hi = {std::min(hi.x, box_cells->max[0] / 8), std::min(hi.y, box_cells->max[1] / 8),
              std::min(hi.z, box_cells->max[2] / 8)};
      }
      for (std::uint32_t z = lo.z; z <= hi.z; ++z) {
        for (std::uint32_t y = lo.y; y <= hi.y; ++y) {
          for (std::uint32_t x = lo.x; x <= hi.x; ++x) {
            const BrickIndex b{x, y, z};
            if (!new_sites.contains(b.packed())) new_sites.emplace(b.packed(), detail::read_brick(tree, layout, b, box_cells));
          }
        }
      }
    }
  });
  if (start_over) {
    rebuild();
    return;
  }
  const std::size_t reread = new_sites.size();
  // Which bricks changed their sites, and (without a box) which became
  // known or unknown, so that the set of kept bricks follows.
  std::vector<BrickIndex> changed;
  std::vector<BrickIndex> became_unknown;
  std::unordered_set<std::uint64_t> added;
  for (auto it = new_sites.begin(); it != new_sites.end();) {
    const BrickBits& before = sites_of(it->first);
    if (it->second == before) {
      it = new_sites.erase(it);
      continue;
    }
    const BrickIndex b = BrickIndex::unpack(it->first);
    changed.push_back(b);
    if (!box_cells) {
      const bool was_known = before.known;
      if (it->second.known && !was_known) {
        for_each_neighbour(b, layout.brick_reach(), [&](BrickIndex n) {
          if (!bricks.contains(n.packed())) added.insert(n.packed());
        });
      }
      if (!it->second.known && was_known) became_unknown.push_back(b);
    }
    ++it;
  }
  const auto known_after = [&](std::uint64_t key) {
    if (const auto it = new_sites.find(key); it != new_sites.end()) return it->second.known;
    return sites_of(key).known;
  };
  std::unordered_set<std::uint64_t> removed;
  for (const BrickIndex b : became_unknown) {
    for_each_neighbour(b, layout.brick_reach(), [&](BrickIndex n) {
      if (!bricks.contains(n.packed()) && !added.contains(n.packed())) return;
      bool near_known = false;
      for_each_neighbour(n, layout.brick_reach(), [&](BrickIndex m) { near_known = near_known || known_after(m.packed()); });
      if (!near_known) removed.insert(n.packed());
    });
  }
  for (const std::uint64_t key : removed) added.erase(key);
  std::unordered_set<std::uint64_t> targets = added;
  for (const BrickIndex b : changed) {
    for_each_neighbour(b, layout.brick_reach(), [&](BrickIndex n) {
      const std::uint64_t key = n.packed();
      if ((bricks.contains(key) || added.contains(key)) && !removed.contains(key) && brick_in_box(n)) targets.insert(key);
    });
  }
  BrickMap staged;
  compute(targets, staged, new_sites, /*consult_live=*/true);
  detail::ClosedGate closed(gate);
  for (auto& [key, brick] : staged) bricks[key] = std::move(brick);
  for (const std::uint64_t key : removed) bricks.erase(key);
  bricks_recomputed = targets.size();
  bricks_reread = reread;
}

DistanceSample DistanceField::State::sample(Vec3d point, std::uint64_t& cached_key, const FieldBrick*& cached) const {
  const std::optional<Key> key = grid.key_checked(point);
  if (!key) {
    throw std::out_of_range("distance field: the point " + point_text(point) + " is outside the map, which spans [" +
                            std::to_string(-grid.half_extent()) + ", " + std::to_string(grid.half_extent()) +
                            ") on every axis");
  }
  const int k = layout.depth();
  const std::uint32_t cx = key->x >> k, cy = key->y >> k, cz = key->z >> k;
  if (box_cells && !box_cells->contains(cx, cy, cz)) {
    throw std::out_of_range("distance field: the point " + point_text(point) + " is outside the field's box " +
                            point_text(options.box->min) + " - " + point_text(options.box->max));
  }
  const std::uint64_t brick_key = BrickIndex{cx >> 3, cy >> 3, cz >> 3}.packed();
  if (brick_key != cached_key) {
    const auto it = bricks.find(brick_key);
    cached = it == bricks.end() ? nullptr : it->second.get();
    cached_key = brick_key;
  }
  DistanceSample out;
  if (cached == nullptr) {  // unknown, and no occupied voxel within max_distance (see the header)
    out.occupied = layout.max_distance();
    out.unknown = 0.0;
    return out;
  }
  const int cell = detail::cell_in_brick(cx, cy, cz);
  const SiteOffset occupied = cached->offsets.occupied[std::size_t(cell)];
  const SiteOffset unknown = cached->offsets.unknown[std::size_t(cell)];
  out.occupied = layout.metres(occupied);
  out.unknown = layout.metres(unknown);
  const SiteOffset nearest =
      occupied.none() ? unknown
                      : (unknown.none() ? occupied
                                        : (layout.squared(occupied) <= layout.squared(unknown) ? occupied : unknown));
  if (!nearest.none() && layout.squared(nearest) > 0) {
    // Away from the site: minus the offset's direction, each axis by its gap.
    const std::int8_t d[3] = {nearest.x, nearest.y, nearest.z};
    double v[3];
    for (int a = 0; a < 3; ++a) {
      const double gap = std::sqrt(double(layout.squared_gap(d[a])));
      v[a] = d[a] > 0 ? -gap : (d[a] < 0 ? gap : 0.0);
    }
    const double norm = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    out.gradient = {v[0] / norm, v[1] / norm, v[2] / norm};
  }
  return out;
}

DistanceField::DistanceField(const OccupancyMap& map, const DistanceFieldOptions& options) {
  options.validate();
  if (options.depth > map.depth_levels() - 3) {
    throw std::invalid_argument("distance field: depth " + std::to_string(options.depth) +
                                " leaves no room for bricks of 8^3 cells in a map of " +
                                std::to_string(map.depth_levels()) + " depth levels (at most " +
                                std::to_string(map.depth_levels() - 3) + ")");
  }
  state_ = std::make_unique<State>(map, options);
  if (state_->layout.window() > 120) {
    throw std::invalid_argument("distance field: max_distance " + std::to_string(options.max_distance) +
                                " m spans " + std::to_string(state_->layout.window()) +
                                " cells, more than the 120 a field looks through; use a coarser depth");
  }
  state_->set_box(options.box);
  state_->rebuild();
}

DistanceField::~DistanceField() {
  if (state_ && state_->journal) state_->journal->unsubscribe();
}

void DistanceField::update() {
  std::lock_guard writer(state_->writer);
  state_->update();
}

void DistanceField::set_box(const std::optional<Aabb>& box) {
  std::lock_guard writer(state_->writer);
  State& s = *state_;
  // The box is read by queries: change it with them kept out, then rebuild.
  {
    detail::ClosedGate closed(s.gate);
    s.set_box(box);
    s.bricks.clear();
  }
  s.rebuild();
}

void DistanceField::rebuild() {
  std::lock_guard writer(state_->writer);
  state_->rebuild();
}

const DistanceFieldOptions& DistanceField::options() const { return state_->options; }

double DistanceField::distance(Vec3d point) const { return distance_and_gradient(point).blocking(); }

DistanceSample DistanceField::distance_and_gradient(Vec3d point) const {
  detail::ReadLock lock(state_->gate);
  std::uint64_t cached_key = ~std::uint64_t{0};
  const FieldBrick* cached = nullptr;
  return state_->sample(point, cached_key, cached);
}

namespace {
constexpr std::size_t kBatchChunk = 4096;

template <typename Out, typename Convert>
void batch(const DistanceField::State& s, const detail::ReadGate& gate, std::span<const Vec3d> points,
           std::span<Out> out, Convert convert) {
  if (points.size() != out.size()) {
    throw std::invalid_argument("distance field: " + std::to_string(points.size()) + " points but room for " +
                                std::to_string(out.size()) + " answers");
  }
  for (std::size_t begin = 0; begin < points.size(); begin += kBatchChunk) {
    const std::size_t end = std::min(points.size(), begin + kBatchChunk);
    detail::ReadLock lock(gate);
    std::uint64_t cached_key = ~std::uint64_t{0};
    const FieldBrick* cached = nullptr;
    for (std::size_t i = begin; i < end; ++i) {
      try {
        out[i] = convert(s.sample(points[i], cached_key, cached));
      } catch (const std::out_of_range& e) {
        throw std::out_of_range("point " + std::to_string(i) + ": " + e.what());
      }
    }
  }
}
}  // namespace

void DistanceField::distance(std::span<const Vec3d> points, std::span<double> out) const {
  batch(*state_, state_->gate, points, out, [](const DistanceSample& s) { return s.blocking(); });
}

void DistanceField::distance_and_gradient(std::span<const Vec3d> points, std::span<DistanceSample> out) const {
  batch(*state_, state_->gate, points, out, [](const DistanceSample& s) { return s; });
}

DistanceFieldStats DistanceField::stats() const {
  detail::ReadLock lock(state_->gate);
  const State& s = *state_;
  DistanceFieldStats out;
  out.bricks = s.bricks.size();
  // A brick, its hash node (key, pointer, next pointer, cached hash) and bucket.
  out.memory_bytes = sizeof(State) + s.bricks.size() * (sizeof(FieldBrick) + 4 * sizeof(void*)) +
                     s.bricks.bucket_count() * sizeof(void*);
  out.bricks_recomputed = s.bricks_recomputed;
  out.bricks_reread = s.bricks_reread;
  return out;
}

}  // namespace umbra
