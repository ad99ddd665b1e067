#pragma once
// Elastic-plastic spring-dashpot rolling resistance as a rolling quasi-force (seed 001 eq. 9-13):
//   v_r   = -R* (omega_i - omega_j) x n                   (eq. 12)
//   F_r  -= k_r v_r dt,  k_r = kr_ratio k_ref              (eq. 11; F_r first turned into the
//   plane) |F_r| <= mu_r F_c (Coulomb-type cap)                   (eq. 13) T_i   = -R* n x F_r, T_j
//   = +R* n x F_r                 (eq. 9-10)
// so |T| <= mu_r R* F_n.  History: [0..2] F_r (N).
#include <array>
#include <cmath>

#include "core/contact/pair.hpp"
#include "core/contact/param_table.hpp"

namespace demcal::contact::rolling {

struct Epsd {
  static constexpr const char* kName = "epsd";
  static constexpr int kHistory = 3;

  double mu_r;      ///< rolling friction coefficient (-)
  double kr_ratio;  ///< k_r / k_ref (-); seed 001 takes k_r = k_n

  static std::array<ParamInfo<Epsd>, 2> table() {
    return {{{"mu_r", "-", 0.0, 10.0, kUnset, "rolling friction coefficient", &Epsd::mu_r},
             {"kr_ratio", "-", 0.0, 10.0, 1.0, "rolling stiffness k_r / k_ref", &Epsd::kr_ratio}}};
  }
  void finalize(const std::string& where) {
    if (!is_set(mu_r)) throw InputError(where + ".mu_r", "required");
  }

  Vec3 torque(const PairInput& in, const NormalResult& nr, double f_coulomb,
              double* history) const {
    Vec3 fr = load_vec(history);
    rotate_into_plane(fr, in.n);
    const Vec3 v_r = -in.r_star * cross(in.w_rel, in.n);
    fr -= v_r * (kr_ratio * nr.k_ref * in.dt);
    const double cap = mu_r * f_coulomb;
    const double mag = norm(fr);
    if (mag > cap) fr *= (mag > 0.0 ? cap / mag : 0.0);
    store_vec(history, fr);
    return -in.r_star * cross(in.n, fr);
  }
};

}  // namespace demcal::contact::rolling
