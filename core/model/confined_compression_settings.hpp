#pragma once
// The settings of the confined_compression lab test as a campaign names them, and its catalogue
// entry: metadata the coordinator validates with, no physics (the runner:
// core/lab/confined_compression.cpp).
#include <array>
#include <cstddef>
#include <string>

#include "core/model/catalog.hpp"
#include "core/model/piston_settings.hpp"

namespace demcal::lab {

struct ConfinedCompressionSettings : PistonServoSettings {
  static constexpr const char* kName = "confined_compression";
  double particles, time_step_safety, max_stress, min_stress, final_stress, cycles,
      wall_stiffness_factor;

  static std::array<contact::ParamInfo<ConfinedCompressionSettings>, 16> table() {
    using S = ConfinedCompressionSettings;
    return with_piston_rows(std::array<contact::ParamInfo<S>, 7>{
        {{"particles", "-", 20, 1e7, 300, "number of particles", &S::particles},
         {"time_step_safety", "-", 0.01, 1.0, 0.2, "time step as a fraction of the critical one",
          &S::time_step_safety},
         {"max_stress", "Pa", 1.0, 1e9, 15000.0, "load stress (real; seed 000: 15 kPa)",
          &S::max_stress},
         {"min_stress", "Pa", 0.0, 1e9, 500.0, "unload stress of the cycles (real; 0.5 kPa)",
          &S::min_stress},
         {"final_stress", "Pa", 0.0, 1e9, 100.0, "stress of the final unload (real)",
          &S::final_stress},
         {"cycles", "-", 1, 50, 5, "unload-reload cycles after the first load", &S::cycles},
         {"wall_stiffness_factor", "-", 0.01, 1e4, 30.0,
          "piston and bottom stiffness over the particle stiffness (seed 000: 30)",
          &S::wall_stiffness_factor}}});
  }
  static std::vector<SettingsRule<ConfinedCompressionSettings>> rules() {
    return {{"min_stress",
             "must be < max_stress",
             [](const ConfinedCompressionSettings& s) { return s.min_stress < s.max_stress; },
             {{"min_stress", 10.0}, {"max_stress", 5.0}}}};
  }
  void finalize(const std::string& where) { check_rules(*this, where); }
};

/// The confined_compression lab test (seed 000 §2.7.2, eq. 31-33; seed 001 §3.2.1, eq. 19): its
/// catalogue entry here, its runner in core/lab/confined_compression.cpp.
struct ConfinedCompressionTest {
  using SettingsType = ConfinedCompressionSettings;
  /// Its die beds are built by any preparation (core/lab/bed.hpp).
  static std::vector<PreparationMethod> preparations() {
    return {kPreparationMethods.begin(), kPreparationMethods.end()};
  }
  static LabTestInfo info() {
    return {
        "confined_compression",
        "bed in a cylindrical die loaded by a stress-servo piston to 15 kPa, unloaded to 0.5 kPa "
        "and reloaded five times, then unloaded",
        "seed 000 §2.7.2 (eq. 31-33); seed 001 §3.2.1 (eq. 19)",
        {{"compressibility", "%", "(h0 - h1) / h0 at the first load (seed 000 eq. 31)"},
         {"k_load", "MPa",
          "mean reload bulk stiffness (sigma_max - sigma_min) h1 / (h_unloaded - h_loaded) "
          "(seed 000 eq. 32)"},
         {"k_unload", "MPa",
          "mean unload bulk stiffness (sigma_max - sigma_min) h1 / (h_unloaded - h_loaded_before) "
          "(seed 000 eq. 33)"},
         {"final_solid_fraction", "-", "solid fraction after the final unload"},
         {"confined_modulus", "MPa",
          "E' = (sigma_max - sigma_min) / (eps_max - eps_min) of the last cycle, eps = "
          "(h0 - h) / h0 (seed 001 eq. 19)"}},
        settings_docs<ConfinedCompressionSettings>(),
        {},
        {},
        Consolidation{"max_stress", {"min_stress"}, "final_solid_fraction"}};
  }
  static LabOutput run(const MaterialModel& material, const Settings& settings,
                       const RunOptions& options);
};

}  // namespace demcal::lab
