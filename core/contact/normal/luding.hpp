#pragma once
// Luding hysteretic elasto-plastic normal force with an adhesive branch (Luding 2008;
// seed 000 eq. 2-11), branch logic as LIGGGHTS 3.8 `model luding`:
//   r_eff     = 2 r_i r_j / (r_i + r_j)                          (seed 000 eq. 4, 13)
//   k1        = given, or 4/3 Y sqrt(r_eff^2 delta')             (eq. 3)
//   k2 = f1 k1 (f1 = k2/k1, eq. 10),  kc = f2 k1 (f2 = kc/k1, eq. 11)
//   delta*_max = k2 / (k2 - k1) phi_f r_eff                      (eq. 4)
//   k2*       = k2 if delta_max >= delta*_max, else k1 + (k2 - k1) delta_max / delta*_max   (eq. 5)
//   f_hys     = k1 delta on the loading branch, k2* (delta - delta_0) on un-/reloading,
//               -kc delta on the adhesive branch, delta_0 = (1 - k1/k2*) delta_max         (eq. 6)
//   fn        = f_hys + gamma_n vn,  gamma_n = sqrt(4 m* k1 / (1 + (pi / ln e)^2))        (eq. 7,
//   9)
// Beyond delta*_max the contact is elastic with k2 about delta_0 = (1 - k1/k2) delta*_max.
// On the adhesive branch delta_max is moved so that a reload leaves along the k2* line through the
// current point: delta_max = (k2* + kc) / (k2* - k1) delta.
// Eq. 8 of seed 000 writes the effective mass as 2 m_i m_j / (m_i + m_j); with that mass eq. 7
// would not give restitution e, so the reduced mass m* = m_i m_j / (m_i + m_j) is used, as LIGGGHTS
// does. History: [0] delta_max (m).
#include <algorithm>
#include <array>
#include <cmath>

#include "core/contact/pair.hpp"
#include "core/contact/param_table.hpp"

namespace demcal::contact::normal {

struct Luding {
  static constexpr const char* kName = "luding";
  static constexpr int kHistory = 1;

  double k1;              ///< loading stiffness (N/m); kUnset = from youngs_modulus by eq. 3
  double youngs_modulus;  ///< Y for eq. 3 (Pa)
  double delta_prime;     ///< dimensionless overlap delta' for eq. 3 (-)
  double k2_ratio;        ///< f1 = k2/k1 (-)
  double kc_ratio;        ///< f2 = kc/k1 (-)
  double phi_f;           ///< plasticity depth (-)
  double restitution;     ///< e (-)

