#pragma once
// packing (seed 000 §2.7.1, §3.1): the bed of a cylindrical die built by the material's
// preparation (material.preparation: the four methods of §2.7.1, preparation.hpp) and settled;
// its solid fraction and coordination number away from the walls.
#include <array>

#include "core/lab/lab_test.hpp"
#include "core/model/packing_settings.hpp"

namespace demcal::lab {

LabOutput run_packing(const MaterialModel& material, const Settings& settings,
                      const RunOptions& options);

}  // namespace demcal::lab
