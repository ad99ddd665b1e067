#include "server/services.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <thread>

#include "core/common/error.hpp"
#include "core/lab/protocol.hpp"
#include "core/model/catalog.hpp"
#include "rpc/effects_convert.hpp"
#include "rpc/protocols.hpp"
#include "rpc/result_check.hpp"
#include "server/admission.hpp"
#include "server/analysis.hpp"
#include "server/auth.hpp"
#include "server/calibration.hpp"
#include "server/convert.hpp"
#include "server/diagnosis.hpp"
#include "server/journal.hpp"
#include "server/limits.hpp"

namespace demcal::server {

double now_seconds() {
  return wall_seconds();
}

namespace {

grpc::Status invalid(const InputError& e) {
  return {grpc::StatusCode::INVALID_ARGUMENT, e.what()};
}
grpc::Status not_found(std::int64_t id) {
  return {grpc::StatusCode::NOT_FOUND, "no campaign " + std::to_string(id)};
}
/// The answer to a call naming a lease that is not the caller's current one.
grpc::Status lease_refused(LeaseAnswer answer, std::int64_t job_id, int attempt,
                           const std::string& worker, const std::string& consequence) {
  const std::string lease = "job " + std::to_string(job_id) + " attempt " + std::to_string(attempt);
  if (answer == LeaseAnswer::kNotHolder)
    return {grpc::StatusCode::PERMISSION_DENIED,
            lease + " is leased to another worker than '" + worker + "'" + consequence};
  return {grpc::StatusCode::FAILED_PRECONDITION, lease + " is not the current lease" + consequence};
}

/// A cancelled campaign runs nothing more: work that would queue jobs on it is refused (the
/// jobs would never be leased and the caller would wait for them forever).
grpc::Status refuse_if_cancelled(const CampaignRow& row, const std::string& what) {
  if (row.state != "cancelled") return grpc::Status::OK;
  return {grpc::StatusCode::FAILED_PRECONDITION,
          "campaign " + std::to_string(row.id) + " is cancelled: " + what +
              " would queue jobs that never run (submit the spec again)"};
}

/// Streams `content` in pieces of at most kExportPiece bytes (one empty piece for empty content).
grpc::Status write_in_pieces(const std::string& content, const std::string& format,
                             grpc::ServerWriter<v1::ExportReply>& writer,
                             const grpc::ServerContext& ctx) {
  constexpr std::size_t kExportPiece = std::size_t(1) << 20;
  std::size_t at = 0;
  do {
    v1::ExportReply piece;
    piece.set_format(format);
    piece.set_content(content.substr(at, kExportPiece));
    if (ctx.IsCancelled() || !writer.Write(piece))
      return {grpc::StatusCode::CANCELLED, "export: the client went away"};
    at += kExportPiece;
  } while (at < content.size());
  return grpc::Status::OK;
}

grpc::Status internal(const std::exception& e) {
  spdlog::error("internal error: {}", e.what());
  return {grpc::StatusCode::INTERNAL, e.what()};
}

/// The authorization check (auth.hpp) and its log line, then the request's size: at most
/// `max_bytes` (limits.hpp). Every handler starts with it. gRPC's server has one receive limit
/// for all methods, the checkpoint's; the smaller limits of the others are checked here, before
/// the request is read further or stored.
grpc::Status admit(const grpc::ServerContext& ctx, const Tokens& tokens, Caller caller,
                   const google::protobuf::Message& request,
                   std::size_t max_bytes = kMaxRequestBytes) {
  auto s = authorize(ctx, tokens, caller);
  if (!s.ok()) {
    spdlog::warn("{} call from {}: {}", caller == Caller::kWorker ? "worker" : "client", ctx.peer(),
                 s.error_message());
    return s;
  }
  if (const std::string e =
          request_size_error(request.ByteSizeLong(), max_bytes, request.GetDescriptor()->name());
      !e.empty()) {
    spdlog::warn("call from {} refused: {}", ctx.peer(), e);
    return {grpc::StatusCode::INVALID_ARGUMENT, e};
  }
  return grpc::Status::OK;
}

/// A worker's id and failure reason within their bounds (limits.hpp); "" when they are.
std::string worker_text_error(const std::string& worker, const std::string& reason = "") {
  if (worker.size() > kMaxWorkerId)
    return fmt::format("worker: {} bytes, at most {}", worker.size(), kMaxWorkerId);
  if (reason.size() > kMaxReason)
    return fmt::format("reason: {} bytes, at most {}", reason.size(), kMaxReason);
  return {};
}

/// The metric values of a result within kMaxMetricMagnitude (finite is checked before); "" when
/// they are.
std::string metrics_error(const google::protobuf::Map<std::string, double>& metrics) {
  for (const auto& [name, value] : metrics)
    if (std::abs(value) > kMaxMetricMagnitude)
      return fmt::format("metrics.{}: {:g} is beyond +-{:g}", name, value, kMaxMetricMagnitude);
  return {};
}

/// The names of a result's metrics against the lab test `test` of its job; "" when the test
/// reports each.
std::string metric_names_error(const google::protobuf::Map<std::string, double>& metrics,
                               const std::string& test) {
  const lab::LabTestInfo& info = lab::find_lab_info(test);
  for (const auto& [name, value] : metrics)
    if (!lab::reports_metric(info, name))
      return fmt::format("metrics.{}: not a metric the {} test reports", echo(name), test);
  return {};
}

doe::ModelKind model_kind(const std::string& text, const std::string& where) {
  return text.empty() ? doe::ModelKind::kTwoFactor : doe::parse_model_kind(text, where);
}

}  // namespace

void CampaignServiceImpl::wait_watch_interval(const grpc::ServerContext& ctx, double seconds) {
  // In slices: a client gone or the coordinator stopping ends the wait within one.
  using Clock = std::chrono::steady_clock;
  constexpr Clock::duration kSlice = std::chrono::milliseconds(50);
  const Clock::time_point until = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                                     std::chrono::duration<double>(seconds));
  while (!ctx.IsCancelled() && !stopping_ && Clock::now() < until)
    std::this_thread::sleep_for(std::min(kSlice, until - Clock::now()));
}

