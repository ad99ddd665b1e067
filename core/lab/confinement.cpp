#include "core/lab/confinement.hpp"

#include <cmath>
#include <cstdio>

#include "core/common/bytes.hpp"

namespace demcal::lab {

std::vector<std::string> confinement_stages(int cycles) {
  std::vector<std::string> names{kPistonBedStage, "load 1"};
  for (int c = 1; c <= cycles; ++c) {
    names.push_back("unload " + std::to_string(c));
    names.push_back("load " + std::to_string(c + 1));
  }
  names.push_back("final unload");
  return names;
}

PistonBedRequest confinement_request(const MaterialModel& material,
                                     const ConfinedCompressionSettings& s) {
  const auto stiff_wall =
      simulated_law(material, stiffen_normal(material.wall_law, s.wall_stiffness_factor));
  return piston_bed_request(s, s.max_stress * material.factors().stress,
                            [stiff_wall](sim::World& w) {
                              w.set_wall_law(kWallPiston, 0, stiff_wall);
                              w.set_wall_law(kWallBottom, 0, stiff_wall);
                            });
}

std::string conditioned_bed_identity(const MaterialModel& material,
                                     const ConfinedCompressionSettings& s,
                                     const RunOptions& options) {
  std::string id =
      protocol_line("confined_compression") + "bed conditioned by confined_compression\n";
  for (const auto& info : ConfinedCompressionSettings::table()) {
    char line[96];
    std::snprintf(line, sizeof line, "settings.%s=%.17g\n", std::string(info.name).c_str(),
                  s.*(info.field));
    id += line;
  }
  id += "seed=" + std::to_string(options.seed) + "\nthreads=" + std::to_string(options.threads) +
        "\n";
  return id + material_identity(material);
}

namespace {

/// The cache record of a conditioned bed: its world's state and its own fields.
std::string bed_record(const PistonBed& bed) {
  ByteWriter record;
  record.put(bed.world.save_state());
  record.field(bed);
  return record.take();
}

}  // namespace

std::optional<PistonBed> cached_conditioned_bed(const MaterialModel& material,
                                                const ConfinedCompressionSettings& s,
                                                const RunOptions& options) {
  if (!options.stage_cache) return std::nullopt;
  const auto record = options.stage_cache->find(conditioned_bed_identity(material, s, options));
  if (!record) return std::nullopt;
  PistonBed bed;
  // The world as the protocol makes it (its laws, its threads), then the state kept.
  bed.world = make_material_world(material, options);
  const PistonBedRequest request = confinement_request(material, s);
  request.set_laws(bed.world);
  // A record this build cannot read (another build's layout) counts as absent.
  try {
    ByteReader in(*record, "stage cache");
    std::string state;
    in.get(state);
    bed.world.restore_state(state);
    in.field(bed);
    in.expect_end();
    check_piston(bed);
  } catch (const InputError&) {
    return std::nullopt;
  }
  return bed;
}

void run_confinement(Confinement& c, const std::function<void(std::size_t stage)>& reached,
                     std::size_t next, const MaterialModel& material,
                     const ConfinedCompressionSettings& s, const RunOptions& options,
                     LabOutput& out,
                     const std::function<std::vector<std::string>(std::size_t)>& depending,
                     double progress_share) {
  const double fs = material.factors().stress;
  const int cycles = static_cast<int>(std::lround(s.cycles));
  const std::vector<std::string> names = confinement_stages(cycles);
  sim::World& w = c.bed.world;
  const ServoSettings& servo = c.bed.servo;
  Cycles& done = c.done;
  // Phase p (stage p + 1) drives the piston to its target and records the curve.
  auto phase = [&](std::size_t p, double target_real) {
    ServoSettings ps = servo;
    ps.tolerance = std::max(servo.tolerance * target_real, 2e-3 * s.max_stress) * fs;
    const double phase_no = static_cast<double>(p + 1);
    const auto r = servo_phase(
        w, c.bed.piston, c.bed.piston, {0, 0, -1}, c.bed.area, target_real * fs, ps, c.bed.limits,
        [&](const sim::World& world, double stress) {
          c.stress_strain.rows.push_back(
              {world.time, std::get<walls::Disk>(world.walls[c.bed.piston].shape).centre.z,
               stress / fs / 1e3, phase_no});
        });
    if (options.progress) options.progress(progress_share * phase_no / (2.0 * s.cycles + 2.0));
    add_servo_phase(out, r, names[p + 1], depending(p));
    c.reached = c.reached && r.reached;
    return r;
  };

  // Eq. 31-33 with h1 = the first loaded height; per cycle c: loaded (h_l, sigma_l) and
  // unloaded (h_u, sigma_u) states; k_unload from loaded c-1 -> unloaded c (eq. 33),
  // k_load from unloaded c -> loaded c (eq. 32); arithmetic means over the cycles (§2.7.2).
  const std::size_t last = names.size() - 2;  // the final unload
  for (std::size_t p = next - 1; p <= last; ++p) {
    const int cycle = static_cast<int>((p + 1) / 2);  // the cycle of an unload (odd p) or reload
    if (p == 0) {
      const ServoPhase first = phase(p, s.max_stress);
      done.h1 = done.loaded_z = first.position;
      done.loaded_stress = first.stress;
    } else if (p == last) {
      done.final_z = phase(p, s.final_stress).position;
    } else if (p % 2 == 1) {
      const ServoPhase un = phase(p, s.min_stress);
      done.unloaded_stress = un.stress;
      done.unloaded_z = un.position;
    } else {
      const ServoPhase re = phase(p, s.max_stress);
      const double ku =
          (done.loaded_stress - done.unloaded_stress) * done.h1 / (done.unloaded_z - done.loaded_z);
      const double kl =
          (re.stress - done.unloaded_stress) * done.h1 / (done.unloaded_z - re.position);
      done.k_unload += ku / fs / 1e6;
      done.k_load += kl / fs / 1e6;
      c.cycles.rows.push_back(
          {double(cycle), re.position, done.unloaded_z, kl / fs / 1e6, ku / fs / 1e6});
      // seed 001 eq. 19 on the last (most stable) loop: E' = (sigma_max - sigma_min) /
      // (eps_max - eps_min), eps = (h0 - h) / h0.
      if (cycle == cycles)
        done.e_conf = (re.stress - done.unloaded_stress) /
                      ((done.unloaded_z - re.position) / c.bed.h0) / fs / 1e6;
      done.loaded_stress = re.stress;
      done.loaded_z = re.position;
    }
    reached(p + 1);
  }
  // Only a bed whose every phase reached its target is offered to other runs.
  if (options.stage_cache && c.reached)
    options.stage_cache->keep(conditioned_bed_identity(material, s, options), bed_record(c.bed));
}

}  // namespace demcal::lab
