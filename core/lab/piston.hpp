#pragma once
// The piston of the die tests (confined_compression, tensile, wall_friction): a disk on the bed
// in the die, driven by a stress servo through phases that end when the stress holds its target
// (docs/lab-tests.md, "Servo phases").
#include <functional>
#include <limits>

#include "core/lab/bed.hpp"
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
/// `record(world, stress)` is called every `record_every` steps if given.
ServoPhase servo_phase(sim::World& world, std::size_t driven, std::size_t measured, Vec3 axis,
                       double area, double target, const ServoSettings& servo,
                       const sim::HealthLimits& limits,
                       const std::function<void(const sim::World&, double stress)>& record = {},
                       int record_every = 50);

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
  std::string resumed_from;  ///< the checkpoint stage it was restored from (empty: built)
};
/// Records the bed's fill and settle phases in `out`; `depending` are the metrics read from the
/// settled state (its height).
void add_bed_phases(LabOutput& out, const PistonBed& bed,
                    const std::vector<std::string>& depending);
/// Records a servo phase under `name`, flagging `depending` if it did not reach its target.
void add_servo_phase(LabOutput& out, const ServoPhase& phase, const std::string& name,
                     const std::vector<std::string>& depending);
/// Builds the die world, lets `set_laws` replace wall laws (e.g. stiff or adhesive piston and
/// bottom), sets dt = safety * critical over all laws, settles relative to `stress_level` (the
/// largest stress the test applies, simulated; BedSpec::rest_stress), and adds the piston at the
/// bed top. The bed is a checkpoint stage ("piston bed"): offered to options.checkpoint once
/// built, and restored instead of built when options.resume names it.
PistonBed make_piston_bed(const MaterialModel& material, std::size_t particles, double safety,
                          double stress_level, const RunOptions& options,
                          const std::function<void(sim::World&)>& set_laws);

}  // namespace demcal::lab
