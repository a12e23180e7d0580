// OccupancyTree: the octree of log-odds occupancy with its indicators.
//
// Layout. Nodes live in groups of eight siblings, one pool of groups per
// depth (0 = finest voxel, depth_levels = root). A node is addressed by
// (depth, group index, slot 0..7); the root is slot 0 of group 0 at the top
// depth (the other seven slots of that group are unused).
//
//   LeafGroup, depth 0 (44 bytes)          InnerGroup, depth >= 1 (80 bytes)
//   +-----------------------+------+       +-----------------------+-----------------------+------+---+---+---+
//   | log_odds[8]: float    | mark |       | log_odds[8]: float    | child[8]: uint32      | mark | F | U | S |
//   +-----------------------+------+       +-----------------------+-----------------------+------+---+---+---+
//
// `mark` (12 bytes) is where the group stands with decay applied lazily: the
// stored values are decayed up to step `mark.step` of the tree's decay clock
// and owe what the steps since then took off; `mark.event` bounds what the
// group's subtree can owe before some value in it changes state (see
// "Decay toward unknown" below and tree_decay.cpp).
//
// An inner node either has a group of eight children (child[i] is the index
// of that group in the pool one depth below) or none (kNoGroup): then it is
// an "inner leaf" whose value stands for every voxel it covers. Unknown
// space is explicit: a child that was never observed exists with l = 0.
// For a node with children, log_odds is the maximum of the children (so a
// coarse query never misses an obstacle), F ("contains free") and U
// ("contains unknown") say whether any voxel below is free / unknown, and S
// ("all same") that all eight children are childless and equal. For a
// childless node F and U describe its own value and S is 0. Leaves carry no
// bits: their state is their value. "Contains occupied" is max > threshold.
//
// Color (optional, chosen at construction): every node group carries a
// ColorGroup attached to it in its pool (GroupPool's attached records), so a
// node's color sits at the same (depth, group, slot) with no allocation of
// its own. A voxel's color is the running
// average of the samples it received (`weight` counts them, saturating at
// 255, after which each new sample weighs 1/256); a node with children has
// the rounded average of its colored children. Equal children merge only if
// their colors and weights are equal too.
//
// Invariants (check_invariants() verifies them all): every value lies in the
// clamping range; inner values, F, U, S and colors equal a recomputation
// from the children; with automatic pruning on, no node has S set (eight
// equal childless children are merged into their parent at once).
//
// Costs: a single-voxel update descends from the root and refreshes the
// depth_levels ancestors on the way back; apply(UpdateBatch) updates a whole
// scan in one depth-first walk that visits each touched node once and
// never expands an inner leaf whose whole region gets the same update;
// add_colors() likewise walks a scan's sorted color samples once. With a
// thread pool both split the walk into disjoint subtrees, one worker each.
//
// Decay toward unknown is applied lazily (docs/design.md, "Decay toward
// unknown", Cost): a step appends its amounts to decay_totals_ and walks only
// into groups where some value changes state (reaches 0, crosses a
// threshold); every other group keeps its stored values and owes the steps
// since its mark. Readers compute the owed decay on the fly (current()), so
// they see exactly the values of the eager rule; every writer first brings
// the groups it reads or writes up to date (catch_up()), and lowers the
// event bounds of what it changed (set_childless, refresh_from). Between
// steps no group owes enough to change a state, so indicators, all_same,
// colors and pruning are always those of the eagerly decayed tree.
// The marks live beside the groups (GroupPool's marks), attached when the
// map first decays lazily (track_decay): a map that never decays keeps its
// groups' sizes and reads its values with one predictable branch.
//
// Thread safety: const member functions may run concurrently with each
// other; nothing may run concurrently with a non-const one.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "umbra/core/color.hpp"
#include "umbra/core/log_odds.hpp"
#include "core/thread_pool.hpp"
#include "umbra/core/morton.hpp"
#include "umbra/core/node.hpp"
#include "tree/group_pool.hpp"
#include "tree/update_batch.hpp"

