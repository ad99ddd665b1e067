#pragma once
// packing (seed 000 §2.7.1, §3.1): four ways of building the initial bed, selected by `method`
// (the seed's numbering):
//   1 van der Waals cluster formation: random insertion, Gaussian velocities, free motion without
//     cohesion and gravity (under a lid), motion stopped, van der Waals on without gravity
//     (clusters form), then settling under gravity;
//   2 contact promotion by random motion: as 1, but the motion is not stopped and cohesion acts
//     only between touching particles;
//   3 limited settling velocity: poured under gravity with every particle's speed capped at its
//     Stokes terminal velocity in air, cohesion only in contact;
//   4 plain pouring (default): poured under gravity, cohesion only in contact.
// "Cohesion only in contact" is the material's van der Waals law with D_max = 1.01 D_min.
#include <array>

#include "core/lab/lab_test.hpp"

namespace demcal::lab {

struct PackingSettings {
  static constexpr const char* kName = "packing";
  double particles;
  double time_step_safety;
  double
      wall_margin;  ///< sampling volume keeps this many largest diameters from die, floor and top
  double method;
  double agitation_speed;    ///< (m/s) standard deviation of each Gaussian velocity component
  double agitation_time;     ///< (s)
  double cluster_time;       ///< (s)
  double terminal_velocity;  ///< (m/s)
  double cut_fraction;       ///< bed cut at this fraction of its height

  static std::array<contact::ParamInfo<PackingSettings>, 9> table() {
    using S = PackingSettings;
    return {
        {{"particles", "-", 20, 1e7, 300, "number of particles", &S::particles},
         {"time_step_safety", "-", 0.01, 1.0, 0.2, "time step as a fraction of the critical one",
          &S::time_step_safety},
         {"wall_margin", "-", 0.0, 10.0, 1.0,
          "distance of the sampling volume from the walls and the top, in largest diameters",
          &S::wall_margin},
         {"method", "-", 1, 4, 4,
          "1 van der Waals clusters, 2 random-motion contact promotion, 3 limited settling "
          "velocity, 4 plain pouring (seed 000 §2.7.1)",
          &S::method},
         {"agitation_speed", "m/s", 0.0, 1e3, 0.0,
          "Gaussian velocity per component (methods 1-2); 0 = sqrt(g d_mean)", &S::agitation_speed},
         {"agitation_time", "s", 0.0, 1e4, 0.0,
          "free motion without gravity (methods 1-2); 0 = 3 mean diameters at agitation_speed",
          &S::agitation_time},
         {"cluster_time", "s", 0.0, 1e4, 0.0,
          "cohesion on without gravity (methods 1-2); 0 = agitation_time", &S::cluster_time},
         {"terminal_velocity", "m/s", 0.0, 1e3, 0.0,
          "speed cap of method 3; 0 = Stokes rho g d^2 / (18 mu_air) per particle",
          &S::terminal_velocity},
         {"cut_fraction", "-", 0.1, 1.0, 1.0,
          "particles above this fraction of the settled bed height are removed",
          &S::cut_fraction}}};
  }
  void finalize(const std::string&) {}
};

LabTestInfo packing_info();  ///< in catalog.cpp
LabOutput run_packing(const MaterialModel& material, const Settings& settings,
                      const RunOptions& options);

}  // namespace demcal::lab
