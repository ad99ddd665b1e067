#pragma once
// The settings of the packing lab test as a campaign names them, and its catalogue entry: metadata
// the coordinator validates with, no physics (the runner: core/lab/packing.cpp).
#include <array>
#include <cmath>
#include <cstddef>
#include <string>

#include "core/model/catalog.hpp"

namespace demcal::lab {

struct PackingSettings {
  static constexpr const char* kName = "packing";
  double particles;
  double time_step_safety;
  double
      wall_margin;  ///< sampling volume keeps this many largest diameters from die, floor and top
  double cut_fraction;  ///< bed cut at this fraction of its height

  static std::array<contact::ParamInfo<PackingSettings>, 4> table() {
    using S = PackingSettings;
    return {{{"particles", "-", 20, 1e7, 300, "number of particles", &S::particles},
             {"time_step_safety", "-", 0.01, 1.0, 0.2,
              "time step as a fraction of the critical one", &S::time_step_safety},
             {"wall_margin", "-", 0.0, 10.0, 1.0,
              "distance of the sampling volume from the walls and the top, in largest diameters",
              &S::wall_margin},
             {"cut_fraction", "-", 0.1, 1.0, 1.0,
              "particles above this fraction of the settled bed height are removed",
              &S::cut_fraction}}};
  }
  void finalize(const std::string&) {}
};

/// The radius of the die a die test builds a bed of `solid_volume` in when it does not fix one:
/// a settled bed of solid fraction 0.6 as high as it is wide, pi R^2 2R 0.6 = solid volume.
inline double die_radius_for(double solid_volume) {
  return std::cbrt(solid_volume / (0.6 * 2.0 * M_PI));
}

/// The packing lab test (seed 000 §2.7.1, §3.1): its catalogue entry here, its runner in
/// core/lab/packing.cpp.
struct PackingTest {
  using SettingsType = PackingSettings;
  /// Its die beds are built by any preparation (core/lab/bed.hpp).
  static std::vector<PreparationMethod> preparations() {
    return {kPreparationMethods.begin(), kPreparationMethods.end()};
  }
  static LabTestInfo info() {
    return {
        "packing",
        "bed built in a cylindrical die by the material's preparation and settled; solid fraction "
        "and coordination number in a sampling volume away from the walls",
        "seed 000 §2.7.1, §3.1",
        {{"solid_fraction", "-", "solid volume over sampling volume"},
         {"coordination_number", "-",
          "mean number of touching particles (clumps: bodies) per particle in the sampling "
          "volume"}},
        settings_docs<PackingSettings>()};
  }
  /// Checks that the bed its particles make leaves a sampling volume `wall_margin` largest
  /// diameters from die, floor and top (packing_bed.cpp); returns the particle count.
  static std::size_t admit(const MaterialModel& material, const PackingSettings& s,
                           const std::string& where);
  static LabOutput run(const MaterialModel& material, const Settings& settings,
                       const RunOptions& options);
};

}  // namespace demcal::lab
