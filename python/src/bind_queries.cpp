// The query layer on umbra.OccupancyMap: iteration with predicates
// (query, query_nearest, count), collision checks of one shape or of many
// (the library's batch is_free over spans, answers straight into a numpy
// bool array), and ray casts of many rays.
//
// Every call converts its arguments first, then releases the GIL for the
// library's work: building the shapes of a batch (one pass, 32-80 bytes per
// shape) and the checks themselves. Matching nodes are collected in a
// std::vector and turned into a structured array afterwards.
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include <pybind11/stl.h>

#include "bindings.hpp"
#include "numpy_arrays.hpp"
#include "umbra/query/collision.hpp"
#include "umbra/query/shapes.hpp"

namespace umbra::python {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Runs the batch check over shapes made by make(i), answers into a bool array.
template <typename Shape, typename Make>
py::array_t<bool> check_batch(const OccupancyMap& map, std::size_t n, const Make& make, bool unknown_is_free,
                              int depth) {
  BoolArray answers(n);
  const CollisionOptions options{unknown_is_free, depth};
  {
    py::gil_scoped_release released;
    std::vector<Shape> shapes;
    shapes.reserve(n);
    for (std::size_t i = 0; i < n; ++i) shapes.push_back(make(i));
    map.is_free(std::span<const Shape>(shapes), std::span<std::uint8_t>(answers.bytes, n), options);
  }
  return answers.array;
}

/// The rotation matrices of a batch of oriented boxes: (N, 3, 3) or one (3, 3).
class RotationArray {
 public:
  explicit RotationArray(py::handle object) {
    array_ = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(object);
    if (!array_) {
      PyErr_Clear();
      throw py::type_error("rotations must be an array of numbers");
    }
    const bool many = array_.ndim() == 3 && array_.shape(1) == 3 && array_.shape(2) == 3;
    broadcast_ = array_.ndim() == 2 && array_.shape(0) == 3 && array_.shape(1) == 3;
    if (!many && !broadcast_) {
      throw py::value_error("rotations must be an array of shape (N, 3, 3) or (3, 3), got shape " +
                            shape_text(array_));
    }
    count_ = many ? static_cast<std::size_t>(array_.shape(0)) : 1;
    data_ = array_.data();
  }
  [[nodiscard]] std::optional<std::size_t> count() const {
    return broadcast_ ? std::nullopt : std::optional(count_);
  }
  /// The box axes: the columns of matrix i.
  [[nodiscard]] std::array<Vec3d, 3> axes(std::size_t i) const {
    const double* r = data_ + (broadcast_ ? 0 : 9 * i);
    return {Vec3d{r[0], r[3], r[6]}, Vec3d{r[1], r[4], r[7]}, Vec3d{r[2], r[5], r[8]}};
  }

