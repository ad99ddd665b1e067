#pragma once
// The coordinator's two gRPC services, one final class each. Handlers authorize, convert at
// the edge (convert.hpp) and call the store and the analysis; invalid input is answered with
// INVALID_ARGUMENT naming the field, a stale lease with FAILED_PRECONDITION.
#include <atomic>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <utility>

#include "demcal/v1/campaign.grpc.pb.h"
#include "demcal/v1/worker.grpc.pb.h"
#include "server/auth.hpp"
#include "server/limits.hpp"
#include "server/store.hpp"

namespace demcal::server {

struct ServiceConfig {
  Tokens tokens;
  double heartbeat_seconds = 10.0;
  double idle_retry_seconds = 1.0;
  int max_starts = 256;                                 ///< Calibrate `starts`, at most
  double max_watch_interval = 60.0;                     ///< Watch `interval_seconds`, at most
  double max_checkpoint_mb = 64.0;                      ///< a checkpoint's state, at most (MiB)
  long max_jobs_per_client = kDefaultMaxJobsPerClient;  ///< unfinished jobs of a token's campaigns
  long max_jobs = kDefaultMaxJobs;                      ///< unfinished jobs of the store, at most
  double yield_after_seconds =
      0.0;  ///< a lease's share before it yields (0: never; Store::yield_due)
};

/// The shortest Watch interval.
constexpr double kMinWatchInterval = 0.05;

double now_seconds();

/// What a Watch tick reads of a campaign, shared by every Watch stream of that campaign for
/// kMinWatchInterval / 2: fifty clients watching at 0.1 s would otherwise read the store (and
/// take its lock, counting every job) 500 times a second, which cost a quarter of the throughput
/// of bench/coordinator.sh. Each stream still sees a read younger than half the shortest interval.
class WatchReads {
 public:
  struct Read {
    std::optional<CampaignRow> row;  ///< none: no such campaign
    Counts counts;
  };
  explicit WatchReads(Store& store) : store_(store) {}
  /// The campaign and its job counts, read at most kMinWatchInterval / 2 ago (steady clock).
  Read read(std::int64_t campaign_id);

 private:
  struct Entry {
    Read read;
    double at = 0.0;
  };
  Store& store_;
  std::mutex mutex_;
  std::map<std::int64_t, Entry> entries_;
};

/// The Watch streams open per client token, each at most kMaxWatchStreamsPerClient: a stream
/// holds one of the coordinator's threads for as long as its campaign runs.
class WatchStreams {
 public:
  /// One open stream of a client, counted until it is destroyed.
  class Slot {
   public:
    Slot(WatchStreams& streams, std::string client)
        : streams_(&streams), client_(std::move(client)) {}
    Slot(Slot&& other) noexcept
        : streams_(std::exchange(other.streams_, nullptr)), client_(std::move(other.client_)) {}
    Slot(const Slot&) = delete;
    Slot& operator=(const Slot&) = delete;
    Slot& operator=(Slot&&) = delete;
    ~Slot() {
      if (streams_) streams_->close(client_);
    }

   private:
    WatchStreams* streams_;
    std::string client_;
  };
  /// A slot for a new stream of `client`; none when it has kMaxWatchStreamsPerClient open.
  std::optional<Slot> open(const std::string& client);

 private:
  void close(const std::string& client);
  std::mutex mutex_;
  std::map<std::string, int> open_;
};

class CampaignServiceImpl final : public v1::CampaignService::Service {
 public:
  CampaignServiceImpl(Store& store, ServiceConfig config, const std::atomic<bool>& stopping)
      : store_(store), config_(std::move(config)), stopping_(stopping), watch_reads_(store) {}

  grpc::Status Submit(grpc::ServerContext*, const v1::SubmitRequest*, v1::SubmitReply*) override;
  grpc::Status Get(grpc::ServerContext*, const v1::GetRequest*, v1::Campaign*) override;
  grpc::Status List(grpc::ServerContext*, const v1::ListRequest*, v1::ListReply*) override;
  grpc::Status Cancel(grpc::ServerContext*, const v1::CancelRequest*, v1::Campaign*) override;
  grpc::Status GiveUp(grpc::ServerContext*, const v1::GiveUpRequest*, v1::GiveUpReply*) override;
  grpc::Status Watch(grpc::ServerContext*, const v1::WatchRequest*,
                     grpc::ServerWriter<v1::Progress>*) override;
  grpc::Status GetDesign(grpc::ServerContext*, const v1::GetRequest*, v1::DesignReply*) override;
  grpc::Status GetResults(grpc::ServerContext*, const v1::GetRequest*, v1::ResultsReply*) override;
  grpc::Status GetEffects(grpc::ServerContext*, const v1::EffectsRequest*,
                          v1::EffectsReply*) override;
  grpc::Status Calibrate(grpc::ServerContext*, const v1::CalibrateRequest*,
                         v1::CalibrateReply*) override;
  grpc::Status Diagnose(grpc::ServerContext*, const v1::DiagnoseRequest*,
                        v1::DiagnoseReply*) override;
  grpc::Status Export(grpc::ServerContext*, const v1::ExportRequest*,
                      grpc::ServerWriter<v1::ExportReply>*) override;
  grpc::Status ImportRuns(grpc::ServerContext*, const v1::ImportRunsRequest*,
                          v1::ImportRunsReply*) override;

 private:
  /// Sleeps `seconds` between two ticks of a Watch, ending early when the client goes away or
  /// the coordinator stops (shutdown waits for every handler).
  void wait_watch_interval(const grpc::ServerContext& ctx, double seconds);
  /// RESOURCE_EXHAUSTED when `jobs` more would take the unfinished jobs of `owner`'s campaigns
  /// or of the store beyond their bounds.
  grpc::Status check_job_bounds(const std::string& owner, std::size_t jobs);

  Store& store_;
  ServiceConfig config_;
  const std::atomic<bool>& stopping_;
  WatchReads watch_reads_;
  WatchStreams watch_streams_;
  /// One submission at a time: the unfinished jobs counted are those the bounds apply to.
  std::mutex submit_mutex_;
  std::mutex diagnose_mutex_;
  std::mutex calibrate_mutex_;
};

class WorkerServiceImpl final : public v1::WorkerService::Service {
 public:
  WorkerServiceImpl(Store& store, ServiceConfig config)
      : store_(store), config_(std::move(config)) {}

  grpc::Status Lease(grpc::ServerContext*, const v1::LeaseRequest*, v1::LeaseReply*) override;
  grpc::Status Heartbeat(grpc::ServerContext*, const v1::HeartbeatRequest*,
                         v1::HeartbeatReply*) override;
  grpc::Status Complete(grpc::ServerContext*, const v1::CompleteRequest*,
                        v1::CompleteReply*) override;
  grpc::Status Fail(grpc::ServerContext*, const v1::FailRequest*, v1::FailReply*) override;
  grpc::Status Checkpoint(grpc::ServerContext*, const v1::CheckpointRequest*,
                          v1::CheckpointReply*) override;

 private:
  Store& store_;
  ServiceConfig config_;
};

}  // namespace demcal::server
