#include "core/lab/bed.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <optional>

#include "core/common/rng.hpp"
#include "core/io/vtk.hpp"
#include "core/lab/run_cancelled.hpp"
#include "core/metrics/bulk.hpp"
#include "core/model/packing_settings.hpp"
#include "core/particles/insertion.hpp"
#include "core/sim/step.hpp"
#include "core/sim/time_step.hpp"
#include "core/walls/servo.hpp"

namespace demcal::lab {
namespace {

/// growth: the solid fraction the die volume holds the particles at when they are inserted at
/// reduced radii; random sequential insertion of equal spheres jams only at ~0.38 (Torquato,
/// Uche & Stillinger, Phys. Rev. E 74 (2006) 061308), so 0.2 inserts every particle at the first
/// attempt round, size distributions included.
constexpr double kGrowthInsertFraction = 0.2;

/// growth: the radius factor the particles are inserted at, phi_insert = phi_target f0^3.
double growth_start_factor(const PreparationSpec& s) {
  return std::cbrt(kGrowthInsertFraction / s.solid_fraction);
}

/// The distribution with every radius times `factor`.
particles::SizeDistribution shrunk(particles::SizeDistribution sizes, double factor) {
  std::visit(
      [factor](auto& d) {
        using D = std::decay_t<decltype(d)>;
        if constexpr (std::is_same_v<D, particles::Monodisperse>)
          d.radius *= factor;
        else if constexpr (std::is_same_v<D, particles::DiscreteClasses>)
          for (double& r : d.radii) r *= factor;
        else
          d.median_radius *= factor;
      },
      sizes);
  return sizes;
}

/// The radius of a sphere of `mass` at `density`: 3 m / (4 pi rho) = r^3.
double full_radius(double mass, double density) {
  return std::cbrt(mass / (4.0 / 3.0 * M_PI * density));
}

/// growth: the particles of the request at `factor` times their sampled radii, each with the
/// mass and moment of inertia (2/5 m r^2) of its full size, so that growth changes the radius
/// alone and the bed has its real masses throughout: the time step bounds sqrt(m / k) are the
/// test's from the start, and nothing needs to be set right after growth.
void insert_shrunk(sim::World& w, particles::InsertRequest req, Rng& rng, double safety,
                   double factor) {
  req.sizes = shrunk(req.sizes, factor);
  const std::size_t first = w.particles.size();
  sim::insert_random(w, req, rng);
  auto& p = w.particles;
  for (std::size_t i = first; i < p.size(); ++i) {
    const double r = p.radius[i] / factor;
    p.mass[i] = req.density * 4.0 / 3.0 * M_PI * r * r * r;
    p.inertia[i] = 0.4 * p.mass[i] * r * r;
    p.set_motion(i, p.motion[i]);
  }
  w.adaptive_safety = safety;
  w.dt = sim::adapted_time_step(w, safety);
}

}  // namespace

double metrics_top(const sim::World& w) {
  double top = 0.0;
  for (std::size_t i = 0; i < w.particles.size(); ++i)
    top = std::max(top, w.particles.x[i].z + w.particles.radius[i]);
  return top;
}

sim::World make_material_world(const MaterialModel& material, const RunOptions& options) {
  sim::World w;
  w.threads = options.threads;
  w.set_pair_law(0, 0, material.simulated_particle_law());
  const auto wall_law = material.simulated_wall_law();
  for (std::uint16_t m : {kWallDefault, kWallDie, kWallPiston, kWallBottom})
    w.set_wall_law(m, 0, wall_law);
  return w;
}

void check_contact_range(const MaterialModel& material) {
  const double r = particles::min_radius(material.simulated_sizes());
  sim::check_pair_range(material.simulated_particle_law(), r, r, "the material");
}

double expected_solid_volume(const particles::SizeDistribution& sizes, double count,
                             std::uint64_t seed) {
  constexpr int kSamples = 2000;
  Rng rng(seed ^ 0x5eed);
  double solid = 0.0;
  for (int k = 0; k < kSamples; ++k)
    solid += 4.0 / 3.0 * M_PI * std::pow(particles::sample_radius(sizes, rng), 3);
  return solid * (count / kSamples);
}

particles::InsertRequest material_insert_request(const MaterialModel& material,
                                                 const particles::Region& region,
                                                 std::size_t count) {
  particles::InsertRequest req;
  req.region = region;
  req.sizes = material.simulated_sizes();
  req.count = count;
  req.density = material.simulated_density();
  req.shape = material.clump_template();
  return req;
}

void fill_region(sim::World& w, particles::InsertRequest req, Rng& rng, double safety,
                 double time_factor, int rounds) {
  constexpr double kPause = 0.1;  // real seconds
  const double pause = kPause * time_factor;
  const std::size_t goal = w.particles.units() + req.count;
  for (int round = 1;; ++round) {
    req.count = goal - w.particles.units();
    try {
      sim::insert_random(w, req, rng);
    } catch (const InputError&) {
      if (round == rounds) throw;
    }
    w.adaptive_safety = safety;
    w.dt = sim::adapted_time_step(w, safety);
    if (w.particles.units() == goal) return;
    sim::run(w, std::max<long>(1, std::lround(pause / w.dt)));
  }
}

PhaseCost timed_fill(sim::World& w, const particles::InsertRequest& req, Rng& rng, double safety,
                     double time_factor) {
  const PhaseClock clock(w);
  fill_region(w, req, rng, safety, time_factor);
  return clock.stop(w, "fill", "all particles inserted", true);
}

sim::World make_die_world(const MaterialModel& material, const BedSpec& spec,
                          const RunOptions& options) {
  sim::World w = make_material_world(material, options);
  const auto sizes = material.simulated_sizes();

  Rng rng(options.seed);
  const double solid =
      expected_solid_volume(sizes, static_cast<double>(spec.particles), options.seed);
  const double radius = spec.die_radius > 0.0 ? spec.die_radius : die_radius_for(solid);
  // Clumps are inserted by their bounding spheres: the loose column is taller by their volume.
  particles::InsertRequest req = material_insert_request(material, {}, spec.particles);
  const PreparationSpec& prep = material.preparation;
  const bool grown = prep.method == PreparationMethod::kGrowth;
  if (grown && req.shape)  // refused at admission (core/model/catalog.cpp)
    throw std::logic_error("growth of a clump bed");
  const double bound = req.shape ? req.shape->bounding_radius : 1.0;
  const double r_max = particles::max_radius(sizes) * bound;
  // growth: the die up to the bed's height at the target solid fraction.
  const double height =
      grown ? solid / (prep.solid_fraction * M_PI * radius * radius)
      : spec.insert_height > 0.0
          ? spec.insert_height
          : std::max(bound * bound * bound * solid / (0.25 * M_PI * radius * radius), 4.0 * r_max);

  w.walls.push_back(
      walls::make_wall("bottom", walls::Plane{{0, 0, kDieFloorZ}, {0, 0, 1}}, kWallBottom));
  w.walls.push_back(
      walls::make_wall("die", walls::Cylinder{{0, 0, 0}, {0, 0, 1}, radius}, kWallDie));
  req.region = particles::CylinderRegion{{0, 0, 0}, radius, kDieFloorZ, kDieFloorZ + height};
  if (grown)
    insert_shrunk(w, req, rng, spec.time_step_safety, growth_start_factor(prep));
  else
    fill_region(w, req, rng, spec.time_step_safety, material.factors().time);
  return w;
}

sim::HealthLimits die_limits(const sim::World& world, double die_radius, double height) {
  sim::HealthLimits h;
  // The whole bed falling through the die.
  h.max_kinetic_energy = sim::kinetic_energy_limit(
      world,
      world.particles.total_mass() * std::max(norm(world.gravity), 1.0) * (height + die_radius));
  h.lo = {-2.0 * die_radius, -2.0 * die_radius, -0.5 * die_radius};
  h.hi = {2.0 * die_radius, 2.0 * die_radius, 2.0 * height + 2.0 * die_radius};
  return h;
}

long run_checked(sim::World& world, long steps, const sim::HealthLimits& limits,
                 const std::function<bool(sim::World&)>& each, int check_every) {
  constexpr long kPollEvery = 64;  // steps between progress polls (a stop request is heard)
  for (long s = 0; s < steps; ++s) {
    sim::step(world);
    if ((s + 1) % check_every == 0) sim::check_health(world, limits);
    if ((s + 1) % kPollEvery == 0) poll_progress();
    if (each && !each(world)) {
      sim::check_health(world, limits);
      return s + 1;
    }
  }
  sim::check_health(world, limits);
  return steps;
}

namespace {

double mean_diameter(const particles::ParticleStore& p) {
  double sum = 0.0;
  for (double r : p.radius) sum += 2.0 * r;
  return p.size() ? sum / static_cast<double>(p.size()) : 0.0;
}

/// Height of the bed's centre of mass (m).
double centre_height(const particles::ParticleStore& p) {
  double mass = 0.0, moment = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    mass += p.mass[i];
    moment += p.mass[i] * p.x[i].z;
  }
  return mass > 0.0 ? moment / mass : 0.0;
}

/// The bed's centre of mass at each settling check, and whether the bed has stopped sinking.
class SinkWatch {
 public:
  /// Watches `checks`, those of a resumed phase included, and adds to them.
  explicit SinkWatch(std::vector<SettleCheck>& checks) : checks_(checks) {}
  void record(const sim::World& w) { checks_.push_back({w.time, centre_height(w.particles)}); }
  /// The centre of mass moved by less than `rate` x the bed's height (twice the centre's height
  /// above `bottom`) per real second over the last kChecks checks.
  bool still(double rate, double bottom, double time_factor) const {
    if (checks_.size() <= kChecks) return false;
    const auto& [t_now, z_now] = checks_.back();
    const auto& [t_then, z_then] = checks_[checks_.size() - 1 - kChecks];
    const double real_time = (t_now - t_then) / time_factor;
    return std::abs(z_now - z_then) < rate * 2.0 * (z_now - bottom) * real_time;
  }
  /// The bed's strain rate |dh| / h / dt (1/s, simulated) over the last `window` (s) or more,
  /// h = twice the centre's height above `bottom`; infinite before a whole window is recorded.
  double strain_rate(double window, double bottom) const {
    const auto& [t_now, z_now] = checks_.back();
    for (auto it = checks_.rbegin(); it != checks_.rend(); ++it)
      if (t_now - it->time >= window)
        return std::abs(z_now - it->z) / (z_now - bottom) / (t_now - it->time);
    return std::numeric_limits<double>::infinity();
  }

