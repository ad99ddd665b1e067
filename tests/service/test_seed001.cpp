// examples/seed001_granules.yaml, the seed 001 campaign with the seed's numbers: it plans as
// written (five tests, four of them one drum per wall surface, each a response of its own, the
// measured values of §4.1 and Table 2), and a small variant of it (lambda 30,000 instead of 64,
// so D/d = 15 and 443 granules; the drum turned at 40 rpm for a short angle window) runs one drum
// job the way a worker does.
#include <gtest/gtest.h>

#include <fstream>
#include <optional>
#include <sstream>

#include "client/spec_yaml.hpp"
#include "core/lab/lab_test.hpp"
#include "core/lab/rotating_drum.hpp"
#include "rpc/material_convert.hpp"
#include "server/convert.hpp"

namespace demcal::test {
namespace {

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
  EXPECT_EQ(plan.tests, (std::vector<std::string>{"compression", "drum_ptfe", "drum_pp",
                                                  "drum_aluminium", "drum_coated"}));
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

TEST(Seed001Example, SmallVariantRunsADrumOfTheSeedsGranules) {
  std::string text = replaced(example(), "factor: 64}", "factor: 30000}");
  text = replaced(text, "rpm: 4, time_step_safety: 0.6,",
                  "rpm: 40, angle_time: 0.1, area_time: 0.02, time_step_safety: 0.6,");
  const auto file = cli::parse_campaign_spec(text, "small.yaml");
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

}  // namespace
}  // namespace demcal::test