std::optional<WatchStreams::Slot> WatchStreams::open(const std::string& client) {
  std::lock_guard lock(mutex_);
  int& open = open_[client];
  if (open >= kMaxWatchStreamsPerClient) return std::nullopt;
  ++open;
  return std::optional<Slot>(std::in_place, *this, client);
}

void WatchStreams::close(const std::string& client) {
  std::lock_guard lock(mutex_);
  if (--open_[client] == 0) open_.erase(client);
}

WatchReads::Read WatchReads::read(std::int64_t campaign_id) {
  // Readers of one campaign wait for the one read under way instead of each reading.
  std::lock_guard lock(mutex_);
  const double now = steady_seconds();
  const auto it = entries_.find(campaign_id);
  if (it != entries_.end() && now - it->second.at <= kMinWatchInterval / 2) return it->second.read;
  Read r{store_.campaign(campaign_id), {}};
  if (!r.row) {  // nothing kept for ids that name no campaign
    if (it != entries_.end()) entries_.erase(it);
    return r;
  }
  r.counts = store_.counts(campaign_id);
  entries_[campaign_id] = {r, now};
  return r;
}

grpc::Status CampaignServiceImpl::check_job_bounds(const std::string& owner, std::size_t jobs) {
  const auto refuse = [&](long unfinished, const std::string& whose, const std::string& flag,
                          long max) {
    const std::string e = fmt::format(
        "{} jobs more would make {} unfinished (queued or leased) {}, beyond the coordinator's "
        "{} {}: wait for jobs to finish or cancel a campaign",
        jobs, unfinished + long(jobs), whose, flag, max);
    spdlog::warn("submit refused: {}", e);
    return grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED, e);
  };
  if (const long own = store_.unfinished_jobs(owner);
      own + long(jobs) > config_.max_jobs_per_client)
    return refuse(own, "of this token's campaigns", "--max-jobs-per-client",
                  config_.max_jobs_per_client);
  if (const long all = store_.unfinished_jobs(); all + long(jobs) > config_.max_jobs)
    return refuse(all, "in the store", "--max-jobs", config_.max_jobs);
  return grpc::Status::OK;
}

