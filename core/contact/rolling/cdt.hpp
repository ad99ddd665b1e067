#pragma once
// Constant directional torque (seed 000 eq. 23; LIGGGHTS `rolling_friction cdt`):
//   T_i = -mu_r F_c R* w_roll / |w_roll|,   T_j = -T_i
// w_roll = the part of omega_i - omega_j perpendicular to n (the rolling, not the twisting,
// motion); F_c the normal force of the Coulomb criterion (seed 000 eq. 18), so |T| <= mu_r R* F_n.
// History: none.
#include <array>

#include "core/contact/pair.hpp"
#include "core/contact/param_table.hpp"

namespace demcal::contact::rolling {

struct Cdt {
  static constexpr const char* kName = "cdt";
  static constexpr int kHistory = 0;

  double mu_r;  ///< rolling friction coefficient (-)

  static std::array<ParamInfo<Cdt>, 1> table() {
    return {{{"mu_r", "-", 0.0, 10.0, kUnset, "rolling friction coefficient", &Cdt::mu_r}}};
  }
  void finalize(const std::string& where) {
    if (!is_set(mu_r)) throw InputError(where + ".mu_r", "required");
  }

  Vec3 torque(const PairInput& in, const NormalResult&, double f_coulomb, double*) const {
    const Vec3 w_roll = in.w_rel - in.n * dot(in.w_rel, in.n);
    const double mag = norm(w_roll);
    if (mag == 0.0) return {};
    return w_roll * (-mu_r * f_coulomb * in.r_star / mag);
  }
};

}  // namespace demcal::contact::rolling
