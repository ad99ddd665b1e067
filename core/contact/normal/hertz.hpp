#pragma once
// Hertz normal force with restitution-based damping, as LIGGGHTS `model hertz`:
//   fn = 4/3 Y* sqrt(R* delta) delta + gamma_n vn
//   gamma_n = -2 sqrt(5/6) beta sqrt(S_n m*),  S_n = 2 Y* sqrt(R* delta),
//   beta = ln e / sqrt(ln^2 e + pi^2)
// Y* = Y / (2 (1 - nu^2)) for two bodies of one material; the reference tangential stiffness is
// Mindlin's S_t = 8 G* sqrt(R* delta), G* = Y / (4 (2 - nu)(1 + nu)).
// Time scale: the Rayleigh time (seed 000 eq. 1). History: none.
#include <array>
#include <cmath>

#include "core/contact/pair.hpp"
#include "core/contact/param_table.hpp"

namespace demcal::contact::normal {

struct Hertz {
  static constexpr const char* kName = "hertz";
  static constexpr int kHistory = 0;

  double youngs_modulus;   ///< Y (Pa)
  double poisson_ratio;    ///< nu (-)
  double restitution;      ///< e (-)
  double clip_attraction;  ///< 1: a net attractive force is set to zero (LIGGGHTS limitForce)

  static std::array<ParamInfo<Hertz>, 4> table() {
    return {{{"youngs_modulus", "Pa", 1.0, 1e13, kUnset, "Young's modulus Y", &Hertz::youngs_modulus},
             {"poisson_ratio", "-", 0.0, 0.499, 0.3, "Poisson's ratio nu", &Hertz::poisson_ratio},
             {"restitution", "-", 1e-6, 1.0, 0.5, "coefficient of restitution e", &Hertz::restitution},
             {"clip_attraction", "0/1", 0, 1, 0, "set a net attractive force to zero",
              &Hertz::clip_attraction}}};
  }
  void validate(const std::string& where) const {
    if (!is_set(youngs_modulus)) throw InputError(where + ".youngs_modulus", "required");
  }
  double y_star() const { return youngs_modulus / (2.0 * (1.0 - poisson_ratio * poisson_ratio)); }
  double g_star() const {
    return youngs_modulus / (4.0 * (2.0 - poisson_ratio) * (1.0 + poisson_ratio));
  }
  double beta() const {
    const double l = std::log(restitution);
    return l / std::sqrt(l * l + M_PI * M_PI);
  }
  /// Stiffness at an overlap of 1 % of the radius, used only for the sqrt(m/k) time-step check.
  double max_stiffness(double r_eff) const { return 2.0 * y_star() * std::sqrt(0.5 * r_eff * 0.01 * r_eff); }

  NormalResult force(const PairInput& in, double* /*history*/) const {
    constexpr double kSqrtFiveSixths = 0.91287092917527685576;
    const double root = std::sqrt(in.r_star * in.delta);
    const double ys = y_star();
    const double s_n = 2.0 * ys * root;
    NormalResult r;
    r.k_ref = 8.0 * g_star() * root;
    r.gamma_n = -2.0 * kSqrtFiveSixths * beta() * std::sqrt(s_n * in.m_star);
    r.fn = (4.0 / 3.0) * ys * root * in.delta + r.gamma_n * in.vn;
    if (clip_attraction != 0.0 && r.fn < 0.0) r.fn = 0.0;
    return r;
  }
};

}  // namespace demcal::contact::normal
