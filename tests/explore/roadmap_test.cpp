// Tests of the explorer's roadmap (examples/explore/roadmap.hpp) against
// brute force: near() against a scan of every vertex, shortest paths
// against Floyd-Warshall on random graphs, paths walked edge by edge.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "roadmap.hpp"

namespace umbra::explore {
namespace {

const Aabb kBounds{{0.0, 0.0, 0.0}, {10.0, 8.0, 4.0}};

Vec3d random_point(std::mt19937& rng) {
  std::uniform_real_distribution<double> x(-1.0, 11.0), y(-1.0, 9.0), z(-1.0, 5.0);  // some outside the bounds
  return {x(rng), y(rng), z(rng)};
}

TEST(Roadmap, NearFindsExactlyTheVerticesWithinTheRadiusNearestFirst) {
  std::mt19937 rng(3);
  Roadmap roadmap(kBounds, 1.5);
  std::vector<Vec3d> points;
  for (int i = 0; i < 800; ++i) {
    points.push_back(random_point(rng));
    EXPECT_EQ(roadmap.add_vertex(points.back()), i);
  }
  for (int q = 0; q < 200; ++q) {
    const Vec3d at = random_point(rng);
    const double radius = q % 2 ? 1.5 : 0.7;
    std::vector<int> expected;
    for (int i = 0; i < int(points.size()); ++i) {
      if ((points[std::size_t(i)] - at).norm() <= radius) expected.push_back(i);
    }
    std::vector<int> found = roadmap.near(at, radius);
    for (std::size_t k = 1; k < found.size(); ++k) {
      EXPECT_LE((roadmap.position(found[k - 1]) - at).norm(), (roadmap.position(found[k]) - at).norm());
    }
    std::sort(found.begin(), found.end());
    EXPECT_EQ(found, expected) << "query " << q;
  }
}

TEST(Roadmap, ShortestPathsEqualFloydWarshallAndWalkRealEdges) {
  std::mt19937 rng(8);
  for (int trial = 0; trial < 20; ++trial) {
    Roadmap roadmap(kBounds, 1.5);
    const int n = 40;
    for (int i = 0; i < n; ++i) roadmap.add_vertex(random_point(rng));
    constexpr double inf = std::numeric_limits<double>::infinity();
    std::vector<std::vector<double>> d(n, std::vector<double>(n, inf));
    for (int i = 0; i < n; ++i) d[i][i] = 0.0;
    std::uniform_int_distribution<int> pick(0, n - 1);
    for (int e = 0; e < 70; ++e) {
      const int a = pick(rng), b = pick(rng);
      roadmap.add_edge(a, b);
      roadmap.add_edge(b, a);  // the same edge again: ignored
      if (a != b) d[a][b] = d[b][a] = (roadmap.position(a) - roadmap.position(b)).norm();
    }
    // Remove a few, in both directions.
    for (int e = 0; e < 10; ++e) {
      const int a = pick(rng), b = pick(rng);
      roadmap.remove_edge(a, b);
      if (a != b) d[a][b] = d[b][a] = inf;
    }
    std::vector<std::vector<double>> edge = d;
    for (int k = 0; k < n; ++k) {
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) d[i][j] = std::min(d[i][j], d[i][k] + d[k][j]);
      }
    }
    const int source = pick(rng);
    const Roadmap::Paths paths = roadmap.shortest_paths(source);
    for (int t = 0; t < n; ++t) {
      SCOPED_TRACE("trial " + std::to_string(trial) + " target " + std::to_string(t));
      if (d[source][t] == inf) {
        EXPECT_EQ(paths.distance[std::size_t(t)], Roadmap::unreachable);
        EXPECT_TRUE(paths.path_to(t).empty());
        continue;
      }
      EXPECT_NEAR(paths.distance[std::size_t(t)], d[source][t], 1e-9);
      const std::vector<int> path = paths.path_to(t);
      ASSERT_FALSE(path.empty());
      EXPECT_EQ(path.front(), source);
      EXPECT_EQ(path.back(), t);
      double length = 0.0;
      for (std::size_t k = 1; k < path.size(); ++k) {
        ASSERT_LT(edge[path[k - 1]][path[k]], inf) << "the path uses a missing edge";
        length += edge[path[k - 1]][path[k]];
      }
      EXPECT_NEAR(length, d[source][t], 1e-9);
    }
  }
}

TEST(Roadmap, DegreesCountEdgesOnceAndBadGeometryIsRefused) {
  Roadmap roadmap(kBounds, 1.0);
  const int a = roadmap.add_vertex({1, 1, 1});
  const int b = roadmap.add_vertex({2, 1, 1});
  roadmap.add_edge(a, b);
  roadmap.add_edge(a, b);
  roadmap.add_edge(a, a);
  EXPECT_EQ(roadmap.degree(a), 1u);
  EXPECT_EQ(roadmap.degree(b), 1u);
  roadmap.remove_edge(b, a);
  EXPECT_EQ(roadmap.degree(a), 0u);
  EXPECT_THROW(Roadmap(kBounds, 0.0), std::invalid_argument);
  EXPECT_THROW(Roadmap(kBounds, std::nan("")), std::invalid_argument);
  EXPECT_THROW(Roadmap(Aabb{{0, 0, 0}, {0, 1, 1}}, 1.0), std::invalid_argument);
}

}  // namespace
}  // namespace umbra::explore
