#pragma once
// A wall servo-controlled to a target normal stress (seed 000 §2.7.2: a PID-controlled piston with
// a speed limit). The stress is the particles' force on the wall along the compression axis over
// the wall's loaded area; the controller sets the wall's velocity along that axis:
//   e = sigma_target - sigma,  v = clamp(kp e + ki integral(e) dt + kd de/dt, -v_max, v_max)
// Positive v moves the wall along `axis`, into the bed.
// Given stiffness_step > 0, the wall's step is also bounded by the stiffness of its contacts, as
// Yade's TriaxialStressController moves a wall by (F - F_target) / K, K the sum of the normal
// stiffnesses of the wall's contacts (Chareyre's rule):
//   |v| dt <= stiffness_step |sigma_target - sigma| A / K   (K = Wall::stiffness)
// A speed limit chosen for the bed is too fast for a wall whose contacts are far stiffer than the
// bed (an adhesive piston with stiffened contacts): one step at that speed swings the stress past
// the target and back, and the controller flips between its limits. The bound keeps every step
// short of the one that would close the error, so the stress approaches the target without
// crossing it as long as K bounds the contacts' slope.
#include "core/walls/wall.hpp"

namespace demcal::walls {

struct StressServo {
  Vec3 axis{0, 0, -1};     ///< unit direction in which the wall compresses the bed
  double area = 0.0;       ///< loaded area (m^2)
  double target = 0.0;     ///< target compressive stress (Pa)
  double kp = 0.0;         ///< proportional gain (m/s per Pa)
  double ki = 0.0;         ///< integral gain (m/s per Pa s)
  double kd = 0.0;         ///< derivative gain (m/s per Pa/s)
  double max_speed = 0.0;  ///< speed limit (m/s)

  /// Compressive stress the particles exert on the wall (Pa).
  double stress(const Wall& wall) const { return -dot(wall.force, axis) / area; }
  /// Sets the wall velocity for the next step from the stress of the last one. stiffness_step:
  /// the fraction of the step that would close the error at the wall's contact stiffness the wall
  /// may take (0: no such bound; see the header). An argument, not a member: the records of the
  /// runs that keep a servo hold its bytes.
  void update(Wall& wall, double dt, double stiffness_step = 0.0);
  /// Forgets the integral and derivative history (call when the target changes).
  void reset() {
    integral_ = 0.0;
    last_error_ = 0.0;
    started_ = false;
  }

 private:
  double integral_ = 0.0, last_error_ = 0.0;
  bool started_ = false;
};

}  // namespace demcal::walls
