#pragma once
// The coordinator's edge: proto messages in, domain values out, and back. The plan
// (plan_input.hpp) reads the campaign's spec; nothing else in server/ reads a proto field for
// domain logic.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/doe/analysis.hpp"
#include "core/doe/model_fit.hpp"
#include "demcal/v1/campaign.pb.h"
#include "demcal/v1/worker.pb.h"
#include "server/analysis.hpp"
#include "server/plan.hpp"
#include "server/store.hpp"

namespace demcal::server {

/// A Calibrate call's arguments: the model the surrogate fits (the campaign's when none), the
/// minimiser's starts and seed, and whether to advance the loop. InputError naming the field.
struct CalibrateCall {
  std::optional<doe::ModelKind> model;
  int starts = 16;
  std::uint64_t seed = 1;
  bool verify = false;
};
CalibrateCall calibrate_call(const v1::CalibrateRequest& request);

v1::DesignSummary design_summary(const CampaignPlan& plan, int jobs);
v1::DesignReply design_reply(const CampaignPlan& plan, int jobs);
v1::Campaign campaign_message(const CampaignRow& row, const Counts& counts, double now,
                              bool with_spec);
v1::Progress progress_message(const CampaignRow& row, const Counts& counts, double now);
v1::JobResult job_message(const JobRow& job);
std::vector<std::string> factor_legend(const CampaignPlan& plan);

std::string to_json(const google::protobuf::Message& message);
/// Parses JSON into a message; InputError on unknown fields or bad values.
void from_json(const std::string& json, google::protobuf::Message& message);

/// The whole campaign (spec, design, runs, results) as JSON, or as a CSV of the design in
/// natural units plus one column per response (readable by `demcal analyze`).
/// The JSON form also holds the calibration rounds.
/// With `series` (job id -> series JSON, JSON form only) each finished job carries its curves.
std::string export_campaign(const CampaignRow& row, const CampaignPlan& plan,
                            const std::vector<JobRow>& jobs,
                            const std::vector<v1::CalibrationRound>& rounds,
                            const std::string& format,
                            const std::map<std::int64_t, std::string>* series = nullptr);

}  // namespace demcal::server
