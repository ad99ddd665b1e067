#pragma once
// tensile (seed 000 §2.7.3, eq. 34-35): a bed consolidated in the die by an adhesive piston, the
// stress reduced close to zero, then the piston pulled up at constant slow speed.
#include <array>

#include "core/lab/confined_compression.hpp"
#include "core/model/tensile_settings.hpp"

namespace demcal::lab {

LabOutput run_tensile(const MaterialModel& material, const Settings& settings,
                      const RunOptions& options);

}  // namespace demcal::lab