 private:
  static constexpr std::size_t kChecks = 5;
  std::vector<SettleCheck>& checks_;
};

/// Where a settle phase begins: the bed's extent and the steps between checks (from the time
/// step it begins with), its clock at the world's step and time.
SettleProgress settle_start(const sim::World& w, const BedSpec& spec, double time_factor) {
  SettleProgress s;
  const auto& p = w.particles;
  s.bottom = std::numeric_limits<double>::infinity();
  s.top = -s.bottom;
  for (std::size_t i = 0; i < p.size(); ++i) {
    s.bottom = std::min(s.bottom, p.x[i].z - p.radius[i]);
    s.top = std::max(s.top, p.x[i].z + p.radius[i]);
  }
  s.chunk = spec.creep_window > 0.0 ? std::max<long>(1, std::lround(0.2 * spec.creep_window / w.dt))
                                    : std::max<long>(200, std::lround(0.002 * time_factor / w.dt));
  s.begun = {w.step_count, w.time, 0.0};
  return s;
}

}  // namespace

PhaseCost settle(sim::World& w, const BedSpec& spec, const sim::HealthLimits& limits,
                 double time_factor, const SettleCheckpoints& checkpoints) {
  SettleProgress at = checkpoints.resume ? *checkpoints.resume : settle_start(w, spec, time_factor);
  const PhaseClock clock(at.begun);
  const double max_time = spec.max_settle_time * time_factor;
  const auto& p = w.particles;
  double mass = 0.0, volume = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    mass += p.mass[i];
    volume += 4.0 / 3.0 * M_PI * std::pow(p.radius[i], 3);
  }
  const double rho = volume > 0.0 ? mass / volume : 0.0;
  const double bottom = at.bottom;
  const double height = std::max(at.top - bottom, 0.0);
  const double g = norm(w.gravity);
  // Two ways to rest, the first met ends the phase:
  // - quiet: the kinetic stress is small against the order of the bed's weight stress (solid
  //   fraction 0.6 over the column) or the test's stress level where that is lower; the bed
  //   height the tests start from is read at rest under the bed's own weight;
  // - static: the bed no longer sinks (below) and the kinetic stress is small against the
  //   test's stress level (its weight stress for a test without one): a bed whose structure has
  //   stopped moving is settled even while its contacts still ring at the level of its weight.
  constexpr double kSolidFraction = 0.6;
  const double weight = kSolidFraction * rho * g * height;
  const double quiet_stress = spec.rest_stress > 0.0 ? std::min(spec.rest_stress, weight) : weight;
  const double static_stress = spec.rest_stress > 0.0 ? spec.rest_stress : weight;
  // rho <v^2> < I^2 sigma with <v^2> = 2 KE / M.
  const double ke_per_stress =
      0.5 * mass * spec.rest_inertial_number * spec.rest_inertial_number / rho;
  // Freshly inserted particles are at rest before they fall: the criterion counts only after
  // the free-fall time of the column they were inserted in.
  // A bed that starts where it ends (creep rule on) has no column to fall: its first window.
  const bool creep_rule = spec.creep_window > 0.0;
  const double fall = creep_rule ? spec.creep_window : g > 0.0 ? std::sqrt(2.0 * height / g) : 0.0;
  const double t_end = creep_rule ? std::min(max_time, spec.settle_budget) : max_time;
  // The creep rule's inertial number of the bed's height change, I_h = strain rate x
  // d sqrt(rho_p / sigma_ref) (GDR MiDi 2004, with the bed's strain rate for the shear rate).
  const double creep_time = mean_diameter(p) * std::sqrt(rho / quiet_stress);
  const double t0 = at.begun.time0;
  SinkWatch sinking(at.checks);
  bool rest = false;
  while (!rest && w.time - t0 < t_end) {
    run_checked(w, at.chunk, limits);
    sinking.record(w);
    const bool still = sinking.still(spec.rest_sink_rate, bottom, time_factor);
    const double ke = p.kinetic_energy();
    rest = w.time - t0 >= fall &&
           (ke < ke_per_stress * quiet_stress || (still && ke < ke_per_stress * static_stress));
    if (creep_rule)
      rest = rest && sinking.strain_rate(spec.creep_window, bottom) * creep_time <
                         spec.creep_inertial_number;
    if (!rest && checkpoints.offer) {
      at.begun = clock.mark();
      checkpoints.offer(at);
    }
  }
  char target[200];
  std::snprintf(target, sizeof target,
                "kinetic stress < %.3g^2 x %s, or sinking < %.3g x height per s and kinetic "
                "stress < %.3g^2 x %s (simulated), within %.3g s",
                spec.rest_inertial_number, stress_text(quiet_stress).c_str(), spec.rest_sink_rate,
                spec.rest_inertial_number, stress_text(static_stress).c_str(), t_end);
  char creep[120] = "";
  if (creep_rule)
    std::snprintf(creep, sizeof creep, "; and the height's change over %.3g s at I_h < %.3g",
                  spec.creep_window, spec.creep_inertial_number);
  return clock.stop(w, "settle", std::string(target) + creep, rest);
}

