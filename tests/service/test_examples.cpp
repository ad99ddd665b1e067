// Every campaign spec in examples/ (a file with a top-level `design:`) reads and plans as the
// coordinator would plan it: a user who copies one gets a campaign, not an error. Its planned
// runs keep their run keys (what a journal finds a run by), and its plan reads back as stored.
#include <google/protobuf/util/message_differencer.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "client/spec_yaml.hpp"
#include "core/io/yaml_node.hpp"
#include "core/lab/lab_run_yaml.hpp"
#include "rpc/material_convert.hpp"
#include "server/convert.hpp"
#include "server/plan.hpp"
#include "server/run_key.hpp"

namespace demcal {
namespace {

namespace fs = std::filesystem;

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<fs::path> example_files(const std::regex& marker) {
  std::vector<fs::path> out;
  for (const auto& entry : fs::directory_iterator(fs::path(DEMCAL_SOURCE_DIR) / "examples"))
    if (entry.path().extension() == ".yaml" && std::regex_search(read_text(entry.path()), marker))
      out.push_back(entry.path());
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<fs::path> campaign_examples() {
  return example_files(std::regex("(^|\n)design:"));
}

TEST(Examples, EveryCampaignSpecReadsAndPlans) {
  const auto files = campaign_examples();
  // The lactose, drum, packing and seed-001 campaigns at least (a wrong directory finds none).
  ASSERT_GE(files.size(), 10u);
  for (const auto& f : files) {
    SCOPED_TRACE(f.filename().string());
    std::vector<server::NewJob> jobs;
    try {
      const auto file = cli::read_campaign_spec(f.string());
      const auto plan = server::plan_campaign(file.spec, jobs);
      EXPECT_FALSE(plan.instances.empty());
      EXPECT_FALSE(plan.targets.empty());
      EXPECT_FALSE(jobs.empty());
    } catch (const std::exception& e) {
      ADD_FAILURE() << e.what();
    }
  }
}

nlohmann::json job_keys(const std::vector<server::NewJob>& jobs) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& j : jobs)
    out.push_back({j.kind, j.std_order, j.run_order, j.test, j.run_key.key});
  return out;
}

/// The diagnosis's model switches, each as the golden file names it.
const std::vector<std::map<std::string, std::string>> kSwitches = {
    {{"sizes", "lognormal"}},
    {{"preparation", "clusters"}},
    {{"shape", "rod"}},
    {{"shape", "cluster"}},
    {{"particle_law.rolling", "cdt"}}};

/// tests/data/run-keys/examples.json (its README says what it holds): the design's jobs, a
/// calibration stage over the lower half of the box, a verification at the centre at the high
/// level, and a diagnosis run at the centre under each switch.
TEST(Examples, EveryCampaignPlansTheRunKeysItAlwaysPlanned) {
  const auto golden = nlohmann::json::parse(
      read_text(fs::path(DEMCAL_SOURCE_DIR) / "tests/data/run-keys/examples.json"));
  const auto files = campaign_examples();
  ASSERT_EQ(files.size(), golden.size());
  int compared = 0;
  for (const auto& f : files) {
    const std::string name = f.filename().string();
    SCOPED_TRACE(name);
    ASSERT_TRUE(golden.contains(name));
    const auto& want = golden.at(name);
    std::vector<server::NewJob> jobs;
    const auto plan = server::plan_campaign(cli::read_campaign_spec(f.string()).spec, jobs);
    EXPECT_EQ(job_keys(jobs), want.at("jobs"));
    auto box = plan.factors;
    for (auto& b : box) b.factor.high = b.factor.to_natural(0.0);
    EXPECT_EQ(job_keys(server::jobs_of(
                  plan, server::design_runs(plan, box, "stage2", plan.design.runs(), false))),
              want.at("stage"));
    std::map<std::string, double> centre;
    for (const auto& b : plan.factors) centre[b.path] = b.factor.to_natural(0.0);
    EXPECT_EQ(
        job_keys(server::jobs_of(plan, server::runs_at(plan, centre, true, 3, "verify", 1000003))),
        want.at("verify"));
    for (const auto& sw : kSwitches) {
      const std::string key = sw.begin()->first + "=" + sw.begin()->second;
      const auto& expected = want.at("switch").at(key);
      const auto runs = server::runs_at(plan, centre, false, 2, "diagnose:x", 1);
      if (expected.is_string()) {
        EXPECT_ANY_THROW(server::jobs_of(plan, runs, sw)) << key;
      } else {
        EXPECT_EQ(job_keys(server::jobs_of(plan, runs, sw)), expected) << key;
      }
    }
    compared += static_cast<int>(want.at("jobs").size());
  }
  EXPECT_GT(compared, 500);
}

/// Seed 000 starts its tensile test from the bed the confined compression conditioned (§2.7.3):
/// each tensile job of the LH220 campaign is leased after its row's compression (the stage cache
/// then hands it that bed), and no other job waits.
TEST(Examples, TheTensileJobsOfTheLh220CampaignWaitForTheirRowsCompression) {
  std::vector<server::NewJob> jobs;
  server::plan_campaign(cli::read_campaign_spec(std::string(DEMCAL_SOURCE_DIR) +
                                                "/examples/lh220_calibration_campaign.yaml")
                            .spec,
                        jobs);
  int tensile = 0;
  for (const auto& j : jobs) {
    EXPECT_EQ(j.waits_for, j.test == "tensile" ? "confined_compression" : "") << j.test;
    tensile += j.test == "tensile";
  }
  EXPECT_EQ(tensile, 33);
}

TEST(Examples, EveryPlanReadsBackAsStored) {
  for (const auto& f : campaign_examples()) {
    SCOPED_TRACE(f.filename().string());
    std::vector<server::NewJob> jobs;
    const auto file = cli::read_campaign_spec(f.string());
    server::CampaignRow row;
    row.spec_json = server::to_json(file.spec);
    row.design_json = server::plan_to_json(server::plan_campaign(file.spec, jobs));
    EXPECT_EQ(server::plan_to_json(server::stored_plan(row)), row.design_json);
  }
}

/// A campaign stored before the plan held the whole campaign (its design_json the design,
/// responses, targets and fidelity axis only) reads as the plan of its stored spec; its jobs wait
/// for none (the catalogue's starts_from is consulted at Submit only).
TEST(Examples, APlanOfTheEarlierFormReadsWithItsStoredSpec) {
  for (const auto& f : campaign_examples()) {
    SCOPED_TRACE(f.filename().string());
    std::vector<server::NewJob> jobs;
    const auto file = cli::read_campaign_spec(f.string());
    auto plan = server::plan_campaign(file.spec, jobs);
    auto earlier = nlohmann::json::parse(server::plan_to_json(plan));
    for (const char* key :
         {"form", "material", "fixed", "instances", "pinned_seeds", "calibration", "diagnosis"})
      earlier.erase(key);
    for (auto& factor : earlier["factors"]) factor.erase("tied");
    server::CampaignRow row;
    row.spec_json = server::to_json(file.spec);
    row.design_json = earlier.dump();
    for (auto& i : plan.instances) i.waits_for.clear();
    EXPECT_EQ(server::plan_to_json(server::stored_plan(row)), server::plan_to_json(plan));
  }
}

/// A campaign stored by an earlier build, whose spec left the material's defaults out (no wall law
/// when it is the particle law, no shape, preparation or size scale), is the same campaign as the
/// spec read today: a work directory of it resumes. A changed factor bound is another campaign.
TEST(Examples, ASpecStoredWithoutTheMaterialsDefaultsReadsAsTheSameCampaign) {
  for (const auto& f : campaign_examples()) {
    SCOPED_TRACE(f.filename().string());
    const v1::CampaignSpec today = cli::read_campaign_spec(f.string()).spec;
    v1::CampaignSpec earlier = today;
    auto& m = *earlier.mutable_material();
    if (google::protobuf::util::MessageDifferencer::Equals(m.wall_law(), m.particle_law()))
      m.clear_wall_law();
    m.clear_shape();
    m.clear_preparation();
    m.set_size_scale(0.0);
    ASSERT_FALSE(google::protobuf::util::MessageDifferencer::Equals(earlier, today));
    EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(rpc::canonical_spec(earlier),
                                                                   rpc::canonical_spec(today)));
    v1::CampaignSpec other = earlier;
    other.mutable_factors(0)->set_high(other.factors(0).high() * 0.75);
    EXPECT_FALSE(google::protobuf::util::MessageDifferencer::Equals(rpc::canonical_spec(other),
                                                                    rpc::canonical_spec(today)));
  }
}

