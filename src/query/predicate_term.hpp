// PredicateTerm: the parts a Predicate is made of (an expression tree).
//
// Built by the pred:: functions and the && || ! operators; immutable and
// shared between copies. A query turns it into a CompiledPredicate bound to
// the map (compiled_predicate.hpp), which is what it evaluates per node.
#pragma once

#include <functional>
#include <memory>
#include <variant>

#include "umbra/core/aabb.hpp"
#include "umbra/core/node.hpp"
#include "umbra/query/shapes.hpp"

namespace umbra::detail {

struct PredicateTerm {
  enum class Kind : unsigned char {
    any,
    occupied,
    free,
    unknown,
    contains_occupied,
    contains_free,
    contains_unknown,
    leaf,
    depth_exactly,
    depth_at_least,
    depth_at_most,
    shape,
    rule,
    all_of,   // a && b
    any_of,   // a || b
    none_of,  // !a
  };
  using Shape = std::variant<Aabb, Sphere, OrientedBox, Capsule, Segment, Frustum>;

  Kind kind = Kind::any;
  int depth = 0;                               // depth_*
  Shape shape;                                 // shape
  std::function<bool(const Node&)> rule;       // rule
  std::shared_ptr<const PredicateTerm> a, b;  // all_of, any_of (a, b), none_of (a)
};

}  // namespace umbra::detail