namespace umbra {

namespace detail {
class TreeBuilder;
}

/// A node's position in the tree. The root is {0, 0, depth_levels}.
struct NodeRef {
  std::uint32_t group = 0;
  std::uint8_t slot = 0;
  std::int8_t depth = 0;
  friend bool operator==(NodeRef, NodeRef) = default;
};

enum class NodeKind : unsigned char {
  inner,       ///< has eight children
  inner_leaf,  ///< depth >= 1, no children: its value covers its whole region
  leaf,        ///< depth 0
};

/// What a query finds at a position and depth.
struct NodeSummary {
  float log_odds = 0.0f;        ///< the node's value (max of its voxels)
  bool contains_free = false;
  bool contains_unknown = false;
  bool has_children = false;
  int depth = 0;                ///< depth of the node found (>= the asked depth when an inner leaf covers it)
  NodeRef node;                 ///< where it is
};

class OccupancyTree {
 public:
  /// A group's place in lazily applied decay (file comment).
  struct DecayMark {
    /// Index into decay_totals_: the group's stored values are decayed up to this step.
    std::uint32_t step;
    /// Per side (0: positive values, 1: negative ones), in quanta of 2^-16
    /// log-odds owed since `step`: below this amount no value in the group
    /// or below it changes state (kNoEvent: none ever does). A lower bound.
    std::array<std::uint32_t, 2> event;
  };
  static constexpr std::uint32_t kNoEvent = 0xFFFFFFFFu;
  struct LeafGroup {
    std::array<float, 8> log_odds;
  };
  struct InnerGroup {
    std::array<float, 8> log_odds;
    std::array<std::uint32_t, 8> child;
    std::uint8_t contains_free;
    std::uint8_t contains_unknown;
    std::uint8_t all_same;
  };
  struct ColorGroup {
    std::array<Rgb, 8> rgb;
    std::array<std::uint8_t, 8> weight;  // 0: no color
  };
  static_assert(sizeof(LeafGroup) == 32, "a leaf group is 8 floats (its decay mark lives beside it)");
  static_assert(sizeof(InnerGroup) == 68, "an inner group is 8 floats, 8 indices, 3 bit masks");
  static_assert(sizeof(ColorGroup) == 32, "a color group is 8 RGB triples and 8 weights");

  /// One color observation of a finest voxel.
  struct ColorSample {
    std::uint64_t code;
    Rgb rgb;
  };

  OccupancyTree(int depth_levels, LogOddsRange range, LogOddsThresholds thresholds, bool with_color = false);

  [[nodiscard]] int depth_levels() const { return depth_levels_; }
  [[nodiscard]] NodeRef root() const { return {0, 0, static_cast<std::int8_t>(depth_levels_)}; }
  [[nodiscard]] const LogOddsRange& range() const { return range_; }
  [[nodiscard]] const LogOddsThresholds& thresholds() const { return thresholds_; }
  [[nodiscard]] bool has_color() const { return with_color_; }

  // --- reading -----------------------------------------------------------
  /// The node at `depth` on the path to finest voxel `code` (or the inner
  /// leaf above it that covers it).
  [[nodiscard]] NodeSummary find(std::uint64_t code, int depth) const;
  [[nodiscard]] bool has_children(NodeRef node) const {
    return node.depth > 0 && inner_[node.depth][node.group].child[node.slot] != kNoGroup;
  }
  /// Child `slot` of a node that has children.
  [[nodiscard]] NodeRef child(NodeRef node, unsigned slot) const {
    UMBRA_ASSERT(has_children(node));
    return {inner_[node.depth][node.group].child[node.slot], static_cast<std::uint8_t>(slot),
            static_cast<std::int8_t>(node.depth - 1)};
  }
  [[nodiscard]] float log_odds(NodeRef node) const {
    const float stored =
        node.depth == 0 ? leaves_[node.group].log_odds[node.slot] : inner_[node.depth][node.group].log_odds[node.slot];
    return current(stored, node.depth, node.group);
  }
  /// The node's color; nothing when it has none or the tree has no color.
  [[nodiscard]] std::optional<Rgb> color(NodeRef node) const;
  /// Samples behind a voxel's color (0: none); 1 for a colored inner node.
  [[nodiscard]] std::uint8_t color_weight(NodeRef node) const {
    return has_color() ? colors(node.depth, node.group).weight[node.slot] : 0;
  }
  [[nodiscard]] bool contains_free(NodeRef node) const;
  // Inline: a segment check asks it at every level of every descent, the
  // information gain of every child it walks (3% of a 20 cm query's cycles).
  // The stored value's state is the current one's (no event is due between
  // decay steps), so no decay is computed here.
  [[nodiscard]] bool contains_unknown(NodeRef node) const {
    if (node.depth == 0) return thresholds_.is_unknown(leaves_[node.group].log_odds[node.slot]);
    return (inner_[node.depth][node.group].contains_unknown >> node.slot & 1u) != 0;
  }
  /// True when the node has eight childless children of one value (only
  /// possible while automatic pruning is off).
  [[nodiscard]] bool all_children_same(NodeRef node) const {
    return node.depth > 0 && (inner_[node.depth][node.group].all_same >> node.slot & 1u);
  }

