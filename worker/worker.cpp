#include "worker/worker.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <thread>
#include <utility>

#include "core/common/error.hpp"
#include "core/lab/lab_run.hpp"
#include "core/lab/run_cancelled.hpp"
#include "core/lab/stage_cache.hpp"
#include "demcal/v1/worker.grpc.pb.h"
#include "rpc/material_convert.hpp"
#include "rpc/protocols.hpp"
#include "rpc/result_check.hpp"

namespace demcal::worker {
namespace {

using Clock = std::chrono::steady_clock;

/// Sleeps up to `seconds`, waking early on a stop request.
void nap(double seconds, const StopFlags& flags) {
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  while (Clock::now() < end && !flags.stop && !flags.abort)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
}

struct Outcome {
  bool ok = false;
  std::map<std::string, double> metrics;
  std::map<std::string, std::string> flags;
  std::vector<v1::Series> series;
  v1::RunCost cost;
  std::string reason;
  bool retryable = false;
  bool cancelled = false;  ///< stopped on request (lease lost or over the time limit)
  bool yielded = false;    ///< stopped at a checkpoint kept, the coordinator asking it to yield
};

/// What may stop a running job from outside, read by its progress callback: the heartbeat
/// thread learning that the lease is gone (expired, cancelled, taken over) and the worker's
/// wall-time limit; and, read by its checkpoint callback, the coordinator asking it to yield.
struct JobStop {
  std::atomic<bool> lease_lost{false};
  std::atomic<bool> yield_asked{false};
  std::optional<Clock::time_point> deadline;  ///< --max-job-seconds after the start
  double max_seconds = 0.0;

