#pragma once
// How a client reads the coordinator's campaign replies, shared by the CLI and the report: a
// reply printed as JSON, and the Export stream read whole.
#include <cstdint>
#include <string>
#include <vector>

#include "demcal/v1/campaign.grpc.pb.h"
#include "rpc/channel.hpp"

namespace demcal::rpc {

/// A message as JSON with every field printed (the one document `--format json` writes).
std::string message_json(const google::protobuf::Message& m);

/// The campaign's Export document in `format` (json, csv or journal; with `series` the jobs'
/// curves too; a journal of the jobs in `jobs` only when it is not empty), read whole from its
/// stream (it may exceed one gRPC message). Returns the stream's status; `content` is complete
/// only when it is OK.
grpc::Status read_export(v1::CampaignService::StubInterface& stub, const ChannelOptions& options,
                         std::int64_t id, const std::string& format, std::string& content,
                         bool series = false, const std::vector<std::int64_t>& jobs = {});

}  // namespace demcal::rpc
