// `demcal lab run SPEC.yaml --out DIR` runs one virtual lab test without the service;
// `demcal lab list` shows every test with its metrics and settings.
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include "client/commands.hpp"
#include "client/json_out.hpp"
#include "core/io/csv.hpp"
#include "core/lab/lab_spec.hpp"

namespace demcal::cli {
namespace {

struct LabOptions {
  std::string spec;
  std::string out_dir;
  int threads = 0;
};

void run_lab(const LabOptions& opt) {
  auto spec = lab::read_lab_run(io::YamlNode::load_file(opt.spec));
  if (opt.threads > 0) spec.options.threads = opt.threads;
  if (!opt.out_dir.empty()) {
    std::filesystem::create_directories(opt.out_dir);
    spec.options.snapshot_dir = opt.out_dir;
  }
  const auto& test = lab::find_lab_info(spec.test);
  const lab::LabOutput out =
      lab::run_lab_test(spec.test, spec.material, spec.settings, spec.options);
  nlohmann::json j;
  j["test"] = spec.test;
  j["metrics"] = out.metrics;
  for (const auto& m : test.metrics) j["units"][m.name] = m.unit;
  if (!out.notes.empty()) j["notes"] = out.notes;
  if (!opt.out_dir.empty()) {
    for (const auto& [name, series] : out.series) {
      const std::string path = opt.out_dir + "/" + name + ".csv";
      io::CsvWriter csv(path, series.columns);
      for (const auto& row : series.rows) csv.row(row);
      j["series"].push_back(path);
    }
    j["snapshots"] = out.snapshots;
    std::ofstream(opt.out_dir + "/metrics.json") << j.dump(2) << "\n";
  }
  std::cout << j.dump(2) << "\n";
}

void list_labs() {
  for (const auto& t : lab::lab_catalog()) {
    std::cout << t.name << " — " << t.description << " (" << t.source << ")\n  metrics:\n";
    for (const auto& m : t.metrics)
      std::cout << "    " << m.name << " (" << m.unit << "): " << m.description << "\n";
    std::cout << "  settings:\n";
    for (const auto& s : t.settings)
      std::cout << "    " << s.name << " (" << s.unit << ", [" << s.lo << ", " << s.hi
                << "], default " << s.fallback << "): " << s.doc << "\n";
  }
}

}  // namespace

void add_lab_command(CLI::App& app) {
  auto* lab = app.add_subcommand("lab", "Virtual lab tests without the service");
  lab->require_subcommand(1);
  auto opt = std::make_shared<LabOptions>();
  auto* run =
      lab->add_subcommand("run", "Run one lab test: metrics (JSON), series (CSV), snapshots (VTK)");
  run->add_option("spec", opt->spec, "lab-run YAML (test, settings, material, seed, threads)")
      ->required()
      ->check(CLI::ExistingFile);
  run->add_option("--out", opt->out_dir,
                  "directory for metrics.json, series CSV and VTK snapshots");
  run->add_option("--threads", opt->threads, "override the spec's thread count");
  run->callback([opt] { run_lab(*opt); });
  lab->add_subcommand("list", "List the lab tests, their metrics and settings")
      ->callback(list_labs);
}

}  // namespace demcal::cli
