#pragma once
// The coordinator's Submit (CampaignServiceImpl::Submit, in process, no network) on a store of
// its own, with an oracle over what the store holds afterwards:
//   - the answer is OK, INVALID_ARGUMENT (naming a field) or RESOURCE_EXHAUSTED, never another
//     code (an unexpected exception reaches the client as INTERNAL);
//   - a refused request leaves the store as it was (no campaign, no job);
//   - an accepted one is stored as sent: the spec read back from the store equals the request's,
//     its plan reads back, it has as many queued jobs as the reply says, and every job's payload
//     is one its lab test admits (core/model/catalog.hpp): a worker would run it, not refuse it
//     as invalid.
// Used by the libFuzzer harness fuzz_submit and by a test that runs in CI (service_submit_oracle).
#include <memory>
#include <string>

#include "demcal/v1/campaign.pb.h"

namespace demcal::test {

class SubmitOracle {
 public:
  SubmitOracle();
  ~SubmitOracle();
  SubmitOracle(const SubmitOracle&) = delete;
  SubmitOracle& operator=(const SubmitOracle&) = delete;

  struct Outcome {
    bool accepted = false;
    std::string broken;  ///< the expectation the store or the answer broke; empty: all held
  };
  /// Submits `request` and checks the store against it.
  Outcome submit(const v1::SubmitRequest& request);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace demcal::test