grpc::Status CampaignServiceImpl::Submit(grpc::ServerContext* ctx, const v1::SubmitRequest* req,
                                         v1::SubmitReply* reply) {
  if (auto s = admit(*ctx, config_.tokens, Caller::kClient, *req, kMaxSpecBytes); !s.ok()) return s;
  try {
    std::vector<NewJob> jobs;
    const CampaignPlan plan = plan_campaign(req->spec(), jobs);
    const std::string owner = token_name(*ctx, config_.tokens);
    std::lock_guard lock(submit_mutex_);
    if (auto s = check_job_bounds(owner, jobs.size()); !s.ok()) return s;
    const auto id = store_.create_campaign(req->spec().name(), to_json(req->spec()),
                                           plan_to_json(plan), jobs, now_seconds(), owner);
    reply->set_id(id);
    *reply->mutable_design() = design_summary(plan, int(jobs.size()));
    spdlog::info("campaign {} '{}' submitted: {} runs, {} jobs", id, req->spec().name(),
                 plan.design.runs(), jobs.size());
    return grpc::Status::OK;
  } catch (const InputError& e) {
    spdlog::info("submit rejected: {}", e.what());
    return invalid(e);
  } catch (const std::exception& e) {
    return internal(e);
  }
}

grpc::Status CampaignServiceImpl::Get(grpc::ServerContext* ctx, const v1::GetRequest* req,
                                      v1::Campaign* reply) {
  if (auto s = admit(*ctx, config_.tokens, Caller::kClient, *req); !s.ok()) return s;
  const auto row = store_.campaign(req->id());
  if (!row) return not_found(req->id());
  try {
    *reply = campaign_message(*row, store_.counts(row->id), now_seconds(), true);
    for (auto& r : calibration_rounds(store_, *row)) *reply->add_calibration_rounds() = r;
    const CampaignPlan plan = stored_plan(*row);
    if (plan.fidelity) *reply->mutable_fidelity_cost() = fidelity_cost(plan, store_.jobs(row->id));
  } catch (const std::exception& e) {
    return internal(e);
  }
  return grpc::Status::OK;
}

grpc::Status CampaignServiceImpl::List(grpc::ServerContext* ctx, const v1::ListRequest* req,
                                       v1::ListReply* reply) {
  if (auto s = admit(*ctx, config_.tokens, Caller::kClient, *req); !s.ok()) return s;
  const double now = now_seconds();
  for (const auto& row : store_.campaigns())
    *reply->add_campaigns() = campaign_message(row, store_.counts(row.id), now, false);
  return grpc::Status::OK;
}

grpc::Status CampaignServiceImpl::Cancel(grpc::ServerContext* ctx, const v1::CancelRequest* req,
                                         v1::Campaign* reply) {
  if (auto s = admit(*ctx, config_.tokens, Caller::kClient, *req); !s.ok()) return s;
  if (!store_.cancel(req->id(), now_seconds())) {
    const auto row = store_.campaign(req->id());
    if (!row) return not_found(req->id());
    return {grpc::StatusCode::FAILED_PRECONDITION,
            "campaign " + std::to_string(req->id()) + " is " + row->state +
                ": only a running campaign can be cancelled"};
  }
  spdlog::info("campaign {} cancelled", req->id());
  const auto row = store_.campaign(req->id());
  *reply = campaign_message(*row, store_.counts(row->id), now_seconds(), false);
  return grpc::Status::OK;
}