namespace {

/// The particle law with its van der Waals range cut to contact (D_max = 1.01 D_min): the
/// "cohesion when in contact" of seed 000 §2.7.1 methods 2-4; none when the law already is so
/// (no van der Waals, or its range no longer).
std::optional<contact::ContactLawSpec> contact_only(contact::ContactLawSpec spec) {
  if (spec.cohesion.model != "van_der_waals") return std::nullopt;
  auto& params = spec.cohesion.params;
  const double d_min = params.count("d_min") ? params["d_min"] : 4e-10;
  const double reach = 1.01 * d_min;
  if (params.count("d_max") && params["d_max"] <= reach) return std::nullopt;
  params["d_max"] = reach;
  return spec;
}

/// Cohesion only in contact from now on, for the fall (the contact history of the fill starts
/// afresh).
void cohesion_in_contact(sim::World& w, const MaterialModel& material) {
  if (const auto spec = contact_only(material.particle_law))
    w.set_pair_law(0, 0, simulated_law(material, *spec));
}

/// Methods clusters and random_motion: free motion without cohesion and gravity under a lid at
/// `lid`, then (clusters) the motion stopped and the full law on, or (random motion) the motion
/// kept and cohesion in contact, still without gravity; the lid is removed, gravity restored.
void agitate(sim::World& w, const MaterialModel& material, const sim::HealthLimits& limits,
             double lid, std::uint64_t seed) {
  const PreparationSpec& s = material.preparation;
  auto& p = w.particles;
  const Vec3 g = w.gravity;
  const auto full_law = w.pair_law(0, 0);
  contact::ContactLawSpec plain = material.particle_law;
  plain.cohesion = {"none", {}};
  w.set_pair_law(0, 0, simulated_law(material, plain));
  w.gravity = {};
  w.walls.push_back(walls::make_wall("lid", walls::Plane{{0, 0, lid}, {0, 0, -1}}, kWallDie));
  const double d_mean = mean_diameter(p);
  const double v_a = s.agitation_speed > 0.0 ? s.agitation_speed : std::sqrt(norm(g) * d_mean);
  const double t_a = s.agitation_time > 0.0 ? s.agitation_time : 3.0 * d_mean / v_a;
  const double t_c = s.cluster_time > 0.0 ? s.cluster_time : t_a;
  Rng rng(seed ^ 0xa917a7e);
  for (auto& v : p.v) v = {v_a * rng.normal(), v_a * rng.normal(), v_a * rng.normal()};
  run_checked(w, std::lround(t_a / w.dt), limits);
  if (s.method == PreparationMethod::kClusters) {
    for (auto& v : p.v) v = {};
    for (auto& o : p.omega) o = {};
    w.set_pair_law(0, 0, full_law);
  } else {
    const auto touch = contact_only(material.particle_law);
    w.set_pair_law(0, 0, touch ? simulated_law(material, *touch) : full_law);
  }
  run_checked(w, std::lround(t_c / w.dt), limits);
  w.walls.pop_back();
  w.gravity = g;
}

/// Method terminal_velocity: the fall with every particle's speed capped at its Stokes terminal
/// velocity in air (mu = 1.81e-5 Pa s), or the given cap, from the top `lid` to the floor.
void fall_at_terminal_velocity(sim::World& w, const MaterialModel& material,
                               const sim::HealthLimits& limits, double lid) {
  constexpr double kMuAir = 1.81e-5;
  auto& p = w.particles;
  std::vector<double> cap(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double rho = p.mass[i] / (4.0 / 3.0 * M_PI * std::pow(p.radius[i], 3));
    cap[i] = material.preparation.terminal_velocity > 0.0
                 ? material.preparation.terminal_velocity
                 : rho * norm(w.gravity) * 4.0 * p.radius[i] * p.radius[i] / (18.0 * kMuAir);
  }
  if (cap.empty()) return;
  const double fall = std::max(lid / *std::min_element(cap.begin(), cap.end()), 0.0);
  run_checked(w, std::lround(std::min(fall, 20.0) / w.dt), limits, [&](sim::World& world) {
    for (std::size_t i = 0; i < world.particles.size(); ++i) {
      const double v = norm(world.particles.v[i]);
      if (v > cap[i]) world.particles.v[i] *= cap[i] / v;
    }
    return true;
  });
}

/// growth: the critical time of a fresh particle-particle contact at the particles' full
/// radii `full` (sqrt(m / k1) of a Luding or linear law, the Rayleigh time of a Hertz law:
/// sim::fresh_contact_time_step over the particle law alone, walls excluded, so that the growth
/// does not depend on a test's wall stiffness).
double particle_contact_time(const sim::World& w, const std::vector<double>& full) {
  sim::World probe;
  probe.particles = w.particles;
  probe.particles.radius = full;
  probe.set_pair_law(0, 0, w.pair_law(0, 0));
  return sim::fresh_contact_time_step(probe).critical;
}

/// The largest overlap of two listed particles over the smaller radius (the list rebuilt first,
/// so that it holds every pair in reach).
double largest_overlap(sim::World& w) {
  w.rebuild_list();
  const auto& p = w.particles;
  double worst = 0.0;
  for (std::size_t i = 0; i + 1 < w.list.row_start.size(); ++i)
    for (int k = w.list.row_start[i]; k < w.list.row_start[i + 1]; ++k) {
      const auto j = static_cast<std::size_t>(w.list.nbr[k]);
      const double gap = norm(p.x[j] - p.x[i]) - p.radius[i] - p.radius[j];
      worst = std::max(worst, -gap / std::min(p.radius[i], p.radius[j]));
    }
  return worst;
}

/// growth: gives every lab wall material the material's wall law without friction, rolling
/// resistance and adhesion (its slots kept, their forces zero, as the tensile test's die), and
/// returns the laws they had.
std::vector<std::pair<std::uint16_t, contact::ContactLaw>> smooth_walls(
    sim::World& w, const MaterialModel& material) {
  contact::ContactLawSpec smooth = material.wall_law;
  if (smooth.cohesion.model == "van_der_waals") smooth.cohesion.params["hamaker"] = 0.0;
  if (smooth.rolling.model != "none") smooth.rolling.params["mu_r"] = 0.0;
  smooth.tangential.params["mu_s"] = 0.0;
  if (smooth.normal.model == "luding") smooth.normal.params["kc_ratio"] = 0.0;
  const contact::ContactLaw law = simulated_law(material, smooth);
  std::vector<std::pair<std::uint16_t, contact::ContactLaw>> kept;
  for (std::uint16_t m : {kWallDefault, kWallDie, kWallPiston, kWallBottom}) {
    kept.emplace_back(m, w.wall_law(m, 0));
    w.change_wall_law(m, 0, law);
  }
  return kept;
}

/// growth: the lid's largest speed over the rate a jammed bed's height grows at.
constexpr double kLidSpeedUp = 4.0;
/// growth: relaxation at full size, quenched, before gravity comes on (critical times).
constexpr double kGrowthRelaxTimes = 50.0;

/// growth: the settle of a bed that starts where it ends (BedSpec's creep rule). The window,
/// 100 critical times, spans several stress-wave transits of a die bed of a few tens of
/// diameters (a transit takes about its height in diameters times t_c), so the bed's elastic
/// sag under the weight that came on has rung out; I_h < 1e-5, two orders below the
/// quasi-static bound 1e-3 of GDR MiDi (2004): the creep allowed strains the bed by less than
/// 1e-5 over the time a quasi-static test takes to cross its height (I = 1e-3), far below any
/// metric's resolution. The budget, 20,000 critical times, is a number of windows, not a
/// real-time limit.
constexpr double kCreepWindowTimes = 100.0;
constexpr double kCreepInertialNumber = 1e-5;
constexpr double kSettleBudgetTimes = 2e4;

BedSpec growth_settle(BedSpec spec, double critical_time) {
  spec.creep_window = kCreepWindowTimes * critical_time;
  spec.creep_inertial_number = kCreepInertialNumber;
  spec.settle_budget = kSettleBudgetTimes * critical_time;
  return spec;
}

/// The growth phase's record in the cost block: what it did and the bed it left.
std::string growth_text(const GrownBed& g) {
  char text[300];
  std::snprintf(text, sizeof text,
                "radii x%.3f -> 1 in %.3g s (critical time %.3g s), %g critical times quenched, "
                "lid at %.4g m: solid fraction %.3f, coordination %.2f, largest overlap %.2g of "
                "a radius",
                g.start_factor, g.growth_time, g.critical_time, kGrowthRelaxTimes, g.height,
                g.solid_fraction, g.coordination, g.largest_overlap);
  return text;
}

}  // namespace

