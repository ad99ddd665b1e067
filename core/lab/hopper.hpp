#pragma once
// hopper (seed 000 §2.7.6): discharge of a wedge hopper slice, periodic front and back.
#include <array>

#include "core/lab/lab_run.hpp"
#include "core/model/hopper_settings.hpp"

namespace demcal::lab {

/// Rose and Tanaka's factor on Beverloo's rate for walls at `half_angle` (rad) from the vertical:
/// (tan theta tan 45 deg)^-0.35 below 45 deg, 1 above (hopper.cpp).
double rose_tanaka_factor(double half_angle);

}  // namespace demcal::lab
