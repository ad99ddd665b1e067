// Coordinator throughput without physics: an in-process coordinator on loopback (real gRPC,
// real SQLite file with synchronous=NORMAL, the default), N fake workers that Lease and Complete
// jobs as fast as they can with synthetic metrics, and W clients holding Watch streams on the
// campaign meanwhile. Prints jobs (lease + complete) per second. With --waiting the campaign's
// rows are a confined compression and the tensile test that waits for it (half the queue waits),
// else one packing run. Run by bench/coordinator.sh.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <iterator>
#include <memory>
#include <thread>
#include <vector>

#include "client/spec_yaml.hpp"
#include "demcal/v1/campaign.grpc.pb.h"
#include "demcal/v1/worker.grpc.pb.h"
#include "rpc/channel.hpp"
#include "rpc/protocols.hpp"
#include "server/coordinator.hpp"

namespace {

using namespace demcal;
using Clock = std::chrono::steady_clock;

/// The factors a spec may vary, in the order the bench takes them: (path, low, high).
constexpr const char* kFactors[][3] = {
    {"particle_law.tangential.mu_s", "0.1", "0.5"},
    {"particle_law.normal.restitution", "0.2", "0.6"},
    {"particle_law.normal.youngs_modulus", "1.0e6", "4.0e6"},
    {"particle_law.tangential.mu_d_ratio", "0.5", "1.0"},
    {"particle_law.tangential.kt_ratio", "0.3", "0.9"},
    {"particle_law.tangential.gamma_t_ratio", "0.3", "0.9"},
    {"sizes.radius", "0.0004", "0.0006"},
    {"density", "2000", "3000"},
    {"particle_law.normal.poisson_ratio", "0.2", "0.4"},
};
constexpr int kMaxFactors = static_cast<int>(std::size(kFactors));

/// A campaign of (2^factors + centre points) x replicates rows, one packing job a row or (waiting)
/// a confined compression and its tensile test; never simulated here.
std::string spec_text(int factors, int centre_points, int replicates, bool waiting) {
  std::string text = R"(
name: bench
material:
  particle_law:
    normal: {model: hertz, youngs_modulus: 2.0e6, restitution: 0.3}
    tangential: {model: history, mu_s: 0.3}
  sizes: {monodisperse: {radius: 0.0005}}
  density: 2500
tests:
)";
  text += waiting ? "  - {test: confined_compression}\n  - {test: tensile}\n"
                  : "  - {test: packing, settings: {particles: 30}}\n";
  text += "factors:\n";
  for (int k = 0; k < factors; ++k)
    text += std::string("  - {path: ") + kFactors[k][0] + ", low: " + kFactors[k][1] +
            ", high: " + kFactors[k][2] + "}\n";
  return text + "design: {type: full_factorial, centre_points: " + std::to_string(centre_points) +
         ", replicates: " + std::to_string(replicates) + "}\n";
}

/// Leases and completes until the queue is empty; returns the jobs completed.
int fake_worker(const rpc::ChannelOptions& channel, const std::string& id) {
  auto stub = v1::WorkerService::NewStub(rpc::make_channel(channel));
  int done = 0;
  for (;;) {
    const v1::LeaseRequest lr = rpc::lease_request(id);
    v1::LeaseReply lease;
    if (!stub->Lease(rpc::make_context(channel, 30).get(), lr, &lease).ok()) continue;
    if (!lease.has_job()) return done;
    v1::CompleteRequest c;
    c.set_job_id(lease.job().job_id());
    c.set_attempt(lease.job().attempt());
    c.set_worker(id);
    c.set_wall_seconds(0.001);
    if (lease.job().test() == "packing") {
      (*c.mutable_metrics())["solid_fraction"] = 0.55;
      (*c.mutable_metrics())["coordination_number"] = 4.0;
    }
    v1::CompleteReply cr;
    if (stub->Complete(rpc::make_context(channel, 30).get(), c, &cr).ok()) ++done;
  }
}

