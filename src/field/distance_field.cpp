// DistanceField (include/umbra/field/distance_field.hpp): bricks of 8^3
// cells in a hash map, each holding its cells' sites (brick_sites.hpp) and
// the offsets to their nearest occupied and unknown sites
// (distance_transform.hpp), coded (cell_codes.hpp). A query is one hash
// lookup and two offsets turned into metres; storing offsets rather than
// distances gives the gradient exactly (the direction from the nearest
// site) for 4 bytes a cell (6 with a wide window).
//
// Building and updating compute aside from the bricks readers use and swap
// the results in with the field's gate closed (the map's ReadGate), so a
// reader sees whole updates only.
#include "umbra/field/distance_field.hpp"

#include <algorithm>
#include <cstdlib>
#include <cmath>
#include <mutex>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include "field/brick_sites.hpp"
#include "field/brick_table.hpp"
#include "field/cell_codes.hpp"
#include "core/thread_pool.hpp"
#include "field/distance_transform.hpp"
#include "field/site_changes.hpp"
#include "map/map_access.hpp"
#include "core/read_gate.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra {

using detail::BrickBits;
using detail::BrickIndex;
using detail::BrickOffsets;
using detail::CellBox;
using detail::FieldLayout;
using detail::kBrickCells;
using detail::SiteOffset;

void DistanceFieldOptions::validate() const {
  if (!(max_distance > 0.0) || !std::isfinite(max_distance)) {
    throw std::invalid_argument("distance field: max_distance must be positive and finite, got " +
                                std::to_string(max_distance));
  }
  if (depth < 0) throw std::invalid_argument("distance field: depth must be >= 0, got " + std::to_string(depth));
  if (threads > ThreadPool::max_threads()) {
    throw std::invalid_argument("distance field: threads " + std::to_string(threads) + " is more than " +
                                std::to_string(ThreadPool::max_threads()));
  }
  if (box) box->validate();
}

namespace {

/// Most bricks a field may hold before it asks for a box (or a smaller one).
constexpr std::size_t kMaxKnownBricks = std::size_t{1} << 23;

/// A stored brick: its sites, the bounds of its cells' nearest sites, and
/// right behind it in the same allocation the cells' coded offsets
/// (CellCodes::bytes_per_brick(): their size is the field's, so one
/// allocation of the header and the cells keeps a query at two cache
/// misses, the table slot and the cell).
struct FieldBrick {
  BrickBits bits;
  detail::SiteBounds bounds;  ///< of the cells' offsets (an update's first test)

  FieldBrick() = default;
  FieldBrick(const FieldBrick&) = delete;  // a copy would leave the cells behind
  FieldBrick& operator=(const FieldBrick&) = delete;

  [[nodiscard]] const unsigned char* cells() const { return reinterpret_cast<const unsigned char*>(this + 1); }
  [[nodiscard]] unsigned char* cells() { return reinterpret_cast<unsigned char*>(this + 1); }

  /// The bytes after the header, for the allocation below.
  struct CellBytes {
    std::size_t count;
  };
  static void* operator new(std::size_t size, CellBytes cells) { return ::operator new(size + cells.count); }
  static void operator delete(void* p, CellBytes) { ::operator delete(p); }
  static void operator delete(void* p) { ::operator delete(p); }
};
static_assert(sizeof(FieldBrick) % alignof(std::uint32_t) == 0);

using BrickMap = detail::BrickTable<FieldBrick>;

std::string point_text(Vec3d p) {
  return "(" + std::to_string(p.x) + ", " + std::to_string(p.y) + ", " + std::to_string(p.z) + ")";
}

/// A brick whose every cell is unknown with no occupied voxel within
/// max_distance: not stored, a query there answers so (see the header).
bool trivial(const BrickOffsets& offsets) {
  for (int i = 0; i < detail::kBrickVolume; ++i) {
    const SiteOffset o = offsets[std::size_t(i)].occupied;
    const SiteOffset u = offsets[std::size_t(i)].unknown;
    if (!o.none() || u.x != 0 || u.y != 0 || u.z != 0) return false;
  }
  return true;
}

/// Whether a narrow window's transform decided every cell of a brick in
/// `kinds` (bit 0 occupied, bit 1 unknown): a cell it answers "none" may
/// have a site beyond that window (distance_transform.hpp, reach_cap()).
bool decided(const BrickOffsets& offsets, int kinds) {
  for (int i = 0; i < detail::kBrickVolume; ++i) {
    if ((kinds & 1) != 0 && offsets[std::size_t(i)].occupied.none()) return false;
    if ((kinds & 2) != 0 && offsets[std::size_t(i)].unknown.none()) return false;
  }
  return true;
}

const BrickBits kAllUnknown = BrickBits::all_unknown();
const BrickBits kNoSites{};

}  // namespace

