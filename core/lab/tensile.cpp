// tensile (seed 000 §2.7.3, eq. 34-35).
// Phases: the confined compression protocol conditions the bed (core/lab/confinement.hpp: settle,
// load to consolidation_stress, `cycles` unload-reload cycles, final unload to final_stress),
// or the stage cache hands over the bed a run of the same material, settings and seed
// conditioned so (seed 000 §2.7.3: "loading the pre-compressed powder as well as the piston at
// its last position from the confined compression test"); then piston and bottom become
// adhesive (the wall law stiffened by wall_stiffness_factor, A_H times eq. 34, k2 times eq. 35)
// and the piston (StressServo) unloads to unload_stress against the die as it was; then the die
// wall becomes frictionless and non-cohesive and the piston is pulled up at constant speed. The
// tensile stress on the piston is sigma_t = -F_z / A (F_z: the particles' force on it); the
// fracture is the peak of sigma_t over the pull, which must come before the pull's last tenth,
// and the tensile strength is that peak less the weight of the powder still stuck to the piston
// at the end of the pull, over A (seed 000 §2.7.3, Fig. 10-11).
#include <algorithm>
#include <cmath>
#include <optional>

#include "core/lab/confinement.hpp"
#include "core/lab/lab_run.hpp"
#include "core/model/tensile_settings.hpp"

