// Roadmap: the places the explorer knows how to reach, as a graph.
//
// Vertices are points in free space: where the robot planned from, and the
// tree nodes on the way to the poses the planner remembers. Edges are
// straight flights known to be free for the robot's ball when they were
// added (a flown edge, an edge of a tree, or a capsule the planner checked).
// The planner routes to a remembered pose far away over this graph (the
// local tree alone never leaves a well-explored neighbourhood) and removes
// an edge found blocked later (a surface seen after it was added).
//
// Layout: vertices in one vector, each with its adjacency list; a uniform
// grid of `cell_size` over `bounds` lists the vertices per cell, so the
// neighbours of a point are found in the 27 cells around it.
//
// Cost: add_vertex and add_edge O(1); near() O(vertices in 27 cells);
// shortest_paths() is Dijkstra, O(E log V): a few milliseconds for the
// tens of thousands of vertices of a 900 s exploration.
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

#include "umbra/core/aabb.hpp"
#include "umbra/core/vec3.hpp"

namespace umbra::explore {

class Roadmap {
 public:
  /// Vertices outside `bounds` go into its border cells. Throws
  /// std::invalid_argument for a cell size that is not > 0 or an empty box.
  Roadmap(const Aabb& bounds, double cell_size);

  /// Adds a vertex; returns its index.
  int add_vertex(Vec3d position);
  /// Adds the undirected edge a - b (its length is the distance); a second
  /// edge between the same vertices, or a loop, is ignored.
  void add_edge(int a, int b);
  /// Removes the edge a - b if present.
  void remove_edge(int a, int b);

  [[nodiscard]] std::size_t size() const { return vertices_.size(); }
  [[nodiscard]] Vec3d position(int vertex) const { return vertices_[std::size_t(vertex)].position; }
  [[nodiscard]] std::size_t degree(int vertex) const { return vertices_[std::size_t(vertex)].edges.size(); }

  /// Vertices within `radius` (<= the cell size) of `point`, nearest first.
  [[nodiscard]] std::vector<int> near(Vec3d point, double radius) const;

  /// Shortest distances from `source` over the edges to every vertex
  /// (infinity when unreachable), and each vertex's predecessor on its path.
  struct Paths {
    std::vector<double> distance;
    std::vector<int> previous;
    /// The vertices from the source to `target`, both included; empty when unreachable.
    [[nodiscard]] std::vector<int> path_to(int target) const;
  };
  [[nodiscard]] Paths shortest_paths(int source) const;

  static constexpr double unreachable = std::numeric_limits<double>::infinity();

 private:
  struct Edge {
    int to;
    double length;
  };
  struct Vertex {
    Vec3d position;
    std::vector<Edge> edges;
  };
  [[nodiscard]] std::size_t cell_of(Vec3d point) const;
  [[nodiscard]] long axis_cell(double coordinate, int axis) const;

  Aabb bounds_;
  double cell_size_;
  long cells_[3] = {1, 1, 1};
  std::vector<Vertex> vertices_;
  std::vector<std::vector<int>> grid_;  ///< vertices per cell, x fastest
};

}  // namespace umbra::explore
