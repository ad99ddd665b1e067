#pragma once
// The stateless worker loop: lease a job, run its lab test with the core (heartbeats from
// their own thread meanwhile), Complete or Fail it, and again. The coordinator away means
// back-off and retry, never a lost result: a finished job's Complete is retried until the
// coordinator answers (a stale lease is then refused by the coordinator, not by the worker).
#include <atomic>
#include <cstdint>
#include <string>

#include "rpc/channel.hpp"

namespace demcal::worker {

struct WorkerOptions {
  rpc::ChannelOptions channel;
  int threads = 2;             ///< simulation threads per job, at most (a job may ask for fewer)
  std::string id;              ///< default: host:pid
  double max_backoff = 10.0;   ///< seconds between reconnection attempts, at most
  int max_jobs = 0;            ///< stop after this many jobs (0 = no limit)
  double idle_exit = 0.0;      ///< stop after this long without work (0 = never)
  double drain_seconds = 0;    ///< after a stop request, give the lease back after this long
                               ///< (0 = finish the job however long it takes)
  double max_particles = 0;    ///< refuse jobs with more particles (0 = no limit)
  double max_job_seconds = 0;  ///< stop a job's simulation after this long and fail it (0 = none)
  /// A checkpoint a job offers is sent once this long has passed since the job's start or its
  /// last one sent (0: every one offered); a re-leased job goes on from the latest.
  double checkpoint_seconds = 300;
  /// Where jobs keep the stages other jobs start from (core/lab/stage_cache.hpp: the bed a
  /// confined compression conditioned, for the tensile job of the same material and seed);
  /// empty: every job computes its own.
  std::string stage_cache_dir;
};

/// Stop requests: `stop` = finish the current job and lease no more; `abort` = give the
/// current lease back now.
struct StopFlags {
  std::atomic<bool> stop{false};
  std::atomic<bool> abort{false};
};

struct WorkerStats {
  int completed = 0, failed = 0, rejected = 0, given_back = 0;
  int abandoned = 0;     ///< simulations stopped because the lease was gone
  int yielded = 0;       ///< leases given back at a checkpoint on the coordinator's request
  int refused_jobs = 0;  ///< jobs over this worker's limits, failed back unrun
  bool unauthenticated = false;
  /// The coordinator runs other lab protocol versions than this build.
  bool other_protocol = false;
};

/// Runs until stopped (or max_jobs / idle_exit). A job given back on abort leaves its
/// simulation running in a detached thread: the caller should exit the process.
WorkerStats run_worker(const WorkerOptions& options, StopFlags& flags);

}  // namespace demcal::worker
