// confined_compression (seed 000 §2.7.2, eq. 31-33; seed 001 §3.2.1, eq. 19).
// The protocol (core/lab/confinement.hpp): settle in the die; piston (kWallPiston, a StressServo)
// loads to max_stress (h1); `cycles` times: unload to min_stress (h2, h5, ...), reload to
// max_stress (h3, ...); final unload. Piston and bottom carry the particle-wall law with its
// stiffness times wall_stiffness_factor once the bed has settled (seed 000 §2.7.2: k_l,wall =
// 30 k_l, so that particles do not escape past the piston). Stresses given and reported are
// real; the simulation runs at sigma_sim = sigma_real * ScaleFactors::stress (seed 000 eq. 30 /
// seed 001 §2.3).
#include <algorithm>
#include <cmath>

#include "core/lab/confinement.hpp"
#include "core/lab/lab_run.hpp"
#include "core/metrics/bulk.hpp"

namespace demcal::lab {

LabOutput ConfinedCompressionTest::run(const MaterialModel& material, const Settings& values,
                                       const RunOptions& options) {
  const auto s = read_settings<ConfinedCompressionSettings>(values, "settings");
  PistonBedRequest request = confinement_request(material, s);
  request.depending = {"compressibility", "confined_modulus"};
  const int cycles = static_cast<int>(std::lround(s.cycles));
  LabOutput out;
  Confinement c;
  Stages stages(options, confinement_stages(cycles), out, [&](auto& a) { a.field(c); });
  const std::size_t next = start_piston_test(stages, material, request, options, c.bed, out);
  sim::World& w = c.bed.world;
  if (next == 1) write_snapshot(w, options, "settled", out);
  // The metrics each phase feeds: the first load all of them, a cycle's phases the stiffnesses
  // (the last cycle's also E'), the final unload the final solid fraction.
  const std::size_t last = stages.size() - 2;
  auto depending = [&](std::size_t p) -> std::vector<std::string> {
    if (p == 0) return {"compressibility", "k_load", "k_unload", "confined_modulus"};
    if (p == last) return {"final_solid_fraction"};
    if (static_cast<int>((p + 1) / 2) == cycles) return {"k_load", "k_unload", "confined_modulus"};
    return {"k_load", "k_unload"};
  };
  run_confinement(
      c, [&](std::size_t stage) { stages.reached(stage, w); }, next, material, s, options, out,
      depending, 1.0);
  write_snapshot(w, options, "final", out);

  const Cycles& done = c.done;
  const metrics::SamplingCylinder region = bed_sample(w, c.bed.radius, done.final_z);
  out.metrics["compressibility"] = 100.0 * (c.bed.h0 - done.h1) / c.bed.h0;  // eq. 31, %
  out.metrics["k_load"] = done.k_load / cycles;
  out.metrics["k_unload"] = done.k_unload / cycles;
  out.metrics["final_solid_fraction"] =
      region.radius > 0.0 && region.z_hi > region.z_lo ? metrics::solid_fraction(w, region) : 0.0;
  out.metrics["confined_modulus"] = done.e_conf;
  // Strain as in seed 000 Fig. 8: (h - h1) / h1.
  Series series = std::move(c.stress_strain);
  series.columns.push_back("strain");
  for (auto& row : series.rows) row.push_back((row[1] - done.h1) / done.h1);
  out.series["stress_strain"] = std::move(series);
  out.series["cycles"] = std::move(c.cycles);
  out.series["summary"] =
      Series{{"h0_m", "h1_m", "h_final_m"}, {{c.bed.h0, done.h1, done.final_z}}};
  out.cost.close(w);
  return out;
}

}  // namespace demcal::lab
