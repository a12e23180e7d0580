// umbra.pred: the predicates of queries (umbra/query/predicate.hpp) as
// Python values combined with &, | and ~ (Python's `and`, `or`, `not`
// cannot be overloaded, so a predicate refuses to be a bool).
//
// pred.satisfies(callable) calls back into Python from a query that runs
// with the GIL released: the rule takes the GIL for each call (and to be
// destroyed). Such a query costs a Python call per node it reaches; combine
// the rule with the other predicates so that the query skips subtrees.
#include <memory>

#include "bindings.hpp"
#include "umbra/query/shapes.hpp"

namespace umbra::python {
namespace {

/// A Python callable usable from any thread: it takes the GIL to be called
/// and to be released.
class PythonRule {
 public:
  explicit PythonRule(py::function rule)
      : rule_(new py::function(std::move(rule)), [](py::function* f) {
          py::gil_scoped_acquire gil;
          delete f;
        }) {}
  bool operator()(const Node& node) const {
    py::gil_scoped_acquire gil;
    return py::bool_((*rule_)(node));
  }

 private:
  std::shared_ptr<py::function> rule_;
};

PyPredicate named(Predicate predicate, std::string text) { return {std::move(predicate), "pred." + text, false}; }

PyPredicate combined(Predicate predicate, const PyPredicate& a, const char* op, const PyPredicate& b) {
  return {std::move(predicate), "(" + a.text + op + b.text + ")", true};
}

/// One overload of pred.intersects; the first carries the docstring
/// (pybind11 would repeat the text of every overload).
template <typename Shape>
void def_intersects(py::module_& pred, const char* doc = "") {
  pred.def(
      "intersects",
      [](const Shape& shape) {
        return named(pred::intersects(shape), "intersects(" + std::string(py::repr(py::cast(shape))) + ")");
      },
      py::arg("shape"), doc);
}

}  // namespace

Predicate predicate_of(const py::object& object) {
  if (object.is_none()) return pred::any();
  return object.cast<const PyPredicate&>().predicate;
}

void bind_predicates(py::module_& m) {
  py::class_<PyPredicate>(m, "Predicate",
                          "Which nodes a query wants; made by the functions of umbra.pred and combined with "
                          "& (and), | (or) and ~ (not).")
      .def("__and__",
           [](const PyPredicate& a, const PyPredicate& b) { return combined(a.predicate && b.predicate, a, " & ", b); })
      .def("__or__",
           [](const PyPredicate& a, const PyPredicate& b) { return combined(a.predicate || b.predicate, a, " | ", b); })
      .def("__invert__", [](const PyPredicate& a) { return PyPredicate{!a.predicate, "~" + a.text, false}; })
      .def("__bool__",
           [](const PyPredicate&) -> bool {
             throw py::type_error("a predicate has no truth value: combine predicates with &, | and ~, "
                                  "not with 'and', 'or' and 'not'");
           })
      .def("__repr__", [](const PyPredicate& p) {
        return p.parenthesised ? p.text.substr(1, p.text.size() - 2) : p.text;
      });

  py::module_ pred = m.def_submodule("pred", "Predicates of queries, combined with &, | and ~.");
  struct Simple {
    const char* name;
    Predicate (*make)();
    const char* doc;
  };
  for (const Simple& simple : {
           Simple{"any", &pred::any, "Every node."},
           Simple{"occupied", &pred::occupied, "Nodes holding an occupied voxel (value above the occupied threshold)."},
           Simple{"free", &pred::free, "Nodes whose voxels are all free."},
           Simple{"unknown", &pred::unknown, "Nodes neither occupied nor free."},
           Simple{"contains_occupied", &pred::contains_occupied, "Nodes with an occupied voxel (as occupied)."},
           Simple{"contains_free", &pred::contains_free, "Nodes with a free voxel."},
           Simple{"contains_unknown", &pred::contains_unknown, "Nodes with an unknown voxel."},
           Simple{"leaf", &pred::leaf,
                  "Nodes without children at the query's depth; together they tile the map once."},
       }) {
    pred.def(
        simple.name, [simple] { return named(simple.make(), std::string(simple.name) + "()"); }, simple.doc);
  }
  pred.def(
      "depth", [](int d) { return named(pred::depth(d), "depth(" + std::to_string(d) + ")"); }, py::arg("depth"),
      "Nodes at exactly this depth.");
  pred.def(
      "min_depth", [](int d) { return named(pred::min_depth(d), "min_depth(" + std::to_string(d) + ")"); },
      py::arg("depth"), "Nodes at this depth or coarser.");
  pred.def(
      "max_depth", [](int d) { return named(pred::max_depth(d), "max_depth(" + std::to_string(d) + ")"); },
      py::arg("depth"), "Nodes at this depth or finer.");
  def_intersects<Aabb>(
      pred, "Nodes that meet the shape (an Aabb, Sphere, OrientedBox, Capsule, Segment or Frustum; see the shapes).");
  def_intersects<Sphere>(pred);
  def_intersects<OrientedBox>(pred);
  def_intersects<Capsule>(pred);
  def_intersects<Segment>(pred);
  def_intersects<Frustum>(pred);
  pred.def(
      "satisfies",
      [](py::function rule) {
        const std::string text = "satisfies(" + std::string(py::repr(rule)) + ")";
        return named(pred::satisfies(PythonRule(std::move(rule))), text);
      },
      py::arg("rule"),
      "Nodes for which rule(node) is true (node: a umbra.Node). Called per node the rest of an & admits; "
      "combine it with other predicates to keep a query fast.");
}

}  // namespace umbra::python
