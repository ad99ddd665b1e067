#pragma once
// The data of a campaign report: one JSON document assembled from the coordinator's own gRPC
// replies (Get, GetDesign, Export, GetEffects, Calibrate without verify, Diagnose read-only),
// each printed exactly as `demcal ... --format json` prints it. The static report
// (`demcal report`) and the live page (`demcal-server --http`) both read this, and only this.
#include <cstdint>
#include <nlohmann/json.hpp>

#include "demcal/v1/campaign.grpc.pb.h"
#include "rpc/channel.hpp"

namespace demcal::report {

/// Every reply the report reads, keyed by what it is: campaign, design, export, effects,
/// calibration, diagnosis (null where the campaign has none yet, with the reason under
/// "notes"). Reads only: nothing is queued. Throws std::runtime_error when the campaign
/// cannot be read at all (unknown id, wrong token).
nlohmann::json report_data(v1::CampaignService::StubInterface& stub,
                           const rpc::ChannelOptions& channel, std::int64_t id);

/// The campaigns the coordinator holds, as the List reply prints (for the live page's index).
nlohmann::json campaign_list(v1::CampaignService::StubInterface& stub,
                             const rpc::ChannelOptions& channel);

/// A call the report cannot do without failed: its gRPC status (mapped onto HTTP statuses).
class ReadError : public std::runtime_error {
 public:
  ReadError(grpc::StatusCode code, const std::string& what)
      : std::runtime_error(what), code_(code) {}
  grpc::StatusCode code() const { return code_; }

 private:
  grpc::StatusCode code_;
};

}  // namespace demcal::report
