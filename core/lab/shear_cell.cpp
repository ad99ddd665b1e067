// shear_cell (seed 000 §2.7.4): the FT4 standard shear test.
//
// Set-up: a cylindrical vessel (inner cylinder, kWallDie) with a floor (kWallBottom) that is the
// moving part of the container, and a shear head (kWallPiston) built as a mesh: a disk of the
// vessel radius R with radial vanes of height h_v below it. As in the seed, the normal stress is
// applied by the container: the floor is servo-controlled (walls::StressServo) to the target
// normal stress measured on the floor, while the head only rotates about the vessel axis.
//
// Torque -> shear stress: the bed shears in the plane of the vane tips (a disk of radius R); for
// a uniform shear stress tau over that disk the torque is
//   T = int_0^R tau 2 pi r r dr = (2/3) pi R^3 tau,   so   tau = 3 T / (2 pi R^3).
//
// Phases: fill and settle; insert head (lowered into the bed); consolidate until the floor holds
// sigma_pre = 3 kPa; pre-shear at constant tip speed until the flow is steady at sigma_pre (at
// least pre_shear_travel diameters): pre_shear_stress is the mean tau of its last window. Then
// re-consolidate the pre-sheared state at sigma_pre with the head at rest, once, and for every
// sigma_x of Table 3 start again from that state (the seed's restart files): reduce to sigma_x, and
// drive the head by torque: the set torque ramps up, the head turns at
//   omega = clamp(k (T_set - T), 0, omega_max)
// and the bed has yielded once the tips have travelled 1.5 diameters; the yield shear stress is
// the largest tau (mean over 0.5 d of tip travel) on the way. A least-squares line through the five
// (measured sigma, tau) points is the yield locus; the Mohr circles follow (mohr_evaluation).
#include "core/lab/shear_cell.hpp"

#include <algorithm>
#include <cmath>

#include "core/common/line_fit.hpp"
#include "core/common/rng.hpp"
#include "core/lab/bed.hpp"
#include "core/lab/block_means.hpp"
#include "core/lab/stages.hpp"
#include "core/metrics/bulk.hpp"
#include "core/particles/insertion.hpp"
#include "core/sim/step.hpp"
#include "core/sim/time_step.hpp"
#include "core/walls/servo.hpp"

