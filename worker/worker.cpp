#include "worker/worker.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <future>
#include <mutex>
#include <optional>
#include <random>
#include <thread>

#include "core/common/error.hpp"
#include "core/lab/lab_test.hpp"
#include "core/lab/run_cancelled.hpp"
#include "demcal/v1/worker.grpc.pb.h"
#include "rpc/material_convert.hpp"

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
};

/// What may stop a running job from outside, read by its progress callback: the heartbeat
/// thread learning that the lease is gone (expired, cancelled, taken over) and the worker's
/// wall-time limit.
struct JobStop {
  std::atomic<bool> lease_lost{false};
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
/// --max-particles.
std::string refusal(const v1::JobSpec& job, double max_particles) {
  const auto it = job.settings().find("particles");
  if (max_particles <= 0 || it == job.settings().end() || !(it->second > max_particles)) return {};
  return "job asks for " + std::to_string(std::llround(it->second)) +
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

Outcome run_job(const v1::JobSpec& job, int threads, std::atomic<double>& progress,
                const JobStop& stop) {
  Outcome o;
  try {
    const lab::MaterialModel material = rpc::job_material(job);
    lab::RunOptions ro;
    ro.threads = job_threads(job, threads);
    ro.seed = job.seed() ? job.seed() : 1;
    ro.progress = [&progress, &stop](double f) {
      progress = f;
      stop.check();
    };
    const lab::LabOutput out =
        lab::run_lab_test(job.test(), material, rpc::to_settings(job.settings()), ro);
    o.ok = true;
    o.metrics = out.metrics;
    o.flags = out.flags;
    o.cost = to_proto(out.cost);
    for (const auto& [name, series] : out.series) o.series.push_back(to_proto(name, series));
  } catch (const lab::RunCancelled& e) {
    o.cancelled = true;
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

}  // namespace

WorkerStats run_worker(const WorkerOptions& opt, StopFlags& flags) {
  WorkerStats stats;
  const std::string id = [&] {
    if (!opt.id.empty()) return opt.id;
    char host[256] = {};
    gethostname(host, sizeof host - 1);
    return std::string(host) + ":" + std::to_string(getpid());
  }();
  auto channel = rpc::make_channel(opt.channel);
  auto stub = v1::WorkerService::NewStub(channel);
  std::mt19937_64 jitter(std::hash<std::string>{}(id));
  double backoff = 0.2;
  auto back_off = [&](const grpc::Status& s, const char* what) {
    spdlog::warn("{}: coordinator {} unavailable ({}); retrying in {:.1f} s", what,
                 opt.channel.address, s.error_message(), backoff);
    nap(backoff * (0.75 + 0.5 * std::uniform_real_distribution<>(0, 1)(jitter)), flags);
    backoff = std::min(opt.max_backoff, backoff * 2);
  };
  // A job this worker will not run goes back as a failed attempt with the reason, so that the
  // coordinator can give it to another worker (and fails it at the attempt cap).
  auto report_refusal = [&](const v1::JobSpec& job, const std::string& why) {
    v1::FailRequest f;
    f.set_job_id(job.job_id());
    f.set_attempt(job.attempt());
    f.set_worker(id);
    f.set_reason(why);
    f.set_retryable(true);
    v1::FailReply fr;
    const auto s = stub->Fail(rpc::make_context(opt.channel, 10).get(), f, &fr);
    ++stats.refused_jobs;
    spdlog::warn("job {} refused: {} ({})", job.job_id(), why,
                 s.ok() ? "reported" : s.error_message());
  };
  auto idle_since = Clock::now();
  spdlog::info("worker {} -> {} ({} threads)", id, opt.channel.address, opt.threads);

  while (!flags.stop && !flags.abort) {
    if (opt.max_jobs > 0 && stats.completed + stats.failed >= opt.max_jobs) break;
    v1::LeaseRequest lreq;
    lreq.set_worker(id);
    v1::LeaseReply lease;
    const auto ls = stub->Lease(rpc::make_context(opt.channel, 10).get(), lreq, &lease);
    if (ls.error_code() == grpc::StatusCode::UNAUTHENTICATED) {
      spdlog::error("coordinator refused the token: {}", ls.error_message());
      stats.unauthenticated = true;
      break;
    }
    if (!ls.ok()) {
      back_off(ls, "lease");
      continue;
    }
    backoff = 0.2;
    if (!lease.has_job()) {
      if (opt.idle_exit > 0 &&
          std::chrono::duration<double>(Clock::now() - idle_since).count() > opt.idle_exit)
        break;
      nap(lease.retry_after_seconds() > 0 ? lease.retry_after_seconds() : 1.0, flags);
      continue;
    }
    const v1::JobSpec job = lease.job();
    spdlog::info("job {} attempt {}: {} (campaign {}) on {} thread(s)", job.job_id(), job.attempt(),
                 job.test(), job.campaign_id(), job_threads(job, opt.threads));
    const auto started = Clock::now();
    if (const std::string why = refusal(job, opt.max_particles); !why.empty()) {
      report_refusal(job, why);
      continue;
    }

    // Heartbeats from their own thread, so a long simulation step never lets the lease lapse.
    std::atomic<double> progress{0.0};
    JobStop job_stop;
    job_stop.max_seconds = opt.max_job_seconds;
    if (opt.max_job_seconds > 0)
      job_stop.deadline = started + std::chrono::duration_cast<Clock::duration>(
                                        std::chrono::duration<double>(opt.max_job_seconds));
    std::atomic<bool>& lease_lost = job_stop.lease_lost;
    std::mutex hb_mutex;
    std::condition_variable hb_cv;
    bool hb_stop = false;
    const double hb_every = lease.heartbeat_seconds() > 0 ? lease.heartbeat_seconds() : 10.0;
    std::thread heartbeat([&] {
      std::unique_lock lock(hb_mutex);
      while (
          !hb_cv.wait_for(lock, std::chrono::duration<double>(hb_every), [&] { return hb_stop; })) {
        lock.unlock();
        v1::HeartbeatRequest h;
        h.set_job_id(job.job_id());
        h.set_attempt(job.attempt());
        h.set_worker(id);
        h.set_progress(progress);
        v1::HeartbeatReply hr;
        const auto s = stub->Heartbeat(rpc::make_context(opt.channel, 5).get(), h, &hr);
        const bool gone = s.error_code() == grpc::StatusCode::FAILED_PRECONDITION ||
                          s.error_code() == grpc::StatusCode::PERMISSION_DENIED;
        if (gone && !lease_lost) {
          lease_lost = true;
          spdlog::warn("job {}: lease {} lost ({}); stopping its simulation", job.job_id(),
                       job.attempt(), s.error_message());
        } else if (!s.ok() && !lease_lost) {
          spdlog::warn("job {}: heartbeat failed: {}", job.job_id(), s.error_message());
        }
        lock.lock();
      }
    });
    auto stop_heartbeat = [&] {
      {
        std::lock_guard lock(hb_mutex);
        hb_stop = true;
      }
      hb_cv.notify_all();
      heartbeat.join();
    };

    // The simulation runs on its own thread so that a stop request can give the lease back.
    // It reads `progress` and `job_stop` only until it returns; a detached simulation (give-back
    // on abort) is followed by the process exiting.
    auto task = std::make_shared<std::packaged_task<Outcome()>>(
        [job, threads = opt.threads, &progress, &job_stop] {
          return run_job(job, threads, progress, job_stop);
        });
    auto future = task->get_future();
    std::thread sim([task] { (*task)(); });
    std::optional<Clock::time_point> stop_seen;
    bool give_back = false;
    while (future.wait_for(std::chrono::milliseconds(50)) != std::future_status::ready) {
      if (flags.abort) give_back = true;
      if (flags.stop && !stop_seen) {
        stop_seen = Clock::now();
        spdlog::info("stop requested: finishing job {} first", job.job_id());
      }
      if (stop_seen && opt.drain_seconds > 0 &&
          std::chrono::duration<double>(Clock::now() - *stop_seen).count() > opt.drain_seconds)
        give_back = true;
      if (give_back) break;
    }
    if (give_back) {
      sim.detach();  // the process is about to exit; the lease goes back now
      stop_heartbeat();
      v1::FailRequest f;
      f.set_job_id(job.job_id());
      f.set_attempt(job.attempt());
      f.set_worker(id);
      f.set_reason("worker " + id + " stopping");
      f.set_give_back(true);
      f.set_retryable(true);
      v1::FailReply fr;
      const auto s = stub->Fail(rpc::make_context(opt.channel, 5).get(), f, &fr);
      spdlog::info("job {}: lease given back ({})", job.job_id(),
                   s.ok() ? "ok" : s.error_message());
      ++stats.given_back;
      break;
    }
    sim.join();
    Outcome out = future.get();
    stop_heartbeat();
    const double wall = std::chrono::duration<double>(Clock::now() - started).count();
    if (out.cancelled && lease_lost) {
      // Nobody wants this result any more: the coordinator refuses it and may have given the
      // job to another worker.
      ++stats.abandoned;
      spdlog::warn("job {}: simulation stopped after {:.2f} s: {}", job.job_id(), wall, out.reason);
      idle_since = Clock::now();
      continue;
    }

    // Report; retried while the coordinator is away (a restart must not lose a result).
    for (int tries = 0;; ++tries) {
      grpc::Status s;
      if (out.ok) {
        v1::CompleteRequest c;
        c.set_job_id(job.job_id());
        c.set_attempt(job.attempt());
        c.set_worker(id);
        c.set_wall_seconds(wall);
        for (const auto& [k, v] : out.metrics) (*c.mutable_metrics())[k] = v;
        for (const auto& [k, v] : out.flags) (*c.mutable_flags())[k] = v;
        *c.mutable_cost() = out.cost;
        for (const auto& s : out.series) *c.add_series() = s;
        v1::CompleteReply cr;
        s = stub->Complete(rpc::make_context(opt.channel, 10).get(), c, &cr);
      } else {
        v1::FailRequest f;
        f.set_job_id(job.job_id());
        f.set_attempt(job.attempt());
        f.set_worker(id);
        f.set_reason(out.reason);
        f.set_retryable(out.retryable);
        v1::FailReply fr;
        s = stub->Fail(rpc::make_context(opt.channel, 10).get(), f, &fr);
      }
      if (s.ok()) {
        if (out.ok) {
          ++stats.completed;
          spdlog::info("job {} done in {:.2f} s", job.job_id(), wall);
        } else {
          ++stats.failed;
          spdlog::warn("job {} failed: {}", job.job_id(), out.reason);
        }
        break;
      }
      if (s.error_code() == grpc::StatusCode::FAILED_PRECONDITION) {
        ++stats.rejected;
        spdlog::warn("job {}: coordinator refused the report: {}", job.job_id(), s.error_message());
        break;
      }
      if (s.error_code() == grpc::StatusCode::UNAUTHENTICATED || flags.abort || tries > 200) {
        spdlog::error("job {}: report not delivered: {}", job.job_id(), s.error_message());
        break;
      }
      back_off(s, out.ok ? "complete" : "fail");
      if (flags.stop) nap(0.5, StopFlags{});  // keep trying while draining
    }
    idle_since = Clock::now();
  }
  spdlog::info(
      "worker {} stopping: {} done, {} failed, {} refused, {} given back, {} abandoned, {} jobs "
      "refused",
      id, stats.completed, stats.failed, stats.rejected, stats.given_back, stats.abandoned,
      stats.refused_jobs);
  return stats;
}

}  // namespace demcal::worker
