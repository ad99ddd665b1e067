// compaction (seed 004 §2.3-2.4, §3.1): a fully periodic cell of particles (spheres or rigid
// clumps: rods, helices, clusters) compacted by shrinking the cell affinely, the particles
// remapped with it, through a list of target solid fractions; at each the cell is held and its
// contact stress tensor (Love-Weber, metrics/stress.hpp) read. No walls: the cheapest
// representative volume of a bulk.
#include <cmath>
#include <numbers>

#include "core/common/rng.hpp"
#include "core/io/vtk.hpp"
#include "core/lab/bed.hpp"
#include "core/lab/lab_run.hpp"
#include "core/lab/stages.hpp"
#include "core/metrics/bulk.hpp"
#include "core/metrics/stress.hpp"
#include "core/metrics/yield_surface.hpp"
#include "core/model/compaction_settings.hpp"
#include "core/sim/step.hpp"
#include "core/sim/time_step.hpp"

namespace demcal::lab {
namespace {

/// Deforms the periodic cell about its centre by the factor s[k] along axis k (< 1 shrinks) and
/// remaps the particles with it (LIGGGHTS' fix deform with remap x): lone spheres affinely, rigid
/// clumps by their centres of mass, their members carried along rigidly. Velocities are kept:
/// they are the particles' motion relative to the cell's affine flow.
void deform_cell(sim::World& w, const Vec3& s) {
  Domain& d = w.domain;
  const Vec3 c = 0.5 * (d.lo + d.hi);
  auto map = [&](const Vec3& x) {
    return Vec3{c.x + (x.x - c.x) * s.x, c.y + (x.y - c.y) * s.y, c.z + (x.z - c.z) * s.z};
  };
  d.lo = map(d.lo);
  d.hi = map(d.hi);
  auto& p = w.particles;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.body[i] < 0) p.x[i] = map(p.x[i]);
  auto& bodies = p.clumps;
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const Vec3 shift = map(bodies.x[b]) - bodies.x[b];
    bodies.x[b] += shift;
    for (std::size_t k = 0; k < bodies.count[b]; ++k) p.x[bodies.first[b] + k] += shift;
  }
}

double cell_volume(const sim::World& w) {
  const Vec3 l = w.domain.length();
  return l.x * l.y * l.z;
}

double solid_volume(const sim::World& w) {
  double v = 0.0;
  for (std::size_t i = 0; i < w.particles.size(); ++i) v += w.particles.solid_volume(i);
  return v;
}

/// The logarithmic strain of the cell's axes from lengths l0 (compression positive).
Vec3 cell_strain(const Vec3& l0, const Vec3& l) {
  return {std::log(l0.x / l.x), std::log(l0.y / l.y), std::log(l0.z / l.z)};
}

/// sqrt(2/3 eps : eps) of a diagonal strain (seed 004 eq. 2.11).
double equivalent_strain(const Vec3& e) {
  return std::sqrt(2.0 / 3.0 * dot(e, e));
}

/// The periodic cell of a run and what its phases share.
struct Cell {
  sim::World& w;
  double solid;         ///< solid volume of the particles (m^3)
  double stress_scale;  ///< the scaling law's stress factor
  double rate;          ///< linear strain per second of a deformation
  long sample_every;    ///< steps between the samples of a curve: 0.002 of strain
  long hold_steps;

  double phi() const { return solid / cell_volume(w); }
  metrics::Tensor3 stress() const { return metrics::contact_stress(w, cell_volume(w)); }
  double kpa(double pa) const { return pa / stress_scale / 1e3; }  ///< real kPa
  /// The same cell's settings on another world (a copy of this one's state).
  Cell on(sim::World& other) const {
    return {other, solid, stress_scale, rate, sample_every, hold_steps};
  }
};

/// Steps the cell hold_steps times undeformed; the stress tensor averaged over the second half.
metrics::Tensor3 hold(const Cell& c) {
  metrics::Tensor3 sum{};
  long reads = 0;
  for (long h = 0; h < c.hold_steps; ++h) {
    sim::step(c.w);
    if (h < c.hold_steps / 2) continue;
    const auto t = c.stress();
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) sum[a][b] += t[a][b];
    ++reads;
  }
  for (auto& row : sum)
    for (double& v : row) v /= static_cast<double>(reads);
  return sum;
}