grpc::Status CampaignServiceImpl::GiveUp(grpc::ServerContext* ctx, const v1::GiveUpRequest* req,
                                         v1::GiveUpReply* reply) {
  if (auto s = admit(*ctx, config_.tokens, Caller::kClient, *req); !s.ok()) return s;
  if (req->reason().empty() || req->reason().size() > kMaxReason)
    return {grpc::StatusCode::INVALID_ARGUMENT,
            fmt::format("reason: {} bytes, must be 1-{} (why the job is given up)",
                        req->reason().size(), kMaxReason)};
  if (!store_.campaign(req->campaign_id())) return not_found(req->campaign_id());
  const std::string job = "job " + std::to_string(req->job_id());
  const auto released = store_.give_up(req->campaign_id(), req->job_id(), req->reason());
  if (!released) {
    const auto row = store_.job(req->job_id());
    if (!row || row->campaign_id != req->campaign_id())
      return {grpc::StatusCode::NOT_FOUND,
              "campaign " + std::to_string(req->campaign_id()) + " has no " + job};
    return {grpc::StatusCode::FAILED_PRECONDITION,
            job + " is " + row->state + ": only a queued or running job can be given up"};
  }
  spdlog::info("campaign {}: {} given up: {}", req->campaign_id(), job, req->reason());
  *reply->mutable_job() = job_message(*store_.job(req->job_id()));
  for (const auto id : *released) *reply->add_released() = job_message(*store_.job(id));
  return grpc::Status::OK;
}

grpc::Status CampaignServiceImpl::Watch(grpc::ServerContext* ctx, const v1::WatchRequest* req,
                                        grpc::ServerWriter<v1::Progress>* writer) {
  if (auto s = admit(*ctx, config_.tokens, Caller::kClient, *req); !s.ok()) return s;
  const double interval = req->interval_seconds() != 0.0 ? req->interval_seconds() : 0.5;
  if (!(interval >= kMinWatchInterval && interval <= config_.max_watch_interval))
    return {grpc::StatusCode::INVALID_ARGUMENT,
            fmt::format("interval_seconds: must lie in [{}, {}] (or 0 for 0.5)", kMinWatchInterval,
                        config_.max_watch_interval)};
  const auto slot = watch_streams_.open(token_name(*ctx, config_.tokens));
  if (!slot)
    return {grpc::StatusCode::RESOURCE_EXHAUSTED,
            fmt::format("Watch: this token has {} streams open, at most {} (close one)",
                        kMaxWatchStreamsPerClient, kMaxWatchStreamsPerClient)};
  std::string last;
  double last_sent = 0.0;
  while (!ctx->IsCancelled() && !stopping_) {
    const auto [row, counts] = watch_reads_.read(req->id());
    if (!row) return not_found(req->id());
    const double now = now_seconds();
    const v1::Progress p = progress_message(*row, counts, now);
    v1::Progress key = p;
    key.clear_elapsed_seconds();
    key.clear_eta_seconds();
    const std::string k = key.SerializeAsString();
    if (k != last || now - last_sent > 5.0) {
      if (!writer->Write(p)) return grpc::Status::OK;
      last = k;
      last_sent = now;
    }
    if (row->state != "running") return grpc::Status::OK;
    wait_watch_interval(*ctx, interval);
  }
  return {grpc::StatusCode::CANCELLED, "watch ended"};
}

grpc::Status CampaignServiceImpl::GetDesign(grpc::ServerContext* ctx, const v1::GetRequest* req,
                                            v1::DesignReply* reply) {
  if (auto s = admit(*ctx, config_.tokens, Caller::kClient, *req); !s.ok()) return s;
  const auto row = store_.campaign(req->id());
  if (!row) return not_found(req->id());
  *reply = design_reply(stored_plan(*row), int(store_.counts(row->id).total()));
  return grpc::Status::OK;
}

grpc::Status CampaignServiceImpl::GetResults(grpc::ServerContext* ctx, const v1::GetRequest* req,
                                             v1::ResultsReply* reply) {
  if (auto s = admit(*ctx, config_.tokens, Caller::kClient, *req); !s.ok()) return s;
  if (!store_.campaign(req->id())) return not_found(req->id());
  try {
    const auto marks = store_.checkpoint_marks(req->id());
    for (const auto& job : store_.jobs(req->id())) {
      auto* j = reply->add_jobs();
      *j = job_message(job);
      if (const auto m = marks.find(job.id); m != marks.end()) {
        j->set_checkpoint_stage(m->second.stage);
        j->set_checkpoint_saved(m->second.stored);
        j->set_checkpoint_simulated_seconds(m->second.clock.simulated_seconds);
        j->set_checkpoint_steps(m->second.clock.steps);
      }
    }
  } catch (const std::exception& e) {
    return internal(e);
  }
  return grpc::Status::OK;
}

