// OccupancyMap's information-gain members: validation, the read lock per
// pose, and the thread pool of a batch. The counting is GainCounter's.
#include <algorithm>
#include <stdexcept>
#include <string>

#include "core/thread_pool.hpp"
#include "map/map_access.hpp"
#include "query/gain_counter.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra {
namespace {

void validate(const GainOptions& options, int depth_levels) {
  if (options.fast_depth < 0 || options.fast_depth > depth_levels) {
    throw std::invalid_argument("information gain: fast_depth must lie in [0, " + std::to_string(depth_levels) +
                                "], got " + std::to_string(options.fast_depth));
  }
}

}  // namespace

GainResult OccupancyMap::information_gain(const Frustum& frustum, const GainOptions& options) const {
  frustum.validate();
  validate(options, depth_levels());
  detail::GainCounter counter(grid());
  return detail::MapAccess::read(*this, [&](const OccupancyTree& tree) { return counter.count(tree, frustum, options); });
}

std::vector<GainResult> OccupancyMap::information_gain(std::span<const Frustum> frustums,
                                                       const GainOptions& options) const {
  validate(options, depth_levels());
  for (const Frustum& frustum : frustums) frustum.validate();
  std::vector<GainResult> results(frustums.size());
  const unsigned threads = std::min<std::size_t>(options.threads == 0 ? ThreadPool::hardware_threads() : options.threads,
                                                 std::max<std::size_t>(frustums.size(), 1));
  // One counter (image and buffers) per thread; the map is held per pose.
  std::vector<detail::GainCounter> counters;
  counters.reserve(threads);
  for (unsigned t = 0; t < threads; ++t) counters.emplace_back(grid());
  auto answer = [&](std::size_t i, unsigned worker) {
    results[i] = detail::MapAccess::read(
        *this, [&](const OccupancyTree& tree) { return counters[worker].count(tree, frustums[i], options); });
  };
  if (threads <= 1) {
    for (std::size_t i = 0; i < frustums.size(); ++i) answer(i, 0);
  } else {
    ThreadPool pool(threads);
    pool.run(frustums.size(), answer);
  }
  return results;
}

}  // namespace umbra