namespace demcal::lab {
namespace {

double real_radius_um(const MaterialModel& m) {
  double r = 0.0;
  if (const auto* mono = std::get_if<particles::Monodisperse>(&m.sizes)) r = mono->radius;
  if (const auto* ln = std::get_if<particles::LogNormal>(&m.sizes)) r = ln->median_radius;
  if (const auto* d = std::get_if<particles::DiscreteClasses>(&m.sizes)) {
    double w = 0.0;
    for (std::size_t k = 0; k < d->radii.size(); ++k) {
      r += d->radii[k] * d->mass_fractions[k];
      w += d->mass_fractions[k];
    }
    r /= w;
  }
  return r * m.size_scale * 1e6;
}

/// The confined compression settings that condition the tensile bed.
ConfinedCompressionSettings conditioning_settings(const TensileSettings& s) {
  ConfinedCompressionSettings c;
  static_cast<PistonServoSettings&>(c) = s;
  c.particles = s.particles;
  c.time_step_safety = s.time_step_safety;
  c.max_stress = s.consolidation_stress;
  c.min_stress = s.min_stress;
  c.final_stress = s.final_stress;
  c.cycles = s.cycles;
  c.wall_stiffness_factor = s.wall_stiffness_factor;
  return c;
}

}  // namespace

double wall_hamaker_ratio_eq34(double r) {
  r = std::clamp(r, 5.0, 50.0);
  return 10.0 + 90.0 * (r - 5.0) / 45.0;
}
double wall_k2_ratio_eq35(double r) {
  r = std::clamp(r, 5.0, 50.0);
  return 10.0 + 5.0 * (r - 5.0) / 45.0;
}

LabOutput TensileTest::run(const MaterialModel& material, const Settings& values,
                           const RunOptions& options) {
  const auto s = read_settings<TensileSettings>(values, "settings");
  const double fs = material.factors().stress;
  const double r_um = real_radius_um(material);
  const double f_ah =
      s.wall_hamaker_factor > 0.0 ? s.wall_hamaker_factor : wall_hamaker_ratio_eq34(r_um);
  const double f_k2 = s.wall_k2_factor > 0.0 ? s.wall_k2_factor : wall_k2_ratio_eq35(r_um);

  // Adhesive piston and bottom: eq. 34 on the Hamaker constant, eq. 35 on k2 (k2/k1 of the
  // Luding law, bounded by its table), stiffness as in the compression test.
  contact::ContactLawSpec adhesive = stiffen_normal(material.wall_law, s.wall_stiffness_factor);
  if (adhesive.cohesion.model == "van_der_waals" && adhesive.cohesion.params.count("hamaker"))
    adhesive.cohesion.params["hamaker"] *= f_ah;
  if (adhesive.normal.model == "luding") {
    const double k2 =
        adhesive.normal.params.count("k2_ratio") ? adhesive.normal.params["k2_ratio"] : 5.0;
    adhesive.normal.params["k2_ratio"] = std::min(1e4, k2 * f_k2);
  }
  // The die for the pull: frictionless and without cohesion, it only stabilises the sample. Its
  // slots keep their models with the forces set to zero, so the bed keeps its wall contacts.
  contact::ContactLawSpec die = material.wall_law;
  if (die.cohesion.model == "van_der_waals") die.cohesion.params["hamaker"] = 0.0;
  if (die.rolling.model != "none") die.rolling.params["mu_r"] = 0.0;
  die.tangential.params["mu_s"] = 0.0;
  if (die.normal.model == "luding") die.normal.params["kc_ratio"] = 0.0;
  const auto adhesive_law = simulated_law(material, adhesive);
  const auto die_law = simulated_law(material, die);

  // The bed the confined compression protocol conditioned (seed 000 §2.7.3), from the stage
  // cache when a run of the same material, settings and seed kept it.
  const ConfinedCompressionSettings cs = conditioning_settings(s);
  PistonBedRequest request = confinement_request(material, cs);
  request.depending = {"tensile_strength"};
  std::vector<std::string> names = confinement_stages(static_cast<int>(std::lround(cs.cycles)));
  names.push_back("unload");
  const std::size_t unload_stage = names.size() - 1;
  LabOutput out;
  Confinement c;
  double conditioned_z = 0.0, unloaded_z = 0.0;
  Stages stages(options, names, out, [&](auto& a) {
    a.field(c);
    a.field(conditioned_z);
    a.field(unloaded_z);
  });
  std::size_t next = 0;
  std::optional<PistonBed> kept;
  if (!stages.resuming()) kept = cached_conditioned_bed(material, cs, options);
  if (kept) {
    c.bed = std::move(*kept);
    next = unload_stage;
    out.notes.push_back(
        "the bed conditioned by the confined compression protocol was taken from the stage cache "
        "(" +
        options.stage_cache->directory().string() +
        "): its phases ran in an earlier run, which reached every target");
  } else {
    next = start_piston_test(stages, material, request, options, c.bed, out);
    run_confinement(
        c, [&](std::size_t stage) { stages.reached(stage, c.bed.world); }, next, material, cs,
        options, out, [](std::size_t) { return std::vector<std::string>{"tensile_strength"}; },
        0.8);
    next = std::max(next, unload_stage);
  }
  sim::World& w = c.bed.world;
  if (next <= unload_stage)
    conditioned_z = std::get<walls::Disk>(w.walls[c.bed.piston].shape).centre.z;
  w.change_wall_law(kWallPiston, 0, adhesive_law);
  w.change_wall_law(kWallBottom, 0, adhesive_law);
  const ServoSettings& servo = c.bed.servo;
  if (next <= unload_stage) {
    ServoSettings ps = servo;
    ps.tolerance = std::max(servo.tolerance * s.unload_stress, 2e-3 * s.consolidation_stress) * fs;
    // The adhesive piston's contacts are far stiffer than the bed the servo's speed limit was
    // chosen for: at that speed one step swings the stress past the target and back, so the
    // controller's steps are bounded by the piston's contact stiffness (Chareyre's rule,
    // core/walls/servo.hpp), half the step that would close the error.
    const ServoPhase r = servo_phase(w, c.bed.piston, c.bed.piston, {0, 0, -1}, c.bed.area,
                                     s.unload_stress * fs, ps, c.bed.limits, {}, 50, 0.5);
    add_servo_phase(out, r, "unload", {"tensile_strength"});
    unloaded_z = r.position;
    if (options.progress) options.progress(0.85);
    write_snapshot(w, options, "consolidated", out);
    stages.reached(unload_stage, w);
  }
  const PistonBed& bed = c.bed;
  // The die keeps the compression's law up to here, as the experiment's glass tube does: the bed
  // was consolidated against it, and a bed conditioned at a low stress, whose lower part the
  // die's friction screened from the consolidation, collapses under the unload's stress once
  // the die no longer holds it.
  w.change_wall_law(kWallDie, 0, die_law);

  // Pull-off at constant speed.
  const auto& p = w.particles;
  double d_mean = 0.0;
  for (double r : p.radius) d_mean += 2.0 * r;
  d_mean /= static_cast<double>(p.size());
  const double v = s.pull_speed > 0.0 ? s.pull_speed : 0.5 * servo.max_speed;
  const double travel = s.pull_distance * d_mean;
  const double h_start = unloaded_z;
  auto& piston = w.walls[bed.piston];
  piston.velocity = {0, 0, v};
  Series series{{"time_s", "displacement_m", "strain", "tensile_stress_kPa"}, {}};
  double peak = -1e300, peak_strain = 0.0;
  long peak_step = 0;
  const long steps = std::lround(travel / (v * w.dt));
  const long record_every = std::max<long>(1, steps / 2000);
  // Smooth the force over a window of ~1 % of the pull so that a single rattling contact does not
  // make the peak.
  const long window = std::max<long>(1, steps / 100);
  double acc = 0.0;
  long n_acc = 0, k = 0;
  std::vector<double> z_late;
  const PhaseClock pull_clock(w);
  run_checked(w, steps, bed.limits, [&](sim::World& world) {
    const double z = std::get<walls::Disk>(world.walls[bed.piston].shape).centre.z;
    acc += -world.walls[bed.piston].force.z / bed.area;
    ++n_acc;
    if (n_acc == window) {
      const double sigma = acc / static_cast<double>(n_acc);
      if (sigma > peak) {
        peak = sigma;
        peak_strain = (z - h_start) / h_start;
        peak_step = k;
      }
      acc = 0.0;
      n_acc = 0;
    }
    if (++k % record_every == 0)
      series.rows.push_back({world.time, z - h_start, (z - h_start) / h_start,
                             -world.walls[bed.piston].force.z / bed.area / fs / 1e3});
    if (k == (steps * 3) / 4) {
      z_late.resize(world.particles.size());
      for (std::size_t i = 0; i < world.particles.size(); ++i) z_late[i] = world.particles.x[i].z;
    }
    return true;
  });
  piston.velocity = {};
  // A stress still rising at the end of the pull has not peaked: the bed stretches, it has not
  // broken, and its peak is somewhere past the pull distance.
  constexpr double kPeakBefore = 0.9;
  out.add_phase(
      pull_clock.stop(w, "pull",
                      "pull distance travelled, the tensile stress's peak before its "
                      "last tenth",
                      static_cast<double>(peak_step) < kPeakBefore * static_cast<double>(steps)),
      {"tensile_strength"});
  // Powder stuck to the piston: the particles that followed it over the last quarter of the pull.
  double stuck_mass = 0.0;
  const double dz_piston = 0.25 * travel;
  for (std::size_t i = 0; i < p.size() && !z_late.empty(); ++i)
    if (p.x[i].z - z_late[i] > 0.5 * dz_piston) stuck_mass += p.mass[i];
  const double stuck_stress = stuck_mass * norm(w.gravity) / bed.area;
  write_snapshot(w, options, "pulled", out);

  out.metrics["tensile_strength"] = (peak - stuck_stress) / fs / 1e3;  // kPa, real
  out.series["tensile"] = std::move(series);
  out.series["fracture"] = Series{
      {"peak_stress_kPa", "peak_strain", "stuck_weight_stress_kPa", "conditioned_height_m",
       "unloaded_height_m", "consolidation_reached", "wall_hamaker_factor", "wall_k2_factor"},
      {{peak / fs / 1e3, peak_strain, stuck_stress / fs / 1e3, conditioned_z, unloaded_z,
        c.reached ? 1.0 : 0.0, f_ah, f_k2}}};
  out.cost.close(w);
  return out;
}

}  // namespace demcal::lab