/// Shrinks the cell isotropically through the targets above phi_start up to phi_max, holding at
/// each; fills the `compression` and `held` series and returns the tensor held at phi_max.
metrics::Tensor3 compress(const Cell& c, const CompactionSettings& s, const RunOptions& options,
                          LabOutput& out) {
  Series compression{{"solid_fraction", "pressure_kpa", "deviatoric_kpa", "coordination_number"},
                     {}};
  Series held{{"solid_fraction", "pressure_kpa", "deviatoric_kpa", "coordination_number",
               "s_xx_kpa", "s_yy_kpa", "s_zz_kpa", "s_xy_kpa", "s_xz_kpa", "s_yz_kpa", "s_yx_kpa",
               "s_zx_kpa", "s_zy_kpa"},
              {}};
  sim::World& w = c.w;
  const int points = static_cast<int>(std::lround(s.points));
  metrics::Tensor3 last{};
  for (int k = 1; k <= points; ++k) {
    const double target = s.phi_start + (s.phi_max - s.phi_start) * k / points;
    char name[64];
    std::snprintf(name, sizeof name, "compact to %.3f", target);
    const PhaseClock clock(w);
    long step = 0;
    for (bool reached = false; !reached;) {
      // The last shrink lands on the target: s^3 = phi / target.
      const double to_target = std::cbrt(c.phi() / target);
      reached = to_target >= 1.0 - c.rate * w.dt;
      const double f = reached ? to_target : 1.0 - c.rate * w.dt;
      deform_cell(w, {f, f, f});
      sim::step(w);
      if (++step % c.sample_every == 0) {
        const auto t = c.stress();
        compression.rows.push_back({c.phi(), c.kpa(metrics::mean_stress(t)),
                                    c.kpa(metrics::deviatoric_stress(t)),
                                    metrics::coordination_number(w)});
      }
    }
    last = hold(c);
    held.rows.push_back({c.phi(), c.kpa(metrics::mean_stress(last)),
                         c.kpa(metrics::deviatoric_stress(last)), metrics::coordination_number(w),
                         c.kpa(last[0][0]), c.kpa(last[1][1]), c.kpa(last[2][2]), c.kpa(last[0][1]),
                         c.kpa(last[0][2]), c.kpa(last[1][2]), c.kpa(last[1][0]), c.kpa(last[2][0]),
                         c.kpa(last[2][1])});
    out.add_phase(clock.stop(w, name, "solid fraction reached, then held", true), {});
    if (options.progress) options.progress(static_cast<double>(k) / points);
  }
  out.series["compression"] = std::move(compression);
  out.series["held"] = std::move(held);
  return last;
}

/// Jamming: where the contact pressure of the compression first exceeds 1e-2 of the final held
/// pressure (between the two samples, linearly). Below it the cell is a granular gas whose
/// contacts are collisions; past it the pressure of a Hertz packing grows as (phi - phi_J)^1.5,
/// so the threshold lies (1e-2)^(2/3) ~ 0.05 of the way from phi_J to phi_max. phi_max and
/// flagged when the pressure never crosses it.
void jamming(double p_final_kpa, double phi_max, LabOutput& out) {
  const auto& rows = out.series.at("compression").rows;
  const double threshold = 1e-2 * p_final_kpa;
  double phi_jam = phi_max;
  bool jammed = false;
  for (std::size_t r = 0; r < rows.size() && !jammed; ++r) {
    if (!(rows[r][1] > threshold)) continue;
    jammed = true;
    phi_jam = rows[r][0];
    if (r > 0) {
      const auto& before = rows[r - 1];
      phi_jam =
          before[0] + (rows[r][0] - before[0]) * (threshold - before[1]) / (rows[r][1] - before[1]);
    }
  }
  out.add_phase({"jamming", "contact pressure above 1e-2 of the final before phi_max", 0, 0.0, 0.0,
                 jammed && p_final_kpa > 0.0},
                {"jamming_fraction"});
  out.metrics["jamming_fraction"] = phi_jam;
}

