#include "core/lab/piston.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/lab/block_means.hpp"
#include "core/lab/run_cancelled.hpp"
#include "core/sim/step.hpp"
#include "core/sim/time_step.hpp"
#include "core/walls/servo.hpp"

namespace demcal::lab {

std::size_t add_piston(sim::World& world, double z) {
  world.walls.push_back(walls::make_wall(
      "piston", walls::Disk{{0, 0, z}, {0, 0, -1}, die_radius(world)}, kWallPiston));
  return world.walls.size() - 1;
}

namespace {
double axial_position(const walls::Wall& w) {
  if (const auto* d = std::get_if<walls::Disk>(&w.shape)) return d->centre.z;
  if (const auto* p = std::get_if<walls::Plane>(&w.shape)) return p->point.z;
  return w.displacement.z;
}
}  // namespace

namespace {

/// Approach speed at `stress` (module comment of ServoSettings): quasi-static at the target,
/// up to approach_inertial_number while the error is at least half the reference stress.
double approach_speed(const ServoSettings& s, double target, double stress) {
  const double ref = std::max(target, std::abs(stress));
  const double blend = std::min(1.0, std::abs(target - stress) / (0.5 * ref));
  const double inertial =
      s.inertial_number + (s.approach_inertial_number - s.inertial_number) * blend;
  return inertial * s.speed_scale * std::sqrt(ref);
}

/// The phase's simulated time limit: the given one, or (rule) twice the time to cross the whole
/// bed height at the quasi-static speed of the larger of the start and target stresses (no phase
/// compacts a bed by more than its height; the controller slows as the stress nears its target,
/// and a loose cohesive first load needed 1.01 times the single crossing), plus 50 hold times.
/// Without an inertial-number scale, the speed limit.
double phase_time_limit(const ServoSettings& s, double target, double start) {
  if (s.max_time > 0.0) return s.max_time;
  const double v = s.speed_scale > 0.0 ? s.inertial_number * s.speed_scale *
                                             std::sqrt(std::max(target, std::abs(start)))
                                       : s.max_speed;
  return 2.0 * s.height / v + 50.0 * s.hold_time;
}

/// Moves the driven wall towards the target until the stress (a running mean over a quarter of
/// the hold time, so one rattling contact does not end it) has made three quarters of its way
/// to it, or the wall reaches its retreat limit, or max_time passes. Nothing to do when the stress
/// is already within tolerance. Returns the hold time of the phase: at least four transits of a
/// stress wave through the bed, c = sqrt(E / rho_b) with E the secant modulus the approach measured
/// (the bed must carry the wall's stress through its height before the stress counts as held), at
/// most a tenth of the phase's time limit, at least ServoSettings::hold_time.
template <class StressOf, class Record>
double approach_target(sim::World& world, std::size_t driven, Vec3 axis, double target,
                       double time_limit, const ServoSettings& s, const sim::HealthLimits& limits,
                       const StressOf& stress_of, const Record& record, int record_every) {
  const double start = stress_of(world);
  if (s.approach_inertial_number <= 0.0 || std::abs(start - target) <= s.tolerance)
    return s.hold_time;
  const double z0 = axial_position(world.walls[driven]);
  const double direction = target > start ? 1.0 : -1.0;
  // The approach hands over to the controller a quarter of the stress change before the target,
  // so the controller makes the last part at quasi-static speed.
  const double handover = target - 0.25 * (target - start);
  const double t0 = world.time;
  const double smoothing = std::min(1.0, 4.0 * world.dt / std::max(s.hold_time, world.dt));
  double mean = start;
  run_checked(world, std::numeric_limits<long>::max() / 2, limits, [&](sim::World& w) {
    const double stress = stress_of(w);
    mean += smoothing * (stress - mean);
    if (record && w.step_count % record_every == 0) record(w, stress);
    const bool at_limit = axial_position(w.walls[driven]) * axis.z <= s.retreat_limit;
    if ((mean - handover) * direction >= 0.0 || (direction < 0.0 && at_limit) ||
        w.time - t0 >= time_limit) {
      w.walls[driven].velocity = {};
      return false;
    }
    w.walls[driven].velocity = axis * (direction * approach_speed(s, target, mean));
    return true;
  });
  const double travel = std::abs(axial_position(world.walls[driven]) - z0);
  const double modulus = travel > 0.0 ? std::abs(mean - start) * s.height / travel : 0.0;
  const double transit =
      modulus > 0.0 ? s.height / std::sqrt(modulus / s.bulk_density) : 0.1 * time_limit;
  return std::clamp(4.0 * transit, s.hold_time, std::max(s.hold_time, 0.1 * time_limit));
}

}  // namespace

ServoPhase servo_phase(sim::World& world, std::size_t driven, std::size_t measured, Vec3 axis,
                       double area, double target, const ServoSettings& s,
                       const sim::HealthLimits& limits,
                       const std::function<void(const sim::World&, double)>& record,
                       int record_every, double stiffness_step) {
  walls::StressServo servo;
  servo.axis = axis;
  servo.area = area;
  servo.target = target;
  servo.kp = s.kp;
  servo.ki = s.ki;
  servo.kd = s.kd;
  servo.max_speed = s.max_speed;
  // The measured wall faces the driven one (or is it): a compressive stress pushes it along
  // -axis_measured, where axis_measured = axis for the driven wall itself and -axis otherwise.
  const double sign = driven == measured ? 1.0 : -1.0;
  auto stress_of = [&](const sim::World& w) {
    return -dot(w.walls[measured].force, axis * sign) / area;
  };
  ServoPhase out;
  const PhaseClock clock(world);
  const double t0 = world.time;
  const double time_limit = phase_time_limit(s, target, stress_of(world));
  const double hold_time = approach_target(world, driven, axis, target, time_limit, s, limits,
                                           stress_of, record, record_every);
  // The stress on a piston is carried by a few tens of contacts and rattles; the phase ends when
  // the mean over a block of hold_time is within tolerance of the target.
  BlockMeans held(world.time, hold_time);  // the stress and the driven wall's position
  run_checked(world, std::numeric_limits<long>::max() / 2, limits, [&](sim::World& w) {
    const double stress = stress_of(w);
    walls::Wall probe;
    probe.force = w.walls[measured].force * sign;
    probe.stiffness = w.walls[measured].stiffness;
    servo.update(probe, w.dt, stiffness_step);
    const bool at_limit = axial_position(w.walls[driven]) * axis.z <= s.retreat_limit;
    w.walls[driven].velocity =
        at_limit && dot(probe.velocity, axis) < 0.0 ? Vec3{} : probe.velocity;
    if (record && w.step_count % record_every == 0) record(w, stress);
    if (held.add(w.time, stress, axial_position(w.walls[driven])) &&
        std::abs(held.mean_a() - target) <= s.tolerance) {
      out.reached = true;
      return false;
    }
    return w.time - t0 < time_limit;
  });
  if (!out.reached) held.close(world.time);
  out.stress = held.mean_a();
  out.position = held.mean_b();
  world.walls[driven].velocity = {};
  out.time = world.time - t0;
  char goal[160];
  std::snprintf(goal, sizeof goal, "stress %s +- %s (simulated) held %.3g s within %.3g s",
                stress_text(target).c_str(), stress_text(s.tolerance).c_str(), hold_time,
                time_limit);
  out.cost = clock.stop(world, "servo", goal, out.reached);
  return out;
}

void add_bed_phases(LabOutput& out, const PistonBed& bed, const PistonBedRequest& request) {
  out.add_phase(bed.filled, {});
  if (bed.built.prepared.steps > 0) out.add_phase(bed.built.prepared, {});
  out.add_phase(bed.built.settled, request.depending);
  out.series["settled_bed"] =
      Series{{"h0_m", "solid_fraction", "coordination_number"},
             {{bed.h0, bed.settled_solid_fraction, bed.settled_coordination}}};
}

void add_servo_phase(LabOutput& out, const ServoPhase& phase, const std::string& name,
                     const std::vector<std::string>& depending) {
  PhaseCost cost = phase.cost;
  cost.name = name;
  out.add_phase(cost, depending);
}

metrics::SamplingCylinder bed_sample(const sim::World& world, double die_radius, double top) {
  const auto& r = world.particles.radius;
  const double d_max = r.empty() ? 0.0 : 2.0 * *std::max_element(r.begin(), r.end());
  return {die_radius - d_max, d_max, top - d_max};
}

void check_piston(const PistonBed& bed) {
  if (bed.piston >= bed.world.walls.size() ||
      !std::holds_alternative<walls::Disk>(bed.world.walls[bed.piston].shape))
    throw InputError("checkpoint", "its piston is not a disk wall of its world");
}

namespace {

/// The settling criterion of a piston test's bed: relative to the test's stress level.
BedSpec piston_bed_spec(const PistonBedRequest& request) {
  BedSpec spec;
  spec.particles = request.particles;
  spec.time_step_safety = request.safety;
  spec.rest_stress = request.stress_level;
  return spec;
}

}  // namespace

PistonBed begin_piston_bed(const MaterialModel& material, const PistonBedRequest& request,
                           const RunOptions& options) {
  PistonBed b;
  const PhaseClock fill_clock;
  b.world = make_die_world(material, piston_bed_spec(request), options);
  b.filled = fill_clock.stop(b.world, "fill", "all particles inserted", true);
  sim::World& w = b.world;
  if (request.set_laws) request.set_laws(w);
  // The piston shares the bottom's law; added far above, it touches nothing while the bed
  // settles, and the step's ceiling covers its law from the start.
  b.radius = die_radius(w);
  b.area = M_PI * b.radius * b.radius;
  const double top = metrics_top(w);
  b.limits = die_limits(w, b.radius, top);
  b.piston = add_piston(w, 1e3 * top + 1.0);
  w.dt = sim::adapted_time_step(w, request.safety);
  b.built = prepare_bed(w, material, b.limits, top, options.seed);
  return b;
}

void finish_piston_bed(PistonBed& b, const MaterialModel& material, const PistonBedRequest& request,
                       const SettleCheckpoints& checkpoints) {
  sim::World& w = b.world;
  settle_prepared(w, material, piston_bed_spec(request), b.limits,
                  material.simulated_particle_law(), b.built, checkpoints);
  b.h0 = metrics_top(w);
  if (const metrics::SamplingCylinder region = bed_sample(w, b.radius, b.h0);
      region.radius > 0.0 && region.z_hi > region.z_lo) {
    b.settled_solid_fraction = metrics::solid_fraction(w, region);
    b.settled_coordination = metrics::coordination_number(w, region);
  }
  auto& disk = std::get<walls::Disk>(w.walls[b.piston].shape);
  disk.centre.z = b.h0;
  w.walls[b.piston].pivot = disk.centre;
  b.limits = die_limits(w, b.radius, b.h0);
  if (request.stress_level > 0.0)
    b.servo = make_servo(w, b.h0, request.stress_level, request.servo);
}

PistonBed make_piston_bed(const MaterialModel& material, const PistonBedRequest& request,
                          const RunOptions& options) {
  PistonBed b = begin_piston_bed(material, request, options);
  finish_piston_bed(b, material, request, {});
  return b;
}

ServoSettings make_servo(const sim::World& w, double h, double stress_max,
                         const PistonServoSettings& r) {
  const auto& p = w.particles;
  double d = 0.0, rho = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    d += 2.0 * p.radius[i];
    rho += p.mass[i] / (4.0 / 3.0 * M_PI * std::pow(p.radius[i], 3));
  }
  d /= static_cast<double>(p.size());
  rho /= static_cast<double>(p.size());
  ServoSettings s;
  // Quasi-static: inertial number I = (v / h) d sqrt(rho / sigma) (GDR MiDi 2004) at the
  // largest stress.
  s.speed_scale = h / (d * std::sqrt(rho));
  s.height = h;
  s.bulk_density = 0.6 * rho;  // a settled bed, for the order of the stress-wave transit time
  s.inertial_number = r.servo_inertial_number;
  s.approach_inertial_number = r.approach_inertial_number;
  s.max_speed = r.servo_max_speed > 0.0
                    ? r.servo_max_speed
                    : r.servo_inertial_number * s.speed_scale * std::sqrt(stress_max);
  // Full speed at an error of the whole largest stress: slow enough that the loop stays well
  // behind the bed's elastic wave transit time for usual bulk stiffnesses.
  s.kp = r.servo_kp > 0.0 ? r.servo_kp : s.max_speed / stress_max;
  s.ki = r.servo_ki;
  s.kd = r.servo_kd;
  s.tolerance = r.servo_tolerance;  // relative; servo_phase callers scale it per target
  s.hold_time = r.hold_steps * w.dt;
  s.max_time = r.max_phase_time;
  return s;
}

}  // namespace demcal::lab
