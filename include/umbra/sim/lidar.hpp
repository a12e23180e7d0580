// A simulated spinning 3D LiDAR (in the style of a 32-ring automotive sensor).
//
// The sensor fires rings x azimuth_steps beams: ring elevations are spread
// evenly from fov_down_deg to fov_up_deg (inclusive; one ring looks at their
// middle), azimuths evenly over a full turn starting at the pose's yaw. Each
// beam is cast into a Scene; a hit within max_range gives its end point in the
// map frame, optionally with Gaussian noise along the beam. The noise is
// drawn from std::mt19937 bits through our own Box-Muller transform, so a
// given seed gives the same noise with every compiler and standard library
// (std::normal_distribution is not specified bit for bit; only the last bit
// of libm's log/sin/cos may differ between platforms). Beams that hit
// nothing can be reported as far points for the integrator to clear free
// space along (emit_no_return).
//
// Cost model: rings * azimuth_steps ray casts through the scene's hierarchy
// (scene.hpp); the default model on the demo scene (~100 primitives) takes a
// few milliseconds. simulate_scan into an existing vector reuses its memory.
#pragma once

#include <cstdint>
#include <vector>

#include "umbra/core/vec3.hpp"
#include "umbra/sim/scene.hpp"

namespace umbra::sim {

struct LidarModel {
  int rings = 32;                   ///< beams per azimuth step, >= 1
  double fov_down_deg = -25.0;      ///< elevation of the lowest ring, > -90
  double fov_up_deg = 15.0;         ///< elevation of the highest ring, >= fov_down_deg, < 90
  int azimuth_steps = 720;          ///< beams per ring over 360 degrees, >= 1
  double max_range = 30.0;          ///< metres; hits farther away are not returned
  double range_noise_stddev = 0.0;  ///< metres, Gaussian along the beam; 0 = exact
  std::uint32_t seed = 1;           ///< seed of the noise generator
  /// If set, a beam that hits nothing within max_range gives a point at
  /// no_return_range along it (exact, no noise): insert the scan with an
  /// InsertOptions::max_range below no_return_range and the integrator
  /// clears free space along the beam without inserting a hit there.
  bool emit_no_return = false;
  double no_return_range = 100.0;  ///< metres, > max_range (checked only with emit_no_return)

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
  /// rings * azimuth_steps: the most points one scan can have.
  [[nodiscard]] std::size_t beam_count() const;
};

/// World-frame end points of one scan from `pose`: one per beam that hits
/// within max_range, plus one per beam without a hit if emit_no_return.
/// Noisy ranges are clamped to [0, max_range]. Points come ring by ring
/// (lowest first), each ring in increasing azimuth. The noise generator is
/// seeded afresh from model.seed on every call, so one call depends only on
/// its arguments. Throws std::invalid_argument for a bad model or a
/// non-finite pose.
std::vector<Vec3f> simulate_scan(const Scene& scene, const SensorPose& pose,
                                 const LidarModel& model);

/// The same, into `points` (cleared first; its capacity is reused).
void simulate_scan(const Scene& scene, const SensorPose& pose, const LidarModel& model,
                   std::vector<Vec3f>& points);

}  // namespace umbra::sim
