// `demcal simulate SCENE.yaml`: runs a whole simulation (phases of steps), prints its metrics and
// throughput as JSON and writes VTK snapshots, the walls' force series, and the final bed as a
// LIGGGHTS data file with a piston STL over its die (the start of the same test in LIGGGHTS).
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include "client/commands.hpp"
#include "client/json_out.hpp"
#include "core/common/error.hpp"
#include "core/io/csv.hpp"
#include "core/io/liggghts_data.hpp"
#include "core/io/scene_yaml.hpp"
#include "core/io/stl.hpp"
#include "core/io/vtk.hpp"
#include "core/metrics/bulk.hpp"
#include "core/sim/step.hpp"
#include "core/sim/time_step.hpp"

namespace demcal::cli {
namespace {

struct SimulateOptions {
  std::string spec;
  std::string out_dir;
  std::string walls_csv;
  std::string bed_data;
  std::string piston_stl;
  int threads = 0;
};

/// Triangles of the piston disk: its polygon circumscribes the die's circle, so it covers the
/// whole opening.
constexpr int kPistonSegments = 64;

/// The die: the scene's first cylinder wall (its axis along z).
const walls::Cylinder& find_die(const sim::World& w) {
  for (const auto& wall : w.walls)
    if (const auto* die = std::get_if<walls::Cylinder>(&wall.shape)) return *die;
  throw InputError("--piston-stl", "the scene has no cylinder wall (die) to cover");
}

/// A disk facing down at the bed top that covers the die.
walls::Mesh piston_over_die(const sim::World& w) {
  const walls::Cylinder& die = find_die(w);
  const Vec3 centre{die.point.x, die.point.y, metrics::bed_top(w)};
  const double radius = die.radius / std::cos(M_PI / kPistonSegments);
  return walls::make_disk(centre, {0.0, 0.0, -1.0}, radius, kPistonSegments);
}

/// The scene's domain as the data file's box; LIGGGHTS needs a finite one.
io::DataBox finite_box(const sim::World& w) {
  for (int k = 0; k < 3; ++k)
    if (!(w.domain.hi[k] - w.domain.lo[k] < 1e29))
      throw InputError("--bed", "the scene needs a finite domain to give the data file a box");
  return {w.domain.lo, w.domain.hi};
}

/// Appends one row per wall: phase, step, time, wall, displacement, force.
void record_walls(io::CsvWriter& csv, const sim::World& w, std::size_t phase, std::int64_t step) {
  for (std::size_t k = 0; k < w.walls.size(); ++k) {
    const auto& wall = w.walls[k];
    csv.row({static_cast<double>(phase), static_cast<double>(step), w.time, static_cast<double>(k),
             wall.displacement.x, wall.displacement.y, wall.displacement.z, wall.force.x,
             wall.force.y, wall.force.z});
  }
}

/// Runs a phase, recording the walls every `record_every` steps when a CSV is open.
void run_phase(sim::World& w, const io::Phase& phase, std::size_t index,
               std::optional<io::CsvWriter>& csv, std::int64_t& step) {
  const std::int64_t chunk = csv && phase.record_every > 0 ? phase.record_every : phase.steps;
  for (std::int64_t done = 0; done < phase.steps;) {
    const std::int64_t n = std::min<std::int64_t>(chunk, phase.steps - done);
    sim::run(w, n);
    done += n;
    step += n;
    if (csv && phase.record_every > 0) record_walls(*csv, w, index, step);
  }
}

void run_simulate(const SimulateOptions& opt) {
  auto scene = io::read_scene(io::YamlNode::load_file(opt.spec));
  auto& w = scene.world;
  if (opt.threads > 0) w.threads = opt.threads;
  // What the outputs need is checked before the run, not after it.
  std::optional<io::DataBox> box;
  if (!opt.bed_data.empty()) box = finite_box(w);
  if (!opt.piston_stl.empty()) find_die(w);
  nlohmann::json report;
  report["particles"] = w.particles.size();
  report["threads"] = w.threads;
  report["time_step"] = w.dt;
  report["critical_time_step"] = sim::critical_time_step(w).critical;
  for (const auto& wall : w.walls) report["walls"].push_back(wall.name);
  std::optional<io::CsvWriter> csv;
  if (!opt.walls_csv.empty())
    csv.emplace(opt.walls_csv, std::vector<std::string>{"phase", "step", "time", "wall", "dx", "dy",
                                                        "dz", "fx", "fy", "fz"});
  std::int64_t step = 0;
  for (std::size_t p = 0; p < scene.phases.size(); ++p) {
    const auto& phase = scene.phases[p];
    const auto t0 = std::chrono::steady_clock::now();
    run_phase(w, phase, p, csv, step);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    report["phases"].push_back(
        {{"name", phase.name},
         {"steps", phase.steps},
         {"wall_seconds", seconds},
         {"particle_steps_per_second",
          static_cast<double>(w.particles.size()) * static_cast<double>(phase.steps) / seconds}});
  }
  report["metrics"] = {{"kinetic_energy", w.particles.kinetic_energy()},
                       {"coordination_number", metrics::coordination_number(w)},
                       {"bed_top", metrics::bed_top(w)},
                       {"neighbour_builds", w.list.builds()},
                       {"simulated_time", w.time}};
  if (!opt.out_dir.empty()) {
    std::filesystem::create_directories(opt.out_dir);
    io::write_particles_vtk(opt.out_dir + "/particles.vtk", w);
    io::write_walls_vtk(opt.out_dir + "/walls.vtk", w, 0.05);
    report["vtk"] = {opt.out_dir + "/particles.vtk", opt.out_dir + "/walls.vtk"};
  }
  if (box) io::write_liggghts_data(opt.bed_data, w.particles, *box, false);
  if (!opt.piston_stl.empty()) io::write_stl_ascii(opt.piston_stl, piston_over_die(w), "piston");
  std::cout << report.dump(2) << "\n";
}

}  // namespace

void add_simulate_command(CLI::App& app) {
  auto opt = std::make_shared<SimulateOptions>();
  auto* cmd =
      app.add_subcommand("simulate", "Run a simulation scene from YAML and print its metrics");
  cmd->add_option("spec", opt->spec, "scene YAML")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", opt->out_dir, "directory for VTK snapshots of the final state");
  cmd->add_option("--threads", opt->threads, "override the scene's thread count");
  cmd->add_option("--walls-csv", opt->walls_csv,
                  "CSV of every wall's displacement and force at each phase's record_every");
  cmd->add_option(
      "--bed", opt->bed_data,
      "write the final particles at rest as a LIGGGHTS data file (atom_style granular)");
  cmd->add_option("--piston-stl", opt->piston_stl,
                  "write an STL disk facing down at the bed top covering the die (first cylinder)");
  cmd->callback([opt] { run_simulate(*opt); });
}

}  // namespace demcal::cli