GrownBed grow_bed(sim::World& w, const MaterialModel& material, const sim::HealthLimits& limits) {
  auto& p = w.particles;
  std::vector<double> full(p.size());
  bool shrunk_bed = p.clumps.size() == 0 && p.size() > 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    full[i] = full_radius(p.mass[i], material.simulated_density());
    shrunk_bed = shrunk_bed && full[i] > p.radius[i];
  }
  if (!shrunk_bed)  // only the die tests accept growth (core/model/catalog.cpp)
    throw std::logic_error("growth of a bed not inserted at reduced radii");
  const PreparationSpec& s = material.preparation;
  // Without cohesion while the radii grow, as the seed's free motion (§2.7.1 step 1): a contact
  // that stuck as it formed would lock in a network the growth then has to push apart (with
  // cohesion in contact an LH220 bed jammed at solid fraction 0.22 and pressed its lid at 80
  // times its weight stress). The walls are smooth meanwhile, so that no stress is held by wall
  // friction or adhesion.
  contact::ContactLawSpec plain = material.particle_law;
  plain.cohesion = {"none", {}};
  w.set_pair_law(0, 0, simulated_law(material, plain));
  const std::vector<std::pair<std::uint16_t, contact::ContactLaw>> wall_laws =
      smooth_walls(w, material);
  GrownBed out;
  out.critical_time = particle_contact_time(w, full);
  const double t_c = out.critical_time;
  const std::vector<double> start = p.radius;
  out.start_factor = start[0] / full[0];
  // r(t) = r_0 exp(g t / t_c): the radius grows by the relative rate g per critical time, so a
  // contact closes at about 2 g r per critical time and is pressed by some g r before its own
  // response (~t_c) pushes the pair apart; the motion is quenched with the time constant t_c.
  out.growth_time = std::log(1.0 / out.start_factor) / s.growth_rate * t_c;
  // The lid: the die up to the height of the bed at the target solid fraction.
  double solid = 0.0;
  for (double r : full) solid += 4.0 / 3.0 * M_PI * r * r * r;
  const double radius = die_radius(w);
  out.height = std::max(solid / (s.solid_fraction * M_PI * radius * radius), metrics_top(w));
  // The lid yields to a bed that jams below the target: pushed by more than the bed's weight
  // stress at the target, rho_p phi g H, it rises at the radii's relative rate, H g / t_c (a
  // jammed bed's height grows so), times the ratio of the stress to that cap (at most
  // kLidSpeedUp), so that the bed grows to full size at about the stress gravity will put on it.
  const Vec3 g = w.gravity;
  const double cap = material.simulated_density() * s.solid_fraction * norm(g) * out.height;
  const double rise = out.height * s.growth_rate / t_c;
  const double area = M_PI * radius * radius;
  w.gravity = {};
  const std::size_t lid = w.walls.size();
  w.walls.push_back(
      walls::make_wall("lid", walls::Plane{{0, 0, out.height}, {0, 0, -1}}, kWallDie));
  // The motion is damped as by a drag of time constant tau: while the radii grow, pushing a
  // particle aside at the growth speed v_g = g r / t_c then costs m v_g / tau = a tenth of its
  // weight, so the drag does not press the growing contacts harder than gravity will; at full
  // size the motion is quenched with tau = t_c.
  const double drag_time =
      std::max(t_c, 10.0 * s.growth_rate * mean_diameter(p) / (2.0 * out.start_factor) / t_c /
                        std::max(norm(g), 1e-12));
  const double t0 = w.time;
  double factor = out.start_factor;  // of the radii at the last neighbour-list build
  std::size_t builds = w.list.builds();
  auto grow_and_quench = [&](sim::World& world) {
    const double f =
        std::min(1.0, out.start_factor * std::exp(s.growth_rate * (world.time - t0) / t_c));
    for (std::size_t i = 0; i < p.size(); ++i) p.radius[i] = start[i] / out.start_factor * f;
    const double pushed = world.walls[lid].force.z / (cap * area);
    world.walls[lid].velocity.z = pushed > 1.0 ? rise * std::min(pushed, kLidSpeedUp) : 0.0;
    const double quench =
        std::exp(-world.dt / (world.time - t0 < out.growth_time ? drag_time : t_c));
    for (auto& v : p.v) v *= quench;
    for (auto& o : p.omega) o *= quench;
    // The list holds the pairs within the skin at its build: rebuilt before growth and drift
    // together could close a gap the list does not know of.
    if (world.list.builds() != builds) factor = f, builds = world.list.builds();
    double moved2 = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i)
      moved2 = std::max(moved2, world.list.displacement2(static_cast<int>(i), p.x[i]));
    const double grown = (f - factor) / f * *std::max_element(full.begin(), full.end());
    if (2.0 * (std::sqrt(moved2) + grown) > 0.9 * world.effective_skin()) {
      world.rebuild_list();
      factor = f;
      builds = world.list.builds();
    }
    return true;
  };
  const double relax = out.growth_time + kGrowthRelaxTimes * t_c;
  while (w.time - t0 < relax)
    run_checked(w, std::max<long>(1, std::lround((relax - (w.time - t0)) / w.dt)), limits,
                grow_and_quench);
  out.height = std::get<walls::Plane>(w.walls[lid].shape).point.z;
  out.largest_overlap = largest_overlap(w);
  const double d_max = 2.0 * *std::max_element(full.begin(), full.end());
  const metrics::SamplingCylinder region{radius - d_max, d_max, out.height - d_max};
  if (region.radius > 0.0 && region.z_hi > region.z_lo) {
    out.solid_fraction = metrics::solid_fraction(w, region);
    out.coordination = metrics::coordination_number(w, region);
  }
  w.walls.pop_back();
  for (const auto& [m, law] : wall_laws) w.change_wall_law(m, 0, law);
  // Cohesion in contact from here on, as for pouring (seed 000 §2.7.1 methods 2-4): it acts on
  // the contacts the grown bed has, before gravity comes back.
  cohesion_in_contact(w, material);
  w.gravity = g;
  return out;
}