namespace demcal::lab {

MohrResult mohr_evaluation(double k, double c, double s_pre, double t_pre) {
  MohrResult m;
  const double phi = std::atan(k), sn = std::sin(phi), cs = std::cos(phi);
  // Unconfined yield strength: the circle through the origin touching the locus; a locus without
  // cohesion (intercept <= 0, within noise of a cohesionless material) has none.
  m.sigma_c = std::max(0.0, 2.0 * c * (1.0 + sn) / cs);
  // Consolidation circle: centre s, radius rho = s sin(phi) + c cos(phi) (touches the locus)
  // and through the pre-shear point: (s_pre - s)^2 + t_pre^2 = rho^2, a quadratic in s.
  // A circle touching the locus lies below it, so a pre-shear point above the locus has none
  // (seed 000 Fig. 23b).
  if (t_pre > k * s_pre + c) return m;
  const double a = cs * cs, b = -2.0 * (s_pre + c * sn * cs),
               cc = s_pre * s_pre + t_pre * t_pre - c * c * cs * cs;
  const double disc = b * b - 4.0 * a * cc;
  if (disc < 0.0 || a <= 0.0) return m;
  const double s = (-b + std::sqrt(disc)) / (2.0 * a);  // the larger circle: sigma_1 > sigma_pre
  const double rho = s * sn + c * cs;
  if (rho <= 0.0 || s <= 0.0) return m;
  m.consistent = true;
  m.centre_1 = s;
  m.radius_1 = rho;
  m.sigma_1 = s + rho;
  m.ffc = m.sigma_c > 0.0 ? std::min(kFfcCap, m.sigma_1 / m.sigma_c) : kFfcCap;
  m.phi_e = std::asin(std::min(1.0, rho / s)) * 180.0 / M_PI;
  return m;
}

namespace {

/// The circles of seed 000 Fig. 23 as (centre, radius) in kPa: the unconfined yield circle
/// through the origin (when the locus has cohesion) and the consolidation circle.
Series mohr_circles(const MohrResult& m) {
  Series circles{{"circle", "centre_kpa", "radius_kpa"}, {}};
  if (m.sigma_c > 0.0) circles.rows.push_back({0.0, 0.5 * m.sigma_c, 0.5 * m.sigma_c});
  if (m.consistent) circles.rows.push_back({1.0, m.centre_1, m.radius_1});
  return circles;
}

enum Wall : std::size_t { kFloor = 0, kVessel = 1, kHead = 2 };

struct Cell {
  double radius = 0.0, d = 0.0;
};

/// The vessel and floor of the small cell (docs/lab-tests.md, "shear_cell"): a frictionless
/// vessel, so that the head's torque is the shear plane's and the floor measures the normal
/// stress on it; a rough floor that holds the bed below the plane.
void set_cell_wall_laws(sim::World& w, const MaterialModel& material, const ShearCellSettings& s) {
  contact::ContactLawSpec vessel = material.wall_law, floor = material.wall_law;
  vessel.tangential.params["mu_s"] = s.vessel_friction;
  vessel.rolling = {"none", {}};
  floor.tangential.params["mu_s"] = s.floor_friction;
  if (s.floor_rolling > 0.0) floor.rolling = {"cdt", {{"mu_r", s.floor_rolling}}};
  w.set_wall_law(kWallDie, 0, simulated_law(material, vessel));
  w.set_wall_law(kWallBottom, 0, simulated_law(material, floor));
}

/// The locus, its Mohr evaluation and the yield shear stress of every step as metrics (and the
/// note of an inconsistent pre-shear point).
void add_locus_metrics(LabOutput& out, const LineFit& locus, const MohrResult& mohr,
                       const std::vector<double>& yield_stress) {
  out.metrics["yield_locus_slope"] = locus.slope();
  out.metrics["yield_locus_intercept"] = locus.intercept();
  out.metrics["mohr_consistent"] = mohr.consistent ? 1.0 : 0.0;
  out.metrics["unconfined_yield_strength"] = mohr.sigma_c;
  out.metrics["major_consolidation_stress"] = mohr.sigma_1;
  out.metrics["ffc"] = mohr.ffc;
  out.metrics["effective_friction_angle"] = mohr.phi_e;
  for (std::size_t i = 0; i < yield_stress.size(); ++i) {
    char name[64];
    std::snprintf(name, sizeof name, "yield_shear_stress_%g", kShearNormalKPa[i]);
    std::string key = name;
    std::replace(key.begin(), key.end(), '.', 'p');  // yield_shear_stress_1p75
    out.metrics[key] = yield_stress[i];
  }
  if (!mohr.consistent)
    out.notes.push_back(
        "mohr_consistent = 0: the pre-shear point lies above the yield locus (seed 000 Fig. 23b), "
        "so no Mohr circle through it touches the locus; ffc, major_consolidation_stress and "
        "effective_friction_angle are 0 (undefined)");
}

double shear_stress(const sim::World& w, double radius) {
  // Resisting torque of the bed on the head (the head turns about +z), T = (2/3) pi R^3 tau.
  return 3.0 * (-w.walls[kHead].torque.z) / (2.0 * M_PI * radius * radius * radius);
}

/// The vessel, its bed, the head and the servo on the floor: what every phase of the test uses.
struct ShearCell {
  sim::World w;
  sim::HealthLimits limits;
  walls::StressServo servo;
  double d = 0.0;          ///< largest particle diameter (m, simulated)
  double radius = 0.0;     ///< vessel (m)
  double r_head = 0.0;     ///< vane tips (m)
  double real_kpa = 0.0;   ///< simulated Pa per real kPa
  double sigma_pre = 0.0;  ///< pre-shear normal stress (Pa, simulated)
  double omega = 0.0;      ///< head speed of the pre-shear (rad/s)

