// NbvPlanner: one step of a receding-horizon next-best-view planner, after
// Bircher et al., "Receding Horizon Next-Best-View Planner for 3D
// Exploration" (ICRA 2016; the nbvplanner the UFOMap paper's case study uses).
//
// From the robot's pose, grow a rapidly-exploring random tree in known free
// space: sample a point in the exploration box, find the nearest node, step
// from it towards the sample by at most `extension_range`; keep the new node
// if the robot's ball there is free (unknown space blocks) and the edge from
// the nearest node is free for the ball (a capsule). Each node gets the best
// of `yaw_samples` headings evenly spaced from a random one and the gain of
// the camera's view from it (visible unknown volume),
// and a score: its parent's score + gain * exp(-lambda * path length from
// the robot), where a gain below the threshold (`min_gain`) counts as none.
// The tree starts with the robot's pose and with what is left of
// the previous step's best branch (re-checked against the current map), so
// the plan stays consistent from step to step. It grows to at least
// `initial_nodes` nodes and on until some node has a gain of at least
// `min_gain` or the tree has `max_nodes` nodes. The step returns the first
// node of the branch to the best-scoring node: the robot flies that edge and
// plans again.
//
// A tree of max_nodes stays within a few metres of the robot: once the
// robot's surroundings are known it finds no gain although other rooms are
// unexplored (the local minimum of receding-horizon planners). The planner
// then grows the same tree on, to at most `max_nodes_no_gain` nodes (as
// nbvplanner's cutoff iterations do), stopping at the first node with gain,
// and draws a share `memory_bias` of its samples at remembered poses: nodes
// of earlier trees that had gain but were not on the chosen branch (one per
// extension_range, the newest), whose gain is computed again before they
// are used (those without gain now are forgotten). Only when that larger
// tree has no node with gain either does the planner halve its threshold
// (down to `final_min_gain`, for the crumbs of unknown space behind clutter
// left at the end), scoring the same tree again; when nothing reaches even
// that, the exploration is over. The threshold is never raised again.
//
// Receding-horizon planners also glean: a node a metre away that sees a
// little unknown space (behind clutter, under the ceiling) outscores a room
// twenty metres away, so whole rooms stay unexplored (the plant's upper
// storey of hall B, seed 1: 4% of the reachable space after 1500 s). So the
// planner keeps a roadmap (roadmap.hpp) of where the robot has been and of
// the branches to its remembered poses, and each step compares the best
// rate of the local tree, gain / (path length + `route_overhead`), with the
// same rate of the remembered poses along the roadmap (their gain computed
// again, lazily: the best bounds first, as a gain never grows while the map
// only learns). When a remembered pose wins, the robot flies the roadmap's
// shortest route there in straight legs that cut its corners (each step
// flies to the farthest of the next 8 waypoints, at most 4 extensions away,
// that the ball reaches freely; when not even the next one is free, its
// edge is removed and the planner plans afresh), facing along its way and
// turning to the remembered heading at the end.
//
// A frame inserted after the robot reached a node may show a surface within
// the check radius of it (a pipe seen from a new side): then no edge leaves
// the robot. The step then flies back to the pose the robot planned from
// before (the way it came, flown and so clear), as often as needed.
//
// Every map query goes through ExplorationMap and is timed per kind (node
// collision, edge, gain), and counted.
//
// Cost: per step up to max_nodes * (1 ball check + 1 capsule check + 1 gain)
// plus rejected samples' checks, the gains dominating; a step that grows on
// up to max_nodes_no_gain times that, plus one gain per remembered pose.
#pragma once

#include <atomic>
#include <cstdint>
#include <optional>
#include <random>
#include <vector>

#include "exploration_map.hpp"
#include "roadmap.hpp"
#include "umbra/core/aabb.hpp"

