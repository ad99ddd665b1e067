// `demcal contact SPEC.yaml`: the single-contact laboratory (see core/lab/single_contact.hpp).
#include <fstream>
#include <iostream>
#include <memory>

#include "client/commands.hpp"
#include "client/json_out.hpp"
#include "core/io/csv.hpp"
#include "core/lab/single_contact.hpp"

namespace demcal::cli {
namespace {

struct ContactOptions {
  std::string spec;
  std::string csv;
  std::string json;
};

void run_contact(const ContactOptions& opt) {
  const auto spec = lab::read_single_contact(io::YamlNode::load_file(opt.spec));
  std::unique_ptr<io::CsvWriter> csv;
  if (!opt.csv.empty())
    csv = std::make_unique<io::CsvWriter>(opt.csv, lab::single_contact_columns());
  const auto sum = lab::run_single_contact(spec, [&](const lab::SingleContactSample& s) {
    if (csv) csv->row(lab::single_contact_row(s));
  });
  nlohmann::json j;
  j["steps"] = sum.steps;
  j["restitution"] = sum.contact_ended ? nlohmann::json(sum.restitution) : nlohmann::json(nullptr);
  j["contact_duration"] =
      sum.contact_ended ? nlohmann::json(sum.contact_duration) : nlohmann::json(nullptr);
  j["max_overlap"] = sum.max_overlap;
  j["max_force"] = sum.max_force;
  for (int b = 0; b < (spec.second ? 2 : 1); ++b) {
    j["final_state"].push_back({{"position", to_json(sum.final_position[b])},
                                {"velocity", to_json(sum.final_velocity[b])},
                                {"angular_velocity", to_json(sum.final_angular_velocity[b])}});
  }
  const std::string text = j.dump(2);
  if (!opt.json.empty()) {
    std::ofstream out(opt.json);
    if (!out) throw InputError(opt.json, "cannot write file");
    out << text << "\n";
  }
  std::cout << text << "\n";
}

}  // namespace

void add_contact_command(CLI::App& app) {
  auto opt = std::make_shared<ContactOptions>();
  auto* cmd = app.add_subcommand("contact", "Run a two-body contact experiment from a YAML file");
  cmd->add_option("spec", opt->spec, "experiment YAML (contact_law, bodies, wall, mode, path, ...)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--csv", opt->csv, "write the time series to this CSV file");
  cmd->add_option("--json", opt->json, "also write the summary JSON to this file");
  cmd->callback([opt] { run_contact(*opt); });
}

}  // namespace demcal::cli
