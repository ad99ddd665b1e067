#pragma once
// Building a powder bed in a cylindrical die from a material model: the shared first phase of
// the lab tests (seed 000 §2.7.1: random non-overlapping insertion in a cylinder, then settling
// under gravity). Tests then add pistons, cut the bed, or shear it.
#include <functional>
#include <limits>

#include "core/lab/lab_run.hpp"
#include "core/particles/insertion.hpp"
#include "core/sim/health.hpp"
#include "core/sim/world.hpp"

namespace demcal::lab {

struct BedSpec {
  std::size_t particles = 300;
  double die_radius = 0.0;  ///< (m); 0 = chosen so the settled bed is about as high as wide
  double insert_height =
      0.0;  ///< height of the insertion region (m); 0 = from a loose fraction 0.25
  double time_step_safety = 0.2;  ///< dt = safety * critical time step
  /// At rest (docs/lab-tests.md, "Settling") when the kinetic stress of the residual motion,
  /// rho_p <v^2> (mass-weighted mean), is below rest_inertial_number^2 times the reference
  /// stress: the test's stress level, or the bed's weight stress for a test without one.
  /// 1e-3: the motion carries 1e-6 of that stress (GDR MiDi's quasi-static bound on I).
  double rest_inertial_number = 1e-3;
  double rest_stress = 0.0;  ///< stress level of the test (Pa, simulated); 0 = the bed's weight
  /// ... and the bed no longer sinks: its centre of mass moved by less than this fraction of the
  /// bed's height per real second over the last five checks (0.01 s real).
  double rest_sink_rate = 1e-3;
  double max_settle_time = 2.0;  ///< (s), real: x the material's time factor when simulated
  /// The creep rule and budget of a bed that starts where it ends (the growth preparation;
  /// 0 = off, the rules above alone): checks every fifth of `creep_window` (s, simulated) from
  /// one window on, and the bed is at rest only if, besides the rules above, its height h (twice
  /// its centre of mass above its bottom) changed over the last window at an inertial number
  /// I_h = (|dh| / h / dt) d_mean sqrt(rho_p / sigma_ref) below `creep_inertial_number`
  /// (sigma_ref the quiet rule's stress); it ends unsettled at `settle_budget` (s, simulated).
  double creep_window = 0.0;
  double creep_inertial_number = 0.0;
  double settle_budget = 0.0;
};

/// Wall materials used by the lab tests: the particle-wall law of the material model is given
/// to every wall material unless a test overrides one (e.g. adhesive piston, frictionless die).
enum WallMaterial : std::uint16_t {
  kWallDefault = 0,
  kWallDie = 1,
  kWallPiston = 2,
  kWallBottom = 3
};

/// A world with the material's simulated particle-particle law and its particle-wall law for
/// every lab wall material; the lab tests add their walls and particles.
sim::World make_material_world(const MaterialModel& material, const RunOptions& options);

/// The contact range check a world of the material makes at its start (sim::check_contact_range),
/// on the material alone: its simulated particle law between two of its smallest particles.
/// Throws SimulationFailure(kContactOutOfRange).
void check_contact_range(const MaterialModel& material);

/// An insertion request for `count` particles of the material (its simulated sizes and density,
/// and its clump shape if not spherical) into `region`.
particles::InsertRequest material_insert_request(const MaterialModel& material,
                                                 const particles::Region& region,
                                                 std::size_t count);

/// Inserts the request's particles into the world as a filling would: what fits at random
/// without overlap, then a pause of 0.1 s (real; x `time_factor` as in settle()) in which it
/// falls, then the rest, for at most `rounds` rounds (a dense fill, or clumps that take more room
/// than spheres). Sets the world's time step to `time_step_safety` times the critical one.
void fill_region(sim::World& world, particles::InsertRequest request, Rng& rng,
                 double time_step_safety, double time_factor, int rounds = 8);

/// fill_region as a recorded phase "fill".
PhaseCost timed_fill(sim::World& world, const particles::InsertRequest& request, Rng& rng,
                     double time_step_safety, double time_factor);

/// Expected solid volume of `count` particles of the distribution (mean of 2,000 seeded samples),
/// for sizing a die, drum or hopper to its bed.
double expected_solid_volume(const particles::SizeDistribution& sizes, double count,
                             std::uint64_t seed);

/// The height of the die world's floor (m): where make_die_world puts the bottom wall.
inline constexpr double kDieFloorZ = 0.0;

/// A world with the material's simulated laws, a floor (kWallBottom, at kDieFloorZ) and a die
/// (kWallDie, an inner cylinder about the z axis), and the particles inserted at random without
/// overlap.
sim::World make_die_world(const MaterialModel& material, const BedSpec& spec,
                          const RunOptions& options);

/// Height of the highest particle top (m), 0 for an empty world.
double metrics_top(const sim::World& world);

/// One check of a settle phase: the time and the height of the bed's centre of mass.
struct SettleCheck {
  double time = 0.0, z = 0.0;
};

/// Where a settle phase stands: what it derived from the bed when it began, its clock and the
/// checks it has made. With the world's state it is all the phase carries from check to check,
/// so a settle resumed from it goes on as the phase that made it would have.
struct SettleProgress {
  double bottom = 0.0, top = 0.0;  ///< the bed's lowest and highest point when it began (m)
  long chunk = 0;                  ///< steps between checks (from the time step it began with)
  PhaseMark begun;
  std::vector<SettleCheck> checks;
};

/// A settle progress in a checkpoint record (core/lab/stages.hpp).
template <class A, RecordOf<SettleProgress> P>
void record_fields(A& a, P& p) {
  a.field(p.bottom);
  a.field(p.top);
  a.field(p.chunk);
  a.field(p.begun);
  a.field(p.checks);
}

/// The checkpoint inside a test's settle phase, before the stage of its settled bed.
inline constexpr const char* kSettlingStage = "settling";

/// Checkpoints inside a settle phase, which in a cohesive bed of fine particles can take most of
/// a run: `offer` (if set) gets the progress after each check that did not end the phase;
/// `resume` (if set) is where an earlier attempt's phase stood, and the phase goes on from there.
struct SettleCheckpoints {
  std::function<void(const SettleProgress&)> offer;
  const SettleProgress* resume = nullptr;
};

/// Steps until the bed is at rest (mean kinetic energy criterion of BedSpec) or max time; checks
/// health every few hundred steps. Returns the phase "settle" with whether it came to rest.
/// `time_factor` turns the protocol's real seconds (the checks every 0.002 s, max_settle_time)
/// into simulated ones: the material's ScaleFactors::time where the test's geometry follows its
/// particles (a coarse-grained bed is then the similar bed of the real particles, exactly), 1
/// where the geometry is the real apparatus (the rotating drum).
PhaseCost settle(sim::World& world, const BedSpec& spec, const sim::HealthLimits& limits,
                 double time_factor, const SettleCheckpoints& checkpoints = {});

/// What the growth preparation built before gravity came on (grow_bed).
struct GrownBed {
  double critical_time = 0.0;    ///< sqrt(m / k1) of a fresh particle contact (Rayleigh: Hertz)
  double start_factor = 0.0;     ///< radius factor the particles were inserted at
  double growth_time = 0.0;      ///< (s, simulated) to full size, quench after it excluded
  double height = 0.0;           ///< the lid's height: the die volume at the target fraction (m)
  double largest_overlap = 0.0;  ///< largest particle-particle overlap over the smaller radius
  double solid_fraction = 0.0;   ///< one largest diameter from die, floor and lid
  double coordination = 0.0;     ///< of the particles whose centres lie there
};

/// Method growth (material.preparation): the particles, inserted by make_die_world at reduced
/// radii with their full masses, grow at `growth_rate` per critical time without gravity under
/// a lid at the height of the die volume at `solid_fraction`, their motion quenched, cohesion only
/// in contact; then the lid goes and gravity comes back. Only the die tests' sphere
/// beds are inserted so (their admission refuses growth elsewhere: core/model/catalog.hpp).
GrownBed grow_bed(sim::World& world, const MaterialModel& material,
                  const sim::HealthLimits& limits);

/// The phases that built a bed from its inserted particles.
struct PreparedBed {
  PhaseCost prepared;  ///< "prepare <method>": no steps for pouring
  PhaseCost settled;
  GrownBed grown;  ///< growth only
};
/// A grown bed in a checkpoint record.
template <class A, RecordOf<GrownBed> G>
void record_fields(A& a, G& g) {
  for (auto* v : {&g.critical_time, &g.start_factor, &g.growth_time, &g.height, &g.largest_overlap,
                  &g.solid_fraction, &g.coordination})
    a.field(*v);
}

/// Builds the bed by the material's preparation method (material.preparation, seed 000 §2.7.1)
/// from the particles inserted below `lid` (the top of the insertion region, where the lid of
/// the methods with free motion sits) and leaves it under the law it settles with (the full van
/// der Waals law after clusters, cohesion only in contact otherwise). Fills `prepared` (and
/// `grown` for growth), not `settled`.
PreparedBed prepare_bed(sim::World& world, const MaterialModel& material,
                        const sim::HealthLimits& limits, double lid, std::uint64_t seed);

/// For a run resumed inside the settle of a prepared bed: gives the world, made as the test
/// makes it, the law the bed settles with, before its state is restored.
void set_settling_law(sim::World& world, const MaterialModel& material);

/// Settles a prepared bed (growth with the creep rule and budget of BedSpec, in critical times
/// of its grown bed), records the phase in `bed.settled` and gives the particles back
/// `full_law`, the material's law the world had before its preparation.
void settle_prepared(sim::World& world, const MaterialModel& material, const BedSpec& spec,
                     const sim::HealthLimits& limits, const contact::ContactLaw& full_law,
                     PreparedBed& bed, const SettleCheckpoints& checkpoints = {});

/// prepare_bed, then settle_prepared.
PreparedBed prepare_and_settle(sim::World& world, const MaterialModel& material,
                               const BedSpec& spec, const sim::HealthLimits& limits, double lid,
                               std::uint64_t seed);

/// Steps `steps` steps with a health check every `check_every`, calling `each` (if given) after
/// every step; stops early when `each` returns false. Returns the steps done.
long run_checked(sim::World& world, long steps, const sim::HealthLimits& limits,
                 const std::function<bool(sim::World&)>& each = {}, int check_every = 200);

/// Health limits for a die world: particles must stay within a box around the die.
sim::HealthLimits die_limits(const sim::World& world, double die_radius, double height);

// ---- What the die tests share (their pistons and servo phases: piston.hpp) ----

/// Radius of the die (wall 1 of make_die_world).
double die_radius(const sim::World& world);

/// The wall law spec with every stiffness of its normal slot (parameters in N/m or Pa: k1, kn,
/// youngs_modulus) multiplied by `factor` (seed 000 §2.7.2: k_l,wall = 30 k_l).
contact::ContactLawSpec stiffen_normal(const contact::ContactLawSpec& spec, double factor);
/// The simulated (scaled) form of a law spec under the material's coarse-graining.
contact::ContactLaw simulated_law(const MaterialModel& material,
                                  const contact::ContactLawSpec& spec);

}  // namespace demcal::lab

namespace demcal::lab {
/// Writes `<dir>/<name>_particles.vtk` and `<name>_walls.vtk` when options.snapshot_dir is set
/// and records them in out.snapshots; the walls are drawn over `extent` (m; 0: the die's
/// diameter).
void write_snapshot(const sim::World& world, const RunOptions& options, const std::string& name,
                    LabOutput& out, double extent = 0.0);
}  // namespace demcal::lab
