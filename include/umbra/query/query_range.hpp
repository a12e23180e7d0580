// Ranges over the nodes a query matches (OccupancyMap::query and
// OccupancyMap::query_nearest).
//
//   for (const umbra::Node& node : map.query(umbra::pred::leaf() && umbra::pred::occupied())) ...
//   for (const umbra::NearNode& near : map.query_nearest(point, umbra::pred::leaf() && umbra::pred::occupied())) ...
//
// A range is lazy: it finds the next match when the loop asks for it, so
// stopping early costs nothing more. query() yields in depth-first Morton
// order, parents before children; query_nearest() by distance from the
// point to the node's cube (0 inside), nearest first.
//
// A range holds the map for reading from its creation to its destruction
// (see the concurrency note in occupancy_map.hpp): inserting waits for it,
// and the thread that holds it must not change the map meanwhile (that
// throws std::logic_error). It cannot be copied or moved; keep it in the
// scope of one loop.
#pragma once

#include <cstddef>
#include <iterator>
#include <limits>
#include <memory>

#include "umbra/core/node.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/query/predicate.hpp"

namespace umbra {

class OccupancyMap;

/// A node and its distance from the point of a nearest-first query.
struct NearNode {
  Node node;
  double distance = 0.0;  ///< metres from the point to the node's cube (0 inside)
};

namespace detail {
class QueryWalk;
class NearestWalk;
// The walks live in the library; a range reaches them through these.
bool advance(QueryWalk& walk);  ///< to the next match; false when there is none
bool advance(NearestWalk& walk);
const Node& current(const QueryWalk& walk);
const NearNode& current(const NearestWalk& walk);
struct WalkDeleter {
  void operator()(QueryWalk* walk) const;
  void operator()(NearestWalk* walk) const;
};
}  // namespace detail

/// An input range over the matches of one walk.
template <typename Walk, typename Value>
class WalkRange {
 public:
  class iterator {
   public:
    using value_type = Value;
    using difference_type = std::ptrdiff_t;
    using iterator_concept = std::input_iterator_tag;
    iterator() = default;
    explicit iterator(Walk* walk) : walk_(walk) {}
    const Value& operator*() const { return detail::current(*walk_); }
    const Value* operator->() const { return &detail::current(*walk_); }
    iterator& operator++() {
      if (!detail::advance(*walk_)) walk_ = nullptr;
      return *this;
    }
    void operator++(int) { ++*this; }
    friend bool operator==(const iterator& it, std::default_sentinel_t) { return it.walk_ == nullptr; }

   private:
    Walk* walk_ = nullptr;
  };

  explicit WalkRange(Walk* walk) : walk_(walk) {}
  WalkRange(const WalkRange&) = delete;
  WalkRange& operator=(const WalkRange&) = delete;
  WalkRange(WalkRange&&) = delete;
  WalkRange& operator=(WalkRange&&) = delete;

  /// The first match. A range is walked once: call begin() once.
  iterator begin() { return detail::advance(*walk_) ? iterator(walk_.get()) : iterator(); }
  std::default_sentinel_t end() const { return {}; }

 private:
  std::unique_ptr<Walk, detail::WalkDeleter> walk_;
};

using QueryRange = WalkRange<detail::QueryWalk, Node>;
using NearestRange = WalkRange<detail::NearestWalk, NearNode>;

}  // namespace umbra