  /// Throws RunCancelled when the job must stop.
  void check() const {
    if (lease_lost) throw lab::RunCancelled("the lease is gone (expired, or campaign cancelled)");
    if (deadline && Clock::now() > *deadline)
      throw lab::RunCancelled(fmt::format(
          "the job ran longer than this worker's --max-job-seconds {:g} s and was stopped",
          max_seconds));
  }
};

/// A job this worker refuses before running it (empty: none): more particles than its
/// --max-particles, counted as the test sizes its bed (the drum's from its geometry). A job
/// its test does not admit is not refused here: running it fails at once, as not retryable.
std::string refusal(const v1::JobSpec& job, double max_particles) {
  if (max_particles <= 0) return {};
  std::size_t particles = 0;
  try {
    particles =
        lab::admit_lab_test(job.test(), rpc::job_material(job), rpc::to_settings(job.settings()));
  } catch (const InputError&) {
    return {};
  }
  if (static_cast<double>(particles) <= max_particles) return {};
  return "job asks for " + std::to_string(particles) +
         " particles, more than this worker's --max-particles " +
         std::to_string(std::llround(max_particles));
}

/// Rows a curve keeps in a result: enough to draw it, far below the coordinator's limit.
constexpr std::size_t kSeriesRows = 500;

/// A curve as a result carries it: thinned, and without rows that hold a value that is not
/// finite (a point that cannot be drawn; the coordinator refuses such numbers).
v1::Series to_proto(const std::string& name, const lab::Series& full) {
  lab::Series drawable{full.columns, {}};
  for (const auto& row : full.rows)
    if (std::all_of(row.begin(), row.end(), [](double v) { return std::isfinite(v); }))
      drawable.rows.push_back(row);
  const lab::Series s = lab::thinned(drawable, kSeriesRows);
  v1::Series out;
  out.set_name(name);
  for (const auto& c : s.columns) out.add_columns(c);
  for (const auto& row : s.rows)
    for (double v : row) out.add_values(v);
  return out;
}

v1::RunCost to_proto(const lab::RunCost& c) {
  v1::RunCost r;
  r.set_time_step(c.time_step);
  r.set_time_step_limit(c.time_step_limit);
  r.set_particles(static_cast<std::int64_t>(c.particles));
  r.set_steps(c.steps);
  r.set_simulated_time(c.simulated_time);
  r.set_wall_seconds(c.wall_seconds);
  r.set_particle_steps_per_second(c.particle_steps_per_second());
  for (const auto& p : c.phases) {
    auto* q = r.add_phases();
    q->set_name(p.name);
    q->set_target(p.target);
    q->set_steps(p.steps);
    q->set_simulated_time(p.simulated_time);
    q->set_wall_seconds(p.wall_seconds);
    q->set_reached(p.reached);
  }
  return r;
}

/// The worker's --threads is what its machine gives it: a spec may ask for fewer, never more.
int job_threads(const v1::JobSpec& job, int worker_threads) {
  return job.threads() > 0 ? std::min(job.threads(), worker_threads) : worker_threads;
}

/// Sends a checkpoint the job offers (stage, the run's clock there, its record) to the
/// coordinator; true when the coordinator kept it.
using CheckpointSender =
    std::function<bool(const std::string&, const lab::CheckpointClock&, std::string)>;

/// Runs the job's lab test, from the checkpoint the lease carries if any: one that this build
/// cannot go on from (another format, a stage the test never reaches) is set aside with a
/// warning, and the job runs from the start.
lab::LabOutput run_lab(const v1::JobSpec& job, lab::RunOptions options) {
  const lab::MaterialModel material = rpc::job_material(job);
  const lab::Settings settings = rpc::to_settings(job.settings());
  options.resume = {job.checkpoint_stage(), job.checkpoint_state()};
  if (!options.resume.stage.empty()) {
    try {
      spdlog::info("job {}: going on from checkpoint '{}'", job.job_id(), options.resume.stage);
      return lab::run_lab_test(job.test(), material, settings, options);
    } catch (const InputError& e) {
      if (e.where() != "checkpoint") throw;
      spdlog::warn("job {}: {}; running it from the start", job.job_id(), e.what());
      options.resume = {};
    }
  }
  return lab::run_lab_test(job.test(), material, settings, options);
}

Outcome run_job(const v1::JobSpec& job, int threads, std::atomic<double>& progress,
                const JobStop& stop, const CheckpointSender& send_checkpoint,
                double checkpoint_seconds, const std::shared_ptr<const lab::StageCache>& cache) {
  Outcome o;
  bool yielded = false;
  try {
    lab::RunOptions ro;
    ro.stage_cache = cache;
    ro.threads = job_threads(job, threads);
    ro.seed = rpc::job_seed(job);
    ro.progress = [&progress, &stop](double f) {
      progress = f;
      stop.check();
    };
    ro.checkpoint = [&send_checkpoint, &stop, &yielded, checkpoint_seconds, last = Clock::now()](
                        const std::string& stage, const lab::CheckpointClock& clock,
                        const std::function<std::string()>& record) mutable {
      const double since = std::chrono::duration<double>(Clock::now() - last).count();
      // Asked to yield, the run stops at the first checkpoint the coordinator keeps (tried at
      // most once a second): the job goes on from it in its next lease, nothing lost.
      if (stop.yield_asked && since >= std::min(checkpoint_seconds, 1.0)) {
        last = Clock::now();
        if (send_checkpoint(stage, clock, record())) {
          yielded = true;
          throw lab::RunCancelled("yielded at its checkpoint '" + stage + "'");
        }
        return;
      }
      if (since < checkpoint_seconds) return;
      send_checkpoint(stage, clock, record());
      last = Clock::now();
    };
    const lab::LabOutput out = run_lab(job, std::move(ro));
    o.ok = true;
    o.metrics = out.metrics;
    o.flags = out.flags;
    o.cost = to_proto(out.cost);
    for (const auto& [name, series] : out.series) o.series.push_back(to_proto(name, series));
  } catch (const lab::RunCancelled& e) {
    o.cancelled = true;
    o.yielded = yielded;
    o.reason = e.what();
  } catch (const SimulationFailure& e) {
    o.reason = std::string("simulation failed (") + to_string(e.reason()) + "): " + e.what();
  } catch (const InputError& e) {
    o.reason = std::string("invalid job: ") + e.what();
  } catch (const std::exception& e) {
    o.reason = std::string("worker error: ") + e.what();
    o.retryable = true;
  }
  return o;
}

/// The failure that replaces a result the coordinator refused as invalid: not retryable.
Outcome refused_result(const grpc::Status& refusal) {
  Outcome o;
  o.reason = "the coordinator refused the result: " + refusal.error_message();
  return o;
}

/// This process's name for the coordinator: --id, or host:pid.
std::string worker_id(const WorkerOptions& opt) {
  if (!opt.id.empty()) return opt.id;
  char host[256] = {};
  gethostname(host, sizeof host - 1);
  return std::string(host) + ":" + std::to_string(getpid());
}

/// Heartbeats of one lease from their own thread, so that a long simulation step never lets the
/// lease lapse; a reply saying the lease is gone sets `lease_lost`, which stops the simulation,
/// and one asking the job to yield sets `yield_asked`, which stops it at its next checkpoint.
class Heartbeat {
 public:
  Heartbeat(v1::WorkerService::Stub& stub, const rpc::ChannelOptions& channel,
            const v1::JobSpec& job, const std::string& worker, double every,
            const std::atomic<double>& progress, JobStop& stop)
      : thread_([&, job, worker, every] {
          std::unique_lock lock(mutex_);
          while (
              !cv_.wait_for(lock, std::chrono::duration<double>(every), [&] { return stopped_; })) {
            lock.unlock();
            beat(stub, channel, job, worker, progress, stop);
            lock.lock();
          }
        }) {}
  Heartbeat(const Heartbeat&) = delete;
  Heartbeat& operator=(const Heartbeat&) = delete;
  ~Heartbeat() { stop(); }