  static std::array<ParamInfo<Luding>, 7> table() {
    return {{{"k1", "N/m", 1e-12, 1e15, kUnset, "loading stiffness (or give youngs_modulus)",
              &Luding::k1},
             {"youngs_modulus", "Pa", 1.0, 1e13, kUnset,
              "Y for k1 = 4/3 Y sqrt(r^2 delta') (eq. 3)", &Luding::youngs_modulus},
             {"delta_prime", "-", 1e-6, 0.5, 0.01, "dimensionless overlap delta' of eq. 3",
              &Luding::delta_prime},
             {"k2_ratio", "-", 1.0001, 1e4, 5.0, "f1 = k2/k1, maximum unloading stiffness",
              &Luding::k2_ratio},
             {"kc_ratio", "-", 0.0, 1e3, 0.0, "f2 = kc/k1, adhesion stiffness", &Luding::kc_ratio},
             {"phi_f", "-", 1e-6, 1.0, 0.05, "plasticity depth phi_f", &Luding::phi_f},
             {"restitution", "-", 1e-6, 1.0, 0.5, "coefficient of restitution e (eq. 7)",
              &Luding::restitution}}};
  }
  void finalize(const std::string& where) {
    if (is_set(k1) == is_set(youngs_modulus))
      throw InputError(where, "give exactly one of 'k1' and 'youngs_modulus' (eq. 3)");
    // The factors of eq. 3, 4 and 7 that do not depend on the pair, computed once with the
    // operations in the order the formulas below apply them (so every force keeps its bits).
    if (!is_set(k1)) {
      eq3_modulus_ = (4.0 / 3.0) * youngs_modulus;
      eq3_root_ = std::sqrt(delta_prime);
    }
    eq4_factor_ = k2_ratio / (k2_ratio - 1.0) * phi_f;
    if (restitution < 1.0) {
      const double q = M_PI / std::log(restitution);
      eq7_denominator_ = 1.0 + q * q;
    }
  }
  double loading_stiffness(double r_eff) const {
    return is_set(k1) ? k1 : eq3_modulus_ * r_eff * eq3_root_;
  }
  /// delta*_max of eq. 4: the overlap beyond which un-/reloading has the full k2.
  double plastic_limit(double r_eff) const { return eq4_factor_ * r_eff; }
  /// The largest slope of the force-overlap curve: k2 (eq. 10) or kc (eq. 11), whichever is larger.
  double max_stiffness(double r_eff) const {
    return std::max(k2_ratio, kc_ratio) * loading_stiffness(r_eff);
  }
  /// The largest slope a contact whose overlap has reached delta_max can present: the loading k1,
  /// the un-/reloading k2*(delta_max) of eq. 5 or the adhesive kc. Under a light load k2* stays
  /// near k1, a step bounded by k2 alone would be f1^(1/2) times shorter than the contacts need.
  double reached_stiffness(double r_eff, double delta_max) const {
    return reached_stiffness(loading_stiffness(r_eff), delta_max, plastic_limit(r_eff));
  }
  /// The same from the pair's k1 and delta*_max, as the force law has them at hand.
  double reached_stiffness(double kl, double delta_max, double delta_lim) const {
    const double k2 = kl + (k2_ratio - 1.0) * kl * std::min(1.0, delta_max / delta_lim);
    return std::max(k2, kc_ratio * kl);
  }
  /// The overlap at which a fresh contact's loading branch carries `force` (N): force / k1.
  double overlap_at(double force, double r_eff) const { return force / loading_stiffness(r_eff); }
  double damping(double m_star, double k) const {
    if (restitution >= 1.0) return 0.0;
    return std::sqrt(4.0 * m_star * k / eq7_denominator_);
  }

  NormalResult force(const PairInput& in, double* history) const {
    const double r_eff = 2.0 * in.r_star;
    const double kl = loading_stiffness(r_eff);
    const double k2_max = k2_ratio * kl;
    const double kc = kc_ratio * kl;
    const double delta = in.delta;
    double& delta_max = history[0];
    if (delta > delta_max) delta_max = delta;
    const double delta_lim = plastic_limit(r_eff);

    double f_hys;
    if (delta_max >= delta_lim) {
      const double f_elastic = k2_max * (delta - delta_lim) + kl * delta_lim;
      if (f_elastic >= -kc * delta) {
        f_hys = f_elastic;
      } else {
        f_hys = -kc * delta;
        delta_max = (k2_max + kc) / (k2_max - kl) * delta;
      }
    } else {
      const double k2 = kl + (k2_max - kl) * delta_max / delta_lim;
      const double f_elastic = k2 * (delta - delta_max) + kl * delta_max;
      if (f_elastic >= kl * delta) {
        f_hys = kl * delta;
      } else if (f_elastic > -kc * delta) {
        f_hys = f_elastic;
      } else {
        f_hys = -kc * delta;
        delta_max = (k2 + kc) / (k2 - kl) * delta;
      }
    }

    NormalResult r;
    r.k_ref = kl;
    r.gamma_n = damping(in.m_star, kl);
    r.fn = f_hys + r.gamma_n * in.vn;
    r.f_adhesive = kc * delta;
    r.k_step = reached_stiffness(kl, delta_max, delta_lim);
    return r;
  }

 private:
  // Derived by finalize(): 4/3 Y and sqrt(delta') of eq. 3, k2 / (k2 - k1) phi_f of eq. 4,
  // 1 + (pi / ln e)^2 of eq. 7.
  double eq3_modulus_ = 0.0, eq3_root_ = 0.0, eq4_factor_ = 0.0, eq7_denominator_ = 1.0;
};

}  // namespace demcal::contact::normal