struct DistanceField::State {
  State(const OccupancyMap& m, const DistanceFieldOptions& o)
      : map(m), options(o), grid(m.grid()), layout(m.resolution(), m.depth_levels(), o.depth, o.max_distance) {}

  const OccupancyMap& map;
  DistanceFieldOptions options;
  Grid grid;
  FieldLayout layout;
  detail::CellCodes codes{layout};
  std::optional<CellBox> box_cells;
  BrickMap bricks;
  std::shared_ptr<detail::ChangeJournal> journal;
  std::uint64_t version = 0;
  std::size_t bricks_recomputed = 0;
  std::size_t bricks_reread = 0;
  std::size_t bricks_transformed = 0;
  std::mutex writer;
  detail::ReadGate gate;
  std::unique_ptr<ThreadPool> pool;  // options.threads != 1

  void set_box(const std::optional<Aabb>& box);
  void rebuild();
  void update();
  /// The window of an update's first transform of its raised bricks: a
  /// third of the field's (16 cells on the TUM benchmark, 2 cm and 1 m,
  /// where it decided 50 to 83% of the raised bricks and the update's
  /// thread CPU fell about 10% against the full window alone, one run
  /// each; docs/benchmarks.md).
  [[nodiscard]] int narrow_window() const { return std::min(layout.window(), std::max(layout.window() / 3, 1)); }
  /// The kinds (bit 0 occupied, bit 1 unknown) in which some cell of brick
  /// `b` (its offsets before the update) had its nearest site among those
  /// `changes` removed (only kinds with removes[kind] are looked at).
  [[nodiscard]] int nearest_site_removed(BrickIndex b, const BrickOffsets& offsets,
                                          const std::unordered_map<std::uint64_t, detail::BrickChange>& changes,
                                          const bool removes[2]) const;

  /// The result of compute(): bricks to store and bricks to drop (trivial),
  /// and those a narrow window left undecided (some cell with no site
  /// within it: compute() again with the full window).
  struct Computed {
    std::vector<std::pair<std::uint64_t, std::unique_ptr<FieldBrick>>> store;
    std::vector<std::uint64_t> drop;
    std::vector<std::uint64_t> undecided;
  };
  /// Recomputes `targets` from `new_sites`, then (with consult_live) the
  /// live bricks, then what a brick not stored holds.
  /// A brick of an update whose transform is needed in some kinds only:
  /// those in `kinds` (bit 0 occupied, bit 1 unknown) come from the
  /// transform, the others from `lowered` (its sites already the new ones).
  struct Partial {
    int kinds = 3;
    std::unique_ptr<BrickOffsets> lowered;
  };
  using Partials = std::unordered_map<std::uint64_t, Partial>;
  /// A brick to store: its sites, and its offsets coded.
  [[nodiscard]] std::unique_ptr<FieldBrick> pack(const BrickBits& bits, const BrickOffsets& offsets) const {
    std::unique_ptr<FieldBrick> brick(new (FieldBrick::CellBytes{codes.bytes_per_brick()}) FieldBrick);
    brick->bits = bits;
    brick->bounds = detail::site_bounds(layout, offsets);
    codes.encode(offsets, brick->cells());
    return brick;
  }
  /// `window`: cells read around the targets (layout.window() by default;
  /// a narrower one, distance_transform.hpp, leaves undecided the bricks
  /// with a cell whose nearest site it cannot prove).
  [[nodiscard]] Computed compute(const std::vector<std::uint64_t>& targets,
                                 const std::unordered_map<std::uint64_t, BrickBits>& new_sites,
                                 bool consult_live, const Partials* partials = nullptr, int window = -1) const;

