#include "nbv_planner.hpp"

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>

namespace umbra::explore {

namespace {

[[noreturn]] void bad_field(const char* field, const std::string& requirement, double value) {
  std::ostringstream out;
  out << "PlannerConfig::" << field << " must be " << requirement << ", got " << value;
  throw std::invalid_argument(out.str());
}

/// Uniform in [low, high) from the engine's bits, the same with every standard library.
double uniform(std::mt19937& rng, double low, double high) {
  return low + (high - low) * (double(rng()) / 4294967296.0);
}

/// Times a query into a tally.
template <typename Query>
auto timed(QueryTally& tally, Query&& query) {
  const auto start = std::chrono::steady_clock::now();
  auto result = query();
  tally.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ++tally.count;
  return result;
}

}  // namespace

Frustum CameraView::frustum(const Pose& pose) const {
  return Frustum::from_degrees(pose.position, pose.yaw * 180.0 / std::numbers::pi, pitch_deg, hfov_deg, vfov_deg, 0.0,
                               max_range);
}

void PlannerConfig::validate() const {
  if (!(robot_radius > 0.0)) bad_field("robot_radius", "> 0", robot_radius);
  if (!(safety_margin >= 0.0)) bad_field("safety_margin", ">= 0", safety_margin);
  if (!(extension_range > 0.0)) bad_field("extension_range", "> 0", extension_range);
  if (initial_nodes < 1) bad_field("initial_nodes", ">= 1", initial_nodes);
  if (max_nodes < initial_nodes) bad_field("max_nodes", ">= initial_nodes", max_nodes);
  if (max_nodes_no_gain < max_nodes) bad_field("max_nodes_no_gain", ">= max_nodes", max_nodes_no_gain);
  if (!(memory_bias >= 0.0 && memory_bias <= 1.0)) bad_field("memory_bias", "in [0, 1]", memory_bias);
  if (memory_size < 0) bad_field("memory_size", ">= 0", memory_size);
  if (!(route_overhead >= 0.0)) bad_field("route_overhead", ">= 0", route_overhead);
  if (samples_per_node < 1) bad_field("samples_per_node", ">= 1", samples_per_node);
  if (yaw_samples < 1) bad_field("yaw_samples", ">= 1", yaw_samples);
  if (!(lambda >= 0.0)) bad_field("lambda", ">= 0", lambda);
  if (!(min_gain > 0.0)) bad_field("min_gain", "> 0", min_gain);
  if (!(final_min_gain > 0.0 && final_min_gain <= min_gain)) bad_field("final_min_gain", "in (0, min_gain]", final_min_gain);
  for (int a = 0; a < 3; ++a) {
    if (!(bounds.min[std::size_t(a)] < bounds.max[std::size_t(a)])) {
      bad_field("bounds", "a box with min < max on every axis; min on that axis", bounds.min[std::size_t(a)]);
    }
  }
  if (!(camera.hfov_deg > 0.0 && camera.hfov_deg < 180.0)) bad_field("camera.hfov_deg", "in (0, 180)", camera.hfov_deg);
  if (!(camera.vfov_deg > 0.0 && camera.vfov_deg < 180.0)) bad_field("camera.vfov_deg", "in (0, 180)", camera.vfov_deg);
  if (!(std::abs(camera.pitch_deg) < 90.0)) bad_field("camera.pitch_deg", "in (-90, 90)", camera.pitch_deg);
  if (!(camera.max_range > 0.0)) bad_field("camera.max_range", "> 0", camera.max_range);
}

NbvPlanner::NbvPlanner(const PlannerConfig& config, std::uint32_t seed, const std::atomic<bool>* inserting)
    : config_((config.validate(), config)),
      rng_(seed),
      inserting_(inserting),
      roadmap_(config.bounds, config.extension_range),
      threshold_(config.min_gain) {}

void NbvPlanner::count_overlap() {
  if (inserting_ != nullptr && inserting_->load(std::memory_order_relaxed)) ++stats_.queries_during_insertion;
}

bool NbvPlanner::node_free(const ExplorationMap& map, Vec3d position) {
  count_overlap();
  return timed(stats_.node_checks, [&] { return map.is_free(Sphere{position, config_.check_radius()}); });
}

bool NbvPlanner::edge_free(const ExplorationMap& map, Vec3d from, Vec3d to) {
  count_overlap();
  return timed(stats_.edge_checks, [&] { return map.is_free(Capsule{from, to, config_.check_radius()}); });
}

double NbvPlanner::view_gain(const ExplorationMap& map, const Pose& pose) {
  count_overlap();
  return timed(stats_.gains, [&] { return map.gain(config_.camera.frustum(pose)); });
}

int NbvPlanner::add_node(const ExplorationMap& map, int parent, const Pose& pose, std::optional<double> gain) {
  const TreeNode& up = tree_[std::size_t(parent)];
  TreeNode node;
  node.pose = pose;
  node.parent = parent;
  node.path_length = up.path_length + (pose.position - up.pose.position).norm();
  node.gain = gain ? *gain : view_gain(map, pose);
  // Crumbs of unknown space (less than the threshold) are worth nothing: counting them kept the robot gleaning
  // them near itself while whole rooms lay unexplored (84% coverage after 900 s in the plant).
  const double useful = node.gain >= threshold_ ? node.gain : 0.0;
  node.score = up.score + useful * std::exp(-config_.lambda * node.path_length);
  tree_.push_back(node);
  ++stats_.nodes;
  return int(tree_.size()) - 1;
}

bool NbvPlanner::grow(const ExplorationMap& map, int enough_nodes, int target_nodes, bool from_memory,
                      bool gain_found) {
  const std::uint64_t max_samples = std::uint64_t(target_nodes) * std::uint64_t(config_.samples_per_node);
  for (std::uint64_t sample = 0; sample < max_samples; ++sample) {
    const int nodes = int(tree_.size()) - 1;
    if (nodes >= target_nodes || (nodes >= enough_nodes && gain_found)) break;
    ++stats_.samples;
    Vec3d target{uniform(rng_, config_.bounds.min.x, config_.bounds.max.x),
                 uniform(rng_, config_.bounds.min.y, config_.bounds.max.y),
                 uniform(rng_, config_.bounds.min.z, config_.bounds.max.z)};
    // Both draws are made either way, so the sequence of draws does not depend on the memory.
    const double pick = uniform(rng_, 0.0, 1.0);
    const double which = uniform(rng_, 0.0, 1.0);
    if (from_memory && !memory_.empty() && pick < config_.memory_bias) {
      target = memory_[std::min(memory_.size() - 1, std::size_t(which * double(memory_.size())))].pose.position;
    }
    std::size_t nearest = 0;
    double nearest_distance = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < tree_.size(); ++i) {
      const double d = (tree_[i].pose.position - target).norm();
      if (d < nearest_distance) {
        nearest_distance = d;
        nearest = i;
      }
    }
    if (nearest_distance < 1e-6) continue;
    const Vec3d from = tree_[nearest].pose.position;
    const Vec3d to = from + (target - from) * (std::min(nearest_distance, config_.extension_range) / nearest_distance);
    const double yaw = uniform(rng_, -std::numbers::pi, std::numbers::pi);
    if (!node_free(map, to) || !edge_free(map, from, to)) continue;
    Pose pose{to, yaw};
    std::optional<double> gain;
    for (int k = 0; k < config_.yaw_samples && config_.yaw_samples > 1; ++k) {
      const Pose heading{to, yaw + 2.0 * std::numbers::pi * k / config_.yaw_samples};
      const double g = view_gain(map, heading);
      if (!gain || g > *gain) {
        gain = g;
        pose = heading;
      }
    }
    const int added = add_node(map, int(nearest), pose, gain);
    gain_found = gain_found || tree_[std::size_t(added)].gain >= threshold_;
  }
  return gain_found;
}

