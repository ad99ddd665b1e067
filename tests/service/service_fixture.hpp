#pragma once
// The fixture of the service tests with real processes (test_service_*.cpp, test_journal.cpp, ...):
// a coordinator started (and restarted) on a loopback port with a file of its own, workers, the CLI
// against it, fake results through the real worker protocol, and the SQLite file read directly.
// Every wait is bounded.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "client/spec_yaml.hpp"
#include "demcal/v1/campaign.grpc.pb.h"
#include "demcal/v1/worker.grpc.pb.h"
#include "rpc/channel.hpp"
#include "rpc/protocols.hpp"
#include "tests/service/process.hpp"

namespace demcal::test {

namespace fs = std::filesystem;
inline const std::string kToken = "test-token-123";
/// Particles of a packing job that runs for minutes on one thread (cancelled or stopped long
/// before it would end).
inline constexpr int kLongJobParticles = 20000;

/// The material and test of the packing campaigns: frictional Hertz spheres of 0.5 mm,
/// `particles` to a bed.
inline std::string packing_material(int particles) {
  return R"(
material:
  particle_law:
    normal: {model: hertz, youngs_modulus: 2.0e6, restitution: 0.3}
    tangential: {model: history, mu_s: 0.3}
  sizes: {monodisperse: {radius: 0.0005}}
  density: 2500
tests:
  - test: packing
    settings: {particles: )" +
         std::to_string(particles) + "}\n";
}

/// A packing campaign of 2^2 runs (+ centre points) at `particles` particles; by default its
/// calibration verifies one round only.
inline std::string tiny_spec(
    int particles, int centre = 0, const std::string& extra_factor = "",
    const std::string& calibration = "calibration: {rounds: 1, stages: 1}\n") {
  return "\nname: tiny" + packing_material(particles) + R"(factors:
  - {path: particle_law.tangential.mu_s, low: 0.1, high: 0.5}
  - {path: particle_law.normal.restitution, low: 0.2, high: 0.6}
)" + extra_factor +
         R"(design: {type: full_factorial, centre_points: )" + std::to_string(centre) + R"(}
measurements:
  - {metric: solid_fraction, value: 0.6, uncertainty: 0.02}
)" + calibration;
}

/// Four wall-friction runs of 30 cohesive Luding spheres, a few seconds each: jobs long enough
/// to be caught running, with stages to checkpoint. `more` is appended (e.g. measurements).
inline std::string wall_friction_spec(const std::string& name, const std::string& more) {
  return "name: " + name + R"(
material:
  particle_law:
    normal: {model: luding, youngs_modulus: 1.0e7, k2_ratio: 5, phi_f: 0.05, restitution: 0.3}
    tangential: {model: history, mu_s: 0.3}
  sizes: {monodisperse: {radius: 0.001}}
  density: 1500
tests:
  - test: wall_friction
    settings: {particles: 30}
factors:
  - {path: particle_law.tangential.mu_s, low: 0.2, high: 0.4}
  - {path: wall_law.tangential.mu_s, low: 0.2, high: 0.4}
design: {type: full_factorial}
)" + more;
}

