#pragma once
// A validated campaign in domain terms: the factors (parameter paths with their doe::Factor
// boxes), the design, the responses (test.metric) and the measured targets. Built from the
// proto spec in convert.cpp; stored as JSON in campaigns.design_json so that analysis after a
// restart uses exactly the design that was run.
#include <optional>
#include <string>
#include <vector>

#include "core/doe/design.hpp"
#include "core/doe/factor.hpp"

namespace demcal::server {

struct PlannedFactor {
  std::string path;
  doe::Factor factor;  ///< factor.name = the label shown in tables
};

struct Target {
  std::string response;  ///< test.metric
  double value = 0.0, weight = 1.0;
  std::optional<double> uncertainty;
  std::string source;
  bool holdout = false;  ///< kept out of calibrations (reported by the diagnosis)
};

/// The fidelity axis of a multi-fidelity campaign: the design runs at `low`, the rows
/// `high_rows` (1-based standard order) at `high` as well.
struct FidelityPlan {
  std::string path;  ///< settings.<name> or a material parameter path
  double low = 0.0, high = 0.0;
  std::vector<int> high_rows;
};

struct CampaignPlan {
  std::vector<PlannedFactor> factors;
  doe::Design design;
  std::vector<std::string> tests;
  std::vector<std::string> responses;  ///< test.metric, tests in spec order
  std::vector<Target> targets;
  std::optional<FidelityPlan> fidelity;
};

std::string plan_to_json(const CampaignPlan& plan);
CampaignPlan plan_from_json(const std::string& json);

}  // namespace demcal::server
