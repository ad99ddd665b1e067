// Hidden-effect system test of the multi-fidelity calibration (docs/doe.md, "Multi-fidelity
// calibration"). The "measured" packing solid fraction and coordination number are a simulation
// of a large bed (kHigh particles) of cohesionless Hertz spheres with a hidden sliding friction.
// The campaign varies the friction (log scale) and the restitution in a 2^2 design with a centre
// run; its low level is a small bed (kLow particles), whose packing is looser and less
// coordinated near the die and floor: a bias no factor of the design can see. Both campaigns run
// as a user runs them (`demcal run spec.yaml --format json`: embedded coordinator and worker over
// gRPC, SQLite):
//   single fidelity  every run at the low level: the calibration misses the hidden friction;
//   multi-fidelity   the same design at the low level, its centre run at the high level too, the
//                    high level modelled from the low one: the hidden friction lies inside the
//                    stated interval, and the design cost at most 40 % of the particle-steps of
//                    running every row at the high level; its report (rendered by headless
//                    Chromium) shows the high level's model and the particle-steps per level.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>

#include "tests/common/command.hpp"

namespace {

constexpr int kLow = 150, kHigh = 1000;
constexpr double kHiddenMu = 0.2;         ///< inside the factor box [0.1, 0.6]
constexpr double kMaxCostFraction = 0.4;  ///< of the all-high design's particle-steps

std::string material_yaml(double mu_s) {
  std::ostringstream y;
  y << "material:\n  particle_law:\n"
    << "    normal: {model: hertz, youngs_modulus: 5.0e6, poisson_ratio: 0.3, restitution: 0.5}\n"
    << "    tangential: {model: history, mu_s: " << mu_s << "}\n"
    << "  wall_law:\n"
    << "    normal: {model: hertz, youngs_modulus: 5.0e6, poisson_ratio: 0.3, restitution: 0.5}\n"
    << "    tangential: {model: history, mu_s: 0.3}\n"
    << "  sizes: {monodisperse: {radius: 0.002}}\n  density: 2500\n";
  return y.str();
}

nlohmann::json run_json(const std::string& cmd) {
  const demcal::test::CommandResult r = demcal::test::run_command(cmd);
  EXPECT_EQ(r.exit_code, 0) << cmd;
  return nlohmann::json::parse(r.out);
}

std::map<std::string, double> measure(const std::filesystem::path& dir) {
  const auto file = dir / "truth.yaml";
  std::ofstream(file) << "test: packing\nsettings: {particles: " << kHigh
                      << "}\nseed: 1001\nthreads: 1\n"
                      << material_yaml(kHiddenMu);
  const auto j = run_json(std::string(DEMCAL_CLI_BIN) + " lab run " + file.string());
  return {{"solid_fraction", j["metrics"]["solid_fraction"].get<double>()},
          {"coordination_number", j["metrics"]["coordination_number"].get<double>()}};
}

std::string campaign_yaml(const std::string& name, const std::map<std::string, double>& measured,
                          bool multi_fidelity) {
  std::ostringstream y;
  y.precision(10);
  y << "name: " << name << "\n" << material_yaml(0.3);
  y << "tests:\n  - test: packing\n    settings: {particles: " << kLow
    << "}\n    seed: 3\n    threads: 1\n";
  y << "factors:\n"
    << "  - {path: particle_law.tangential.mu_s, low: 0.1, high: 0.6, scale: log}\n"
    << "  - {path: particle_law.normal.restitution, low: 0.2, high: 0.8}\n";
  y << "design: {type: full_factorial, centre_points: 1}\n";
  y << "calibration: {stages: 1, rounds: 2}\n";
  if (multi_fidelity)
    y << "fidelity: {path: settings.particles, low: " << kLow << ", high: " << kHigh << "}\n";
  y << "measurements:\n";
  for (const auto& [metric, value] : measured)
    y << "  - {test: packing, metric: " << metric << ", value: " << value
      << ", source: hidden truth}\n";
  return y.str();
}

nlohmann::json run_campaign(const std::filesystem::path& dir, const std::string& name,
                            const std::map<std::string, double>& measured, bool multi_fidelity) {
  const auto spec = dir / (name + ".yaml");
  std::ofstream(spec) << campaign_yaml(name, measured, multi_fidelity);
  return run_json(std::string(DEMCAL_CLI_BIN) + " run " + spec.string() +
                  " --format json --threads 1 --workdir " + (dir / name).string() + " 2>" +
                  (dir / (name + ".log")).string());
}

/// The calibration's interval of the friction factor.
nlohmann::json friction_interval(const nlohmann::json& run) {
  for (const auto& i : run["calibration"]["intervals"])
    if (i["factor"] == "particle_law.tangential.mu_s") return i;
  ADD_FAILURE() << "no interval for the friction";
  return {};
}

bool inside(const nlohmann::json& interval, double v) {
  return interval.value("available", false) && interval["low"].get<double>() <= v &&
         v <= interval["high"].get<double>();
}

TEST(MultiFidelityHidden, TheHighLevelModelFindsTheFrictionTheSmallBedMisses) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("demcal-mf-hidden-" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const auto measured = measure(dir);
  const auto single = run_campaign(dir, "single", measured, false);
  const auto multi = run_campaign(dir, "multi", measured, true);
  std::cout << "measured (" << kHigh << " particles, mu_s " << kHiddenMu
            << "): " << nlohmann::json(measured).dump() << "\nsingle fidelity:\n"
            << single["calibration"].dump(2) << "\nmulti-fidelity:\n"
            << multi["calibration"].dump(2) << "\n";

  const auto single_interval = friction_interval(single);
  const auto multi_interval = friction_interval(multi);
  EXPECT_FALSE(inside(single_interval, kHiddenMu)) << single_interval.dump();
  EXPECT_TRUE(inside(multi_interval, kHiddenMu)) << multi_interval.dump();

  const auto& cost = multi["calibration"]["fidelity_cost"];
  const double design =
      cost["low_particle_steps"].get<double>() + cost["high_particle_steps"].get<double>();
  const double all_high = cost["all_high_particle_steps"].get<double>();
  EXPECT_LE(design, kMaxCostFraction * all_high) << cost.dump();
  ASSERT_EQ(multi["calibration"]["fidelity"].size(), 2u);
  for (const auto& f : multi["calibration"]["fidelity"])
    EXPECT_GT(f["mean_bias"].get<double>(), 0.0)
        << "the small bed is looser and less coordinated: " << f.dump();

  // The report shows the high level's model and the cost of each level (rendered in Chromium).
  const std::string report = std::string(DEMCAL_CLI_BIN) + " report " +
                             (dir / "multi.yaml").string() + " --threads 1 --workdir " +
                             (dir / "multi").string() + " -o " + (dir / "report").string() +
                             " 2>/dev/null";
  ASSERT_EQ(demcal::test::run_command(report).exit_code, 0) << report;
  const auto dom = demcal::test::run_command(
      "chromium --headless --no-sandbox --disable-gpu --user-data-dir=" +
      (dir / "chromium-profile").string() + " --virtual-time-budget=10000 --dump-dom " +
      (dir / "report" / "report.html").string() + " 2>/dev/null");
  // Rendered elements, not the script's text (which the page also holds).
  EXPECT_NE(dom.out.find("<h3>High fidelity level from the low one</h3>"), std::string::npos);
  EXPECT_TRUE(std::regex_search(dom.out, std::regex(R"(\(this design: \d+ %\))")));
  std::filesystem::remove_all(dir);
}

}  // namespace