  void stop() {
    {
      std::lock_guard lock(mutex_);
      stopped_ = true;
    }
    cv_.notify_all();
    if (thread_.joinable()) thread_.join();
  }

 private:
  static void beat(v1::WorkerService::Stub& stub, const rpc::ChannelOptions& channel,
                   const v1::JobSpec& job, const std::string& worker,
                   const std::atomic<double>& progress, JobStop& stop) {
    v1::HeartbeatRequest h;
    h.set_job_id(job.job_id());
    h.set_attempt(job.attempt());
    h.set_worker(worker);
    h.set_progress(progress);
    v1::HeartbeatReply hr;
    const auto s = stub.Heartbeat(rpc::make_context(channel, 5).get(), h, &hr);
    const bool gone = s.error_code() == grpc::StatusCode::FAILED_PRECONDITION ||
                      s.error_code() == grpc::StatusCode::PERMISSION_DENIED;
    if (gone && !stop.lease_lost) {
      stop.lease_lost = true;
      spdlog::warn("job {}: lease {} lost ({}); stopping its simulation", job.job_id(),
                   job.attempt(), s.error_message());
    } else if (!s.ok() && !stop.lease_lost) {
      spdlog::warn("job {}: heartbeat failed: {}", job.job_id(), s.error_message());
    } else if (s.ok() && hr.yield_at_checkpoint() && !stop.yield_asked) {
      stop.yield_asked = true;
      spdlog::info("job {}: the coordinator asks it to yield at its next checkpoint", job.job_id());
    }
  }

  std::mutex mutex_;
  std::condition_variable cv_;
  bool stopped_ = false;
  std::thread thread_;  ///< last: started once the members it uses exist
};

/// The worker's loop: lease, run, report, until stopped. Each job is one pass of step().
class Worker {
 public:
  Worker(const WorkerOptions& opt, StopFlags& flags)
      : opt_(opt),
        flags_(flags),
        id_(worker_id(opt)),
        lease_request_(rpc::lease_request(id_)),
        stub_(v1::WorkerService::NewStub(rpc::make_channel(opt.channel))),
        jitter_(std::hash<std::string>{}(id_)),
        stage_cache_(opt.stage_cache_dir.empty()
                         ? nullptr
                         : std::make_shared<const lab::StageCache>(opt.stage_cache_dir)) {}

