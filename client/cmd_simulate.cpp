// `demcal simulate SCENE.yaml`: runs a whole simulation (phases of steps), prints its metrics and
// throughput as JSON and writes VTK snapshots.
#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>

#include "client/commands.hpp"
#include "client/json_out.hpp"
#include "core/io/scene_yaml.hpp"
#include "core/io/vtk.hpp"
#include "core/metrics/bulk.hpp"
#include "core/sim/step.hpp"
#include "core/sim/time_step.hpp"

namespace demcal::cli {
namespace {

struct SimulateOptions {
  std::string spec;
  std::string out_dir;
  int threads = 0;
};

void run_simulate(const SimulateOptions& opt) {
  auto scene = io::read_scene(io::YamlNode::load_file(opt.spec));
  auto& w = scene.world;
  if (opt.threads > 0) w.threads = opt.threads;
  nlohmann::json report;
  report["particles"] = w.particles.size();
  report["threads"] = w.threads;
  report["time_step"] = w.dt;
  report["critical_time_step"] = sim::critical_time_step(w).critical;
  for (const auto& phase : scene.phases) {
    const auto t0 = std::chrono::steady_clock::now();
    sim::run(w, phase.steps);
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
  cmd->callback([opt] { run_simulate(*opt); });
}

}  // namespace demcal::cli