namespace umbra::explore {

/// A position and a heading (yaw about +z, counter-clockwise from +x).
struct Pose {
  Vec3d position;
  double yaw = 0.0;
};

/// The depth camera's field of view, in the frame of Frustum (shapes.hpp).
struct CameraView {
  double hfov_deg = 115.0;
  double vfov_deg = 60.0;
  double pitch_deg = 0.0;  ///< fixed on the robot
  double max_range = 6.5;  ///< metres; the gain counts voxels up to here
  [[nodiscard]] Frustum frustum(const Pose& pose) const;
};

struct PlannerConfig {
  double robot_radius = 0.3;
  /// Added to the robot's radius for every check: the map's voxels and the
  /// robot's motion are coarse, and the robot must never touch a surface.
  double safety_margin = 0.1;
  double extension_range = 1.5;  ///< metres, longest edge
  int initial_nodes = 15;
  int max_nodes = 150;
  /// When no node of max_nodes has gain, the tree grows on to this many.
  int max_nodes_no_gain = 1500;
  /// Then this share of samples is drawn at a remembered pose with gain.
  double memory_bias = 0.25;
  /// Remembered poses at most (the oldest are dropped; each is one gain
  /// computation when the tree grows on).
  int memory_size = 4096;
  /// Route to remembered poses over the roadmap when they promise more
  /// gain per metre than the local tree (see the file comment).
  bool route_to_memory = true;
  /// Metres added to every path length in the gain rate: the cost of
  /// turning and settling at a goal, so that a crumb next to the robot does
  /// not outrate a room (a rate is gain / (path length + route_overhead)).
  double route_overhead = 2.0;
  /// Samples tried per step at most, as a multiple of max_nodes (in a
  /// cramped map most samples give no node).
  int samples_per_node = 20;
  /// Headings tried per new node, evenly spaced from a random one; the node
  /// keeps the one with the most gain (1: the random heading alone). Four
  /// cost four gains per node and, in the plant (seed 1), brought 50%
  /// coverage at 302 s instead of 442 s (docs/exploration.md).
  int yaw_samples = 4;
  double lambda = 0.5;    ///< 1/m, discount of gain with path length
  double min_gain = 1.0;  ///< m^3: less is no gain (the threshold at first)
  double final_min_gain = 0.125;  ///< m^3: the threshold at the end (see the file comment)
  Aabb bounds;            ///< where nodes may lie (the building's inside)
  CameraView camera;

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
  [[nodiscard]] double check_radius() const { return robot_radius + safety_margin; }
};

/// Counts and seconds per kind of query, summed over steps.
struct QueryTally {
  std::uint64_t count = 0;
  double seconds = 0.0;
};

struct PlannerStats {
  QueryTally node_checks;  ///< ball collision checks
  QueryTally edge_checks;  ///< capsule (segment with radius) checks
  QueryTally gains;        ///< information gain of a view
  std::uint64_t steps = 0;
  std::uint64_t nodes = 0;    ///< tree nodes made (the roots not counted)
  std::uint64_t samples = 0;  ///< samples drawn
  std::uint64_t grown_on = 0;  ///< steps whose tree grew past max_nodes (no gain near)
  std::uint64_t threshold_lowered = 0;  ///< times the gain threshold was halved
  std::uint64_t backtracks = 0;         ///< steps back along the way the robot came (trapped)
  std::uint64_t routes = 0;             ///< routes chosen to a remembered pose
  std::uint64_t route_steps = 0;        ///< steps that flew an edge of a route
  std::uint64_t routes_blocked = 0;     ///< routes abandoned at an edge found blocked
  std::uint64_t roadmap_vertices = 0;   ///< the roadmap's size
  /// Queries that began while the mapping thread was inserting (set by the
  /// explorer): proof that mapping and planning overlapped.
  std::uint64_t queries_during_insertion = 0;
};

struct PlanStep {
  bool gain_found = false;
  bool grown_on = false;  ///< the tree grew past max_nodes to find gain
  bool backtracked = false;  ///< the robot was trapped: `next` is where it planned from before
  bool routed = false;       ///< `next` is on a route to a remembered pose
  Pose next;              ///< first node of the best branch (when gain_found)
  double best_gain = 0.0;  ///< m^3, the best node's own gain
  double best_score = 0.0;
  int tree_nodes = 0;
};

class NbvPlanner {
 public:
  /// `inserting` (may be null) is raised by the mapping thread while it
  /// inserts: queries that start then are counted in the stats.
  NbvPlanner(const PlannerConfig& config, std::uint32_t seed, const std::atomic<bool>* inserting = nullptr);

