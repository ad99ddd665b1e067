#include "core/lab/lab_test.hpp"

#include <chrono>

#include "core/common/error.hpp"
#include "core/lab/confined_compression.hpp"
#include "core/lab/hopper.hpp"
#include "core/lab/packing.hpp"
#include "core/lab/rotating_drum.hpp"
#include "core/lab/shear_cell.hpp"
#include "core/lab/tensile.hpp"
#include "core/lab/wall_friction.hpp"

namespace demcal::lab {

LabRunner find_lab_runner(const std::string& name) {
  if (name == "packing") return run_packing;
  if (name == "shear_cell") return run_shear_cell;
  if (name == "rotating_drum") return run_rotating_drum;
  if (name == "hopper") return run_hopper;
  if (name == "wall_friction") return run_wall_friction;
  if (name == "tensile") return run_tensile;
  if (name == "confined_compression") return run_confined_compression;
  find_lab_info(name);  // throws with the known names
  throw InputError("test", "lab test '" + name + "' is catalogued but has no runner");
}

void LabOutput::add_phase(const PhaseCost& phase, const std::vector<std::string>& depending) {
  cost.phases.push_back(phase);
  if (phase.reached) return;
  const std::string why = "phase '" + phase.name + "' did not reach " + phase.target;
  for (const auto& m : depending) {
    std::string& flag = flags[m];
    flag += (flag.empty() ? "" : "; ") + why;
  }
}

LabOutput run_lab_test(const std::string& name, const MaterialModel& material,
                       const Settings& settings, const RunOptions& options) {
  const LabTestInfo& info = find_lab_info(name);
  validate_settings(info, settings, "settings");
  const auto started = std::chrono::steady_clock::now();
  LabOutput out = find_lab_runner(name)(material, settings, options);
  out.cost.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  for (const auto& m : info.metrics)
    if (!out.metrics.count(m.name))
      throw std::logic_error("lab test '" + name + "' did not produce its metric '" + m.name + "'");
  return out;
}

}  // namespace demcal::lab
