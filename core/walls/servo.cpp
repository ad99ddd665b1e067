#include "core/walls/servo.hpp"

#include <algorithm>

namespace demcal::walls {

void StressServo::update(Wall& wall, double dt, double stiffness_step) {
  const double error = target - stress(wall);
  const double derivative = started_ ? (error - last_error_) / dt : 0.0;
  const double unclamped_integral = integral_ + error * dt;
  double v = kp * error + ki * unclamped_integral + kd * derivative;
  double limit = max_speed;
  if (stiffness_step > 0.0 && wall.stiffness > 0.0)
    limit = std::min(limit, stiffness_step * std::abs(error) * area / (wall.stiffness * dt));
  // Anti-windup: the integral only grows while the output is not saturated.
  if (v > limit || v < -limit)
    v = std::clamp(v, -limit, limit);
  else
    integral_ = unclamped_integral;
  last_error_ = error;
  started_ = true;
  wall.velocity = axis * v;
}

}  // namespace demcal::walls