void NbvPlanner::remember(const std::vector<std::size_t>& branch) {
  std::vector<std::size_t> chosen;
  for (std::size_t i = 1; i < tree_.size(); ++i) {
    if (tree_[i].gain < threshold_ || std::find(branch.begin(), branch.end(), i) != branch.end()) continue;
    // One pose per neighbourhood, the newest: the memory spreads over the places left behind.
    const Vec3d here = tree_[i].pose.position;
    const auto near = [&](Vec3d other) { return (other - here).norm() < config_.extension_range; };
    std::erase_if(memory_, [&](const Remembered& old) { return near(old.pose.position); });
    std::erase_if(chosen, [&](std::size_t j) { return near(tree_[j].pose.position); });
    chosen.push_back(i);
  }
  // The chosen nodes' branches from the root go into the roadmap (tree
  // edges were checked free), sharing the vertices of common ancestors.
  std::vector<int> vertex_of(tree_.size(), -1);
  vertex_of[0] = robot_vertex_;
  for (std::size_t i : chosen) {
    std::vector<std::size_t> up;
    for (std::size_t j = i; vertex_of[j] < 0; j = std::size_t(tree_[j].parent)) up.push_back(j);
    for (auto it = up.rbegin(); it != up.rend(); ++it) {
      vertex_of[*it] = roadmap_.add_vertex(tree_[*it].pose.position);
      roadmap_.add_edge(vertex_of[std::size_t(tree_[*it].parent)], vertex_of[*it]);
    }
    memory_.push_back({tree_[i].pose, vertex_of[i], tree_[i].gain});
  }
  if (memory_.size() > std::size_t(config_.memory_size)) {
    memory_.erase(memory_.begin(), memory_.end() - config_.memory_size);
  }
  stats_.roadmap_vertices = roadmap_.size();
}

