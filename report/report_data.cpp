#include "report/report_data.hpp"

#include <string>

#include "rpc/job_kind.hpp"
#include "rpc/replies.hpp"

namespace demcal::report {
namespace {

using nlohmann::json;

constexpr double kDeadlineSeconds = 300;

json as_json(const google::protobuf::Message& m) {
  return json::parse(rpc::message_json(m));
}

/// A reply the report cannot do without: a failure is thrown with its status.
template <class Call>
void required(const Call& call, const std::string& what) {
  const grpc::Status s = call();
  if (!s.ok()) throw ReadError(s.error_code(), what + ": " + s.error_message());
}

/// A reply the report shows when the campaign has it: null and a note otherwise.
template <class Reply, class Call>
json optional(const Call& call, const std::string& what, json& notes) {
  Reply reply;
  const grpc::Status s = call(reply);
  if (s.ok()) return as_json(reply);
  if (s.error_code() == grpc::StatusCode::UNAUTHENTICATED)
    throw ReadError(s.error_code(), what + ": " + s.error_message());
  notes[what] = s.error_message();
  return nullptr;
}

v1::Campaign read_campaign(v1::CampaignService::StubInterface& stub, const rpc::ChannelOptions& ch,
                           std::int64_t id) {
  v1::GetRequest get;
  get.set_id(id);
  v1::Campaign campaign;
  required([&] { return stub.Get(rpc::make_context(ch, 60).get(), get, &campaign); }, "campaign");
  return campaign;
}

json read_design(v1::CampaignService::StubInterface& stub, const rpc::ChannelOptions& ch,
                 std::int64_t id) {
  v1::GetRequest get;
  get.set_id(id);
  v1::DesignReply design;
  required([&] { return stub.GetDesign(rpc::make_context(ch, 60).get(), get, &design); }, "design");
  return as_json(design);
}

/// The Export reply's content is itself the JSON document `demcal export --format json --series`
/// prints.
json read_export(v1::CampaignService::StubInterface& stub, const rpc::ChannelOptions& ch,
                 std::int64_t id) {
  std::string content;
  required([&] { return rpc::read_export(stub, ch, id, "json", content, true); }, "export");
  return json::parse(content);
}

/// The request `demcal effects ID --format json` sends: model 2fi, alpha 0.05 (the defaults).
json read_effects(v1::CampaignService::StubInterface& stub, const rpc::ChannelOptions& ch,
                  std::int64_t id, json& notes) {
  v1::EffectsRequest req;
  req.set_id(id);
  return optional<v1::EffectsReply>(
      [&](v1::EffectsReply& r) {
        return stub.GetEffects(rpc::make_context(ch, kDeadlineSeconds).get(), req, &r);
      },
      "effects", notes);
}

/// Without verify: the proposal and the rounds so far, nothing queued.
json read_calibration(v1::CampaignService::StubInterface& stub, const rpc::ChannelOptions& ch,
                      std::int64_t id, json& notes) {
  v1::CalibrateRequest req;
  req.set_id(id);
  return optional<v1::CalibrateReply>(
      [&](v1::CalibrateReply& r) {
        return stub.Calibrate(rpc::make_context(ch, kDeadlineSeconds).get(), req, &r);
      },
      "calibration", notes);
}

bool has_diagnosis_jobs(const json& exported) {
  for (const auto& j : exported.value("jobs", json::array()))
    if (job_kind::is_diagnosis(j.value("kind", ""))) return true;
  return false;
}

json read_diagnosis(v1::CampaignService::StubInterface& stub, const rpc::ChannelOptions& ch,
                    std::int64_t id, json& notes) {
  v1::DiagnoseRequest req;
  req.set_id(id);
  req.set_read_only(true);
  return optional<v1::DiagnoseReply>(
      [&](v1::DiagnoseReply& r) {
        return stub.Diagnose(rpc::make_context(ch, kDeadlineSeconds).get(), req, &r);
      },
      "diagnosis", notes);
}

}  // namespace

json report_data(v1::CampaignService::StubInterface& stub, const rpc::ChannelOptions& ch,
                 std::int64_t id) {
  json doc = {{"id", id}, {"notes", json::object()}};
  json& notes = doc["notes"];
  const v1::Campaign campaign = read_campaign(stub, ch, id);
  doc["campaign"] = as_json(campaign);
  doc["design"] = read_design(stub, ch, id);
  doc["export"] = read_export(stub, ch, id);
  doc["effects"] = read_effects(stub, ch, id, notes);
  doc["calibration"] = nullptr;
  if (campaign.spec().measurements_size() == 0)
    notes["calibration"] = "no measurements in the spec: nothing to calibrate against";
  else
    doc["calibration"] = read_calibration(stub, ch, id, notes);
  doc["diagnosis"] = nullptr;
  if (has_diagnosis_jobs(doc["export"]))
    doc["diagnosis"] = read_diagnosis(stub, ch, id, notes);
  else
    notes["diagnosis"] = "not diagnosed: `demcal diagnose " + std::to_string(id) + "` starts it";
  return doc;
}

json campaign_list(v1::CampaignService::StubInterface& stub, const rpc::ChannelOptions& ch) {
  v1::ListReply list;
  required([&] { return stub.List(rpc::make_context(ch, 60).get(), {}, &list); }, "list");
  json out = as_json(list);
  // The specs are the bulk of a List reply and the index shows names and progress only.
  for (auto& c : out["campaigns"]) c.erase("spec");
  return out;
}

}  // namespace demcal::report
