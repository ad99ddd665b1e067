#pragma once
// confined_compression (seed 000 §2.7.2, eq. 31-33; seed 001 §3.2.1, eq. 19): a bed in a
// cylindrical die loaded by a stress-servo piston to max_stress, unloaded to min_stress and
// reloaded `cycles` times, then unloaded to final_stress.
#include <array>

#include "core/lab/lab_test.hpp"
#include "core/lab/piston.hpp"
#include "core/model/confined_compression_settings.hpp"

namespace demcal::lab {

LabOutput run_confined_compression(const MaterialModel& material, const Settings& settings,
                                   const RunOptions& options);

}  // namespace demcal::lab
