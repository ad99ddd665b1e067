#include "rpc/protocols.hpp"

#include "core/lab/protocol.hpp"
#include "core/model/catalog.hpp"

namespace demcal::rpc {

v1::LeaseRequest lease_request(const std::string& worker) {
  v1::LeaseRequest request;
  request.set_worker(worker);
  for (const lab::LabTestInfo& info : lab::lab_catalog())
    (*request.mutable_protocols())[info.name] = lab::protocol_version(info.name);
  return request;
}

std::string protocol_mismatch(const google::protobuf::Map<std::string, std::int32_t>& theirs) {
  constexpr const char* advice = ": run a worker of the coordinator's build";
  for (const lab::LabTestInfo& info : lab::lab_catalog()) {
    const int ours = lab::protocol_version(info.name);
    const auto it = theirs.find(info.name);
    if (it == theirs.end())
      return "protocols: the worker names no protocol version for lab test " + info.name +
             " (this coordinator runs " + std::to_string(ours) + ")" + advice;
    if (it->second != ours)
      return "protocols." + info.name + ": the worker simulates it under lab protocol version " +
             std::to_string(it->second) + ", this coordinator keys its runs under " +
             std::to_string(ours) + advice;
  }
  return {};
}

}  // namespace demcal::rpc
