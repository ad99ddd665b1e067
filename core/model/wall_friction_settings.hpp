#pragma once
// The settings of the wall_friction lab test as a campaign names them, and its catalogue entry:
// metadata the coordinator validates with, no physics (the runner: core/lab/wall_friction.cpp).
#include <array>
#include <cstddef>
#include <string>

#include "core/model/catalog.hpp"
#include "core/model/piston_settings.hpp"

namespace demcal::lab {

struct WallFrictionSettings : PistonServoSettings {
  static constexpr const char* kName = "wall_friction";
  double particles, time_step_safety, stress_factor, rim_speed, rotation_diameters,
      wall_stiffness_factor, bottom_friction;

  static std::array<contact::ParamInfo<WallFrictionSettings>, 16> table() {
    using S = WallFrictionSettings;
    return with_piston_rows(std::array<contact::ParamInfo<S>, 7>{
        {{"particles", "-", 20, 1e7, 300, "number of particles", &S::particles},
         {"time_step_safety", "-", 0.01, 1.0, 0.2, "time step as a fraction of the critical one",
          &S::time_step_safety},
         {"stress_factor", "-", 1e-3, 1e3, 1.0,
          "multiplies the normal stresses 1, 1.25, 1.5, 1.75, 2, 3 kPa (real)", &S::stress_factor},
         {"rim_speed", "m/s", 0.0, 100.0, 0.0, "piston rim speed; 0 = twice the servo speed limit",
          &S::rim_speed},
         {"rotation_diameters", "-", 0.1, 1e3, 1.0,
          "rim travel per normal stress in mean diameters (torque averaged over its second "
          "half)",
          &S::rotation_diameters},
         {"wall_stiffness_factor", "-", 0.01, 1e4, 30.0,
          "piston and bottom stiffness over the particle stiffness (seed 000: 30)",
          &S::wall_stiffness_factor},
         {"bottom_friction", "-", 0.0, 10.0, 1.0,
          "friction coefficient of the container bottom, which holds the bed against the "
          "turning piston",
          &S::bottom_friction}}});
  }
  void finalize(const std::string&) {}
};

/// The normal stresses of seed 000 §2.7.5 (Pa, real).
inline const std::vector<double>& wall_friction_stresses() {
  static const std::vector<double> s = {1000, 1250, 1500, 1750, 2000, 3000};
  return s;
}
/// Wall shear stress from the torque on a disk of radius R: tau = 3 T / (2 pi R^3).
inline double shear_stress_from_torque(double torque, double radius) {
  return 3.0 * torque / (2.0 * M_PI * radius * radius * radius);
}
/// Slope of the least-squares line through the origin: sum(x y) / sum(x^2).
double slope_through_origin(const std::vector<double>& x, const std::vector<double>& y);
/// Two-point calibration (seed 000 §3.3.4): the particle-wall friction coefficient that the line
/// through (mu_a, phi_a) and (mu_b, phi_b) maps to `phi_target`.
double two_point_calibration(double mu_a, double phi_a, double mu_b, double phi_b,
                             double phi_target);

/// The wall_friction lab test (seed 000 §2.7.5, §3.3.4): its catalogue entry here, its runner in
/// core/lab/wall_friction.cpp.
struct WallFrictionTest {
  using SettingsType = WallFrictionSettings;
  /// Its die beds are built by any preparation (core/lab/bed.hpp).
  static std::vector<PreparationMethod> preparations() {
    return {kPreparationMethods.begin(), kPreparationMethods.end()};
  }
  static LabTestInfo info() {
    return {"wall_friction",
            "bed pressed by the container against a piston that turns at constant normal stress "
            "(1, 1.25, 1.5, 1.75, 2, 3 kPa); tau = 3 T / (2 pi R^3); regression through the origin",
            "seed 000 §2.7.5, §3.3.4",
            {{"wall_friction_angle", "deg",
              "atan of the slope of the wall shear stress over the normal stress, fitted through "
              "the origin"}},
            settings_docs<WallFrictionSettings>()};
  }
  static LabOutput run(const MaterialModel& material, const Settings& settings,
                       const RunOptions& options);
};

}  // namespace demcal::lab
