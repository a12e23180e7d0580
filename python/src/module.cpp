// The compiled part of the Python package umbra (umbra/_umbra*.so); the
// package's __init__.py re-exports it. Docstrings are written here and
// repeated in the type stubs (umbra/*.pyi); a test checks that they match.
#include "bindings.hpp"

PYBIND11_MODULE(_umbra, m) {
  namespace py = pybind11;
  using namespace umbra::python;
  // Docstrings are the text alone: the stubs carry the signatures.
  py::options options;
  options.disable_function_signatures();
  m.doc() = "umbra: probabilistic 3D occupancy maps with unknown, free and occupied space explicit.";
  bind_values(m);
  bind_shapes(m);
  bind_predicates(m);
  MapClass map = bind_map(m);
  bind_queries(m, map);
  bind_gain(m, map);
  bind_io(m, map);
  bind_depth(m, map);
  bind_sim(m);
}
