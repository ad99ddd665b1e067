#pragma once
// The coordinator: the store, the two services, grpc.health.v1, reflection and the lease
// reaper, wired into one gRPC server. Used by `demcal-server` and by `demcal run`.
#include <grpcpp/grpcpp.h>

#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "server/limits.hpp"
#include "server/reflection.hpp"
#include "server/services.hpp"
#include "server/store.hpp"

namespace demcal::server {

struct CoordinatorOptions {
  std::string listen = "127.0.0.1:7311";  ///< port 0 picks a free one (see port())
  std::string db = "demcal.db";
  std::string token;         ///< opens both services (all three empty: refused unless no_auth)
  std::string worker_token;  ///< opens only the WorkerService
  std::string client_token;  ///< opens only the CampaignService
  bool reflection = false;   ///< serve gRPC server reflection (behind the client token)
  /// Serve without any token (loopback only): must be asked for, never the default.
  bool no_auth = false;
  double lease_seconds = 60.0;
  double heartbeat_seconds = 10.0;
  double reaper_seconds = 1.0;
  /// How long a worker that found no job waits before it asks again (at most the heartbeat).
  double idle_retry_seconds = 1.0;
  /// A lease found in the file at start-up expires no sooner than this (nor than a lease)
  /// after start-up: workers that ran on while the coordinator was down reconnect and report.
  double grace_seconds = 30.0;
  /// The leases found in the file at start-up go back to the queue uncounted instead: its
  /// workers lived and died with the process that held them (the embedded default).
  bool give_back_leases_at_start = false;
  /// The wall-clock time (s) the progress's ETA rates jobs from; 0: the coordinator's start.
  /// A coordinator reading a copy of a store another one holds rates from that one's start.
  double rate_since = 0.0;
  int max_attempts = 3;
  /// Sync the SQLite file at every commit (power-cut durability; store.hpp), not only at
  /// checkpoints.
  bool fsync_every_commit = false;
  int max_starts = 256;              ///< Calibrate `starts`, at most
  double max_watch_interval = 60.0;  ///< Watch `interval_seconds`, at most
  double max_checkpoint_mb = 64.0;   ///< a worker's checkpoint, at most (MiB)
  /// Unfinished jobs of one token's campaigns, and of the store, at most.
  long max_jobs_per_client = kDefaultMaxJobsPerClient;
  long max_jobs = kDefaultMaxJobs;
  /// A lease that has run this long (doubled per earlier yield of its job) gives its job back at
  /// the run's next checkpoint when a job that yielded no more often waits (0: never).
  double yield_after_seconds = 0.0;
  std::string tls_cert, tls_key;
  bool insecure = false;  ///< plain TCP (behind a trusted network or a TLS-terminating proxy)
};

class Coordinator {
 public:
  /// Opens the store, starts serving and the reaper; throws on a bad option or address.
  explicit Coordinator(CoordinatorOptions options);
  ~Coordinator();
  int port() const { return port_; }
  Store& store() { return *store_; }
  /// A channel to this coordinator's services inside the process (the live report page).
  std::shared_ptr<grpc::Channel> in_process_channel() {
    return server_->InProcessChannel(grpc::ChannelArguments());
  }
  /// Stops accepting calls, ends watches, waits for handlers and stops the reaper.
  void shutdown();
  void wait();

 private:
  void reap_loop();
  CoordinatorOptions options_;
  std::unique_ptr<Store> store_;
  std::atomic<bool> stopping_{false};
  std::unique_ptr<CampaignServiceImpl> campaigns_;
  std::unique_ptr<WorkerServiceImpl> workers_;
  std::unique_ptr<ReflectionService> reflection_;  ///< only with `reflection`
  std::unique_ptr<grpc::Server> server_;
  int port_ = 0;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::thread reaper_;
  bool shut_ = false;
};

}  // namespace demcal::server