 private:
  py::array_t<double, py::array::c_style | py::array::forcecast> array_;
  const double* data_ = nullptr;
  std::size_t count_ = 0;
  bool broadcast_ = false;
};

/// Ray casts of many rays, as numpy arrays.
struct RayHits {
  py::array_t<bool> hit;
  py::array_t<double> distance;
  py::array_t<double> point;
  py::array_t<double> center;
  py::array_t<double> size;
};

void bind_iteration(MapClass& map) {
  map.def(
         "query",
         [](const OccupancyMap& m, const py::object& predicate, int depth) {
           const Predicate p = predicate_of(predicate);
           std::vector<Node> nodes;
           {
             py::gil_scoped_release released;
             for (const Node& node : m.query(p, depth)) nodes.push_back(node);
           }
           return node_array(nodes);
         },
         py::arg("predicate") = py::none(), py::arg("depth") = 0,
         "The nodes the predicate holds for (None: all), visiting the tree down to `depth`, parents before "
         "children in Morton order: a structured array of umbra.NODE_DTYPE.")
      .def(
          "query_nearest",
          [](const OccupancyMap& m, py::handle point, const py::object& predicate, int depth, double max_distance,
             std::optional<std::size_t> k) {
            const Vec3d at = vec3_of(point, "point");
            const Predicate p = predicate_of(predicate);
            std::vector<Node> nodes;
            std::vector<double> distances;
            {
              py::gil_scoped_release released;
              for (const NearNode& near : m.query_nearest(at, p, depth, max_distance)) {
                if (k && nodes.size() == *k) break;
                nodes.push_back(near.node);
                distances.push_back(near.distance);
              }
            }
            py::array_t<double> distance_array(static_cast<py::ssize_t>(distances.size()), distances.data());
            return py::make_tuple(node_array(nodes), distance_array);
          },
          py::arg("point"), py::arg("predicate") = py::none(), py::arg("depth") = 0,
          py::arg("max_distance") = std::numeric_limits<double>::infinity(), py::arg("k") = py::none(),
          "The matching nodes nearest to point first, up to max_distance metres and at most k of them: "
          "(nodes, distances), a structured array of umbra.NODE_DTYPE and the float64 distances to the nodes' "
          "cubes (0 inside).")
      .def(
          "count",
          [](const OccupancyMap& m, const py::object& predicate, int depth) {
            const Predicate p = predicate_of(predicate);
            py::gil_scoped_release released;
            return m.count(p, depth);
          },
          py::arg("predicate") = py::none(), py::arg("depth") = 0, "How many nodes query(predicate, depth) yields.");
}

/// One overload of is_free; the first carries the docstring (pybind11
/// would repeat the text of every overload).
template <typename Shape>
void def_is_free(MapClass& map, const char* doc = "") {
  map.def(
      "is_free",
      [](const OccupancyMap& m, const Shape& shape, bool unknown_is_free, int depth) {
        py::gil_scoped_release released;
        return m.is_free(shape, CollisionOptions{unknown_is_free, depth});
      },
      py::arg("shape"), py::kw_only(), py::arg("unknown_is_free") = false, py::arg("depth") = 0, doc);
}

void bind_collisions(MapClass& map) {
  def_is_free<Aabb>(map,
                    "Whether no voxel of the shape (an Aabb, Sphere, OrientedBox, Capsule or Segment) blocks: "
                    "occupied, or unknown unless unknown_is_free; checked at `depth` (coarser is conservative). "
                    "Returns a CollisionResult (true when free) with one blocking node.");
  def_is_free<Sphere>(map);
  def_is_free<OrientedBox>(map);
  def_is_free<Capsule>(map);
  def_is_free<Segment>(map);

  map.def(
         "spheres_free",
         [](const OccupancyMap& m, py::handle centers, py::handle radii, bool unknown_is_free, int depth) {
           const RowArray c(centers, "centers");
           const ValueArray r(radii, "radii");
           const std::size_t n = batch_count({{c.name(), c.count()}, {r.name(), r.count()}});
           return check_batch<Sphere>(m, n, [&](std::size_t i) { return Sphere{c[i], r[i]}; }, unknown_is_free,
                                      depth);
         },
         py::arg("centers"), py::arg("radii"), py::kw_only(), py::arg("unknown_is_free") = false,
         py::arg("depth") = 0,
         "Whether each sphere is free: centers (N, 3), radii (N,) or one radius. A bool array (N,).")
      .def(
          "boxes_free",
          [](const OccupancyMap& m, py::handle mins, py::handle maxs, bool unknown_is_free, int depth) {
            const RowArray lo(mins, "mins");
            const RowArray hi(maxs, "maxs");
            const std::size_t n = batch_count({{lo.name(), lo.count()}, {hi.name(), hi.count()}});
            return check_batch<Aabb>(m, n, [&](std::size_t i) { return Aabb{lo[i], hi[i]}; }, unknown_is_free,
                                     depth);
          },
          py::arg("mins"), py::arg("maxs"), py::kw_only(), py::arg("unknown_is_free") = false, py::arg("depth") = 0,
          "Whether each axis-aligned box [mins[i], maxs[i]] is free: a bool array (N,).")
      .def(
          "oriented_boxes_free",
          [](const OccupancyMap& m, py::handle centers, py::handle half_extents, py::handle rotations,
             bool unknown_is_free, int depth) {
            const RowArray c(centers, "centers");
            const RowArray h(half_extents, "half_extents");
            const RotationArray r(rotations);
            const std::size_t n =
                batch_count({{c.name(), c.count()}, {h.name(), h.count()}, {"rotations", r.count()}});
            return check_batch<OrientedBox>(
                m, n, [&](std::size_t i) { return OrientedBox{c[i], h[i], r.axes(i)}; }, unknown_is_free, depth);
          },
          py::arg("centers"), py::arg("half_extents"), py::arg("rotations"), py::kw_only(),
          py::arg("unknown_is_free") = false, py::arg("depth") = 0,
          "Whether each oriented box is free: centers (N, 3), half_extents (N, 3), rotations (N, 3, 3) whose "
          "columns are the boxes' axes (each may be one row for all). A bool array (N,).")
      .def(
          "capsules_free",
          [](const OccupancyMap& m, py::handle starts, py::handle ends, py::handle radii, bool unknown_is_free,
             int depth) {
            const RowArray a(starts, "starts");
            const RowArray b(ends, "ends");
            const ValueArray r(radii, "radii");
            const std::size_t n =
                batch_count({{a.name(), a.count()}, {b.name(), b.count()}, {r.name(), r.count()}});
            return check_batch<Capsule>(m, n, [&](std::size_t i) { return Capsule{a[i], b[i], r[i]}; },
                                        unknown_is_free, depth);
          },
          py::arg("starts"), py::arg("ends"), py::arg("radii"), py::kw_only(), py::arg("unknown_is_free") = false,
          py::arg("depth") = 0,
          "Whether each capsule (the points within radii[i] of the segment starts[i] -> ends[i]) is free: a "
          "bool array (N,).")
      .def(
          "segments_free",
          [](const OccupancyMap& m, py::handle starts, py::handle ends, bool unknown_is_free, int depth) {
            const RowArray a(starts, "starts");
            const RowArray b(ends, "ends");
            const std::size_t n = batch_count({{a.name(), a.count()}, {b.name(), b.count()}});
            return check_batch<Segment>(m, n, [&](std::size_t i) { return Segment{a[i], b[i]}; }, unknown_is_free,
                                        depth);
          },
          py::arg("starts"), py::arg("ends"), py::kw_only(), py::arg("unknown_is_free") = false,
          py::arg("depth") = 0,
          "Whether each segment's ray walk (OctoMap's computeRayKeys plus the end voxel) is free: a bool "
          "array (N,).");
}

void bind_ray_casts(MapClass& map) {
  map.def(
         "cast_ray",
         [](const OccupancyMap& m, py::handle origin, py::handle direction, double max_range, bool stop_at_unknown,
            int depth) {
           const Vec3d o = vec3_of(origin, "origin");
           const Vec3d d = vec3_of(direction, "direction");
           py::gil_scoped_release released;
           return m.cast_ray(o, d, RayCastOptions{max_range, stop_at_unknown, depth});
         },
         py::arg("origin"), py::arg("direction"), py::kw_only(), py::arg("max_range") = -1.0,
         py::arg("stop_at_unknown") = false, py::arg("depth") = 0,
         "The first occupied (or, with stop_at_unknown, unknown) node along the ray within max_range (<= 0: to "
         "the map's edge): a RayHit.")
      .def(
          "cast_rays",
          [](const OccupancyMap& m, py::handle origins, py::handle directions, py::handle max_range,
             bool stop_at_unknown, int depth) {
            const RowArray o(origins, "origins");
            const RowArray d(directions, "directions");
            const ValueArray range(max_range, "max_range");
            const std::size_t n =
                batch_count({{o.name(), o.count()}, {d.name(), d.count()}, {range.name(), range.count()}});
            const auto rows = static_cast<py::ssize_t>(n);
            RayHits hits{py::array_t<bool>(rows), py::array_t<double>(rows), py::array_t<double>({rows, py::ssize_t{3}}),
                         py::array_t<double>({rows, py::ssize_t{3}}), py::array_t<double>(rows)};
            auto* hit = reinterpret_cast<std::uint8_t*>(hits.hit.mutable_data());
            double* distance = hits.distance.mutable_data();
            double* point = hits.point.mutable_data();
            double* center = hits.center.mutable_data();
            double* size = hits.size.mutable_data();
            py::gil_scoped_release released;
            std::size_t i = 0;
            try {
              for (; i < n; ++i) {
                const RayHit h = m.cast_ray(o[i], d[i], RayCastOptions{range[i], stop_at_unknown, depth});
                hit[i] = h.hit ? 1 : 0;
                distance[i] = h.hit ? h.distance : kNaN;
                size[i] = h.hit ? h.node.size : kNaN;
                for (std::size_t axis = 0; axis < 3; ++axis) {
                  point[3 * i + axis] = h.hit ? h.point[axis] : kNaN;
                  center[3 * i + axis] = h.hit ? h.node.center[axis] : kNaN;
                }
              }
            } catch (const std::out_of_range& e) {
              throw std::out_of_range("ray " + std::to_string(i) + ": " + e.what());
            } catch (const std::invalid_argument& e) {
              throw std::invalid_argument("ray " + std::to_string(i) + ": " + e.what());
            }
            return hits;
          },
          py::arg("origins"), py::arg("directions"), py::kw_only(), py::arg("max_range") = -1.0,
          py::arg("stop_at_unknown") = false, py::arg("depth") = 0,
          "cast_ray for many rays: origins and directions (N, 3) or one row each, max_range (N,) or one number. "
          "Returns RayHits: hit (N,) bool, and distance, point (N, 3), center (N, 3) and size of the node hit "
          "(NaN where nothing was hit).")
      .def(
          "cast_rays_octomap",
          [](const OccupancyMap& m, py::handle origins, py::handle directions, bool ignore_unknown, double max_range) {
            // OctoMap reads a NaN range as unlimited (NaN > 0 is false); cast_ray refuses it, and so does this.
            if (std::isnan(max_range)) throw std::invalid_argument("ray cast: max_range is NaN");
            const RowArray o(origins, "origins");
            const RowArray d(directions, "directions");
            const std::size_t n = batch_count({{o.name(), o.count()}, {d.name(), d.count()}});
            const auto rows = static_cast<py::ssize_t>(n);
            BoolArray hit(n);
            py::array_t<float> ends({rows, py::ssize_t{3}});
            float* end = ends.mutable_data();
            {
              py::gil_scoped_release released;
              std::size_t i = 0;
              try {
                for (; i < n; ++i) {
                  Vec3f e;
                  hit.bytes[i] = m.cast_ray_octomap(Vec3f(o[i]), Vec3f(d[i]), e, ignore_unknown, max_range) ? 1 : 0;
                  end[3 * i] = e.x;
                  end[3 * i + 1] = e.y;
                  end[3 * i + 2] = e.z;
                }
              } catch (const std::out_of_range& e) {
                throw std::out_of_range("ray " + std::to_string(i) + ": " + e.what());
              } catch (const std::invalid_argument& e) {
                throw std::invalid_argument("ray " + std::to_string(i) + ": " + e.what());
              }
            }
            return py::make_tuple(hit.array, ends);
          },
          py::arg("origins"), py::arg("directions"), py::kw_only(), py::arg("ignore_unknown") = false,
          py::arg("max_range") = -1.0,
          "OctoMap's OcTree::castRay rule for rule, for many rays (float32, as OctoMap): (hit (N,) bool, end "
          "(N, 3) float32), end being the centre of the voxel hit or where the ray stopped.");
}

void bind_results(py::module_& m) {
  py::class_<CollisionResult>(m, "CollisionResult",
                              "The answer of is_free: free, and when not free one blocking node (for a segment "
                              "the first along it). True when free.")
      .def_readonly("free", &CollisionResult::free, "No voxel of the shape blocks.")
      .def_readonly("blocking", &CollisionResult::blocking, "A blocking Node, or None when free.")
      .def("__bool__", [](const CollisionResult& r) { return r.free; })
      .def("__repr__", [](const CollisionResult& r) {
        return r.free ? std::string("CollisionResult(free=True)")
                      : "CollisionResult(free=False, blocking=" + std::string(py::repr(py::cast(*r.blocking))) + ")";
      });

  py::class_<RayHit>(m, "RayHit", "The answer of cast_ray. True when something was hit.")
      .def_readonly("hit", &RayHit::hit, "An occupied (or, when asked, unknown) node was hit within range.")
      .def_property_readonly(
          "node", [](const RayHit& h) -> py::object { return h.hit ? py::cast(h.node) : py::none(); },
          "The Node hit, or None.")
      .def_readonly("distance", &RayHit::distance, "Metres from the origin to where the ray enters the node.")
      .def_property_readonly(
          "point", [](const RayHit& h) { return to_tuple(h.point); }, "origin + direction * distance.")
      .def("__bool__", [](const RayHit& h) { return h.hit; })
      .def("__repr__", [](const RayHit& h) {
        return h.hit ? "RayHit(hit=True, distance=" + std::string(py::repr(py::float_(h.distance))) +
                           ", node=" + std::string(py::repr(py::cast(h.node))) + ")"
                     : std::string("RayHit(hit=False)");
      });

  py::class_<RayHits>(m, "RayHits", "The answers of cast_rays, one row per ray.")
      .def_readonly("hit", &RayHits::hit, "(N,) bool: something was hit within range.")
      .def_readonly("distance", &RayHits::distance, "(N,) metres to where the ray enters the node hit, or NaN.")
      .def_readonly("point", &RayHits::point, "(N, 3) origin + direction * distance, or NaN.")
      .def_readonly("center", &RayHits::center, "(N, 3) centre of the node hit, or NaN.")
      .def_readonly("size", &RayHits::size, "(N,) edge of the node hit, or NaN.")
      .def("__len__", [](const RayHits& h) { return h.hit.size(); })
      .def("__repr__", [](const RayHits& h) {
        // A summary: the arrays are attributes and can be long.
        const auto hits = std::count(h.hit.data(), h.hit.data() + h.hit.size(), true);
        return "RayHits(rays=" + std::to_string(h.hit.size()) + ", hits=" + std::to_string(hits) + ")";
      });
}

}  // namespace

void bind_queries(py::module_& m, MapClass& map) {
  bind_results(m);
  bind_iteration(map);
  bind_collisions(map);
  bind_ray_casts(map);
}

}  // namespace umbra::python
