// `demcal lab run SPEC.yaml --out DIR` runs one virtual lab test without the service;
// `demcal lab list` shows every test with its metrics and settings.
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "client/commands.hpp"
#include "client/json_out.hpp"
#include "client/markdown.hpp"
#include "client/study_journal.hpp"
#include "core/common/exact_number.hpp"
#include "core/io/csv.hpp"
#include "core/lab/lab_run_yaml.hpp"
#include "core/lab/protocol.hpp"
#include "core/lab/size_extrapolation.hpp"
#include "core/lab/stage_cache.hpp"
#include "core/lab/study.hpp"

namespace demcal::cli {
namespace {

struct LabOptions {
  std::string spec;
  std::string out_dir;
  std::string stage_cache;
  int threads = 0;
  double tolerance = 0.0;  ///< of an expected metric, relative; 0: the same double
};

/// The spec's expected metrics against the run, as `j["expected"]` and `j["reproduced"]`; the
/// ones not reproduced, in words (empty when every one is).
std::string check_expected(const lab::LabRunSpec& spec, const lab::LabOutput& out, double tolerance,
                           nlohmann::json& j) {
  if (spec.expected.empty()) return {};
  std::string missed;
  bool reproduced = true;
  for (const auto& m : lab::compare_expected(spec, out.metrics, tolerance)) {
    j["expected"][m.metric] = {{"stored", m.stored},
                               {"simulated", m.simulated},
                               {"relative_difference", m.difference},
                               {"reproduced", m.reproduced}};
    reproduced = reproduced && m.reproduced;
    if (m.reproduced) continue;
    missed += "\n  " + m.metric + ": simulated " + exact_number(m.simulated) +
              " against the stored " + exact_number(m.stored);
  }
  j["reproduced"] = reproduced;
  return missed;
}

void run_lab(const LabOptions& opt) {
  auto spec = lab::read_lab_run(io::YamlNode::load_file(opt.spec));
  if (opt.threads > 0) spec.options.threads = opt.threads;
  if (!opt.out_dir.empty()) {
    std::filesystem::create_directories(opt.out_dir);
    spec.options.snapshot_dir = opt.out_dir;
  }
  if (!opt.stage_cache.empty())
    spec.options.stage_cache = std::make_shared<const lab::StageCache>(opt.stage_cache);
  const auto& test = lab::find_lab_info(spec.test);
  const lab::LabOutput out =
      lab::run_lab_test(spec.test, spec.material, spec.settings, spec.options);
  nlohmann::json j;
  j["test"] = spec.test;
  j["metrics"] = out.metrics;
  for (const auto& m : test.metrics) j["units"][m.name] = m.unit;
  if (!out.notes.empty()) j["notes"] = out.notes;
  j["flags"] = out.flags;
  j["cost"] = to_json(out.cost);
  if (!opt.out_dir.empty()) {
    for (const auto& [name, series] : out.series) {
      const std::string path = opt.out_dir + "/" + name + ".csv";
      io::CsvWriter csv(path, series.columns);
      for (const auto& row : series.rows) csv.row(row);
      j["series"].push_back(path);
    }
    j["snapshots"] = out.snapshots;
  }
  const std::string missed = check_expected(spec, out, opt.tolerance, j);
  if (!opt.out_dir.empty()) std::ofstream(opt.out_dir + "/metrics.json") << j.dump(2) << "\n";
  std::cout << j.dump(2) << "\n";
  if (missed.empty()) return;
  std::ostringstream why;
  why << opt.spec << ": the run does not reproduce its expected metrics ";
  if (opt.tolerance > 0.0)
    why << "within a relative " << opt.tolerance;
  else
    why << "to the bit";
  throw std::runtime_error(why.str() + ":" + missed);
}

struct StudyOptions {
  std::string spec, scale, particles, out_dir;
  int threads = 0;
  int seeds = 1;
  std::optional<double> extrapolate;  ///< a value of the study's axis
};

std::vector<double> parse_list(const std::string& text, const std::string& flag) {
  std::vector<double> v;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) try {
      v.push_back(std::stod(item));
    } catch (const std::exception&) {
      throw InputError(flag, "expected comma-separated numbers, got '" + text + "'");
    }
  return v;
}

nlohmann::json optional_json(const std::optional<double>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

/// One metric's extrapolation (docs/lab-tests.md, "Size extrapolation"); without a fit (a
/// replicate's value not finite) the estimate is null and a note says why.
nlohmann::json extrapolation_json(const lab::StudyExtrapolation& e,
                                  const lab::MetricExtrapolation& m) {
  nlohmann::json j{{"value", e.value},
                   {"x", e.x},
                   {"particles", e.particles},
                   {"form", e.form},
                   {"confidence", lab::kExtrapolationConfidence},
                   {"flagged", m.flagged}};
  if (!m.fit) {
    j["estimate"] = nullptr;
    j["note"] = "a replicate's value is not finite: no fit";
    return j;
  }
  const lab::LineExtrapolation& f = *m.fit;
  j["m_inf"] = f.intercept;
  j["slope"] = f.slope;
  j["estimate"] = f.estimate;
  j["ci_low"] = f.ci_low();
  j["ci_high"] = f.ci_high();
  j["ci_half_width"] = f.half_width;
  j["t_quantile"] = f.t_quantile;
  j["points"] = f.points;
  j["distinct_values"] = f.distinct_x;
  j["residual_sd"] = f.residual_sd;
  if (f.lack_of_fit) {
    const lab::LackOfFit& t = *f.lack_of_fit;
    j["lack_of_fit"] = {{"f_ratio", t.f_ratio},
                        {"df_lack", t.df_lack},
                        {"df_pure", t.df_pure},
                        {"p_value", t.p_value},
                        {"rejected", t.rejected}};
  } else {
    j["lack_of_fit"] = nullptr;
    j["lack_of_fit_note"] = f.lack_of_fit_note;
  }
  return j;
}

nlohmann::json study_json(const lab::StudyResult& r, const std::string& test,
                          const std::optional<lab::StudyExtrapolation>& extrapolated) {
  nlohmann::json j;
  j["test"] = test;
  j["axis"] = r.axis == lab::StudyAxis::kScaleFactor ? "scale_factor" : "particles";
  j["seeds"] = r.seeds;
  for (const auto& run : r.runs) {
    nlohmann::json reps = nlohmann::json::array();
    for (const auto& rep : run.replicates)
      reps.push_back({{"seed", rep.seed},
                      {"metrics", rep.metrics},
                      {"flags", rep.flags},
                      {"wall_seconds", rep.wall_seconds}});
    j["runs"].push_back({{"value", run.value},
                         {"x", lab::size_coordinate(r.axis, r.scaling, run.value)},
                         {"particles", run.particles},
                         {"metrics", run.metrics},
                         {"spread", run.spread},
                         {"flagged", run.flagged},
                         {"replicates", reps}});
  }
  j["relative_change"] = r.relative_change;
  j["max_deviation_from_last"] = r.max_deviation_from_last;
  if (r.seeds >= 2) {
    for (const auto& [name, from] : r.converged_from)
      j["converged_from"][name] = optional_json(from);
    j["chosen"] = optional_json(r.chosen);
  }
  if (extrapolated)
    for (const auto& [name, m] : extrapolated->metrics)
      j["extrapolated"][name] = extrapolation_json(*extrapolated, m);
  return j;
}

/// The extrapolated row of summary.csv: the value, the particles it implies, seeds 0 (no run),
/// and per metric the estimate and the half-width of its confidence interval in the mean and sd
/// columns; empty cells for a metric not extrapolated (not catalogued, or no fit).
void append_extrapolated_row(const std::string& path, const std::vector<std::string>& names,
                             const lab::StudyExtrapolation& e) {
  std::ofstream out(path, std::ios::app);
  out << exact_number(e.value) << "," << exact_number(e.particles) << ",0";
  for (const auto& n : names) {
    const auto it = e.metrics.find(n);
    if (it == e.metrics.end() || !it->second.fit) {
      out << ",,";
      continue;
    }
    out << "," << exact_number(it->second.fit->estimate) << ","
        << exact_number(it->second.fit->half_width);
  }
  out << "\n";
  if (!out) throw InputError(path, "cannot write file");
}

/// runs.csv: one row per value and seed (the curves behind a bed-size table); summary.csv: per
/// value the mean and the seed-to-seed spread of every metric, then the extrapolated row if any.
void write_study_csv(const lab::StudyResult& r, const std::string& dir,
                     const std::optional<lab::StudyExtrapolation>& extrapolated) {
  std::vector<std::string> names;
  for (const auto& [name, unused] : r.runs.front().metrics) names.push_back(name);
  std::vector<std::string> columns{"value", "particles", "seed", "wall_seconds"};
  for (const auto& n : names) columns.push_back(n);
  io::CsvWriter runs(dir + "/runs.csv", columns);
  columns = {"value", "particles", "seeds"};
  for (const auto& n : names) {
    columns.push_back(n + "_mean");
    columns.push_back(n + "_sd");
  }
  {
    io::CsvWriter summary(dir + "/summary.csv", columns);
    for (const auto& run : r.runs) {
      for (const auto& rep : run.replicates) {
        std::vector<double> row{run.value, run.particles, static_cast<double>(rep.seed),
                                rep.wall_seconds};
        for (const auto& n : names) row.push_back(rep.metrics.at(n));
        runs.row(row);
      }
      std::vector<double> row{run.value, run.particles, static_cast<double>(run.replicates.size())};
      for (const auto& n : names) {
        row.push_back(run.metrics.at(n));
        row.push_back(run.spread.at(n));
      }
      summary.row(row);
    }
  }
  if (extrapolated) append_extrapolated_row(dir + "/summary.csv", names, *extrapolated);
}

/// `demcal lab study SPEC.yaml --scale 1,2,4 | --particles 200,400,800 [--seeds 3]
/// [--extrapolate VALUE]`: the same test at each value (and seed), how every metric moves, with
/// two or more seeds the size from which the metrics stay within their seed-to-seed spread (seed
/// 000 §2.3, seed 001 App. B; seed 004 §3.1), and each catalogued metric extrapolated to VALUE
/// (core/lab/size_extrapolation.hpp).
void run_lab_study(const StudyOptions& opt) {
  auto spec = lab::read_lab_run(io::YamlNode::load_file(opt.spec));
  if (opt.threads > 0) spec.options.threads = opt.threads;
  if (opt.scale.empty() == opt.particles.empty())
    throw InputError("study", "give exactly one of --scale and --particles");
  const bool by_scale = !opt.scale.empty();
  const auto values =
      by_scale ? parse_list(opt.scale, "--scale") : parse_list(opt.particles, "--particles");
  if (opt.extrapolate) lab::check_extrapolation(values, *opt.extrapolate, "--extrapolate");
  std::optional<StudyJournalFile> kept;
  if (!opt.out_dir.empty()) {
    std::filesystem::create_directories(opt.out_dir);
    std::ifstream text(opt.spec);
    std::stringstream spec_text;
    spec_text << text.rdbuf();
    kept.emplace(std::filesystem::path(opt.out_dir) / "replicates.jsonl",
                 nlohmann::json{{"spec", spec_text.str()},
                                {"axis", by_scale ? "scale_factor" : "particles"},
                                {"threads", opt.threads},
                                {"protocol", lab::protocol_version(spec.test)}});
    if (kept->runs_read() > 0)
      std::cerr << "study: " << kept->runs_read() << " finished run(s) read from " << opt.out_dir
                << "/replicates.jsonl\n";
  }
  const auto r =
      lab::run_study(spec.test, spec.material, spec.settings, spec.options,
                     by_scale ? lab::StudyAxis::kScaleFactor : lab::StudyAxis::kParticles, values,
                     opt.seeds, kept ? kept->journal() : lab::StudyJournal{});
  std::optional<lab::StudyExtrapolation> extrapolated;
  if (opt.extrapolate) {
    std::vector<std::string> catalogued;
    for (const auto& m : lab::find_lab_info(spec.test).metrics) catalogued.push_back(m.name);
    extrapolated = lab::extrapolate_study(r, catalogued, *opt.extrapolate, "--extrapolate");
  }
  const nlohmann::json j = study_json(r, spec.test, extrapolated);
  if (!opt.out_dir.empty()) {
    std::ofstream(opt.out_dir + "/study.json") << j.dump(2) << "\n";
    write_study_csv(r, opt.out_dir, extrapolated);
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

/// The catalogue as Markdown: per test its metrics and its settings table (docs/lab-tests.md).
void list_labs_markdown() {
  for (const auto& t : lab::lab_catalog()) {
    std::cout << "### `" << t.name << "`\n\n"
              << t.description << " (" << t.source << ").\n\n"
              << "| metric | unit | meaning |\n|---|---|---|\n";
    for (const auto& m : t.metrics)
      std::cout << "| `" << m.name << "` | " << m.unit << " | " << m.description << " |\n";
    std::cout << "\n";
    print_param_table(std::cout, t.settings, "setting");
    std::cout << "\n";
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
  run->add_option("--tolerance", opt->tolerance,
                  "relative difference allowed between the spec's `expected` metrics and the run's "
                  "(default 0: the same bits); a miss exits with status 1")
      ->check(CLI::Range(0.0, 1.0));
  run->add_option("--stage-cache", opt->stage_cache,
                  "directory where runs keep the stages other runs start from (e.g. the bed a "
                  "confined compression conditioned, for a tensile test)");
  run->callback([opt] { run_lab(*opt); });
  auto sopt = std::make_shared<StudyOptions>();
  auto* study = lab->add_subcommand(
      "study", "Run one lab test at several scale factors or particle counts; metric changes");
  study->add_option("spec", sopt->spec, "lab-run YAML")->required()->check(CLI::ExistingFile);
  study->add_option("--scale", sopt->scale, "scale factors, e.g. 1,2,4 (needs material.scaling)");
  study->add_option("--particles", sopt->particles, "particle counts, e.g. 200,400,800");
  study
      ->add_option("--seeds", sopt->seeds,
                   "seeds per value (the spec's seed and the next ones); 2 or more: the size "
                   "from which every metric stays within its seed-to-seed spread")
      ->check(CLI::Range(1, lab::kMaxStudySeeds));
  study->add_option("--extrapolate", sopt->extrapolate,
                    "a particle count (--particles) or scale factor (--scale) to extrapolate every "
                    "catalogued metric to: m = m_inf + a x fitted over all runs (x = N^(-1/3), "
                    "or the length factor of lambda), with its 95 % confidence interval and a "
                    "lack-of-fit test; needs 3 or more values");
  study->add_option("--out", sopt->out_dir, "directory for study.json, runs.csv, summary.csv");
  study->add_option("--threads", sopt->threads, "override the spec's thread count");
  study->callback([sopt] { run_lab_study(*sopt); });
  auto markdown = std::make_shared<bool>(false);
  auto* list = lab->add_subcommand("list", "List the lab tests, their metrics and settings");
  list->add_flag("--markdown", *markdown,
                 "as Markdown tables (the reference in docs/lab-tests.md)");
  list->callback([markdown] { *markdown ? list_labs_markdown() : list_labs(); });
  add_lab_compare_command(*lab);
}

}  // namespace demcal::cli
