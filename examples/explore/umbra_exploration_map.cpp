#include "umbra_exploration_map.hpp"

#include <cmath>
#include <ctime>

namespace umbra::explore {

namespace {
double thread_cpu_seconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return double(now.tv_sec) + 1e-9 * double(now.tv_nsec);
}
}  // namespace

UmbraExplorationMap::UmbraExplorationMap(const UmbraMapOptions& options) : map_(options.resolution) {
  insert_options_.integrator = options.integrator;
  insert_options_.threads = 1;  // one mapping thread, as the OctoMap twin has
  gain_options_.method = options.gain;
  gain_options_.fast_depth = options.fast_gain_depth;
  if (options.clearance == ClearanceSource::distance_field) {
    clearance_ = std::make_unique<FieldClearance>(map_, options.field_max_distance);
  }
  if (options.window_half_extent > 0.0) {
    MovingWindow window;
    window.half_extent = options.window_half_extent;
    map_.set_moving_window(window);
  }
}

void UmbraExplorationMap::assume_free(const Sphere& ball) {
  const float free_log_odds = map_.sensor_model().clamp_min_log_odds();
  const double res = map_.resolution();
  const Key low = map_.key(ball.center - Vec3d{ball.radius, ball.radius, ball.radius});
  const Key high = map_.key(ball.center + Vec3d{ball.radius, ball.radius, ball.radius});
  for (std::uint32_t z = low.z; z <= high.z; ++z) {
    for (std::uint32_t y = low.y; y <= high.y; ++y) {
      for (std::uint32_t x = low.x; x <= high.x; ++x) {
        const Vec3d c = map_.grid().center(Key{x, y, z});
        // The voxel belongs to the ball when its cube is within the radius.
        double squared = 0.0;
        for (std::size_t a = 0; a < 3; ++a) {
          const double outside = std::max(0.0, std::abs(c[a] - ball.center[a]) - 0.5 * res);
          squared += outside * outside;
        }
        if (squared <= ball.radius * ball.radius) map_.set_log_odds(c, free_log_odds);
      }
    }
  }
  if (clearance_) clearance_->update();
}

void UmbraExplorationMap::insert(Vec3f origin, std::span<const Vec3f> points, double max_range) {
  InsertOptions options = insert_options_;
  options.max_range = max_range;
  exclusive_seconds_ += map_.insert_point_cloud(origin, points, options).exclusive_seconds;
  if (clearance_) {
    // Part of inserting a frame, so charged to the mapping thread's
    // simulated time; counted in CPU time, which a loaded machine changes less.
    const double start = thread_cpu_seconds();
    clearance_->update();
    field_update_seconds_ += thread_cpu_seconds() - start;
  }
}

bool UmbraExplorationMap::is_free(const Sphere& ball) const {
  return clearance_ ? clearance_->is_free(ball) : map_.is_free(ball).free;
}

bool UmbraExplorationMap::is_free(const Capsule& path) const {
  return clearance_ ? clearance_->is_free(path) : map_.is_free(path).free;
}

double UmbraExplorationMap::gain(const Frustum& view) const {
  return map_.information_gain(view, gain_options_).volume;
}

std::size_t UmbraExplorationMap::memory_bytes() const {
  return map_.memory_bytes() + (clearance_ ? clearance_->memory_bytes() : 0);
}

void UmbraExplorationMap::for_each_free_node(FunctionRef<void(Vec3d min, Vec3d max)> visit) const {
  for (const Node& node : map_.query(pred::leaf() && pred::free())) visit(node.min_corner(), node.max_corner());
}

}  // namespace umbra::explore