  /// One step from `robot` (see the file comment).
  PlanStep plan(const ExplorationMap& map, const Pose& robot);

  [[nodiscard]] const PlannerStats& stats() const { return stats_; }
  /// The gain threshold now (min_gain until the end game lowers it).
  [[nodiscard]] double gain_threshold() const { return threshold_; }

  /// A node of the tree; the root (index 0) is the robot's pose.
  struct TreeNode {
    Pose pose;
    int parent = -1;
    double path_length = 0.0;  ///< metres from the root along the tree
    double gain = 0.0;
    double score = 0.0;
  };
  /// The tree the last plan() grew (for tests and pictures).
  [[nodiscard]] const std::vector<TreeNode>& tree() const { return tree_; }

 private:

  bool node_free(const ExplorationMap& map, Vec3d position);
  bool edge_free(const ExplorationMap& map, Vec3d from, Vec3d to);
  double view_gain(const ExplorationMap& map, const Pose& pose);
  /// Adds a node under `parent` with its gain and score; returns its index.
  /// `gain`: the pose's gain when already computed.
  int add_node(const ExplorationMap& map, int parent, const Pose& pose, std::optional<double> gain = std::nullopt);
  /// Draws samples until the tree has `target_nodes` nodes or, once it has
  /// at least `enough_nodes`, some node has gain (or the samples run out).
  /// Returns whether some node has gain.
  bool grow(const ExplorationMap& map, int enough_nodes, int target_nodes, bool from_memory, bool gain_found);
  /// A pose of an earlier tree that had gain, and the roadmap vertex there.
  struct Remembered {
    Pose pose;
    int vertex = -1;
    double gain = 0.0;  ///< when last computed: a bound on its gain now
  };

  /// Remembers the nodes of the tree with gain that are not on `branch`,
  /// with their branches from the root in the roadmap.
  void remember(const std::vector<std::size_t>& branch);
  /// Makes the robot's position a roadmap vertex joined to where it came
  /// from and to the free neighbours near it.
  void enter_roadmap(const ExplorationMap& map, Vec3d position);
  /// The next edge of the route being flown, if it is still free.
  std::optional<Pose> follow_route(const ExplorationMap& map, const Pose& robot);
  /// Chooses a remembered pose whose rate beats `local_rate` and sets the
  /// route there; returns the first pose to fly to.
  std::optional<Pose> choose_route(const ExplorationMap& map, double local_rate);
  /// The local tree's best gain / (path length + route_overhead).
  [[nodiscard]] double local_rate() const;
  /// Drops remembered poses that have no gain now.
  void refresh_memory(const ExplorationMap& map);
  /// Whether some node's gain reaches the threshold.
  [[nodiscard]] bool has_gain() const;
  /// Scores of all nodes again (after the threshold changed).
  void rescore();
  void count_overlap();

  PlannerConfig config_;
  std::mt19937 rng_;
  const std::atomic<bool>* inserting_;
  std::vector<TreeNode> tree_;
  std::vector<Pose> previous_branch_;  ///< the last best branch after its first node
  std::vector<Remembered> memory_;     ///< poses of earlier trees with gain, oldest first
  Roadmap roadmap_;
  int robot_vertex_ = -1;              ///< the roadmap vertex where the robot is
  std::vector<int> route_;             ///< vertices still to fly to, in order
  double route_yaw_ = 0.0;             ///< the heading at the route's end
  double threshold_;                   ///< gain below it is none: min_gain, lowered at the end
  std::vector<Pose> history_;          ///< poses the robot planned from, oldest first
  PlannerStats stats_;
};

}  // namespace umbra::explore
