#include "server/convert.hpp"

#include <google/protobuf/util/json_util.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string_view>

#include "core/common/error.hpp"
#include "core/doe/alias_structure.hpp"
#include "rpc/material_convert.hpp"
#include "server/plan_input.hpp"
#include "server/stored_columns.hpp"

namespace demcal::server {

std::string to_json(const google::protobuf::Message& message) {
  std::string out;
  google::protobuf::util::JsonPrintOptions o;
  o.preserve_proto_field_names = true;
  (void)google::protobuf::util::MessageToJsonString(message, &out, o);
  return out;
}

void from_json(const std::string& json, google::protobuf::Message& message) {
  google::protobuf::util::JsonParseOptions o;
  o.case_insensitive_enum_parsing = true;
  const auto status = google::protobuf::util::JsonStringToMessage(json, &message, o);
  if (!status.ok()) throw InputError("", std::string(status.message()));
}

CalibrateCall calibrate_call(const v1::CalibrateRequest& req) {
  CalibrateCall call;
  if (!req.model().empty()) call.model = polynomial_model(req.model(), "model");
  if (req.starts() < 0 || req.starts() > 1000) throw InputError("starts", "must lie in [0, 1000]");
  if (req.starts() > 0) call.starts = req.starts();
  if (req.seed()) call.seed = req.seed();
  call.verify = req.verify();
  return call;
}

std::vector<std::string> factor_legend(const CampaignPlan& plan) {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < plan.factors.size(); ++i) {
    const auto& f = plan.factors[i];
    std::string s = std::string(1, doe::factor_letter(int(i))) + "=" + f.factor.name;
    if (f.factor.name != f.path) s += " (" + f.path + ")";
    s += " [" + message_number(f.factor.low) + ", " + message_number(f.factor.high) + "]";
    if (f.factor.scale == doe::Scale::kLog) s += " log";
    out.push_back(s);
  }
  return out;
}

v1::DesignSummary design_summary(const CampaignPlan& plan, int jobs) {
  v1::DesignSummary s;
  const auto a = doe::analyse_aliasing(plan.design.coded);
  s.set_description(plan.design.description);
  s.set_runs(plan.design.runs());
  s.set_jobs(jobs);
  s.set_resolution(doe::resolution_name(a.resolution));
  s.set_generators(doe::generators_text(plan.design));
  for (const auto& w : a.defining_relation) s.add_defining_relation(doe::word_name(w));
  for (const auto& c : a.two_factor_chains) s.add_two_factor_alias_chains(doe::chain_name(c));
  for (const auto& c : a.main_effect_chains) s.add_main_effect_alias_chains(doe::chain_name(c));
  for (const auto w : a.clear_two_factor) s.add_clear_two_factor_interactions(doe::word_name(w));
  for (const auto& l : factor_legend(plan)) s.add_factor_letters(l);
  return s;
}

v1::DesignReply design_reply(const CampaignPlan& plan, int jobs) {
  v1::DesignReply r;
  *r.mutable_summary() = design_summary(plan, jobs);
  for (const auto& f : plan.factors) r.add_factors(f.path);
  const auto& d = plan.design;
  for (int row : d.rows_in_run_order()) {
    auto* run = r.add_runs();
    run->set_std_order(row + 1);
    run->set_run_order(d.run_order[std::size_t(row)]);
    run->set_point_type(doe::to_string(d.point_type[std::size_t(row)]));
    run->set_replicate(d.replicate[std::size_t(row)]);
    for (int c = 0; c < d.factors(); ++c) {
      run->add_coded(d.coded(row, c));
      run->add_natural(plan.factors[std::size_t(c)].factor.to_natural(d.coded(row, c)));
    }
  }
  return r;
}

v1::Progress progress_message(const CampaignRow& row, const Counts& c, double now) {
  v1::Progress p;
  p.set_queued(c.queued);
  p.set_leased(c.leased);
  p.set_done(c.done);
  p.set_failed(c.failed);
  p.set_cancelled(c.cancelled);
  p.set_reused(c.reused);
  p.set_total(c.total());
  const double end = row.finished > 0 ? row.finished : now;
  p.set_elapsed_seconds(std::max(0.0, end - row.created));
  // The rate of the jobs simulated since the store was opened: a result taken from an earlier
  // run (a journal's, another campaign's) took no time, and the days a campaign waited for its
  // coordinator to run again are no part of its jobs' cost.
  const double window = std::max(0.0, end - std::max(row.created, c.opening));
  const auto remaining = c.queued + c.leased;
  p.set_eta_seconds(remaining == 0 ? 0.0
                    : c.simulated_since_opening > 0
                        ? window / double(c.simulated_since_opening) * double(remaining)
                        : -1.0);
  return p;
}

