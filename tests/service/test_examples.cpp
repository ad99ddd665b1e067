// Every campaign spec in examples/ (a file with a top-level `design:`) reads and plans as the
// coordinator would plan it: a user who copies one gets a campaign, not an error.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "client/spec_yaml.hpp"
#include "server/convert.hpp"

namespace demcal {
namespace {

namespace fs = std::filesystem;

std::vector<fs::path> campaign_examples() {
  std::vector<fs::path> out;
  const std::regex design("(^|\n)design:");
  for (const auto& entry : fs::directory_iterator(fs::path(DEMCAL_SOURCE_DIR) / "examples")) {
    if (entry.path().extension() != ".yaml") continue;
    std::ifstream in(entry.path());
    std::ostringstream text;
    text << in.rdbuf();
    if (std::regex_search(text.str(), design)) out.push_back(entry.path());
  }
  std::sort(out.begin(), out.end());
  return out;
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
      EXPECT_FALSE(plan.tests.empty());
      EXPECT_FALSE(plan.targets.empty());
      EXPECT_FALSE(jobs.empty());
    } catch (const std::exception& e) {
      ADD_FAILURE() << e.what();
    }
  }
}

}  // namespace
}  // namespace demcal
