#pragma once
// The settings of the rotating_drum lab test as a campaign names them, and its catalogue entry:
// metadata the coordinator validates with, no physics (the runner: core/lab/rotating_drum.cpp).
#include <array>
#include <cstddef>
#include <string>

#include "core/model/catalog.hpp"
#include "core/particles/size_distribution.hpp"

namespace demcal::lab {

/// The drum speeds of the area method (seed 001 §3.2.3), rpm of the seed's 100 mm drum.
inline constexpr std::array<int, 5> kDrumSpeeds = {4, 40, 80, 105, 116};

struct RotatingDrumSettings {
  static constexpr const char* kName = "rotating_drum";
  double diameter;        ///< (mm) inner drum diameter D, real (seed 001 §3.2.2: 100 mm)
  double length;          ///< (mm) drum depth W between the end plates, real (seed: 44 mm)
  double fill;            ///< filling degree (bulk volume over drum volume; seed: 43 %)
  double solid_fraction;  ///< solid fraction of the bulk the fill is counted in
  double rpm;             ///< drum speed of the dynamic angle of repose (seed: 4 rpm)
  double max_particles;   ///< resource limit on the particle count the geometry asks for
  double froude_scaling;  ///< 1: speeds keep the Froude number of the seed's 100 mm drum
  double speed_scale;     ///< multiplies every drum speed
  double angle_time;      ///< (s) at `rpm` (after the bed has turned to its angle)
  double area_time;       ///< (s) per speed of the area method
  double time_step_safety;

  static std::array<contact::ParamInfo<RotatingDrumSettings>, 11> table() {
    return {
        {{"diameter", "mm", 1, 5000, 100, "inner drum diameter D (seed 001: 100 mm)",
          &RotatingDrumSettings::diameter},
         {"length", "mm", 0.5, 5000, 44, "drum depth W between the end plates (seed 001: 44 mm)",
          &RotatingDrumSettings::length},
         {"fill", "-", 0.05, 0.9, 0.43,
          "filling degree: bulk volume over drum volume "
          "(seed 001: 43 %)",
          &RotatingDrumSettings::fill},
         {"solid_fraction", "-", 0.3, 0.74, 0.6,
          "solid fraction of the bulk: particles = fill pi D^2/4 W solid_fraction / mean "
          "particle volume (simulated sizes)",
          &RotatingDrumSettings::solid_fraction},
         {"rpm", "rpm", 0.1, 200, 4, "drum speed of the dynamic angle of repose (seed 001: 4 rpm)",
          &RotatingDrumSettings::rpm},
         {"max_particles", "-", 20, 1e8, 20000,
          "resource limit: a geometry asking for more particles is refused",
          &RotatingDrumSettings::max_particles},
         {"froude_scaling", "-", 0, 1, 1,
          "1: scale the rpm to keep the Froude number w^2 D / 2g of the seed's 100 mm drum "
          "(no change at D = 100 mm); 0: use the rpm as they are",
          &RotatingDrumSettings::froude_scaling},
         {"speed_scale", "-", 0.01, 100, 1, "multiplies every drum speed",
          &RotatingDrumSettings::speed_scale},
         {"angle_time", "s", 0.05, 100, 1.5,
          "time at `rpm` for the dynamic angle, after the bed has turned to its angle",
          &RotatingDrumSettings::angle_time},
         {"area_time", "s", 0.02, 100, 0.8, "time per speed of the area method",
          &RotatingDrumSettings::area_time},
         {"time_step_safety", "-", 0.01, 1.0, 0.2, "time step as a fraction of the critical one",
          &RotatingDrumSettings::time_step_safety}}};
  }
  void finalize(const std::string&) {}
};

/// The drum and its bed as the geometry decides them: the drum in real units, the particle count
/// from the fill and the simulated (coarse-grained) size distribution.
struct DrumBed {
  double radius = 0.0;          ///< (m)
  double length = 0.0;          ///< (m)
  std::size_t particles = 0;    ///< fill pi R^2 W solid_fraction / mean simulated particle volume
  double mean_diameter = 0.0;   ///< number-mean simulated particle diameter d (m)
  double diameter_ratio = 0.0;  ///< D / d
};
/// Sizes the bed of a drum; InputError naming `where`.max_particles when the count exceeds the
/// limit, `where`.diameter or `where`.length when the drum is too small for its particles.
DrumBed drum_bed(const RotatingDrumSettings& s, const particles::SizeDistribution& simulated,
                 const std::string& where);
/// The drum speed as written in phase names ("4", "105", "2.5").
std::string drum_rpm_label(double rpm);

/// The rotating_drum lab test (seed 001 §3.2.2-3.2.3, eq. 20): its catalogue entry here, its runner
/// in core/lab/rotating_drum.cpp.
struct RotatingDrumTest {
  using SettingsType = RotatingDrumSettings;
  /// Its bed is poured into the drum (seed 001 §3.2.2).
  static std::vector<PreparationMethod> preparations() { return {PreparationMethod::kPour}; }
  static LabTestInfo info() {
    return {
        "rotating_drum",
        "drum of D x W mm (100 x 44 in the seed), fill 43 %: the particle count follows from "
        "the drum, the fill and the simulated sizes; dynamic angle of repose at `rpm` (4) from "
        "a line fitted to the projected free surface, and the area method at 4, 40, 80, 105 and "
        "116 rpm from a raster of the projected bed; also reports drum_diameter_ratio D/d and "
        "particles",
        "seed 001 §3.2.2-3.2.3 (eq. 20, Fig. 13)",
        {{"dynamic_angle_of_repose", "deg", "free-surface angle at `rpm` (image fit)"},
         {"csa_occupied_4", "%", "occupied cross-sectional area at 4 rpm (eq. 20)"},
         {"csa_occupied_40", "%", "occupied cross-sectional area at 40 rpm (eq. 20)"},
         {"csa_occupied_80", "%", "occupied cross-sectional area at 80 rpm (eq. 20)"},
         {"csa_occupied_105", "%", "occupied cross-sectional area at 105 rpm (eq. 20)"},
         {"csa_occupied_116", "%", "occupied cross-sectional area at 116 rpm (eq. 20)"},
         {"centrifuging_116", "0/1", "1 when the bed centrifuges at 116 rpm"}},
        settings_docs<RotatingDrumSettings>(),
        {"centrifuging_4", "centrifuging_40", "centrifuging_80", "centrifuging_105",
         "drum_diameter", "drum_diameter_ratio", "particles"}};
  }
  /// Its particle count follows from the drum, the fill and the simulated sizes (drum_bed).
  static std::size_t admit(const MaterialModel& material, const RotatingDrumSettings& s,
                           const std::string& where);
  static LabOutput run(const MaterialModel& material, const Settings& settings,
                       const RunOptions& options);
};

}  // namespace demcal::lab