  /// Cursor: repeated lookups along a path (a ray) at the cost of the part
  /// of the path that changed, by caching the groups of the last lookup.
  /// It reads the tree: any change to the tree makes it stale (make a new
  /// one). Not thread-safe; use one cursor per thread (the tree itself may
  /// be read by many).
  class Cursor {
   public:
    explicit Cursor(const OccupancyTree& tree);
    /// Value (the maximum) of the node at `depth` on the path to `code`, or of
    /// the inner leaf above it that covers it.
    float max_log_odds(std::uint64_t code, int depth);

   private:
    const OccupancyTree& tree_;
    std::uint64_t last_code_ = 0;
    std::array<std::uint32_t, kMaxDepthLevels + 1> path_{};  // group per depth, valid from valid_from_ up
    int valid_from_;
  };

  /// Calls visit(node, code) for every childless node, in Morton order;
  /// `code` is the node's first finest voxel.
  template <typename Visit>
  void for_each_leaf(Visit&& visit) const {
    visit_leaves(root(), 0, visit);
  }

  // --- writing -----------------------------------------------------------
  /// Adds `delta` to finest voxel `code` (then clamps), like OctoMap's updateNode.
  void update(std::uint64_t code, float delta);
  /// Sets finest voxel `code` to `log_odds` (clamped).
  void set(std::uint64_t code, float log_odds);
  /// Applies one scan's updates: `hit` to the batch's hit voxels, `miss` to
  /// its misses. With a thread pool, independent subtrees are updated in
  /// parallel; the result is the same, bit for bit.
  void apply(const UpdateBatch& batch, float hit, float miss, ThreadPool* pool = nullptr);
  /// apply() of several batches at once, as if they were merged into one
  /// (UpdateBatch::merge): a voxel with a hit in any of them gets a hit, else
  /// one with a miss in any gets a miss; the map is the one apply() of the
  /// merged batch gives, bit for bit. For batches filled by different
  /// workers, with no serial merge (tree/apply_batches.cpp).
  void apply(std::span<const UpdateBatch* const> batches, float hit, float miss, ThreadPool* pool = nullptr);
  /// One addition for add_to_nodes: `delta` to every voxel of the
  /// depth-`depth` node whose first finest voxel is `code`.
  struct NodeDelta {
    std::uint64_t code;
    int depth;
    float delta;
  };
  /// Adds each region's delta to every voxel it covers (then clamps), in one
  /// depth-first walk: sorted by code, disjoint. A region that is a whole
  /// childless node of the tree changes that node alone, so the cost follows
  /// the regions and the nodes they meet, not the voxels (tree/node_deltas.cpp;
  /// merging maps uses it).
  void add_to_nodes(std::span<const NodeDelta> regions);
  /// Adds one color sample to finest voxel `code` (the tree must have color).
  void add_color(std::uint64_t code, Rgb rgb);
  /// Adds color samples in one walk; sorted by code, each voxel's samples
  /// in the order they were observed (a stable sort keeps it). With a
  /// thread pool, independent subtrees get their samples in parallel; the
  /// result is the same, bit for bit.
  void add_colors(std::span<const ColorSample> samples, ThreadPool* pool = nullptr);
  /// Sets the color of finest voxel `code` with `weight` samples behind it (>= 1).
  void set_color(std::uint64_t code, Rgb rgb, std::uint8_t weight = 1);
  /// Empties the tree (everything unknown).
  void clear();

