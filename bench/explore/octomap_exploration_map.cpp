#include "octomap_exploration_map.hpp"

#include <algorithm>
#include <cmath>
#include <mutex>

namespace umbra::explore {

namespace {

octomap::point3d point(Vec3d p) { return {float(p.x), float(p.y), float(p.z)}; }

/// Squared distance from `p` to the cube of edge `size` centred at `centre`.
double squared_distance_to_cube(Vec3d p, Vec3d centre, double size) {
  double sum = 0.0;
  for (std::size_t a = 0; a < 3; ++a) {
    const double outside = std::max(0.0, std::abs(p[a] - centre[a]) - 0.5 * size);
    sum += outside * outside;
  }
  return sum;
}

Vec3d centre_of(const octomap::OcTree& tree, const octomap::OcTreeKey& key) {
  const octomap::point3d c = tree.keyToCoord(key);
  return {double(c.x()), double(c.y()), double(c.z())};
}

}  // namespace

OctomapExplorationMap::OctomapExplorationMap(double resolution) : tree_(resolution) {}

bool OctomapExplorationMap::blocks(const octomap::OcTreeKey& key) const {
  const octomap::OcTreeNode* node = tree_.search(key);
  return node == nullptr || tree_.isNodeOccupied(node);
}

bool OctomapExplorationMap::line_free(const octomap::point3d& from, const octomap::point3d& to) const {
  if (!tree_.computeRayKeys(from, to, ray_)) return false;
  for (const octomap::OcTreeKey& key : ray_) {
    if (blocks(key)) return false;
  }
  return !blocks(tree_.coordToKey(to));
}

void OctomapExplorationMap::assume_free(const Sphere& ball) {
  const std::lock_guard lock(mutex_);
  const double r = ball.radius;
  const octomap::OcTreeKey low = tree_.coordToKey(point(ball.center - Vec3d{r, r, r}));
  const octomap::OcTreeKey high = tree_.coordToKey(point(ball.center + Vec3d{r, r, r}));
  octomap::OcTreeKey key;
  for (key[2] = low[2]; key[2] <= high[2]; ++key[2]) {
    for (key[1] = low[1]; key[1] <= high[1]; ++key[1]) {
      for (key[0] = low[0]; key[0] <= high[0]; ++key[0]) {
        if (squared_distance_to_cube(ball.center, centre_of(tree_, key), tree_.getResolution()) <= r * r) {
          tree_.setNodeValue(key, tree_.getClampingThresMinLog());
        }
      }
    }
  }
}

void OctomapExplorationMap::insert(Vec3f origin, std::span<const Vec3f> points, double max_range) {
  const std::lock_guard lock(mutex_);
  cloud_.clear();
  cloud_.reserve(points.size());
  for (const Vec3f& p : points) cloud_.push_back(p.x, p.y, p.z);
  tree_.insertPointCloud(cloud_, octomap::point3d(origin.x, origin.y, origin.z), max_range, false, true);
}

bool OctomapExplorationMap::is_free(const Sphere& ball) const {
  const std::lock_guard lock(mutex_);
  const double r = ball.radius;
  octomap::OcTreeKey low;
  octomap::OcTreeKey high;
  if (!tree_.coordToKeyChecked(point(ball.center - Vec3d{r, r, r}), low) ||
      !tree_.coordToKeyChecked(point(ball.center + Vec3d{r, r, r}), high)) {
    return false;
  }
  octomap::OcTreeKey key;
  for (key[2] = low[2]; key[2] <= high[2]; ++key[2]) {
    for (key[1] = low[1]; key[1] <= high[1]; ++key[1]) {
      for (key[0] = low[0]; key[0] <= high[0]; ++key[0]) {
        if (squared_distance_to_cube(ball.center, centre_of(tree_, key), tree_.getResolution()) > r * r) continue;
        if (blocks(key)) return false;
      }
    }
  }
  return true;
}

bool OctomapExplorationMap::is_free(const Capsule& path) const {
  const std::lock_guard lock(mutex_);
  const double step = tree_.getResolution();
  const int n = int(std::floor(path.radius / step));
  for (int k = -n; k <= n; ++k) {
    for (int j = -n; j <= n; ++j) {
      for (int i = -n; i <= n; ++i) {
        const Vec3d offset{i * step, j * step, k * step};
        if (offset.dot(offset) > path.radius * path.radius) continue;
        if (!line_free(point(path.a + offset), point(path.b + offset))) return false;
      }
    }
  }
  return true;
}

double OctomapExplorationMap::gain(const Frustum& view) const {
  const std::lock_guard lock(mutex_);
  // The frustum lies in the pyramid from the origin to the four corners at
  // max_range along the forward axis, and in the cube of the range sphere.
  const Vec3d f = view.forward();
  const Vec3d l = view.left() * std::tan(0.5 * view.hfov);
  const Vec3d u = view.up() * std::tan(0.5 * view.vfov);
  const double range = view.max_range;
  Vec3d low = view.origin;
  Vec3d high = view.origin;
  for (const double a : {-1.0, 1.0}) {
    for (const double b : {-1.0, 1.0}) {
      const Vec3d corner = view.origin + (f + l * a + u * b) * range;
      for (std::size_t axis = 0; axis < 3; ++axis) {
        low[axis] = std::min(low[axis], corner[axis]);
        high[axis] = std::max(high[axis], corner[axis]);
      }
    }
  }
  for (std::size_t axis = 0; axis < 3; ++axis) {
    low[axis] = std::max(low[axis], view.origin[axis] - range);
    high[axis] = std::min(high[axis], view.origin[axis] + range);
  }
  octomap::OcTreeKey first;
  octomap::OcTreeKey last;
  if (!tree_.coordToKeyChecked(point(low), first) || !tree_.coordToKeyChecked(point(high), last)) return 0.0;
  const octomap::point3d origin = point(view.origin);
  std::size_t unknown_visible = 0;
  octomap::OcTreeKey key;
  for (key[2] = first[2]; key[2] <= last[2]; ++key[2]) {
    for (key[1] = first[1]; key[1] <= last[1]; ++key[1]) {
      for (key[0] = first[0]; key[0] <= last[0]; ++key[0]) {
        const octomap::point3d centre = tree_.keyToCoord(key);
        if (!view.contains({double(centre.x()), double(centre.y()), double(centre.z())})) continue;
        if (tree_.search(key) != nullptr) continue;  // known
        if (!tree_.computeRayKeys(origin, centre, ray_)) continue;
        bool hidden = false;
        for (const octomap::OcTreeKey& on_ray : ray_) {
          const octomap::OcTreeNode* node = tree_.search(on_ray);
          if (node != nullptr && tree_.isNodeOccupied(node)) {
            hidden = true;
            break;
          }
        }
        if (!hidden) ++unknown_visible;
      }
    }
  }
  const double res = tree_.getResolution();
  return double(unknown_visible) * res * res * res;
}

void OctomapExplorationMap::for_each_free_node(FunctionRef<void(Vec3d min, Vec3d max)> visit) const {
  const std::lock_guard lock(mutex_);
  for (auto it = tree_.begin_leafs(), end = tree_.end_leafs(); it != end; ++it) {
    if (tree_.isNodeOccupied(*it)) continue;
    const Vec3d c{double(it.getX()), double(it.getY()), double(it.getZ())};
    const double half = 0.5 * it.getSize();
    visit(c - Vec3d{half, half, half}, c + Vec3d{half, half, half});
  }
}

std::size_t OctomapExplorationMap::memory_bytes() const {
  const std::lock_guard lock(mutex_);
  return tree_.memoryUsage();
}

}  // namespace umbra::explore
