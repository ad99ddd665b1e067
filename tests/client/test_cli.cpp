// The `demcal` command line, run as a user runs it: real processes, real files, JSON parsed back.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/common/rng.hpp"
#include "core/io/yaml_node.hpp"
#include "core/lab/lab_run_yaml.hpp"
#include "core/lab/size_extrapolation.hpp"
#include "core/model/preparation.hpp"
#include "tests/common/command.hpp"

namespace {

namespace fs = std::filesystem;

using Result = demcal::test::CommandResult;

/// The CLI with `args`, standard error merged into the output.
Result demcal(const std::string& args) {
  return demcal::test::run_command(std::string(DEMCAL_BINARY_DIR) + "/client/demcal " + args +
                                   " 2>&1");
}

std::string source(const std::string& rel) {
  return std::string(DEMCAL_SOURCE_DIR) + "/" + rel;
}

fs::path scratch_dir(const std::string& name) {
  const fs::path p =
      fs::temp_directory_path() / ("demcal_cli_" + name + "_" + std::to_string(::getpid()));
  fs::create_directories(p);
  return p;
}

/// The text a doc holds between "<!-- begin: MARK -->" and "<!-- end: MARK -->" lines; empty
/// when it has no such section.
std::string generated_section(const std::string& doc_path, const std::string& mark) {
  std::ifstream in(doc_path);
  std::stringstream text;
  text << in.rdbuf();
  const std::string doc = text.str();
  const std::string begin = "<!-- begin: " + mark + " -->\n", end = "<!-- end: " + mark + " -->";
  const auto a = doc.find(begin);
  const auto b = doc.find(end);
  if (a == std::string::npos || b == std::string::npos || b < a) return {};
  return doc.substr(a + begin.size(), b - a - begin.size());
}

TEST(Cli, DocsHoldTheTablesTheCommandsPrint) {
  const std::array<std::pair<const char*, const char*>, 2> generated{
      {{"docs/contact-models.md", "models"}, {"docs/lab-tests.md", "lab list --markdown"}}};
  for (const auto& [doc, args] : generated) {
    const Result r = demcal(args);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    ASSERT_NE(r.out.find("| `"), std::string::npos) << args << " printed no table";
    EXPECT_EQ(generated_section(source(doc), std::string("demcal ") + args), r.out)
        << doc << " differs from `demcal " << args << "`: run scripts/docs-tables";
  }
}

TEST(Cli, DesignReportsTheAliasStructureOfTheSeedScreening) {
  const Result r = demcal("design --factors 12 --runs 32 --center 1 --format json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["resolution"], 4);
  EXPECT_EQ(j["runs"].size(), 33u);
  EXPECT_EQ(j["clear_two_factor_interactions"].size(), 0u) << "no 2FI is clear in the 2^(12-7)";
  EXPECT_EQ(j["two_factor_alias_chains"].size(), 15u);
}

TEST(Cli, BadArgumentsAreRejectedWithAMessage) {
  const Result r = demcal("design --factors 12 --runs 7");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.out.find("runs"), std::string::npos) << r.out;
}

TEST(Cli, AnalyzeFindsTheActiveEffectsOfACsv) {
  const fs::path dir = scratch_dir("analyze");
  const Result d = demcal("design --factors 5 --runs 16 --format json");
  ASSERT_EQ(d.exit_code, 0) << d.out;
  const auto design = nlohmann::json::parse(d.out);
  std::ofstream csv(dir / "runs.csv");
  csv << "A,B,C,D,E,y\n";
  demcal::Rng rng(11);
  for (const auto& run : design["runs"]) {
    std::array<double, 5> x{};
    for (int k = 0; k < 5; ++k) x[k] = run["coded"][k];
    const double y = 10 + 3 * x[0] - 2 * x[1] + 1.5 * x[0] * x[2] + 0.1 * rng.normal();
    csv << x[0] << "," << x[1] << "," << x[2] << "," << x[3] << "," << x[4] << "," << y << "\n";
  }
  csv.close();
  const Result r = demcal("analyze --design " + (dir / "runs.csv").string() +
                          " --response y --model 2fi --format json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  // The form of `demcal effects --format json`: the factor letters and one analysis per response.
  ASSERT_EQ(j["metrics"].size(), 1u) << r.out;
  EXPECT_EQ(j["factor_letters"].size(), 5u) << r.out;
  const auto& y = j["metrics"][0];
  EXPECT_EQ(y["metric"], "y");
  EXPECT_EQ(y["runs_used"], 16);
  std::set<std::string> active;
  for (const auto& e : y["effects"])
    if (e["active_me"]) active.insert(e["chain"]);
  EXPECT_TRUE(active.count("A") && active.count("B")) << r.out;
  bool interaction_found = false;
  for (const auto& name : active) interaction_found |= name.find("AC") != std::string::npos;
  EXPECT_TRUE(interaction_found) << "the chain holding AC must be flagged";
  EXPECT_FALSE(active.count("D") || active.count("E")) << "inactive factors stay unflagged";
  fs::remove_all(dir);
}

// The seed's screening 2^(12-7) as `demcal export --format csv` writes it: natural units (a
// Hamaker constant in J, a radius in m, a factor whose levels are 0 and 1) and NA for the four
// runs of the corner the build refuses (A_H high, r low, Y low). Every factor is read, none as
// coded unless it is, and the main effects come back from the 28 runs.
TEST(Cli, AnalyzeReadsFactorsInSiUnitsAndLeavesOutAFailedCorner) {
  const fs::path dir = scratch_dir("analyze_si");
  const Result d = demcal("design --factors 12 --runs 32 --format json");
  ASSERT_EQ(d.exit_code, 0) << d.out;
  const auto design = nlohmann::json::parse(d.out);
  // Natural ranges: A_H (J), r (m), Y (Pa), mu_r 0..1, the rest as the seed's Table 17.
  const std::vector<std::pair<double, double>> range{
      {1e-18, 1.5e-17}, {5e-6, 5e-5}, {0.1, 0.3}, {0.5, 1.0}, {1e7, 5e7},  {2, 20},
      {0.5, 5},         {0.2, 1.0},   {0.5, 0.8}, {0.2, 1.0}, {0.02, 0.2}, {0.0, 1.0}};
  std::ofstream csv(dir / "runs.csv");
  for (int k = 0; k < 12; ++k) csv << "f" << k << ",";
  csv << "y\n";
  demcal::Rng rng(5);
  int refused = 0;
  for (const auto& run : design["runs"]) {
    std::array<double, 12> x{};
    for (int k = 0; k < 12; ++k) {
      x[std::size_t(k)] = run["coded"][k];
      const auto [lo, hi] = range[std::size_t(k)];
      csv << std::setprecision(17) << lo + (hi - lo) * (x[std::size_t(k)] + 1) / 2 << ",";
    }
    const bool corner = x[0] > 0 && x[1] < 0 && x[4] < 0;
    refused += corner;
    const double y = 10 + 3 * x[0] + 2 * x[1] - x[4] + 0.8 * x[11] + 0.05 * rng.normal();
    csv << (corner ? std::string("NA") : std::to_string(y)) << "\n";
  }
  csv.close();
  ASSERT_EQ(refused, 4);
  const Result r = demcal("analyze --design " + (dir / "runs.csv").string() +
                          " --response y --model main --format json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["factor_letters"].size(), 12u) << r.out;
  EXPECT_EQ(j["factor_letters"][0], "A=f0 [1e-18, 1.5e-17]") << r.out;
  EXPECT_EQ(j["factor_letters"][11], "M=f11 [0, 1]") << r.out;
  const auto& y = j["metrics"][0];
  EXPECT_EQ(y["runs_used"], 28);
  std::map<std::string, double> effect;
  for (const auto& e : y["effects"]) effect[e["chain"]] = e["effect"];
  EXPECT_NEAR(effect.at("A"), 6.0, 0.2) << r.out;
  EXPECT_NEAR(effect.at("B"), 4.0, 0.2) << r.out;
  EXPECT_NEAR(effect.at("E"), -2.0, 0.2) << r.out;
  EXPECT_NEAR(effect.at("M"), 1.6, 0.2) << r.out;
  EXPECT_NEAR(effect.at("C"), 0.0, 0.2) << r.out;
  fs::remove_all(dir);
}

/// The lines of a text file.
std::vector<std::string> file_lines(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

TEST(Cli, LabStudyGoesOnWhereItStopped) {
  const fs::path dir = scratch_dir("study");
  const auto write_spec = [&](const std::string& name, double mu_s) {
    std::ofstream(dir / name)
        << "test: packing\nseed: 1\nthreads: 1\nmaterial:\n"
        << "  particle_law:\n"
        << "    normal: {model: hertz, youngs_modulus: 5.0e6, restitution: 0.3}\n"
        << "    tangential: {model: history, mu_s: " << mu_s << "}\n"
        << "  sizes: {monodisperse: {radius: 5.0e-4}}\n  density: 2500\n";
    return (dir / name).string();
  };
  const std::string spec = write_spec("spec.yaml", 0.3);
  const std::string out = (dir / "out").string();
  const std::string study = "lab study " + spec + " --particles 60,120 --seeds 2 --out " + out;
  const Result first = demcal(study);
  ASSERT_EQ(first.exit_code, 0) << first.out;
  const fs::path journal = dir / "out" / "replicates.jsonl";
  const auto lines = file_lines(journal);
  ASSERT_EQ(lines.size(), 5u);  // the study's name, then one line per value and seed
  const auto before = nlohmann::json::parse(std::ifstream(dir / "out" / "study.json"));
  // Interrupted during the third run's line: two runs kept, the cut line dropped, two run again.
  {
    std::ofstream cut(journal, std::ios::trunc);
    cut << lines[0] << "\n" << lines[1] << "\n" << lines[2] << "\n" << lines[3].substr(0, 20);
  }
  const Result resumed = demcal(study);
  ASSERT_EQ(resumed.exit_code, 0) << resumed.out;
  EXPECT_NE(resumed.out.find("2 finished run(s) read"), std::string::npos) << resumed.out;
  EXPECT_NE(resumed.out.find("replicates.jsonl:4: a line cut short"), std::string::npos);
  EXPECT_EQ(file_lines(journal).size(), 5u);
  const auto after = nlohmann::json::parse(std::ifstream(dir / "out" / "study.json"));
  // The 60-particle runs are the kept ones, wall times included; the 120-particle runs ran
  // again to the same metrics.
  EXPECT_EQ(after["runs"][0]["replicates"], before["runs"][0]["replicates"]);
  EXPECT_EQ(after["runs"][1]["metrics"], before["runs"][1]["metrics"]);
  // Another spec into the same directory is refused, and the runs kept stay as they were.
  const auto kept = file_lines(journal);
  const Result other = demcal("lab study " + write_spec("other.yaml", 0.5) +
                              " --particles 60,120 --seeds 2 --out " + out);
  EXPECT_NE(other.exit_code, 0);
  EXPECT_NE(other.out.find("replicates.jsonl: holds the runs of another study"), std::string::npos)
      << other.out;
  EXPECT_EQ(file_lines(journal), kept);
  // So is the same spec's file written under another version of the test's protocol: its runs
  // are not this build's.
  auto header = nlohmann::json::parse(kept[0]);
  header["study"]["protocol"] = header["study"]["protocol"].get<int>() + 1;
  {
    std::ofstream changed(journal, std::ios::trunc);
    changed << header.dump() << "\n";
    for (std::size_t i = 1; i < kept.size(); ++i) changed << kept[i] << "\n";
  }
  const Result other_protocol = demcal(study);
  EXPECT_NE(other_protocol.exit_code, 0);
  EXPECT_NE(other_protocol.out.find("replicates.jsonl: holds the runs of another study"),
            std::string::npos)
      << other_protocol.out;
  fs::remove_all(dir);
}

TEST(Cli, LabStudyExtrapolatesToAnotherSize) {
  const fs::path dir = scratch_dir("extrapolate");
  std::ofstream(dir / "spec.yaml") << "test: packing\nseed: 1\nthreads: 1\nmaterial:\n"
                                   << "  particle_law:\n"
                                   << "    normal: {model: hertz, youngs_modulus: 5.0e6, "
                                      "restitution: 0.3}\n"
                                   << "    tangential: {model: history, mu_s: 0.3}\n"
                                   << "  sizes: {monodisperse: {radius: 5.0e-4}}\n"
                                   << "  density: 2500\n";
  const std::string spec = (dir / "spec.yaml").string(), out = (dir / "out").string();
  // Two values cannot give a line and its test: refused before anything runs.
  const Result few =
      demcal("lab study " + spec + " --particles 40,80 --seeds 2 --extrapolate 1000 --out " + out);
  EXPECT_NE(few.exit_code, 0);
  EXPECT_NE(few.out.find("--extrapolate: needs at least 3 distinct study values"),
            std::string::npos)
      << few.out;
  EXPECT_FALSE(fs::exists(dir / "out" / "replicates.jsonl"));
  const Result r = demcal("lab study " + spec +
                          " --particles 40,60,80 --seeds 2 --extrapolate 1000 --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(std::ifstream(dir / "out" / "study.json"));
  for (const char* name : {"solid_fraction", "coordination_number"}) {
    const auto& e = j["extrapolated"][name];
    EXPECT_EQ(e["value"], 1000.0);
    EXPECT_NEAR(e["x"].get<double>(), 0.1, 1e-12);
    EXPECT_EQ(e["form"], "m = m_inf + a N^(-1/3)");
    EXPECT_EQ(e["points"], 6);
    EXPECT_LE(e["ci_low"].get<double>(), e["estimate"].get<double>());
    EXPECT_GE(e["ci_high"].get<double>(), e["estimate"].get<double>());
    EXPECT_TRUE(e["lack_of_fit"].is_object() || e["lack_of_fit_note"].is_string()) << e.dump();
    EXPECT_TRUE(e["flagged"].is_boolean());
  }
  // summary.csv: the three values, then the extrapolated row (seeds 0, the estimate in the mean
  // column, the interval's half-width in the sd column).
  const auto lines = file_lines(dir / "out" / "summary.csv");
  ASSERT_EQ(lines.size(), 5u);
  const std::string header = lines[0];
  std::vector<std::string> columns, cells;
  std::stringstream h(header), row(lines[4]);
  for (std::string c; std::getline(h, c, ',');) columns.push_back(c);
  for (std::string c; std::getline(row, c, ',');) cells.push_back(c);
  cells.resize(columns.size());
  const auto cell = [&](const std::string& column) {
    const auto at = std::find(columns.begin(), columns.end(), column) - columns.begin();
    return cells.at(static_cast<std::size_t>(at));
  };
  EXPECT_EQ(cell("value"), "1000");
  EXPECT_EQ(cell("particles"), "1000");
  EXPECT_EQ(cell("seeds"), "0");
  const auto& sf = j["extrapolated"]["solid_fraction"];
  EXPECT_NEAR(std::stod(cell("solid_fraction_mean")), sf["estimate"].get<double>(), 1e-12);
  EXPECT_NEAR(std::stod(cell("solid_fraction_sd")), sf["ci_half_width"].get<double>(), 1e-12);
  fs::remove_all(dir);
}

/// A study.json as `lab study --out` writes it, reduced to what a comparison reads: per value its
/// size coordinate, the mean and spread of metric "angle" and each replicate's value, extrapolated
/// to x0 = 0.5.
nlohmann::json study_of(const std::vector<std::vector<double>>& angles) {
  nlohmann::json j{{"axis", "scale_factor"}, {"runs", nlohmann::json::array()}};
  const std::vector<double> values{1000, 8000, 27000};
  for (std::size_t i = 0; i < values.size(); ++i) {
    nlohmann::json reps = nlohmann::json::array();
    for (double a : angles[i]) reps.push_back({{"metrics", {{"angle", a}}}});
    const auto m = demcal::lab::sample_moments(angles[i]);
    j["runs"].push_back({{"value", values[i]},
                         {"x", std::cbrt(values[i])},
                         {"metrics", {{"angle", m.mean}}},
                         {"spread", {{"angle", m.sd}}},
                         {"replicates", reps}});
  }
  j["extrapolated"]["angle"] = {{"value", 0.125}, {"x", 0.5}};
  return j;
}

TEST(Cli, LabCompareGivesTheDifferencesOfTwoStudies) {
  const fs::path dir = scratch_dir("compare");
  const std::vector<std::vector<double>> a{{40, 42, 44}, {43, 46, 46}, {47, 50, 50}},
      b{{37, 38, 41}, {41, 41, 44}, {44, 45, 49}};
  for (const auto& [name, angles] : {std::pair{"a", a}, std::pair{"b", b}}) {
    fs::create_directories(dir / name);
    std::ofstream(dir / name / "study.json") << study_of(angles).dump();
  }
  const Result r =
      demcal("lab compare " + (dir / "a").string() + " " + (dir / "b").string() + " --format json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out)["metrics"]["angle"];
  ASSERT_EQ(j["values"].size(), 3u);
  std::vector<double> xa, ya, xb, yb;
  for (std::size_t i = 0; i < 3; ++i) {
    const auto d = demcal::lab::mean_difference(a[i], b[i], "angle");
    const auto& row = j["values"][i]["difference"];
    EXPECT_NEAR(row["estimate"].get<double>(), d.estimate, 1e-12);
    EXPECT_NEAR(row["ci_low"].get<double>(), d.low(), 1e-12);
    EXPECT_NEAR(row["df"].get<double>(), d.df, 1e-12);
    for (double v : a[i])
      xa.push_back(std::cbrt(j["values"][i]["value"].get<double>())), ya.push_back(v);
    for (double v : b[i])
      xb.push_back(std::cbrt(j["values"][i]["value"].get<double>())), yb.push_back(v);
  }
  const auto line =
      demcal::lab::line_difference(demcal::lab::extrapolate_line(xa, ya, 0.5, "a"),
                                   demcal::lab::extrapolate_line(xb, yb, 0.5, "b"), "w");
  const auto& e = j["extrapolated"]["difference"];
  EXPECT_NEAR(e["estimate"].get<double>(), line.estimate, 1e-12);
  EXPECT_NEAR(e["ci_high"].get<double>(), line.high(), 1e-12);
  EXPECT_EQ(e["df"].get<double>(), 14.0);
  // A study written before each value carried its size coordinate is refused, saying how to mend
  // it.
  auto old = study_of(a);
  for (auto& run : old["runs"]) run.erase("x");
  std::ofstream(dir / "a" / "study.json") << old.dump();
  const Result refused = demcal("lab compare " + (dir / "a").string() + " " + (dir / "b").string());
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.out.find("size coordinate"), std::string::npos) << refused.out;
  fs::remove_all(dir);
}

TEST(Cli, ContactPrintsTheSummaryAndWritesTheSeries) {
  const fs::path dir = scratch_dir("contact");
  const Result r = demcal("contact " + source("examples/contact_hertz_collision.yaml") + " --csv " +
                          (dir / "series.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  // LIGGGHTS 3.8 measures 0.499965884831271 for this collision
  // (tests/data/liggghts/in.collision_hertz).
  EXPECT_NEAR(j["restitution"].get<double>(), 0.499965884831271, 1e-9);
  std::ifstream series(dir / "series.csv");
  std::string header;
  std::getline(series, header);
  EXPECT_EQ(header.rfind("time,x1_x", 0), 0u);
  int rows = 0;
  for (std::string line; std::getline(series, line);) ++rows;
  EXPECT_EQ(rows, 800);  // 8000 steps, every 10th
  fs::remove_all(dir);
}

TEST(Cli, ContactSpecErrorsNameFileLineAndField) {
  const fs::path dir = scratch_dir("bad");
  std::ofstream(dir / "bad.yaml") << "contact_law:\n  normal: {model: linear, kn: -5}\n"
                                     "  tangential: {model: history, mu_s: 0.5}\n"
                                     "bodies: []\ntime_step: 1.0e-6\n";
  const Result r = demcal("contact " + (dir / "bad.yaml").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("bad.yaml:2"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("contact_law.normal.kn"), std::string::npos) << r.out;
  fs::remove_all(dir);
}

TEST(Cli, SimulateRunsAScenePrintsMetricsAndWritesVtk) {
  const fs::path dir = scratch_dir("simulate");
  std::ofstream(dir / "scene.yaml") << R"(
threads: 2
time_step_safety: 0.2
density: 2500
contact_law:
  normal: {model: hertz, youngs_modulus: 1.0e7, poisson_ratio: 0.3, restitution: 0.5}
  tangential: {model: history, mu_s: 0.5}
walls:
  - {name: floor, plane: {point: [0, 0, 0], normal: [0, 0, 1]}}
  - {name: die, cylinder: {point: [0, 0, 0], axis: [0, 0, 1], radius: 0.01}}
particles:
  random: {region: {cylinder: {centre: [0, 0, 0], radius: 0.0099, z_lo: 0, z_hi: 0.02}}, count: 150,
           sizes: {monodisperse: {radius: 0.001}}}
phases:
  - {name: fall, steps: 2000}
)";
  const Result r =
      demcal("simulate " + (dir / "scene.yaml").string() + " --out " + (dir / "vtk").string());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["particles"], 150);
  EXPECT_LT(j["time_step"].get<double>(), j["critical_time_step"].get<double>());
  EXPECT_GT(j["phases"][0]["particle_steps_per_second"].get<double>(), 0.0);
  std::ifstream vtk(dir / "vtk" / "particles.vtk");
  std::string first;
  std::getline(vtk, first);
  EXPECT_EQ(first, "# vtk DataFile Version 3.0");
  EXPECT_TRUE(fs::exists(dir / "vtk" / "walls.vtk"));
  fs::remove_all(dir);
}

// A settled bed handed over as a LIGGGHTS data file and a piston STL, then compressed by that
// piston read back as a mesh wall moving down: the bed file holds every particle, the piston sits
// at the bed top and covers the die, and the force series ends with the bed pushing the piston up.
TEST(Cli, SimulateWritesABedAndPistonThatASceneCompresses) {
  const fs::path dir = scratch_dir("bed");
  const std::string law = R"(
density: 2500
time_step: 1.0e-5
domain: {lo: [-0.0105, -0.0105, -0.001], hi: [0.0105, 0.0105, 0.03]}
contact_law:
  normal: {model: hertz, youngs_modulus: 1.0e7, poisson_ratio: 0.3, restitution: 0.5}
  tangential: {model: history, mu_s: 0.5, kt_ratio: 1.0}
walls:
  - {name: floor, plane: {point: [0, 0, 0], normal: [0, 0, 1]}}
  - {name: die, cylinder: {point: [0, 0, 0], axis: [0, 0, 1], radius: 0.01}}
)";
  std::ofstream(dir / "bed.yaml") << law << R"(
particles:
  random: {region: {cylinder: {centre: [0, 0, 0], radius: 0.0089, z_lo: 0.0011, z_hi: 0.012}},
           count: 150, sizes: {monodisperse: {radius: 0.001}}}
phases:
  - {name: settle, steps: 8000}
)";
  const Result bed =
      demcal("simulate " + (dir / "bed.yaml").string() + " --bed " + (dir / "bed.data").string() +
             " --piston-stl " + (dir / "piston.stl").string());
  ASSERT_EQ(bed.exit_code, 0) << bed.out;
  const double top = nlohmann::json::parse(bed.out)["metrics"]["bed_top"].get<double>();
  std::ifstream data(dir / "bed.data");
  std::string line;
  int atoms = 0;
  for (bool in_atoms = false; std::getline(data, line);) {
    if (in_atoms && !line.empty()) ++atoms;
    in_atoms = in_atoms || line == "Atoms";
  }
  EXPECT_EQ(atoms, 150);
  std::ifstream stl(dir / "piston.stl");
  double max_r = 0.0;
  for (std::string word; stl >> word;)
    if (word == "vertex") {
      double x, y, z;
      stl >> x >> y >> z;
      EXPECT_DOUBLE_EQ(z, top);
      max_r = std::max(max_r, std::hypot(x, y));
    }
  EXPECT_GT(max_r, 0.01) << "the piston covers the die";

  std::ofstream(dir / "press.yaml") << law << R"(
  - {name: piston, mesh: {stl: piston.stl}, velocity: [0, 0, -0.05]}
particles: {data_file: bed.data}
phases:
  - {name: press, steps: 3000, record_every: 500}
)";
  const Result press = demcal("simulate " + (dir / "press.yaml").string() + " --walls-csv " +
                              (dir / "walls.csv").string());
  ASSERT_EQ(press.exit_code, 0) << press.out;
  EXPECT_EQ(nlohmann::json::parse(press.out)["walls"][2], "piston");
  std::ifstream csv(dir / "walls.csv");
  std::getline(csv, line);
  EXPECT_EQ(line, "phase,step,time,wall,dx,dy,dz,fx,fy,fz");
  int rows = 0;
  std::string last;
  while (std::getline(csv, line)) {
    ++rows;
    last = line;
  }
  EXPECT_EQ(rows, 6 * 3) << "a row per wall every 500 steps";
  double values[10];
  std::replace(last.begin(), last.end(), ',', ' ');
  std::istringstream(last) >> values[0] >> values[1] >> values[2] >> values[3] >> values[4] >>
      values[5] >> values[6] >> values[7] >> values[8] >> values[9];
  EXPECT_EQ(values[3], 2.0);
  EXPECT_NEAR(values[6], -0.05 * 3000 * 1e-5, 1e-12);
  EXPECT_GT(values[9], 0.0) << "the bed pushes the piston up";
  fs::remove_all(dir);
}

/// A 2^2 packing campaign of 30 spheres, poured and grown, with one verification round.
constexpr const char* kTinyPackingCampaign = R"(name: tiny
material:
  particle_law:
    normal: {model: hertz, youngs_modulus: 2.0e6, restitution: 0.3}
    tangential: {model: history, mu_s: 0.3}
  sizes: {monodisperse: {radius: 0.0005}}
  density: 2500
tests:
  - test: packing
    settings: {particles: 30}
  - name: grown
    test: packing
    settings: {particles: 30}
    preparation: {method: growth}
factors:
  - {path: particle_law.tangential.mu_s, low: 0.1, high: 0.5}
  - {path: particle_law.normal.restitution, low: 0.2, high: 0.6}
fixed:
  wall_law.tangential.mu_s: 0.25
design: {type: full_factorial}
measurements:
  - {test: packing, metric: solid_fraction, value: 0.49, uncertainty: 0.01}
  - {test: grown, metric: solid_fraction, value: 0.455, uncertainty: 0.01}
calibration: {rounds: 1, stages: 1}
)";

/// The embedded default's `demcal export --format yaml`: a tiny packing campaign (2^2 runs of
/// 30 spheres, poured and grown, one verification round) is run and calibrated; the exported
/// material block read back by the lab-run spec reader holds the calibrated values and the fixed
/// one, and the lab run spec written for each test instance (the grown one with its own
/// preparation) simulates the verified number again, to the bit, which it holds as expected; a
/// spec expecting another value fails `demcal lab run`, naming the metric, and `scripts/resimulate`
/// of the directory.
TEST(Cli, ExportYamlWritesTheCalibratedMaterialAndALabRunSpecPerTest) {
  const fs::path dir = scratch_dir("yaml");
  std::ofstream(dir / "tiny.yaml") << kTinyPackingCampaign;
  const std::string spec = (dir / "tiny.yaml").string();
  const std::string work = " --workdir " + (dir / "work").string();
  const Result none = demcal("export " + spec + work + " --format yaml");
  EXPECT_NE(none.exit_code, 0);
  EXPECT_NE(none.out.find("campaign 1: has no calibration yet"), std::string::npos) << none.out;

  const auto run =
      demcal::test::run_command(std::string(DEMCAL_BINARY_DIR) + "/client/demcal run " + spec +
                                work + " --threads 1 --format json 2>/dev/null");
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const auto calibration = nlohmann::json::parse(run.out)["calibration"];
  const Result exported =
      demcal("export " + spec + work + " --format yaml -o " + (dir / "material.yaml").string() +
             " --lab-specs " + (dir / "specs").string());
  ASSERT_EQ(exported.exit_code, 0) << exported.out;

  const auto material = demcal::io::read_material(
      demcal::io::YamlNode::load_file((dir / "material.yaml").string())["material"]);
  ASSERT_FALSE(calibration["proposed"].empty());
  for (const auto& [path, value] : calibration["proposed"].items())
    EXPECT_EQ(demcal::lab::get_parameter(material, path), value.get<double>()) << path;
  EXPECT_EQ(demcal::lab::get_parameter(material, "wall_law.tangential.mu_s"), 0.25);

  const auto& round = calibration["rounds"].back();
  for (const auto& [instance, preparation] :
       std::vector<std::pair<std::string, std::string>>{{"packing", "pour"}, {"grown", "growth"}}) {
    const fs::path lab_spec = dir / "specs" / (instance + ".yaml");
    const auto lab = demcal::lab::read_lab_run(demcal::io::YamlNode::load_file(lab_spec.string()));
    // The calibrated material with the instance's preparation.
    auto expected = material;
    expected.preparation = demcal::lab::make_preparation(preparation, {}, "preparation");
    EXPECT_EQ(demcal::lab::material_identity(lab.material),
              demcal::lab::material_identity(expected))
        << instance;
    const auto rerun = demcal::test::run_command(
        std::string(DEMCAL_BINARY_DIR) + "/client/demcal lab run " + lab_spec.string() + " --out " +
        (dir / ("rerun-" + instance)).string() + " 2>/dev/null");
    ASSERT_EQ(rerun.exit_code, 0) << rerun.out;
    const std::size_t at = instance == "packing" ? 0 : 1;  // the measurements' order
    const double verified = round["simulated"][at].get<double>();
    EXPECT_EQ(lab.expected.at("solid_fraction"), verified) << instance;
    const auto rerun_json = nlohmann::json::parse(rerun.out);
    EXPECT_EQ(rerun_json["metrics"]["solid_fraction"].get<double>(), verified) << instance;
    EXPECT_TRUE(rerun_json["reproduced"].get<bool>()) << rerun.out;
  }

  // A spec whose expected value the run does not give: `demcal lab run` exits with status 1 and
  // names the metric, unless the difference is within --tolerance.
  auto off = demcal::lab::read_lab_run(
      demcal::io::YamlNode::load_file((dir / "specs" / "packing.yaml").string()));
  const double verified = off.expected.at("solid_fraction");
  off.expected["solid_fraction"] = verified * 1.01;
  const fs::path off_file = dir / "off.yaml";
  std::ofstream(off_file) << demcal::lab::lab_run_yaml(off);
  const auto missed = demcal::test::run_command(
      std::string(DEMCAL_BINARY_DIR) + "/client/demcal lab run " + off_file.string() + " 2>&1");
  EXPECT_EQ(missed.exit_code, 1) << missed.out;
  char named[200];
  std::snprintf(named, sizeof named, "solid_fraction: simulated %.17g against the stored %.17g",
                verified, verified * 1.01);
  EXPECT_NE(missed.out.find("does not reproduce its expected metrics to the bit:"),
            std::string::npos)
      << missed.out;
  EXPECT_NE(missed.out.find(named), std::string::npos) << missed.out;
  const auto within =
      demcal::test::run_command(std::string(DEMCAL_BINARY_DIR) + "/client/demcal lab run " +
                                off_file.string() + " --tolerance 0.02 2>&1");
  EXPECT_EQ(within.exit_code, 0) << within.out;

  // scripts/resimulate runs every spec of a directory: the exported ones reproduce their numbers;
  // with the off one beside them it exits 1 and names it and its metric.
  const std::string resimulate = "DEMCAL=" + std::string(DEMCAL_BINARY_DIR) + "/client/demcal " +
                                 source("scripts/resimulate") + " ";
  const auto exported_dir =
      demcal::test::run_command(resimulate + (dir / "specs").string() + " 2>&1");
  EXPECT_EQ(exported_dir.exit_code, 0) << exported_dir.out;
  for (const std::string line :
       {"grown.yaml: reproduced", "packing.yaml: reproduced", "2 spec(s), 0 not reproduced"})
    EXPECT_NE(exported_dir.out.find(line), std::string::npos) << exported_dir.out;
  fs::copy_file(off_file, dir / "specs" / "off.yaml");
  const auto with_off = demcal::test::run_command(resimulate + (dir / "specs").string() + " 2>&1");
  EXPECT_EQ(with_off.exit_code, 1) << with_off.out;
  for (const std::string& line : {std::string("off.yaml: NOT REPRODUCED"), std::string(named),
                                  std::string("3 spec(s), 1 not reproduced")})
    EXPECT_NE(with_off.out.find(line), std::string::npos) << with_off.out;
  fs::remove(dir / "specs" / "off.yaml");

  // With no finished run of an instance at the calibrated set (inside the box, so no design run
  // is there: the grown verification job marked failed in the store), its spec is the run the
  // instance would make there: the calibrated material with its preparation, the instance's own
  // settings and seed.
  const auto marked = demcal::test::run_command(
      "sqlite3 " + (dir / "work" / "campaign.db").string() +
      " \"UPDATE jobs SET state = 'failed', error = 'marked by the test' WHERE test = 'grown' AND "
      "kind = 'verify'\" 2>&1");
  ASSERT_EQ(marked.exit_code, 0) << marked.out;
  const Result unverified =
      demcal("export " + spec + work + " --format yaml --lab-specs " + (dir / "planned").string());
  ASSERT_EQ(unverified.exit_code, 0) << unverified.out;
  const auto first_line = [](const fs::path& file) {
    std::ifstream in(file);
    std::string line;
    std::getline(in, line);
    return line;
  };
  const fs::path planned = dir / "planned" / "grown.yaml";
  EXPECT_NE(first_line(planned).find("test grown: no finished run at the calibrated set; the "
                                     "test's own settings and seed"),
            std::string::npos)
      << first_line(planned);
  EXPECT_NE(first_line(dir / "planned" / "packing.yaml").find("test packing: the verification run"),
            std::string::npos);
  const auto lab = demcal::lab::read_lab_run(demcal::io::YamlNode::load_file(planned.string()));
  auto expected = material;
  expected.preparation = demcal::lab::make_preparation("growth", {}, "preparation");
  EXPECT_EQ(demcal::lab::material_identity(lab.material), demcal::lab::material_identity(expected));
  EXPECT_EQ(lab.options.seed, 1u);
  EXPECT_EQ(lab.settings.at("particles"), 30.0);
  EXPECT_TRUE(lab.expected.empty());  // no stored run to expect
  fs::remove_all(dir);
}

/// `demcal export --format yaml --job N`: the `demcal lab run` spec of one job of a campaign
/// still without a calibration (the tiny packing campaign, run with --no-verify). Run, the spec of
/// a grown job gives the stored solid fraction to the bit, its first comment names the job, and its
/// `expected` holds the stored metrics, which `demcal lab run` reports reproduced; the poured job,
/// marked failed in the store afterwards, has its spec
/// written all the same, its error in the comment, and that spec gives the solid fraction its run
/// stored. The grown job, queued again, has its spec written without the campaign being run: it
/// stays queued. A job the campaign does not have, the option outside the yaml format and beside
/// --lab-specs are refused, naming --job.
/// `demcal effects SPEC` and `demcal calibrate SPEC` on the embedded default read the spec's
/// campaign as `demcal run` left it: the effect tables and the calibration the run printed;
/// `calibrate SPEC --verify [--wait]` advances its loop. `--wait` without `--verify` is refused
/// at its flag.
TEST(Cli, EffectsAndCalibrateOfASpecReadItsCampaignOnTheEmbeddedDefault) {
  const fs::path dir = scratch_dir("effects_spec");
  std::ofstream(dir / "tiny.yaml") << kTinyPackingCampaign;
  const std::string spec = (dir / "tiny.yaml").string();
  const std::string work = " --workdir " + (dir / "work").string();
  const std::string cli = std::string(DEMCAL_BINARY_DIR) + "/client/demcal ";
  const auto run = demcal::test::run_command(cli + "run " + spec + work +
                                             " --threads 1 --format json 2>/dev/null");
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const auto doc = nlohmann::json::parse(run.out);

  const auto effects =
      demcal::test::run_command(cli + "effects " + spec + work + " --format json 2>/dev/null");
  ASSERT_EQ(effects.exit_code, 0) << effects.out;
  ASSERT_FALSE(doc["effects"]["metrics"].empty());
  EXPECT_EQ(nlohmann::json::parse(effects.out), doc["effects"]);

  const auto calibration =
      demcal::test::run_command(cli + "calibrate " + spec + work + " --format json 2>/dev/null");
  ASSERT_EQ(calibration.exit_code, 0) << calibration.out;
  const auto read = nlohmann::json::parse(calibration.out);
  ASSERT_FALSE(doc["calibration"]["proposed"].empty());
  EXPECT_EQ(read["proposed"], doc["calibration"]["proposed"]);
  EXPECT_EQ(read["rounds"], doc["calibration"]["rounds"]);
  // The loop ended with the run (its one round verified): advancing it queues nothing, on the
  // store as it stands or with local workers.
  for (const std::string verify : {" --verify", " --verify --wait --threads 1"}) {
    const auto advanced = demcal::test::run_command(cli + "calibrate " + spec + work + verify +
                                                    " --format json 2>/dev/null");
    ASSERT_EQ(advanced.exit_code, 0) << verify << ": " << advanced.out;
    EXPECT_EQ(nlohmann::json::parse(advanced.out)["rounds"], doc["calibration"]["rounds"])
        << verify;
  }

  const Result wait = demcal("calibrate " + spec + work + " --wait");
  EXPECT_NE(wait.exit_code, 0);
  EXPECT_NE(wait.out.find("--wait: only with --verify"), std::string::npos) << wait.out;
  fs::remove_all(dir);
}

TEST(Cli, ExportJobWritesTheLabRunSpecThatSimulatesAJobAgain) {
  const fs::path dir = scratch_dir("job");
  std::ofstream(dir / "tiny.yaml") << kTinyPackingCampaign;
  const std::string spec = (dir / "tiny.yaml").string();
  const std::string work = " --workdir " + (dir / "work").string();
  const auto run =
      demcal::test::run_command(std::string(DEMCAL_BINARY_DIR) + "/client/demcal run " + spec +
                                work + " --threads 1 --no-verify 2>&1");
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const auto listed =
      demcal::test::run_command(std::string(DEMCAL_BINARY_DIR) + "/client/demcal export " + spec +
                                work + " --format json 2>/dev/null");
  ASSERT_EQ(listed.exit_code, 0) << listed.out;
  std::map<std::string, nlohmann::json> last_of;  // instance -> its last design job
  const auto exported_jobs = nlohmann::json::parse(listed.out)["jobs"];
  for (const auto& job : exported_jobs)
    if (job["kind"] == "design" && job["state"] == "done") last_of[job["test"]] = job;
  ASSERT_EQ(last_of.size(), 2u);
  const std::string store = (dir / "work" / "campaign.db").string();
  const std::string failure = "simulation failed (escaped_particles): marked by the test";
  const auto marked = demcal::test::run_command(
      "sqlite3 " + store + " \"UPDATE jobs SET state = 'failed', " + "error = '" + failure +
      "' WHERE id = " + std::to_string(last_of.at("packing")["job_id"].get<std::int64_t>()) +
      "\" 2>&1");
  ASSERT_EQ(marked.exit_code, 0) << marked.out;

  for (const auto& [instance, job] : last_of) {
    const auto id = job["job_id"].get<std::int64_t>();
    const fs::path file = dir / (instance + ".yaml");
    const Result exported = demcal("export " + spec + work + " --format yaml --job " +
                                   std::to_string(id) + " -o " + file.string());
    ASSERT_EQ(exported.exit_code, 0) << exported.out;
    std::ifstream in(file);
    const std::string text{std::istreambuf_iterator<char>(in), {}};
    const std::string first = text.substr(0, text.find('\n'));
    EXPECT_NE(first.find("job " + std::to_string(id) + " (" + instance + ")"), std::string::npos)
        << first;
    const double stored = job["metrics"]["solid_fraction"].get<double>();
    const auto lab = demcal::lab::read_lab_run(demcal::io::YamlNode::load_file(file.string()));
    EXPECT_EQ(lab.material.preparation.method == demcal::lab::PreparationMethod::kGrowth,
              instance == "grown");
    if (instance == "packing") {
      EXPECT_LT(text.find("\n#   failed: " + failure + "\n"), text.find("\ntest: packing")) << text;
      EXPECT_TRUE(lab.expected.empty());
    } else {
      EXPECT_NE(first.find("simulates it again, its stored metrics expected"), std::string::npos)
          << first;
      EXPECT_EQ(lab.expected.at("solid_fraction"), stored);
    }
    const auto rerun = demcal::test::run_command(
        std::string(DEMCAL_BINARY_DIR) + "/client/demcal lab run " + file.string() + " --out " +
        (dir / ("rerun-" + instance)).string() + " 2>/dev/null");
    ASSERT_EQ(rerun.exit_code, 0) << rerun.out;
    const auto rerun_json = nlohmann::json::parse(rerun.out);
    EXPECT_EQ(rerun_json["metrics"]["solid_fraction"].get<double>(), stored) << instance;
    EXPECT_EQ(rerun_json.value("reproduced", false), instance == "grown") << rerun.out;
  }

  // A job not yet run, of a campaign running again: its spec is written at once, and the campaign
  // is not run for it (the job stays queued in the store).
  const auto queued_id = last_of.at("grown")["job_id"].get<std::int64_t>();
  const auto requeued = demcal::test::run_command(
      "sqlite3 " + store +
      " \"DELETE FROM result_series WHERE job_id = " + std::to_string(queued_id) +
      "; DELETE FROM results WHERE job_id = " + std::to_string(queued_id) +
      "; UPDATE jobs SET state = 'queued' WHERE id = " + std::to_string(queued_id) +
      "; UPDATE campaigns SET state = 'running'\" 2>&1");
  ASSERT_EQ(requeued.exit_code, 0) << requeued.out;
  const fs::path queued_file = dir / "queued.yaml";
  const Result queued = demcal("export " + spec + work + " --format yaml --job " +
                               std::to_string(queued_id) + " -o " + queued_file.string());
  ASSERT_EQ(queued.exit_code, 0) << queued.out;
  std::ifstream queued_in(queued_file);
  const std::string queued_text{std::istreambuf_iterator<char>(queued_in), {}};
  EXPECT_NE(queued_text.find("\n#   not finished: queued\n"), std::string::npos) << queued_text;
  EXPECT_TRUE(demcal::lab::read_lab_run(demcal::io::YamlNode::load_file(queued_file.string()))
                  .expected.empty());
  // `status` of the spec reads the store as it stands too: the job queued, the failed one with
  // its error, nothing run.
  const Result status = demcal("status " + spec + work + " --jobs");
  ASSERT_EQ(status.exit_code, 0) << status.out;
  EXPECT_NE(status.out.find("job " + std::to_string(queued_id) + " design run "), std::string::npos)
      << status.out;
  EXPECT_NE(status.out.find(" grown queued attempt "), std::string::npos) << status.out;
  EXPECT_NE(status.out.find(" packing failed attempt "), std::string::npos) << status.out;
  EXPECT_NE(status.out.find("(" + failure + ")"), std::string::npos) << status.out;
  const auto state = demcal::test::run_command(
      "sqlite3 " + store + " \"SELECT state FROM jobs WHERE id = " + std::to_string(queued_id) +
      "\" 2>&1");
  EXPECT_EQ(state.out, "queued\n");

  const Result unknown = demcal("export " + spec + work + " --format yaml --job 99");
  EXPECT_NE(unknown.exit_code, 0);
  EXPECT_NE(unknown.out.find("--job: campaign 1 has no job 99"), std::string::npos) << unknown.out;
  const Result csv = demcal("export " + spec + work + " --format csv --job 1");
  EXPECT_NE(csv.exit_code, 0);
  EXPECT_NE(csv.out.find("--job: only with --format yaml"), std::string::npos) << csv.out;
  const Result both =
      demcal("export " + spec + work + " --format yaml --job 1 --lab-specs " + dir.string());
  EXPECT_NE(both.exit_code, 0);
  EXPECT_NE(both.out.find("--job: not with --lab-specs"), std::string::npos) << both.out;
  fs::remove_all(dir);
}

/// `scripts/campaign-snapshot WORKDIR PREFIX` (docs/data/campaigns/README.md) on the tiny packing
/// campaign's work directory: refused while the store's lock is held, as a running coordinator
/// holds it; then PREFIX.db.gz unpacks to a store with the same jobs and results, and the work
/// directory's stage records are added to PREFIX.stages/ beside those already there, none
/// replaced.
TEST(Cli, CampaignSnapshotKeepsAStoppedStoreAndItsStageRecords) {
  const fs::path dir = scratch_dir("snapshot");
  std::ofstream(dir / "tiny.yaml") << kTinyPackingCampaign;
  const fs::path work = dir / "work";
  const auto run = demcal::test::run_command(
      std::string(DEMCAL_BINARY_DIR) + "/client/demcal run " + (dir / "tiny.yaml").string() +
      " --workdir " + work.string() + " --threads 1 --no-verify 2>&1");
  ASSERT_EQ(run.exit_code, 0) << run.out;
  fs::create_directories(work / "stages");
  std::ofstream(work / "stages" / "new.rec") << "new";
  std::ofstream(work / "stages" / "kept.rec") << "from the work directory";
  const fs::path prefix = dir / "kept" / "tiny";
  fs::create_directories(dir / "kept" / "tiny.stages");
  std::ofstream(dir / "kept" / "tiny.stages" / "kept.rec") << "committed before";
  const std::string snapshot =
      source("scripts/campaign-snapshot") + " " + work.string() + " " + prefix.string() + " 2>&1";

  {  // a coordinator's lock on the store
    const int fd = ::open((work / "campaign.db.lock").c_str(), O_RDWR | O_CREAT, 0600);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
    const auto refused = demcal::test::run_command(snapshot);
    ::close(fd);
    EXPECT_NE(refused.exit_code, 0);
    EXPECT_NE(refused.out.find("is in use by a coordinator"), std::string::npos) << refused.out;
    EXPECT_FALSE(fs::exists(prefix.string() + ".db.gz"));
  }
  const auto kept = demcal::test::run_command(snapshot);
  ASSERT_EQ(kept.exit_code, 0) << kept.out;
  EXPECT_NE(kept.out.find("added 1 stage record(s)"), std::string::npos) << kept.out;
  EXPECT_NE(kept.out.find("jobs: done 8"), std::string::npos) << kept.out;

  const std::string rows =
      " \"select j.id, j.state, j.run_key, r.metrics_json from jobs j join results r on "
      "r.job_id = j.id order by j.id\"";
  const auto original =
      demcal::test::run_command("sqlite3 " + (work / "campaign.db").string() + rows);
  const auto unpacked = demcal::test::run_command("gunzip -c " + prefix.string() + ".db.gz > " +
                                                  (dir / "copy.db").string() + " && sqlite3 " +
                                                  (dir / "copy.db").string() + rows);
  ASSERT_EQ(unpacked.exit_code, 0) << unpacked.out;
  EXPECT_EQ(std::count(original.out.begin(), original.out.end(), '\n'), 8) << original.out;
  EXPECT_EQ(unpacked.out, original.out);
  auto text = [](const fs::path& file) {
    std::ifstream in(file);
    return std::string{std::istreambuf_iterator<char>(in), {}};
  };
  EXPECT_EQ(text(dir / "kept" / "tiny.stages" / "new.rec"), "new");
  EXPECT_EQ(text(dir / "kept" / "tiny.stages" / "kept.rec"), "committed before");
  fs::remove_all(dir);
}

}  // namespace
