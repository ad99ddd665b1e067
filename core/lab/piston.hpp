#pragma once
// The piston of the die tests (confined_compression, tensile, wall_friction): a disk on the bed
// in the die, driven by a stress servo through phases that end when the stress holds its target
// (docs/lab-tests.md, "Servo phases").
#include <functional>
#include <limits>

#include "core/lab/bed.hpp"
#include "core/metrics/bulk.hpp"
#include "core/model/piston_settings.hpp"

namespace demcal::lab {

/// Adds a piston (kWallPiston): a disk of the die's radius facing down (-z) with its face at
/// height z; returns its index.
std::size_t add_piston(sim::World& world, double z);

/// Controller settings of a stress-servo piston (walls::StressServo), as exposed by the tests.
struct ServoSettings {
  double max_speed = 0.0;  ///< speed limit (m/s, simulated)
  double kp = 0.0;         ///< m/s per Pa
  double ki = 0.0;         ///< m/s per Pa s
  double kd = 0.0;         ///< m/s per Pa/s
  double tolerance = 0.0;  ///< |stress - target| (Pa) counted as reached
  double hold_time = 0.0;  ///< (s) the stress must stay within tolerance (at least; see approach)
  double max_time = 0.0;   ///< (s) per phase, reached or not; 0 = by the rule (phase_time_limit)
  /// The driven wall does not back away (move against the compression axis) past this
  /// coordinate along the axis: a container bottom never sinks below the floor the bed settled
  /// on, even when a bed jammed against the die keeps the stress above the target.
  double retreat_limit = -std::numeric_limits<double>::infinity();
  /// The approach before the controller holds (docs/lab-tests.md, "Servo phases"): the wall
  /// moves at v = I h sqrt(sigma_ref / rho) / d, I blending from approach_inertial_number far
  /// from the target to inertial_number at it, until the stress crosses the target.
  /// speed_scale = h / (d sqrt(rho)); approach_inertial_number 0 = no approach (the controller
  /// alone).
  double speed_scale = 0.0;
  double height = 0.0;        ///< bed height h the speeds and the time-limit rule refer to (m)
  double bulk_density = 0.0;  ///< rho_b of the bed (kg/m^3), for the stress-wave transit time
  double inertial_number = 0.0;
  double approach_inertial_number = 0.0;
};

/// What a servo phase ended with: mean stress and wall position over the hold window.
struct ServoPhase {
  double stress = 0.0;    ///< (Pa, simulated)
  double position = 0.0;  ///< wall's axial coordinate (m): piston face z or bottom z
  double time = 0.0;      ///< simulated time spent (s)
  bool reached = false;
  PhaseCost cost;  ///< named "servo"; callers rename it
};

/// Drives `driven` (a wall index) by a StressServo until the compressive stress read from wall
/// `measured` holds `target` for hold_time (or max_time passes). `axis` (+z or -z) is the direction
/// in which the driven wall compresses the bed; `servo.retreat_limit` is a coordinate along it.
/// `record(world, stress)` is called every `record_every` steps if given. `stiffness_step` > 0
/// bounds the controller's step by the measured wall's contact stiffness
/// (walls::StressServo::update); kept apart from ServoSettings, whose bytes the records of
/// conditioned beds hold.
ServoPhase servo_phase(sim::World& world, std::size_t driven, std::size_t measured, Vec3 axis,
                       double area, double target, const ServoSettings& servo,
                       const sim::HealthLimits& limits,
                       const std::function<void(const sim::World&, double stress)>& record = {},
                       int record_every = 50, double stiffness_step = 0.0);

/// Servo settings from the exposed values: automatic speed limit (the inertial number
/// I = v/h d sqrt(rho/sigma) at `stress_max`), gains, tolerance, hold and time limits, and the
/// approach (docs/lab-tests.md, "Servo phases").
ServoSettings make_servo(const sim::World& world, double bed_height, double stress_max,
                         const PistonServoSettings& exposed);

/// A settled die bed with a piston resting at its top: the start of the piston tests.
struct PistonBed {
  sim::World world;
  std::size_t piston = 0;
  double radius = 0.0, area = 0.0;
  double h0 = 0.0;  ///< settled bed height = initial piston position (m)
  sim::HealthLimits limits;
  PhaseCost filled;  ///< the phases that built it
  PreparedBed built;
  /// The settled bed, at h0 (sampled one largest diameter from die, floor and top): its solid
  /// fraction and coordination number, reported with every piston test (series `settled_bed`).
  double settled_solid_fraction = 0.0, settled_coordination = 0.0;
  /// The piston's servo at the test's largest stress (make_servo); fixed with the bed, as its
  /// hold time is in steps of the bed's time step, which adapts as the run goes.
  ServoSettings servo;
};

/// What a piston bed keeps beside its world, in a checkpoint record (core/lab/stages.hpp).
template <class A, RecordOf<PistonBed> B>
void record_fields(A& a, B& b) {
  a.field(b.piston);
  a.field(b.radius);
  a.field(b.area);
  a.field(b.h0);
  a.field(b.limits);
  a.field(b.filled);
  a.field(b.built.prepared);
  a.field(b.built.settled);
  a.field(b.settled_solid_fraction);
  a.field(b.settled_coordination);
  a.field(b.servo);
}

/// The die bed a piston test asks for.
struct PistonBedRequest {
  std::size_t particles = 0;
  double safety = 0.0;  ///< time-step safety factor
  /// The largest stress the test applies (simulated; BedSpec::rest_stress): the settling
  /// criterion's scale.
  double stress_level = 0.0;
  /// The test's servo settings, for PistonBed::servo at stress_level (none when it is 0).
  PistonServoSettings servo{};
  /// Replaces wall laws (e.g. stiff or adhesive piston and bottom).
  std::function<void(sim::World&)> set_laws;
  /// The metrics read from the settled state (its height): flagged if settling fell short.
  std::vector<std::string> depending;
};

/// The request of a piston test: its settings' particles, time-step safety and servo settings,
/// the largest stress it applies (simulated) and its wall laws.
template <class S>
PistonBedRequest piston_bed_request(const S& settings, double stress_level,
                                    std::function<void(sim::World&)> set_laws) {
  PistonBedRequest request;
  request.particles = static_cast<std::size_t>(settings.particles);
  request.safety = settings.time_step_safety;
  request.stress_level = stress_level;
  request.servo = settings;
  request.set_laws = std::move(set_laws);
  return request;
}

/// Records the bed's fill and settle phases in `out`, flagging the request's `depending`, and
/// the settled bed's solid fraction and coordination number (series `settled_bed`).
void add_bed_phases(LabOutput& out, const PistonBed& bed, const PistonBedRequest& request);
/// Records a servo phase under `name`, flagging `depending` if it did not reach its target.
void add_servo_phase(LabOutput& out, const ServoPhase& phase, const std::string& name,
                     const std::vector<std::string>& depending);
/// The die bed up to its settle: the die world filled, `set_laws` replacing wall laws, the
/// piston far above, the time step adapted, the bed prepared (prepare_bed).
PistonBed begin_piston_bed(const MaterialModel& material, const PistonBedRequest& request,
                           const RunOptions& options);
/// Settles a begun bed relative to the stress level (settle_prepared, back to the material's
/// simulated particle law, the one make_material_world gave the world), rests the piston on its
/// top and sets its servo.
void finish_piston_bed(PistonBed& bed, const MaterialModel& material,
                       const PistonBedRequest& request, const SettleCheckpoints& checkpoints);
/// begin_piston_bed, then finish_piston_bed.
PistonBed make_piston_bed(const MaterialModel& material, const PistonBedRequest& request,
                          const RunOptions& options);

/// The first checkpoint stage of every piston test: the settled bed with its piston.
inline constexpr const char* kPistonBedStage = "piston bed";

/// The sampling cylinder of a die bed up to `top`: one largest diameter from die, floor and top.
metrics::SamplingCylinder bed_sample(const sim::World& world, double die_radius, double top);

/// Throws naming `checkpoint` unless the bed's piston is a disk wall of its world.
void check_piston(const PistonBed& bed);

/// The start of a piston test whose stages (core/lab/stages.hpp) begin with kPistonBedStage:
/// a run resumed from one of them gets its bed, output and fields restored; any other makes
/// the bed, offering kSettlingStage checkpoints during its settle (a run resumed from one goes
/// on with that settle), records its phases in `out` and offers the stage. Returns the index of
/// the first stage still to reach.
template <class S>
std::size_t start_piston_test(S& stages, const MaterialModel& material,
                              const PistonBedRequest& request, const RunOptions& options,
                              PistonBed& bed, LabOutput& out) {
  stages.add_within(kSettlingStage, 0);
  // The settle's progress and the grown bed's record (growth settles by its critical time): the
  // phase's own fields of a kSettlingStage record.
  SettleProgress progress;
  auto settle_fields = [&](auto& a) {
    a.field(progress);
    a.field(bed.built.grown);
  };
  SettleCheckpoints checkpoints;
  checkpoints.offer = [&](const SettleProgress& at) {
    stages.offer_within(kSettlingStage, bed.world, [&](auto& a) {
      progress = at;  // only for a checkpoint the receiver keeps
      settle_fields(a);
    });
  };
  if (stages.resuming()) {
    bed.world = make_material_world(material, options);
    if (request.set_laws) request.set_laws(bed.world);
    const bool settling = stages.resuming_within();
    if (settling) set_settling_law(bed.world, material);
    const std::size_t next = stages.resume(bed.world);
    check_piston(bed);
    if (!settling) return next;
    stages.read_within(settle_fields);
    // The earlier attempt's wall time: the bed's phases up to the checkpoint.
    out.cost.wall_seconds +=
        bed.filled.wall_seconds + bed.built.prepared.wall_seconds + progress.begun.wall_seconds;
    checkpoints.resume = &progress;
  } else {
    bed = begin_piston_bed(material, request, options);
  }
  finish_piston_bed(bed, material, request, checkpoints);
  add_bed_phases(out, bed, request);
  stages.reached(0, bed.world);
  return 1;
}

}  // namespace demcal::lab