namespace {

/// The law a prepared bed settles with, when it is not the material's full law: cohesion only
/// in contact, except after clusters (seed 000 §2.7.1).
std::optional<contact::ContactLawSpec> settling_law(const MaterialModel& material) {
  if (material.preparation.method == PreparationMethod::kClusters) return std::nullopt;
  return contact_only(material.particle_law);
}

}  // namespace

PreparedBed prepare_bed(sim::World& w, const MaterialModel& material,
                        const sim::HealthLimits& limits, double lid, std::uint64_t seed) {
  const PhaseClock clock(w);
  PreparedBed out;
  switch (material.preparation.method) {
    case PreparationMethod::kClusters:
    case PreparationMethod::kRandomMotion:
      agitate(w, material, limits, lid, seed);
      break;
    case PreparationMethod::kTerminalVelocity:
      cohesion_in_contact(w, material);
      fall_at_terminal_velocity(w, material, limits, lid);
      break;
    case PreparationMethod::kPour:
      cohesion_in_contact(w, material);
      break;
    case PreparationMethod::kGrowth:
      out.grown = grow_bed(w, material, limits);
      break;
  }
  const std::string name = "prepare " + preparation_method_name(material.preparation.method);
  const bool grown = material.preparation.method == PreparationMethod::kGrowth;
  out.prepared = clock.stop(w, name, grown ? growth_text(out.grown) : "its fixed time", true);
  return out;
}

