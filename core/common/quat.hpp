#pragma once
// Unit quaternions for the orientation of rigid bodies (multisphere clumps): q maps body-frame
// vectors to the world frame, x_world = q x_body q*.
#include <cmath>

#include "core/common/vec3.hpp"

namespace demcal {

struct Quat {
  double w = 1.0, x = 0.0, y = 0.0, z = 0.0;

  Vec3 vec() const { return {x, y, z}; }
  Quat conjugate() const { return {w, -x, -y, -z}; }
  /// Rotates a body-frame vector into the world frame (Rodrigues form of q v q*).
  Vec3 rotate(const Vec3& v) const {
    const Vec3 u = vec();
    const Vec3 t = 2.0 * cross(u, v);
    return v + w * t + cross(u, t);
  }
  /// The inverse rotation: world frame to body frame.
  Vec3 unrotate(const Vec3& v) const { return conjugate().rotate(v); }
  Quat normalized() const {
    const double inv = 1.0 / std::sqrt(w * w + x * x + y * y + z * z);
    return {w * inv, x * inv, y * inv, z * inv};
  }
};

/// Hamilton product: rotation b followed by rotation a.
inline Quat operator*(const Quat& a, const Quat& b) {
  return {
      a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
      a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}

/// The rotation by the rotation vector phi (axis phi/|phi|, angle |phi|): the exact exponential
/// map, so a constant angular velocity omega turns a body by exactly omega dt per step.
inline Quat rotation_quat(const Vec3& phi) {
  const double angle = norm(phi);
  if (angle < 1e-12) return Quat{1.0, 0.5 * phi.x, 0.5 * phi.y, 0.5 * phi.z}.normalized();
  const double s = std::sin(0.5 * angle) / angle;
  return {std::cos(0.5 * angle), s * phi.x, s * phi.y, s * phi.z};
}

}  // namespace demcal