grpc::Status CampaignServiceImpl::GetEffects(grpc::ServerContext* ctx,
                                             const v1::EffectsRequest* req,
                                             v1::EffectsReply* reply) {
  if (auto s = admit(*ctx, config_.tokens, Caller::kClient, *req); !s.ok()) return s;
  const auto row = store_.campaign(req->id());
  if (!row) return not_found(req->id());
  try {
    const CampaignPlan plan = stored_plan(*row);
    const auto jobs = store_.jobs(row->id);
    const Eigen::MatrixXd y = response_matrix(plan, jobs);
    const auto flagged = flagged_runs(jobs);
    const auto kind = model_kind(req->model(), "model");
    const double alpha = req->alpha() != 0.0 ? req->alpha() : 0.05;
    if (!(alpha > 0.0 && alpha < 0.5)) throw InputError("alpha", "must lie in (0, 0.5)");
    for (const auto& l : factor_legend(plan)) reply->add_factor_letters(l);
    for (std::size_t c = 0; c < plan.responses.size(); ++c) {
      const Eigen::VectorXd col = y.col(Eigen::Index(c));
      if (!col.array().isFinite().any()) {
        auto* m = reply->add_metrics();
        m->set_metric(plan.responses[c]);
        m->set_runs_total(plan.design.runs());
        m->add_notes("no results yet");
        continue;
      }
      try {
        v1::MetricEffects effects =
            rpc::effects_message(plan.responses[c], analyse(plan, col, kind, alpha));
        auto* m = reply->add_metrics();
        *m = std::move(effects);
        if (const auto f = flagged.find(plan.responses[c]); f != flagged.end())
          m->add_notes(flagged_runs_note(f->second));
      } catch (const InputError& e) {
        auto* m = reply->add_metrics();
        m->set_metric(plan.responses[c]);
        m->add_notes(std::string("not analysable yet: ") + e.what());
      }
    }
    return grpc::Status::OK;
  } catch (const InputError& e) {
    return invalid(e);
  } catch (const std::exception& e) {
    return internal(e);
  }
}

grpc::Status CampaignServiceImpl::Calibrate(grpc::ServerContext* ctx,
                                            const v1::CalibrateRequest* req,
                                            v1::CalibrateReply* reply) {
  if (auto s = admit(*ctx, config_.tokens, Caller::kClient, *req); !s.ok()) return s;
  if (req->starts() < 0 || req->starts() > config_.max_starts)
    return {grpc::StatusCode::INVALID_ARGUMENT,
            "starts: must lie in [0, " + std::to_string(config_.max_starts) + "] (0 for 16)"};
  const auto row = store_.campaign(req->id());
  if (!row) return not_found(req->id());
  if (req->verify())
    if (auto s = refuse_if_cancelled(*row, "calibrate --verify"); !s.ok()) return s;
  try {
    // One calibration step at a time: two concurrent calls must not queue the same round twice.
    std::lock_guard lock(calibrate_mutex_);
    // A call whose client has gone (deadline, Ctrl-C) or that shutdown waits for stops at the
    // next start of its minimisations instead of holding the lock for the next caller.
    *reply = calibrate_campaign(store_, *row, calibrate_call(*req), [ctx, this] {
      if (ctx->IsCancelled()) throw calib::Interrupted("its client went away");
      if (stopping_) throw calib::Interrupted("the coordinator is stopping");
    });
    return grpc::Status::OK;
  } catch (const calib::Interrupted& e) {
    spdlog::info("calibrate of campaign {} abandoned: {}", req->id(), e.what());
    return {grpc::StatusCode::CANCELLED, std::string("calibration abandoned: ") + e.what()};
  } catch (const InputError& e) {
    // A bad request field is invalid; a campaign not ready to calibrate is a precondition.
    const std::string where = e.where();
    if (where == "model" || where == "starts") return invalid(e);
    return {grpc::StatusCode::FAILED_PRECONDITION, e.what()};
  } catch (const std::exception& e) {
    return internal(e);
  }
}