void set_settling_law(sim::World& w, const MaterialModel& material) {
  if (const auto spec = settling_law(material))
    w.set_pair_law(0, 0, simulated_law(material, *spec));
}

void settle_prepared(sim::World& w, const MaterialModel& material, const BedSpec& spec,
                     const sim::HealthLimits& limits, const contact::ContactLaw& full_law,
                     PreparedBed& bed, const SettleCheckpoints& checkpoints) {
  const bool grown = material.preparation.method == PreparationMethod::kGrowth;
  bed.settled = settle(w, grown ? growth_settle(spec, bed.grown.critical_time) : spec, limits,
                       material.factors().time, checkpoints);
  // The settled bed keeps its contacts' history under the full law.
  if (settling_law(material)) w.change_pair_law(0, 0, full_law);
}

PreparedBed prepare_and_settle(sim::World& w, const MaterialModel& material, const BedSpec& spec,
                               const sim::HealthLimits& limits, double lid, std::uint64_t seed) {
  const auto full_law = w.pair_law(0, 0);
  PreparedBed bed = prepare_bed(w, material, limits, lid, seed);
  settle_prepared(w, material, spec, limits, full_law, bed);
  return bed;
}

}  // namespace demcal::lab

namespace demcal::lab {

double die_radius(const sim::World& world) {
  return std::get<walls::Cylinder>(world.walls.at(1).shape).radius;
}

contact::ContactLawSpec stiffen_normal(const contact::ContactLawSpec& spec, double factor) {
  contact::ContactLawSpec out = spec;
  for (const auto& p : contact::model_params("normal", spec.normal.model))
    if (p.unit == "N/m" || p.unit == "Pa")
      if (auto it = out.normal.params.find(p.name); it != out.normal.params.end())
        it->second *= factor;
  return out;
}

contact::ContactLaw simulated_law(const MaterialModel& material,
                                  const contact::ContactLawSpec& spec) {
  return contact::scale(contact::ContactLaw::from_spec(spec, "wall_law"), material.factors());
}

}  // namespace demcal::lab

namespace demcal::lab {
void write_snapshot(const sim::World& world, const RunOptions& options, const std::string& name,
                    LabOutput& out, double extent) {
  if (options.snapshot_dir.empty()) return;
  const std::string base = options.snapshot_dir + "/" + name;
  io::write_particles_vtk(base + "_particles.vtk", world);
  io::write_walls_vtk(base + "_walls.vtk", world, extent > 0.0 ? extent : 2.0 * die_radius(world));
  out.snapshots.push_back(base + "_particles.vtk");
  out.snapshots.push_back(base + "_walls.vtk");
}
}  // namespace demcal::lab