/// Probe: axisymmetric shear at constant volume of a copy of the state held at phi_max (the cell
/// shortened along z, widened equally along x and y), its stress ratio q / p read every 0.002 of
/// axial strain up to probe_strain. The yield is the peak ratio; the steady ratio the mean over
/// the last fifth of the probe (the critical state when probe_strain is large enough).
void shear_probe(const Cell& compacted, double probe_strain, LabOutput& out) {
  Series probe{{"axial_strain", "pressure_kpa", "deviatoric_kpa", "stress_ratio"}, {}};
  double peak_ratio = 0.0, steady_sum = 0.0;
  long steady_reads = 0;
  if (probe_strain > 0.0) {
    sim::World w = compacted.w;
    const Cell c = compacted.on(w);
    const PhaseClock clock(w);
    const double h0 = w.domain.length().z;
    double strain = 0.0;
    long step = 0;
    while (strain < probe_strain) {
      const double sz = 1.0 - c.rate * w.dt, sxy = 1.0 / std::sqrt(sz);
      deform_cell(w, {sxy, sxy, sz});
      sim::step(w);
      strain = 1.0 - w.domain.length().z / h0;
      if (++step % c.sample_every != 0) continue;
      const auto t = c.stress();
      const double p = metrics::mean_stress(t), q = metrics::deviatoric_stress(t);
      const double ratio = p > 0.0 ? q / p : 0.0;
      probe.rows.push_back({strain, c.kpa(p), c.kpa(q), ratio});
      peak_ratio = std::max(peak_ratio, ratio);
      if (strain >= 0.8 * probe_strain) {
        steady_sum += ratio;
        ++steady_reads;
      }
    }
    out.add_phase(clock.stop(w, "probe", "axial strain of probe_strain at constant volume", true),
                  {});
  }
  out.metrics["peak_stress_ratio"] = peak_ratio;
  out.metrics["steady_stress_ratio"] =
      steady_reads ? steady_sum / static_cast<double>(steady_reads) : 0.0;
  out.series["probe"] = std::move(probe);
}

/// The reference state of the yield probes (seed 004 §2.2.3.2, "Unloading Step"): the cell held
/// at phi_max is expanded isotropically at the strain rate until its contact pressure falls to
/// unload_ratio of the held one, then held. Its strain recovered from phi_max is the elastic
/// strain eps_el of eq. 2.11.
struct Reference {
  sim::World w;
  double elastic_strain = 0.0;  ///< sqrt(2/3 eps_el : eps_el)
  bool reached = false;
};

Reference unload(const Cell& compacted, double held_pressure, double unload_ratio, LabOutput& out) {
  Reference ref{compacted.w};
  const Cell c = compacted.on(ref.w);
  const PhaseClock clock(ref.w);
  const Vec3 l0 = ref.w.domain.length();
  const double target = unload_ratio * held_pressure;
  // The pressure is read every 10 steps; the expansion gives up at a linear strain of 0.2.
  const double f = 1.0 + c.rate * ref.w.dt;
  for (long step = 1; !ref.reached && ref.w.domain.length().x < 1.2 * l0.x; ++step) {
    deform_cell(ref.w, {f, f, f});
    sim::step(ref.w);
    if (step % 10 == 0) ref.reached = metrics::mean_stress(c.stress()) <= target;
  }
  const double p = metrics::mean_stress(hold(c));
  ref.reached = ref.reached && p > 0.0;
  ref.elastic_strain = equivalent_strain(cell_strain(l0, ref.w.domain.length()));
  out.add_phase(clock.stop(ref.w, "unload",
                           "pressure down to unload_ratio of the held one, then held, the cell "
                           "still loaded",
                           ref.reached),
                {"isotropic_yield_pressure", "yield_cap_pressure", "yield_slope"});
  return ref;
}

