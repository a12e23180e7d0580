// OccupancyTree::decay: every value moves toward 0 (unknown) by one step
// (docs/design.md, "Decay toward unknown"), applied lazily.
//
// A step appends its amounts (whole quanta of 2^-16 log-odds) to
// decay_totals_ and walks only into groups where some value changes state:
// each group's mark says up to which step its values are decayed and, per
// side, how much more decay the group and everything below it can take
// before some value reaches 0 or crosses a threshold (its events). Between
// events only values move, all by the same amount and monotonically, so
// inner values (maxima), indicators, all_same bits, colors and pruning stay
// what the eager rule gives; readers add what a group owes on the fly
// (current()), writers first apply it (catch_up()). Decay amounts of whole
// quanta compose exactly in single precision (|l| < 256), so applying what
// a group owes late, in one go, gives the bits the steps would have given.
//
// A due group is walked: its values are brought up to date (childless ones
// changing state get their indicators, color, journal entry), the due child
// groups below are walked and their parents refreshed (value, indicators,
// color, pruning), and the group's events are recomputed. So a step costs
// the groups where something changes state and their ancestors (and, once
// the table of steps outgrows the tree, one walk of every group that settles
// what they owe: amortised, a few per cent of a group per step).
//
// decay_eagerly() is the walk of every known node, kept as the tests'
// reference and for steps limited to a region: one depth-first walk that
// skips subtrees whose values are all 0, or all of a sign whose step is 0,
// and subtrees outside the region; on the way back each node is refreshed
// from its children, as apply() does.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "tree/key_box_overlap.hpp"
#include "tree/occupancy_tree.hpp"

