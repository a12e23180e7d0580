// OccupancyMap's query members: thin doors to the walks in src/query.
#include "query/query_walk.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra {

QueryRange OccupancyMap::query(const Predicate& predicate, int depth) const {
  return QueryRange(new detail::QueryWalk(*this, predicate, depth));
}

NearestRange OccupancyMap::query_nearest(Vec3d point, const Predicate& predicate, int depth,
                                         double max_distance) const {
  return NearestRange(new detail::NearestWalk(*this, point, predicate, depth, max_distance));
}

std::size_t OccupancyMap::count(const Predicate& predicate, int depth) const {
  return detail::QueryWalk(*this, predicate, depth).count_rest();
}

}  // namespace umbra
