// When does a cube meet a query shape? Written independently of the
// library's src/query/geometry (corner projections instead of radii, a
// ternary search instead of the piecewise quadratic), for the query tests'
// brute force.
#pragma once

#include "umbra/core/aabb.hpp"
#include "umbra/query/shapes.hpp"

namespace umbra::test {

/// A closed cube (or box) in metres.
struct Cube {
  Vec3d min;
  Vec3d max;
};

/// Squared distance from a point to the cube (0 inside).
double clamp_distance_squared(Vec3d p, const Cube& c);

bool meets(const Aabb& box, const Cube& c);
bool meets(const Sphere& s, const Cube& c);
bool meets(const Capsule& capsule, const Cube& c);
bool meets(const OrientedBox& box, const Cube& c);

}  // namespace umbra::test