class Service : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("demcal_service_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    workers_.clear();
    server_.reset();
    if (!HasFailure()) fs::remove_all(dir_);
  }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  /// Starts (or restarts on the same port and file) the coordinator.
  void start_server(double lease = 1.5, double heartbeat = 0.3, int port = 0,
                    const std::vector<std::string>& extra = {}) {
    const std::string port_file = path("port");
    fs::remove(port_file);
    std::vector<std::string> argv{DEMCAL_SERVER_BIN,
                                  "--listen",
                                  "127.0.0.1:" + std::to_string(port),
                                  "--db",
                                  path("c.db"),
                                  "--token",
                                  kToken,
                                  "--lease",
                                  std::to_string(lease),
                                  "--heartbeat",
                                  std::to_string(heartbeat),
                                  "--reaper-interval",
                                  "0.1",
                                  "--port-file",
                                  port_file};
    argv.insert(argv.end(), extra.begin(), extra.end());
    server_ = std::make_unique<Process>(argv, path("server.log"));
    ASSERT_TRUE(wait_until([&] { return fs::exists(port_file); }, 20)) << server_->log();
    std::ifstream(port_file) >> port_;
    channel_.address = "127.0.0.1:" + std::to_string(port_);
    channel_.token = kToken;
    campaigns_ = v1::CampaignService::NewStub(rpc::make_channel(channel_));
    workers_stub_ = v1::WorkerService::NewStub(rpc::make_channel(channel_));
  }

  Process& start_worker(const std::string& id, const std::string& token = kToken,
                        const std::vector<std::string>& extra = {}) {
    std::vector<std::string> argv{DEMCAL_WORKER_BIN,
                                  "--coordinator",
                                  channel_.address,
                                  "--token",
                                  token,
                                  "--threads",
                                  "1",
                                  "--id",
                                  id,
                                  "--max-backoff",
                                  "0.5"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    workers_.push_back(std::make_unique<Process>(argv, path(id + ".log")));
    return *workers_.back();
  }

  /// The id of a job in state `state`, polled for at most `seconds` (0 if none appeared).
  std::int64_t wait_for_job(std::int64_t campaign, const std::string& state, double seconds) {
    std::int64_t found = 0;
    wait_until(
        [&] {
          const auto now = results(campaign);
          for (const auto& j : now.jobs())
            if (j.state() == state) found = j.job_id();
          return found != 0;
        },
        seconds);
    return found;
  }

  std::unique_ptr<grpc::ClientContext> ctx(double seconds = 30) {
    return rpc::make_context(channel_, seconds);
  }

  grpc::Status submit(const std::string& yaml, std::int64_t* id = nullptr) {
    v1::SubmitRequest req;
    *req.mutable_spec() = cli::parse_campaign_spec(yaml, "spec.yaml").spec;
    v1::SubmitReply reply;
    const auto s = campaigns_->Submit(ctx().get(), req, &reply);
    if (id) *id = reply.id();
    return s;
  }

  v1::ResultsReply results(std::int64_t id) {
    v1::GetRequest req;
    req.set_id(id);
    v1::ResultsReply r;
    const auto status = campaigns_->GetResults(ctx().get(), req, &r);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return r;
  }

  /// The coordinator's answer to a Lease of `worker` (no job in it when none is to be run).
  void lease_as(const std::string& worker, v1::LeaseReply& lease) {
    const auto status = workers_stub_->Lease(ctx().get(), rpc::lease_request(worker), &lease);
    ASSERT_TRUE(status.ok()) << status.error_message();
  }

  /// Leases the next job as `worker` into `job` and starts its result `c` (job, attempt,
  /// worker): a result through the real worker protocol, no physics.
  void lease_request(const std::string& worker, v1::JobSpec& job, v1::CompleteRequest& c) {
    v1::LeaseReply lease;
    ASSERT_NO_FATAL_FAILURE(lease_as(worker, lease));
    ASSERT_TRUE(lease.has_job());
    job = lease.job();
    c.set_job_id(job.job_id());
    c.set_attempt(job.attempt());
    c.set_worker(worker);
  }

  /// Leases the next job as worker "fake" and completes it with what `fill` writes into the
  /// request (metrics, cost).
  void complete_fake_job(
      const std::function<void(const v1::JobSpec&, v1::CompleteRequest&)>& fill) {
    v1::JobSpec job;
    v1::CompleteRequest c;
    ASSERT_NO_FATAL_FAILURE(lease_request("fake", job, c));
    fill(job, c);
    v1::CompleteReply cr;
    const auto st = workers_stub_->Complete(ctx().get(), c, &cr);
    ASSERT_TRUE(st.ok()) << st.error_message();
  }

  /// Completes the four design jobs of tiny_spec's packing campaign with fake metrics: the solid
  /// fraction rising with mu_s over the box 0.1-0.5, 0.6 + 0.1 (mu_s - 0.3) / 0.2.
  void complete_linear_design() {
    for (int k = 0; k < 4; ++k)
      ASSERT_NO_FATAL_FAILURE(complete_fake_job([](const v1::JobSpec& job, v1::CompleteRequest& c) {
        const double a = (job.parameters().at("particle_law.tangential.mu_s") - 0.3) / 0.2;
        (*c.mutable_metrics())["solid_fraction"] = 0.6 + 0.1 * a;
        (*c.mutable_metrics())["coordination_number"] = 4.0;
      }));
  }

  /// Completes the `design_jobs` design jobs of a packing campaign with fake metrics (the solid
  /// fraction rising with mu_s), then calls Diagnose once: the runs it queues first.
  void finish_design_and_diagnose(std::int64_t id, int design_jobs, v1::DiagnoseReply& reply) {
    for (int k = 0; k < design_jobs; ++k)
      ASSERT_NO_FATAL_FAILURE(
          complete_fake_job([&](const v1::JobSpec& job, v1::CompleteRequest& c) {
            (*c.mutable_metrics())["solid_fraction"] =
                0.5 + 0.1 * job.parameters().at("particle_law.tangential.mu_s");
            (*c.mutable_metrics())["coordination_number"] = 4.0 + 0.1 * k;
          }));
    v1::DiagnoseRequest diagnose;
    diagnose.set_id(id);
    const auto st = campaigns_->Diagnose(ctx().get(), diagnose, &reply);
    ASSERT_TRUE(st.ok()) << st.error_message();
  }

  bool campaign_done(std::int64_t id) {
    v1::GetRequest req;
    req.set_id(id);
    v1::Campaign c;
    return campaigns_->Get(ctx(5).get(), req, &c).ok() && c.state() == v1::DONE;
  }

  /// Calls `row` on each row of `sql` run on the SQLite file `db_path` itself (read-only).
  static void each_row(const std::string& db_path, const char* sql,
                       const std::function<void(sqlite3_stmt*)>& row) {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open_v2(db_path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK)
        << db_path;
    sqlite3_stmt* st = nullptr;
    EXPECT_EQ(sqlite3_prepare_v2(db, sql, -1, &st, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
    while (st && sqlite3_step(st) == SQLITE_ROW) row(st);
    sqlite3_finalize(st);
    sqlite3_close(db);
  }

  /// The first column's integers of `sql` on the SQLite file `db_path`, polled while a run may be
  /// creating it: none while the file or its tables are not there yet.
  static std::vector<std::int64_t> polled_ids(const std::string& db_path, const std::string& sql) {
    std::vector<std::int64_t> out;
    sqlite3* db = nullptr;
    sqlite3_stmt* st = nullptr;
    if (fs::exists(db_path) &&
        sqlite3_open_v2(db_path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK &&
        sqlite3_prepare_v2(db, sql.c_str(), -1, &st, nullptr) == SQLITE_OK)
      while (sqlite3_step(st) == SQLITE_ROW) out.push_back(sqlite3_column_int64(st, 0));
    sqlite3_finalize(st);
    sqlite3_close(db);
    return out;
  }

  /// Rows of the results table per job, read from the SQLite file itself.
  std::map<std::int64_t, int> stored_results() {
    std::map<std::int64_t, int> out;
    each_row(
        path("c.db"), "SELECT job_id, COUNT(*) FROM results GROUP BY job_id",
        [&](sqlite3_stmt* st) { out[sqlite3_column_int64(st, 0)] = sqlite3_column_int(st, 1); });
    return out;
  }

  fs::path dir_;
  int port_ = 0;
  rpc::ChannelOptions channel_;
  std::unique_ptr<Process> server_;
  std::vector<std::unique_ptr<Process>> workers_;
  std::unique_ptr<v1::CampaignService::Stub> campaigns_;
  std::unique_ptr<v1::WorkerService::Stub> workers_stub_;
};

/// Runs the CLI against the test's coordinator; returns its standard output, which stays in
/// `dir`/`file` (its standard error beside it, `file`.err).
inline std::string cli_text(const std::string& dir, const std::string& file,
                            const std::vector<std::string>& args, const rpc::ChannelOptions& ch) {
  std::vector<std::string> argv{DEMCAL_CLI_BIN};
  argv.insert(argv.end(), args.begin(), args.end());
  for (const std::string a : {"--coordinator", ch.address.c_str(), "--token", kToken.c_str()})
    argv.push_back(a);
  Process p(argv, dir + "/" + file, dir + "/" + file + ".err");
  EXPECT_EQ(p.wait_exit(150), 0) << file << ": " << p.log();
  return p.log();
}

/// Runs the CLI against the test's coordinator; returns its standard output (kept in
/// `dir`/`name`.json) parsed as JSON.
inline nlohmann::json cli_json(const std::string& dir, const std::string& name,
                               const std::vector<std::string>& args,
                               const rpc::ChannelOptions& ch) {
  const std::string out = cli_text(dir, name + ".json", args, ch);
  try {
    return nlohmann::json::parse(out);
  } catch (const std::exception& e) {
    ADD_FAILURE() << name << " did not print one JSON document: " << e.what() << "\n" << out;
    return {};
  }
}

}  // namespace demcal::test
