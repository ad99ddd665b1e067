#pragma once
// Van der Waals attraction between spheres after Hamaker (seed 000 eq. 12-15, Parteli et al. 2014):
//   D = -delta (surface distance, eq. 14),  r_eff = 2 r_i r_j / (r_i + r_j)  (eq. 13)
//   F_vdw = A_H r_eff / (6 D_min^2)  if D < D_min   (includes every overlapping contact)
//           A_H r_eff / (6 D^2)      if D_min <= D <= D_max
//           0                        if D > D_max
// The force acts beyond contact up to D_max, so the neighbour search range includes D_max.
// It is returned as a magnitude; the law subtracts it from the normal force (eq. 15).
// History: none.
#include <array>

#include "core/contact/pair.hpp"
#include "core/contact/param_table.hpp"

namespace demcal::contact::cohesion {

struct VanDerWaals {
  static constexpr const char* kName = "van_der_waals";

  double hamaker;  ///< A_H (J)
  double d_min;    ///< D_min (m)
  double d_max;    ///< D_max (m)

  static std::array<ParamInfo<VanDerWaals>, 3> table() {
    return {
        {{"hamaker", "J", 0.0, 1e-10, kUnset, "Hamaker constant A_H", &VanDerWaals::hamaker},
         {"d_min", "m", 1e-12, 1.0, 4e-10, "minimum surface distance D_min", &VanDerWaals::d_min},
         {"d_max", "m", 1e-12, 1.0, kUnset, "cut-off surface distance D_max",
          &VanDerWaals::d_max}}};
  }
  void finalize(const std::string& where) {
    if (!is_set(hamaker)) throw InputError(where + ".hamaker", "required");
    if (!is_set(d_max)) throw InputError(where + ".d_max", "required");
    if (d_max <= d_min) throw InputError(where + ".d_max", "must exceed d_min");
  }
  double range() const { return d_max; }

  double force(const PairInput& in) const {
    const double d = -in.delta;
    if (d > d_max) return 0.0;
    const double dd = d < d_min ? d_min : d;
    return hamaker * 2.0 * in.r_star / (6.0 * dd * dd);
  }
  /// The attraction at contact and in every overlap: A_H r_eff / (6 D_min^2) (N).
  double contact_force(double r_eff) const { return hamaker * r_eff / (6.0 * d_min * d_min); }
  /// The work the attraction does on a pair coming from D_max to D_min (J):
  /// integral of A_H r_eff / (6 D^2) dD = A_H r_eff / 6 (1 / D_min - 1 / D_max).
  double approach_work(double r_eff) const {
    return hamaker * r_eff / 6.0 * (1.0 / d_min - 1.0 / d_max);
  }
};

}  // namespace demcal::contact::cohesion