/// Every material of the examples (campaigns' and lab runs') gives itself back through its proto
/// form: each parameter and each choice a run key holds.
TEST(Examples, EveryMaterialKeepsEveryValueThroughItsProtoForm) {
  std::vector<lab::MaterialModel> materials;
  for (const auto& f : campaign_examples())
    materials.push_back(rpc::to_material_model(cli::read_campaign_spec(f.string()).spec.material(),
                                               "spec.material"));
  for (const auto& f : example_files(std::regex("(^|\n)test:")))
    materials.push_back(lab::read_lab_run(io::YamlNode::load_file(f.string())).material);
  ASSERT_GE(materials.size(), 20u);
  for (const auto& m : materials) {
    const lab::MaterialModel back = rpc::to_material_model(rpc::to_material_message(m), "m");
    EXPECT_EQ(back.particle_law, m.particle_law);
    EXPECT_EQ(back.wall_law, m.wall_law);
    EXPECT_EQ(lab::parameters(back).size(), lab::parameters(m).size());
    for (const auto& p : lab::parameters(m)) {
      const double was = lab::get_parameter(m, p.path), is = lab::get_parameter(back, p.path);
      EXPECT_TRUE(is == was || (std::isnan(is) && std::isnan(was))) << p.path;  // NaN: derived
    }
    EXPECT_EQ(io::material_yaml(back), io::material_yaml(m));
  }
}

}  // namespace
}  // namespace demcal
