#pragma once
// What every contact-law slot sees of one pair, and what the law hands back.
// Sign conventions (used by every model):
//   n      unit normal pointing from body i to body j (for a wall: from the particle into the wall)
//   delta  overlap r_i + r_j - |x_j - x_i| (seed 000 eq. 2): > 0 in contact, < 0 a gap of -delta
//   vn     d(delta)/dt = (v_i - v_j) . n: > 0 while the bodies approach
//   fn     scalar normal force, > 0 repulsive; the force on i is -fn n and on j is +fn n
#include "core/common/vec3.hpp"

namespace demcal::contact {

struct PairInput {
  Vec3 n;
  double delta = 0.0;
  double r_i = 0.0;     ///< radius of i (m): lever arm of the tangential force
  double r_j = 0.0;     ///< radius of j (m); 0 for a wall
  double r_star = 0.0;  ///< reduced radius R* = r_i r_j / (r_i + r_j); r_i for a wall (m)
  double m_star = 0.0;  ///< reduced mass m* = m_i m_j / (m_i + m_j); m_i for a wall (kg)
  double vn = 0.0;      ///< rate of overlap (m/s)
  Vec3 vt;              ///< tangential velocity of i's contact point relative to j's (m/s)
  Vec3 w_rel;           ///< omega_i - omega_j (rad/s)
  double dt = 0.0;      ///< time step (s)
};

/// Output of the normal slot, read by the tangential and rolling slots.
struct NormalResult {
  double fn = 0.0;        ///< normal force incl. damping, without the cohesion slot (N)
  double f_adhesive = 0;  ///< attraction built into the normal law (Luding k_c delta), added back
                          ///< for the Coulomb criterion as seed 000 eq. 18 does (N)
  double k_ref = 0.0;     ///< the stiffness tangential and rolling stiffness ratios refer to (N/m)
  double gamma_n = 0.0;   ///< normal damping coefficient (kg/s)
  /// The steepest slope of the force-overlap curve the contact can follow from where it is, for
  /// the time step (sim/time_step.hpp): the tangent of an elastic law, the larger of the
  /// un-/reloading and adhesive slopes of a hysteretic one (N/m).
  double k_step = 0.0;
};

namespace normal {
/// Whether the time step resolves a contact of normal model N at its stiffness in use
/// (NormalResult::k_step; true unless N says otherwise with kAccuracyFromOwnBound): the step of a
/// Hertz contact is accurate by the Rayleigh time (seed 000 eq. 1) as it is in common practice,
/// and its tangent stiffness only has to stay stable (sim/time_step.hpp).
template <class N>
constexpr bool stiffness_sets_accuracy() {
  if constexpr (requires { N::kAccuracyFromOwnBound; })
    return !N::kAccuracyFromOwnBound;
  else
    return true;
}
}  // namespace normal

struct PairOutput {
  double fn = 0.0;         ///< total normal force, > 0 repulsive (N)
  double stiffness = 0.0;  ///< NormalResult::k_step of a contact; 0 out of contact (N/m)
  Vec3 force;              ///< force on i (N); j receives -force
  Vec3 ft;                 ///< tangential part of `force` (N)
  Vec3 torque_i;           ///< (N m)
  Vec3 torque_j;           ///< (N m)
  Vec3 rolling_torque;     ///< rolling-resistance part of torque_i (N m)
};

/// Removes the normal component of a history vector and restores its length: the history is
/// carried into the current tangent plane when the contact normal turns (MercuryDPM, LIGGGHTS).
inline void rotate_into_plane(Vec3& h, const Vec3& n) {
  const double before = norm2(h);
  if (before == 0.0) return;
  h -= n * dot(h, n);
  const double after = norm2(h);
  if (after > 0.0) h *= std::sqrt(before / after);
}

/// Clears the history of a contact that ended. Most such pairs were not touching before either:
/// their history is only read, not written again every step.
template <int kStride>
void clear_history(double* h) {
  bool set = false;
  for (int s = 0; s < kStride; ++s) set |= h[s] != 0.0;
  if (set)
    for (int s = 0; s < kStride; ++s) h[s] = 0.0;
}

inline Vec3 load_vec(const double* p) {
  return {p[0], p[1], p[2]};
}
inline void store_vec(double* p, const Vec3& v) {
  p[0] = v.x;
  p[1] = v.y;
  p[2] = v.z;
}

}  // namespace demcal::contact
