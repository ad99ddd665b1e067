// demcal-worker: leases jobs from a coordinator and runs them. main only wires: flags, the
// signal thread, the worker loop. SIGTERM/SIGINT: finish the current job (or give its lease
// back after --drain seconds) and exit; a second signal gives the lease back at once.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <fstream>
#include <thread>

#include "core/sim/threads.hpp"
#include "rpc/stop_signals.hpp"
#include "worker/worker.hpp"

int main(int argc, char** argv) {
  demcal::sim::wait_passively(argv);
  demcal::worker::WorkerOptions o;
  std::string token_file;
  CLI::App app{"demcal-worker - runs demcal lab-test jobs for a coordinator"};
  app.add_option("--coordinator", o.channel.address, "host:port of demcal-server")->required();
  app.add_option("--token", o.channel.token, "bearer token")->envname("DEMCAL_TOKEN");
  app.add_option("--token-file", token_file, "read the token from a file");
  app.add_option("--tls-ca", o.channel.tls_ca, "CA certificate (PEM) for a TLS coordinator");
  app.add_flag("--insecure", o.channel.insecure, "plain TCP (coordinator started with --insecure)");
  app.add_option("--threads", o.threads, "simulation threads per job, at most")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--id", o.id, "worker name in the coordinator's records (default host:pid)");
  app.add_option("--max-jobs", o.max_jobs, "exit after this many jobs (0 = no limit)");
  app.add_option("--idle-exit", o.idle_exit, "exit after this many idle seconds (0 = never)");
  app.add_option("--drain", o.drain_seconds,
                 "on SIGTERM, give the lease back after this many seconds (0 = finish the job)");
  app.add_option("--max-particles", o.max_particles,
                 "refuse jobs with more particles than this (0 = no limit)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--max-job-seconds", o.max_job_seconds,
                 "stop and fail a job running longer than this (s; 0 = no limit)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--checkpoint-seconds", o.checkpoint_seconds,
                 "send a checkpoint a job offers once this long has passed since its start or "
                 "its last one (s; 0 = every one offered)")
      ->check(CLI::Range(0.0, 86400.0))
      ->capture_default_str();
  app.add_option("--max-backoff", o.max_backoff, "longest reconnection back-off (s)")
      ->capture_default_str();
  app.add_option("--stage-cache", o.stage_cache_dir,
                 "directory where jobs keep the stages other jobs start from (e.g. the bed a "
                 "confined compression conditioned, for a tensile job); none by default");
  CLI11_PARSE(app, argc, argv);
  if (!token_file.empty()) try {
      o.channel.token = demcal::rpc::read_token_file(token_file);
    } catch (const std::exception& e) {
      spdlog::critical("{}", e.what());
      return 2;
    }
  // Signals are taken synchronously by one thread; every other thread inherits the mask.
  const sigset_t set = demcal::rpc::block_stop_signals();
  demcal::worker::StopFlags flags;
  std::thread signals([&] {
    for (int n = 0; n < 2; ++n) {
      int sig = 0;
      sigwait(&set, &sig);
      spdlog::info("signal {}: {}", sig, n == 0 ? "finishing the current job" : "giving back");
      (n == 0 ? flags.stop : flags.abort) = true;
    }
  });
  signals.detach();
  try {
    const auto stats = demcal::worker::run_worker(o, flags);
    std::fflush(nullptr);
    // A given-back job may still be simulating in a detached thread: leave without joining it.
    std::_Exit(stats.unauthenticated ? 2 : stats.other_protocol ? 3 : 0);
  } catch (const std::exception& e) {
    spdlog::critical("{}", e.what());
    return 1;
  }
}
