#pragma once
// A value's deviation from a measured target as a fraction of the target: the calibration's
// relative error, shown for predictions and simulations alike.
#include <cmath>

namespace demcal {

/// (value - target) / |target|; NaN for a target of 0, which gives no relative scale.
inline double relative_error(double value, double target) {
  return target != 0.0 ? (value - target) / std::abs(target) : std::nan("");
}

}  // namespace demcal
