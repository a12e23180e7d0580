// The parts of the Python module umbra, one function per concern (each in
// its own bind_*.cpp), and what they share: the structured array of nodes
// and the Python predicate.
//
// Every binding that touches the map releases the GIL while the C++ library
// works (py::gil_scoped_release), so Python threads query while another
// inserts; the map's own locks order the calls (occupancy_map.hpp). Python
// objects are only touched with the GIL held: arguments are converted to C++
// values or numpy views before the release, results after it.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "umbra/core/node.hpp"
#include "umbra/integrate/insert_options.hpp"
#include "umbra/map/occupancy_map.hpp"
#include "umbra/query/predicate.hpp"

namespace umbra::python {

namespace py = pybind11;

using MapClass = py::class_<OccupancyMap>;

/// One row of the structured arrays of nodes (umbra.NODE_DTYPE).
struct NodeRecord {
  double center[3];
  double size;
  std::uint32_t key[3];
  std::int32_t depth;
  float log_odds;
  std::uint8_t state;  ///< umbra.UNKNOWN, FREE, OCCUPIED
  bool contains_free;
  bool contains_unknown;
  bool has_children;
  bool has_color;
  std::uint8_t color[3];  ///< (0, 0, 0) without color
};

/// Writes the node into a row (all of it, padding included).
void write_record(const Node& node, NodeRecord& row);
/// The nodes as a structured array of NodeRecord (made with the GIL held).
py::array node_array(const std::vector<Node>& nodes);

/// A predicate as Python holds it: the C++ value and how it was written
/// ("(pred.occupied() & pred.leaf())"; parenthesised when it is an & or |).
struct PyPredicate {
  Predicate predicate;
  std::string text;
  bool parenthesised = false;
};

/// The predicate argument of a query: None (every node) or a umbra.pred value.
Predicate predicate_of(const py::object& object);

/// "Name(a=..., b=...)": the repr() of each named attribute of object, for
/// the __repr__ of value classes whose attributes say it all.
std::string repr_of_attributes(py::handle object, const std::string& class_name,
                               std::initializer_list<const char*> attributes);

/// The options insert() and insert_depth_image() share; ValueError for negative threads or an unknown integrator.
InsertOptions insert_options(const std::string& integrator, double max_range, int clear_depth, int fine_steps,
                             int threads);

void bind_values(py::module_& m);
void bind_shapes(py::module_& m);
void bind_predicates(py::module_& m);
MapClass bind_map(py::module_& m);
void bind_queries(py::module_& m, MapClass& map);
void bind_gain(py::module_& m, MapClass& map);
void bind_io(py::module_& m, MapClass& map);
void bind_depth(py::module_& m, MapClass& map);
void bind_sim(py::module_& m);
void bind_navigation(py::module_& m, MapClass& map);
void bind_field(py::module_& m);
void bind_merge(py::module_& m, MapClass& map);
void bind_window(py::module_& m, MapClass& map);
/// Gives every function of m and its submodules a __text_signature__ (text_signatures.cpp); call last.
void add_text_signatures(py::module_& m);

}  // namespace umbra::python