  WorkerStats run() {
    spdlog::info("worker {} -> {} ({} threads)", id_, opt_.channel.address, opt_.threads);
    while (!flags_.stop && !flags_.abort) {
      if (opt_.max_jobs > 0 && stats_.completed + stats_.failed >= opt_.max_jobs) break;
      if (!step()) break;
    }
    spdlog::info(
        "worker {} stopping: {} done, {} failed, {} refused, {} given back, {} yielded, {} "
        "abandoned, {} jobs refused",
        id_, stats_.completed, stats_.failed, stats_.rejected, stats_.given_back, stats_.yielded,
        stats_.abandoned, stats_.refused_jobs);
    return stats_;
  }

 private:
  /// One lease and what follows from it; false when the loop must end.
  bool step() {
    v1::LeaseReply lease;
    const auto ls = stub_->Lease(rpc::make_context(opt_.channel, 10).get(), lease_request_, &lease);
    if (ls.error_code() == grpc::StatusCode::UNAUTHENTICATED) {
      spdlog::error("coordinator refused the token: {}", ls.error_message());
      stats_.unauthenticated = true;
      return false;
    }
    if (ls.error_code() == grpc::StatusCode::FAILED_PRECONDITION) {
      spdlog::error("coordinator refused this build: {}", ls.error_message());
      stats_.other_protocol = true;
      return false;
    }
    if (!ls.ok()) {
      back_off(ls, "lease");
      return true;
    }
    backoff_ = kFirstBackoff;
    if (!lease.has_job()) {
      if (opt_.idle_exit > 0 &&
          std::chrono::duration<double>(Clock::now() - idle_since_).count() > opt_.idle_exit)
        return false;
      nap(lease.retry_after_seconds() > 0 ? lease.retry_after_seconds() : 1.0, flags_);
      return true;
    }
    return run_leased(lease);
  }

  bool run_leased(const v1::LeaseReply& lease) {
    const v1::JobSpec& job = lease.job();
    spdlog::info("job {} attempt {}: {} (campaign {}) on {} thread(s)", job.job_id(), job.attempt(),
                 job.test(), job.campaign_id(), job_threads(job, opt_.threads));
    const auto started = Clock::now();
    if (const std::string why = refusal(job, opt_.max_particles); !why.empty()) {
      // A job this worker will not run goes back as a failed attempt with the reason, so that
      // the coordinator can give it to another worker (and fails it at the attempt cap).
      const auto s = fail(job, why, /*retryable=*/true, /*give_back=*/false, 10);
      ++stats_.refused_jobs;
      spdlog::warn("job {} refused: {} ({})", job.job_id(), why,
                   s.ok() ? "reported" : s.error_message());
      return true;
    }
    // Shared with the simulation's thread, which a give-back on abort detaches: it may write
    // them after this function has returned (until the process exits).
    const auto shared = std::make_shared<std::pair<std::atomic<double>, JobStop>>();
    std::atomic<double>& progress = shared->first;
    JobStop& job_stop = shared->second;
    job_stop.max_seconds = opt_.max_job_seconds;
    if (opt_.max_job_seconds > 0)
      job_stop.deadline = started + std::chrono::duration_cast<Clock::duration>(
                                        std::chrono::duration<double>(opt_.max_job_seconds));
    Heartbeat heartbeat(*stub_, opt_.channel, job, id_,
                        lease.heartbeat_seconds() > 0 ? lease.heartbeat_seconds() : 10.0, progress,
                        job_stop);
    // The simulation runs on its own thread so that a stop request can give the lease back; a
    // detached simulation (give-back on abort) is followed by the process exiting.
    auto task = std::make_shared<std::packaged_task<Outcome()>>(
        [this, job, threads = opt_.threads, shared] {
          const CheckpointSender send = [this, &job](const std::string& stage,
                                                     const lab::CheckpointClock& clock,
                                                     std::string state) {
            return send_checkpoint(job, stage, clock, std::move(state));
          };
          return run_job(job, threads, shared->first, shared->second, send, opt_.checkpoint_seconds,
                         stage_cache_);
        });
    auto future = task->get_future();
    std::thread sim([task] { (*task)(); });
    if (must_give_back(future, job)) {
      sim.detach();  // the process is about to exit; the lease goes back now
      heartbeat.stop();
      const auto s = fail(job, "worker " + id_ + " stopping", true, /*give_back=*/true, 5);
      spdlog::info("job {}: lease given back ({})", job.job_id(),
                   s.ok() ? "ok" : s.error_message());
      ++stats_.given_back;
      return false;
    }
    sim.join();
    const Outcome out = future.get();
    const double wall = std::chrono::duration<double>(Clock::now() - started).count();
    if (out.cancelled && job_stop.lease_lost) {
      // Nobody wants this result any more: the coordinator refuses it and may have given the
      // job to another worker.
      ++stats_.abandoned;
      spdlog::warn("job {}: simulation stopped after {:.2f} s: {}", job.job_id(), wall, out.reason);
    } else if (out.yielded) {
      // Queued again behind the jobs that yielded fewer times; its next lease goes on from the
      // checkpoint just kept. A give-back the coordinator does not hear ends as a lapsed lease.
      const auto s = fail(job, out.reason, true, /*give_back=*/true, 10, /*yielded=*/true);
      ++stats_.yielded;
      spdlog::info("job {}: {} after {:.2f} s ({})", job.job_id(), out.reason, wall,
                   s.ok() ? "given back" : s.error_message());
    } else {
      // Heartbeats go on while the report is retried: the lease must outlive a coordinator
      // that is slow or restarting.
      report(job, out, wall);
    }
    heartbeat.stop();
    idle_since_ = Clock::now();
    return true;
  }