v1::Campaign campaign_message(const CampaignRow& row, const Counts& counts, double now,
                              bool with_spec) {
  v1::Campaign c;
  c.set_id(row.id);
  c.set_name(row.name);
  c.set_state(row.state == "running"     ? v1::RUNNING
              : row.state == "done"      ? v1::DONE
              : row.state == "cancelled" ? v1::CANCELLED
                                         : v1::CAMPAIGN_STATE_UNSPECIFIED);
  *c.mutable_progress() = progress_message(row, counts, now);
  const auto t = static_cast<std::time_t>(row.created);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  c.set_created_at(buf);
  if (with_spec) *c.mutable_spec() = spec_from_json(row.spec_json);
  return c;
}

namespace {

/// What the job simulates, from its payload: its settings, parameters and seed; none when the
/// payload (of a job planned by an older build) cannot be read.
void add_job_run(const std::string& payload, v1::JobResult& r) {
  v1::JobSpec spec;
  try {
    spec = job_from_payload(payload);
  } catch (const std::exception&) {
    return;
  }
  *r.mutable_settings() = spec.settings();
  *r.mutable_parameters() = spec.parameters();
  r.set_seed(rpc::job_seed(spec));
}

}  // namespace

v1::JobResult job_message(const JobRow& job) {
  v1::JobResult r;
  r.set_job_id(job.id);
  r.set_std_order(job.std_order);
  r.set_test(job.test);
  r.set_kind(job.kind);
  r.set_state(job.state);
  r.set_attempt(job.attempt);
  r.set_yields(job.yields);
  if (job.metrics_json)
    for (const auto& [k, v] : metrics_from_json(*job.metrics_json)) (*r.mutable_metrics())[k] = v;
  r.set_error(job.error);
  r.set_worker(job.worker);
  r.set_wall_seconds(job.wall_seconds);
  for (const auto& [k, v] : flags_from_json(job.flags_json)) (*r.mutable_flags())[k] = v;
  *r.mutable_cost() = cost_from_json(job.cost_json);
  r.set_run_key(job.run_key.key);
  r.set_run_protocol(job.run_key.protocol);
  r.set_reused_from(job.reused_from);
  r.set_reused_journal(job.reused_journal);
  add_job_run(job.payload, r);
  return r;
}

std::string export_campaign(const CampaignRow& row, const CampaignPlan& plan,
                            const std::vector<JobRow>& jobs,
                            const std::vector<v1::CalibrationRound>& rounds,
                            const std::string& format,
                            const std::map<std::int64_t, std::string>* series) {
  const Eigen::MatrixXd y = response_matrix(plan, jobs);
  const auto& d = plan.design;
  if (format == "csv") {
    std::ostringstream s;
    s << std::setprecision(10) << "run,std_order,point_type,replicate";
    for (const auto& f : plan.factors) s << "," << f.factor.name;
    for (const auto& r : plan.responses) s << "," << r;
    s << "\n";
    for (int r : d.rows_in_run_order()) {
      s << d.run_order[std::size_t(r)] << "," << r + 1 << ","
        << doe::to_string(d.point_type[std::size_t(r)]) << "," << d.replicate[std::size_t(r)];
      for (std::size_t f = 0; f < plan.factors.size(); ++f)
        s << "," << plan.factors[f].factor.to_natural(d.coded(r, Eigen::Index(f)));
      for (Eigen::Index c = 0; c < y.cols(); ++c) {
        s << ",";
        if (std::isfinite(y(r, c)))
          s << y(r, c);
        else
          s << "NA";
      }
      s << "\n";
    }
    return s.str();
  }
  nlohmann::json j;
  j["id"] = row.id;
  j["name"] = row.name;
  j["state"] = row.state;
  j["spec"] = column_document(row.spec_json);
  j["design"] = nlohmann::json::parse(plan_to_json(plan));
  j["reused"] =
      std::count_if(jobs.begin(), jobs.end(), [](const JobRow& job) { return job.reused(); });
  for (const auto& job : jobs) {
    nlohmann::json o = {{"job_id", job.id},
                        {"std_order", job.std_order},
                        {"test", job.test},
                        {"kind", job.kind},
                        {"state", job.state},
                        {"attempt", job.attempt},
                        {"error", job.error},
                        {"worker", job.worker},
                        {"wall_seconds", job.wall_seconds},
                        {"run_key", job.run_key.key},
                        {"reused_from", job.reused_from},
                        {"reused_journal", job.reused_journal}};
    if (job.metrics_json) {
      o["metrics"] = column_document(*job.metrics_json);
      o["flags"] = column_document(job.flags_json);
      o["cost"] = column_document(job.cost_json);
    }
    if (series) {
      const auto it = series->find(job.id);
      o["series"] = it == series->end() ? nlohmann::json::object() : column_document(it->second);
    }
    j["jobs"].push_back(o);
  }
  j["calibration_rounds"] = nlohmann::json::array();
  for (const auto& r : rounds) j["calibration_rounds"].push_back(nlohmann::json::parse(to_json(r)));
  return j.dump(2);
}

}  // namespace demcal::server