  double floor_stress(const sim::World& world) const { return servo.stress(world.walls[kFloor]); }
  /// Runs `world` (the cell or a copy of it) for `seconds` with the floor servo at `target`,
  /// calling `each` after every step until it returns false.
  long servo_run(sim::World& world, double target, double seconds,
                 const std::function<bool(sim::World&)>& each) {
    return servo_steps(world, servo_start(world, target, seconds), each);
  }
  /// Sets the floor servo to `target` afresh and returns the steps of `seconds` at the world's
  /// time step: the start of a servo phase that a checkpoint may split.
  long servo_start(const sim::World& world, double target, double seconds) {
    servo.target = target;
    servo.reset();
    return std::max<long>(1, std::lround(seconds / world.dt));
  }
  /// Runs `world` for `steps` steps with the floor servo as it stands, calling `each` after every
  /// step until it returns false.
  long servo_steps(sim::World& world, long steps, const std::function<bool(sim::World&)>& each) {
    return run_checked(world, steps, limits, [&](sim::World& ww) {
      servo.update(ww.walls[kFloor], ww.dt);
      return each ? each(ww) : true;
    });
  }
};

/// What the cell keeps beside its world, in a checkpoint record (core/lab/stages.hpp).
template <class A, RecordOf<ShearCell> C>
void record_fields(A& a, C& c) {
  a.field(c.limits);
  a.field(c.servo);
  a.field(c.d);
  a.field(c.radius);
  a.field(c.r_head);
  a.field(c.real_kpa);
  a.field(c.sigma_pre);
  a.field(c.omega);
}

/// The world of the cell as the test sets it up: the material's laws, the vessel's and floor's.
sim::World cell_world(const MaterialModel& material, const ShearCellSettings& s,
                      const RunOptions& options) {
  sim::World w = make_material_world(material, options);
  set_cell_wall_laws(w, material, s);
  return w;
}

/// The names of every metric of the test: what a phase of the bed's making that missed its target
/// flags.
std::vector<std::string> every_metric() {
  std::vector<std::string> names;
  for (const auto& m : find_lab_info(ShearCellSettings::kName).metrics) names.push_back(m.name);
  return names;
}

/// Hangs the head over the settled bed, its vane tips a quarter diameter above the bed top, and
/// lowers it at tip_speed until its disk is half a diameter above the bed top, the vanes
/// h_v - d/2 deep in the bed (phase "insert head"). A head placed there at once would cut the
/// particles under its vanes up to 0.9 radii deep, each overlap an energy of the order of k1 r^2
/// set free in one step: more than the bed's whole potential energy, and for a cohesive bed of
/// small particles more than the kinetic energy the health check allows.
void insert_head(ShearCell& c, const ShearCellSettings& s, double h_v, LabOutput& out) {
  sim::World& w = c.w;
  const PhaseClock clock(w);
  const double final_z = metrics::bed_top(w) + 0.5 * c.d;
  const double travel = h_v - 0.25 * c.d;  // vane_height >= 0.5: at least d/4
  const double head_z = final_z + travel;
  c.r_head = c.radius - 0.25 * c.d;
  auto head = walls::make_wall("head",
                               walls::make_vane_head({0, 0, head_z}, {0, 0, 1}, c.r_head, h_v,
                                                     static_cast<int>(s.vanes), 32),
                               kWallPiston);
  head.pivot = {0, 0, head_z};
  w.walls.push_back(head);
  w.walls[kHead].velocity = {0, 0, -s.tip_speed};
  // The time step may change on the way: the head stops where it is due, not after a step count.
  const long most_steps = 4 * std::lround(travel / s.tip_speed / w.dt) + 1;
  run_checked(w, most_steps, c.limits,
              [&](sim::World& ww) { return ww.walls[kHead].pivot.z > final_z; });
  w.walls[kHead].velocity = {};
  const bool reached = w.walls[kHead].pivot.z <= final_z;
  char target[128];
  std::snprintf(target, sizeof target,
                "vane tips lowered at tip_speed from d/4 above the bed top to %.3g d below it",
                h_v / c.d - 0.5);
  out.add_phase(clock.stop(w, "insert head", target, reached), every_metric());
}

/// Fills the vessel (phase "fill") and sets the bed's health limits: the cell before its settle.
ShearCell fill_cell(const MaterialModel& material, const ShearCellSettings& s,
                    const RunOptions& options, LabOutput& out) {
  ShearCell c;
  sim::World& w = c.w;
  w = cell_world(material, s, options);
  const auto sizes = material.simulated_sizes();
  c.d = 2.0 * particles::max_radius(sizes);
  Rng rng(options.seed);
  const double solid = expected_solid_volume(sizes, s.particles, options.seed);
  // A settled bed (~0.6) about as high as the vessel is wide.
  c.radius = std::max(4.0 * c.d, std::cbrt(solid / (0.6 * 2.0 * M_PI)));
  const double fill_h = solid / (0.2 * M_PI * c.radius * c.radius);
  w.walls.push_back(walls::make_wall("floor", walls::Plane{{0, 0, 0}, {0, 0, 1}}, kWallBottom));
  w.walls.push_back(
      walls::make_wall("vessel", walls::Cylinder{{0, 0, 0}, {0, 0, 1}, c.radius}, kWallDie));
  particles::InsertRequest req =
      material_insert_request(material, particles::CylinderRegion{{0, 0, 0}, c.radius, 0.0, fill_h},
                              static_cast<std::size_t>(s.particles));
  out.add_phase(timed_fill(w, req, rng, s.time_step_safety, material.factors().time), {});
  c.limits = die_limits(w, c.radius, fill_h + s.vane_height * c.d);
  c.limits.lo.z = -fill_h;
  // Settings and metrics are real stresses; the bed feels them x the scaling law's stress factor.
  c.real_kpa = 1e3 * material.factors().stress;
  c.sigma_pre = kShearPreKPa * c.real_kpa * s.stress_scale;
  return c;
}

/// Settles the filled bed (phase "settle") at rest against the pre-shear stress; `checkpoints`
/// as for settle().
void settle_cell(ShearCell& c, const MaterialModel& material, LabOutput& out,
                 const SettleCheckpoints& checkpoints) {
  BedSpec spec;
  spec.max_settle_time = 1.0;
  spec.rest_stress = c.sigma_pre;
  out.add_phase(settle(c.w, spec, c.limits, material.factors().time, checkpoints), every_metric());
}

/// Lowers the head into the settled bed (insert_head) and sets the floor's servo up: the cell
/// built.
void finish_cell(ShearCell& c, const ShearCellSettings& s, LabOutput& out) {
  insert_head(c, s, s.vane_height * c.d, out);
  c.servo.axis = {0, 0, 1};  // the floor pushes the bed up against the head
  c.servo.area = M_PI * c.radius * c.radius;
  c.servo.max_speed = 0.5 * s.tip_speed;
  c.servo.kp = c.servo.max_speed / c.sigma_pre;
  // Removes the steady error of a dilating / compacting bed in ~20 ms.
  c.servo.ki = c.servo.kp / 0.02;
  c.omega = s.tip_speed / c.r_head;
}

struct PreShear {
  double tau = 0.0;    ///< steady shear stress (Pa, simulated)
  double sigma = 0.0;  ///< normal stress measured on the floor meanwhile (Pa, simulated)
};

/// The bed's height between the floor and its top (m).
double bed_height(const ShearCell& c) {
  return metrics::bed_top(c.w) - std::get<walls::Plane>(c.w.walls[kFloor].shape).point.z;
}

/// Whether a mean normal stress is sigma_pre within the stress tolerance.
bool at_pre_stress(const ShearCell& c, const ShearCellSettings& s, double sigma) {
  return std::abs(sigma - c.sigma_pre) <= s.stress_tolerance * c.sigma_pre;
}

/// Where the consolidation stands, for a checkpoint inside it: what the phase fixed when it
/// began, its clock and the floor stress's block means so far (the servo is the cell's own).
/// A record holds it as it is in memory (trivially copyable).
struct Consolidating {
  PhaseMark begun;
  double limit = 0.0;  ///< its time limit (s), from the bed's height when it began
  long steps = 0;      ///< the steps of that limit at the time step it began with
  BlockMeans stress{0.0, 0.0};
};

/// The checkpoint inside the consolidation, before the stage "consolidated".
constexpr const char* kConsolidatingStage = "consolidating";

/// Consolidates at sigma_pre with the head at rest, the bed rising into the vanes (phase
/// "consolidate"), until the floor's stress averaged over a block of consolidation_time is within
/// the stress tolerance of sigma_pre. A loose bed compacts by a good part of its height first, at
/// most at the servo's speed limit: the phase may take the time that limit needs for twice the
/// bed's height. `offer` gets where it stands after each block that does not end it; from
/// `resume` (if set) it goes on where an earlier attempt's phase stood.
void consolidate(ShearCell& c, const ShearCellSettings& s, LabOutput& out,
                 const std::function<void(const Consolidating&)>& offer,
                 const Consolidating* resume) {
  Consolidating at;
  if (resume) {
    at = *resume;
  } else {
    at.begun = {c.w.step_count, c.w.time, 0.0};
    at.limit = s.consolidation_time + 2.0 * bed_height(c) / c.servo.max_speed;
    at.steps = c.servo_start(c.w, c.sigma_pre, at.limit);
    at.stress = BlockMeans(c.w.time, s.consolidation_time);
  }
  const PhaseClock clock(at.begun);
  bool reached = false;
  c.servo_steps(c.w, at.steps - (c.w.step_count - at.begun.steps0), [&](sim::World& w) {
    if (!at.stress.add(w.time, c.floor_stress(w))) return true;
    reached = at_pre_stress(c, s, at.stress.mean_a());
    if (!reached && offer) {
      at.begun = clock.mark();
      offer(at);
    }
    return !reached;
  });
  char target[160];
  std::snprintf(target, sizeof target,
                "floor stress %s +- %.3g %% (simulated), mean over %.3g s, within %.3g s",
                stress_text(c.sigma_pre).c_str(), 100.0 * s.stress_tolerance, s.consolidation_time,
                at.limit);
  // Flags nothing: the pre-shear's steady flow at sigma_pre is the state the metrics come from.
  out.add_phase(clock.stop(c.w, "consolidate", target, reached), {});
}

/// Where the pre-shear stands, for a checkpoint inside it: what the phase fixed when it began, its
/// clock, its thirds' means so far and the series it has recorded (the servo is the cell's own).
struct PreShearing {
  PhaseMark begun;
  long steps = 0;   ///< the steps of max_pre_shear_travel at the time step it began with
  long record = 0;  ///< steps between the series' rows
  BlockMeans thirds{0.0, 0.0};
  double previous_tau = 0.0;  ///< the shear stress of the third before
  PreShear last;              ///< the last third's means
  Series series;
};

template <class A, RecordOf<PreShearing> P>
void record_fields(A& a, P& p) {
  a.field(p.begun);
  a.field(p.steps);
  a.field(p.record);
  a.field(p.thirds);
  a.field(p.previous_tau);
  a.field(p.last);
  a.field(p.series);
}

/// The checkpoint inside the pre-shear, before the stage "re-consolidated".
constexpr const char* kPreShearingStage = "pre-shearing";

/// Turns the head at tip_speed, the floor holding sigma_pre, until the flow is steady (phase
/// "pre-shear"): over the last third of pre_shear_travel diameters of tip travel the floor's mean
/// stress is within the stress tolerance of sigma_pre, the mean shear stress differs from the
/// previous third's by at most pre_shear_steadiness of it, and the tips have travelled at least
/// pre_shear_travel diameters; at most max_pre_shear_travel. The steady shear stress and the
/// normal stress are the last third's means. A bed still compacting or dilating is not in steady
/// flow: its shear stress is that of another normal stress or density (seed 000 §2.7.4: "the
/// duration ... set high enough for the simulation to reach a stationary shear stress").
/// `offer` gets where it stands after each third that does not end it; from `resume` (if set) it
/// goes on where an earlier attempt's phase stood.
PreShear pre_shear(ShearCell& c, const ShearCellSettings& s, const RunOptions& options,
                   LabOutput& out, const std::function<void(const PreShearing&)>& offer,
                   const PreShearing* resume) {
  sim::World& w = c.w;
  const double window = s.pre_shear_travel / 3.0 * c.d / s.tip_speed;
  PreShearing at;
  if (resume) {
    at = *resume;
  } else {
    w.walls[kHead].omega = {0, 0, c.omega};
    at.begun = {w.step_count, w.time, 0.0};
    at.steps = c.servo_start(w, c.sigma_pre, s.max_pre_shear_travel * c.d / s.tip_speed);
    at.record = std::max<long>(1, std::lround(0.002 / w.dt));
    at.thirds = BlockMeans(w.time, window);  // shear stress and floor stress of each third
    at.series = {{"time", "normal_stress_kpa", "shear_stress_kpa", "tip_travel"}, {}};
  }
  const PhaseClock clock(at.begun);
  bool steady = false;
  c.servo_steps(w, at.steps - (w.step_count - at.begun.steps0), [&](sim::World& ww) {
    const double t = ww.time - at.begun.time0;
    const double tau = shear_stress(ww, c.r_head), sigma = c.floor_stress(ww);
    if (ww.step_count % at.record == 0)
      at.series.rows.push_back(
          {ww.time, sigma / c.real_kpa, tau / c.real_kpa, t * s.tip_speed / c.d});
    if (options.progress) options.progress(0.4 * std::min(1.0, t / (3.0 * window)));
    if (!at.thirds.add(ww.time, tau, sigma)) return true;
    at.last = {at.thirds.mean_a(), at.thirds.mean_b()};
    steady =
        at.thirds.blocks() >= 3 && at_pre_stress(c, s, at.last.sigma) &&
        std::abs(at.last.tau - at.previous_tau) <= s.pre_shear_steadiness * std::abs(at.last.tau);
    at.previous_tau = at.last.tau;
    if (!steady && offer) {
      at.begun = clock.mark();
      offer(at);
    }
    return !steady;
  });
  char target[200];
  std::snprintf(target, sizeof target,
                "steady over the last third of %.3g diameters of tip travel: floor stress %s +- "
                "%.3g %%, shear stress within %.3g %% of the third before; within %.3g diameters",
                s.pre_shear_travel, stress_text(c.sigma_pre).c_str(), 100.0 * s.stress_tolerance,
                100.0 * s.pre_shear_steadiness, s.max_pre_shear_travel);
  out.add_phase(clock.stop(w, "pre-shear", target, steady), every_metric());
  w.walls[kHead].omega = {};
  out.series["pre_shear"] = std::move(at.series);
  return at.last;
}

/// The mean of the last `n` values pushed (and of a second quantity alongside), in a ring of
/// its own: a checkpoint record holds it as it stands.
struct WindowMeans {
  long n;
  std::vector<double> a, b;  ///< the last n values, the oldest at `next` once full
  long next = 0, count = 0;
  double sum_a = 0.0, sum_b = 0.0;