grpc::Status CampaignServiceImpl::Diagnose(grpc::ServerContext* ctx, const v1::DiagnoseRequest* req,
                                           v1::DiagnoseReply* reply) {
  if (auto s = admit(*ctx, config_.tokens, Caller::kClient, *req); !s.ok()) return s;
  const auto row = store_.campaign(req->id());
  if (!row) return not_found(req->id());
  if (auto s = refuse_if_cancelled(*row, "diagnose"); !s.ok()) return s;
  if (req->rounds() != 0 && req->read_only())
    return {grpc::StatusCode::INVALID_ARGUMENT,
            "rounds: not with read_only (a look changes nothing)"};
  try {
    // One diagnosis step at a time: two concurrent calls must not queue the same runs twice.
    std::lock_guard lock(diagnose_mutex_);
    const CampaignRow stored =
        req->rounds() != 0 ? with_diagnosis_rounds(store_, *row, req->rounds()) : *row;
    *reply = diagnose_campaign(store_, stored, req->seed(), req->read_only());
    return grpc::Status::OK;
  } catch (const InputError& e) {
    // A bad request field is invalid; a campaign that cannot be diagnosed is a precondition.
    if (e.where() == "rounds") return invalid(e);
    return {grpc::StatusCode::FAILED_PRECONDITION, e.what()};
  } catch (const std::exception& e) {
    return internal(e);
  }
}

grpc::Status CampaignServiceImpl::Export(grpc::ServerContext* ctx, const v1::ExportRequest* req,
                                         grpc::ServerWriter<v1::ExportReply>* writer) {
  if (auto s = admit(*ctx, config_.tokens, Caller::kClient, *req); !s.ok()) return s;
  const auto row = store_.campaign(req->id());
  if (!row) return not_found(req->id());
  const std::string format = req->format().empty() ? "json" : req->format();
  if (format != "json" && format != "csv" && format != "journal")
    return {grpc::StatusCode::INVALID_ARGUMENT, "format: expected csv, json or journal"};
  if (req->series() && format != "json")
    return {grpc::StatusCode::INVALID_ARGUMENT, "series: only with format json"};
  if (req->jobs_size() > 0 && format != "journal")
    return {grpc::StatusCode::INVALID_ARGUMENT, "jobs: only with format journal"};
  std::string content;
  try {
    if (format == "journal") {
      content = export_journal(*row, store_.jobs(row->id), store_.series(row->id),
                               {req->jobs().begin(), req->jobs().end()});
    } else {
      const auto series =
          req->series() ? store_.series(row->id) : std::map<std::int64_t, std::string>{};
      content = export_campaign(*row, stored_plan(*row), store_.jobs(row->id),
                                calibration_rounds(store_, *row), format,
                                req->series() ? &series : nullptr);
    }
  } catch (const std::exception& e) {
    return internal(e);
  }
  return write_in_pieces(content, format, *writer, *ctx);
}

grpc::Status CampaignServiceImpl::ImportRuns(grpc::ServerContext* ctx,
                                             const v1::ImportRunsRequest* req,
                                             v1::ImportRunsReply* reply) {
  if (auto s = admit(*ctx, config_.tokens, Caller::kClient, *req, kMaxResultRequestBytes); !s.ok())
    return s;
  try {
    const ImportCounts counts = import_runs(store_, *req);
    reply->set_kept(counts.kept);
    reply->set_known(counts.known);
    reply->set_other_protocol(counts.other_protocol);
    reply->set_protocol(lab::kProtocolVersion);
    for (const auto& [test, version] : lab::kOwnProtocolVersions)
      (*reply->mutable_test_protocol())[std::string(test)] = version;
    spdlog::info("journal runs imported: {} new, {} held already, {} of another lab protocol",
                 counts.kept, counts.known, counts.other_protocol);
    return grpc::Status::OK;
  } catch (const InputError& e) {
    return invalid(e);
  } catch (const std::exception& e) {
    return internal(e);
  }
}

