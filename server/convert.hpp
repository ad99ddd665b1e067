#pragma once
// The coordinator's edge: proto messages in, domain values out, and back. Nothing else in
// server/ reads a proto field for domain logic.
#include <map>
#include <string>
#include <vector>

#include "core/doe/analysis.hpp"
#include "demcal/v1/worker.pb.h"
#include "server/analysis.hpp"
#include "server/plan.hpp"
#include "server/store.hpp"

namespace demcal::server {

/// A number in an error message: six significant digits.
std::string fmt(double v);

/// Validates a spec and plans it; InputError names the field ("spec.factors[2].high").
/// Factor paths must exist in the material's parameter table (lab::parameters) with bounds
/// inside the valid range; tests, settings and measured metrics must exist in the catalogue.
CampaignPlan plan_campaign(const v1::CampaignSpec& spec, std::vector<NewJob>& jobs);

/// The name of a test instance, which its responses carry ("<name>.<metric>"): its `name`, or the
/// lab test's when it has none.
std::string instance_name(const v1::LabTest& test);

/// Jobs that simulate each test of the spec with `material` at one parameter set (the spec's
/// fixed parameters, then `parameters`), as design row `std_order` of job kind `kind`, with
/// the test's seed + `seed_offset`.
std::vector<NewJob> jobs_at(const v1::CampaignSpec& spec, const v1::Material& material,
                            const std::map<std::string, double>& parameters, int std_order,
                            const std::string& kind, std::uint64_t seed_offset = 0);

/// One job per design row and test, the plan's design laid over `box` (the campaign's factors
/// or a calibration stage's narrowed box), of job kind `kind`. Seeds: see Design.Seeds in the
/// proto; a later stage adds `stage_offset` to keep its runs' seeds apart from the first.
/// With `rows` (1-based standard order), only those rows.
std::vector<NewJob> design_jobs(const v1::CampaignSpec& spec, const CampaignPlan& plan,
                                const std::vector<PlannedFactor>& box, const std::string& kind,
                                int stage_offset, const std::vector<int>* rows = nullptr);

/// The spec at one level of the plan's fidelity axis (the low or the high value in every test
/// instance that has the setting, or as a fixed material parameter); the spec itself without one.
v1::CampaignSpec at_fidelity(const v1::CampaignSpec& spec, const CampaignPlan& plan, bool high);

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