namespace umbra {
using detail::Overlap;
using detail::overlap;

void OccupancyTree::forget_color(int depth, std::uint32_t group, unsigned slot) {
  // A voxel decayed to unknown is as if never observed: no color either.
  if (!has_color()) return;
  ColorGroup& own = colors(depth, group);
  own.rgb[slot] = Rgb{};
  own.weight[slot] = 0;
}

namespace {

constexpr double kQuantaPerLogOdds = 65536.0;  // map_decay.cpp's quantum, 2^-16 log-odds
/// Owed amounts from this many quanta (256 log-odds) on take every value to 0.
constexpr std::int64_t kAllQuanta = std::int64_t{1} << 24;

float amount_of(std::int64_t quanta) {
  return quanta >= kAllQuanta ? 1e30f : static_cast<float>(quanta) / 65536.0f;  // exact below 2^24
}

/// A step's amount in quanta; nothing when it is not a whole number of them.
std::optional<std::int64_t> quanta_of(float amount) {
  if (amount >= 256.0f) return kAllQuanta;
  const double quanta = static_cast<double>(amount) * kQuantaPerLogOdds;
  if (quanta != std::floor(quanta)) return std::nullopt;
  return static_cast<std::int64_t>(quanta);
}

/// Quanta of decay below which a value `distance` log-odds from its next
/// event keeps its state: one less than whole quanta, so that rounding can
/// only make an event early (which costs a visit, never a wrong state).
std::uint32_t event_quanta(double distance) {
  // Distances are below the clamping bound, far below 2^16 log-odds; the
  // truncation is floor (distance >= 0).
  const auto quanta = static_cast<std::int64_t>(distance * kQuantaPerLogOdds) - 1;
  if (quanta <= 0) return 0;
  return quanta >= std::int64_t{OccupancyTree::kNoEvent - 1} ? OccupancyTree::kNoEvent - 1
                                                               : static_cast<std::uint32_t>(quanta);
}

std::uint32_t lowered(std::uint32_t event, std::int64_t owed) {
  if (event == OccupancyTree::kNoEvent) return event;
  return owed >= event ? 0 : static_cast<std::uint32_t>(event - owed);
}

}  // namespace

OccupancyTree::DecayStep OccupancyTree::owed_step(std::uint32_t step) const {
  const std::array<std::int64_t, 2> owed = owed_quanta(step);
  return {amount_of(owed[0]), amount_of(owed[1])};
}

bool OccupancyTree::decay_due(const DecayMark& mark) const {
  if (mark.step == decay_now()) return false;
  const std::array<std::int64_t, 2> owed = owed_quanta(mark.step);
  for (int side = 0; side < 2; ++side) {
    if (mark.event[side] != kNoEvent && owed[side] > 0 && owed[side] >= mark.event[side]) return true;
  }
  return false;
}

void OccupancyTree::catch_up_values(std::array<float, 8>& values, DecayMark& mark) const {
  const std::array<std::int64_t, 2> owed = owed_quanta(mark.step);
  const DecayStep step{amount_of(owed[0]), amount_of(owed[1])};
  for (float& v : values) v = decayed(v, step);
  mark.event = {lowered(mark.event[0], owed[0]), lowered(mark.event[1], owed[1])};
  mark.step = decay_now();
}

void OccupancyTree::lower_events(std::array<std::uint32_t, 2>& event, float value) const {
  if (!decay_tracked_ || value == 0.0f) return;  // 0 never changes
  // The events of a value: reaching 0 (unknown, color dropped, equal to its
  // unknown siblings) and crossing a threshold on the way there: the
  // nearest of 0 and the thresholds between the value and 0. The distance
  // is taken in double, where the difference of two floats is exact: then
  // the bound of a value less what it owes is the bound of its decayed
  // value, exactly (check_marks relies on it).
  const float o = thresholds_.occupied;
  const float f = thresholds_.free;
  float stop = 0.0f;
  if (value > 0.0f) {
    if (o <= value && o > stop) stop = o;
    if (f <= value && f > stop) stop = f;
  } else {
    if (o >= value && o < stop) stop = o;
    if (f >= value && f < stop) stop = f;
  }
  std::uint32_t& side = event[value > 0.0f ? 0 : 1];
  side = std::min(side, event_quanta(std::abs(static_cast<double>(value) - static_cast<double>(stop))));
}

OccupancyTree::DecayMark OccupancyTree::new_mark(float value) const {
  DecayMark mark{decay_now(), {kNoEvent, kNoEvent}};
  lower_events(mark.event, value);
  return mark;
}

std::array<std::uint32_t, 2> OccupancyTree::events_of(const std::array<float, 8>& values) const {
  std::array<std::uint32_t, 2> event{kNoEvent, kNoEvent};
  if (thresholds_.occupied != 0.0f || thresholds_.free != 0.0f) {
    for (const float v : values) lower_events(event, v);
    return event;
  }
  // Both thresholds at 0 (p = 0.5, the default): a value's only event is
  // reaching 0, at distance |value|, and event_quanta grows with the
  // distance, so a side's bound is that of its value nearest to 0: one
  // conversion per side instead of lower_events' per value, and no branch
  // on the values' signs (lower_events for the eight values of every leaf
  // group a scan wrote was half of what decay added to a TUM frame).
  constexpr float kFar = std::numeric_limits<float>::infinity();
  float nearest_positive = kFar;
  float nearest_negative = kFar;
  for (const float v : values) {
    nearest_positive = std::min(nearest_positive, v > 0.0f ? v : kFar);
    nearest_negative = std::min(nearest_negative, v < 0.0f ? -v : kFar);
  }
  if (nearest_positive != kFar) event[0] = event_quanta(nearest_positive);
  if (nearest_negative != kFar) event[1] = event_quanta(nearest_negative);
  return event;
}

void OccupancyTree::set_leaf_events(std::uint32_t group) {
  if (!decay_tracked_) return;
  mark(0, group).event = events_of(leaves_[group].log_odds);
}

void OccupancyTree::attach_marks() {
  const DecayMark up_to_date{decay_now(), {kNoEvent, kNoEvent}};
  leaves_.attach_marks(up_to_date);
  for (int d = 1; d <= depth_levels_; ++d) inner_[d].attach_marks(up_to_date);
}

void OccupancyTree::decay(DecayStep step, const std::optional<KeyBox>& region, std::vector<DecayChange>* changes,
                          int change_depth, ThreadPool* /*pool*/) {
  UMBRA_ASSERT(step.occupied >= 0.0f && step.free >= 0.0f);
  if (step.occupied == 0.0f && step.free == 0.0f) return;
  const std::optional<std::int64_t> occupied = quanta_of(step.occupied);
  const std::optional<std::int64_t> free = quanta_of(step.free);
  // A region's step cuts the tree by the region, not by events; amounts
  // not in whole quanta would not compose exactly: both eagerly.
  if (region || !occupied || !free) {
    decay_eagerly(step, region, changes, change_depth);
    return;
  }
  track_decay();
  std::array<std::int64_t, 2> totals = decay_totals_.back();
  totals[0] += *occupied;
  totals[1] += *free;
  decay_totals_.push_back(totals);
  if (decay_due(mark(depth_levels_, 0))) decay_group(depth_levels_, 0, 0, changes, change_depth);
  // The table costs 16 bytes a step: settle once it outgrows a small part
  // of the tree (a walk of every group, amortised over as many steps).
  std::size_t groups = leaves_.size();
  for (int d = 1; d <= depth_levels_; ++d) groups += inner_[d].size();
  if (decay_totals_.size() > 64 + groups / 8) settle_decay();
}

void OccupancyTree::track_decay() {
  if (decay_tracked_) return;
  // From now on every writer keeps the events. Nothing is owed yet (the
  // table has one entry until the first lazy step). The marks are
  // allocated only now: a map that never decays does not pay for them.
  attach_marks();
  decay_tracked_ = true;
  recompute_events(depth_levels_, 0);
}

void OccupancyTree::decay_eagerly(DecayStep step, const std::optional<KeyBox>& region,
                                  std::vector<DecayChange>* changes, int change_depth) {
  UMBRA_ASSERT(step.occupied >= 0.0f && step.free >= 0.0f);
  if (step.occupied == 0.0f && step.free == 0.0f) return;
  settle_decay();
  decay_below(depth_levels_, 0, 0, 0, step, region, changes, change_depth);
}

bool OccupancyTree::decay_leaf(std::uint32_t group, unsigned slot, DecayStep step) {
  float& stored = leaves_[group].log_odds[slot];
  const float value = stored;
  const float next = decayed(value, step);
  if (next == value) return false;
  stored = next;
  if (next == 0.0f) forget_color(0, group, slot);
  return thresholds_.classify(value) != thresholds_.classify(next);
}

bool OccupancyTree::decay_group(int depth, std::uint32_t group, std::uint64_t code,
                                std::vector<DecayChange>* changes, int change_depth) {
  const std::uint32_t now = decay_now();
  ++decay_groups_walked_;
  bool changed = false;
  if (depth == 0) {
    const DecayStep owed = owed_step(mark(0, group).step);
    for (unsigned i = 0; i < 8; ++i) {
      if (decay_leaf(group, i, owed)) {
        changed = true;
        if (change_depth == 0 && changes != nullptr) changes->push_back({code | i, 0});
      }
    }
    mark(0, group).step = now;
    set_leaf_events(group);
    return changed;
  }
  std::array<float, 8> before{};
  {
    InnerGroup& node = inner_[depth][group];
    before = node.log_odds;
    const DecayStep owed = owed_step(mark(depth, group).step);
    for (float& v : node.log_odds) v = decayed(v, owed);
    mark(depth, group) = {now, {kNoEvent, kNoEvent}};  // recomputed slot by slot below
  }
  for (unsigned i = 0; i < 8; ++i) {
    const std::uint64_t slot_code = code | (std::uint64_t{i} << (3 * depth));
    InnerGroup& node = inner_[depth][group];  // no pool grows in this walk; fetched anew for clarity
    const std::uint32_t child = node.child[i];
    if (child == kNoGroup) {
      const float next = node.log_odds[i];
      set_childless(depth, group, i, next);  // its indicators, and the group's events
      if (next == before[i]) continue;
      if (next == 0.0f) forget_color(depth, group, i);
      if (thresholds_.classify(before[i]) != thresholds_.classify(next)) {
        changed = true;
        if (depth >= change_depth && changes != nullptr) changes->push_back({slot_code, depth});
      }
      continue;
    }
    const DecayMark& below = mark(depth - 1, child);
    if (!decay_due(below)) {
      // Nothing below changes state: the children keep what they owe, and
      // this group's events are theirs, less what they owe.
      const std::array<std::int64_t, 2> owed = owed_quanta(below.step);
      DecayMark& own = mark(depth, group);
      for (int side = 0; side < 2; ++side) {
        own.event[side] = std::min(own.event[side], lowered(below.event[side], owed[side]));
      }
      continue;
    }
    const bool changed_below = decay_group(depth - 1, child, slot_code, changes, change_depth);
    refresh(depth, group, i, auto_prune_);  // value, indicators, color, pruning; lowers the events
    changed |= changed_below;
    if (changed_below && depth == change_depth && changes != nullptr) changes->push_back({slot_code, depth});
  }
  return changed;
}

std::array<std::uint32_t, 2> OccupancyTree::recompute_events(int depth, std::uint32_t group) {
  if (depth == 0) {
    UMBRA_ASSERT(mark(0, group).step == decay_now());
    set_leaf_events(group);
    return mark(0, group).event;
  }
  std::array<std::uint32_t, 2> event{kNoEvent, kNoEvent};
  for (unsigned i = 0; i < 8; ++i) {
    const std::uint32_t child = inner_[depth][group].child[i];
    if (child == kNoGroup) {
      lower_events(event, inner_[depth][group].log_odds[i]);
      continue;
    }
    const std::array<std::uint32_t, 2> below = recompute_events(depth - 1, child);
    event = {std::min(event[0], below[0]), std::min(event[1], below[1])};
  }
  UMBRA_ASSERT(mark(depth, group).step == decay_now());
  mark(depth, group).event = event;
  return event;
}

void OccupancyTree::settle_decay() {
  if (decay_totals_.size() == 1) return;  // nothing owed anywhere
  settle_below(depth_levels_, 0);
  decay_totals_.assign(1, {0, 0});
}

void OccupancyTree::settle_below(int depth, std::uint32_t group) {
  // Caught up against the table as it is; marked with step 0 of the table
  // settle_decay() leaves.
  if (depth == 0) {
    catch_up(0, group);
    mark(0, group).step = 0;
    return;
  }
  catch_up(depth, group);
  mark(depth, group).step = 0;
  for (unsigned i = 0; i < 8; ++i) {
    const std::uint32_t child = inner_[depth][group].child[i];
    if (child != kNoGroup) settle_below(depth - 1, child);
  }
}

std::string OccupancyTree::check_marks(int depth, std::uint32_t group, std::array<std::int64_t, 2>& event) const {
  // The exact events of the values as readers see them, against the bound
  // the group keeps less what it owes: a bound above them is an event a
  // step could miss (a writer that did not lower it).
  const DecayMark& mark = this->mark(depth, group);
  const auto where = [&] { return "decay mark of group " + std::to_string(group) + " at depth " + std::to_string(depth) + ": "; };
  if (mark.step > decay_now()) return where() + "step beyond the clock";
  if (decay_due(mark)) return where() + "owes a state change between steps";
  std::array<std::uint32_t, 2> exact{kNoEvent, kNoEvent};
  for (unsigned i = 0; i < 8; ++i) {
    const NodeRef node{group, static_cast<std::uint8_t>(i), static_cast<std::int8_t>(depth)};
    if (!has_children(node)) {
      lower_events(exact, log_odds(node));
      continue;
    }
    std::array<std::int64_t, 2> below{};
    std::string problem = check_marks(depth - 1, inner_[depth][group].child[i], below);
    if (!problem.empty()) return problem;
    for (int side = 0; side < 2; ++side) {
      exact[side] = static_cast<std::uint32_t>(std::min<std::int64_t>(exact[side], below[side]));
    }
  }
  const std::array<std::int64_t, 2> owed = owed_quanta(mark.step);
  for (int side = 0; side < 2; ++side) {
    if (lowered(mark.event[side], owed[side]) > exact[side]) {
      return where() + "event bound " + std::to_string(mark.event[side]) + " (owing " + std::to_string(owed[side]) +
             ") above the values' " + std::to_string(exact[side]) + " on side " + std::to_string(side);
    }
    event[side] = exact[side];
  }
  return {};
}

bool OccupancyTree::decay_below(int depth, std::uint32_t group, unsigned slot, std::uint64_t code, DecayStep step,
                                const std::optional<KeyBox>& region, std::vector<DecayChange>* changes,
                                int change_depth) {
  const Overlap where = overlap(code, depth, region);
  if (where == Overlap::outside) return false;
  const auto record = [&](int at) {
    if (changes != nullptr) changes->push_back({code, at});
  };
  {
    InnerGroup& node = inner_[depth][group];
    if (node.child[slot] == kNoGroup) {
      const float value = node.log_odds[slot];
      const float next = decayed(value, step);
      if (next == value) return false;  // unknown already, or its sign does not decay
      if (where == Overlap::inside) {
        set_childless(depth, group, slot, next);
        if (next == 0.0f) forget_color(depth, group, slot);
        const bool changed = thresholds_.classify(value) != thresholds_.classify(next);
        if (changed && depth >= change_depth) record(depth);
        return changed;
      }
      expand(depth, group, slot);  // only a part of it decays
    } else {
      // Nothing below can change when every value is 0 or of a sign that
      // does not decay. The maximum bounds the positive values; contains_free
      // rules out negative ones only when every negative value is free
      // (free threshold >= 0, i.e. p_free >= 0.5, the default).
      const bool no_positive = node.log_odds[slot] <= 0.0f;
      const bool no_negative = thresholds_.free >= 0.0f && (node.contains_free & (1u << slot)) == 0;
      if ((no_positive || step.occupied == 0.0f) && (no_negative || step.free == 0.0f)) return false;
    }
  }
  const std::uint32_t child = inner_[depth][group].child[slot];
  bool changed = false;
  if (depth == 1) {
    for (unsigned i = 0; i < 8; ++i) {
      const std::uint64_t leaf_code = code | i;
      if (where == Overlap::partial && overlap(leaf_code, 0, region) == Overlap::outside) continue;
      if (decay_leaf(child, i, step)) {
        changed = true;
        if (change_depth == 0 && changes != nullptr) changes->push_back({leaf_code, 0});
      }
    }
  } else {
    const int child_depth = depth - 1;
    for (unsigned i = 0; i < 8; ++i) {
      changed |= decay_below(child_depth, child, i, code | (std::uint64_t{i} << (3 * child_depth)), step, region,
                             changes, change_depth);
    }
  }
  refresh(depth, group, slot, auto_prune_);
  if (changed && depth == change_depth) record(depth);
  return changed;
}

}  // namespace umbra
