// A simulated depth camera (pinhole model, in the style of an RGB-D or
// stereo camera), for tests, benchmarks and exploration studies.
//
// The camera has `width` x `height` pixels spread over a horizontal field of
// view `hfov_deg` and a vertical one `vfov_deg` (pinhole: fx = width / 2 /
// tan(hfov / 2), fy = height / 2 / tan(vfov / 2), principal point in the
// middle). Pixel (u, v) (u to the right, v down, sampled at the pixel's
// centre) looks along d = f - ((u + 0.5 - width / 2) / fx) l - ((v + 0.5 -
// height / 2) / fy) up, normalised, where the pose gives forward f = (cos p
// cos y, cos p sin y, sin p), left l = (-sin y, cos y, 0) and up = f x l (the
// frame docs/design.md (Semantics) uses for the information gain, so a pixel's ray lies in the
// frustum of the same hfov, vfov and range). The ray is cast into a Scene; a
// surface at Euclidean range r in [min_range, max_range] gives the point at
// r + n along the ray, n Gaussian noise with standard deviation
// noise_stddev + noise_per_square_metre * r^2 (depth cameras get worse with
// the square of the range), the noisy range clamped to [0, max_range].
// Noise comes from our own Box-Muller transform over std::mt19937 (see
// lidar.hpp), so a seed gives the same image with every compiler.
//
// demo_camera_path() is a trajectory through make_demo_scene() whose views
// overlap from frame to frame as a hand-held or robot-mounted camera's do:
// later frames look through the noisy surfaces of earlier ones.
//
// Cost model: width * height ray casts through the scene's hierarchy
// (scene.hpp): about 10 ms for 640 x 240 pixels on the demo scene, about
// 1.3 us per pixel on the 870 primitives of make_industrial_scene() (brute
// force over them took 9.6 us).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "umbra/core/pose.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/map/depth_image.hpp"
#include "umbra/sim/scene.hpp"

namespace umbra::sim {

/// Where a camera is and where it looks: yaw counter-clockwise from +x about
/// +z, pitch up from the horizontal (radians); no roll.
struct CameraPose {
  Vec3d position;
  double yaw = 0.0;
  double pitch = 0.0;
};

struct DepthCameraModel {
  int width = 640;                       ///< pixels, >= 1
  int height = 240;                      ///< pixels, >= 1
  double hfov_deg = 115.0;               ///< horizontal field of view, in (0, 180)
  double vfov_deg = 60.0;                ///< vertical field of view, in (0, 180)
  double min_range = 0.1;                ///< metres, >= 0: nearer surfaces give no point
  double max_range = 6.5;                ///< metres, > min_range: farther surfaces give no point
  double noise_stddev = 0.0;             ///< metres, Gaussian noise along the ray at range 0
  double noise_per_square_metre = 0.0;   ///< 1/m: added standard deviation per squared metre of range
  std::uint32_t seed = 1;                ///< seed of the noise generator
  /// If set, a pixel that sees no surface within max_range gives a point at
  /// no_return_range along its ray (exact): insert it with
  /// InsertOptions::max_range below no_return_range and the integrator clears
  /// free space along it without a hit.
  bool emit_no_return = false;
  double no_return_range = 100.0;        ///< metres, > max_range (checked only with emit_no_return)

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
  [[nodiscard]] std::size_t pixel_count() const;
  /// Unit direction of the ray through the centre of pixel (u, v) from `pose`.
  [[nodiscard]] Vec3d pixel_direction(const CameraPose& pose, int u, int v) const;
};

/// World-frame points of one depth image from `pose`: one per pixel that sees
/// a surface in [min_range, max_range] (plus one per pixel without one if
/// emit_no_return), row by row from the top, each row left to right. The
/// noise generator is seeded afresh from model.seed on every call, so one
/// call depends only on its arguments. Throws std::invalid_argument for a
/// bad model or a non-finite pose.
std::vector<Vec3f> simulate_depth_image(const Scene& scene, const CameraPose& pose, const DepthCameraModel& model);

/// The same, into `points` (cleared first; its capacity is reused).
void simulate_depth_image(const Scene& scene, const CameraPose& pose, const DepthCameraModel& model,
                          std::vector<Vec3f>& points);

/// A depth image as a depth camera gives it: per pixel the depth along the
/// optical axis (metres; 0: no reading), with the pinhole intrinsics and the
/// pose (optical frame to map) that describe the model and pose exactly.
/// back_project(view(), camera, pose) gives simulate_depth_image's points
/// for the same arguments, up to float rounding (the image stores depths,
/// the points are made from them).
struct SimulatedDepthImage {
  int width = 0;
  int height = 0;
  std::vector<float> depth;
  PinholeCamera camera;
  Pose pose;
  [[nodiscard]] DepthImage view() const;
};

/// The image simulate_depth_image's points come from (same noise, same seed).
/// Throws as simulate_depth_image.
SimulatedDepthImage simulate_depth_frame(const Scene& scene, const CameraPose& pose, const DepthCameraModel& model);

/// One image per pose, seeded as simulate_depth_sequence.
std::vector<SimulatedDepthImage> simulate_depth_frames(const Scene& scene, std::span<const CameraPose> poses,
                                                       const DepthCameraModel& model);

/// One depth image of a sequence: the camera's position and the points.
struct DepthFrame {
  Vec3f origin;
  std::vector<Vec3f> points;
};

/// One image per pose; image i draws its noise from seed model.seed + i, so
/// frames have independent noise and the sequence depends only on the seed.
std::vector<DepthFrame> simulate_depth_sequence(const Scene& scene, std::span<const CameraPose> poses,
                                                const DepthCameraModel& model);

/// Sixteen poses through make_demo_scene() at 1.3 m height, looking slightly
/// down: ten 0.4 to 0.5 m apart along the west half of the corridor, panning
/// from side to side, then six from the door of the middle north room into
/// it. Every pose is in free space, at least 0.3 m from any surface.
std::vector<CameraPose> demo_camera_path();

/// The depth camera the tests and benchmarks use: DepthCameraModel's defaults
/// (640 x 240 pixels, hfov 115, vfov 60, 6.5 m) with noise of a Kinect-like
/// spread (2 mm + 1.5 mm per square metre of range: 1.6 cm at 3 m, 6.5 cm at
/// 6.5 m) and the given seed.
DepthCameraModel noisy_depth_camera(std::uint32_t seed = 1);

/// noisy_depth_camera() along demo_camera_path() in make_demo_scene().
std::vector<DepthFrame> demo_depth_sequence(std::uint32_t seed = 1);
/// The same as depth images.
std::vector<SimulatedDepthImage> demo_depth_images(std::uint32_t seed = 1);

}  // namespace umbra::sim
