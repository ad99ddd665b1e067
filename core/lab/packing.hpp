#pragma once
// packing (seed 000 §2.7.1, §3.1).
#include <array>

#include "core/lab/lab_test.hpp"

namespace demcal::lab {

struct PackingSettings {
  static constexpr const char* kName = "packing";
  double particles;
  double time_step_safety;
  double
      wall_margin;  ///< sampling volume keeps this many largest diameters from die, floor and top

  static std::array<contact::ParamInfo<PackingSettings>, 3> table() {
    return {{{"particles", "-", 20, 1e7, 300, "number of particles", &PackingSettings::particles},
             {"time_step_safety", "-", 0.01, 1.0, 0.2,
              "time step as a fraction of the critical one", &PackingSettings::time_step_safety},
             {"wall_margin", "-", 0.0, 10.0, 1.0,
              "distance of the sampling volume from the walls and the top, in largest diameters",
              &PackingSettings::wall_margin}}};
  }
  void finalize(const std::string&) {}
};

LabTestInfo packing_info();  ///< in catalog.cpp
LabOutput run_packing(const MaterialModel& material, const Settings& settings,
                      const RunOptions& options);

}  // namespace demcal::lab
