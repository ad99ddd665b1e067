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
/// map, so a constant angular velocity omega turns a body by exactly omega dt per step,
///   q = (cos h, sin h phi / |phi|),  h = |phi| / 2.
/// The turn of one time step is small: for h < 0.1 the Taylor series of cos h and of
/// sin h / (2 h) to their h^8 terms are used (the first term left out, h^10 / 10!, is below
/// 2^-53 there), so the step's turn costs neither a square root nor a sine.
inline Quat rotation_quat(const Vec3& phi) {
  const double h2 = 0.25 * dot(phi, phi);
  if (h2 < 0.01) {
    const double c =
        1.0 + h2 * (-1.0 / 2.0 + h2 * (1.0 / 24.0 + h2 * (-1.0 / 720.0 + h2 * (1.0 / 40320.0))));
    const double s =
        0.5 * (1.0 + h2 * (-1.0 / 6.0 +
                           h2 * (1.0 / 120.0 + h2 * (-1.0 / 5040.0 + h2 * (1.0 / 362880.0)))));
    return {c, s * phi.x, s * phi.y, s * phi.z};
  }
  const double angle = std::sqrt(4.0 * h2);
  const double s = std::sin(0.5 * angle) / angle;
  return {std::cos(0.5 * angle), s * phi.x, s * phi.y, s * phi.z};
}

/// A product of unit quaternions brought back to unit length. Its norm differs from 1 by
/// rounding only (e = |q|^2 - 1 of order 1e-16), so one Newton step for 1/sqrt(1 + e),
/// 1 - e/2, leaves an error of 3 e^2 / 8: unit to rounding, without a square root or division.
inline Quat renormalized(const Quat& q) {
  const double f = 1.5 - 0.5 * (q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  return {q.w * f, q.x * f, q.y * f, q.z * f};
}

}  // namespace demcal