  /// Waits for the simulation; true when the lease must go back unfinished: an abort, or a
  /// stop request that has waited longer than --drain-seconds.
  bool must_give_back(std::future<Outcome>& future, const v1::JobSpec& job) {
    std::optional<Clock::time_point> stop_seen;
    while (future.wait_for(std::chrono::milliseconds(50)) != std::future_status::ready) {
      if (flags_.abort) return true;
      if (flags_.stop && !stop_seen) {
        stop_seen = Clock::now();
        spdlog::info("stop requested: finishing job {} first", job.job_id());
      }
      if (stop_seen && opt_.drain_seconds > 0 &&
          std::chrono::duration<double>(Clock::now() - *stop_seen).count() > opt_.drain_seconds)
        return true;
    }
    return false;
  }

  /// Reports the outcome; retried while the coordinator is away (a restart must not lose a
  /// result). A result the coordinator refuses as invalid is never sent again: the job fails,
  /// not retryable, with the coordinator's message (another worker would compute the same).
  void report(const v1::JobSpec& job, const Outcome& out, double wall) {
    for (int tries = 0;; ++tries) {
      const grpc::Status s =
          out.ok ? complete(job, out, wall) : fail(job, out.reason, out.retryable, false, 10);
      if (s.ok()) {
        if (out.ok) {
          ++stats_.completed;
          spdlog::info("job {} done in {:.2f} s", job.job_id(), wall);
        } else {
          ++stats_.failed;
          spdlog::warn("job {} failed: {}", job.job_id(), out.reason);
        }
        return;
      }
      if (out.ok && s.error_code() == grpc::StatusCode::INVALID_ARGUMENT) {
        spdlog::error("job {}: coordinator refused the result: {}", job.job_id(),
                      s.error_message());
        report(job, refused_result(s), wall);
        return;
      }
      if (s.error_code() == grpc::StatusCode::FAILED_PRECONDITION ||
          s.error_code() == grpc::StatusCode::PERMISSION_DENIED) {
        ++stats_.rejected;
        spdlog::warn("job {}: coordinator refused the report: {}", job.job_id(), s.error_message());
        return;
      }
      if (s.error_code() == grpc::StatusCode::UNAUTHENTICATED ||
          s.error_code() == grpc::StatusCode::INVALID_ARGUMENT || flags_.abort || tries > 200) {
        spdlog::error("job {}: report not delivered: {}", job.job_id(), s.error_message());
        return;
      }
      back_off(s, out.ok ? "complete" : "fail");
      if (flags_.stop) nap(0.5, StopFlags{});  // keep trying while draining
    }
  }

