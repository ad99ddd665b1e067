// compaction (seed 004 §2.3-2.4, §3.1): a fully periodic cell compacted by shrinking it affinely
// through target solid fractions, its contact stress read at each after a hold.
#include "core/lab/compaction.hpp"

#include <cmath>

#include "core/common/rng.hpp"
#include "core/io/vtk.hpp"
#include "core/lab/bed.hpp"
#include "core/metrics/bulk.hpp"
#include "core/metrics/stress.hpp"
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

}  // namespace

LabOutput run_compaction(const MaterialModel& material, const Settings& values,
                         const RunOptions& options) {
  const auto s = read_settings<CompactionSettings>(values, "settings");
  const double fs = material.factors().stress;
  sim::World w = make_material_world(material, options);
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
  LabOutput out;
  out.add_phase(fill_clock.stop(w, "fill", "all particles inserted", true), {});

  const double solid = solid_volume(w);
  const double t_c = sim::critical_time_step(w).critical;
  const double rate = s.strain_rate / t_c;  // linear strain per second
  const long hold_steps = std::max<long>(2, std::lround(s.hold * t_c / w.dt));
  const long sample_every = std::max<long>(1, std::lround(0.002 / (rate * w.dt)));
  auto phi = [&] { return solid / cell_volume(w); };
  auto real_kpa = [&](double pa) { return pa / fs / 1e3; };

  Series compression{{"solid_fraction", "pressure_kpa", "deviatoric_kpa", "coordination_number"},
                     {}};
  Series held{{"solid_fraction", "pressure_kpa", "deviatoric_kpa", "coordination_number",
               "s_xx_kpa", "s_yy_kpa", "s_zz_kpa", "s_xy_kpa", "s_xz_kpa", "s_yz_kpa"},
              {}};
  auto stress = [&] { return metrics::contact_stress(w, cell_volume(w)); };
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
      const double to_target = std::cbrt(phi() / target);
      reached = to_target >= 1.0 - rate * w.dt;
      const double f = reached ? to_target : 1.0 - rate * w.dt;
      deform_cell(w, {f, f, f});
      sim::step(w);
      if (++step % sample_every == 0) {
        const auto t = stress();
        compression.rows.push_back({phi(), real_kpa(metrics::mean_stress(t)),
                                    real_kpa(metrics::deviatoric_stress(t)),
                                    metrics::coordination_number(w)});
      }
    }
    // Hold: the stress is the mean over the hold's second half.
    metrics::Tensor3 sum{};
    long reads = 0;
    for (long h = 0; h < hold_steps; ++h) {
      sim::step(w);
      if (h >= hold_steps / 2) {
        const auto t = stress();
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) sum[a][b] += t[a][b];
        ++reads;
      }
    }
    for (auto& row : sum)
      for (double& v : row) v /= static_cast<double>(reads);
    last = sum;
    held.rows.push_back({phi(), real_kpa(metrics::mean_stress(sum)),
                         real_kpa(metrics::deviatoric_stress(sum)), metrics::coordination_number(w),
                         real_kpa(sum[0][0]), real_kpa(sum[1][1]), real_kpa(sum[2][2]),
                         real_kpa(sum[0][1]), real_kpa(sum[0][2]), real_kpa(sum[1][2])});
    out.add_phase(clock.stop(w, name, "solid fraction reached, then held", true), {});
    if (options.progress) options.progress(static_cast<double>(k) / points);
  }

  // Jamming: where the contact pressure of the compression first exceeds 1e-2 of the final held
  // pressure (between the two samples, linearly). Below it the cell is a granular gas whose
  // contacts are collisions; past it the pressure of a Hertz packing grows as (phi - phi_J)^1.5,
  // so the threshold lies (1e-2)^(2/3) ~ 0.05 of the way from phi_J to phi_max.
  const double p_final = metrics::mean_stress(last);
  const double threshold = 1e-2 * real_kpa(p_final);
  double phi_jam = s.phi_max;
  bool jammed = false;
  for (std::size_t r = 0; r < compression.rows.size() && !jammed; ++r) {
    const auto& row = compression.rows[r];
    if (!(row[1] > threshold)) continue;
    jammed = true;
    phi_jam = row[0];
    if (r > 0) {
      const auto& before = compression.rows[r - 1];
      phi_jam = before[0] + (row[0] - before[0]) * (threshold - before[1]) / (row[1] - before[1]);
    }
  }
  PhaseCost jam{"jamming", "contact pressure above 1e-2 of the final before phi_max",
                0,         0.0,
                0.0,       jammed && p_final > 0.0};
  out.add_phase(jam, {"jamming_fraction"});
  // Probe: axisymmetric shear at constant volume from the state held at phi_max (the cell
  // shortened along z, widened equally along x and y), its stress ratio q / p read every 0.002
  // of axial strain up to probe_strain. The yield is the peak ratio; the steady ratio the mean
  // over the last fifth of the probe (the critical state when probe_strain is large enough).
  Series probe{{"axial_strain", "pressure_kpa", "deviatoric_kpa", "stress_ratio"}, {}};
  double peak_ratio = 0.0, steady_sum = 0.0;
  long steady_reads = 0;
  if (s.probe_strain > 0.0) {
    const PhaseClock clock(w);
    const double h0 = w.domain.length().z;
    double strain = 0.0;
    long step = 0;
    while (strain < s.probe_strain) {
      const double sz = 1.0 - rate * w.dt, sxy = 1.0 / std::sqrt(sz);
      deform_cell(w, {sxy, sxy, sz});
      sim::step(w);
      strain = 1.0 - w.domain.length().z / h0;
      if (++step % sample_every != 0) continue;
      const auto t = stress();
      const double p = metrics::mean_stress(t), q = metrics::deviatoric_stress(t);
      const double ratio = p > 0.0 ? q / p : 0.0;
      probe.rows.push_back({strain, real_kpa(p), real_kpa(q), ratio});
      peak_ratio = std::max(peak_ratio, ratio);
      if (strain >= 0.8 * s.probe_strain) {
        steady_sum += ratio;
        ++steady_reads;
      }
    }
    out.add_phase(clock.stop(w, "probe", "axial strain of probe_strain at constant volume", true),
                  {});
  }
  out.metrics["peak_stress_ratio"] = peak_ratio;
  out.metrics["steady_stress_ratio"] = steady_reads ? steady_sum / steady_reads : 0.0;
  out.series["probe"] = std::move(probe);
  out.metrics["jamming_fraction"] = phi_jam;
  out.metrics["final_pressure"] = real_kpa(p_final);
  out.metrics["final_coordination_number"] = metrics::coordination_number(w);
  out.series["compression"] = std::move(compression);
  out.series["held"] = std::move(held);
  if (!options.snapshot_dir.empty()) {  // no walls to draw
    out.snapshots.push_back(options.snapshot_dir + "/compaction_particles.vtk");
    io::write_particles_vtk(out.snapshots.back(), w);
  }
  out.cost.close(w);
  return out;
}

}  // namespace demcal::lab
