// How a worker reports a finished job to a coordinator that does not take it at once: a result
// refused as invalid fails the job (not retried) with the coordinator's message, and heartbeats
// keep the lease while a report is retried; and how it leases: naming its lab protocol versions,
// and stopping when the coordinator refuses them. The coordinator is a fake WorkerService in
// process on loopback that leases one small packing job and answers Complete as each test says; the
// worker is the real one (run_worker), the job is simulated for real.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>

#include "demcal/v1/worker.grpc.pb.h"
#include "rpc/protocols.hpp"
#include "worker/worker.hpp"

namespace demcal::test {
namespace {

using Clock = std::chrono::steady_clock;

/// A packing job of 30 frictional Hertz spheres: a fraction of a second on one thread.
v1::JobSpec small_job() {
  v1::JobSpec job;
  job.set_job_id(7);
  job.set_attempt(1);
  job.set_campaign_id(1);
  job.set_test("packing");
  (*job.mutable_settings())["particles"] = 30;
  auto* law = job.mutable_material()->mutable_particle_law();
  law->mutable_normal()->set_model("hertz");
  (*law->mutable_normal()->mutable_params())["youngs_modulus"] = 2.0e6;
  (*law->mutable_normal()->mutable_params())["restitution"] = 0.3;
  law->mutable_tangential()->set_model("history");
  (*law->mutable_tangential()->mutable_params())["mu_s"] = 0.3;
  job.mutable_material()->mutable_sizes()->mutable_monodisperse()->set_radius(0.0005);
  job.mutable_material()->set_density(2500);
  job.set_seed(1);
  return job;
}

/// The coordinator's side: one job leased once, Complete answered by `answer_complete`, every
/// call counted.
class FakeCoordinator final : public v1::WorkerService::Service {
 public:
  explicit FakeCoordinator(std::function<grpc::Status()> answer_complete)
      : answer_complete_(std::move(answer_complete)) {}

  /// Every Lease is answered with `status` (and no job when it is not OK).
  void refuse_leases(grpc::Status status) { lease_status_ = std::move(status); }

  grpc::Status Lease(grpc::ServerContext*, const v1::LeaseRequest* req,
                     v1::LeaseReply* reply) override {
    {
      std::lock_guard lock(mutex_);
      ++leases_;
      protocol_mismatch_ = rpc::protocol_mismatch(req->protocols());
    }
    if (!lease_status_.ok()) return lease_status_;
    reply->set_lease_seconds(30);
    reply->set_heartbeat_seconds(0.1);
    reply->set_retry_after_seconds(0.05);
    if (!leased_.exchange(true)) *reply->mutable_job() = small_job();
    return grpc::Status::OK;
  }
  grpc::Status Heartbeat(grpc::ServerContext*, const v1::HeartbeatRequest*,
                         v1::HeartbeatReply* reply) override {
    std::lock_guard lock(mutex_);
    ++heartbeats_;
    if (completes_ > 0) ++heartbeats_after_first_complete_;
    reply->set_lease_seconds(30);
    return grpc::Status::OK;
  }
  grpc::Status Complete(grpc::ServerContext*, const v1::CompleteRequest*,
                        v1::CompleteReply*) override {
    {
      std::lock_guard lock(mutex_);
      ++completes_;
    }
    return answer_complete_();
  }
  grpc::Status Fail(grpc::ServerContext*, const v1::FailRequest* req, v1::FailReply*) override {
    std::lock_guard lock(mutex_);
    fails_.push_back(*req);
    return grpc::Status::OK;
  }
  grpc::Status Checkpoint(grpc::ServerContext*, const v1::CheckpointRequest*,
                          v1::CheckpointReply*) override {
    return grpc::Status::OK;
  }

  int leases() {
    std::lock_guard lock(mutex_);
    return leases_;
  }
  /// rpc::protocol_mismatch of the latest lease request's versions against this build's.
  std::string protocol_mismatch() {
    std::lock_guard lock(mutex_);
    return protocol_mismatch_;
  }
  int completes() {
    std::lock_guard lock(mutex_);
    return completes_;
  }
  int heartbeats_after_first_complete() {
    std::lock_guard lock(mutex_);
    return heartbeats_after_first_complete_;
  }
  std::vector<v1::FailRequest> fails() {
    std::lock_guard lock(mutex_);
    return fails_;
  }