/// Holds a Watch stream until the campaign is no longer running; returns the updates read.
int watcher(const rpc::ChannelOptions& channel, std::int64_t id) {
  auto stub = v1::CampaignService::NewStub(rpc::make_channel(channel));
  v1::WatchRequest req;
  req.set_id(id);
  req.set_interval_seconds(0.1);
  auto context = rpc::make_context(channel, 600);
  auto reader = stub->Watch(context.get(), req);
  v1::Progress p;
  int updates = 0;
  while (reader->Read(&p)) ++updates;
  reader->Finish();
  return updates;
}

}  // namespace

int main(int argc, char** argv) {
  int workers = 8, watchers = 50, factors = 2, centre_points = 64, replicates = 16;
  bool waiting = false;
  std::string dir = "coordinator-bench";
  CLI::App app{"coordinator throughput: lease + complete per second, no physics"};
  app.add_option("--workers", workers, "fake workers (threads)")->capture_default_str();
  app.add_option("--watchers", watchers, "concurrent Watch streams")->capture_default_str();
  app.add_option("--factors", factors, "factors of the full factorial (2^factors runs)")
      ->check(CLI::Range(1, kMaxFactors))
      ->capture_default_str();
  app.add_option("--centre-points", centre_points)->capture_default_str();
  app.add_option("--replicates", replicates)->capture_default_str();
  app.add_option("--dir", dir, "directory of the SQLite file (emptied)")->capture_default_str();
  app.add_flag("--waiting", waiting,
               "rows of a confined compression and the tensile test that waits for it");
  CLI11_PARSE(app, argc, argv);
  spdlog::set_level(spdlog::level::warn);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);

  server::CoordinatorOptions co;
  co.listen = "127.0.0.1:0";
  co.db = dir + "/bench.db";
  co.token = "bench-token";
  auto first = std::make_unique<server::Coordinator>(co);
  rpc::ChannelOptions channel;
  channel.address = "127.0.0.1:" + std::to_string(first->port());
  channel.token = co.token;

  v1::SubmitRequest sreq;
  *sreq.mutable_spec() =
      cli::parse_campaign_spec(spec_text(factors, centre_points, replicates, waiting), "bench.yaml")
          .spec;
  v1::SubmitReply sr;
  const auto submit_start = Clock::now();
  const auto st = v1::CampaignService::NewStub(rpc::make_channel(channel))
                      ->Submit(rpc::make_context(channel, 60).get(), sreq, &sr);
  if (!st.ok()) {
    std::cerr << "submit: " << st.error_message() << "\n";
    return 1;
  }
  const double submit_s = std::chrono::duration<double>(Clock::now() - submit_start).count();
  const int jobs = sr.design().jobs();

  // A coordinator started again on the file, every job still queued: its start derives each
  // queued job's run key again (this build's protocol versions).
  first->shutdown();
  first.reset();
  const auto reopen_start = Clock::now();
  server::Coordinator coordinator(co);
  const double reopen_s = std::chrono::duration<double>(Clock::now() - reopen_start).count();
  channel.address = "127.0.0.1:" + std::to_string(coordinator.port());

  std::vector<std::thread> watch_threads;
  std::atomic<int> updates{0};
  for (int i = 0; i < watchers; ++i)
    watch_threads.emplace_back([&] { updates += watcher(channel, sr.id()); });
  const auto start = Clock::now();
  std::vector<std::thread> worker_threads;
  std::atomic<int> completed{0};
  for (int i = 0; i < workers; ++i)
    worker_threads.emplace_back(
        [&, i] { completed += fake_worker(channel, "fake-" + std::to_string(i)); });
  for (auto& t : worker_threads) t.join();
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  for (auto& t : watch_threads) t.join();
  coordinator.shutdown();

  std::printf(
      "jobs %d (submitted in %.3f s; a coordinator started on them, their run keys derived "
      "again, in %.3f s), completed %d by %d fake workers with %d Watch streams (%d updates)\n",
      jobs, submit_s, reopen_s, completed.load(), workers, watchers, updates.load());
  std::printf("lease + complete: %.0f jobs/s (%.2f s)\n", completed / seconds, seconds);
  return completed == jobs ? 0 : 1;
}
