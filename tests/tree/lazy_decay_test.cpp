// Lazily applied decay (tree/tree_decay.cpp; docs/design.md "Decay toward
// unknown", Cost) against the eager walk it replaced, kept as the reference
// (OccupancyTree::decay_eagerly). Two trees get the same random sequence of
// writes (scans as update batches, serially, on threads and several at once,
// single voxels, per-node additions, colors, clamping range, thresholds,
// pruning switched, a moving window's forgetting) interleaved with decay
// steps: one tree decays lazily, the other eagerly. After every operation the
// trees must agree node for node at every depth (shape, value bit for bit,
// indicators, all_same, color), the changes a step reports must be the same,
// and check_invariants() must hold (for the lazy tree it also checks every
// group's decay mark: nothing owed that changes a state, no event bound
// above its subtree's values). A writer that forgot to bring a group up to
// date (or to lower its event bound) shows up here as a differing value.
#include <algorithm>
#include <bit>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/thread_pool.hpp"
#include "tree/occupancy_tree.hpp"

namespace umbra {
namespace {

const SensorModel kSensor;
const LogOddsRange kRange = LogOddsRange::from(kSensor);

/// The first difference between two trees, node by node from the root; empty when none.
std::string difference(const OccupancyTree& lazy, const OccupancyTree& eager, NodeRef a, NodeRef b,
                       std::uint64_t code) {
  const auto where = [&] { return "depth " + std::to_string(a.depth) + " code " + std::to_string(code) + ": "; };
  if (lazy.has_children(a) != eager.has_children(b)) return where() + "children differ";
  const float la = lazy.log_odds(a);
  const float lb = eager.log_odds(b);
  if (std::bit_cast<std::uint32_t>(la) != std::bit_cast<std::uint32_t>(lb)) {
    return where() + "value " + std::to_string(la) + " lazily, " + std::to_string(lb) + " eagerly";
  }
  if (lazy.contains_free(a) != eager.contains_free(b)) return where() + "contains_free differs";
  if (lazy.contains_unknown(a) != eager.contains_unknown(b)) return where() + "contains_unknown differs";
  if (lazy.all_children_same(a) != eager.all_children_same(b)) return where() + "all_same differs";
  if (lazy.color(a) != eager.color(b) || lazy.color_weight(a) != eager.color_weight(b)) return where() + "color differs";
  if (!lazy.has_children(a)) return {};
  for (unsigned i = 0; i < 8; ++i) {
    std::string problem = difference(lazy, eager, lazy.child(a, i), eager.child(b, i),
                                     code | (std::uint64_t{i} << (3 * (a.depth - 1))));
    if (!problem.empty()) return problem;
  }
  return {};
}

struct Case {
  int depth_levels;
  bool auto_prune;
  bool color;
  Thresholds thresholds;
};

void run_case(const Case& c, unsigned seed) {
  SCOPED_TRACE("depth " + std::to_string(c.depth_levels) + " prune " + std::to_string(c.auto_prune) + " color " +
               std::to_string(c.color) + " seed " + std::to_string(seed));
  OccupancyTree lazy(c.depth_levels, kRange, LogOddsThresholds::from(c.thresholds), c.color);
  lazy.set_auto_prune(c.auto_prune);
  OccupancyTree eager = lazy;
  std::mt19937 rng(seed);
  const std::uint32_t size = 1u << c.depth_levels;
  // Writes go to one corner of the map (a quarter along each axis) most of the
  // time, so that the same voxels are written, decayed and written again.
  const auto code = [&] {
    const std::uint32_t span = rng() % 4 == 0 ? size : std::max<std::uint32_t>(size / 4, 2);
    return morton::encode({static_cast<std::uint32_t>(rng() % span), static_cast<std::uint32_t>(rng() % span),
                           static_cast<std::uint32_t>(rng() % span)});
  };
  const auto node_code = [&](int depth) { return code() >> (3 * depth) << (3 * depth); };
  ThreadPool pool(3);
  std::uniform_real_distribution<float> value(kRange.min, kRange.max);

  const auto random_batch = [&] {
    UpdateBatch batch(c.depth_levels);
    for (int i = 0; i < 40; ++i) batch.add_miss(code());
    for (int i = 0; i < 3; ++i) {
      const int depth = 1 + static_cast<int>(rng() % std::min(3, c.depth_levels - 1));
      batch.add_miss_node(node_code(depth), depth);
    }
    for (int i = 0; i < 15; ++i) batch.add_hit(code());
    return batch;
  };
  std::uniform_int_distribution<int> quanta(1, 20000);  // up to 0.3 log-odds a step
  std::string step_log;
  for (int op = 0; op < 140; ++op) {
    const int kind = static_cast<int>(rng() % 20);
    std::string what;
    if (kind < 6) {
      // A decay step of whole quanta, sometimes of one side only.
      OccupancyTree::DecayStep step{static_cast<float>(quanta(rng)) / 65536.0f,
                                    static_cast<float>(quanta(rng)) / 65536.0f};
      if (kind == 0) step.occupied = 0.0f;
      if (kind == 1) step.free = 0.0f;
      std::vector<OccupancyTree::DecayChange> lazy_changes;
      std::vector<OccupancyTree::DecayChange> eager_changes;
      const int change_depth = static_cast<int>(rng() % 3);
      if (kind == 5) {
        // A region's step: the lazy tree settles, then walks the region eagerly.
        const auto axis = [&](std::uint32_t n) { return static_cast<std::uint32_t>(rng() % n); };
        const Key lo{axis(size), axis(size), axis(size)};
        const auto hi = [&](std::uint32_t from) { return std::min(from + axis(4), size - 1); };
        const OccupancyTree::KeyBox box{lo, {hi(lo.x), hi(lo.y), hi(lo.z)}};
        lazy.decay(step, box, &lazy_changes, change_depth);
        eager.decay_eagerly(step, box, &eager_changes, change_depth);
      } else {
        lazy.decay(step, std::nullopt, &lazy_changes, change_depth);
        eager.decay_eagerly(step, std::nullopt, &eager_changes, change_depth);
      }
      ASSERT_EQ(lazy_changes.size(), eager_changes.size()) << "op " << op;
      for (std::size_t i = 0; i < lazy_changes.size(); ++i) {
        ASSERT_EQ(lazy_changes[i].code, eager_changes[i].code) << "op " << op << " change " << i;
        ASSERT_EQ(lazy_changes[i].depth, eager_changes[i].depth) << "op " << op << " change " << i;
      }
      what = "decay step";
    } else if (kind < 10) {
      const UpdateBatch batch = random_batch();
      const float hit = kSensor.hit_log_odds();
      const float miss = kSensor.miss_log_odds();
      ThreadPool* threads = kind == 9 ? &pool : nullptr;
      lazy.apply(batch, hit, miss, threads);
      eager.apply(batch, hit, miss, threads);
      what = threads ? "scan on threads" : "scan";
    } else if (kind == 10) {
      // Several batches at once (apply_batches.cpp), on threads.
      const UpdateBatch a = random_batch();
      const UpdateBatch b = random_batch();
      const std::vector<const UpdateBatch*> both{&a, &b};
      lazy.apply(both, kSensor.hit_log_odds(), kSensor.miss_log_odds(), &pool);
      eager.apply(both, kSensor.hit_log_odds(), kSensor.miss_log_odds(), &pool);
      what = "batches";
    } else if (kind == 11) {
      const std::uint64_t at = code();
      const float delta = value(rng);
      lazy.update(at, delta);
      eager.update(at, delta);
      what = "update";
    } else if (kind == 12) {
      const std::uint64_t at = code();
      const float v = rng() % 4 == 0 ? 0.0f : value(rng);
      lazy.set(at, v);
      eager.set(at, v);
      what = "set";
    } else if (kind == 13) {
      // Per-node additions (merging maps): disjoint nodes, sorted.
      std::vector<OccupancyTree::NodeDelta> regions;
      for (int i = 0; i < 6; ++i) {
        const int depth = static_cast<int>(rng() % 3);
        regions.push_back({node_code(depth), depth, value(rng) * 0.5f});
      }
      std::sort(regions.begin(), regions.end(), [](const auto& x, const auto& y) { return x.code < y.code; });
      std::vector<OccupancyTree::NodeDelta> disjoint;
      for (const auto& r : regions) {
        if (!disjoint.empty()) {
          const auto& last = disjoint.back();
          const std::uint64_t end = last.code + (std::uint64_t{1} << (3 * last.depth));
          if (r.code < end) continue;
        }
        disjoint.push_back(r);
      }
      lazy.add_to_nodes(disjoint);
      eager.add_to_nodes(disjoint);
      what = "add_to_nodes";
    } else if (kind == 14 && c.color) {
      std::vector<OccupancyTree::ColorSample> samples;
      for (int i = 0; i < 20; ++i) {
        samples.push_back({code(), Rgb{static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng()),
                                       static_cast<std::uint8_t>(rng())}});
      }
      std::stable_sort(samples.begin(), samples.end(), [](const auto& x, const auto& y) { return x.code < y.code; });
      ThreadPool* threads = rng() % 2 == 0 ? &pool : nullptr;
      lazy.add_colors(samples, threads);
      eager.add_colors(samples, threads);
      what = "colors";
    } else if (kind == 15) {
      // New thresholds, either side of 0.5 (the events depend on them).
      const double occupied = 0.5 + 0.2 * static_cast<double>(rng() % 100) / 100.0;
      const double free = 0.3 + 0.3 * static_cast<double>(rng() % 100) / 100.0;
      const LogOddsThresholds t = LogOddsThresholds::from(Thresholds{occupied, std::min(free, occupied)});
      lazy.set_thresholds(t);
      eager.set_thresholds(t);
      what = "thresholds";
    } else if (kind == 16) {
      const std::uint64_t at = code();
      const Key key = morton::decode(at);
      const std::uint32_t half = size / 2;
      const OccupancyTree::KeyBox keep{{key.x / 2, key.y / 2, key.z / 2},
                                       {std::min(key.x / 2 + half, size - 1), std::min(key.y / 2 + half, size - 1),
                                        std::min(key.z / 2 + half, size - 1)}};
      EXPECT_EQ(lazy.forget_outside(keep), eager.forget_outside(keep));
      what = "forget_outside";
    } else if (kind == 17 && op % 3 == 0) {
      const LogOddsRange range{kRange.min * 0.8f, kRange.max * 0.9f};
      lazy.set_range(range);
      eager.set_range(range);
      what = "range";
    } else if (kind == 18 && op % 4 == 0) {
      lazy.set_auto_prune(!lazy.auto_prune());
      eager.set_auto_prune(!eager.auto_prune());
      what = "auto_prune";
    } else if (kind == 19) {
      // A copy of the lazy tree (the copy owes what the original owes).
      OccupancyTree copy = lazy;
      lazy = copy;
      what = "copy";
    } else {
      continue;
    }
    ASSERT_EQ(difference(lazy, eager, lazy.root(), eager.root(), 0), "") << "after op " << op << " (" << what << ")";
    ASSERT_EQ(lazy.check_invariants(), "") << "after op " << op << " (" << what << ")";
    ASSERT_EQ(eager.check_invariants(), "") << "after op " << op << " (" << what << ")";
  }
}

TEST(LazyDecay, EqualsTheEagerWalkNodeForNodeThroughWritesAndSteps) {
  unsigned seed = 1;
  for (const int depth : {3, 5, 7}) {
    for (const bool prune : {true, false}) {
      for (const bool color : {false, true}) {
        run_case({depth, prune, color, Thresholds{}}, seed++);
        run_case({depth, prune, color, Thresholds{0.6, 0.4}}, seed++);
        run_case({depth, prune, color, Thresholds{0.7, 0.55}}, seed++);
      }
    }
  }
}

/// The point of it: a step costs the groups where something changes state,
/// not the map. A map of values far from any event takes steps that walk
/// nothing below the root (the mark of every other group stays untouched),
/// and reads still see every step's decay.
TEST(LazyDecay, StepsFarFromEventsLeaveTheGroupsBelowTheRootAlone) {
  OccupancyTree tree(6, kRange, LogOddsThresholds::from(Thresholds{}));
  tree.set_auto_prune(false);
  std::mt19937 rng(5);
  std::vector<std::uint64_t> codes;
  for (int i = 0; i < 200; ++i) {
    const auto axis = [&] { return static_cast<std::uint32_t>(rng() % 64); };
    codes.push_back(morton::encode({axis(), axis(), axis()}));
    tree.set(codes.back(), 3.0f);  // 3 log-odds from unknown, 3 from the thresholds (0)
  }
  const OccupancyTree::DecayStep step{1.0f / 1024.0f, 0.0f};  // 64 quanta
  for (int s = 0; s < 100; ++s) tree.decay(step, std::nullopt);
  EXPECT_EQ(tree.decay_groups_walked(), 0u);
  const float expected = 3.0f - 100.0f / 1024.0f;
  for (const std::uint64_t code : codes) ASSERT_EQ(tree.find(code, 0).log_odds, expected);
  ASSERT_EQ(tree.check_invariants(), "");
  // Settled, the stored values are the read ones.
  tree.settle_decay();
  for (const std::uint64_t code : codes) ASSERT_EQ(tree.find(code, 0).log_odds, expected);
  ASSERT_EQ(tree.check_invariants(), "");
  // A step that takes them all to 0 walks their groups, and the tree prunes
  // back to an empty one.
  tree.set_auto_prune(true);
  tree.decay({3.0f, 0.0f}, std::nullopt);
  EXPECT_GT(tree.decay_groups_walked(), 200u);
  EXPECT_FALSE(tree.has_children(tree.root()));
  EXPECT_EQ(tree.log_odds(tree.root()), 0.0f);
}

}  // namespace
}  // namespace umbra
