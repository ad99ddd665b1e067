#pragma once
// What the store's text columns hold (server/store.hpp), written and read in one place: the
// campaign's spec, a job's payload, a result's metrics, flags, cost and curves, a calibration
// stage's box and a calibration round's proposal (jobs.kind: rpc/job_kind.hpp). The campaign's
// design (campaigns.design_json) is the plan's own JSON (plan.hpp: plan_to_json, stored_plan).
#include <Eigen/Dense>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/doe/factor.hpp"
#include "demcal/v1/campaign.pb.h"
#include "demcal/v1/worker.pb.h"
#include "rpc/job_kind.hpp"
#include "server/plan.hpp"

namespace demcal::server {

/// A JSON column as the document it holds, its values as stored (the export embeds them so).
nlohmann::json column_document(const std::string& column);

/// campaigns.spec_json: the campaign's spec as JSON.
v1::CampaignSpec spec_from_json(const std::string& spec_json);
/// The stored spec in canonical JSON (keys sorted; the stored text has protobuf's map order,
/// which differs between processes), so that one spec has one text and one hash.
std::string canonical_spec_json(const std::string& spec_json);

/// jobs.payload: the job as a worker receives it (v1::JobSpec as JSON, without id and attempt).
v1::JobSpec job_from_payload(const std::string& payload);

/// results.metrics_json: metric -> value; a value that is not finite is stored as null and read
/// as NaN.
std::string metrics_to_json(const std::map<std::string, double>& metrics);
std::map<std::string, double> metrics_from_json(const std::string& metrics_json);

/// results.flags_json: metric -> why its value cannot be trusted.
std::string flags_to_json(const google::protobuf::Map<std::string, std::string>& flags);
std::map<std::string, std::string> flags_from_json(const std::string& flags_json);

/// results.cost_json: the run's cost block (v1::RunCost as JSON).
v1::RunCost cost_from_json(const std::string& cost_json);

/// result_series.series_json: a result's curves, {name: {"columns": [...], "rows": [[...], ...]}};
/// "" for none.
std::string series_to_json(const google::protobuf::RepeatedPtrField<v1::Series>& series);
google::protobuf::RepeatedPtrField<v1::Series> series_from_json(const std::string& series_json);

/// calibration_stages.box_json: a stage's box, [{"low": ..., "high": ...}] per factor of the plan.
std::string box_to_json(const std::vector<doe::Factor>& box);
/// The plan's factors with the stored box's ranges.
std::vector<doe::Factor> box_from_json(const CampaignPlan& plan, const std::string& box_json);

/// calibration_rounds.proposal_json: the point a round simulates, in natural units, with the
/// values the surrogate predicts for `metrics` and the batch of rounds it was proposed in.
std::string proposal_to_json(const Eigen::VectorXd& natural, const Eigen::VectorXd& predicted,
                             const std::vector<std::string>& metrics, int batch);
struct StoredProposal {
  Eigen::VectorXd natural, predicted;  ///< NaN where the stored value is null
  std::optional<int> batch;            ///< none in rounds stored before batches
};
StoredProposal proposal_from_json(const std::string& proposal_json);

}  // namespace demcal::server