  WindowMeans() : WindowMeans(1) {}
  explicit WindowMeans(long size) : n(size), a(size), b(size) {}
  void push(double va, double vb) {
    sum_a += va;
    sum_b += vb;
    if (count == n) {
      sum_a -= a[next];
      sum_b -= b[next];
    } else {
      ++count;
    }
    a[next] = va;
    b[next] = vb;
    next = (next + 1) % n;
  }
  bool full() const { return count == n; }
  double mean_a() const { return sum_a / static_cast<double>(n); }
  double mean_b() const { return sum_b / static_cast<double>(n); }
};

template <class A, RecordOf<WindowMeans> W>
void record_fields(A& a, W& w) {
  a.field(w.n);
  a.field(w.a);
  a.field(w.b);
  a.field(w.next);
  a.field(w.count);
  a.field(w.sum_a);
  a.field(w.sum_b);
}

struct YieldStep {
  double sigma_x = 0.0;  ///< the step's normal stress (Pa, simulated)
  double sigma = 0.0;    ///< normal stress on the floor at the yield point
  double tau = 0.0;      ///< yield shear stress: the peak of the windowed mean
  bool yielded = false;  ///< the tips moved 1.5 diameters within the time
};

/// Where a shear step's shear stands, for a checkpoint inside it: the step's world (a copy of the
/// re-consolidated cell), its clock, the shear's start and steps, the head's turn so far and the
/// windowed means (the servo is the cell's own).
struct ShearStepping {
  std::string world;  ///< the step's world's state (in a record only)
  PhaseMark begun;
  std::int64_t shear_steps0 = 0;  ///< the step count and time when the shear began
  double shear_time0 = 0.0;
  long steps = 0;      ///< the shear's steps at the time step it began with
  double angle = 0.0;  ///< the head's turn so far (rad)
  YieldStep y;
  WindowMeans window;
};

template <class A, RecordOf<ShearStepping> S>
void record_fields(A& a, S& s) {
  a.field(s.world);
  a.field(s.begun);
  a.field(s.shear_steps0);
  a.field(s.shear_time0);
  a.field(s.steps);
  a.field(s.angle);
  a.field(s.y);
  a.field(s.window);
}

/// Steps of a shear step's shear between the offers of a checkpoint inside it.
constexpr long kShearOfferSteps = 10000;

/// Re-consolidates the pre-sheared cell at sigma_pre with the head at rest (phase
/// "re-consolidate"): the state every shear step starts from (the seed's restart files). The five
/// steps start from the same state, so it is made once.
void reconsolidate(ShearCell& c, const ShearCellSettings& s, LabOutput& out) {
  const PhaseClock clock(c.w);
  c.servo_run(c.w, c.sigma_pre, s.consolidation_time, {});
  out.add_phase(clock.stop(c.w, "re-consolidate", "fixed time under the servo", true), {});
}

/// One shear step (phase `name`) from a copy of the re-consolidated cell: reduced to sigma_x, then
/// sheared under torque control, the set torque ramped to twice the pre-shear torque; the yield
/// point is the peak of the shear stress averaged over the time the tips need for 0.5 d at full
/// speed (a shorter mean would pick up contact noise, not the bed's strength). `offer` gets where
/// the shear stands every kShearOfferSteps steps; from `resume` (if set) the step goes on where an
/// earlier attempt's shear stood.
YieldStep shear_step(ShearCell& c, const std::string& name, double step_kpa,
                     const ShearCellSettings& s, double tau_pre, LabOutput& out,
                     const std::function<void(const ShearStepping&, const sim::World&)>& offer,
                     const ShearStepping* resume) {
  sim::World v = c.w;
  ShearStepping at;
  if (resume) {
    at = *resume;
    v.restore_state(at.world);
    at.world.clear();  // v holds it from here; a record takes it from v
  } else {
    at.begun = {v.step_count, v.time, 0.0};
    at.y.sigma_x = step_kpa * c.real_kpa * s.stress_scale;
    at.y.sigma = at.y.sigma_x;
  }
  const PhaseClock step_clock(at.begun);
  if (!resume) {
    c.servo_run(v, at.y.sigma_x, s.consolidation_time, {});
    at.shear_steps0 = v.step_count;
    at.shear_time0 = v.time;
    at.steps = c.servo_start(v, at.y.sigma_x, 2.0 * s.torque_ramp_time + 1.5 * c.d / s.tip_speed);
    at.window = WindowMeans(std::max<long>(1, std::lround(0.5 * c.d / s.tip_speed / v.dt)));
  }
  const double torque_pre = tau_pre * 2.0 * M_PI * std::pow(c.r_head, 3) / 3.0;
  const double t_max = std::max(torque_pre, 1e-12) * 2.0;
  const double gain = c.omega / (0.05 * std::max(torque_pre, 1e-12));
  YieldStep& y = at.y;
  c.servo_steps(v, at.steps - (v.step_count - at.shear_steps0), [&](sim::World& ww) {
    const double t = ww.time - at.shear_time0;
    const double t_set = t_max * std::min(1.0, t / s.torque_ramp_time);
    const double torque = -ww.walls[kHead].torque.z;
    const double om = std::clamp(gain * (t_set - torque), 0.0, c.omega);
    ww.walls[kHead].omega = {0, 0, om};
    at.angle += om * ww.dt;
    at.window.push(shear_stress(ww, c.r_head), c.floor_stress(ww));
    if (at.window.full() && at.window.mean_a() > y.tau) {
      y.tau = at.window.mean_a();
      y.sigma = at.window.mean_b();
    }
    const bool turning = at.angle * c.r_head < 1.5 * c.d;  // yielded: the tips moved 1.5 d
    if (turning && offer && (ww.step_count - at.shear_steps0) % kShearOfferSteps == 0) {
      at.begun = step_clock.mark();
      offer(at, ww);
    }
    return turning;
  });
  y.yielded = at.angle * c.r_head >= 1.5 * c.d;
  out.add_phase(
      step_clock.stop(v, name, "yield: tips moved 1.5 diameters within the time", y.yielded),
      {"yield_locus_slope", "yield_locus_intercept", "ffc", "effective_friction_angle",
       "mohr_consistent", "unconfined_yield_strength", "major_consolidation_stress"});
  return y;
}

}  // namespace

LabOutput ShearCellTest::run(const MaterialModel& material, const Settings& values,
                             const RunOptions& options) {
  const auto s = read_settings<ShearCellSettings>(values, "settings");
  LabOutput out;
  ShearCell c;
  PreShear pre;
  Series points{{"sigma_x_kpa", "sigma_measured_kpa", "yield_shear_stress_kpa"}, {}};
  LineFit locus;
  std::vector<double> ys;
  // The stages: the cell built (filled, settled, the head in the bed), consolidated, pre-sheared
  // and re-consolidated, then each shear step done. Its settle, consolidation, pre-shear and the
  // shear of each step also offer checkpoints inside them: a cohesive bed of fine particles may
  // take most of its run in any of them, and a stopped run then loses little of it.
  std::vector<std::string> names{"cell built", "consolidated", "re-consolidated"};
  std::vector<std::string> shearing;  // inside each shear step
  constexpr std::size_t kFirstStep = 3;
  for (const double kpa : kShearNormalKPa) {
    char name[64];
    std::snprintf(name, sizeof name, "shear step %g kPa", kpa);
    names.emplace_back(name);
    std::snprintf(name, sizeof name, "shearing %g kPa", kpa);
    shearing.emplace_back(name);
  }
  Stages stages(options, std::move(names), out, [&](auto& a) {
    a.field(c);
    a.field(pre);
    a.field(points);
    a.field(locus);
    a.field(ys);
  });
  stages.add_within(kSettlingStage, 0);
  stages.add_within(kConsolidatingStage, 1);
  stages.add_within(kPreShearingStage, 2);
  for (std::size_t k = 0; k < shearing.size(); ++k) stages.add_within(shearing[k], kFirstStep + k);
  // Where each of those phases stands, in its checkpoints' records.
  SettleProgress settling;
  Consolidating consolidating;
  PreShearing pre_shearing;
  ShearStepping shear_stepping;
  // The phase's offer of the checkpoint `stage` from inside it.
  auto offer_at = [&](const char* stage, auto& kept) {
    return [&stages, &c, stage, phase = &kept](const auto& at) {
      stages.offer_within(stage, c.w, [&](auto& a) {
        *phase = at;  // only for a checkpoint the receiver keeps
        a.field(*phase);
      });
    };
  };
  // Where the phase stands when the run goes on from the checkpoint `stage` inside it, else null.
  auto resumed_at = [&](const std::string& stage, auto& kept) -> decltype(&kept) {
    if (!stages.resuming_within(stage)) return nullptr;
    stages.read_within([&](auto& a) { a.field(kept); });
    out.cost.wall_seconds += kept.begun.wall_seconds;  // the earlier attempt's, in the phase
    return &kept;
  };
  std::size_t next = 0;
  if (stages.resuming()) {
    c.w = cell_world(material, s, options);
    next = stages.resume(c.w);
  }
  if (next == 0) {
    const SettleProgress* from = resumed_at(kSettlingStage, settling);
    if (!from) c = fill_cell(material, s, options, out);
    settle_cell(c, material, out, {offer_at(kSettlingStage, settling), from});
    finish_cell(c, s, out);
    stages.reached(0, c.w);
  }
  if (next <= 1) {
    consolidate(c, s, out, offer_at(kConsolidatingStage, consolidating),
                resumed_at(kConsolidatingStage, consolidating));
    stages.reached(1, c.w);
  }
  if (next <= 2) {
    pre = pre_shear(c, s, options, out, offer_at(kPreShearingStage, pre_shearing),
                    resumed_at(kPreShearingStage, pre_shearing));
    write_snapshot(c.w, options, "shear_cell_preshear", out, c.radius);
    reconsolidate(c, s, out);
    stages.reached(2, c.w);
  }
  // The shear steps, each from the re-consolidated state (c.w, left as it is); the locus uses the
  // normal stress measured on the floor at the yield point.
  for (std::size_t k = std::max(next, kFirstStep) - kFirstStep; k < kShearNormalKPa.size(); ++k) {
    const std::size_t stage = kFirstStep + k;
    const std::string& within = shearing[k];
    const YieldStep y = shear_step(
        c, stages.name(stage), kShearNormalKPa[k], s, pre.tau, out,
        [&](const ShearStepping& at, const sim::World& step_world) {
          stages.offer_within(within, c.w, [&](auto& a) {
            shear_stepping = at;  // only for a checkpoint the receiver keeps
            shear_stepping.world = step_world.save_state();
            a.field(shear_stepping);
          });
        },
        resumed_at(within, shear_stepping));
    points.rows.push_back({y.sigma_x / c.real_kpa, y.sigma / c.real_kpa, y.tau / c.real_kpa});
    locus.add(y.sigma / c.real_kpa, y.tau / c.real_kpa);
    ys.push_back(y.tau / c.real_kpa);
    if (options.progress)
      options.progress(0.4 + 0.6 * static_cast<double>(k + 1) /
                                 static_cast<double>(kShearNormalKPa.size()));
    stages.reached(stage, c.w);
  }
  // The yield locus: least squares tau = slope sigma + intercept through the yield points (kPa).
  const MohrResult mohr = mohr_evaluation(locus.slope(), locus.intercept(),
                                          c.sigma_pre / c.real_kpa, pre.tau / c.real_kpa);
  out.metrics["pre_shear_stress"] = pre.tau / c.real_kpa;
  out.metrics["pre_shear_normal_stress"] = pre.sigma / c.real_kpa;
  add_locus_metrics(out, locus, mohr, ys);
  out.series["yield_points"] = std::move(points);
  out.series["mohr_circles"] = mohr_circles(mohr);
  out.cost.close(c.w);
  return out;
}

}  // namespace demcal::lab