  // --- indicators, pruning -----------------------------------------------
  /// New thresholds; every indicator is recomputed at once.
  void set_thresholds(LogOddsThresholds thresholds);
  /// New clamping range. Stored values outside it are clamped into it (and
  /// the tree refreshed and pruned), so every value always lies in the range.
  /// OctoMap leaves them until their next update; the difference shows only
  /// when the range is narrowed on a non-empty map.
  void set_range(LogOddsRange range);
  /// With automatic pruning on (the default) eight equal childless children
  /// are merged into their parent as soon as they become equal. Switching it
  /// on prunes the whole tree.
  void set_auto_prune(bool on);
  [[nodiscard]] bool auto_prune() const { return auto_prune_; }
  /// Merges every group of eight equal childless children, bottom up.
  void prune();

  // --- decay toward unknown (tree_decay.cpp; docs/design.md, "Decay toward unknown")
  /// How far one decay step moves values toward 0 (unknown): `occupied` is
  /// taken off positive values, `free` added to negative ones (both >= 0).
  struct DecayStep {
    float occupied = 0.0f;
    float free = 0.0f;
  };
  /// The finest voxels lo <= key <= hi (inclusive, every axis).
  struct KeyBox {
    Key lo;
    Key hi;
  };
  /// A node some voxel of which changed state in a decay step.
  struct DecayChange {
    std::uint64_t code;  ///< first finest voxel of the node
    int depth;
  };
  /// The decay rule for one value: 0 when |value| <= the step for its sign,
  /// else value moved toward 0 by that step (single precision). Monotone, so
  /// the maximum of decayed values is the decayed maximum.
  [[nodiscard]] static float decayed(float value, DecayStep step) {
    if (value > 0.0f) return value > step.occupied ? value - step.occupied : 0.0f;
    if (value < 0.0f) return -value > step.free ? value + step.free : 0.0f;
    return 0.0f;
  }
  /// Applies `step` to every finest voxel (inside `region` when given); a
  /// voxel reaching 0 becomes unknown as if never observed (its color is
  /// dropped). Walks only subtrees where some value can change; inner
  /// values, indicators and pruning are refreshed on the way back. With
  /// `changes`, appends the nodes of depth >= `change_depth` (childless
  /// coarser ones at their own depth) in which some voxel changed state.
  /// With a thread pool and no region, disjoint subtrees decay in parallel;
  /// the result (and the list of changes) is the same, bit for bit.
  ///
  /// Without a region the step is lazy (file comment): it costs the groups
  /// where some value changes state and their ancestors, not the map.
  /// `pool` is unused (kept for the callers; the lazy walk is serial). With a
  /// region, every group is first brought up to date and the step walks
  /// every known node in the region (decay_eagerly()'s walk).
  void decay(DecayStep step, const std::optional<KeyBox>& region, std::vector<DecayChange>* changes = nullptr,
             int change_depth = 0, ThreadPool* pool = nullptr);
  /// The same step, applied at once to every known node: the walk decay()
  /// did before it was lazy, kept as the reference the tests compare the
  /// lazy step with (and the region's walk).
  void decay_eagerly(DecayStep step, const std::optional<KeyBox>& region = std::nullopt,
                     std::vector<DecayChange>* changes = nullptr, int change_depth = 0);
  /// Starts keeping every group's event bounds (one walk of the tree, the
  /// first time; the first lazy step does it otherwise), so that the steps
  /// after it cost only what changes state. The map calls it when decay is
  /// switched on; writers then maintain the bounds as they go.
  void track_decay();
  /// Brings every group up to date with the decay it owes (O(nodes)); the
  /// map reads the same before and after.
  void settle_decay();
  /// Groups the lazy steps walked so far (tests, benchmarks).
  [[nodiscard]] std::uint64_t decay_groups_walked() const { return decay_groups_walked_; }

  // --- a map that moves (tree_window.cpp; docs/design.md, "A map that moves")
  /// Makes every finest voxel outside `keep` unknown as if never observed
  /// (color dropped) and frees the subtrees that lie wholly outside it. The
  /// walk descends only into nodes that `keep`'s faces cut and that hold
  /// something known, so with a box aligned to depth-d nodes its cost is the
  /// nodes it frees plus the cut nodes above depth d. Subtrees are freed even
  /// with automatic pruning off (as clear() does). With `changes`, appends
  /// the nodes of depth >= `change_depth` (childless coarser ones at their
  /// own depth) that held something known outside `keep`. Returns the
  /// number of groups of eight nodes freed.
  std::size_t forget_outside(const KeyBox& keep, std::vector<DecayChange>* changes = nullptr, int change_depth = 0);

