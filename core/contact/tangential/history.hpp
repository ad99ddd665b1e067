#pragma once
// Tangential history spring with a Coulomb limit and static/dynamic friction
// (seed 000 eq. 16-22, Luding 2008; seed 001 eq. 6-8):
//   xi    += vt dt                        (eq. 16; xi first turned into the current tangent plane)
//   ft     = -kt xi - gamma_t vt          (eq. 19),  kt = f3 k_ref (eq. 20),  gamma_t = f5 gamma_n
//   (eq. 22) static while |ft| <= mu_s F_c;  else sliding: ft = mu_d F_c t_hat, mu_d = f4 mu_s (eq.
//   21), and xi is reset to the spring length that gives that force: xi = -(ft + gamma_t vt) / kt
//   F_c = F_n + kc delta + F_vdw          (eq. 18: the normal force without its adhesive parts)
// k_ref is the normal law's own stiffness: k1 (Luding), kn (linear), 8 G* sqrt(R* delta) (Hertz).
// History: [0..2] xi, the tangential spring elongation (m).
#include <array>
#include <cmath>

#include "core/contact/pair.hpp"
#include "core/contact/param_table.hpp"

namespace demcal::contact::tangential {

struct History {
  static constexpr const char* kName = "history";
  static constexpr int kHistory = 3;

  double kt_ratio;       ///< f3 = kt / k_ref (-)
  double mu_s;           ///< static friction coefficient (-)
  double mu_d_ratio;     ///< f4 = mu_d / mu_s (-)
  double gamma_t_ratio;  ///< f5 = gamma_t / gamma_n (-)

  static std::array<ParamInfo<History>, 4> table() {
    return {{{"kt_ratio", "-", 0.0, 10.0, 2.0 / 7.0, "f3 = kt / k_ref", &History::kt_ratio},
             {"mu_s", "-", 0.0, 10.0, kUnset, "static friction coefficient", &History::mu_s},
             {"mu_d_ratio", "-", 0.0, 1.0, 1.0, "f4 = mu_d / mu_s", &History::mu_d_ratio},
             {"gamma_t_ratio", "-", 0.0, 10.0, 0.0, "f5 = gamma_t / gamma_n",
              &History::gamma_t_ratio}}};
  }
  void finalize(const std::string& where) {
    if (!is_set(mu_s)) throw InputError(where + ".mu_s", "required");
  }

  Vec3 force(const PairInput& in, const NormalResult& nr, double f_coulomb, double* history) const {
    const double kt = kt_ratio * nr.k_ref;
    const double gamma_t = gamma_t_ratio * nr.gamma_n;
    Vec3 xi = load_vec(history);
    rotate_into_plane(xi, in.n);
    xi += in.vt * in.dt;
    Vec3 ft = -(xi * kt) - in.vt * gamma_t;
    // Squares compared: a sticking contact needs no square root (the limit is >= 0).
    const double limit = mu_s * f_coulomb;
    const double ft_mag2 = norm2(ft);
    if (ft_mag2 > limit * limit) {
      ft *= mu_d_ratio * limit / std::sqrt(ft_mag2);
      xi = kt > 0.0 ? -(ft + in.vt * gamma_t) / kt : Vec3{};
    }
    store_vec(history, xi);
    return ft;
  }
};

}  // namespace demcal::contact::tangential
