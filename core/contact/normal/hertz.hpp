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
  /// The step's accuracy comes from the Rayleigh time; k_step only bounds its stability.
  static constexpr bool kAccuracyFromOwnBound = true;

  double youngs_modulus;   ///< Y (Pa)
  double poisson_ratio;    ///< nu (-)
  double restitution;      ///< e (-)
  double clip_attraction;  ///< 1: a net attractive force is set to zero (LIGGGHTS limitForce)

  static std::array<ParamInfo<Hertz>, 4> table() {
    return {
        {{"youngs_modulus", "Pa", 1.0, 1e13, kUnset, "Young's modulus Y", &Hertz::youngs_modulus},
         {"poisson_ratio", "-", 0.0, 0.499, 0.3, "Poisson's ratio nu", &Hertz::poisson_ratio},
         {"restitution", "-", 1e-6, 1.0, 0.5, "coefficient of restitution e", &Hertz::restitution},
         {"clip_attraction", "0/1", 0, 1, 0, "set a net attractive force to zero",
          &Hertz::clip_attraction}}};
  }
  void finalize(const std::string& where) {
    if (!is_set(youngs_modulus)) throw InputError(where + ".youngs_modulus", "required");
    y_star = youngs_modulus / (2.0 * (1.0 - poisson_ratio * poisson_ratio));
    g_star = youngs_modulus / (4.0 * (2.0 - poisson_ratio) * (1.0 + poisson_ratio));
    const double l = std::log(restitution);
    const double beta = l / std::sqrt(l * l + M_PI * M_PI);
    constexpr double kSqrtFiveSixths = 0.91287092917527685576;
    damping_factor = -2.0 * kSqrtFiveSixths * beta * std::sqrt(2.0 * y_star);
  }
  /// Stiffness at an overlap of 1 % of the radius, used only for the sqrt(m/k) time-step check.
  double max_stiffness(double r_eff) const {
    return 2.0 * y_star * std::sqrt(0.5 * r_eff * 0.01 * r_eff);
  }

  /// The overlap at which the elastic force 4/3 Y* sqrt(R*) delta^(3/2), R* = r_eff / 2, is
  /// `force` (N).
  double overlap_at(double force, double r_eff) const {
    const double x = 3.0 * force / (4.0 * y_star * std::sqrt(0.5 * r_eff));
    return std::cbrt(x * x);
  }

  // Derived by finalize(): Y*, G*, and -2 sqrt(5/6) beta sqrt(2 Y*) so that
  // gamma_n = damping_factor sqrt(sqrt(R* delta) m*).
  double y_star = 0.0, g_star = 0.0, damping_factor = 0.0;

  NormalResult force(const PairInput& in, double* /*history*/) const {
    const double root = std::sqrt(in.r_star * in.delta);
    NormalResult r;
    r.k_ref = 8.0 * g_star * root;
    r.gamma_n = damping_factor * std::sqrt(root * in.m_star);
    r.fn = (4.0 / 3.0) * y_star * root * in.delta + r.gamma_n * in.vn;
    if (clip_attraction != 0.0 && r.fn < 0.0) r.fn = 0.0;
    r.k_step = 2.0 * y_star * root;  // d/d(delta) of 4/3 Y* sqrt(R*) delta^(3/2)
    return r;
  }
};

}  // namespace demcal::contact::normal