/// The strain paths probed from the reference state: radial in (eps_v, eps_q), at `angle` from
/// isotropic compression towards axisymmetric compression along z (eps_v = eps_x + eps_y + eps_z,
/// eps_q = 2/3 (eps_z - eps_x)).
struct StrainPath {
  const char* name;
  double angle;  ///< degrees
};
constexpr StrainPath kYieldPaths[] = {{"isotropic", 0.0},
                                      {"uniaxial strain", 33.690067525979785},  // atan(2/3)
                                      {"radial 60 deg", 60.0},
                                      {"radial 75 deg", 75.0},
                                      {"constant volume", 90.0}};

/// One yield probe on a copy of the reference state: the cell deformed along `path` at the
/// equivalent strain rate until the equivalent plastic strain of seed 004 eq. 2.11,
/// eps_pl = sqrt(2/3 eps : eps) - sqrt(2/3 eps_el : eps_el), reaches yield_strain (Loidolt et
/// al.'s criterion). The yield point is the stress averaged over the last quarter of
/// yield_strain before it. Along a radial path the equivalent strain grows linearly, so the
/// probe's length is known in advance.
metrics::YieldPoint yield_probe(const Cell& reference, double elastic_strain, double yield_strain,
                                const StrainPath& path, Series& paths, LabOutput& out) {
  sim::World w = reference.w;
  const Cell c = reference.on(w);
  const PhaseClock clock(w);
  const double th = path.angle * std::numbers::pi / 180.0;
  const double ev = std::cos(th), eq = std::sin(th);
  const Vec3 dir{ev / 3.0 - eq / 2.0, ev / 3.0 - eq / 2.0, ev / 3.0 + eq};
  const double per_step = c.rate * w.dt;  // equivalent strain per step
  const Vec3 de = dir * (per_step / equivalent_strain(dir));
  const Vec3 shrink{std::exp(-de.x), std::exp(-de.y), std::exp(-de.z)};
  const auto steps = static_cast<long>(std::ceil((elastic_strain + yield_strain) / per_step));
  const long window = std::max<long>(1, std::lround(0.25 * yield_strain / per_step));
  const Vec3 l0 = w.domain.length();
  metrics::Tensor3 sum{};
  for (long step = 1; step <= steps; ++step) {
    deform_cell(w, shrink);
    sim::step(w);
    const bool sample = step % c.sample_every == 0, averaged = step > steps - window;
    if (!sample && !averaged) continue;
    const auto t = c.stress();
    if (averaged)
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) sum[a][b] += t[a][b] / static_cast<double>(window);
    if (sample)
      paths.rows.push_back({path.angle, equivalent_strain(cell_strain(l0, w.domain.length())),
                            c.kpa(metrics::mean_stress(t)), c.kpa(metrics::deviatoric_stress(t))});
  }
  out.add_phase(clock.stop(w, std::string("yield ") + path.name,
                           "equivalent plastic strain of yield_strain (seed 004 eq. 2.11)", true),
                {});
  return {c.kpa(metrics::mean_stress(sum)), c.kpa(metrics::deviatoric_stress(sum))};
}

/// Unloads to the reference state, probes every path of kYieldPaths and fits the modified
/// Cam-clay ellipse to the yield points (metrics/yield_surface.hpp).
void probe_yield(const Cell& compacted, double held_pressure, const CompactionSettings& s,
                 LabOutput& out) {
  Series points{{"path_angle_deg", "pressure_kpa", "deviatoric_kpa", "stress_ratio"}, {}};
  Series paths{{"path_angle_deg", "equivalent_strain", "pressure_kpa", "deviatoric_kpa"}, {}};
  double isotropic = 0.0;
  metrics::CamClayFit fit;
  if (s.yield_probes > 0.0) {
    Reference ref = unload(compacted, held_pressure, s.unload_ratio, out);
    const Cell reference = compacted.on(ref.w);
    std::vector<metrics::YieldPoint> yield;
    for (const auto& path : kYieldPaths) {
      yield.push_back(yield_probe(reference, ref.elastic_strain, s.yield_strain, path, paths, out));
      const auto& y = yield.back();
      points.rows.push_back({path.angle, y.p, y.q, y.p > 0.0 ? y.q / y.p : 0.0});
    }
    isotropic = yield.front().p;
    fit = metrics::fit_modified_cam_clay(yield);
    out.add_phase({"yield surface", "a modified Cam-clay ellipse through the yield points", 0, 0.0,
                   0.0, fit.valid},
                  {"yield_cap_pressure", "yield_slope"});
  }
  out.metrics["isotropic_yield_pressure"] = isotropic;
  out.metrics["yield_cap_pressure"] = fit.cap;
  out.metrics["yield_slope"] = fit.slope;
  out.series["yield_points"] = std::move(points);
  out.series["yield_paths"] = std::move(paths);
}