  grpc::Status complete(const v1::JobSpec& job, const Outcome& out, double wall) {
    v1::CompleteRequest c;
    c.set_job_id(job.job_id());
    c.set_attempt(job.attempt());
    c.set_worker(id_);
    c.set_wall_seconds(wall);
    for (const auto& [k, v] : out.metrics) (*c.mutable_metrics())[k] = v;
    for (const auto& [k, v] : out.flags) (*c.mutable_flags())[k] = v;
    *c.mutable_cost() = out.cost;
    for (const auto& series : out.series) *c.add_series() = series;
    v1::CompleteReply cr;
    return stub_->Complete(rpc::make_context(opt_.channel, 10).get(), c, &cr);
  }

  /// One try: a checkpoint that does not arrive costs only the time it would have saved.
  bool send_checkpoint(const v1::JobSpec& job, const std::string& stage,
                       const lab::CheckpointClock& clock, std::string state) {
    const std::size_t bytes = state.size();
    v1::CheckpointRequest c;
    c.set_job_id(job.job_id());
    c.set_attempt(job.attempt());
    c.set_worker(id_);
    c.set_stage(stage);
    c.set_simulated_seconds(clock.simulated_seconds);
    c.set_steps(clock.steps);
    c.set_state(std::move(state));
    v1::CheckpointReply cr;
    const auto s = stub_->Checkpoint(rpc::make_context(opt_.channel, 30).get(), c, &cr);
    if (s.ok())
      spdlog::info("job {}: checkpoint '{}' sent ({} bytes, at {:.4g} s simulated, {} steps)",
                   job.job_id(), stage, bytes, c.simulated_seconds(), c.steps());
    else
      spdlog::warn("job {}: checkpoint '{}' not kept: {}", job.job_id(), stage, s.error_message());
    return s.ok();
  }

  grpc::Status fail(const v1::JobSpec& job, const std::string& reason, bool retryable,
                    bool give_back, double deadline_seconds, bool yielded = false) {
    v1::FailRequest f;
    f.set_job_id(job.job_id());
    f.set_attempt(job.attempt());
    f.set_worker(id_);
    f.set_reason(rpc::fail_reason(reason));
    f.set_retryable(retryable);
    f.set_give_back(give_back);
    f.set_yielded(yielded);
    v1::FailReply fr;
    return stub_->Fail(rpc::make_context(opt_.channel, deadline_seconds).get(), f, &fr);
  }

  /// Waits before the next call to an unavailable coordinator: doubling up to --max-backoff,
  /// with +-25 % jitter so that many workers do not return at once.
  void back_off(const grpc::Status& s, const char* what) {
    spdlog::warn("{}: coordinator {} unavailable ({}); retrying in {:.1f} s", what,
                 opt_.channel.address, s.error_message(), backoff_);
    nap(backoff_ * (0.75 + 0.5 * std::uniform_real_distribution<>(0, 1)(jitter_)), flags_);
    backoff_ = std::min(opt_.max_backoff, backoff_ * 2);
  }

  static constexpr double kFirstBackoff = 0.2;
  const WorkerOptions& opt_;
  StopFlags& flags_;
  const std::string id_;
  /// The same every lease: the id and the lab protocol versions.
  const v1::LeaseRequest lease_request_;
  std::unique_ptr<v1::WorkerService::Stub> stub_;
  std::mt19937_64 jitter_;
  std::shared_ptr<const lab::StageCache> stage_cache_;
  double backoff_ = kFirstBackoff;
  Clock::time_point idle_since_ = Clock::now();
  WorkerStats stats_;
};

}  // namespace

WorkerStats run_worker(const WorkerOptions& opt, StopFlags& flags) {
  return Worker(opt, flags).run();
}

}  // namespace demcal::worker
