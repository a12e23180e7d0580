#include "integrate/centre_box.hpp"

#include <algorithm>
#include <cmath>

#include "core/assert.hpp"
#include "integrate/projective_frame.hpp"

namespace umbra {

CentreBox::CentreBox(const ProjectiveFrame& frame, Vec3d first, double span) {
  const Vec3d c0 = frame.to_camera(first);
  const Vec3d ex = frame.rotate(Vec3d{span, 0.0, 0.0});
  const Vec3d ey = frame.rotate(Vec3d{0.0, span, 0.0});
  const Vec3d ez = frame.rotate(Vec3d{0.0, 0.0, span});
  for (unsigned i = 0; i < 8; ++i) {
    corners[i] = c0;
    if (i & 1u) corners[i] = corners[i] + ex;
    if (i & 2u) corners[i] = corners[i] + ey;
    if (i & 4u) corners[i] = corners[i] + ez;
  }
  z_min = corners[0].z;
  z_max = corners[0].z;
  for (const Vec3d& c : corners) {
    z_min = std::min(z_min, c.z);
    z_max = std::max(z_max, c.z);
  }
}

CentreBox::Pixels CentreBox::pixels(const ProjectiveFrame& frame, double pad) const {
  const double near = z_min - pad;
  UMBRA_ASSERT(near > 0.0);
  const double u_offset = frame.cx + 0.5;
  const double v_offset = frame.cy + 0.5;
  Pixels p{1e300, -1e300, 1e300, -1e300, 0.0, 0.0};
  double lateral = 0.0;  // largest |x| or |y|
  for (const Vec3d& c : corners) {
    const double u = frame.fx * (c.x / c.z) + u_offset;
    const double v = frame.fy * (c.y / c.z) + v_offset;
    p.u_min = std::min(p.u_min, u);
    p.u_max = std::max(p.u_max, u);
    p.v_min = std::min(p.v_min, v);
    p.v_max = std::max(p.v_max, v);
    lateral = std::max({lateral, std::abs(c.x), std::abs(c.y)});
  }
  // A coordinate off by `pad` moves the projection by about f pad (1 +
  // lateral / z) / z pixels; the projection's own rounding is relative.
  const double spread = pad * (1.0 + lateral / near) / near;
  p.u_pad = 1e-3 + frame.fx * spread + 1e-6 * std::max(std::abs(p.u_min), std::abs(p.u_max));
  p.v_pad = 1e-3 + frame.fy * spread + 1e-6 * std::max(std::abs(p.v_min), std::abs(p.v_max));
  return p;
}

}  // namespace umbra
