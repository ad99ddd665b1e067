#pragma once
// The settings of a stress-servo piston that the die tests expose (confined_compression, tensile,
// wall_friction): metadata only, so the catalogue can list them without the physics. A test's
// settings struct derives from PistonServoSettings and appends its table.
#include <array>
#include <cstddef>

#include "core/contact/param_table.hpp"

namespace demcal::lab {

/// Speeds in m/s and gains in m/s per Pa are simulated values; 0 = automatic (docs/lab-tests.md,
/// "Servo phases").
struct PistonServoSettings {
  double servo_max_speed, servo_kp, servo_ki, servo_kd, servo_tolerance, hold_steps,
      servo_inertial_number, approach_inertial_number, max_phase_time;

  /// The rows of these settings in the table of a test's settings struct S.
  template <class S>
  static std::array<contact::ParamInfo<S>, 9> table() {
    return {{{"servo_max_speed", "m/s", 0.0, 100.0, 0.0,
              "piston speed limit; 0 = from an inertial number of 2e-3 at the largest stress",
              &S::servo_max_speed},
             {"servo_kp", "m/s/Pa", 0.0, 1e3, 0.0,
              "proportional gain; 0 = full speed at an error equal to the largest stress",
              &S::servo_kp},
             {"servo_ki", "m/s/(Pa s)", 0.0, 1e6, 0.0, "integral gain", &S::servo_ki},
             {"servo_kd", "m/s/(Pa/s)", 0.0, 1e3, 0.0, "derivative gain", &S::servo_kd},
             {"servo_tolerance", "-", 1e-4, 0.5, 0.02,
              "stress counted as reached within this fraction of the target (at least 0.2 % of "
              "the largest stress)",
              &S::servo_tolerance},
             {"hold_steps", "-", 10, 1e7, 400,
              "steps over which the mean stress must be within tolerance", &S::hold_steps},
             {"servo_inertial_number", "-", 1e-5, 0.1, 2e-3,
              "inertial number of the wall at its target (quasi-static; docs/lab-tests.md)",
              &S::servo_inertial_number},
             {"approach_inertial_number", "-", 0.0, 0.1, 0.0,
              "inertial number of the approach far from the target; 0 = no approach (the "
              "default: it changes the cycle stiffnesses, docs/lab-tests.md)",
              &S::approach_inertial_number},
             {"max_phase_time", "s", 0.0, 1e4, 0.0,
              "simulated time limit of one servo phase; 0 = by the rule of docs/lab-tests.md",
              &S::max_phase_time}}};
  }
};

/// A test's own rows followed by its piston's.
template <class S, std::size_t N>
std::array<contact::ParamInfo<S>, N + 9> with_piston_rows(
    const std::array<contact::ParamInfo<S>, N>& own) {
  std::array<contact::ParamInfo<S>, N + 9> out{};
  const auto piston = PistonServoSettings::table<S>();
  for (std::size_t i = 0; i < N; ++i) out[i] = own[i];
  for (std::size_t i = 0; i < 9; ++i) out[N + i] = piston[i];
  return out;
}

}  // namespace demcal::lab
