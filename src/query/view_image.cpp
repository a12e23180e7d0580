#include "query/view_image.hpp"

#include <algorithm>
#include <cmath>

namespace umbra::detail {
namespace {

/// The largest float not above `value` (draws must never overstate a distance).
float round_down(double value) {
  float f = static_cast<float>(value);
  if (double(f) > value) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}

}  // namespace

void ViewImage::reset(const Setup& setup) {
  setup_ = setup;
  inverse_pixel_ = 1.0 / setup.pixel;
  width_ = std::max(1, static_cast<int>(std::ceil(2.0 * setup.half_width / setup.pixel)));
  height_ = std::max(1, static_cast<int>(std::ceil(2.0 * setup.half_height / setup.pixel)));
  level_sizes_.clear();
  int w = width_;
  int h = height_;
  for (;;) {
    level_sizes_.push_back({w, h});
    if (w == 1 && h == 1) break;
    w = (w + 1) / 2;
    h = (h + 1) / 2;
  }
  minima_.resize(level_sizes_.size());
  maxima_.resize(level_sizes_.size());
  if (setup.candidates) {
    minima_[0].resize(std::size_t(width_) * std::size_t(height_));  // finish() fills it from the lists
    // Left uninitialised: a pixel's list is read only up to its count. (A
    // single-pose query has a new image each time; zeroing these 200 KB at
    // 20 cm was 4% of its instructions.)
    const std::size_t slots = std::size_t(width_) * std::size_t(height_) * kCandidates;
    if (slots > candidate_capacity_) {
      candidates_ = std::make_unique_for_overwrite<Candidate[]>(slots);
      candidate_capacity_ = slots;
    }
    counts_.assign(std::size_t(width_) * std::size_t(height_), 0);
  } else {
    minima_[0].assign(std::size_t(width_) * std::size_t(height_), std::numeric_limits<float>::infinity());
  }
}

bool ViewImage::footprint(const Aabb& box, PixelRect& rect, bool& clipped) const {
  const Setup& s = setup_;
  const Vec3d d0 = box.min - s.apex;
  const Vec3d e = box.max - box.min;
  // The corners' coordinates from the first corner's and the edges' (the
  // rounding differs from a dot product per corner by ~1e-16 relative,
  // well inside the margin below; 24 products instead of 72).
  const double z0 = d0.dot(s.f);
  const double x0 = d0.dot(s.l);
  const double y0 = d0.dot(s.u);
  const Vec3d ez{e.x * s.f.x, e.y * s.f.y, e.z * s.f.z};
  const Vec3d ex{e.x * s.l.x, e.y * s.l.y, e.z * s.l.z};
  const Vec3d ey{e.x * s.u.x, e.y * s.u.y, e.z * s.u.z};
  std::array<double, 8> z;
  std::array<double, 8> x;
  std::array<double, 8> y;
  for (unsigned i = 0; i < 8; ++i) {
    z[i] = z0 + ((i & 1u) ? ez.x : 0.0) + ((i & 2u) ? ez.y : 0.0) + ((i & 4u) ? ez.z : 0.0);
    x[i] = x0 + ((i & 1u) ? ex.x : 0.0) + ((i & 2u) ? ex.y : 0.0) + ((i & 4u) ? ex.z : 0.0);
    y[i] = y0 + ((i & 1u) ? ey.x : 0.0) + ((i & 2u) ? ey.y : 0.0) + ((i & 4u) ? ey.z : 0.0);
  }
  double x_low = std::numeric_limits<double>::infinity();
  double x_high = -x_low;
  double y_low = x_low;
  double y_high = -x_low;
  auto take = [&](double px, double py) {
    x_low = std::min(x_low, px);
    x_high = std::max(x_high, px);
    y_low = std::min(y_low, py);
    y_high = std::max(y_high, py);
  };
  clipped = false;
  for (unsigned i = 0; i < 8; ++i) {
    if (z[i] >= s.near_plane) {
      const double inverse = 1.0 / z[i];  // one division per corner, not two
      take(x[i] * inverse, y[i] * inverse);
    } else {
      clipped = true;
    }
  }
  if (clipped) {
    // The box cut by the near plane: its corners in front (taken above) and
    // the points where its edges cross the plane.
    for (unsigned bit = 1; bit < 8; bit <<= 1) {
      for (unsigned i = 0; i < 8; ++i) {
        if (i & bit) continue;
        const unsigned j = i | bit;
        if ((z[i] >= s.near_plane) == (z[j] >= s.near_plane)) continue;
        const double t = (s.near_plane - z[i]) / (z[j] - z[i]);
        take((x[i] + t * (x[j] - x[i])) / s.near_plane, (y[i] + t * (y[j] - y[i])) / s.near_plane);
      }
    }
    if (!(x_low <= x_high)) return false;  // wholly behind the plane
  }
  // A relative margin for the rounding of the projections.
  x_low -= 1e-9 * (1.0 + std::fabs(x_low));
  x_high += 1e-9 * (1.0 + std::fabs(x_high));
  y_low -= 1e-9 * (1.0 + std::fabs(y_low));
  y_high += 1e-9 * (1.0 + std::fabs(y_high));
  const double left = (x_low + s.half_width) * inverse_pixel_;
  const double right = (x_high + s.half_width) * inverse_pixel_;
  const double bottom = (y_low + s.half_height) * inverse_pixel_;
  const double top = (y_high + s.half_height) * inverse_pixel_;
  if (right < 0.0 || bottom > double(height_) || top < 0.0 || left > double(width_)) return false;
  rect.x0 = std::max(0, static_cast<int>(std::floor(std::max(left, -1.0))));
  rect.x1 = std::min(width_ - 1, static_cast<int>(std::floor(std::min(right, double(width_)))));
  rect.y0 = std::max(0, static_cast<int>(std::floor(std::max(bottom, -1.0))));
  rect.y1 = std::min(height_ - 1, static_cast<int>(std::floor(std::min(top, double(height_)))));
  return rect.x0 <= rect.x1 && rect.y0 <= rect.y1;
}

void ViewImage::draw(const PixelRect& rect, double near, std::uint32_t obstacle) {
  const float distance = round_down(near);
  if (!setup_.candidates) {
    std::vector<float>& nearest = minima_[0];
    for (int py = rect.y0; py <= rect.y1; ++py) {
      for (int px = rect.x0; px <= rect.x1; ++px) nearest[index(px, py)] = std::min(nearest[index(px, py)], distance);
    }
    return;
  }
  // With lists the nearest distance is the head of the list: finish() reads
  // it from there (one store per pixel less; drawing was 18% of a 20 cm query).
  for (int py = rect.y0; py <= rect.y1; ++py) {
    const std::size_t row = index(rect.x0, py);
    Candidate* list = &candidates_[row * kCandidates];
    std::uint8_t* count = &counts_[row];
    for (int px = rect.x0; px <= rect.x1; ++px, list += kCandidates, ++count) {
      int n = *count & ~kOverflow;
      if (n == kCandidates) {
        *count |= kOverflow;
        if (!(distance < list[n - 1].near)) continue;
        --n;  // the farthest one makes room
      } else {
        ++*count;
      }
      int at = n;
      while (at > 0 && list[at - 1].near > distance) {
        list[at] = list[at - 1];
        --at;
      }
      list[at] = {distance, obstacle};
    }
  }
}

void ViewImage::finish() {
  if (setup_.candidates) {
    std::vector<float>& nearest = minima_[0];
    for (std::size_t i = 0; i < nearest.size(); ++i) {
      nearest[i] = counts_[i] != 0 ? candidates_[i * kCandidates].near : std::numeric_limits<float>::infinity();
    }
  }
  build(minima_, false);
  if (!setup_.maxima) return;  // (the information gain's fast method sweeps nothing, so never reads them)
  maxima_[0] = minima_[0];
  build(maxima_, true);
}

void ViewImage::build(Pyramid& pyramid, bool greatest) {
  for (std::size_t level = 1; level < pyramid.size(); ++level) {
    const auto [w, h] = level_sizes_[level];
    const auto [below_w, below_h] = level_sizes_[level - 1];
    const std::vector<float>& below = pyramid[level - 1];
    std::vector<float>& out = pyramid[level];
    out.resize(std::size_t(w) * std::size_t(h));
    for (int py = 0; py < h; ++py) {
      for (int px = 0; px < w; ++px) {
        // Blocks at the right and top edges may have fewer than four pixels.
        const int x0 = 2 * px;
        const int y0 = 2 * py;
        const int x1 = std::min(x0 + 1, below_w - 1);
        const int y1 = std::min(y0 + 1, below_h - 1);
        // below_w by init-capture: clang 14 cannot capture a structured binding (the fuzz build uses it).
        auto at = [&below, row = std::size_t(below_w)](int x, int y) {
          return below[std::size_t(y) * row + std::size_t(x)];
        };
        const float a = greatest ? std::max(at(x0, y0), at(x1, y0)) : std::min(at(x0, y0), at(x1, y0));
        const float b = greatest ? std::max(at(x0, y1), at(x1, y1)) : std::min(at(x0, y1), at(x1, y1));
        out[std::size_t(py) * std::size_t(w) + std::size_t(px)] = greatest ? std::max(a, b) : std::min(a, b);
      }
    }
  }
}

float ViewImage::read(const Pyramid& pyramid, const PixelRect& rect, bool greatest) const {
  int level = 0;
  while ((rect.x1 >> level) - (rect.x0 >> level) > 1 || (rect.y1 >> level) - (rect.y0 >> level) > 1) ++level;
  const int w = level_sizes_[std::size_t(level)][0];
  const std::vector<float>& image = pyramid[std::size_t(level)];
  float value = greatest ? -std::numeric_limits<float>::infinity() : std::numeric_limits<float>::infinity();
  for (int py = rect.y0 >> level; py <= rect.y1 >> level; ++py) {
    for (int px = rect.x0 >> level; px <= rect.x1 >> level; ++px) {
      const float v = image[std::size_t(py) * std::size_t(w) + std::size_t(px)];
      value = greatest ? std::max(value, v) : std::min(value, v);
    }
  }
  return value;
}

}  // namespace umbra::detail