/// The periodic cell without gravity at phi_start, filled at random (the fill phase).
void fill_cell(sim::World& w, const MaterialModel& material, const CompactionSettings& s,
               const RunOptions& options, LabOutput& out) {
  w.gravity = {0.0, 0.0, 0.0};
  const auto n = static_cast<std::size_t>(s.particles);
  const double side = std::cbrt(
      expected_solid_volume(material.simulated_sizes(), s.particles, options.seed) / s.phi_start);
  w.domain.lo = {0.0, 0.0, 0.0};
  w.domain.hi = {side, side, side};
  w.domain.periodic = {true, true, true};

  // Fill: inside the cell, every sphere clear of its faces, so none overlaps a periodic image.
  const PhaseClock fill_clock;
  Rng rng(options.seed);
  try {
    fill_region(
        w, material_insert_request(material, particles::BoxRegion{w.domain.lo, w.domain.hi}, n),
        rng, s.time_step_safety, material.factors().time);
  } catch (const InputError& e) {
    throw InputError("settings.phi_start",
                     "the cell at this solid fraction cannot take the particles at random (" +
                         e.message() + "); elongated clumps need a lower phi_start, e.g. 0.06");
  }
  out.add_phase(fill_clock.stop(w, "fill", "all particles inserted", true), {});
}

}  // namespace

LabOutput CompactionTest::run(const MaterialModel& material, const Settings& values,
                              const RunOptions& options) {
  const auto s = read_settings<CompactionSettings>(values, "settings");
  LabOutput out;
  metrics::Tensor3 held{};  // the stress held at phi_max
  // The cell's scales, fixed once filled: its solid volume, strain rate (linear strain per
  // second), steps between samples (0.002 of strain) and of a hold.
  struct {
    double solid = 0.0, rate = 0.0;
    long sample_every = 0, hold_steps = 0;
  } scales;
  // The one stage: the cell compacted to phi_max (the probes start from it).
  Stages stages(options, {"compacted"}, out, [&](auto& a) {
    a.field(held);
    a.field(scales);
  });
  sim::World w = make_material_world(material, options);
  const bool resumed = stages.resume(w) > 0;
  if (!resumed) {
    fill_cell(w, material, s, options, out);
    const double t_c = sim::critical_time_step(w).critical;
    scales.solid = solid_volume(w);
    scales.rate = s.strain_rate / t_c;
    scales.sample_every = std::max<long>(1, std::lround(0.002 / (scales.rate * w.dt)));
    scales.hold_steps = std::max<long>(2, std::lround(s.hold * t_c / w.dt));
  }
  const Cell cell{w,           scales.solid,        material.factors().stress,
                  scales.rate, scales.sample_every, scales.hold_steps};
  if (!resumed) {
    held = compress(cell, s, options, out);
    stages.reached(0, w);
  }
  const double p_held = metrics::mean_stress(held);
  jamming(cell.kpa(p_held), s.phi_max, out);
  out.metrics["final_pressure"] = cell.kpa(p_held);
  out.metrics["final_coordination_number"] = metrics::coordination_number(w);
  if (!options.snapshot_dir.empty()) {  // the state held at phi_max; no walls to draw
    out.snapshots.push_back(options.snapshot_dir + "/compaction_particles.vtk");
    io::write_particles_vtk(out.snapshots.back(), w);
  }
  shear_probe(cell, s.probe_strain, out);
  probe_yield(cell, p_held, s, out);
  out.cost.close(w);
  return out;
}

}  // namespace demcal::lab
