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
#include "core/lab/stages.hpp"
#include "core/metrics/bulk.hpp"
#include "core/model/confined_compression_settings.hpp"
#include "core/sim/time_step.hpp"

namespace demcal::lab {
namespace {

/// What the servo phases have measured so far, in simulated units: the states the cycles'
/// stiffnesses are computed from (seed 000 eq. 31-33) and their running sums.
struct Cycles {
  double h1 = 0.0;                                 ///< the first loaded height (m)
  double loaded_stress = 0.0, loaded_z = 0.0;      ///< the last loaded state
  double unloaded_stress = 0.0, unloaded_z = 0.0;  ///< the last unloaded state
  double k_load = 0.0, k_unload = 0.0;             ///< sums over the cycles (MPa, real)
  double e_conf = 0.0;                             ///< eq. 19 on the last loop (MPa, real)
  double final_z = 0.0;                            ///< piston after the final unload (m)
};

/// The checkpoint stages: the bed, then every servo phase in the order they run (load 1,
/// unload 1, load 2, ..., final unload), so that phase p ends stage p + 1.
std::vector<std::string> stage_names(int cycles) {
  std::vector<std::string> names{kPistonBedStage, "load 1"};
  for (int c = 1; c <= cycles; ++c) {
    names.push_back("unload " + std::to_string(c));
    names.push_back("load " + std::to_string(c + 1));
  }
  names.push_back("final unload");
  return names;
}

}  // namespace

LabOutput ConfinedCompressionTest::run(const MaterialModel& material, const Settings& values,
                                       const RunOptions& options) {
  const auto s = read_settings<ConfinedCompressionSettings>(values, "settings");
  const double fs = material.factors().stress;
  const auto stiff_wall =
      simulated_law(material, stiffen_normal(material.wall_law, s.wall_stiffness_factor));
  PistonBedRequest request = piston_bed_request(s, s.max_stress * fs, [&](sim::World& w) {
    w.set_wall_law(kWallPiston, 0, stiff_wall);
    w.set_wall_law(kWallBottom, 0, stiff_wall);
  });
  request.depending = {"compressibility", "confined_modulus"};
  const int cycles = static_cast<int>(std::lround(s.cycles));
  LabOutput out;
  PistonBed bed;
  Cycles done;
  Series series{{"time_s", "height_m", "stress_kPa", "phase"}, {}};
  Series cycles_series{{"cycle", "h_loaded_m", "h_unloaded_m", "k_load_MPa", "k_unload_MPa"}, {}};
  Stages stages(options, stage_names(cycles), out, [&](auto& a) {
    a.field(bed);
    a.field(done);
    a.field(series);
    a.field(cycles_series);
  });
  const std::size_t next = start_piston_test(stages, material, request, options, bed, out);
  sim::World& w = bed.world;
  const ServoSettings& servo = bed.servo;
  if (next == 1) write_snapshot(w, options, "settled", out);
  // Phase p (stage p + 1) is recorded with the metrics computed from its end state.
  auto phase = [&](std::size_t p, double target_real, const std::vector<std::string>& depending) {
    ServoSettings ps = servo;
    ps.tolerance = std::max(servo.tolerance * target_real, 2e-3 * s.max_stress) * fs;
    const double phase_no = static_cast<double>(p + 1);
    const auto r = servo_phase(
        w, bed.piston, bed.piston, {0, 0, -1}, bed.area, target_real * fs, ps, bed.limits,
        [&](const sim::World& world, double stress) {
          series.rows.push_back({world.time,
                                 std::get<walls::Disk>(world.walls[bed.piston].shape).centre.z,
                                 stress / fs / 1e3, phase_no});
        });
    if (options.progress) options.progress(phase_no / (2.0 * s.cycles + 2.0));
    add_servo_phase(out, r, stages.name(p + 1), depending);
    return r;
  };

  // Eq. 31-33 with h1 = the first loaded height; per cycle c: loaded (h_l, sigma_l) and
  // unloaded (h_u, sigma_u) states; k_unload from loaded c-1 -> unloaded c (eq. 33),
  // k_load from unloaded c -> loaded c (eq. 32); arithmetic means over the cycles (§2.7.2).
  const std::size_t last = stages.size() - 2;  // the final unload
  for (std::size_t p = next - 1; p <= last; ++p) {
    const int c = static_cast<int>((p + 1) / 2);  // the cycle of an unload (odd p) or reload
    std::vector<std::string> depending{"k_load", "k_unload"};
    if (c == cycles) depending.push_back("confined_modulus");
    if (p == 0) {
      const ServoPhase first =
          phase(p, s.max_stress, {"compressibility", "k_load", "k_unload", "confined_modulus"});
      done.h1 = done.loaded_z = first.position;
      done.loaded_stress = first.stress;
    } else if (p == last) {
      done.final_z = phase(p, s.final_stress, {"final_solid_fraction"}).position;
    } else if (p % 2 == 1) {
      const ServoPhase un = phase(p, s.min_stress, depending);
      done.unloaded_stress = un.stress;
      done.unloaded_z = un.position;
    } else {
      const ServoPhase re = phase(p, s.max_stress, depending);
      const double ku =
          (done.loaded_stress - done.unloaded_stress) * done.h1 / (done.unloaded_z - done.loaded_z);
      const double kl =
          (re.stress - done.unloaded_stress) * done.h1 / (done.unloaded_z - re.position);
      done.k_unload += ku / fs / 1e6;
      done.k_load += kl / fs / 1e6;
      cycles_series.rows.push_back(
          {double(c), re.position, done.unloaded_z, kl / fs / 1e6, ku / fs / 1e6});
      // seed 001 eq. 19 on the last (most stable) loop: E' = (sigma_max - sigma_min) /
      // (eps_max - eps_min), eps = (h0 - h) / h0.
      if (c == cycles)
        done.e_conf = (re.stress - done.unloaded_stress) /
                      ((done.unloaded_z - re.position) / bed.h0) / fs / 1e6;
      done.loaded_stress = re.stress;
      done.loaded_z = re.position;
    }
    stages.reached(p + 1, w);
  }
  write_snapshot(w, options, "final", out);

  const double d_max =
      2.0 * *std::max_element(w.particles.radius.begin(), w.particles.radius.end());
  const metrics::SamplingCylinder region{bed.radius - d_max, d_max, done.final_z - d_max};
  out.metrics["compressibility"] = 100.0 * (bed.h0 - done.h1) / bed.h0;  // eq. 31, %
  out.metrics["k_load"] = done.k_load / cycles;
  out.metrics["k_unload"] = done.k_unload / cycles;
  out.metrics["final_solid_fraction"] =
      region.radius > 0.0 && region.z_hi > region.z_lo ? metrics::solid_fraction(w, region) : 0.0;
  out.metrics["confined_modulus"] = done.e_conf;
  // Strain as in seed 000 Fig. 8: (h - h1) / h1.
  series.columns.push_back("strain");
  for (auto& row : series.rows) row.push_back((row[1] - done.h1) / done.h1);
  out.series["stress_strain"] = std::move(series);
  out.series["cycles"] = std::move(cycles_series);
  out.series["summary"] = Series{{"h0_m", "h1_m", "h_final_m"}, {{bed.h0, done.h1, done.final_z}}};
  out.cost.close(w);
  return out;
}

}  // namespace demcal::lab
