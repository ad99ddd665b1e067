#pragma once
// Coarse-graining: the explicit transform from real to simulated parameters.
//   Kottlan 2018 (seed 000 eq. 24-30), scale factor SF:
//     r = SF r_real, rho = rho_real / SF^3, Y = Y_real / SF^2, A_H = SF A_H,real,
//     D_min = SF D_min,real, D_max = SF D_max,real, sigma = sigma_real / SF^2
//     (so k1 = 4/3 Y r sqrt(delta') scales as 1/SF, and a given stiffness does too).
//   Tiscar 2019 (seed 001 eq. 15-18), scale factor lambda = N_real / N_sim = (R_s / R_r)^3:
//     R_s = lambda^(1/3) R_r, rho_s = rho_r / lambda (eq. 17, particle mass kept),
//     k_s = lambda^(-1/3) k_r (eq. 18, relative overlap kept); by the same rule Y_s = lambda^(-2/3)
//     Y_r (k ~ Y R), stresses lambda^(-2/3) (the same forces on areas lambda^(2/3) larger), lengths
//     of cohesion lambda^(1/3), A_H lambda^(1/3).
// Parameters are scaled by their unit as declared in the model's parameter table.
#include <string>

#include "core/contact/contact_law.hpp"

namespace demcal::contact {

enum class ScalingLaw { kNone, kKottlan2018, kTiscar2019 };

struct ScaleFactors {
  double length = 1.0;     ///< radii, distances (m)
  double density = 1.0;    ///< (kg/m^3)
  double stiffness = 1.0;  ///< (N/m)
  double modulus = 1.0;    ///< Young's modulus (Pa)
  double stress = 1.0;     ///< applied stresses (Pa) of a lab test
  double hamaker = 1.0;    ///< (J)
  /// Durations of a lab test's protocol (s): sqrt(length) for both laws, whose masses and forces
  /// are those of the real system's similar bed (time^2 ~ length x mass / force).
  double time = 1.0;
};

/// The factors simulated / real for a law and its factor (SF or lambda).
ScaleFactors scale_factors(ScalingLaw law, double factor);
ScalingLaw scaling_law_from_name(const std::string& name, const std::string& where);
/// The name scaling_law_from_name reads.
std::string scaling_law_name(ScalingLaw law);

/// The simulated law: every parameter multiplied by the factor of its unit.
ContactLaw scale(const ContactLaw& law, const ScaleFactors& f);

}  // namespace demcal::contact