// ---- WorkerService ----

grpc::Status WorkerServiceImpl::Lease(grpc::ServerContext* ctx, const v1::LeaseRequest* req,
                                      v1::LeaseReply* reply) {
  if (auto s = admit(*ctx, config_.tokens, Caller::kWorker, *req); !s.ok()) return s;
  if (const std::string error = worker_text_error(req->worker()); !error.empty())
    return {grpc::StatusCode::INVALID_ARGUMENT, error};
  if (const std::string error = rpc::protocol_mismatch(req->protocols()); !error.empty()) {
    spdlog::warn("lease to {} refused: {}", req->worker(), error);
    return {grpc::StatusCode::FAILED_PRECONDITION, error};
  }
  reply->set_lease_seconds(store_.limits().lease_seconds);
  reply->set_heartbeat_seconds(config_.heartbeat_seconds);
  reply->set_retry_after_seconds(config_.idle_retry_seconds);
  const auto job = store_.lease(req->worker(), steady_seconds());
  if (!job) return grpc::Status::OK;
  v1::JobSpec spec;
  try {
    spec = job_from_payload(job->payload);
  } catch (const std::exception& e) {
    return internal(e);
  }
  spec.set_job_id(job->id);
  spec.set_attempt(job->attempt);
  spec.set_campaign_id(job->campaign_id);
  // A checkpoint comes from an earlier lease of the job: a first lease has none to look up.
  if (auto checkpoint = job->attempt > 1 ? store_.checkpoint(job->id) : std::nullopt) {
    spec.set_checkpoint_stage(checkpoint->stage);
    spec.set_checkpoint_state(std::move(checkpoint->state));
  }
  *reply->mutable_job() = std::move(spec);
  spdlog::info("job {} ({} run {}) leased to {} (attempt {})", job->id, job->test, job->std_order,
               req->worker(), job->attempt);
  return grpc::Status::OK;
}

grpc::Status WorkerServiceImpl::Heartbeat(grpc::ServerContext* ctx, const v1::HeartbeatRequest* req,
                                          v1::HeartbeatReply* reply) {
  if (auto s = admit(*ctx, config_.tokens, Caller::kWorker, *req); !s.ok()) return s;
  if (const std::string error = worker_text_error(req->worker()); !error.empty())
    return {grpc::StatusCode::INVALID_ARGUMENT, error};
  if (const auto answer =
          store_.heartbeat(req->job_id(), req->attempt(), req->worker(), steady_seconds());
      answer != LeaseAnswer::kOk)
    return lease_refused(answer, req->job_id(), req->attempt(), req->worker(), "");
  reply->set_lease_seconds(store_.limits().lease_seconds);
  reply->set_yield_at_checkpoint(
      store_.yield_due(req->job_id(), steady_seconds(), config_.yield_after_seconds));
  return grpc::Status::OK;
}

grpc::Status WorkerServiceImpl::Complete(grpc::ServerContext* ctx, const v1::CompleteRequest* req,
                                         v1::CompleteReply*) {
  if (auto s = admit(*ctx, config_.tokens, Caller::kWorker, *req, kMaxResultRequestBytes); !s.ok())
    return s;
  if (const std::string error = worker_text_error(req->worker()); !error.empty())
    return {grpc::StatusCode::INVALID_ARGUMENT, error};
  if (const std::string error = rpc::result_error(*req); !error.empty())
    return {grpc::StatusCode::INVALID_ARGUMENT, error};
  if (const std::string error = metrics_error(req->metrics()); !error.empty())
    return {grpc::StatusCode::INVALID_ARGUMENT, error};
  try {
    // A job not in the store is answered by the lease check below.
    if (const auto job = store_.job(req->job_id())) {
      const v1::JobSpec spec = job_from_payload(job->payload);
      if (const std::string error = metric_names_error(req->metrics(), spec.test()); !error.empty())
        return {grpc::StatusCode::INVALID_ARGUMENT, error};
    }
  } catch (const std::exception& e) {
    return internal(e);
  }
  std::map<std::string, double> metrics(req->metrics().begin(), req->metrics().end());
  if (const auto answer =
          store_.complete(req->job_id(), req->attempt(), req->worker(), metrics_to_json(metrics),
                          req->wall_seconds(), steady_seconds(), flags_to_json(req->flags()),
                          to_json(req->cost()), series_to_json(req->series()));
      answer != LeaseAnswer::kOk) {
    spdlog::warn("job {}: result of attempt {} from {} rejected", req->job_id(), req->attempt(),
                 req->worker());
    return lease_refused(answer, req->job_id(), req->attempt(), req->worker(),
                         "; result not stored");
  }
  spdlog::info("job {} done by {} in {:.2f} s", req->job_id(), req->worker(), req->wall_seconds());
  return grpc::Status::OK;
}

