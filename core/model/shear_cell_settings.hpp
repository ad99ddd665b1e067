#pragma once
// The settings of the shear_cell lab test as a campaign names them, and its catalogue entry:
// metadata the coordinator validates with, no physics (the runner: core/lab/shear_cell.cpp).
#include <array>
#include <cstddef>
#include <string>

#include "core/model/catalog.hpp"

namespace demcal::lab {

/// Normal stresses of the shear steps, seed 000 Table 3 (kPa); pre-shear at 3 kPa.
inline constexpr double kShearPreKPa = 3.0;
inline constexpr std::array<double, 5> kShearNormalKPa = {2.0, 1.75, 1.5, 1.25, 1.0};

struct ShearCellSettings {
  static constexpr const char* kName = "shear_cell";
  double particles;
  double vanes;
  double vane_height;       ///< in largest particle diameters
  double tip_speed;         ///< (m/s) of the vane tips in pre-shear; also the shear steps' limit
  double pre_shear_travel;  ///< least tip travel of the pre-shear, in diameters
  double max_pre_shear_travel;  ///< most tip travel of the pre-shear, in diameters
  double pre_shear_steadiness;  ///< steady: a third's mean shear stress within this of the last
  double stress_tolerance;      ///< a mean normal stress within this fraction of the target
  double consolidation_time;    ///< (s) per servo phase (re-consolidate, reduce)
  double torque_ramp_time;      ///< (s) for the set torque to reach twice the pre-shear torque
  double stress_scale;          ///< multiplies every normal stress (for coarse-grained beds)
  double time_step_safety;
  double vessel_friction;  ///< mu_s of the vessel wall (docs/lab-tests.md: 0)
  double floor_friction;   ///< mu_s of the floor (a rough floor holds the bed below the plane)
  double floor_rolling;    ///< CDT mu_r of the floor; 0: the material's wall law's rolling

  static std::array<contact::ParamInfo<ShearCellSettings>, 15> table() {
    return {
        {{"particles", "-", 20, 1e7, 500, "number of particles", &ShearCellSettings::particles},
         {"vanes", "-", 2, 36, 8, "vanes of the shear head", &ShearCellSettings::vanes},
         {"vane_height", "-", 0.5, 20, 2, "vane height in largest particle diameters",
          &ShearCellSettings::vane_height},
         {"tip_speed", "m/s", 1e-4, 1.0, 0.02,
          "vane tip speed of the pre-shear (and the speed limit of the torque control)",
          &ShearCellSettings::tip_speed},
         {"pre_shear_travel", "-", 0.5, 100, 5,
          "least vane tip travel of the pre-shear, in largest particle diameters; its last third "
          "is the steady flow's window",
          &ShearCellSettings::pre_shear_travel},
         {"max_pre_shear_travel", "-", 0.5, 1000, 30,
          "most vane tip travel of the pre-shear before it counts as not steady",
          &ShearCellSettings::max_pre_shear_travel},
         {"pre_shear_steadiness", "-", 0.001, 1, 0.05,
          "steady flow: the mean shear stress of the last window within this fraction of the "
          "window's before",
          &ShearCellSettings::pre_shear_steadiness},
         {"stress_tolerance", "-", 0.001, 0.5, 0.05,
          "the consolidation's and the pre-shear's mean normal stress within this fraction of "
          "sigma_pre",
          &ShearCellSettings::stress_tolerance},
         {"consolidation_time", "s", 0.005, 10, 0.05,
          "duration of each servo phase (re-consolidate at 3 kPa, reduce to sigma_x); the block "
          "the "
          "consolidation averages its stress over",
          &ShearCellSettings::consolidation_time},
         {"torque_ramp_time", "s", 0.01, 10, 0.3,
          "time for the set torque of a shear step to reach twice the pre-shear torque",
          &ShearCellSettings::torque_ramp_time},
         {"stress_scale", "-", 1e-3, 1e3, 1, "multiplies the normal stresses of seed 000 Table 3",
          &ShearCellSettings::stress_scale},
         {"time_step_safety", "-", 0.01, 1.0, 0.2, "time step as a fraction of the critical one",
          &ShearCellSettings::time_step_safety},
         {"vessel_friction", "-", 0.0, 10.0, 0.0,
          "mu_s of the vessel wall (0: it carries neither torque nor weight of the bed)",
          &ShearCellSettings::vessel_friction},
         {"floor_friction", "-", 0.0, 10.0, 1.0,
          "mu_s of the floor (rough: the bed below the shear plane is held by it)",
          &ShearCellSettings::floor_friction},
         {"floor_rolling", "-", 0.0, 10.0, 0.5,
          "CDT rolling resistance mu_r of the floor (0: the material's wall law's)",
          &ShearCellSettings::floor_rolling}}};
  }
  static std::vector<SettingsRule<ShearCellSettings>> rules() {
    return {
        {"max_pre_shear_travel",
         "must be >= pre_shear_travel",
         [](const ShearCellSettings& s) { return s.max_pre_shear_travel >= s.pre_shear_travel; },
         {{"pre_shear_travel", 10.0}, {"max_pre_shear_travel", 5.0}}}};
  }
  void finalize(const std::string& where) { check_rules(*this, where); }
};

/// The shear_cell lab test (seed 000 §2.7.4, Table 3, Fig. 12 and 23): its catalogue entry here,
/// its runner in core/lab/shear_cell.cpp.
struct ShearCellTest {
  using SettingsType = ShearCellSettings;
  /// Its bed is poured into the cell.
  static std::vector<PreparationMethod> preparations() { return {PreparationMethod::kPour}; }
  static LabTestInfo info() {
    return {
        "shear_cell",
        "FT4 standard shear test: vaned shear head (mesh) in a cylindrical vessel, normal stress "
        "applied by the container; pre-shear at 3 kPa, then yield under torque control at 2, "
        "1.75, 1.5, 1.25 and 1 kPa, each from the pre-sheared state; tau = 3 T / (2 pi R^3)",
        "seed 000 §2.7.4 (Table 3, Fig. 12, Fig. 23)",
        {{"pre_shear_stress", "kPa", "steady shear stress of the pre-shear at sigma_pre = 3 kPa"},
         {"yield_locus_slope", "-", "slope of the least-squares yield locus"},
         {"yield_locus_intercept", "kPa", "intercept (cohesion) of the yield locus"},
         {"ffc", "-",
          "flow function sigma_1 / sigma_c from the Mohr circles, at most 100 (100 without "
          "cohesion, 0 if inconsistent)"},
         {"effective_friction_angle", "deg",
          "angle of the origin line touching the consolidation circle (0 if inconsistent)"},
         {"mohr_consistent", "0/1",
          "0 when the pre-shear point lies above the yield locus (seed 000 Fig. 23b)"},
         {"unconfined_yield_strength", "kPa", "sigma_c of the Mohr circle through the origin"},
         {"major_consolidation_stress", "kPa",
          "sigma_1 of the circle through the pre-shear point touching the locus"}},
        settings_docs<ShearCellSettings>(),
        // the yield shear stress at each of kShearNormalKPa ('.' written 'p')
        {"pre_shear_normal_stress", "yield_shear_stress_2", "yield_shear_stress_1p75",
         "yield_shear_stress_1p5", "yield_shear_stress_1p25", "yield_shear_stress_1"}};
  }
  static LabOutput run(const MaterialModel& material, const Settings& settings,
                       const RunOptions& options);
};

}  // namespace demcal::lab
