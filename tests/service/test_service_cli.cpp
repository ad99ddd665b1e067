// Service tests with real processes, real gRPC on loopback and real SQLite files (the fixture:
// service_fixture.hpp). The CLI against a coordinator and the embedded default: a campaign end to
// end, a work directory of another spec, the embedded run interrupted, an export larger than a
// message. Leases and heartbeats are short (flags); every wait is bounded.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>
#include <utility>

#include "client/service_client.hpp"
#include "client/spec_yaml.hpp"
#include "core/common/error.hpp"
#include "core/lab/lab_run.hpp"
#include "demcal/v1/campaign.grpc.pb.h"
#include "demcal/v1/worker.grpc.pb.h"
#include "rpc/channel.hpp"
#include "rpc/material_convert.hpp"
#include "server/limits.hpp"
#include "tests/service/service_fixture.hpp"

namespace demcal::test {
namespace {

// `demcal run` on a work directory whose campaign of that name was submitted with another spec
// refuses, naming the directory, instead of resuming the old campaign as if it were this one.
TEST_F(Service, RunOnAWorkDirectoryWhoseCampaignHasAnotherSpecRefuses) {
  const std::string spec = path("tiny.yaml");
  std::ofstream(spec) << tiny_spec(200);
  Process first(
      {DEMCAL_CLI_BIN, "run", spec, "--workdir", path("work"), "--threads", "1", "--no-verify"},
      path("first.log"));
  ASSERT_EQ(first.wait_exit(150), 0) << first.log();
  std::string edited = tiny_spec(200);
  edited.replace(edited.find("low: 0.1, high: 0.5"), 19, "low: 0.1, high: 0.4");
  std::ofstream(spec) << edited;
  Process second(
      {DEMCAL_CLI_BIN, "run", spec, "--workdir", path("work"), "--threads", "1", "--no-verify"},
      path("second.log"));
  EXPECT_NE(second.wait_exit(150), 0) << second.log();
  EXPECT_NE(second.log().find("another spec"), std::string::npos) << second.log();
  EXPECT_NE(second.log().find(path("work")), std::string::npos) << second.log();
  EXPECT_EQ(second.log().find("resuming campaign"), std::string::npos) << second.log();
  // The unchanged spec still resumes.
  std::ofstream(spec) << tiny_spec(200);
  Process third(
      {DEMCAL_CLI_BIN, "run", spec, "--workdir", path("work"), "--threads", "1", "--no-verify"},
      path("third.log"));
  EXPECT_EQ(third.wait_exit(150), 0) << third.log();
  EXPECT_NE(third.log().find("resuming campaign 1"), std::string::npos) << third.log();
}

TEST_F(Service, CliRunsACampaignEndToEnd) {
  const std::string spec = path("tiny.yaml");
  std::ofstream(spec) << tiny_spec(200, 1);  // (60 particles: packing could not insert them all)
  Process run(
      {DEMCAL_CLI_BIN, "run", spec, "--workdir", path("work"), "--workers", "2", "--threads", "1"},
      path("run.log"));
  ASSERT_EQ(run.wait_exit(150), 0) << run.log();
  // The new work directory (it holds the database) is its owner's alone.
  EXPECT_EQ(fs::status(path("work")).permissions() & (fs::perms::group_all | fs::perms::others_all),
            fs::perms::none);
  const std::string out = run.log();
  EXPECT_NE(out.find("resolution full factorial"), std::string::npos) << out;
  EXPECT_NE(out.find("== packing.solid_fraction (5 of 5 runs) =="), std::string::npos) << out;
  EXPECT_NE(out.find("alias chain"), std::string::npos);
  EXPECT_NE(out.find("proposed parameter set"), std::string::npos);
  EXPECT_NE(out.find("verification: done, 1 simulation(s) added by the calibration"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("round 1 (stage 1, batch 1): done"), std::string::npos) << out;
  // Both local workers ran jobs side by side (--workers 2), by the jobs table of the file.
  std::map<std::string, int> jobs_by_worker;
  each_row(path("work/campaign.db"), "SELECT worker, COUNT(*) FROM jobs GROUP BY worker",
           [&](sqlite3_stmt* st) {
             jobs_by_worker[reinterpret_cast<const char*>(sqlite3_column_text(st, 0))] =
                 sqlite3_column_int(st, 1);
           });
  EXPECT_GE(jobs_by_worker["embedded-1"], 1) << out;
  EXPECT_GE(jobs_by_worker["embedded-2"], 1) << out;
  EXPECT_EQ(jobs_by_worker["embedded-1"] + jobs_by_worker["embedded-2"], 6);  // 5 runs + verify
  // Every stored result carries the worker's cost block, with its phases and steps.
  int with_cost = 0;
  each_row(path("work/campaign.db"), "SELECT cost_json FROM results", [&](sqlite3_stmt* st) {
    const auto cost =
        nlohmann::json::parse(reinterpret_cast<const char*>(sqlite3_column_text(st, 0)));
    EXPECT_GT(std::stoll(cost.at("steps").get<std::string>()), 0) << cost.dump();
    EXPECT_EQ(cost.at("phases").at(1).at("name"), "settle") << cost.dump();
    ++with_cost;
  });
  EXPECT_EQ(with_cost, 6);
  // Run again with --format json: the campaign resumes, and standard output is one JSON
  // document (design, effects, calibration); progress went to standard error.
  Process again({DEMCAL_CLI_BIN, "run", spec, "--workdir", path("work"), "--format", "json"},
                path("again.json"), path("again.err"));
  ASSERT_EQ(again.wait_exit(120), 0) << again.log();
  const auto doc = nlohmann::json::parse(again.log());
  EXPECT_EQ(doc.at("design").at("runs"), 5);
  EXPECT_EQ(doc.at("effects").at("metrics").size(), 2u);
  EXPECT_EQ(doc.at("calibration").at("rounds").size(), 1u);
  EXPECT_EQ(doc.at("calibration").at("simulations"), 1);
  // A bad spec is refused before anything runs, naming the file, line and field.
  std::string bad = tiny_spec(60);
  bad.replace(bad.find("density: 2500"), 13, "densty: 2500");
  std::ofstream(path("bad.yaml")) << bad;
  Process refused({DEMCAL_CLI_BIN, "run", path("bad.yaml"), "--workdir", path("work2")},
                  path("bad.log"));
  EXPECT_EQ(refused.wait_exit(30), 2);
  EXPECT_NE(refused.log().find("bad.yaml:8: material.densty"), std::string::npos) << refused.log();
}

// The embedded default stopped mid-job, by a signal or killed outright, counts no attempt
// against the job it was running: on SIGINT its workers give their leases back and it exits
// 130; after a SIGKILL the next run finds the lease in the file and gives it back at start-up.
// Interrupted as often as a long campaign spread over sessions is, no job fails for it.
TEST_F(Service, TheEmbeddedDefaultInterruptedCountsNoAttemptAgainstItsJobs) {
  const std::string spec = path("interrupted.yaml");
  std::ofstream(spec) << wall_friction_spec("interrupted", "");
  const std::string db = path("work/campaign.db");
  const std::vector<std::string> argv{DEMCAL_CLI_BIN, "run", spec,        "--workdir", path("work"),
                                      "--workers",    "1",   "--threads", "1"};
  auto leased = [&] {
    return !polled_ids(db, "SELECT id FROM jobs WHERE state = 'leased'").empty();
  };
  auto counted = [&] {
    std::map<std::int64_t, int> by_job;
    each_row(db, "SELECT id, counted FROM jobs", [&](sqlite3_stmt* st) {
      by_job[sqlite3_column_int64(st, 0)] = sqlite3_column_int(st, 1);
    });
    return by_job;
  };
  {
    Process run(argv, path("run1.log"));
    ASSERT_TRUE(wait_until(leased, 60)) << run.log();
    run.signal(SIGINT);
    EXPECT_EQ(run.wait_exit(40), 128 + SIGINT) << run.log();
    EXPECT_NE(run.log().find("giving the running jobs back"), std::string::npos) << run.log();
  }
  EXPECT_FALSE(leased());  // given back before the exit
  for (const auto& [job, n] : counted()) EXPECT_LE(n, 1) << job;
  {
    Process run(argv, path("run2.log"));
    ASSERT_TRUE(wait_until(leased, 60)) << run.log();
    run.signal(SIGKILL);
    EXPECT_EQ(run.wait_exit(10), 128 + SIGKILL);
  }
  EXPECT_TRUE(leased());  // the killed run's lease is still in the file
  Process last(argv, path("run3.log"));
  ASSERT_EQ(last.wait_exit(150), 0) << last.log();
  int given_back = 0;
  each_row(db, "SELECT state, counted, attempt, error FROM jobs", [&](sqlite3_stmt* st) {
    EXPECT_STREQ(reinterpret_cast<const char*>(sqlite3_column_text(st, 0)), "done");
    EXPECT_EQ(sqlite3_column_int(st, 1), 1);  // only the lease that finished counts
    given_back += sqlite3_column_int(st, 2) > 1;
  });
  EXPECT_GE(given_back, 1);
}

// `demcal give-up SPEC` on the embedded default: through the campaign's `demcal run` while that
// one holds the store (the address it left in the work directory), which goes on to the
// campaign's end without the job; refused while a holder left no address it may use (a file
// others could read), and where there is no store; on the store itself once no run holds it.
TEST_F(Service, GiveUpOnTheEmbeddedDefaultReachesTheRunningCoordinatorOrChangesTheStore) {
  const std::string spec = path("gaveup.yaml");
  std::ofstream(spec) << wall_friction_spec("gaveup", "");
  const std::string db = path("work/campaign.db");
  // The last job in `state`, 0 if none.
  auto job_in = [&](const std::string& state) {
    const auto ids =
        polled_ids(db, "SELECT id FROM jobs WHERE state = '" + state + "' ORDER BY id");
    return ids.empty() ? std::int64_t{0} : ids.back();
  };
  auto give_up = [&](const std::string& log, const std::string& workdir, std::int64_t job) {
    Process p({DEMCAL_CLI_BIN, "give-up", spec, "--workdir", workdir, "--job", std::to_string(job),
               "--reason", "creeps"},
              path(log));
    const int status = p.wait_exit(60);
    return std::pair(status, p.log());
  };
  const auto [none, none_log] = give_up("none.log", path("elsewhere"), 1);
  EXPECT_NE(none, 0);
  EXPECT_NE(none_log.find("no campaign store"), std::string::npos) << none_log;
  EXPECT_FALSE(fs::exists(path("elsewhere/campaign.db")));
  const std::vector<std::string> run_argv{
      DEMCAL_CLI_BIN, "run", spec,        "--workdir", path("work"),
      "--workers",    "1",   "--threads", "1",         "--no-verify"};
  auto given_up = [&] {
    int n = 0;
    each_row(db, "SELECT COUNT(*) FROM jobs WHERE error LIKE 'given up%'",
             [&](sqlite3_stmt* st) { n = sqlite3_column_int(st, 0); });
    return n;
  };
  const fs::path address = path("work/coordinator.json");
  {
    Process run(run_argv, path("run1.log"));
    ASSERT_TRUE(wait_until([&] { return job_in("leased") != 0 && fs::exists(address); }, 60))
        << run.log();
    EXPECT_EQ(fs::status(address).permissions() & fs::perms::all,
              fs::perms::owner_read | fs::perms::owner_write);
    // An address others could read is not used: refused, naming the holder.
    fs::permissions(address, fs::perms::group_read, fs::perm_options::add);
    const auto [open, open_log] = give_up("open.log", path("work"), job_in("leased"));
    EXPECT_NE(open, 0);
    EXPECT_NE(open_log.find("held by a running coordinator"), std::string::npos) << open_log;
    EXPECT_NE(open_log.find(db), std::string::npos) << open_log;
    run.signal(SIGINT);
    EXPECT_EQ(run.wait_exit(40), 128 + SIGINT) << run.log();
  }
  EXPECT_FALSE(fs::exists(address));  // a stopped run takes its address away
  EXPECT_EQ(given_up(), 0);           // the refused give-up changed nothing
  std::int64_t leased = 0;
  {
    Process run(run_argv, path("run2.log"));
    ASSERT_TRUE(wait_until([&] { return job_in("leased") != 0 && fs::exists(address); }, 60))
        << run.log();
    leased = job_in("leased");
    const auto [live, live_log] = give_up("live.log", path("work"), leased);
    ASSERT_EQ(live, 0) << live_log;
    EXPECT_NE(live_log.find("reaching it at 127.0.0.1:"), std::string::npos) << live_log;
    EXPECT_NE(live_log.find("given up: creeps"), std::string::npos) << live_log;
    ASSERT_EQ(run.wait_exit(150), 0) << run.log();
  }
  EXPECT_FALSE(fs::exists(address));
  std::map<std::string, int> states;
  each_row(db, "SELECT state FROM jobs", [&](sqlite3_stmt* st) {
    ++states[reinterpret_cast<const char*>(sqlite3_column_text(st, 0))];
  });
  EXPECT_EQ(states["done"], 3);
  EXPECT_EQ(states["failed"], 1);
  EXPECT_EQ(job_in("failed"), leased);
  EXPECT_EQ(given_up(), 1);
  // With no run holding it, the store itself: the job has ended.
  const auto [again, again_log] = give_up("again.log", path("work"), leased);
  EXPECT_NE(again, 0);
  EXPECT_NE(again_log.find("is failed"), std::string::npos) << again_log;
}

// `demcal status SPEC` of a campaign whose `demcal run` holds the store asks that run's
// coordinator. Where the run left no address, it reads a copy of the store, with that run's lease
// (its job in flight shows as running) and rated from that run's start (its lock file's date):
// once a job of the run has ended, it shows an ETA.
TEST_F(Service, StatusOfACampaignRunningInAnotherProcessShowsAnEta) {
  const std::string spec = path("held.yaml");
  std::ofstream(spec) << wall_friction_spec("held", "");
  const std::string db = path("work/campaign.db");
  Process run({DEMCAL_CLI_BIN, "run", spec, "--workdir", path("work"), "--workers", "1",
               "--threads", "1", "--no-verify"},
              path("run.log"));
  auto in = [&](const char* state) {
    return !polled_ids(db, std::string("SELECT id FROM jobs WHERE state = '") + state + "'")
                .empty();
  };
  ASSERT_TRUE(
      wait_until([&] { return in("leased") && fs::exists(path("work/coordinator.json")); }, 90))
      << run.log();
  {
    Process live({DEMCAL_CLI_BIN, "status", spec, "--workdir", path("work")}, path("live.log"));
    ASSERT_EQ(live.wait_exit(60), 0) << live.log();
    EXPECT_NE(live.log().find("reaching it at 127.0.0.1:"), std::string::npos) << live.log();
    EXPECT_EQ(live.log().find("copy"), std::string::npos) << live.log();
    EXPECT_NE(live.log().find("/4 done"), std::string::npos) << live.log();  // its progress
  }
  // Frozen (SIGSTOP: the run holds its store, its progress stops while the copy is read) with a
  // job done, one running and one queued; a freeze between two leases is thawed and tried again.
  // Its address is taken away, as a run of an earlier build leaves none.
  fs::remove(path("work/coordinator.json"));
  bool frozen = false;
  for (int attempt = 0; attempt < 5 && !frozen; ++attempt) {
    ASSERT_TRUE(wait_until([&] { return in("done") && in("leased") && in("queued"); }, 90))
        << run.log();
    run.signal(SIGSTOP);
    frozen = in("leased") && in("queued");
    if (!frozen) run.signal(SIGCONT);
  }
  ASSERT_TRUE(frozen) << run.log();
  Process status({DEMCAL_CLI_BIN, "status", spec, "--workdir", path("work")}, path("status.log"));
  const int exit_status = status.wait_exit(60);
  run.signal(SIGCONT);
  run.signal(SIGINT);
  EXPECT_EQ(run.wait_exit(40), 128 + SIGINT) << run.log();
  ASSERT_EQ(exit_status, 0) << status.log();
  EXPECT_NE(status.log().find("held by a running coordinator"), std::string::npos) << status.log();
  EXPECT_NE(status.log().find(", 1 running,"), std::string::npos) << status.log();  // its lease
  EXPECT_NE(status.log().find(", ETA "), std::string::npos) << status.log();
  EXPECT_EQ(status.log().find("ETA --:--"), std::string::npos) << status.log();
}

TEST_F(Service, AnExportLargerThanAGrpcMessageArrivesWhole) {
  // Synthetic results through the real worker protocol, no physics: each with a cost block of
  // 5,000 long-named phases (about 1.5 MB of JSON), so that the export exceeds gRPC's 4 MB.
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(30), &id).ok());  // 4 jobs
  for (int k = 0; k < 4; ++k)
    ASSERT_NO_FATAL_FAILURE(complete_fake_job([&](const v1::JobSpec&, v1::CompleteRequest& c) {
      (*c.mutable_metrics())["solid_fraction"] = 0.55 + 0.01 * k;
      (*c.mutable_metrics())["coordination_number"] = 4.0;
      for (int p = 0; p < 5000; ++p) {
        auto* phase = c.mutable_cost()->add_phases();
        phase->set_name("phase " + std::to_string(p) + std::string(200, '.'));
        phase->set_steps(p);
      }
    }));
  ASSERT_TRUE(campaign_done(id));
  const auto exported =
      cli_json(dir_, "export", {"export", std::to_string(id), "--format", "json"}, channel_);
  EXPECT_GT(fs::file_size(path("export.json")), 4u << 20);
  ASSERT_EQ(exported.at("jobs").size(), 4u);
  for (const auto& j : exported.at("jobs")) EXPECT_EQ(j.at("cost").at("phases").size(), 5000u);
}

}  // namespace
}  // namespace demcal::test