  // --- statistics, checks ------------------------------------------------
  [[nodiscard]] NodeCounts count_nodes() const;
  /// Bytes allocated for the tree (capacity, not use).
  [[nodiscard]] std::size_t memory_bytes() const;
  /// Empty when every invariant in the file comment holds, else the first violation.
  [[nodiscard]] std::string check_invariants() const;

 private:
  // --- building: only through TreeBuilder (file readers) ------------------
  friend class detail::TreeBuilder;
  /// Gives a childless node eight children that all carry its value.
  void subdivide(NodeRef node);
  /// Sets a childless node's value without touching its ancestors; call
  /// refresh_all() when done.
  void set_childless_value(NodeRef node, float log_odds);
  /// Sets a childless node's color (weight 0: no color); then refresh_all().
  void set_childless_color(NodeRef node, Rgb rgb, std::uint8_t weight);
  /// Recomputes every inner value and indicator bottom up (no pruning).
  void refresh_all();

  template <typename Visit>
  void visit_leaves(NodeRef node, std::uint64_t first_code, Visit& visit) const {
    if (!has_children(node)) {
      visit(node, first_code);
      return;
    }
    const int child_depth = node.depth - 1;
    const std::uint32_t group = inner_[node.depth][node.group].child[node.slot];
    for (unsigned slot = 0; slot < 8; ++slot) {
      visit_leaves(NodeRef{group, static_cast<std::uint8_t>(slot), static_cast<std::int8_t>(child_depth)},
                   first_code | (std::uint64_t{slot} << (3 * child_depth)), visit);
    }
  }

