// `demcal design --factors K --runs N [--center C] [--generators "..."] [--seed S]
// [--format table|csv|json]`: a two-level design and everything about its aliasing
// (core/doe). Without --generators the design is the minimum-aberration 2^(K-p).
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "client/commands.hpp"
#include "core/common/error.hpp"
#include "core/doe/alias_structure.hpp"
#include "core/doe/design.hpp"
#include "core/doe/minimum_aberration.hpp"

namespace demcal::cli {
namespace {

struct DesignOptions {
  int factors = 0;
  int runs = 0;
  int center = 0;
  std::string generators;
  std::optional<std::uint64_t> seed;
  std::string format = "table";
};

std::vector<std::string> chain_list(const std::vector<std::vector<doe::SignedWord>>& chains) {
  std::vector<std::string> out;
  for (const auto& c : chains) out.push_back(doe::chain_name(c));
  return out;
}

std::string joined(const std::vector<std::string>& items, const std::string& sep) {
  std::string s;
  for (std::size_t i = 0; i < items.size(); ++i) s += (i ? sep : "") + items[i];
  return s;
}

void run_design(const DesignOptions& opt) {
  doe::Design d;
  if (opt.generators.empty()) {
    d = doe::minimum_aberration_design(opt.factors, opt.runs);
  } else {
    d = doe::fractional_factorial(opt.factors, opt.generators);
    if (d.runs() != opt.runs) {
      throw InputError("--runs", "the generators give " + std::to_string(d.runs()) + " runs, not " +
                                     std::to_string(opt.runs));
    }
  }
  const doe::AliasStructure a = doe::analyse_aliasing(d.coded);
  doe::add_centre_points(d, opt.center);
  if (opt.seed) doe::randomise_run_order(d, *opt.seed);

  std::vector<std::string> defining, clear, wlp;
  for (const auto& w : a.defining_relation) defining.push_back(doe::word_name(w));
  for (const auto w : a.clear_two_factor) clear.push_back(doe::word_name(w));
  for (const int n : a.word_length_pattern) wlp.push_back(std::to_string(n));
  const std::vector<int> order = d.rows_in_run_order();

  if (opt.format == "json") {
    nlohmann::json j;
    j["description"] = d.description;
    j["factors"] = d.factor_names;
    j["generators"] = doe::generators_text(d);
    j["defining_relation"] = defining;
    j["word_length_pattern"] = a.word_length_pattern;
    j["resolution"] = a.resolution ? nlohmann::json(*a.resolution) : nlohmann::json(nullptr);
    j["two_factor_alias_chains"] = chain_list(a.two_factor_chains);
    j["main_effect_alias_chains"] = chain_list(a.main_effect_chains);
    j["clear_two_factor_interactions"] = clear;
    j["two_factor_interactions"] = a.two_factor_count();
    j["center_points"] = opt.center;
    j["seed"] = opt.seed ? nlohmann::json(*opt.seed) : nlohmann::json(nullptr);
    for (const int r : order) {
      std::vector<double> row;
      for (int c = 0; c < d.factors(); ++c) row.push_back(d.coded(r, c));
      j["runs"].push_back({{"run", d.run_order[std::size_t(r)]},
                           {"std_order", r + 1},
                           {"point_type", doe::to_string(d.point_type[std::size_t(r)])},
                           {"coded", row}});
    }
    std::cout << j.dump(2) << "\n";
    return;
  }
  if (opt.format == "csv") {
    std::cout << "run,std_order,point_type";
    for (const auto& n : d.factor_names) std::cout << "," << n;
    std::cout << "\n";
    for (const int r : order) {
      std::cout << d.run_order[std::size_t(r)] << "," << r + 1 << ","
                << doe::to_string(d.point_type[std::size_t(r)]);
      for (int c = 0; c < d.factors(); ++c) std::cout << "," << d.coded(r, c);
      std::cout << "\n";
    }
    return;
  }
  std::cout << d.description << "\n"
            << "runs: " << d.runs() << " (" << opt.center << " centre points)"
            << (opt.seed ? ", run order randomised with seed " + std::to_string(*opt.seed)
                         : std::string(", run order = standard order"))
            << "\n"
            << "resolution: " << doe::resolution_name(a.resolution) << "\n"
            << "word-length pattern A3..A" << opt.factors << ": " << joined(wlp, " ") << "\n"
            << "defining relation: I" << (defining.empty() ? "" : " = ") << joined(defining, " = ")
            << "\n"
            << "clear 2FIs: " << clear.size() << " of " << a.two_factor_count()
            << (clear.empty() ? "" : ": " + joined(clear, " ")) << "\n";
  if (!a.main_effect_chains.empty()) {
    std::cout << "main effects aliased with 2FIs:\n";
    for (const auto& c : chain_list(a.main_effect_chains)) std::cout << "  " << c << "\n";
  }
  std::cout << "2FI alias chains (" << a.two_factor_chains.size()
            << "; an estimate belongs to the whole chain):\n";
  for (const auto& c : chain_list(a.two_factor_chains)) std::cout << "  " << c << "\n";
  std::cout << "\n" << std::setw(5) << "run" << std::setw(5) << "std" << std::setw(11) << "type";
  for (const auto& n : d.factor_names) std::cout << std::setw(4) << n;
  std::cout << "\n";
  for (const int r : order) {
    std::cout << std::setw(5) << d.run_order[std::size_t(r)] << std::setw(5) << r + 1
              << std::setw(11) << doe::to_string(d.point_type[std::size_t(r)]);
    for (int c = 0; c < d.factors(); ++c) std::cout << std::setw(4) << d.coded(r, c);
    std::cout << "\n";
  }
}

}  // namespace

void add_design_command(CLI::App& app) {
  auto opt = std::make_shared<DesignOptions>();
  auto* cmd = app.add_subcommand(
      "design", "A two-level design with its defining relation, resolution and alias chains");
  cmd->add_option("--factors", opt->factors, "number of factors K")->required();
  cmd->add_option("--runs", opt->runs, "number of runs N (a power of two)")->required();
  cmd->add_option("--center", opt->center, "centre points to append")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--generators", opt->generators,
                  "generators, e.g. \"F=ABC G=ABD H=ACDE\" (default: minimum aberration)");
  cmd->add_option("--seed", opt->seed, "randomise the run order with this seed");
  cmd->add_option("--format", opt->format, "table, csv or json")
      ->check(CLI::IsMember({"table", "csv", "json"}));
  cmd->callback([opt] { run_design(*opt); });
}

}  // namespace demcal::cli
