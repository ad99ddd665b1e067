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
#include "core/particles/insertion.hpp"
#include "core/sim/step.hpp"
#include "core/sim/time_step.hpp"
#include "core/walls/servo.hpp"

namespace demcal::lab {
namespace {}  // namespace

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
  // A settled bed of solid fraction ~0.6 as high as it is wide: pi R^2 2R 0.6 = solid volume.
  const double radius =
      spec.die_radius > 0.0 ? spec.die_radius : std::cbrt(solid / (0.6 * 2.0 * M_PI));
  // Clumps are inserted by their bounding spheres: the loose column is taller by their volume.
  particles::InsertRequest req = material_insert_request(material, {}, spec.particles);
  const double bound = req.shape ? req.shape->bounding_radius : 1.0;
  const double r_max = particles::max_radius(sizes) * bound;
  const double height =
      spec.insert_height > 0.0
          ? spec.insert_height
          : std::max(bound * bound * bound * solid / (0.25 * M_PI * radius * radius), 4.0 * r_max);

  w.walls.push_back(walls::make_wall("bottom", walls::Plane{{0, 0, 0}, {0, 0, 1}}, kWallBottom));
  w.walls.push_back(
      walls::make_wall("die", walls::Cylinder{{0, 0, 0}, {0, 0, 1}, radius}, kWallDie));
  req.region = particles::CylinderRegion{{0, 0, 0}, radius, 0.0, height};
  fill_region(w, req, rng, spec.time_step_safety, material.factors().time);
  return w;
}

sim::HealthLimits die_limits(const sim::World& world, double die_radius, double height) {
  sim::HealthLimits h;
  // Far more than the potential energy of the whole bed falling through the die: a bed whose
  // kinetic energy exceeds it has been blown up by a too-stiff contact or a runaway wall.
  h.max_kinetic_energy = 1e3 * world.particles.total_mass() * std::max(norm(world.gravity), 1.0) *
                         (height + die_radius);
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
  void record(const sim::World& w) { checks_.emplace_back(w.time, centre_height(w.particles)); }
  /// The centre of mass moved by less than `rate` x the bed's height (twice the centre's height
  /// above `bottom`) per real second over the last kChecks checks.
  bool still(double rate, double bottom, double time_factor) const {
    if (checks_.size() <= kChecks) return false;
    const auto& [t_now, z_now] = checks_.back();
    const auto& [t_then, z_then] = checks_[checks_.size() - 1 - kChecks];
    const double real_time = (t_now - t_then) / time_factor;
    return std::abs(z_now - z_then) < rate * 2.0 * (z_now - bottom) * real_time;
  }

 private:
  static constexpr std::size_t kChecks = 5;
  std::vector<std::pair<double, double>> checks_;  // (time, centre of mass height)
};

}  // namespace

PhaseCost settle(sim::World& w, const BedSpec& spec, const sim::HealthLimits& limits,
                 double time_factor) {
  const PhaseClock clock(w);
  const double max_time = spec.max_settle_time * time_factor;
  const auto& p = w.particles;
  double mass = 0.0, volume = 0.0;
  double bottom = std::numeric_limits<double>::infinity(), top = -bottom;
  for (std::size_t i = 0; i < p.size(); ++i) {
    mass += p.mass[i];
    volume += 4.0 / 3.0 * M_PI * std::pow(p.radius[i], 3);
    bottom = std::min(bottom, p.x[i].z - p.radius[i]);
    top = std::max(top, p.x[i].z + p.radius[i]);
  }
  const double rho = volume > 0.0 ? mass / volume : 0.0;
  const double height = std::max(top - bottom, 0.0);
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
  const double fall = g > 0.0 ? std::sqrt(2.0 * height / g) : 0.0;
  const double t0 = w.time;
  const long chunk = std::max<long>(200, std::lround(0.002 * time_factor / w.dt));
  SinkWatch sinking;
  bool rest = false;
  while (!rest && w.time - t0 < max_time) {
    run_checked(w, chunk, limits);
    sinking.record(w);
    const bool still = sinking.still(spec.rest_sink_rate, bottom, time_factor);
    const double ke = p.kinetic_energy();
    rest = w.time - t0 >= fall &&
           (ke < ke_per_stress * quiet_stress || (still && ke < ke_per_stress * static_stress));
  }
  char target[200];
  std::snprintf(target, sizeof target,
                "kinetic stress < %.3g^2 x %s, or sinking < %.3g x height per s and kinetic "
                "stress < %.3g^2 x %s (simulated), within %.3g s",
                spec.rest_inertial_number, stress_text(quiet_stress).c_str(), spec.rest_sink_rate,
                spec.rest_inertial_number, stress_text(static_stress).c_str(), max_time);
  return clock.stop(w, "settle", target, rest);
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

double mean_diameter(const particles::ParticleStore& p) {
  double sum = 0.0;
  for (double r : p.radius) sum += 2.0 * r;
  return p.size() ? sum / static_cast<double>(p.size()) : 0.0;
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

}  // namespace

void require_pour(const MaterialModel& material, const std::string& test) {
  if (pours_only(test) && material.preparation.method != PreparationMethod::kPour)
    throw InputError("material.preparation.method",
                     "the " + test +
                         " test builds its bed by pouring only: use 'pour' or leave "
                         "preparation out");
}

PreparedBed prepare_and_settle(sim::World& w, const MaterialModel& material, const BedSpec& spec,
                               const sim::HealthLimits& limits, double lid, std::uint64_t seed) {
  const auto full_law = w.pair_law(0, 0);
  const PhaseClock clock(w);
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
  }
  PreparedBed out;
  out.prepared = clock.stop(w, "prepare " + preparation_method_name(material.preparation.method),
                            "its fixed time", true);
  out.settled = settle(w, spec, limits, material.factors().time);
  // The settled bed keeps its contacts' history under the full law.
  if (material.preparation.method != PreparationMethod::kClusters &&
      contact_only(material.particle_law))
    w.change_pair_law(0, 0, full_law);
  return out;
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