 private:
  std::function<grpc::Status()> answer_complete_;
  grpc::Status lease_status_ = grpc::Status::OK;
  std::atomic<bool> leased_{false};
  std::mutex mutex_;
  std::string protocol_mismatch_ = "no lease asked for";
  int leases_ = 0, heartbeats_ = 0, heartbeats_after_first_complete_ = 0, completes_ = 0;
  std::vector<v1::FailRequest> fails_;
};

/// Serves `fake` on a free loopback port and runs one real worker (one job, then it stops)
/// against it; the worker is stopped after `seconds` at the latest.
worker::WorkerStats run_worker_against(FakeCoordinator& fake, double seconds) {
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort("127.0.0.1:0", grpc::experimental::LocalServerCredentials(LOCAL_TCP),
                           &port);
  builder.RegisterService(&fake);
  auto server = builder.BuildAndStart();
  EXPECT_NE(port, 0);
  worker::WorkerOptions o;
  o.channel.address = "127.0.0.1:" + std::to_string(port);
  o.threads = 1;
  o.id = "w1";
  o.max_jobs = 1;
  o.max_backoff = 0.05;
  worker::StopFlags flags;
  std::optional<worker::WorkerStats> stats;
  std::thread t([&] { stats = worker::run_worker(o, flags); });
  const auto until = Clock::now() + std::chrono::duration<double>(seconds);
  while (!stats && Clock::now() < until) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  flags.abort = true;
  t.join();
  server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(1));
  return *stats;
}

TEST(WorkerReports, AResultRefusedAsInvalidFailsTheJobOnceNotRetryableWithTheCoordinatorsMessage) {
  FakeCoordinator fake([] {
    return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                        "metrics.solid_fraction: must be finite");
  });
  const auto stats = run_worker_against(fake, 20);
  EXPECT_EQ(fake.completes(), 1) << "a refused result was sent again";
  const auto fails = fake.fails();
  ASSERT_EQ(fails.size(), 1u);
  EXPECT_FALSE(fails[0].retryable());
  EXPECT_FALSE(fails[0].give_back());
  EXPECT_EQ(fails[0].job_id(), 7);
  EXPECT_NE(fails[0].reason().find("metrics.solid_fraction: must be finite"), std::string::npos)
      << fails[0].reason();
  EXPECT_EQ(stats.completed, 0);
  EXPECT_EQ(stats.failed, 1);
}

TEST(WorkerReports, HeartbeatsGoOnWhileAReportIsRetried) {
  // The coordinator cannot take the result for its first second (overloaded, restarting): the
  // worker retries it, and meanwhile keeps its lease with heartbeats (every 0.1 s).
  std::optional<Clock::time_point> first;
  std::mutex m;
  FakeCoordinator fake([&] {
    std::lock_guard lock(m);
    if (!first) first = Clock::now();
    if (Clock::now() - *first < std::chrono::seconds(1))
      return grpc::Status(grpc::StatusCode::UNAVAILABLE, "busy");
    return grpc::Status::OK;
  });
  const auto stats = run_worker_against(fake, 20);
  EXPECT_EQ(stats.completed, 1);
  EXPECT_GT(fake.completes(), 1);
  EXPECT_GE(fake.heartbeats_after_first_complete(), 3);
  EXPECT_TRUE(fake.fails().empty());
}

TEST(WorkerReports, AWorkerLeasesNamingItsProtocolVersionsAndStopsWhenTheCoordinatorRunsOthers) {
  FakeCoordinator runs([] { return grpc::Status::OK; });
  const auto done = run_worker_against(runs, 20);
  EXPECT_EQ(done.completed, 1);
  EXPECT_EQ(runs.protocol_mismatch(), "") << "the worker's lease named other versions";

  // A coordinator of another build refuses the lease: the worker leaves at once (its exit status
  // 3), without retrying and without running anything.
  FakeCoordinator other([] { return grpc::Status::OK; });
  other.refuse_leases({grpc::StatusCode::FAILED_PRECONDITION,
                       "protocols.shear_cell: the worker simulates it under lab protocol "
                       "version 3, this coordinator keys its runs under 4"});
  const auto refused = run_worker_against(other, 20);
  EXPECT_TRUE(refused.other_protocol);
  EXPECT_EQ(other.leases(), 1) << "a refused build asked again";
  EXPECT_EQ(refused.completed + refused.failed, 0);
  EXPECT_EQ(other.completes(), 0);
}

}  // namespace
}  // namespace demcal::test