  /// What a brick that is not stored holds: unknown everywhere (known space
  /// far away, or a trivial brick), or no sites at all outside the box.
  [[nodiscard]] const BrickBits& default_sites(BrickIndex b) const {
    if (!box_cells) return kAllUnknown;
    const std::uint32_t v[3] = {b.x, b.y, b.z};
    for (int a = 0; a < 3; ++a) {
      const std::uint32_t first = v[a] * kBrickCells, last = first + kBrickCells - 1;
      if (first < box_cells->min[std::size_t(a)] || last > box_cells->max[std::size_t(a)]) return kNoSites;
    }
    return kAllUnknown;
  }
  [[nodiscard]] const BrickBits& sites_of(std::uint64_t brick) const {
    const FieldBrick* stored = bricks.find(brick);
    return stored != nullptr ? stored->bits : default_sites(BrickIndex::unpack(brick));
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
  /// The bricks meeting the box.
  template <typename Visit>
  void for_each_box_brick(Visit&& visit) const {
    for (std::uint32_t z = box_cells->min[2] / 8; z <= box_cells->max[2] / 8; ++z) {
      for (std::uint32_t y = box_cells->min[1] / 8; y <= box_cells->max[1] / 8; ++y) {
        for (std::uint32_t x = box_cells->min[0] / 8; x <= box_cells->max[0] / 8; ++x) visit(BrickIndex{x, y, z});
      }
    }
  }
  [[nodiscard]] bool brick_meets_box(BrickIndex b) const {
    if (!box_cells) return true;
    const std::uint32_t v[3] = {b.x, b.y, b.z};
    for (int a = 0; a < 3; ++a) {
      if (v[a] < box_cells->min[std::size_t(a)] / 8 || v[a] > box_cells->max[std::size_t(a)] / 8) return false;
    }
    return true;
  }
  /// Swaps the computed bricks in, with readers kept out.
  void publish(Computed& computed, const std::vector<std::uint64_t>& removed, std::size_t recomputed,
               std::size_t reread, std::size_t transformed) {
    detail::ClosedGate closed(gate);
    for (auto& [key, brick] : computed.store) bricks.insert_or_assign(key, std::move(brick));
    for (const std::uint64_t key : computed.drop) bricks.erase(key);
    for (const std::uint64_t key : removed) bricks.erase(key);
    bricks_recomputed = recomputed;
    bricks_reread = reread;
    bricks_transformed = transformed;
  }

  /// The brick and cell of a point; throws std::out_of_range outside the map or the box.
  struct Located {
    std::uint64_t brick = 0;
    int cell = 0;
  };
  [[nodiscard]] Located locate(Vec3d point) const;
  [[nodiscard]] DistanceSample answer(const FieldBrick* brick, int cell) const;
  [[nodiscard]] DistanceSample sample(Vec3d point) const {
    const Located at = locate(point);
    return answer(bricks.find(at.brick), at.cell);
  }
};

void DistanceField::State::set_box(const std::optional<Aabb>& box) {
  options.box = box;
  box_cells.reset();
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
}

DistanceField::State::Computed DistanceField::State::compute(
    const std::vector<std::uint64_t>& targets, const std::unordered_map<std::uint64_t, BrickBits>& new_sites,
    bool consult_live, const Partials* partials, int window) const {
  if (window < 0) window = layout.window();
  const bool narrow = window < layout.window();
  const auto sites = [&](BrickIndex b) -> const BrickBits* {
    const std::uint64_t key = b.packed();
    if (const auto it = new_sites.find(key); it != new_sites.end()) return &it->second;
    if (consult_live) {
      if (const FieldBrick* stored = bricks.find(key)) return &stored->bits;
    }
    return &default_sites(b);
  };
  const std::unordered_set<std::uint64_t> wanted(targets.begin(), targets.end());
  const std::uint32_t n = std::uint32_t(detail::chunk_bricks(window));
  std::unordered_map<std::uint64_t, int> chunk_kinds;  // the kinds any of its targets needs
  for (const std::uint64_t key : targets) {
    const BrickIndex b = BrickIndex::unpack(key);
    chunk_kinds[BrickIndex{b.x / n * n, b.y / n * n, b.z / n * n}.packed()] |=
        partials != nullptr ? partials->at(key).kinds : 3;
  }
  const std::vector<std::pair<std::uint64_t, int>> chunks(chunk_kinds.begin(), chunk_kinds.end());
  // One transform and one result per worker; chunks are independent.
  const unsigned workers = pool ? pool->size() : 1;
  std::vector<std::unique_ptr<detail::ChunkTransform>> transforms(workers);
  std::vector<Computed> parts(workers);
  const auto work = [&](std::size_t task, unsigned worker) {
    if (!transforms[worker]) transforms[worker] = std::make_unique<detail::ChunkTransform>(layout, window);
    Computed& out = parts[worker];
    transforms[worker]->run(
        BrickIndex::unpack(chunks[task].first), sites, [&](BrickIndex b) { return wanted.contains(b.packed()); },
        [&](BrickIndex b, const BrickOffsets& transformed) {
          if (narrow && !decided(transformed, partials != nullptr ? partials->at(b.packed()).kinds : 3)) {
            out.undecided.push_back(b.packed());
            return;
          }
          const BrickOffsets* offsets = &transformed;
          BrickOffsets merged;
          if (partials != nullptr) {
            const Partial& partial = partials->at(b.packed());
            merged = transformed;
            for (int i = 0; i < detail::kBrickVolume; ++i) {
              detail::CellSites& cell = merged[std::size_t(i)];
              const detail::CellSites& lowered = (*partial.lowered)[std::size_t(i)];
              if ((partial.kinds & 1) == 0) cell.occupied = lowered.occupied;
              if ((partial.kinds & 2) == 0) cell.unknown = lowered.unknown;
            }
            offsets = &merged;
          }
          if (trivial(*offsets)) {
            out.drop.push_back(b.packed());
            return;
          }
          out.store.emplace_back(b.packed(), pack(*sites(b), *offsets));
        },
        chunks[task].second);
  };
  if (pool && chunks.size() > 1) {
    pool->run(chunks.size(), work);
  } else {
    for (std::size_t i = 0; i < chunks.size(); ++i) work(i, 0);
  }
  Computed out = std::move(parts[0]);
  for (unsigned i = 1; i < workers; ++i) {
    for (auto& entry : parts[i].store) out.store.push_back(std::move(entry));
    out.drop.insert(out.drop.end(), parts[i].drop.begin(), parts[i].drop.end());
    out.undecided.insert(out.undecided.end(), parts[i].undecided.begin(), parts[i].undecided.end());
  }
  return out;
}

void DistanceField::State::rebuild() {
  std::unordered_map<std::uint64_t, BrickBits> new_sites;
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
  std::unordered_set<std::uint64_t> targets;
  if (box_cells) {
    for (const auto& [key, bits] : new_sites) targets.insert(key);
  } else {
    // Without a box, the bricks within reach of known space (the rest are
    // unknown with no occupied voxel within max_distance).
    for (const auto& [key, bits] : new_sites) {
      if (!bits.known) continue;
      for_each_neighbour(BrickIndex::unpack(key), layout.brick_reach(),
                         [&](BrickIndex n) { targets.insert(n.packed()); });
    }
  }
  const std::vector<std::uint64_t> target_list(targets.begin(), targets.end());
  Computed computed = compute(target_list, new_sites, /*consult_live=*/false);  // every live brick is replaced
  BrickMap fresh;
  for (auto& [key, brick] : computed.store) fresh.insert_or_assign(key, std::move(brick));
  detail::ClosedGate closed(gate);
  bricks.swap(fresh);
  bricks_recomputed = target_list.size();
  bricks_transformed = target_list.size();
  bricks_reread = new_sites.size();
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
            const std::uint64_t b = BrickIndex{x, y, z}.packed();
            if (!new_sites.contains(b)) new_sites.emplace(b, detail::read_brick(tree, layout, BrickIndex{x, y, z}, box_cells));
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
  // Only the bricks whose sites changed matter: their sites before and after.
  std::unordered_map<std::uint64_t, detail::BrickChange> changes;
  std::vector<BrickIndex> changed;
  for (auto it = new_sites.begin(); it != new_sites.end();) {
    const BrickBits& before = sites_of(it->first);
    if (it->second == before) {
      it = new_sites.erase(it);
    } else {
      changed.push_back(BrickIndex::unpack(it->first));
      changes.emplace(it->first, detail::BrickChange{before, it->second});
      ++it;
    }
  }
  const auto known_after = [&](std::uint64_t key) {
    if (const auto it = new_sites.find(key); it != new_sites.end()) return it->second.known;
    return sites_of(key).known;
  };
  // Which bricks a change may reach: those within reach of it that the
  // field keeps (in the box; without one, stored already or within reach
  // of known space now: a brick not stored is trivial, and only a change
  // holding known space can make it otherwise).
  std::vector<std::uint64_t> target_keys;
  std::vector<std::uint64_t> removed;
  const int reach = layout.brick_reach();
  std::uint32_t lo[3] = {~0u, ~0u, ~0u}, hi[3] = {0, 0, 0};
  for (const BrickIndex b : changed) {
    const std::uint32_t v[3] = {b.x, b.y, b.z};
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], v[a] < std::uint32_t(reach) ? 0u : v[a] - std::uint32_t(reach));
      hi[a] = std::max(hi[a], std::min(v[a] + std::uint32_t(reach), layout.bricks_per_axis() - 1));
    }
  }
  if (changed.empty()) lo[0] = lo[1] = lo[2] = 0;
  detail::BrickMarks target_set(lo, hi);
  for (std::uint32_t c = 0; c < changed.size(); ++c) {
    const BrickIndex b = changed[c];
    const bool known = known_after(b.packed());
    for_each_neighbour(b, reach, [&](BrickIndex n) {
      const std::uint64_t key = n.packed();
      if (target_set.contains(n.x, n.y, n.z, key)) return;
      if (!(box_cells ? brick_meets_box(n) : (known || bricks.contains(key)))) return;
      target_set.insert(n.x, n.y, n.z, key);
      target_keys.push_back(key);
    });
  }
  if (!box_cells) {
    // A stored brick with no known space within reach any more goes.
    detail::BrickKeySet gone;
    for (const BrickIndex b : changed) {
      if (known_after(b.packed()) || !sites_of(b.packed()).known) continue;  // only bricks that became unknown
      for_each_neighbour(b, reach, [&](BrickIndex n) {
        if (!target_set.contains(n.x, n.y, n.z, n.packed()) || gone.contains(n.packed())) return;
        bool near_known = false;
        for_each_neighbour(n, reach, [&](BrickIndex m) { near_known = near_known || known_after(m.packed()); });
        if (!near_known) {
          gone.insert(n.packed());
          removed.push_back(n.packed());
        }
      });
    }
    if (!removed.empty()) {
      std::erase_if(target_keys, [&](std::uint64_t key) { return gone.contains(key); });
    }
  }
  // Per change, the sites it adds and the range of the cells it adds or
  // removes, per kind; a target looks through the changes within reach (a
  // scan of a list of a few thousand beats a list per target).
  std::vector<std::array<std::vector<detail::CellCoord>, 2>> added(changed.size());
  std::vector<detail::ChangeExtent> extents(changed.size());
  for (std::size_t c = 0; c < changed.size(); ++c) {
    const detail::BrickChange& change = changes.at(changed[c].packed());
    extents[c] = detail::change_extent(change, changed[c]);
    for (int kind = 0; kind < 2; ++kind) change.append_added(kind, changed[c], added[c][std::size_t(kind)]);
  }
  // A target whose cells all keep their nearest sites is lowered by the
  // added ones; one with a cell whose nearest site went is transformed
  // again (site_changes.hpp). The target's SiteBounds skip, without
  // reading its cells, the changes too far to matter to it: most targets
  // (every brick within reach of a change) meet none that does.
  const detail::BrickOffsets implicit_offsets = detail::trivial_offsets();
  const detail::SiteBounds implicit_bounds = detail::site_bounds(layout, implicit_offsets);
  // The least S between two whole bricks, by their offset (a target's
  // first, cheapest test against a change).
  const std::int64_t side = 2 * reach + 1;
  std::vector<std::uint32_t> brick_least(std::size_t(side * side * side));
  const BrickIndex centre{std::uint32_t(reach), std::uint32_t(reach), std::uint32_t(reach)};
  for (std::int64_t i = 0; i < side * side * side; ++i) {
    const std::int64_t at[3] = {i % side, i / side % side, i / (side * side)};
    detail::CellRange whole;
    for (int a = 0; a < 3; ++a) {
      whole.lo[a] = at[a] * kBrickCells;
      whole.hi[a] = whole.lo[a] + kBrickCells - 1;
    }
    brick_least[std::size_t(i)] = detail::least_squared(layout, centre, whole);
  }
  const unsigned workers = pool ? pool->size() : 1;
  std::vector<Computed> lowered_parts(workers);
  std::vector<std::vector<std::pair<std::uint64_t, Partial>>> dirty_parts(workers);
  std::vector<std::array<std::vector<detail::AddedSites>, 2>> near_parts(workers);
  std::vector<BrickOffsets> decoded_parts(workers);  // a stored target's offsets, decoded
  const auto lower = [&](std::size_t task, unsigned worker) {
    const std::uint64_t key = target_keys[task];
    const BrickIndex b = BrickIndex::unpack(key);
    const FieldBrick* stored = bricks.find(key);
    const detail::SiteBounds& bounds = stored != nullptr ? stored->bounds : implicit_bounds;
    std::array<std::vector<detail::AddedSites>, 2>& near = near_parts[worker];
    near[0].clear();
    near[1].clear();
    bool may_remove[2] = {false, false};
    const std::uint32_t most_relevant =
        std::max({bounds.farthest[0], bounds.farthest[1], bounds.farthest_site[0], bounds.farthest_site[1]});
    for (std::uint32_t c = 0; c < changed.size(); ++c) {
      const BrickIndex a = changed[c];
      if (std::abs(std::int64_t(a.x) - std::int64_t(b.x)) > reach ||
          std::abs(std::int64_t(a.y) - std::int64_t(b.y)) > reach ||
          std::abs(std::int64_t(a.z) - std::int64_t(b.z)) > reach) {
        continue;
      }
      // The least S between the two bricks as a whole first (a table by
      // the bricks' offset), the changed cells' range only where that passes.
      const std::uint32_t between = brick_least[std::size_t(
          ((std::int64_t(a.z) - b.z + reach) * side + (std::int64_t(a.y) - b.y + reach)) * side +
          (std::int64_t(a.x) - b.x + reach))];
      if (between > most_relevant) continue;
      for (std::size_t kind = 0; kind < 2; ++kind) {
        const detail::ChangeExtent& extent = extents[c];
        // A cell's nearest site is at most farthest_site away: a removed
        // site farther than that from the whole brick was no cell's.
        if (!may_remove[kind] && !extent.removed[kind].empty() &&
            detail::least_squared(layout, b, extent.removed[kind]) <= bounds.farthest_site[kind]) {
          may_remove[kind] = true;
        }
        // An added site lowers (or ties) a cell only within the cap and no
        // farther than the cell's site (lower_by_added_sites() checks the
        // same per site).
        if (!added[c][kind].empty()) {
          const std::uint32_t least = detail::least_squared(layout, b, extent.added[kind]);
          if (least != detail::SiteBounds::kFarthest && layout.within_cap(least) && least <= bounds.farthest[kind]) {
            near[kind].push_back({a, added[c][kind], least});
          }
        }
      }
    }
    // Nearest changes first: they lower the cells' S early, so that the
    // bounds (brick, slab, row) skip more of the farther sites. The result
    // is the same in any order (the least under one total order).
    for (auto& list : near) {
      std::sort(list.begin(), list.end(),
                [](const detail::AddedSites& l, const detail::AddedSites& r) { return l.least < r.least; });
    }
    const auto own = changes.find(key);
    if (!may_remove[0] && !may_remove[1] && near[0].empty() && near[1].empty() && own == changes.end()) {
      return;  // untouched: its cells need not be decoded
    }
    if (stored != nullptr) codes.decode(stored->cells(), decoded_parts[worker]);
    const detail::BrickOffsets& before = stored != nullptr ? decoded_parts[worker] : implicit_offsets;
    const int transform_kinds =
        may_remove[0] || may_remove[1] ? nearest_site_removed(b, before, changes, may_remove) : 0;
    for (int kind = 0; kind < 2; ++kind) {
      if ((transform_kinds >> kind & 1) != 0) near[std::size_t(kind)].clear();  // the transform gives that kind
    }
    if (transform_kinds == 0 && near[0].empty() && near[1].empty() && own == changes.end()) return;  // untouched
    const BrickBits& bits =
        own != changes.end() ? own->second.after : (stored != nullptr ? stored->bits : default_sites(b));
    auto offsets = std::make_unique<BrickOffsets>(before);
    const detail::LoweringResult result = detail::lower_by_added_sites(layout, b, *offsets, near);
    const bool lowered = result.changed;
    if (transform_kinds != 0) {
      dirty_parts[worker].emplace_back(key, Partial{transform_kinds, std::move(offsets)});
      return;
    }
    if (!lowered && own == changes.end()) return;  // nothing to store
    Computed& out = lowered_parts[worker];
    if (trivial(*offsets)) {
      if (stored != nullptr) out.drop.push_back(key);
      return;
    }
    out.store.emplace_back(key, pack(bits, *offsets));
  };
  if (pool && target_keys.size() > 1) {
    pool->run(target_keys.size(), lower);
  } else {
    for (std::size_t i = 0; i < target_keys.size(); ++i) lower(i, 0);
  }
  std::vector<std::uint64_t> dirty;
  Partials partials;
  for (auto& part : dirty_parts) {
    for (auto& [key, partial] : part) {
      dirty.push_back(key);
      partials.emplace(key, std::move(partial));
    }
  }
  // Most raised cells find their new site near them: a narrow window first,
  // the full one only for the bricks it leaves undecided.
  Computed computed = compute(dirty, new_sites, /*consult_live=*/true, &partials, narrow_window());
  if (!computed.undecided.empty()) {
    Computed wide = compute(computed.undecided, new_sites, /*consult_live=*/true, &partials);
    for (auto& entry : wide.store) computed.store.push_back(std::move(entry));
    computed.drop.insert(computed.drop.end(), wide.drop.begin(), wide.drop.end());
  }
  std::size_t lowered_count = 0;
  for (Computed& part : lowered_parts) {
    lowered_count += part.store.size() + part.drop.size();
    for (auto& entry : part.store) computed.store.push_back(std::move(entry));
    computed.drop.insert(computed.drop.end(), part.drop.begin(), part.drop.end());
  }
  publish(computed, removed, dirty.size() + lowered_count, reread, dirty.size());
}

