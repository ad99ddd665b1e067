#include "tests/fuzz/submit_oracle.hpp"

#include <google/protobuf/util/message_differencer.h>
#include <grpcpp/server_context.h>

#include <atomic>

#include "core/common/error.hpp"
#include "core/model/catalog.hpp"
#include "rpc/material_convert.hpp"
#include "server/convert.hpp"
#include "server/plan.hpp"
#include "server/services.hpp"
#include "server/store.hpp"

namespace demcal::test {

namespace {

/// Accepted campaigns a store keeps before the oracle starts a fresh one (the job bounds
/// would refuse every Submit of a store that only grows).
constexpr int kCampaignsPerStore = 200;

/// Why a stored job would be refused by its worker as invalid input (empty: it would run).
std::string refusal_of(const server::JobRow& row) {
  v1::JobSpec job;
  try {
    server::from_json(row.payload, job);
    lab::admit_lab_test(job.test(), rpc::job_material(job), rpc::to_settings(job.settings()));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

/// What differs between the spec sent and the spec stored (empty: nothing).
std::string differences(const v1::CampaignSpec& sent, const v1::CampaignSpec& stored) {
  google::protobuf::util::MessageDifferencer d;
  std::string report;
  d.ReportDifferencesToString(&report);
  d.Compare(sent, stored);
  return report.substr(0, 2000);
}

}  // namespace

struct SubmitOracle::State {
  std::unique_ptr<server::Store> store;
  std::unique_ptr<server::CampaignServiceImpl> service;
  std::atomic<bool> stopping{false};
  int campaigns = 0;

  void fresh() {
    service.reset();
    store = std::make_unique<server::Store>(":memory:");
    service =
        std::make_unique<server::CampaignServiceImpl>(*store, server::ServiceConfig{}, stopping);
    campaigns = 0;
  }
};

SubmitOracle::SubmitOracle() : state_(std::make_unique<State>()) {
  state_->fresh();
}
SubmitOracle::~SubmitOracle() = default;

SubmitOracle::Outcome SubmitOracle::submit(const v1::SubmitRequest& request) {
  if (state_->campaigns >= kCampaignsPerStore) state_->fresh();
  server::Store& store = *state_->store;
  const auto before = store.campaigns().size();
  const auto unfinished = store.unfinished_jobs();
  grpc::ServerContext context;
  v1::SubmitReply reply;
  const grpc::Status status = state_->service->Submit(&context, &request, &reply);
  Outcome out;
  if (!status.ok()) {
    if (status.error_code() != grpc::StatusCode::INVALID_ARGUMENT &&
        status.error_code() != grpc::StatusCode::RESOURCE_EXHAUSTED)
      out.broken = "Submit answered code " + std::to_string(status.error_code()) + ": " +
                   status.error_message();
    else if (status.error_message().empty())
      out.broken = "a refusal without a message";
    else if (store.campaigns().size() != before || store.unfinished_jobs() != unfinished)
      out.broken = "a refused Submit changed the store: " + status.error_message();
    return out;
  }
  out.accepted = true;
  ++state_->campaigns;
  const auto row = store.campaign(reply.id());
  if (!row) return {true, "campaign " + std::to_string(reply.id()) + " is not in the store"};
  if (store.campaigns().size() != before + 1) return {true, "not exactly one campaign added"};
  v1::CampaignSpec stored;
  server::from_json(row->spec_json, stored);
  if (const std::string d = differences(request.spec(), stored); !d.empty())
    return {true, "the stored spec differs from the one sent: " + d};
  if (server::plan_to_json(server::stored_plan(*row)) != row->design_json)
    return {true, "the stored plan does not read back as itself"};
  const auto jobs = store.jobs(row->id);
  if (static_cast<int>(jobs.size()) != reply.design().jobs())
    return {true, std::to_string(jobs.size()) + " jobs stored, the reply says " +
                      std::to_string(reply.design().jobs())};
  for (const auto& job : jobs) {
    if (job.state != "queued") return {true, "job " + std::to_string(job.id) + " is " + job.state};
    if (const std::string why = refusal_of(job); !why.empty())
      return {true,
              "job " + std::to_string(job.id) + " stored, its worker would refuse it: " + why};
  }
  return out;
}

}  // namespace demcal::test
