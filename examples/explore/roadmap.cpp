#include "roadmap.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <queue>
#include <stdexcept>
#include <utility>

namespace umbra::explore {

Roadmap::Roadmap(const Aabb& bounds, double cell_size) : bounds_(bounds), cell_size_(cell_size) {
  if (!(cell_size > 0.0) || !std::isfinite(cell_size)) {
    throw std::invalid_argument("Roadmap: cell size must be finite and > 0, got " + std::to_string(cell_size));
  }
  std::size_t cells = 1;
  for (int a = 0; a < 3; ++a) {
    const double extent = bounds.max[std::size_t(a)] - bounds.min[std::size_t(a)];
    if (!(extent > 0.0)) throw std::invalid_argument("Roadmap: bounds must have min < max on every axis");
    cells_[a] = std::max(1L, long(std::ceil(extent / cell_size)));
    cells *= std::size_t(cells_[a]);
  }
  grid_.resize(cells);
}

long Roadmap::axis_cell(double coordinate, int axis) const {
  const long cell = long(std::floor((coordinate - bounds_.min[std::size_t(axis)]) / cell_size_));
  return std::clamp(cell, 0L, cells_[axis] - 1);
}

std::size_t Roadmap::cell_of(Vec3d point) const {
  return std::size_t((axis_cell(point.z, 2) * cells_[1] + axis_cell(point.y, 1)) * cells_[0] + axis_cell(point.x, 0));
}

int Roadmap::add_vertex(Vec3d position) {
  vertices_.push_back({position, {}});
  const int index = int(vertices_.size()) - 1;
  grid_[cell_of(position)].push_back(index);
  return index;
}

void Roadmap::add_edge(int a, int b) {
  if (a == b) return;
  auto& from = vertices_[std::size_t(a)].edges;
  if (std::any_of(from.begin(), from.end(), [&](const Edge& e) { return e.to == b; })) return;
  const double length = (position(a) - position(b)).norm();
  from.push_back({b, length});
  vertices_[std::size_t(b)].edges.push_back({a, length});
}

void Roadmap::remove_edge(int a, int b) {
  std::erase_if(vertices_[std::size_t(a)].edges, [&](const Edge& e) { return e.to == b; });
  std::erase_if(vertices_[std::size_t(b)].edges, [&](const Edge& e) { return e.to == a; });
}

std::vector<int> Roadmap::near(Vec3d point, double radius) const {
  std::vector<std::pair<double, int>> found;
  const long cx = axis_cell(point.x, 0), cy = axis_cell(point.y, 1), cz = axis_cell(point.z, 2);
  for (long z = std::max(0L, cz - 1); z <= std::min(cells_[2] - 1, cz + 1); ++z) {
    for (long y = std::max(0L, cy - 1); y <= std::min(cells_[1] - 1, cy + 1); ++y) {
      for (long x = std::max(0L, cx - 1); x <= std::min(cells_[0] - 1, cx + 1); ++x) {
        for (int v : grid_[std::size_t((z * cells_[1] + y) * cells_[0] + x)]) {
          const double d = (position(v) - point).norm();
          if (d <= radius) found.emplace_back(d, v);
        }
      }
    }
  }
  std::sort(found.begin(), found.end());
  std::vector<int> result;
  result.reserve(found.size());
  for (const auto& [d, v] : found) result.push_back(v);
  return result;
}

Roadmap::Paths Roadmap::shortest_paths(int source) const {
  Paths paths;
  paths.distance.assign(vertices_.size(), unreachable);
  paths.previous.assign(vertices_.size(), -1);
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> open;
  paths.distance[std::size_t(source)] = 0.0;
  open.emplace(0.0, source);
  while (!open.empty()) {
    const auto [d, v] = open.top();
    open.pop();
    if (d > paths.distance[std::size_t(v)]) continue;  // a stale entry
    for (const Edge& e : vertices_[std::size_t(v)].edges) {
      const double through = d + e.length;
      if (through < paths.distance[std::size_t(e.to)]) {
        paths.distance[std::size_t(e.to)] = through;
        paths.previous[std::size_t(e.to)] = v;
        open.emplace(through, e.to);
      }
    }
  }
  return paths;
}

std::vector<int> Roadmap::Paths::path_to(int target) const {
  if (distance[std::size_t(target)] == unreachable) return {};
  std::vector<int> path;
  for (int v = target; v != -1; v = previous[std::size_t(v)]) path.push_back(v);
  std::reverse(path.begin(), path.end());
  return path;
}

}  // namespace umbra::explore
