#pragma once
// The settings of the hopper lab test as a campaign names them, and its catalogue entry: metadata
// the coordinator validates with, no physics (the runner: core/lab/hopper.cpp).
#include <array>
#include <cstddef>
#include <string>

#include "core/model/catalog.hpp"

namespace demcal::lab {

struct HopperSettings {
  static constexpr const char* kName = "hopper";
  double particles;
  double half_angle;  ///< (deg) from the vertical
  double outlet;      ///< slot width in largest particle diameters
  double depth;       ///< periodic slice depth in largest particle diameters
  double arch_time;   ///< (s) without discharge that counts as an arch
  double max_time;    ///< (s) of discharge simulated at most
  double time_step_safety;

  static std::array<contact::ParamInfo<HopperSettings>, 7> table() {
    return {
        {{"particles", "-", 20, 1e7, 400, "number of particles", &HopperSettings::particles},
         {"half_angle", "deg", 5, 60, 20, "hopper wall angle from the vertical",
          &HopperSettings::half_angle},
         {"outlet", "-", 1, 100, 6, "slot width in largest particle diameters",
          &HopperSettings::outlet},
         {"depth", "-", 1, 100, 3, "periodic slice depth in largest particle diameters",
          &HopperSettings::depth},
         {"arch_time", "s", 0.01, 10, 0.25,
          "time without any discharge after which the outlet counts as arched",
          &HopperSettings::arch_time},
         {"max_time", "s", 0.05, 100, 3, "longest discharge simulated", &HopperSettings::max_time},
         {"time_step_safety", "-", 0.01, 1.0, 0.2, "time step as a fraction of the critical one",
          &HopperSettings::time_step_safety}}};
  }
  void finalize(const std::string&) {}
};

/// The hopper lab test (seed 000 §2.7.6): its catalogue entry here, its runner in
/// core/lab/hopper.cpp.
struct HopperTest {
  using SettingsType = HopperSettings;
  /// Its bin is filled by any preparation but growth, which grows the die beds only.
  static std::vector<PreparationMethod> preparations() {
    return {PreparationMethod::kClusters, PreparationMethod::kRandomMotion,
            PreparationMethod::kTerminalVelocity, PreparationMethod::kPour};
  }
  static LabTestInfo info() {
    return {
        "hopper",
        "wedge hopper slice with periodic front and back: fill and settle with the gate closed, "
        "open it, discharge rate from the mass-time curve, arching, ratio to Beverloo's slot "
        "law (hydraulic-diameter form) W = (4 sqrt 2 / pi) C rho_b sqrt(g) L (b - k d)^1.5 with "
        "C = 0.58, k = 1.5, times Rose and Tanaka's factor (tan theta tan 45 deg)^-0.35 for walls "
        "steeper than 45 deg",
        "seed 000 §2.7.6",
        {{"discharge_rate", "kg/s", "slope of the discharged mass over time after start-up"},
         {"arched", "0/1", "1 when no particle left for arch_time before the hopper emptied"},
         {"beverloo_rate", "kg/s", "Beverloo's slot-form rate with the wall factor"},
         {"beverloo_ratio", "-", "discharge_rate over beverloo_rate"}},
        settings_docs<HopperSettings>(),
        {"discharged_fraction", "bulk_density"}};
  }
  static LabOutput run(const MaterialModel& material, const Settings& settings,
                       const RunOptions& options);
};

}  // namespace demcal::lab
