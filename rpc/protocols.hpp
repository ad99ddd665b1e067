#pragma once
// The lab protocol versions (core/lab/protocol.hpp) as a worker names them with each lease and
// a coordinator checks them: a worker of another build would store its results under run keys
// that claim the coordinator's protocol, so a coordinator leases only to workers whose versions
// are its own.
#include <cstdint>
#include <string>

#include "demcal/v1/worker.pb.h"

namespace demcal::rpc {

/// A lease request of `worker` naming this build's protocol version of every lab test.
v1::LeaseRequest lease_request(const std::string& worker);

/// A worker's versions against this build's, for every test of the catalogue; "" when they are
/// the same, else the first test whose version is missing or differs, with both versions.
std::string protocol_mismatch(const google::protobuf::Map<std::string, std::int32_t>& theirs);

}  // namespace demcal::rpc