  // Nodes are passed as (depth, group index, slot); references into a pool
  // are taken only where nothing allocates in that pool meanwhile.
  std::uint32_t new_leaf_group(float value);
  std::uint32_t new_inner_group(int depth, float value);
  ColorGroup& colors(int depth, std::uint32_t group) {
    return depth == 0 ? leaves_.attached(group) : inner_[depth].attached(group);
  }
  [[nodiscard]] const ColorGroup& colors(int depth, std::uint32_t group) const {
    return depth == 0 ? leaves_.attached(group) : inner_[depth].attached(group);
  }
  void release_group(int depth, std::uint32_t group);
  /// Value and indicator bits of a childless slot (its color is kept).
  void set_childless(int depth, std::uint32_t group, unsigned slot, float value);
  /// Gives a childless node eight children with its value and color.
  void expand(int depth, std::uint32_t group, unsigned slot);
  /// What a node with children takes from them (the child group `child` one depth below).
  struct ChildrenSummary {
    float max;         ///< maximum value
    bool any_free;     ///< some voxel below is free
    bool any_unknown;  ///< some voxel below is unknown
    bool same;         ///< all eight childless and of one value
  };
  [[nodiscard]] ChildrenSummary summarize_children(int depth, std::uint32_t child) const;
  /// Recomputes a node with children from them; prunes when allowed.
  void refresh(int depth, std::uint32_t group, unsigned slot, bool allow_prune);
  /// refresh() with the children's summary already known.
  void refresh_from(int depth, std::uint32_t group, unsigned slot, const ChildrenSummary& summary, bool allow_prune);
  void apply_group(int depth, std::uint32_t group, const UpdateBatch& batch, std::uint32_t batch_group,
                   float hit, float miss);
  void apply_in_parallel(const UpdateBatch& batch, float hit, float miss, ThreadPool& pool);
  /// A group of one of the batches apply(batches) writes, at the walk's depth.
  struct BatchGroup {
    const UpdateBatch* batch;
    std::uint32_t group;
  };
  /// apply(batches) below map group `group` at `depth`: `todo` holds the
  /// batches' groups there (all of the same node), `missed` says every voxel
  /// below gets a miss from a full node above. `scratch` has room for one
  /// list of batch groups per depth (tree/apply_batches.cpp).
  void apply_groups(int depth, std::uint32_t group, std::span<const BatchGroup> todo, bool missed, float hit,
                    float miss, std::span<BatchGroup> scratch);
  /// What apply(batches) does to a slot of a node: nothing, a miss to its
  /// whole region, or a walk below (`children`, the batches' groups there).
  enum class SlotUpdate : std::uint8_t { none, everywhere, below };
  SlotUpdate slot_update(int depth, unsigned slot, std::span<const BatchGroup> todo, bool missed,
                         std::span<BatchGroup> scratch, std::span<const BatchGroup>& children,
                         bool& children_missed) const;
  void apply_batches_in_parallel(std::span<const UpdateBatch* const> batches, float hit, float miss,
                                 ThreadPool& pool);
  /// A node above the subtrees of a parallel phase, refreshed after it.
  struct SplitNode {
    int depth;
    std::uint32_t group;
    unsigned slot;
  };
  /// Runs task(i) for i in [0, tasks) on the pool, the pools allocating per
  /// worker; new_groups[d] bounds the groups the tasks add at depth d. Then
  /// refreshes `parents` (listed top down) bottom up.
  void run_concurrently(ThreadPool& pool, const std::vector<std::size_t>& new_groups, std::size_t tasks,
                        const std::function<void(std::size_t)>& task, const std::vector<SplitNode>& parents);
  void add_to_nodes_below(int depth, std::uint32_t group, unsigned slot, std::span<const NodeDelta> regions);
  void add_to_nodes_in_group(int depth, std::uint32_t group, std::span<const NodeDelta> regions);
  void apply_brick(std::uint32_t group, const UpdateBatch::Brick& todo, float hit, float miss);
  void apply_everywhere(int depth, std::uint32_t group, unsigned slot, float delta);
  void prune_below(int depth, std::uint32_t group, unsigned slot);
  void refresh_below(int depth, std::uint32_t group, unsigned slot);
  void clamp_below(int depth, std::uint32_t group, unsigned slot);
  using Path = std::array<std::uint32_t, kMaxDepthLevels + 1>;
  /// Walks to finest voxel `code`, splitting inner leaves on the way; returns
  /// its leaf group and fills path[d] with the group at depth d.
  std::uint32_t descend_splitting(std::uint64_t code, Path& path);
  /// Refreshes (and prunes) every ancestor of `code` along `path`, bottom up.
  void refresh_path(std::uint64_t code, const Path& path);
  void add_colors_below(int depth, std::uint32_t group, unsigned slot, std::span<const ColorSample> samples);
  /// The samples of group `group` at `depth` (all in it), slot by slot.
  void add_colors_to_group(int depth, std::uint32_t group, std::span<const ColorSample> samples);
  void add_colors_in_parallel(std::span<const ColorSample> samples, ThreadPool& pool);
  /// Running average of a voxel's color with one more sample.
  static void blend(Rgb& rgb, std::uint8_t& weight, Rgb sample);
  /// decay_eagerly() below node (depth, group, slot) whose first voxel is
  /// `code`; true when some voxel below changed state.
  bool decay_below(int depth, std::uint32_t group, unsigned slot, std::uint64_t code, DecayStep step,
                   const std::optional<KeyBox>& region, std::vector<DecayChange>* changes, int change_depth);

