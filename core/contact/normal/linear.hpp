#pragma once
// Linear spring-dashpot normal force (seed 001 eq. 3-5):
//   fn = kn delta + gamma_n vn,   gamma_n = 2 xi sqrt(m* kn)
// with the damping applied on approach only (seed 001 eq. 4) or throughout the contact.
// With damping throughout and no clipping the restitution coefficient is
//   e = exp(-pi xi / sqrt(1 - xi^2)),  contact time t_c = pi / sqrt(kn/m* (1 - xi^2)).
// History: none.
#include <array>
#include <cmath>

#include "core/contact/pair.hpp"
#include "core/contact/param_table.hpp"

namespace demcal::contact::normal {

struct Linear {
  static constexpr const char* kName = "linear";
  static constexpr int kHistory = 0;

  double kn;                  ///< normal stiffness (N/m)
  double damping_ratio;       ///< xi, fraction of critical damping (-)
  double damp_approach_only;  ///< 1: seed 001 eq. 4 (no damping while separating); 0: always
  double clip_attraction;     ///< 1: a net attractive normal force is set to zero

  static std::array<ParamInfo<Linear>, 4> table() {
    return {{{"kn", "N/m", 1e-12, 1e15, kUnset, "normal spring stiffness", &Linear::kn},
             {"damping_ratio", "-", 0.0, 0.999, 0.0, "fraction of critical damping xi",
              &Linear::damping_ratio},
             {"damp_approach_only", "0/1", 0, 1, 1, "damp only while approaching (seed 001 eq. 4)",
              &Linear::damp_approach_only},
             {"clip_attraction", "0/1", 0, 1, 1, "set a net attractive force to zero",
              &Linear::clip_attraction}}};
  }
  void finalize(const std::string& where) {
    if (!is_set(kn)) throw InputError(where + ".kn", "required");
  }
  double max_stiffness(double /*r_eff*/) const { return kn; }
  /// The overlap at which a fresh contact's spring carries `force` (N): force / kn.
  double overlap_at(double force, double /*r_eff*/) const { return force / kn; }

  NormalResult force(const PairInput& in, double* /*history*/) const {
    NormalResult r;
    r.k_ref = kn;
    r.gamma_n = 2.0 * damping_ratio * std::sqrt(in.m_star * kn);
    const bool damp = damp_approach_only == 0.0 || in.vn > 0.0;
    r.fn = kn * in.delta + (damp ? r.gamma_n * in.vn : 0.0);
    if (clip_attraction != 0.0 && r.fn < 0.0) r.fn = 0.0;
    r.k_step = kn;
    return r;
  }
};

}  // namespace demcal::contact::normal
