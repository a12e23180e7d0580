#include "umbra/query/predicate.hpp"

#include <stdexcept>
#include <string>
#include <utility>

#include "query/predicate_term.hpp"

namespace umbra {
namespace {

using Term = detail::PredicateTerm;
using Kind = Term::Kind;

Predicate make(Kind kind) {
  auto term = std::make_shared<Term>();
  term->kind = kind;
  return Predicate(std::move(term));
}

Predicate make_depth(Kind kind, int depth) {
  if (depth < 0 || depth > kMaxDepthLevels) {
    throw std::invalid_argument("depth predicate: depth must be in [0, " + std::to_string(kMaxDepthLevels) +
                                "], got " + std::to_string(depth));
  }
  auto term = std::make_shared<Term>();
  term->kind = kind;
  term->depth = depth;
  return Predicate(std::move(term));
}

template <typename Shape>
Predicate make_shape(const Shape& shape) {
  shape.validate();
  auto term = std::make_shared<Term>();
  term->kind = Kind::shape;
  term->shape = shape;
  return Predicate(std::move(term));
}

Predicate combine(Kind kind, std::shared_ptr<const Term> a, std::shared_ptr<const Term> b) {
  auto term = std::make_shared<Term>();
  term->kind = kind;
  term->a = std::move(a);
  term->b = std::move(b);
  return Predicate(std::move(term));
}

}  // namespace

Predicate::Predicate() : Predicate(std::make_shared<Term>()) {}

Predicate::Predicate(std::shared_ptr<const detail::PredicateTerm> term) : term_(std::move(term)) {}

Predicate operator&&(const Predicate& a, const Predicate& b) { return combine(Kind::all_of, a.term_, b.term_); }
Predicate operator||(const Predicate& a, const Predicate& b) { return combine(Kind::any_of, a.term_, b.term_); }
Predicate operator!(const Predicate& a) { return combine(Kind::none_of, a.term_, nullptr); }

namespace pred {

Predicate any() { return make(Kind::any); }
Predicate occupied() { return make(Kind::occupied); }
Predicate free() { return make(Kind::free); }
Predicate unknown() { return make(Kind::unknown); }
Predicate contains_occupied() { return make(Kind::contains_occupied); }
Predicate contains_free() { return make(Kind::contains_free); }
Predicate contains_unknown() { return make(Kind::contains_unknown); }
Predicate leaf() { return make(Kind::leaf); }
Predicate depth(int exactly) { return make_depth(Kind::depth_exactly, exactly); }
Predicate min_depth(int depth) { return make_depth(Kind::depth_at_least, depth); }
Predicate max_depth(int depth) { return make_depth(Kind::depth_at_most, depth); }
Predicate intersects(const Aabb& box) { return make_shape(box); }
Predicate intersects(const Sphere& sphere) { return make_shape(sphere); }
Predicate intersects(const OrientedBox& box) { return make_shape(box); }
Predicate intersects(const Capsule& capsule) { return make_shape(capsule); }
Predicate intersects(const Segment& segment) { return make_shape(segment); }
Predicate intersects(const Frustum& frustum) { return make_shape(frustum); }

Predicate satisfies(std::function<bool(const Node&)> rule) {
  if (!rule) throw std::invalid_argument("pred::satisfies: the rule is empty");
  auto term = std::make_shared<Term>();
  term->kind = Kind::rule;
  term->rule = std::move(rule);
  return Predicate(std::move(term));
}

}  // namespace pred
}  // namespace umbra