  // --- lazily applied decay (tree_decay.cpp) -------------------------------
  [[nodiscard]] std::uint32_t decay_now() const { return static_cast<std::uint32_t>(decay_totals_.size() - 1); }
  /// What a group marked at step `step` owes, in quanta per side.
  [[nodiscard]] std::array<std::int64_t, 2> owed_quanta(std::uint32_t step) const {
    const auto& from = decay_totals_[step];
    const auto& to = decay_totals_.back();
    return {to[0] - from[0], to[1] - from[1]};
  }
  [[nodiscard]] DecayStep owed_step(std::uint32_t step) const;
  /// The decay mark of group `group` at `depth` (only while decay_tracked_).
  DecayMark& mark(int depth, std::uint32_t group) {
    return depth == 0 ? leaves_.mark(group) : inner_[depth].mark(group);
  }
  [[nodiscard]] const DecayMark& mark(int depth, std::uint32_t group) const {
    return depth == 0 ? leaves_.mark(group) : inner_[depth].mark(group);
  }
  /// A stored value as the eager rule has it now.
  [[nodiscard]] float current(float stored, const DecayMark& mark) const {
    return mark.step == decay_now() ? stored : decayed(stored, owed_step(mark.step));
  }
  /// A stored value of group `group` at `depth` as the eager rule has it
  /// now. Without tracked decay nothing is ever owed (and there are no
  /// marks): one predictable branch.
  [[nodiscard]] float current(float stored, int depth, std::uint32_t group) const {
    return decay_tracked_ ? current(stored, mark(depth, group)) : stored;
  }
  /// True when what the group owes may change a state below it.
  [[nodiscard]] bool decay_due(const DecayMark& mark) const;
  /// Applies what the group owes to its values (no state changes: none is
  /// due outside a step's walk) and marks it up to date. O(8); nothing when
  /// it is. Every writer calls it before it reads or writes a group.
  void catch_up(int depth, std::uint32_t group) {
    if (!decay_tracked_) return;
    DecayMark& own = mark(depth, group);
    if (own.step == decay_now()) return;
    catch_up_values(depth == 0 ? leaves_[group].log_odds : inner_[depth][group].log_odds, own);
  }
  void catch_up_values(std::array<float, 8>& values, DecayMark& mark) const;
  /// A new group's mark: up to date, with the events of its one value.
  [[nodiscard]] DecayMark new_mark(float value) const;
  /// Gives every group of every pool a mark (up to date, no events yet).
  void attach_marks();
  /// Lowers `event` to the events of `value` (when decay is tracked).
  void lower_events(std::array<std::uint32_t, 2>& event, float value) const;
  /// The exact events of a leaf group's values (when decay is tracked).
  void set_leaf_events(std::uint32_t group);
  /// The events of eight values: lower_events of each, from kNoEvent.
  [[nodiscard]] std::array<std::uint32_t, 2> events_of(const std::array<float, 8>& values) const;
  /// The lazy step's walk into group `group` of `depth` (due), whose first
  /// voxel is `code`; true when some voxel below changed state.
  bool decay_group(int depth, std::uint32_t group, std::uint64_t code, std::vector<DecayChange>* changes,
                   int change_depth);
  /// Recomputes every group's events exactly (decay up to date), bottom up.
  std::array<std::uint32_t, 2> recompute_events(int depth, std::uint32_t group);
  void settle_below(int depth, std::uint32_t group);
  /// check_invariants() of the decay marks below group `group` of `depth`:
  /// `event` gets the exact events of the subtree, owed decay applied.
  std::string check_marks(int depth, std::uint32_t group, std::array<std::int64_t, 2>& event) const;
  /// Drops a node's color (no-op without color).
  void forget_color(int depth, std::uint32_t group, unsigned slot);
  /// Decays leaf `slot` of leaf group `group` by `step` (its color dropped at 0);
  /// true when its state (occupied, free, unknown) changed.
  bool decay_leaf(std::uint32_t group, unsigned slot, DecayStep step);
  /// forget_outside() below node (depth, group, slot) whose first voxel is
  /// `code`; true when something known below was forgotten.
  bool forget_outside_below(int depth, std::uint32_t group, unsigned slot, std::uint64_t code, const KeyBox& keep,
                            std::vector<DecayChange>* changes, int change_depth, std::size_t& freed);
  /// Returns group `group` of depth `depth` and every group below it to their pools.
  void release_subtree(int depth, std::uint32_t group, std::size_t& freed);
  std::string check_node(int depth, std::uint32_t group, unsigned slot, std::vector<std::vector<bool>>& seen) const;

  int depth_levels_;
  LogOddsRange range_;
  LogOddsThresholds thresholds_;
  bool auto_prune_ = true;
  bool with_color_;
  bool concurrent_ = false;  // inside run_concurrently: pools allocate per worker
  // Lazily applied decay: entry k holds the quanta (positive side, negative
  // side) the steps up to k took off in all; a group's mark.step indexes it.
  std::vector<std::array<std::int64_t, 2>> decay_totals_{{0, 0}};
  // Events are kept (lower_events, set_leaf_events) from the first lazy step on.
  bool decay_tracked_ = false;
  std::uint64_t decay_groups_walked_ = 0;
  // With color every group has its ColorGroup attached (colors()).
  // With tracked decay every group has its DecayMark too (mark()).
  GroupPool<LeafGroup, ColorGroup, DecayMark> leaves_;
  std::vector<GroupPool<InnerGroup, ColorGroup, DecayMark>> inner_;  // index = depth; [0] is unused
};

}  // namespace umbra