void NbvPlanner::enter_roadmap(const ExplorationMap& map, Vec3d position) {
  const std::vector<int> near = roadmap_.near(position, config_.extension_range);
  const int from = robot_vertex_;
  if (!near.empty() && (roadmap_.position(near.front()) - position).norm() < 1e-9) {
    robot_vertex_ = near.front();  // arrived at a vertex (a route's waypoint)
  } else {
    robot_vertex_ = roadmap_.add_vertex(position);
    // Shortcuts to the nearest vertices around (a few: each is a capsule check), so
    // that routes do not retrace every loop the robot flew.
    constexpr int kShortcuts = 6;
    int tried = 0;
    for (int v : near) {
      if (tried++ == kShortcuts) break;
      if (edge_free(map, roadmap_.position(v), position)) roadmap_.add_edge(v, robot_vertex_);
    }
  }
  if (from >= 0) roadmap_.add_edge(from, robot_vertex_);  // flown, so free
  stats_.roadmap_vertices = roadmap_.size();
}

std::optional<Pose> NbvPlanner::follow_route(const ExplorationMap& map, const Pose& robot) {
  if (route_.empty()) return std::nullopt;
  // Cut corners: fly straight to the farthest of the next few waypoints the
  // ball can reach in one free leg. Routes over the roadmap retrace the
  // flown zig-zags: on seed 1 a route took 7.5 edges on average, and 2 legs
  // once cut, and the run reached 95% coverage within 900 s (docs/exploration.md).
  constexpr std::size_t kLookahead = 8;
  const double longest_leg = 4.0 * config_.extension_range;
  std::optional<std::size_t> reach;
  for (std::size_t k = std::min(route_.size(), kLookahead); k-- > 0;) {
    const Vec3d to = roadmap_.position(route_[k]);
    if ((to - robot.position).norm() > longest_leg && k > 0) continue;
    if (node_free(map, to) && edge_free(map, robot.position, to)) {
      reach = k;
      break;
    }
  }
  if (!reach) {
    roadmap_.remove_edge(robot_vertex_, route_.front());
    route_.clear();
    ++stats_.routes_blocked;
    return std::nullopt;
  }
  const Vec3d to = roadmap_.position(route_[*reach]);
  route_.erase(route_.begin(), route_.begin() + std::ptrdiff_t(*reach) + 1);
  ++stats_.route_steps;
  const Vec3d way = to - robot.position;
  // Face along the way (the camera sees what is ahead), the remembered heading at the end.
  const bool along = !route_.empty() && (way.x != 0.0 || way.y != 0.0);
  return Pose{to, route_.empty() ? route_yaw_ : along ? std::atan2(way.y, way.x) : robot.yaw};
}

double NbvPlanner::local_rate() const {
  double best = 0.0;
  for (std::size_t i = 1; i < tree_.size(); ++i) {
    if (tree_[i].gain >= threshold_) {
      best = std::max(best, tree_[i].gain / (tree_[i].path_length + config_.route_overhead));
    }
  }
  return best;
}

std::optional<Pose> NbvPlanner::choose_route(const ExplorationMap& map, double local_rate) {
  if (memory_.empty()) return std::nullopt;
  const Roadmap::Paths paths = roadmap_.shortest_paths(robot_vertex_);
  const auto rate = [&](const Remembered& r) {
    return r.gain / (paths.distance[std::size_t(r.vertex)] + config_.route_overhead);
  };
  // Best bounds first; a gain computed again only falls (the map only
  // learns), so the search stops at the first bound below the best rate.
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < memory_.size(); ++i) {
    if (paths.distance[std::size_t(memory_[i].vertex)] != Roadmap::unreachable) order.push_back(i);
  }
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return rate(memory_[a]) > rate(memory_[b]); });
  std::optional<std::size_t> best;
  double best_rate = local_rate;
  for (std::size_t i : order) {
    if (rate(memory_[i]) <= best_rate) break;
    memory_[i].gain = view_gain(map, memory_[i].pose);
    if (memory_[i].gain >= threshold_ && rate(memory_[i]) > best_rate) {
      best = i;
      best_rate = rate(memory_[i]);
    }
  }
  std::optional<Pose> first;
  const int goal_vertex = best ? memory_[*best].vertex : -1;
  if (best) {
    const Remembered goal = memory_[*best];
    route_ = paths.path_to(goal.vertex);
    route_.erase(route_.begin());  // the robot's own vertex
    route_yaw_ = goal.pose.yaw;
    ++stats_.routes;
    if (route_.empty()) {
      first = goal.pose;  // here already: turn to it
    } else {
      const Pose robot{roadmap_.position(robot_vertex_), 0.0};
      first = follow_route(map, robot);
    }
  }
  std::erase_if(memory_, [&](const Remembered& r) {
    return r.gain < threshold_ || r.vertex == goal_vertex;
  });
  return first;
}

