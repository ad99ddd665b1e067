// wall_friction (seed 000 §2.7.5; calibration §3.3.4).
// Phases: settle in the die; piston (kWallPiston) placed on the bed top and held at that height;
// for each normal stress the bottom (kWallBottom, StressServo along +z) raises the bed until the
// piston carries the stress, then the piston turns about z at constant rim speed while the servo
// keeps the stress; the mean torque over the second half of the turn gives tau = 3 T/(2 pi R^3).
// The piston and bottom have the wall law stiffened by wall_stiffness_factor (seed 000 §2.7.2);
// the bottom has friction bottom_friction so that the bed does not turn with the piston.
// Torque to shear stress for a uniform shear stress on a disk of radius R:
//   T = int_0^R tau 2 pi r^2 dr = (2/3) pi R^3 tau   =>   tau = 3 T / (2 pi R^3).
#include <cmath>

#include "core/lab/bed.hpp"
#include "core/lab/lab_run.hpp"
#include "core/lab/piston.hpp"
#include "core/lab/stages.hpp"
#include "core/model/wall_friction_settings.hpp"

namespace demcal::lab {

double slope_through_origin(const std::vector<double>& x, const std::vector<double>& y) {
  double sxy = 0.0, sxx = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxy += x[i] * y[i];
    sxx += x[i] * x[i];
  }
  return sxy / sxx;
}

double two_point_calibration(double mu_a, double phi_a, double mu_b, double phi_b,
                             double phi_target) {
  return mu_a + (phi_target - phi_a) * (mu_b - mu_a) / (phi_b - phi_a);
}

LabOutput WallFrictionTest::run(const MaterialModel& material, const Settings& values,
                                const RunOptions& options) {
  const auto s = read_settings<WallFrictionSettings>(values, "settings");
  const double fs = material.factors().stress;
  const auto piston_spec = stiffen_normal(material.wall_law, s.wall_stiffness_factor);
  auto bottom_spec = piston_spec;
  bottom_spec.tangential.params["mu_s"] = s.bottom_friction;
  const auto piston_law = simulated_law(material, piston_spec);
  const auto bottom_law = simulated_law(material, bottom_spec);
  const auto& stresses = wall_friction_stresses();
  const PistonBedRequest request =
      piston_bed_request(s, stresses.back() * s.stress_factor * fs, [&](sim::World& w) {
        w.set_wall_law(kWallPiston, 0, piston_law);
        w.set_wall_law(kWallBottom, 0, bottom_law);
      });
  // The stages: the bed, then each normal stress once turned.
  std::vector<std::string> names{kPistonBedStage};
  for (double sigma_real : stresses)
    names.push_back("turn " + stress_text(sigma_real * s.stress_factor));
  LabOutput out;
  PistonBed bed;
  Series series{{"normal_stress_kPa", "shear_stress_kPa", "torque_Nm", "measured_normal_kPa"}, {}};
  std::vector<double> sig, tau;  // the measured (normal, shear) pairs so far
  Stages stages(options, std::move(names), out, [&](auto& a) {
    a.field(bed);
    a.field(series);
    a.field(sig);
    a.field(tau);
  });
  const std::size_t next = start_piston_test(stages, material, request, options, bed, out);
  sim::World& w = bed.world;
  const ServoSettings& servo = bed.servo;
  double d_mean = 0.0;
  for (double r : w.particles.radius) d_mean += 2.0 * r;
  d_mean /= static_cast<double>(w.particles.size());
  const double rim_speed = s.rim_speed > 0.0 ? s.rim_speed : 2.0 * servo.max_speed;
  const double omega = rim_speed / bed.radius;
  const double turn_time = s.rotation_diameters * d_mean / rim_speed;
  auto& piston = w.walls[bed.piston];
  const std::size_t bottom = 0;

  for (std::size_t k = next - 1; k < stresses.size(); ++k) {
    const double sigma_real = stresses[k];
    const double target = sigma_real * s.stress_factor * fs;
    ServoSettings ps = servo;
    ps.tolerance = std::max(servo.tolerance * target, 2e-3 * request.stress_level);
    // A turn can jam the bed between the piston and the die: the stress then stays above the
    // target however far the bottom sinks, and the loose powder would fall with it. The bottom
    // stops at the die's floor, where it stood when the bed was built (not where it stands at a
    // checkpoint it went on from); the measured stress, not the target, enters the regression.
    ps.retreat_limit = kDieFloorZ;
    piston.omega = {};
    const std::string at = stress_text(sigma_real * s.stress_factor);
    add_servo_phase(out,
                    servo_phase(w, bottom, bed.piston, {0, 0, 1}, bed.area, target, ps, bed.limits),
                    "press " + at, {"wall_friction_angle"});
    // Turn at constant normal stress: the same servo runs through the whole turn (a tolerance
    // that always holds, a hold time of the turn), torque averaged over its second half.
    piston.omega = {0, 0, omega};
    double t_sum = 0.0, n_sum = 0.0, s_sum = 0.0;
    const double t_half = w.time + 0.5 * turn_time;
    ServoSettings turn = ps;
    turn.tolerance = 1e300;
    turn.hold_time = turn_time;
    turn.max_time = 2.0 * turn_time;
    const ServoPhase turned = servo_phase(
        w, bottom, bed.piston, {0, 0, 1}, bed.area, target, turn, bed.limits,
        [&](const sim::World& world, double stress) {
          if (world.time < t_half) return;
          // The particles resist the turn: their torque on the piston opposes omega.
          t_sum += -world.walls[bed.piston].torque.z;
          s_sum += stress;
          n_sum += 1.0;
        },
        1);
    add_servo_phase(out, turned, stages.name(k + 1), {});
    piston.omega = {};
    const double torque = t_sum / n_sum;
    const double t = shear_stress_from_torque(torque, bed.radius);
    sig.push_back(s_sum / n_sum / fs);
    tau.push_back(t / fs);
    series.rows.push_back(
        {sigma_real * s.stress_factor / 1e3, t / fs / 1e3, torque, s_sum / n_sum / fs / 1e3});
    if (options.progress)
      options.progress(static_cast<double>(k + 1) / static_cast<double>(stresses.size()));
    stages.reached(k + 1, w);
  }
  write_snapshot(w, options, "final", out);
  // Regression through the origin on the measured (normal, shear) pairs (seed 000 §2.7.5).
  out.metrics["wall_friction_angle"] = std::atan(slope_through_origin(sig, tau)) * 180.0 / M_PI;
  out.series["wall_shear"] = std::move(series);
  out.cost.close(w);
  return out;
}

}  // namespace demcal::lab
