#pragma once
// The settings of the compaction lab test as a campaign names them, and its catalogue entry:
// metadata the coordinator validates with, no physics (the runner: core/lab/compaction.cpp).
#include <array>
#include <cstddef>
#include <string>

#include "core/model/catalog.hpp"

namespace demcal::lab {

struct CompactionSettings {
  static constexpr const char* kName = "compaction";
  double particles;
  double phi_start;     ///< solid fraction of the random fill
  double phi_max;       ///< the last target
  double points;        ///< targets, evenly spaced above phi_start up to phi_max
  double strain_rate;   ///< linear strain of the cell per critical time (quasi-static: << 1)
  double hold;          ///< hold at each target, in critical times
  double probe_strain;  ///< axial strain of the constant-volume shear probe at phi_max; 0: none
  double yield_probes;  ///< 1: unload to the reference state and probe yield along five paths
  double unload_ratio;  ///< the reference state's pressure over the one held at phi_max
  double yield_strain;  ///< equivalent plastic strain at yield (seed 004 eq. 2.11)
  double time_step_safety;

  static std::array<contact::ParamInfo<CompactionSettings>, 11> table() {
    using S = CompactionSettings;
    return {{{"particles", "-", 20, 1e6, 300, "number of particles (bodies)", &S::particles},
             {"phi_start", "-", 0.05, 0.3, 0.2, "solid fraction of the random fill", &S::phi_start},
             {"phi_max", "-", 0.36, 0.9, 0.7, "last target solid fraction", &S::phi_max},
             {"points", "-", 1, 50, 8,
              "targets held and read, evenly spaced above phi_start up to phi_max", &S::points},
             {"strain_rate", "-", 1e-7, 1e-2, 1e-5,
              "linear strain of the cell per critical time sqrt(m/k) (quasi-static: << 1)",
              &S::strain_rate},
             {"hold", "-", 10, 1e5, 200, "hold at each target, in critical times", &S::hold},
             {"probe_strain", "-", 0.0, 0.5, 0.1,
              "axial strain of the constant-volume shear probe from phi_max (0: no probe)",
              &S::probe_strain},
             {"yield_probes", "-", 0.0, 1.0, 1,
              "1: unload to the reference state and probe yield along five strain paths; 0: none",
              &S::yield_probes},
             {"unload_ratio", "-", 0.01, 0.9, 0.1,
              "pressure of the reference state over the one held at phi_max", &S::unload_ratio},
             {"yield_strain", "-", 1e-4, 0.05, 2e-3,
              "equivalent plastic strain at yield (seed 004 eq. 2.11: 0.002)", &S::yield_strain},
             {"time_step_safety", "-", 0.01, 1.0, 0.2,
              "time step as a fraction of the critical one", &S::time_step_safety}}};
  }
  static std::vector<SettingsRule<CompactionSettings>> rules() {
    using S = CompactionSettings;
    // phi_max > phi_start holds by their ranges.
    return {{"yield_probes",
             "must be 0 or 1",
             [](const S& s) { return s.yield_probes == 0.0 || s.yield_probes == 1.0; },
             {{"yield_probes", 0.5}}}};
  }
  void finalize(const std::string& where) { check_rules(*this, where); }
};

/// The compaction lab test (seed 004 §2.3-2.4, §3.1): its catalogue entry here, its runner in
/// core/lab/compaction.cpp.
struct CompactionTest {
  using SettingsType = CompactionSettings;
  /// Its periodic cell is filled at random and compacted: it has no bed to prepare.
  static std::vector<PreparationMethod> preparations() { return {PreparationMethod::kPour}; }
  static LabTestInfo info() {
    return {
        "compaction",
        "fully periodic cell filled at random and compacted by shrinking it affinely through "
        "target solid fractions, held at each; contact stress tensor (Love-Weber), "
        "pressure-density curve, a constant-volume shear probe from the last, and yield probes "
        "along five strain paths from an unloaded reference state with the modified Cam-clay "
        "ellipse fitted to their yield points",
        "seed 004 §2.3-2.4, §3.1",
        {{"jamming_fraction", "-",
          "solid fraction at which the contact pressure of the compression first exceeds 1e-2 of "
          "the final held pressure"},
         {"final_pressure", "kPa", "mean contact stress p = tr(sigma) / 3 held at phi_max"},
         {"final_coordination_number", "-", "contacts per body at phi_max"},
         {"peak_stress_ratio", "-",
          "yield: the largest q / p of the constant-volume axisymmetric shear probe from "
          "phi_max"},
         {"steady_stress_ratio", "-", "mean q / p over the last fifth of the probe"},
         {"isotropic_yield_pressure", "kPa",
          "p at yield of the isotropic reload from the reference state (seed 004 eq. 2.11)"},
         {"yield_cap_pressure", "kPa",
          "p_c of the modified Cam-clay ellipse q^2 = M^2 p (p_c - p) fitted to the yield points"},
         {"yield_slope", "-", "M of that ellipse: the critical state stress ratio q / p"}},
        settings_docs<CompactionSettings>()};
  }
  static LabOutput run(const MaterialModel& material, const Settings& settings,
                       const RunOptions& options);
};

}  // namespace demcal::lab
