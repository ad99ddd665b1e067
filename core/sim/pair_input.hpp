#pragma once
// The contact-law input of one particle pair, built the same way by the force kernel and by the
// measurements that evaluate a law again (metrics/stress.hpp).
#include "core/contact/pair.hpp"

namespace demcal::sim {

/// Pair (i, j) at separation d = x_j - x_i (minimum image) of length dist > 0, with radii, masses,
/// velocities and spins of both; dt is the time step the tangential spring integrates over.
inline contact::PairInput particle_pair_input(const Vec3& d, double dist, double ri, double rj,
                                              double mi, double mj, const Vec3& vi, const Vec3& vj,
                                              const Vec3& wi, const Vec3& wj, double dt) {
  // R* = ri rj / (ri + rj) and m* = mi mj / (mi + mj) share one division.
  const double inv_sums = 1.0 / ((ri + rj) * (mi + mj));
  contact::PairInput in;
  in.n = d * (1.0 / dist);
  in.delta = ri + rj - dist;
  in.r_i = ri;
  in.r_j = rj;
  in.r_star = ri * rj * (mi + mj) * inv_sums;
  in.m_star = mi * mj * (ri + rj) * inv_sums;
  const Vec3 v_rel = vi - vj;
  in.vn = dot(v_rel, in.n);
  in.vt = v_rel - in.n * in.vn + cross(wi * ri + wj * rj, in.n);
  in.w_rel = wi - wj;
  in.dt = dt;
  return in;
}

}  // namespace demcal::sim
