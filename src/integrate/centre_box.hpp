// CentreBox: where a node's voxel centres lie in a depth image, as the
// projective walk (projective_tracer.cpp) and the surface band
// (surface_band.cpp) bound them before deciding the node whole.
//
// The centres of a node of n x n x n voxels fill a box in the map frame;
// its eight corners, taken to the camera frame, bound the centres' camera
// depths, and where all of them lie in front of the camera their
// projections bound the pixels the centres project onto (a projection of a
// box's points lies in the hull of its corners' projections). The rule
// (projective_frame.hpp) evaluates the centres in float; the bounds here are
// in double, widened by the caller's `pad` (metres the float coordinates may
// be off by) and its effect on the projections.
#pragma once

#include <array>

#include "umbra/core/vec3.hpp"

namespace umbra {

struct ProjectiveFrame;

/// How far the rule's float camera-frame coordinates may stray from the
/// exact ones, relative to their size: the brick origin is rounded once
/// (2^-24), the offset once, their sum once; 2e-6 is several times that.
inline constexpr double kProjectiveRelativeError = 2e-6;

struct CentreBox {
  /// `first`: the map-frame centre of the node's first voxel; `span`: the
  /// distance from it to the last centre along each map axis ((n - 1)
  /// resolutions for a node n voxels wide).
  CentreBox(const ProjectiveFrame& frame, Vec3d first, double span);

  /// The corners in the camera frame: corner i is `first` plus `span` along
  /// the map's x axis where i & 1, y where i & 2, z where i & 4.
  std::array<Vec3d, 8> corners;
  double z_min = 0.0;  ///< the least camera depth of a corner
  double z_max = 0.0;  ///< the largest

  /// The centres' pixels (u as the rule's: fx x / z + cx + 1/2): every
  /// centre, off by up to `pad` metres, projects into [u_min - u_pad, u_max
  /// + u_pad] x [v_min - v_pad, v_max + v_pad]. Only where z_min - pad > 0.
  struct Pixels {
    double u_min, u_max, v_min, v_max;
    double u_pad, v_pad;
  };
  [[nodiscard]] Pixels pixels(const ProjectiveFrame& frame, double pad) const;
};

}  // namespace umbra
