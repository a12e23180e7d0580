// The compiled part of the Python package umbra (umbra/_umbra*.so); the
// package's __init__.py re-exports it. Docstrings are written here and
// repeated in the type stubs (umbra/*.pyi); a test checks that they match.
// pybind11 puts each function's signature (names, types, defaults) in front
// of its docstring, which help() shows; add_text_signatures makes
// inspect.signature read it too.
#include "bindings.hpp"

PYBIND11_MODULE(_umbra, m) {
  namespace py = pybind11;
  using namespace umbra::python;
  m.doc() = "umbra: probabilistic 3D occupancy maps with unknown, free and occupied space explicit.";
  m.attr("__version__") = UMBRA_VERSION_TEXT;  // the project's version (CMakeLists.txt, project())
  bind_values(m);
  bind_shapes(m);
  bind_predicates(m);
  MapClass map = bind_map(m);
  bind_queries(m, map);
  bind_gain(m, map);
  bind_io(m, map);
  bind_depth(m, map);
  bind_navigation(m, map);
  bind_merge(m, map);
  bind_window(m, map);
  bind_sim(m);
  bind_field(m);
  add_text_signatures(m);
}
