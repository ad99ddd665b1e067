#include "core/walls/servo.hpp"

#include <algorithm>

namespace demcal::walls {

void StressServo::update(Wall& wall, double dt) {
  const double error = target - stress(wall);
  const double derivative = started_ ? (error - last_error_) / dt : 0.0;
  const double unclamped_integral = integral_ + error * dt;
  double v = kp * error + ki * unclamped_integral + kd * derivative;
  // Anti-windup: the integral only grows while the output is not saturated.
  if (v > max_speed || v < -max_speed)
    v = std::clamp(v, -max_speed, max_speed);
  else
    integral_ = unclamped_integral;
  last_error_ = error;
  started_ = true;
  wall.velocity = axis * v;
}

}  // namespace demcal::walls
