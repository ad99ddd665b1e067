// examples/seed001_granules.yaml, the seed 001 campaign with the seed's numbers: it plans as
// written (five tests, four of them one drum per wall surface, each a response of its own, the
// measured values of §4.1 and Table 2), and a small variant of it (lambda 30,000 instead of 64,
// so D/d = 15 and 443 granules; the drum turned at 40 rpm for a short angle window) runs one drum
// job the way a worker does, and the whole campaign end to end with its drums half as deep.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>

#include "client/spec_yaml.hpp"
#include "core/lab/lab_run.hpp"
#include "core/lab/rotating_drum.hpp"
#include "process.hpp"
#include "rpc/material_convert.hpp"
#include "server/convert.hpp"
#include "server/plan.hpp"

namespace demcal::test {
namespace {

namespace fs = std::filesystem;

std::string example() {
  std::ifstream in(std::string(DEMCAL_SOURCE_DIR) + "/examples/seed001_granules.yaml");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? text : text.replace(at, from.size(), to);
}

/// The payload of the job of test instance `test` at design row `std_order`.
std::optional<v1::JobSpec> find_job(const std::vector<server::NewJob>& jobs,
                                    const std::string& test, int std_order) {
  for (const auto& j : jobs)
    if (j.test == test && j.std_order == std_order) {
      v1::JobSpec spec;
      server::from_json(j.payload, spec);
      return spec;
    }
  return std::nullopt;
}

TEST(Seed001Example, PlansWithTheSeedsMeasurementsAndOneDrumPerSurface) {
  const auto file = cli::parse_campaign_spec(example(), "seed001_granules.yaml");
  std::vector<server::NewJob> jobs;
  const auto plan = server::plan_campaign(file.spec, jobs);
  EXPECT_EQ(server::instance_names(plan),
            (std::vector<std::string>{"compression", "drum_ptfe", "drum_pp", "drum_aluminium",
                                      "drum_coated"}));
  std::map<std::string, double> target;
  for (const auto& t : plan.targets) target[t.response] = t.value;
  EXPECT_EQ(target,
            (std::map<std::string, double>{{"compression.confined_modulus", 45.4},       // §4.1
                                           {"drum_ptfe.dynamic_angle_of_repose", 31.9},  // Table 2
                                           {"drum_pp.dynamic_angle_of_repose", 32.2},
                                           {"drum_aluminium.dynamic_angle_of_repose", 34.2},
                                           {"drum_coated.dynamic_angle_of_repose", 34.6}}));
  EXPECT_EQ(jobs.size(), 5u * 5u);  // 2^2 + 1 centre point, five tests
  // The polymer drums carry Table 3's granule-polymer pair, the others the aluminium one.
  const auto ptfe = find_job(jobs, "drum_ptfe", 1);
  const auto coated = find_job(jobs, "drum_coated", 1);
  ASSERT_TRUE(ptfe && coated);
  EXPECT_EQ(ptfe->material().wall_law().rolling().params().at("mu_r"), 1e-4);
  EXPECT_EQ(ptfe->material().wall_law().tangential().params().at("mu_s"), 0.9);
  EXPECT_EQ(coated->material().wall_law().rolling().params().at("mu_r"), 0.2);
  // At the seed's lambda = 64 each drum holds about the seed's 200,000 granules (§4.2).
  const auto model = rpc::job_material(*coated);
  const auto s =
      lab::read_settings<lab::RotatingDrumSettings>(rpc::to_settings(coated->settings()), "s");
  EXPECT_NEAR(double(lab::drum_bed(s, model.simulated_sizes(), "s").particles), 2e5, 2e4);
}

/// The example at lambda 30,000 (443 granules a drum, D/d 15), the drum at 40 rpm for a short
/// angle window, the die with 100 granules; `calibration` appended when not empty.
std::string small_variant(const std::string& calibration = "") {
  std::string text = replaced(example(), "factor: 64}", "factor: 30000}");
  text = replaced(text, "rpm: 4, time_step_safety: 0.6,",
                  "rpm: 40, angle_time: 0.1, area_time: 0.02, time_step_safety: 0.6,");
  text = replaced(text, "particles: 26000,", "particles: 100,");
  return text + calibration;
}

TEST(Seed001Example, SmallVariantRunsADrumOfTheSeedsGranules) {
  const auto file = cli::parse_campaign_spec(small_variant(), "small.yaml");
  std::vector<server::NewJob> jobs;
  server::plan_campaign(file.spec, jobs);
  const auto job = find_job(jobs, "drum_coated", 5);  // the centre point
  ASSERT_TRUE(job.has_value());
  EXPECT_NEAR(job->parameters().at("particle_law.tangential.mu_s"), 0.535, 1e-12);
  const auto model = rpc::job_material(*job);
  const auto out = lab::run_lab_test(job->test(), model, rpc::to_settings(job->settings()), {});
  const auto s =
      lab::read_settings<lab::RotatingDrumSettings>(rpc::to_settings(job->settings()), "s");
  const auto bed = lab::drum_bed(s, model.simulated_sizes(), "s");
  EXPECT_EQ(out.metrics.at("particles"), double(bed.particles));
  EXPECT_NEAR(out.metrics.at("drum_diameter_ratio"), 15.4, 0.5);  // 100 mm / (31 x 208 um)
  // A rolling bed with a sloped surface that fills the drum's lower part (43 % fill of a bulk
  // at solid fraction 0.6 shows as ~45-60 % black in the projected image).
  EXPECT_GT(out.metrics.at("dynamic_angle_of_repose"), 20.0);
  EXPECT_LT(out.metrics.at("dynamic_angle_of_repose"), 60.0);
  EXPECT_GT(out.metrics.at("csa_occupied_4"), 35.0);
  EXPECT_LT(out.metrics.at("csa_occupied_4"), 65.0);
  EXPECT_EQ(out.metrics.at("centrifuging_116"), 0.0);
}

TEST(Seed001Example, SmallVariantRunsEndToEndOnTheEmbeddedDefault) {
  // `demcal run` of the small variant with two local workers: 25 design jobs, the effect table of
  // each of the five responses, and one verification round (one job per test instance). The
  // drums are 22 mm deep instead of 44 (about 220 granules each, half the run time).
  const fs::path dir = fs::temp_directory_path() / ("demcal_seed001_" + std::to_string(getpid()));
  const std::string spec = replaced(small_variant("calibration: {rounds: 1, stages: 1}\n"),
                                    "length: 44,", "length: 22,");
  Process run = embedded_run(DEMCAL_CLI_BIN, dir, spec);
  ASSERT_EQ(run.wait_exit(900), 0) << run.log();
  const std::string out = run.log();
  for (const char* header : {"== compression.confined_modulus (5 of 5 runs) ==",
                             "== drum_ptfe.dynamic_angle_of_repose (5 of 5 runs) ==",
                             "== drum_pp.dynamic_angle_of_repose (5 of 5 runs) ==",
                             "== drum_aluminium.dynamic_angle_of_repose (5 of 5 runs) ==",
                             "== drum_coated.dynamic_angle_of_repose (5 of 5 runs) =="})
    EXPECT_NE(out.find(header), std::string::npos) << header << "\n" << out;
  EXPECT_NE(out.find("verification: done, 5 simulation(s) added by the calibration"),
            std::string::npos)
      << out;
  // Each measured value against what the box reaches, by instance.
  for (const auto& [response, target] : std::vector<std::pair<std::string, std::string>>{
           {"compression.confined_modulus", "45.4"},
           {"drum_ptfe.dynamic_angle_of_repose", "31.9"},
           {"drum_coated.dynamic_angle_of_repose", "34.6"}})
    EXPECT_NE(out.find("target " + target + " of " + response), std::string::npos)
        << response << "\n"
        << out;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace demcal::test
