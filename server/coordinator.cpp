#include "server/coordinator.hpp"

#include <grpcpp/health_check_service_interface.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <stdexcept>

#include "rpc/channel.hpp"
#include "server/auth.hpp"
#include "server/reflection.hpp"
#include "server/run_key.hpp"

namespace demcal::server {

Coordinator::Coordinator(CoordinatorOptions options) : options_(std::move(options)) {
  if (options_.lease_seconds <= 0 || options_.heartbeat_seconds <= 0 ||
      options_.heartbeat_seconds >= options_.lease_seconds)
    throw std::invalid_argument("need 0 < heartbeat < lease (got heartbeat " +
                                std::to_string(options_.heartbeat_seconds) + " s, lease " +
                                std::to_string(options_.lease_seconds) + " s)");
  if (options_.max_attempts < 1) throw std::invalid_argument("max attempts must be >= 1");
  const Tokens tokens{options_.token, options_.worker_token, options_.client_token};
  if (tokens.empty() && !options_.no_auth)
    throw std::invalid_argument(
        "no token: give --token-file (or --worker-token-file and --client-token-file), or "
        "--no-auth to serve without authentication (loopback only)");
  if (tokens.empty() && !is_loopback(options_.listen))
    throw std::invalid_argument(
        "a coordinator listening beyond loopback needs --token-file (or "
        "--worker-token-file and --client-token-file)");
  if (!(options_.grace_seconds >= 0.0 && options_.grace_seconds <= 3600.0))
    throw std::invalid_argument("--grace must lie in [0, 3600] s");
  if (!(std::isfinite(options_.rate_since) && options_.rate_since >= 0.0))
    throw std::invalid_argument("the rate's start must be a finite time >= 0");
  // Before the store is opened (and migrated).
  if (!yield_after_admitted(options_.yield_after_seconds))
    throw std::invalid_argument("--yield-after must be 0 (never) or lie in [1, 86400] s");
  store_ = std::make_unique<Store>(options_.db, StoreLimits{options_.lease_seconds,
                                                            options_.max_attempts,
                                                            options_.grace_seconds,
                                                            {},
                                                            options_.fsync_every_commit,
                                                            options_.give_back_leases_at_start,
                                                            options_.rate_since});
  // Jobs of a file from before run keys get theirs, so that later jobs can take their results,
  // and jobs still to run the keys of this build's protocol versions.
  store_->refresh_run_keys(payload_run_key);
  if (options_.max_starts < 1 || options_.max_starts > 1000)
    throw std::invalid_argument("--max-starts must lie in [1, 1000]");
  if (!(options_.max_watch_interval >= kMinWatchInterval && options_.max_watch_interval <= 3600))
    throw std::invalid_argument("--max-watch-interval must lie in [0.05, 3600] s");
  if (!(options_.idle_retry_seconds >= 0.01 && options_.idle_retry_seconds <= 60.0))
    throw std::invalid_argument("the idle retry must lie in [0.01, 60] s");
  if (!(options_.max_checkpoint_mb >= 1.0 && options_.max_checkpoint_mb <= 1024.0))
    throw std::invalid_argument("--max-checkpoint-mb must lie in [1, 1024]");
  if (options_.max_jobs_per_client < 1 || options_.max_jobs < 1)
    throw std::invalid_argument("--max-jobs-per-client and --max-jobs must be >= 1");
  ServiceConfig config{tokens,
                       options_.heartbeat_seconds,
                       std::min(options_.idle_retry_seconds, options_.heartbeat_seconds),
                       options_.max_starts,
                       options_.max_watch_interval,
                       options_.max_checkpoint_mb,
                       options_.max_jobs_per_client,
                       options_.max_jobs,
                       options_.yield_after_seconds};
  campaigns_ = std::make_unique<CampaignServiceImpl>(*store_, config, stopping_);
  workers_ = std::make_unique<WorkerServiceImpl>(*store_, config);

  grpc::EnableDefaultHealthCheckService(true);
  // Reflection describes every service and message: off unless asked, and then behind the
  // client token (reflection.hpp).
  if (options_.reflection)
    reflection_ = std::make_unique<ReflectionService>(
        tokens,
        std::vector<std::string>{v1::CampaignService::service_full_name(),
                                 v1::WorkerService::service_full_name(), "grpc.health.v1.Health",
                                 grpc::reflection::v1alpha::ServerReflection::service_full_name()});
  grpc::ServerBuilder builder;
  const auto creds =
      server_credentials(options_.listen, options_.tls_cert, options_.tls_key, options_.insecure);
  if (options_.insecure)
    spdlog::warn("listening on {} without TLS: tokens and data travel in clear text",
                 options_.listen);
  builder.AddListeningPort(options_.listen, creds, &port_);
  // A checkpoint is the largest message a call carries; every other one is far below it.
  builder.SetMaxReceiveMessageSize(rpc::checkpoint_message_limit(options_.max_checkpoint_mb));
  builder.RegisterService(campaigns_.get());
  builder.RegisterService(workers_.get());
  if (reflection_) builder.RegisterService(reflection_.get());
  server_ = builder.BuildAndStart();
  if (!server_ || port_ == 0) throw std::runtime_error("cannot listen on " + options_.listen);
  if (auto* health = server_->GetHealthCheckService()) health->SetServingStatus(true);
  spdlog::info(
      "coordinator on port {} (db {}, lease {} s, heartbeat {} s, {} attempts, grace {} s{}{})",
      port_, options_.db, options_.lease_seconds, options_.heartbeat_seconds, options_.max_attempts,
      std::max(options_.grace_seconds, options_.lease_seconds), tokens.empty() ? ", NO AUTH" : "",
      options_.reflection ? ", reflection" : "");
  for (const auto& c : store_->campaigns())
    if (c.state == "running") spdlog::info("resuming campaign {} '{}'", c.id, c.name);
  reaper_ = std::thread([this] { reap_loop(); });
}

Coordinator::~Coordinator() {
  shutdown();
}

void Coordinator::reap_loop() {
  std::unique_lock lock(mutex_);
  while (!shut_) {
    lock.unlock();
    try {
      if (const int n = store_->reap(steady_seconds()); n > 0)
        spdlog::warn("reaper: {} expired lease(s) returned to the queue or failed", n);
    } catch (const std::exception& e) {
      spdlog::error("reaper: {}", e.what());
    }
    lock.lock();
    cv_.wait_for(lock, std::chrono::duration<double>(options_.reaper_seconds),
                 [this] { return shut_; });
  }
}

void Coordinator::shutdown() {
  {
    std::lock_guard lock(mutex_);
    if (shut_) return;
    shut_ = true;
  }
  cv_.notify_all();
  stopping_ = true;
  if (auto* health = server_->GetHealthCheckService()) health->SetServingStatus(false);
  server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(2));
  if (reaper_.joinable()) reaper_.join();
  spdlog::info("coordinator stopped");
}

void Coordinator::wait() {
  server_->Wait();
}

}  // namespace demcal::server
