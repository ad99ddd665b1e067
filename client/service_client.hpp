#pragma once
// What the service subcommands share: connection flags, status -> error mapping, and the
// printing of design summaries, progress, effect tables and calibrations.
#include <CLI/CLI.hpp>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "demcal/v1/campaign.grpc.pb.h"
#include "rpc/channel.hpp"
#include "rpc/replies.hpp"

namespace demcal::cli {

/// --coordinator (DEMCAL_COORDINATOR), --token (DEMCAL_TOKEN), --tls-ca, --insecure.
void add_connection_options(CLI::App& cmd, rpc::ChannelOptions& options);

std::unique_ptr<v1::CampaignService::Stub> campaign_stub(const rpc::ChannelOptions& options);

/// Throws for a failed call: InputError for INVALID_ARGUMENT (the message names the field),
/// std::runtime_error "<what>: <CODE>: <message>" otherwise.
void check(const grpc::Status& status, const std::string& what);

/// The reply printer and the Export stream reader live in rpc/ (the report reads with them too).
using rpc::message_json;
using rpc::read_export;

void print_design_summary(std::ostream& out, const v1::DesignSummary& d);
std::string progress_line(const v1::Progress& p, int width = 30);
/// Streams Watch and draws a progress bar on `out` until the campaign is no longer running.
v1::Progress watch_campaign(v1::CampaignService::Stub& stub, const rpc::ChannelOptions& o,
                            std::int64_t id, std::ostream& out);
/// A response's analysis as JSON: its MetricEffects with every field printed, in the message's
/// field order. The one JSON form of a response analysis: `demcal effects` prints one per
/// metric, `demcal analyze` one for its response (with what only the offline analysis has).
nlohmann::ordered_json analysis_json(const v1::MetricEffects& m);
/// The document of `demcal effects --format json`: the factor letters and each metric's
/// analysis_json.
nlohmann::ordered_json effects_json(const v1::EffectsReply& e);
/// table | csv | json
void print_effects(std::ostream& out, const v1::EffectsReply& e, const std::string& format);
void print_calibration(std::ostream& out, const v1::CalibrateReply& c, const std::string& format);
/// A multi-fidelity campaign's particle-steps per level against the all-high design.
void print_fidelity_cost(std::ostream& out, const v1::FidelityCost& cost);
/// The rounds of a sequential calibration as a table.
void print_rounds(std::ostream& out,
                  const google::protobuf::RepeatedPtrField<v1::CalibrationRound>& rounds);
/// Calls Calibrate until the calibration no longer runs (with `request.verify`: the whole
/// sequential loop), watching the campaign's jobs on `progress` in between.
v1::CalibrateReply drive_calibration(v1::CampaignService::Stub& stub,
                                     const rpc::ChannelOptions& channel,
                                     const v1::CalibrateRequest& request, std::ostream& progress);
std::string state_name(v1::CampaignState s);

}  // namespace demcal::cli