int DistanceField::State::nearest_site_removed(BrickIndex b, const BrickOffsets& offsets,
                                                const std::unordered_map<std::uint64_t, detail::BrickChange>& changes,
                                                const bool removes[2]) const {
  const std::int64_t first[3] = {std::int64_t(b.x) * kBrickCells, std::int64_t(b.y) * kBrickCells,
                                 std::int64_t(b.z) * kBrickCells};
  std::uint64_t last_key = ~std::uint64_t{0};
  const detail::BrickChange* last = nullptr;
  int kinds = 0;
  for (int kind = 0; kind < 2; ++kind) {
    if (!removes[kind]) continue;
    for (int i = 0; i < detail::kBrickVolume; ++i) {
      const SiteOffset o = kind == 0 ? offsets[std::size_t(i)].occupied : offsets[std::size_t(i)].unknown;
      if (o.none()) continue;
      const std::int64_t x = first[0] + (i & 7) + o.x, y = first[1] + ((i >> 3) & 7) + o.y,
                         z = first[2] + (i >> 6) + o.z;
      const std::uint64_t key = BrickIndex{std::uint32_t(x >> 3), std::uint32_t(y >> 3), std::uint32_t(z >> 3)}.packed();
      if (key != last_key) {
        const auto it = changes.find(key);
        last = it != changes.end() ? &it->second : nullptr;
        last_key = key;
      }
      if (last != nullptr &&
          last->removed(kind, detail::cell_in_brick(std::uint32_t(x), std::uint32_t(y), std::uint32_t(z)))) {
        kinds |= 1 << kind;
        break;
      }
    }
  }
  return kinds;
}

