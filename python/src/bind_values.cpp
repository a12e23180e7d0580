// Small values of the module: the state codes, the sensor model and the
// thresholds, nodes (as objects and as rows of a structured array), node
// counts, insertion statistics and map statistics. All are immutable
// copies: they never point into a map.
#include <cstring>
#include <sstream>

#include <pybind11/operators.h>

#include "bindings.hpp"
#include "numpy_arrays.hpp"
#include "umbra/integrate/insert_options.hpp"
#include "umbra/map/map_statistics.hpp"

namespace umbra::python {

void write_record(const Node& node, NodeRecord& r) {
  std::memset(&r, 0, sizeof r);  // padding too: no stray bytes in the array
  for (int axis = 0; axis < 3; ++axis) {
    r.center[axis] = node.center[static_cast<std::size_t>(axis)];
    r.key[axis] = node.key[axis];
  }
  r.size = node.size;
  r.depth = node.depth;
  r.log_odds = node.log_odds;
  r.state = static_cast<std::uint8_t>(node.state);
  r.contains_free = node.contains_free;
  r.contains_unknown = node.contains_unknown;
  r.has_children = node.has_children;
  r.has_color = node.color.has_value();
  if (node.color) {
    r.color[0] = node.color->r;
    r.color[1] = node.color->g;
    r.color[2] = node.color->b;
  }
}

std::string repr_of_attributes(py::handle object, const std::string& class_name,
                               std::initializer_list<const char*> attributes) {
  std::string text = class_name + "(";
  const char* separator = "";
  for (const char* name : attributes) {
    text += separator;
    text += name;
    text += "=";
    text += py::repr(object.attr(name));
    separator = ", ";
  }
  return text + ")";
}

py::array node_array(const std::vector<Node>& nodes) {
  py::array_t<NodeRecord> array(static_cast<py::ssize_t>(nodes.size()));
  NodeRecord* out = array.mutable_data();
  for (std::size_t i = 0; i < nodes.size(); ++i) write_record(nodes[i], out[i]);
  return array;
}

namespace {

std::string number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

py::object color_of(const Node& node) {
  if (!node.color) return py::none();
  return py::make_tuple(node.color->r, node.color->g, node.color->b);
}

void bind_node(py::module_& m) {
  py::class_<Node>(m, "Node", "One node of a map as a query reports it: a copy that stays valid after the map changes.")
      .def_property_readonly(
          "key", [](const Node& n) { return py::make_tuple(n.key.x, n.key.y, n.key.z); },
          "Finest key (x, y, z) of the node's lowest corner voxel.")
      .def_readonly("depth", &Node::depth, "0: a voxel; d: a node of 8**d voxels.")
      .def_property_readonly(
          "center", [](const Node& n) { return to_tuple(n.center); }, "Centre (x, y, z) in metres.")
      .def_readonly("size", &Node::size, "Edge length in metres.")
      .def_readonly("log_odds", &Node::log_odds, "Log-odds occupancy: the maximum over the node's voxels.")
      .def_property_readonly(
          "occupancy", [](const Node& n) { return probability(n.log_odds); },
          "Occupancy probability of log_odds.")
      .def_property_readonly(
          "state", [](const Node& n) { return static_cast<int>(n.state); },
          "umbra.UNKNOWN, umbra.FREE or umbra.OCCUPIED.")
      .def_property_readonly("contains_occupied", &Node::contains_occupied, "Some voxel in the node is occupied.")
      .def_readonly("contains_free", &Node::contains_free, "Some voxel in the node is free.")
      .def_readonly("contains_unknown", &Node::contains_unknown, "Some voxel in the node is unknown.")
      .def_readonly("has_children", &Node::has_children,
                    "The node has children in the map; a childless node's value holds for all its voxels.")
      .def_property_readonly("color", color_of, "The (r, g, b) color of a colored node, else None.")
      .def_property_readonly(
          "min_corner", [](const Node& n) { return to_tuple(n.min_corner()); }, "Lowest corner in metres.")
      .def_property_readonly(
          "max_corner", [](const Node& n) { return to_tuple(n.max_corner()); }, "Highest corner in metres.")
      .def("__repr__", [](const Node& n) {
        return "Node(center=(" + number(n.center.x) + ", " + number(n.center.y) + ", " + number(n.center.z) +
               "), depth=" + std::to_string(n.depth) + ", state=" + to_string(n.state) +
               ", log_odds=" + number(n.log_odds) + ")";
      });
}

void bind_sensor_model_and_thresholds(py::module_& m) {
  py::class_<SensorModel>(m, "SensorModel",
                          "Probabilities of the inverse sensor model (OctoMap's defaults). Raises ValueError "
                          "unless 0.5 < p_hit < 1, 0 < p_miss < 0.5 and 0 < clamp_min <= 0.5 <= clamp_max < 1.")
      .def(py::init([](double p_hit, double p_miss, double clamp_min, double clamp_max) {
             const SensorModel model{p_hit, p_miss, clamp_min, clamp_max};
             model.validate();
             return model;
           }),
           py::arg("p_hit") = 0.7, py::arg("p_miss") = 0.4, py::arg("clamp_min") = 0.1192,
           py::arg("clamp_max") = 0.971, "The probabilities; the defaults are OctoMap's.")
      .def_readonly("p_hit", &SensorModel::p_hit, "Probability a hit stands for.")
      .def_readonly("p_miss", &SensorModel::p_miss, "Probability a miss stands for.")
      .def_readonly("clamp_min", &SensorModel::clamp_min, "Lowest probability a voxel keeps.")
      .def_readonly("clamp_max", &SensorModel::clamp_max, "Highest probability a voxel keeps.")
      .def(py::self == py::self)
      .def("__repr__", [](const SensorModel& s) {
        return "SensorModel(p_hit=" + number(s.p_hit) + ", p_miss=" + number(s.p_miss) +
               ", clamp_min=" + number(s.clamp_min) + ", clamp_max=" + number(s.clamp_max) + ")";
      });

  py::class_<Thresholds>(m, "Thresholds",
                         "Occupied if p > occupied, free if p < free, unknown otherwise. Raises ValueError "
                         "unless 0 < free <= occupied < 1.")
      .def(py::init([](double occupied, double free) {
             const Thresholds thresholds{occupied, free};
             thresholds.validate();
             return thresholds;
           }),
           py::arg("occupied") = 0.5, py::arg("free") = 0.5,
           "The two thresholds on the occupancy probability; the defaults are OctoMap's.")
      .def_readonly("occupied", &Thresholds::occupied, "Probability above which a voxel is occupied.")
      .def_readonly("free", &Thresholds::free, "Probability below which a voxel is free.")
      .def(py::self == py::self)
      .def("__repr__", [](const Thresholds& t) {
        return "Thresholds(occupied=" + number(t.occupied) + ", free=" + number(t.free) + ")";
      });
}

void bind_counts_and_stats(py::module_& m) {
  py::class_<NodeCounts>(m, "NodeCounts", "How many nodes of each kind a map holds.")
      .def_readonly("inner", &NodeCounts::inner, "Nodes with eight children.")
      .def_readonly("inner_leaf", &NodeCounts::inner_leaf, "Childless nodes above the finest depth.")
      .def_readonly("leaf", &NodeCounts::leaf, "Finest voxels stored.")
      .def_property_readonly("total", &NodeCounts::total, "All nodes.")
      .def("__repr__", [](const NodeCounts& c) {
        return "NodeCounts(inner=" + std::to_string(c.inner) + ", inner_leaf=" + std::to_string(c.inner_leaf) +
               ", leaf=" + std::to_string(c.leaf) + ")";
      });

  py::class_<InsertStats>(m, "InsertStats", "What happened to the points of one scan.")
      .def_readonly("points", &InsertStats::points, "Points given.")
      .def_readonly("rays", &InsertStats::rays, "Rays traced (after de-duplication per voxel for discrete / fast).")
      .def_readonly("hits", &InsertStats::hits, "Rays whose end voxel got a hit.")
      .def_readonly("truncated", &InsertStats::truncated, "Rays beyond max_range, cut there without a hit.")
      .def_readonly("non_finite", &InsertStats::non_finite, "NaN or infinite points, skipped.")
      .def_readonly("out_of_bounds", &InsertStats::out_of_bounds, "Points outside the map, skipped.")
      .def_readonly("outside_box", &InsertStats::outside_box, "Rays missing the bounding box, skipped.")
      .def_readonly("exclusive_seconds", &InsertStats::exclusive_seconds,
                    "Seconds the scan kept queries out (its apply phase).")
      .def("__repr__", [](const InsertStats& s) {
        return "InsertStats(points=" + std::to_string(s.points) + ", rays=" + std::to_string(s.rays) +
               ", hits=" + std::to_string(s.hits) + ", truncated=" + std::to_string(s.truncated) +
               ", non_finite=" + std::to_string(s.non_finite) + ", out_of_bounds=" + std::to_string(s.out_of_bounds) +
               ", outside_box=" + std::to_string(s.outside_box) + ", exclusive_seconds=" + number(s.exclusive_seconds) +
               ")";
      });

  py::class_<MapStatistics>(m, "MapStatistics",
                            "What `umbra info` reports. Voxel counts are in finest voxels; bounds are those of "
                            "the known space (None when nothing is known).")
      .def_readonly("resolution", &MapStatistics::resolution, "Edge of a finest voxel, metres.")
      .def_readonly("depth_levels", &MapStatistics::depth_levels, "Depth levels of the tree.")
      .def_readonly("nodes", &MapStatistics::nodes, "Node counts.")
      .def_readonly("memory_bytes", &MapStatistics::memory_bytes, "Bytes allocated for the map.")
      .def_readonly("occupied_voxels", &MapStatistics::occupied_voxels, "Occupied finest voxels.")
      .def_readonly("free_voxels", &MapStatistics::free_voxels, "Free finest voxels.")
      .def_readonly("occupied_volume_m3", &MapStatistics::occupied_volume_m3, "Occupied volume, cubic metres.")
      .def_readonly("free_volume_m3", &MapStatistics::free_volume_m3, "Free volume, cubic metres.")
      .def_property_readonly(
          "known_min",
          [](const MapStatistics& s) -> py::object {
            if (!s.has_known_space) return py::none();
            return to_tuple(s.known_min);
          },
          "Lowest corner of the known space, or None.")
      .def_property_readonly(
          "known_max",
          [](const MapStatistics& s) -> py::object {
            if (!s.has_known_space) return py::none();
            return to_tuple(s.known_max);
          },
          "Highest corner of the known space, or None.")
      .def("__repr__", [](py::handle self) {
        return repr_of_attributes(self, "MapStatistics",
                                  {"resolution", "depth_levels", "nodes", "memory_bytes", "occupied_voxels",
                                   "free_voxels", "occupied_volume_m3", "free_volume_m3", "known_min", "known_max"});
      });
}

}  // namespace

void bind_values(py::module_& m) {
  PYBIND11_NUMPY_DTYPE(NodeRecord, center, size, key, depth, log_odds, state, contains_free, contains_unknown,
                       has_children, has_color, color);
  m.attr("UNKNOWN") = static_cast<int>(OccupancyState::unknown);
  m.attr("FREE") = static_cast<int>(OccupancyState::free);
  m.attr("OCCUPIED") = static_cast<int>(OccupancyState::occupied);
  m.attr("NODE_DTYPE") = py::dtype::of<NodeRecord>();
  bind_node(m);
  bind_sensor_model_and_thresholds(m);
  bind_counts_and_stats(m);
}

}  // namespace umbra::python
