#pragma once
// confined_compression (seed 000 §2.7.2, eq. 31-33; seed 001 §3.2.1, eq. 19): a bed in a
// cylindrical die loaded by a stress-servo piston to max_stress, unloaded to min_stress and
// reloaded `cycles` times, then unloaded to final_stress.
#include <array>

#include "core/lab/bed.hpp"
#include "core/lab/lab_test.hpp"

namespace demcal::lab {

/// Piston-servo settings shared by confined_compression, tensile and wall_friction.
/// Speeds in m/s and gains in m/s per Pa are simulated values; 0 = automatic (see docs).
#define DEMCAL_SERVO_SETTINGS(S)                                                                 \
  {"servo_max_speed",                                                                            \
   "m/s",                                                                                        \
   0.0,                                                                                          \
   100.0,                                                                                        \
   0.0,                                                                                          \
   "piston speed limit; 0 = from an inertial number of 2e-3 at the largest stress",              \
   &S::servo_max_speed},                                                                         \
      {"servo_kp",  "m/s/Pa",                                                                    \
       0.0,         1e3,                                                                         \
       0.0,         "proportional gain; 0 = full speed at an error equal to the largest stress", \
       &S::servo_kp},                                                                            \
      {"servo_ki", "m/s/(Pa s)", 0.0, 1e6, 0.0, "integral gain", &S::servo_ki},                  \
      {"servo_kd", "m/s/(Pa/s)", 0.0, 1e3, 0.0, "derivative gain", &S::servo_kd},                \
      {"servo_tolerance",                                                                        \
       "-",                                                                                      \
       1e-4,                                                                                     \
       0.5,                                                                                      \
       0.02,                                                                                     \
       "stress counted as reached within this fraction of the target (at least 0.2 % of the "    \
       "largest stress)",                                                                        \
       &S::servo_tolerance},                                                                     \
      {"hold_steps",  "-", 10,                                                                   \
       1e7,           400, "steps over which the mean stress must be within tolerance",          \
       &S::hold_steps},                                                                          \
      {"servo_inertial_number",                                                                  \
       "-",                                                                                      \
       1e-5,                                                                                     \
       0.1,                                                                                      \
       2e-3,                                                                                     \
       "inertial number of the wall at its target (quasi-static; docs/lab-tests.md)",            \
       &S::servo_inertial_number},                                                               \
      {"approach_inertial_number",                                                               \
       "-",                                                                                      \
       0.0,                                                                                      \
       0.1,                                                                                      \
       0.0,                                                                                      \
       "inertial number of the approach far from the target; 0 = no approach (the default: it "  \
       "changes the cycle stiffnesses, docs/lab-tests.md)",                                      \
       &S::approach_inertial_number},                                                            \
  {                                                                                              \
    "max_phase_time", "s", 0.0, 1e4, 0.0,                                                        \
        "simulated time limit of one servo phase; 0 = by the rule of docs/lab-tests.md",         \
        &S::max_phase_time                                                                       \
  }

struct ConfinedCompressionSettings {
  static constexpr const char* kName = "confined_compression";
  double particles, time_step_safety, max_stress, min_stress, final_stress, cycles,
      wall_stiffness_factor;
  double servo_max_speed, servo_kp, servo_ki, servo_kd, servo_tolerance, hold_steps, max_phase_time,
      servo_inertial_number, approach_inertial_number;

  static std::array<contact::ParamInfo<ConfinedCompressionSettings>, 16> table() {
    using S = ConfinedCompressionSettings;
    return {{{"particles", "-", 20, 1e7, 300, "number of particles", &S::particles},
             {"time_step_safety", "-", 0.01, 1.0, 0.2,
              "time step as a fraction of the critical one", &S::time_step_safety},
             {"max_stress", "Pa", 1.0, 1e9, 15000.0, "load stress (real; seed 000: 15 kPa)",
              &S::max_stress},
             {"min_stress", "Pa", 0.0, 1e9, 500.0, "unload stress of the cycles (real; 0.5 kPa)",
              &S::min_stress},
             {"final_stress", "Pa", 0.0, 1e9, 100.0, "stress of the final unload (real)",
              &S::final_stress},
             {"cycles", "-", 1, 50, 5, "unload-reload cycles after the first load", &S::cycles},
             {"wall_stiffness_factor", "-", 0.01, 1e4, 30.0,
              "piston and bottom stiffness over the particle stiffness (seed 000: 30)",
              &S::wall_stiffness_factor},
             DEMCAL_SERVO_SETTINGS(S)}};
  }
  void finalize(const std::string& where) {
    if (min_stress >= max_stress) throw InputError(where + ".min_stress", "must be < max_stress");
  }
};

/// The servo settings a test exposes (DEMCAL_SERVO_SETTINGS), 0 = automatic where documented.
struct ServoRequest {
  double max_speed, kp, ki, kd, tolerance, hold_steps, max_phase_time, inertial_number,
      approach_inertial_number;
};
template <class S>
ServoRequest servo_request(const S& s) {
  return {s.servo_max_speed,         s.servo_kp,   s.servo_ki,       s.servo_kd,
          s.servo_tolerance,         s.hold_steps, s.max_phase_time, s.servo_inertial_number,
          s.approach_inertial_number};
}

/// Servo settings from the exposed values: automatic speed limit (the inertial number
/// I = v/h d sqrt(rho/sigma) at `stress_max`), gains, tolerance, hold and time limits, and the
/// approach (docs/lab-tests.md, "Servo phases").
ServoSettings make_servo(const sim::World& world, double bed_height, double stress_max,
                         const ServoRequest& request);

LabTestInfo confined_compression_info();  ///< in catalog.cpp
LabOutput run_confined_compression(const MaterialModel& material, const Settings& settings,
                                   const RunOptions& options);

}  // namespace demcal::lab
