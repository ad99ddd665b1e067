// The compaction lab test as a campaign response (seed 004 in a calibration): its yield-surface
// metrics are planned as responses and measured targets, and a small campaign of periodic cells
// runs end to end on the embedded `demcal run`, where the effects table finds the friction's
// effect on the jamming fraction (frictional spheres jam looser: 0.63 frictionless against about
// 0.57 at mu_s 0.5, docs/lab-tests.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "client/spec_yaml.hpp"
#include "server/convert.hpp"
#include "server/plan.hpp"
#include "tests/service/process.hpp"

namespace demcal::test {
namespace {

namespace fs = std::filesystem;

/// Four cells of 40 spheres (a two-factor full factorial), compacted to 0.66 in two steps and
/// probed for yield; a measured M of the yield surface.
constexpr const char* kSpec = R"(
name: compaction_yield
material:
  particle_law:
    normal: {model: hertz, youngs_modulus: 5.0e7, poisson_ratio: 0.25, restitution: 0.5}
    tangential: {model: history, mu_s: 0.5}
  sizes: {monodisperse: {radius: 0.001}}
  density: 2500
tests:
  - test: compaction
    settings: {particles: 40, phi_max: 0.66, points: 2, strain_rate: 1.0e-4, hold: 100, probe_strain: 0}
factors:
  - {path: particle_law.tangential.mu_s, low: 0.0, high: 0.5, name: mu_s}
  - {path: particle_law.normal.restitution, low: 0.3, high: 0.6, name: e}
design: {type: full_factorial}
measurements:
  - {test: compaction, metric: yield_slope, value: 0.35, uncertainty: 0.05}
calibration: {rounds: 1, stages: 1}
)";

TEST(CompactionCampaign, YieldSurfaceMetricsAreResponsesAndTargets) {
  const auto file = cli::parse_campaign_spec(kSpec, "compaction.yaml");
  std::vector<server::NewJob> jobs;
  const auto plan = server::plan_campaign(file.spec, jobs);
  for (const char* r : {"compaction.yield_slope", "compaction.yield_cap_pressure",
                        "compaction.isotropic_yield_pressure", "compaction.jamming_fraction"})
    EXPECT_NE(std::find(plan.responses.begin(), plan.responses.end(), r), plan.responses.end())
        << r;
  ASSERT_EQ(plan.targets.size(), 1u);
  EXPECT_EQ(plan.targets[0].response, "compaction.yield_slope");
  EXPECT_EQ(jobs.size(), 4u);
}

/// The effect in `log`'s effects block of `metric` whose alias chain is exactly `chain`.
double effect(const std::string& log, const std::string& metric, const std::string& chain) {
  const auto at = log.find("== " + metric + " (");
  if (at == std::string::npos) return NAN;
  std::istringstream block(log.substr(at, log.find("\n==", at + 1) - at));
  const std::regex row("^\\s+(-?[0-9.eE+-]+)\\s+\\**\\s*" + chain + "$");
  std::smatch m;
  for (std::string line; std::getline(block, line);)
    if (std::regex_match(line, m, row)) return std::stod(m[1]);
  return NAN;
}

TEST(CompactionCampaign, EmbeddedRunFindsTheFrictionEffectOnJamming) {
  const fs::path dir =
      fs::temp_directory_path() / ("demcal_compaction_" + std::to_string(getpid()));
  Process run = embedded_run(DEMCAL_CLI_BIN, dir, kSpec);
  ASSERT_EQ(run.wait_exit(200), 0) << run.log();
  const std::string out = run.log();
  EXPECT_NE(out.find("== compaction.yield_slope (4 of 4 runs) =="), std::string::npos) << out;
  EXPECT_NE(out.find("verification: done, 1 simulation(s) added by the calibration"),
            std::string::npos)
      << out;
  // A = mu_s from 0 to 0.5: -0.052 in one build, against a noise sd (Lenth) of 0.008.
  EXPECT_LT(effect(out, "compaction.jamming_fraction", "A"), -0.03) << out;
  if (!HasFailure()) fs::remove_all(dir);
}

}  // namespace
}  // namespace demcal::test