grpc::Status WorkerServiceImpl::Fail(grpc::ServerContext* ctx, const v1::FailRequest* req,
                                     v1::FailReply*) {
  if (auto s = admit(*ctx, config_.tokens, Caller::kWorker, *req); !s.ok()) return s;
  if (const std::string error = worker_text_error(req->worker(), req->reason()); !error.empty())
    return {grpc::StatusCode::INVALID_ARGUMENT, error};
  if (req->yielded() && !req->give_back())
    return {grpc::StatusCode::INVALID_ARGUMENT, "yielded: only with give_back"};
  if (const auto answer =
          store_.fail(req->job_id(), req->attempt(), req->worker(), req->reason(), req->retryable(),
                      req->give_back(), steady_seconds(), req->yielded());
      answer != LeaseAnswer::kOk)
    return lease_refused(answer, req->job_id(), req->attempt(), req->worker(), "");
  spdlog::info("job {} attempt {} {} by {}: {}", req->job_id(), req->attempt(),
               req->yielded()     ? "yielded"
               : req->give_back() ? "given back"
                                  : "failed",
               req->worker(), req->reason());
  return grpc::Status::OK;
}

grpc::Status WorkerServiceImpl::Checkpoint(grpc::ServerContext* ctx,
                                           const v1::CheckpointRequest* req, v1::CheckpointReply*) {
  // The one large request: its state is bounded below by --max-checkpoint-mb.
  if (auto s = admit(*ctx, config_.tokens, Caller::kWorker, *req, SIZE_MAX); !s.ok()) return s;
  if (const std::string error = worker_text_error(req->worker()); !error.empty())
    return {grpc::StatusCode::INVALID_ARGUMENT, error};
  if (req->stage().empty() || req->stage().size() > 64)
    return {grpc::StatusCode::INVALID_ARGUMENT, "stage: 1-64 characters"};
  if (!std::isfinite(req->simulated_seconds()) || req->simulated_seconds() < 0.0 ||
      req->steps() < 0)
    return {grpc::StatusCode::INVALID_ARGUMENT,
            "simulated_seconds, steps: must be finite and >= 0"};
  const double max_bytes = config_.max_checkpoint_mb * 1024.0 * 1024.0;
  if (static_cast<double>(req->state().size()) > max_bytes)
    return {grpc::StatusCode::INVALID_ARGUMENT,
            fmt::format("state: {} bytes, more than the coordinator's --max-checkpoint-mb {:g}",
                        req->state().size(), config_.max_checkpoint_mb)};
  if (const auto answer = store_.save_checkpoint(req->job_id(), req->attempt(), req->worker(),
                                                 req->stage(), req->state(), steady_seconds(),
                                                 {req->simulated_seconds(), req->steps()});
      answer != LeaseAnswer::kOk)
    return lease_refused(answer, req->job_id(), req->attempt(), req->worker(),
                         "; checkpoint not kept");
  spdlog::info("job {} attempt {}: checkpoint '{}' ({} bytes) from {}", req->job_id(),
               req->attempt(), req->stage(), req->state().size(), req->worker());
  return grpc::Status::OK;
}

}  // namespace demcal::server
