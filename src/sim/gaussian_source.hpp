// GaussianSource: standard normal numbers that are the same on every
// platform, for the simulated sensors' noise.
//
// std::normal_distribution is not specified bit for bit, so a seed would give
// different noise with another standard library. The engine's output
// (std::mt19937) is fully specified; the Box-Muller transform below then uses
// only log, sqrt, cos and sin, whose last bit may differ between maths
// libraries (far below any test tolerance). Cost: two engine draws and one
// log/sqrt/sin/cos per two numbers.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

namespace umbra::sim::detail {

class GaussianSource {
 public:
  explicit GaussianSource(std::uint32_t seed) : engine_(seed) {}

  double next() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    // u1 in (0, 1] so that log(u1) is finite; u2 in [0, 1). 32 random bits each.
    const double u1 = (double(engine_()) + 1.0) / 4294967296.0;
    const double u2 = double(engine_()) / 4294967296.0;
    const double radius = std::sqrt(-2.0 * std::log(u1));
    const double angle = 2.0 * std::numbers::pi * u2;
    spare_ = radius * std::sin(angle);
    has_spare_ = true;
    return radius * std::cos(angle);
  }

 private:
  std::mt19937 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace umbra::sim::detail
