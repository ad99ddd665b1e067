#pragma once
// wall_friction (seed 000 §2.7.5): the container (bottom, a StressServo) presses the bed against
// the piston, which rotates at constant normal stress; the torque gives the wall shear stress at
// 1, 1.25, 1.5, 1.75, 2 and 3 kPa, and the slope of a regression through the origin the wall
// friction angle. Torque to shear stress for a uniform shear stress on a disk of radius R:
//   T = int_0^R tau 2 pi r^2 dr = (2/3) pi R^3 tau   =>   tau = 3 T / (2 pi R^3).
#include <array>
#include <vector>

#include "core/lab/confined_compression.hpp"
#include "core/model/wall_friction_settings.hpp"

namespace demcal::lab {

LabOutput run_wall_friction(const MaterialModel& material, const Settings& settings,
                            const RunOptions& options);

}  // namespace demcal::lab
