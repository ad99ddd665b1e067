// confined_compression (seed 000 §2.7.2, eq. 31-33; seed 001 §3.2.1, eq. 19).
// Phases: settle in the die; piston (kWallPiston, a StressServo) loads to max_stress (h1);
// `cycles` times: unload to min_stress (h2, h5, ...), reload to max_stress (h3, ...); final unload.
// Piston and bottom carry the particle-wall law with its stiffness times wall_stiffness_factor
// (seed 000 §2.7.2: k_l,wall = 30 k_l, so that particles do not escape past the piston).
// Stresses given and reported are real; the simulation runs at sigma_sim = sigma_real *
// ScaleFactors::stress (seed 000 eq. 30 / seed 001 §2.3).
#include <algorithm>
#include <cmath>

#include "core/lab/lab_test.hpp"
#include "core/lab/piston.hpp"
#include "core/metrics/bulk.hpp"
#include "core/model/confined_compression_settings.hpp"
#include "core/sim/time_step.hpp"

namespace demcal::lab {

LabOutput ConfinedCompressionTest::run(const MaterialModel& material, const Settings& values,
                                       const RunOptions& options) {
  const auto s = read_settings<ConfinedCompressionSettings>(values, "settings");
  const double fs = material.factors().stress;
  const auto stiff_wall =
      simulated_law(material, stiffen_normal(material.wall_law, s.wall_stiffness_factor));
  PistonBed bed =
      make_piston_bed(material, static_cast<std::size_t>(s.particles), s.time_step_safety,
                      s.max_stress * fs, options, [&](sim::World& w) {
                        w.set_wall_law(kWallPiston, 0, stiff_wall);
                        w.set_wall_law(kWallBottom, 0, stiff_wall);
                      });
  sim::World& w = bed.world;
  LabOutput out;
  add_bed_phases(out, bed, {"compressibility", "confined_modulus"});
  write_snapshot(w, options, "settled", out);
  const double s_max = s.max_stress * fs;
  ServoSettings servo = make_servo(w, bed.h0, s_max, s);
  Series series{{"time_s", "height_m", "stress_kPa", "phase"}, {}};
  int phase_no = 0;
  // Each phase is recorded with the metrics computed from its end state.
  auto phase = [&](const std::string& name, double target_real,
                   const std::vector<std::string>& depending) {
    ServoSettings ps = servo;
    ps.tolerance = std::max(servo.tolerance * target_real, 2e-3 * s.max_stress) * fs;
    ++phase_no;
    const auto r = servo_phase(
        w, bed.piston, bed.piston, {0, 0, -1}, bed.area, target_real * fs, ps, bed.limits,
        [&](const sim::World& world, double stress) {
          series.rows.push_back({world.time,
                                 std::get<walls::Disk>(world.walls[bed.piston].shape).centre.z,
                                 stress / fs / 1e3, static_cast<double>(phase_no)});
        });
    if (options.progress) options.progress(phase_no / (2.0 * s.cycles + 2.0));
    add_servo_phase(out, r, name, depending);
    return r;
  };

  // Eq. 31-33 with h1 = the first loaded height; per cycle c: loaded (h_l, sigma_l) and
  // unloaded (h_u, sigma_u) states; k_unload from loaded c-1 -> unloaded c (eq. 33),
  // k_load from unloaded c -> loaded c (eq. 32); arithmetic means over the cycles (§2.7.2).
  const ServoPhase first =
      phase("load 1", s.max_stress, {"compressibility", "k_load", "k_unload", "confined_modulus"});
  const double h1 = first.position;
  ServoPhase loaded = first;
  double k_load = 0.0, k_unload = 0.0, e_conf = 0.0;
  const int cycles = static_cast<int>(std::lround(s.cycles));
  Series cycles_series{{"cycle", "h_loaded_m", "h_unloaded_m", "k_load_MPa", "k_unload_MPa"}, {}};
  for (int c = 1; c <= cycles; ++c) {
    std::vector<std::string> depending{"k_load", "k_unload"};
    if (c == cycles) depending.push_back("confined_modulus");
    const ServoPhase un = phase("unload " + std::to_string(c), s.min_stress, depending);
    const ServoPhase re = phase("load " + std::to_string(c + 1), s.max_stress, depending);
    const double ku = (loaded.stress - un.stress) * h1 / (un.position - loaded.position);
    const double kl = (re.stress - un.stress) * h1 / (un.position - re.position);
    k_unload += ku / fs / 1e6;
    k_load += kl / fs / 1e6;
    cycles_series.rows.push_back(
        {double(c), re.position, un.position, kl / fs / 1e6, ku / fs / 1e6});
    // seed 001 eq. 19 on the last (most stable) loop: E' = (sigma_max - sigma_min) /
    // (eps_max - eps_min), eps = (h0 - h) / h0.
    if (c == cycles)
      e_conf = (re.stress - un.stress) / ((un.position - re.position) / bed.h0) / fs / 1e6;
    loaded = re;
  }
  const ServoPhase final_unload = phase("final unload", s.final_stress, {"final_solid_fraction"});
  write_snapshot(w, options, "final", out);

  const double d_max =
      2.0 * *std::max_element(w.particles.radius.begin(), w.particles.radius.end());
  const metrics::SamplingCylinder region{bed.radius - d_max, d_max, final_unload.position - d_max};
  out.metrics["compressibility"] = 100.0 * (bed.h0 - h1) / bed.h0;  // eq. 31, %
  out.metrics["k_load"] = k_load / cycles;
  out.metrics["k_unload"] = k_unload / cycles;
  out.metrics["final_solid_fraction"] =
      region.radius > 0.0 && region.z_hi > region.z_lo ? metrics::solid_fraction(w, region) : 0.0;
  out.metrics["confined_modulus"] = e_conf;
  // Strain as in seed 000 Fig. 8: (h - h1) / h1.
  series.columns.push_back("strain");
  for (auto& row : series.rows) row.push_back((row[1] - h1) / h1);
  out.series["stress_strain"] = std::move(series);
  out.series["cycles"] = std::move(cycles_series);
  out.series["summary"] =
      Series{{"h0_m", "h1_m", "h_final_m"}, {{bed.h0, h1, final_unload.position}}};
  out.cost.close(w);
  return out;
}

}  // namespace demcal::lab