void NbvPlanner::refresh_memory(const ExplorationMap& map) {
  for (Remembered& r : memory_) r.gain = view_gain(map, r.pose);
  std::erase_if(memory_, [&](const Remembered& r) { return r.gain < threshold_; });
}

bool NbvPlanner::has_gain() const {
  for (std::size_t i = 1; i < tree_.size(); ++i) {
    if (tree_[i].gain >= threshold_) return true;
  }
  return false;
}

void NbvPlanner::rescore() {
  for (std::size_t i = 1; i < tree_.size(); ++i) {
    TreeNode& node = tree_[i];
    const double useful = node.gain >= threshold_ ? node.gain : 0.0;
    node.score = tree_[std::size_t(node.parent)].score + useful * std::exp(-config_.lambda * node.path_length);
  }
}

PlanStep NbvPlanner::plan(const ExplorationMap& map, const Pose& robot) {
  ++stats_.steps;
  tree_.clear();
  tree_.push_back({robot, -1, 0.0, 0.0, 0.0});

  // Trapped: a frame inserted since the robot got here put a surface within
  // the check radius of it, so every edge from here fails. Fly back along
  // the way it came (flown, so clear) until it is somewhere free again.
  if (!node_free(map, robot.position)) {
    ++stats_.backtracks;
    previous_branch_.clear();
    route_.clear();
    while (!history_.empty() && (history_.back().position - robot.position).norm() < 1e-9) history_.pop_back();
    PlanStep step;
    if (history_.empty()) return step;
    step.gain_found = true;
    step.backtracked = true;
    step.next = history_.back();
    history_.pop_back();
    return step;
  }
  history_.push_back(robot);
  if (config_.route_to_memory) {
    enter_roadmap(map, robot.position);
    if (const std::optional<Pose> next = follow_route(map, robot)) {
      PlanStep step;
      step.gain_found = step.routed = true;
      step.next = *next;
      return step;
    }
  }

  // What is left of the last best branch, as long as it is still free.
  int parent = 0;
  for (const Pose& pose : previous_branch_) {
    if (!node_free(map, pose.position) || !edge_free(map, tree_[std::size_t(parent)].pose.position, pose.position)) {
      break;
    }
    parent = add_node(map, parent, pose);
  }
  bool gain_found = has_gain();

  PlanStep step;
  gain_found = grow(map, config_.initial_nodes, config_.max_nodes, false, gain_found);
  if (config_.route_to_memory) {
    const double rate = local_rate();
    if (const std::optional<Pose> next = choose_route(map, rate)) {
      remember({});
      previous_branch_.clear();
      step.gain_found = step.routed = true;
      step.next = *next;
      step.tree_nodes = int(tree_.size()) - 1;
      return step;
    }
  }
  if (!gain_found) {
    // No gain near: grow on, drawn partly to the remembered poses that still have gain.
    refresh_memory(map);
    step.grown_on = true;
    ++stats_.grown_on;
    gain_found = grow(map, config_.max_nodes, config_.max_nodes_no_gain, true, false);
    // Still none: what is left is crumbs; lower the threshold and score the same tree again.
    while (!gain_found && threshold_ > config_.final_min_gain) {
      threshold_ = std::max(config_.final_min_gain, 0.5 * threshold_);
      ++stats_.threshold_lowered;
      rescore();
      gain_found = has_gain();
    }
  }
  step.tree_nodes = int(tree_.size()) - 1;
  if (!gain_found) {
    previous_branch_.clear();
    return step;
  }
  std::size_t best = 1;
  for (std::size_t i = 1; i < tree_.size(); ++i) {
    if (tree_[i].score > tree_[best].score) best = i;
  }
  // The branch root -> best, reversed; its first node is where to fly.
  std::vector<std::size_t> branch;
  for (std::size_t i = best; i != 0; i = std::size_t(tree_[i].parent)) branch.push_back(i);
  step.gain_found = true;
  step.next = tree_[branch.back()].pose;
  step.best_gain = tree_[best].gain;
  step.best_score = tree_[best].score;
  previous_branch_.clear();
  for (auto it = branch.rbegin() + 1; it != branch.rend(); ++it) previous_branch_.push_back(tree_[*it].pose);
  remember(branch);
  return step;
}

}  // namespace umbra::explore
