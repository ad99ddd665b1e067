// Fuzzes what the coordinator's Submit does with a request before anything is stored
// (CampaignServiceImpl::Submit in server/services.cpp): the bytes of a SubmitRequest as gRPC
// would hand them over, parsed, validated and planned (plan_campaign: factor paths, bounds,
// tests, settings, design, limits, jobs), then turned into what the store and the reply get
// (the spec and plan as JSON, the design summary). In process, no network, no store. Every
// input that parses must end in a plan or an InputError (INVALID_ARGUMENT naming the field);
// any other exception would reach the client as INTERNAL and is a finding.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/common/error.hpp"
#include "demcal/v1/campaign.pb.h"
#include "server/convert.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  demcal::v1::SubmitRequest request;
  if (!request.ParseFromArray(data, static_cast<int>(size))) return 0;  // gRPC would refuse it
  try {
    std::vector<demcal::server::NewJob> jobs;
    const auto plan = demcal::server::plan_campaign(request.spec(), jobs);
    (void)demcal::server::to_json(request.spec());
    (void)demcal::server::plan_to_json(plan);
    (void)demcal::server::design_summary(plan, static_cast<int>(jobs.size()));
  } catch (const demcal::InputError&) {
  }
  return 0;
}
