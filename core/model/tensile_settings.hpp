#pragma once
// The settings of the tensile lab test as a campaign names them, and its catalogue entry: metadata
// the coordinator validates with, no physics (the runner: core/lab/tensile.cpp).
#include <array>
#include <cstddef>
#include <string>

#include "core/model/catalog.hpp"
#include "core/model/piston_settings.hpp"

namespace demcal::lab {

struct TensileSettings : PistonServoSettings {
  static constexpr const char* kName = "tensile";
  double particles, time_step_safety, consolidation_stress, min_stress, final_stress, cycles,
      unload_stress, pull_speed, pull_distance, wall_stiffness_factor, wall_hamaker_factor,
      wall_k2_factor;

  static std::array<contact::ParamInfo<TensileSettings>, 21> table() {
    using S = TensileSettings;
    return with_piston_rows(std::array<contact::ParamInfo<S>, 12>{
        {{"particles", "-", 20, 1e7, 300, "number of particles", &S::particles},
         {"time_step_safety", "-", 0.01, 1.0, 0.2, "time step as a fraction of the critical one",
          &S::time_step_safety},
         {"consolidation_stress", "Pa", 1.0, 1e9, 15000.0,
          "max_stress of the confined compression that conditions the bed (real; seed 000: "
          "15 kPa)",
          &S::consolidation_stress},
         {"min_stress", "Pa", 0.0, 1e9, 500.0,
          "unload stress of the conditioning's cycles (real; as confined_compression)",
          &S::min_stress},
         {"final_stress", "Pa", 0.0, 1e9, 100.0,
          "stress of the conditioning's final unload (real; as confined_compression)",
          &S::final_stress},
         {"cycles", "-", 1, 50, 5,
          "unload-reload cycles of the conditioning (as confined_compression)", &S::cycles},
         {"unload_stress", "Pa", 0.0, 1e9, 50.0,
          "stress the adhesive piston is unloaded to before pulling (real; 'close to zero')",
          &S::unload_stress},
         {"pull_speed", "m/s", 0.0, 100.0, 0.0,
          "constant pull-off speed; 0 = half the servo speed limit", &S::pull_speed},
         {"pull_distance", "-", 0.1, 100.0, 2.0, "pull-off travel in mean particle diameters",
          &S::pull_distance},
         {"wall_stiffness_factor", "-", 0.01, 1e4, 30.0,
          "piston and bottom stiffness over the particle stiffness (seed 000: 30)",
          &S::wall_stiffness_factor},
         {"wall_hamaker_factor", "-", 0.0, 1e6, 0.0,
          "A_H,wall / A_H of piston and bottom; 0 = seed 000 eq. 34 with r_real in [5, 50] um",
          &S::wall_hamaker_factor},
         {"wall_k2_factor", "-", 0.0, 1e4, 0.0,
          "k2,wall / k2 of piston and bottom; 0 = seed 000 eq. 35 with r_real in [5, 50] um",
          &S::wall_k2_factor}}});
  }
  static std::vector<SettingsRule<TensileSettings>> rules() {
    return {{"min_stress",
             "must be < consolidation_stress",
             [](const TensileSettings& s) { return s.min_stress < s.consolidation_stress; },
             {{"min_stress", 10.0}, {"consolidation_stress", 5.0}}}};
  }
  void finalize(const std::string& where) { check_rules(*this, where); }
};

/// Seed 000 eq. 34: A_H,wall / A_H = 10 + 90 (r_real - 5) / 45, r_real in um (clamped to the
/// seed's radius range 5-50 um, where the relation was fitted).
double wall_hamaker_ratio_eq34(double r_real_um);
/// Seed 000 eq. 35: k2,wall / k2 = 10 + 5 (r_real - 5) / 45, r_real in um (clamped likewise).
double wall_k2_ratio_eq35(double r_real_um);

/// The tensile lab test (seed 000 §2.7.3, eq. 34-35): its catalogue entry here, its runner in
/// core/lab/tensile.cpp.
struct TensileTest {
  using SettingsType = TensileSettings;
  /// Its die beds are built by any preparation (core/lab/bed.hpp).
  static std::vector<PreparationMethod> preparations() {
    return {kPreparationMethods.begin(), kPreparationMethods.end()};
  }
  static LabTestInfo info() {
    return {"tensile",
            "bed conditioned in the die by the confined compression protocol, then held by an "
            "adhesive piston and bottom (eq. 34-35), unloaded, and pulled apart at constant slow "
            "speed inside a frictionless non-cohesive die wall",
            "seed 000 §2.7.3 (eq. 34-35, Fig. 10-11)",
            {{"tensile_strength", "kPa",
              "peak tensile stress on the piston less the weight of the powder stuck to it, over "
              "the piston area"}},
            settings_docs<TensileSettings>(),
            {},
            "confined_compression",
            Consolidation{"consolidation_stress", {"min_stress"}}};
  }
  static LabOutput run(const MaterialModel& material, const Settings& settings,
                       const RunOptions& options);
};

}  // namespace demcal::lab
