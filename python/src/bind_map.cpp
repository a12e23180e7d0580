// umbra.OccupancyMap: construction, settings, inserting scans, changing
// single voxels, and reading the nodes that contain many points at once.
//
// Per-point functions loop in C++ over a numpy view with the GIL released,
// calling the same public function a C++ user calls per point (so their
// answers and costs are the library's; bench/python_batch_benchmark.py
// measures the difference). A point outside the map raises IndexError
// naming its index and the coordinate.
#include <sstream>
#include <stdexcept>

#include <pybind11/stl.h>

#include "bindings.hpp"
#include "numpy_arrays.hpp"
#include "umbra/integrate/insert_options.hpp"
#include "umbra/map/map_statistics.hpp"

namespace umbra::python {
namespace {

/// Runs answer(i) for every point with the GIL released; an out_of_range
/// error gets the index of the point that caused it.
template <typename Answer>
void for_each_point(const PointArray& points, const Answer& answer) {
  py::gil_scoped_release released;
  std::size_t i = 0;
  try {
    for (; i < points.size(); ++i) answer(i);
  } catch (const std::out_of_range& e) {
    throw std::out_of_range("points[" + std::to_string(i) + "]: " + e.what());
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("points[" + std::to_string(i) + "]: " + e.what());
  }
}

/// map.f(points, depth) -> array of T, one per point: answer(map, point, depth, out).
template <typename T, typename Answer>
py::array_t<T> per_point(const OccupancyMap& map, py::handle object, int depth, const Answer& answer) {
  const PointArray points(object, "points");
  py::array_t<T> answers(points.leading_shape());
  T* out = answers.mutable_data();
  for_each_point(points, [&](std::size_t i) { answer(map, points[i], depth, out[i]); });
  return answers;
}

InsertStats insert(OccupancyMap& map, py::handle points_object, py::handle origin_object, py::handle colors_object,
                   const std::string& integrator, double max_range, int clear_depth, int fine_steps, int threads,
                   std::optional<double> stamp) {
  const ScanPoints points(points_object, "points");
  const Vec3f origin(vec3_of(origin_object, "origin"));
  InsertOptions options = insert_options(integrator, max_range, clear_depth, fine_steps, threads);
  options.stamp = stamp;
  if (colors_object.is_none()) {
    py::gil_scoped_release released;
    return map.insert_point_cloud(origin, points.span(), options);
  }
  const ColorArray colors(colors_object, "colors");
  py::gil_scoped_release released;
  return map.insert_point_cloud(origin, points.span(), colors.span(), options);
}

/// A member function as a Python callable that releases the GIL while it
/// runs: everything that takes the map's locks must, or a thread waiting
/// for the map while holding the GIL could wait for a thread that needs the
/// GIL (a pred.satisfies rule) while holding the map.
template <typename Member>
py::cpp_function released(Member member) {
  return py::cpp_function(member, py::call_guard<py::gil_scoped_release>());
}

std::string describe(const OccupancyMap& map) {
  std::size_t nodes = 0;
  {
    py::gil_scoped_release released;
    nodes = map.node_counts().total();
  }
  std::ostringstream s;
  s << "OccupancyMap(resolution=" << map.resolution() << ", depth_levels=" << map.depth_levels()
    << ", color=" << (map.has_color() ? "True" : "False") << ", nodes=" << nodes << ")";
  return s.str();
}

void bind_settings(MapClass& map) {
  map.def_property_readonly("resolution", &OccupancyMap::resolution, "Edge of a finest voxel, metres.")
      .def_property_readonly("depth_levels", &OccupancyMap::depth_levels, "Depth levels of the tree (1..21).")
      .def_property_readonly(
          "half_extent", [](const OccupancyMap& m) { return m.grid().half_extent(); },
          "The map spans [-half_extent, half_extent) metres on every axis.")
      .def_property_readonly("has_color", &OccupancyMap::has_color, "Whether the map keeps a color per voxel.")
      .def_property("sensor_model", released(&OccupancyMap::sensor_model), released(&OccupancyMap::set_sensor_model),
                    "The SensorModel of future updates; setting it clamps stored values into its range.")
      .def_property("thresholds", released(&OccupancyMap::thresholds), released(&OccupancyMap::set_thresholds),
                    "The Thresholds of the states; setting them updates every indicator at once.")
      .def_property("auto_prune", released(&OccupancyMap::auto_prune), released(&OccupancyMap::set_auto_prune),
                    "Merge eight equal children into their parent (default True; setting it prunes the map).")
      .def_property("bounding_box", released(&OccupancyMap::bounding_box),
                    released(&OccupancyMap::set_bounding_box),
                    "An Aabb limiting future insertions (rays clipped to it), or None.")
      // --- decay toward unknown
      .def(
          "set_decay",
          [](OccupancyMap& m, double occupied_per_second, double free_per_second, std::optional<Aabb> region) {
            m.set_decay(DecayRates{occupied_per_second, free_per_second, region});
          },
          py::arg("occupied_per_second"), py::arg("free_per_second"), py::arg("region") = py::none(),
          py::call_guard<py::gil_scoped_release>(),
          "From now on every advance of the clock moves each voxel (in region, an Aabb, if given) toward unknown "
          "(log-odds 0) by rate x seconds passed: occupied_per_second off occupied values, free_per_second off "
          "free ones; both 0: no decay. ValueError for a negative or non-finite rate.")
      .def_property_readonly(
          "decay",
          [](const OccupancyMap& m) {
            const DecayRates rates = m.decay();
            return py::make_tuple(rates.occupied_per_second, rates.free_per_second, rates.region);
          },
          "The decay rates as (occupied_per_second, free_per_second, region or None).")
      .def("advance_clock", &OccupancyMap::advance_clock, py::arg("time"), py::call_guard<py::gil_scoped_release>(),
           "Advances the map's clock to time (seconds) and decays the map by the time passed; the first time only "
           "sets the clock, an earlier time changes nothing.")
      .def_property_readonly("clock", released(&OccupancyMap::clock),
                             "The clock's time in seconds, or None before the first advance_clock or stamp.")
      .def("prune", &OccupancyMap::prune, py::call_guard<py::gil_scoped_release>(), "Merge equal children now.")
      .def("clear", &OccupancyMap::clear, py::call_guard<py::gil_scoped_release>(), "Make everything unknown again.")
      .def("node_counts", &OccupancyMap::node_counts, py::call_guard<py::gil_scoped_release>(),
           "How many nodes of each kind the map holds (a NodeCounts).")
      .def("memory_bytes", &OccupancyMap::memory_bytes, py::call_guard<py::gil_scoped_release>(),
           "Bytes allocated for the map.")
      .def("statistics", &compute_statistics, py::call_guard<py::gil_scoped_release>(),
           "Voxel counts, volumes and bounds of the known space (a MapStatistics; one pass over the leaves).")
      .def("copy", [](const OccupancyMap& m) { return OccupancyMap(m); }, py::call_guard<py::gil_scoped_release>(),
           "A deep copy.")
      .def("__copy__", [](const OccupancyMap& m) { return OccupancyMap(m); }, py::call_guard<py::gil_scoped_release>())
      .def(
          "__deepcopy__", [](const OccupancyMap& m, py::handle) { return OccupancyMap(m); }, py::arg("memo"),
          py::call_guard<py::gil_scoped_release>())
      .def("__repr__", describe);
}

void bind_insertion_and_updates(MapClass& map) {
  map.def("insert", &insert, py::arg("points"), py::arg("origin"), py::arg("colors") = py::none(), py::kw_only(),
          py::arg("integrator") = "discrete", py::arg("max_range") = -1.0, py::arg("clear_depth") = -1,
          py::arg("fine_steps") = 2, py::arg("threads") = 0, py::arg("stamp") = py::none(),
          "Integrates one scan: points (N, 3) seen from origin (3,), optionally colors (N, 3) uint8. Returns "
          "InsertStats. integrator: 'discrete' (OctoMap's discretize=true), 'simple' (discretize=false) or "
          "'fast' (free space cleared at clear_depth, -1: 16 cm nodes; fine_steps coarse nodes before each end "
          "point traced voxel by voxel). max_range <= 0: unlimited. threads: 0 for all cores. stamp: seconds on "
          "the map's clock, advanced to it first (decay, see set_decay); None: the clock is left alone.");

  map.def(
         "update_hit",
         [](OccupancyMap& m, py::handle points) {
           const PointArray p(points, "points");
           for_each_point(p, [&](std::size_t i) { m.update_hit(p[i]); });
         },
         py::arg("points"), "One hit for the voxel of each point (..., 3).")
      .def(
          "update_miss",
          [](OccupancyMap& m, py::handle points) {
            const PointArray p(points, "points");
            for_each_point(p, [&](std::size_t i) { m.update_miss(p[i]); });
          },
          py::arg("points"), "One miss for the voxel of each point (..., 3).")
      .def(
          "update_log_odds",
          [](OccupancyMap& m, py::handle points, py::handle deltas) {
            const PointArray p(points, "points");
            const ValueArray d(deltas, "deltas");
            batch_count({{"points", std::optional(p.size())}, {d.name(), d.count()}});
            for_each_point(p, [&](std::size_t i) { m.update_log_odds(p[i], static_cast<float>(d[i])); });
          },
          py::arg("points"), py::arg("deltas"), "Adds deltas (N,) or one number to the voxels' log-odds, then clamps.")
      .def(
          "set_log_odds",
          [](OccupancyMap& m, py::handle points, py::handle values) {
            const PointArray p(points, "points");
            const ValueArray v(values, "values");
            batch_count({{"points", std::optional(p.size())}, {v.name(), v.count()}});
            for_each_point(p, [&](std::size_t i) { m.set_log_odds(p[i], static_cast<float>(v[i])); });
          },
          py::arg("points"), py::arg("values"), "Sets the voxels' log-odds (clamped) to values (N,) or one number.")
      .def(
          "add_color",
          [](OccupancyMap& m, py::handle points, py::handle colors) {
            // The library says std::logic_error here (RuntimeError); insert() says invalid_argument.
            if (!m.has_color()) throw py::value_error("the map was made without color (MapConfig::color)");
            const PointArray p(points, "points");
            const ColorArray c(colors, "colors");
            batch_count({{"points", std::optional(p.size())}, {"colors", std::optional(c.span().size())}});
            for_each_point(p, [&](std::size_t i) { m.add_color(p[i], c.span()[i]); });
          },
          py::arg("points"), py::arg("colors"),
          "One more color sample (N, 3) uint8 for the voxel of each point (running average).");
}

void bind_point_lookups(MapClass& map) {
  map.def(
         "states",
         [](const OccupancyMap& m, py::handle points, int depth) {
           return per_point<std::uint8_t>(m, points, depth, [](const OccupancyMap& mm, Vec3d p, int d, auto& out) {
             out = static_cast<std::uint8_t>(mm.state(p, d));
           });
         },
         py::arg("points"), py::arg("depth") = 0,
         "State of the depth-`depth` node holding each point (..., 3): a uint8 array (...) of umbra.UNKNOWN, "
         "FREE, OCCUPIED.")
      .def(
          "log_odds",
          [](const OccupancyMap& m, py::handle points, int depth) {
            return per_point<float>(m, points, depth, [](const OccupancyMap& mm, Vec3d p, int d, auto& out) {
              out = mm.log_odds(p, d);
            });
          },
          py::arg("points"), py::arg("depth") = 0,
          "Log-odds of the node holding each point (the maximum over its voxels): a float32 array (...).")
      .def(
          "occupancy",
          [](const OccupancyMap& m, py::handle points, int depth) {
            return per_point<double>(m, points, depth, [](const OccupancyMap& mm, Vec3d p, int d, auto& out) {
              out = mm.occupancy(p, d);
            });
          },
          py::arg("points"), py::arg("depth") = 0,
          "Occupancy probability of the node holding each point: a float64 array (...).")
      .def(
          "nodes",
          [](const OccupancyMap& m, py::handle points, int depth) {
            return per_point<NodeRecord>(m, points, depth, [](const OccupancyMap& mm, Vec3d p, int d, auto& out) {
              write_record(mm.node(p, d), out);
            });
          },
          py::arg("points"), py::arg("depth") = 0,
          "The depth-`depth` node holding each point (or the childless node above it): a structured array "
          "(...) of umbra.NODE_DTYPE.")
      .def(
          "leaves",
          [](const OccupancyMap& m) {
            std::vector<Node> leaves;
            {
              py::gil_scoped_release released;
              m.for_each_leaf([&](const Node& n) { leaves.push_back(n); });
            }
            return node_array(leaves);
          },
          "Every childless node in Morton order: a structured array of umbra.NODE_DTYPE.");
}

}  // namespace

InsertOptions insert_options(const std::string& integrator, double max_range, int clear_depth, int fine_steps,
                             int threads) {
  if (threads < 0) throw std::invalid_argument("threads must be >= 0 (0: all cores), got " + std::to_string(threads));
  InsertOptions options;
  options.integrator = parse_integrator_kind(integrator);
  options.max_range = max_range;
  options.clear_depth = clear_depth;
  options.fine_steps = fine_steps;
  options.threads = static_cast<unsigned>(threads);
  return options;
}

MapClass bind_map(py::module_& m) {
  MapClass map(m, "OccupancyMap",
               "A probabilistic occupancy octree with unknown, free and occupied space explicit. Every method "
               "may be called from any thread; queries run while another thread inserts.");
  map.def(py::init([](double resolution, int depth_levels, bool color, const std::optional<SensorModel>& sensor,
                      const std::optional<Thresholds>& thresholds) {
            MapConfig config;
            config.resolution = resolution;
            config.depth_levels = depth_levels;
            config.color = color;
            if (sensor) config.sensor = *sensor;
            if (thresholds) config.thresholds = *thresholds;
            return OccupancyMap(config);
          }),
          py::arg("resolution"), py::arg("depth_levels") = 16, py::arg("color") = false,
          py::arg("sensor_model") = py::none(), py::arg("thresholds") = py::none(),
          "An empty map, everything unknown: finest voxels of resolution metres, depth_levels levels (1..21; the "
          "map spans [-resolution * 2**(depth_levels - 1), resolution * 2**(depth_levels - 1)) on every axis), a "
          "color per voxel when color, and a SensorModel and Thresholds (None: OctoMap's defaults).");
  bind_settings(map);
  bind_insertion_and_updates(map);
  bind_point_lookups(map);
  return map;
}

}  // namespace umbra::python