DistanceField::State::Located DistanceField::State::locate(Vec3d point) const {
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
  return {BrickIndex{cx >> 3, cy >> 3, cz >> 3}.packed(), detail::cell_in_brick(cx, cy, cz)};
}

DistanceSample DistanceField::State::answer(const FieldBrick* brick, int cell) const {
  DistanceSample out;
  if (brick == nullptr) {  // unknown, and no occupied voxel within max_distance (see the header)
    out.occupied = layout.max_distance();
    out.unknown = 0.0;
    return out;
  }
  const detail::CellSites sites = codes.cell(brick->cells(), cell);
  out.occupied = layout.metres(sites.occupied);
  out.unknown = layout.metres(sites.unknown);
  const SiteOffset nearest =
      sites.occupied.none()
          ? sites.unknown
          : (sites.unknown.none() || layout.squared(sites.occupied) <= layout.squared(sites.unknown) ? sites.occupied
                                                                                                   : sites.unknown);
  if (!nearest.none() && layout.squared(nearest) > 0) {
    // Away from the site: minus the offset's direction, each axis by its gap.
    const std::int8_t d[3] = {nearest.x, nearest.y, nearest.z};
    double v[3];
    for (int a = 0; a < 3; ++a) {
      const double gap = layout.gap(d[a]);
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
  if (options.threads != 1) state_->pool = std::make_unique<ThreadPool>(options.threads);
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

double DistanceField::distance(Vec3d point) const {
  // The blocking distance only: one square root, no gradient (a single
  // query's time is mostly the cache miss on its cell; this is the rest).
  detail::ReadLock lock(state_->gate);
  const State& s = *state_;
  const State::Located at = s.locate(point);
  const FieldBrick* brick = s.bricks.find(at.brick);
  if (brick == nullptr) return 0.0;  // unknown (see answer())
  const detail::CellSites sites = s.codes.cell(brick->cells(), at.cell);
  if (sites.occupied.none()) return s.layout.metres(sites.unknown);
  if (sites.unknown.none()) return s.layout.metres(sites.occupied);
  return s.layout.metres(s.layout.squared(sites.occupied) <= s.layout.squared(sites.unknown) ? sites.occupied
                                                                                             : sites.unknown);
}

DistanceSample DistanceField::distance_and_gradient(Vec3d point) const {
  detail::ReadLock lock(state_->gate);
  return state_->sample(point);
}

namespace {
constexpr std::size_t kBatchChunk = 1024;

/// Answers a batch a chunk at a time, in three passes so that the memory
/// accesses of many points overlap (a query is two cache misses: the table
/// slot, then the cell): locate every point and prefetch its table slot,
/// find every brick and prefetch its cell, then answer. A bad point stops
/// the batch there, its error naming its index.
template <typename Out, typename Convert>
void batch(const DistanceField::State& s, const detail::ReadGate& gate, std::span<const Vec3d> points,
           std::span<Out> out, Convert convert) {
  if (points.size() != out.size()) {
    throw std::invalid_argument("distance field: " + std::to_string(points.size()) + " points but room for " +
                                std::to_string(out.size()) + " answers");
  }
  std::vector<DistanceField::State::Located> located(std::min(points.size(), kBatchChunk));
  std::vector<const FieldBrick*> found(located.size());
  for (std::size_t begin = 0; begin < points.size(); begin += kBatchChunk) {
    const std::size_t count = std::min(points.size() - begin, kBatchChunk);
    std::size_t good = count;
    std::string problem;
    {
      detail::ReadLock lock(gate);  // the box may change between chunks
      for (std::size_t i = 0; i < count; ++i) {
        try {
          located[i] = s.locate(points[begin + i]);
        } catch (const std::out_of_range& e) {
          good = i;
          problem = "point " + std::to_string(begin + i) + ": " + e.what();
          break;
        }
      }
      for (std::size_t i = 0; i < good; ++i) s.bricks.prefetch(located[i].brick);
      for (std::size_t i = 0; i < good; ++i) {
        found[i] = s.bricks.find(located[i].brick);
        if (found[i] != nullptr) __builtin_prefetch(s.codes.cell_address(found[i]->cells(), located[i].cell));
      }
      for (std::size_t i = 0; i < good; ++i) out[begin + i] = convert(s.answer(found[i], located[i].cell));
    }
    if (good < count) throw std::out_of_range(problem);
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
  out.memory_bytes = sizeof(State) + s.codes.memory_bytes() +
                     s.bricks.memory_bytes(sizeof(FieldBrick) + s.codes.bytes_per_brick());
  out.bricks_recomputed = s.bricks_recomputed;
  out.bricks_reread = s.bricks_reread;
  out.bricks_transformed = s.bricks_transformed;
  return out;
}

}  // namespace umbra
