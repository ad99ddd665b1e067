// Fuzzes the coordinator's Submit (CampaignServiceImpl::Submit, in process, no network) on a
// store, with the store-backed oracle of submit_oracle.hpp: the bytes of a SubmitRequest as gRPC
// would hand them over; a refused request leaves the store as it was, an accepted one is stored
// as sent with jobs every worker would run, and no answer is INTERNAL. A broken expectation
// aborts with its description (a finding).
#include <spdlog/spdlog.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "demcal/v1/campaign.pb.h"
#include "tests/fuzz/submit_oracle.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static demcal::test::SubmitOracle* oracle = [] {
    spdlog::set_level(spdlog::level::off);
    return new demcal::test::SubmitOracle();
  }();
  demcal::v1::SubmitRequest request;
  if (!request.ParseFromArray(data, static_cast<int>(size))) return 0;  // gRPC would refuse it
  const auto outcome = oracle->submit(request);
  if (!outcome.broken.empty()) {
    std::fprintf(stderr, "submit oracle: %s\n", outcome.broken.c_str());
    std::abort();
  }
  return 0;
}
