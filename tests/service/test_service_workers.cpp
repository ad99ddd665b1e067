// Service tests with real processes, real gRPC on loopback and real SQLite files (the fixture:
// service_fixture.hpp). The worker side: leases, checkpoints, late and refused results, curves,
// cancellation, a worker's limits and threads, workers racing, a worker and the coordinator
// SIGKILLed. Leases and heartbeats are short (flags); every wait is bounded.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <thread>

#include "client/service_client.hpp"
#include "client/spec_yaml.hpp"
#include "core/common/error.hpp"
#include "core/lab/lab_run.hpp"
#include "core/lab/protocol.hpp"
#include "demcal/v1/campaign.grpc.pb.h"
#include "demcal/v1/worker.grpc.pb.h"
#include "rpc/channel.hpp"
#include "rpc/material_convert.hpp"
#include "server/limits.hpp"
#include "tests/service/service_fixture.hpp"

namespace demcal::test {
namespace {

/// The Fail of a worker giving back its lease of `job` (retryable, not counted).
v1::FailRequest give_back_request(const v1::JobSpec& job, const std::string& worker) {
  v1::FailRequest f;
  f.set_job_id(job.job_id());
  f.set_attempt(job.attempt());
  f.set_worker(worker);
  f.set_retryable(true);
  f.set_give_back(true);
  return f;
}

// A job's checkpoint goes from the lease that sent it to the job's next lease, and a real worker
// goes on from it to the result of a run that was never interrupted, to the bit.
TEST_F(Service, AReleasedJobGoesOnFromItsCheckpointToTheUninterruptedResult) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  const std::string spec = wall_friction_spec("checkpointed",
                                              "measurements:\n  - {metric: wall_friction_angle, "
                                              "value: 20, uncertainty: 1}\n");
  std::int64_t id = 0;
  ASSERT_TRUE(submit(spec, &id).ok());
  v1::LeaseReply first;
  ASSERT_NO_FATAL_FAILURE(lease_as("first", first));
  ASSERT_TRUE(first.has_job());
  const v1::JobSpec& job = first.job();
  EXPECT_TRUE(job.checkpoint_stage().empty());
  // The first worker's run, as the worker runs it, keeping the checkpoints it offers; it sends
  // the one after its first normal stress (the bed and a turn done), then stops and gives the
  // lease back.
  lab::RunOptions options;
  options.seed = job.seed() ? job.seed() : 1;  // as the worker
  std::vector<lab::Checkpoint> offered;
  std::vector<lab::CheckpointClock> clocks;
  options.checkpoint = [&offered, &clocks](const std::string& stage,
                                           const lab::CheckpointClock& clock,
                                           const std::function<std::string()>& record) {
    offered.push_back({stage, record()});
    clocks.push_back(clock);
  };
  const lab::LabOutput whole = lab::run_lab_test(job.test(), rpc::job_material(job),
                                                 rpc::to_settings(job.settings()), options);
  // The checkpoints inside the settle and the bed's come first, then one per turn.
  auto is_turn = [](const lab::Checkpoint& c) { return c.stage.rfind("turn ", 0) == 0; };
  const auto first_turn = std::find_if(offered.begin(), offered.end(), is_turn);
  ASSERT_NE(first_turn, offered.end());
  const auto turns = std::count_if(offered.begin(), offered.end(), is_turn);
  ASSERT_GE(turns, 2);
  const lab::Checkpoint kept = *first_turn;
  const lab::CheckpointClock kept_clock = clocks[std::size_t(first_turn - offered.begin())];
  ASSERT_GT(kept_clock.steps, 0);
  v1::CheckpointRequest cp;
  cp.set_job_id(job.job_id());
  cp.set_attempt(job.attempt());
  cp.set_worker("intruder");
  cp.set_stage(kept.stage);
  cp.set_state(kept.state);
  cp.set_simulated_seconds(kept_clock.simulated_seconds);
  cp.set_steps(kept_clock.steps);
  v1::CheckpointReply cpr;
  EXPECT_EQ(workers_stub_->Checkpoint(ctx().get(), cp, &cpr).error_code(),
            grpc::StatusCode::PERMISSION_DENIED);
  cp.set_worker("first");
  v1::CheckpointRequest unnamed = cp;
  unnamed.set_stage("");
  EXPECT_EQ(workers_stub_->Checkpoint(ctx().get(), unnamed, &cpr).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
  for (const double bad : {std::nan(""), -1.0, HUGE_VAL}) {
    v1::CheckpointRequest unclocked = cp;
    unclocked.set_simulated_seconds(bad);
    EXPECT_EQ(workers_stub_->Checkpoint(ctx().get(), unclocked, &cpr).error_code(),
              grpc::StatusCode::INVALID_ARGUMENT)
        << bad;
  }
  v1::CheckpointRequest negative_steps = cp;
  negative_steps.set_steps(-1);
  EXPECT_EQ(workers_stub_->Checkpoint(ctx().get(), negative_steps, &cpr).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
  ASSERT_TRUE(workers_stub_->Checkpoint(ctx().get(), cp, &cpr).ok());
  v1::FailReply fr;
  ASSERT_TRUE(workers_stub_->Fail(ctx().get(), give_back_request(job, "first"), &fr).ok());
  // Queued again, the job shows the checkpoint it goes on from, in the results and in the job
  // list of `demcal status --jobs`.
  const double before =
      std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  const v1::ResultsReply queued = results(id);
  for (const auto& j : queued.jobs())
    if (j.job_id() == job.job_id()) {
      EXPECT_EQ(j.state(), "queued");
      EXPECT_EQ(j.checkpoint_stage(), kept.stage);
      EXPECT_GT(j.checkpoint_saved(), before - 600.0);
      EXPECT_LE(j.checkpoint_saved(), before);
      EXPECT_EQ(j.checkpoint_simulated_seconds(), kept_clock.simulated_seconds);
      EXPECT_EQ(j.checkpoint_steps(), kept_clock.steps);
    } else {
      EXPECT_TRUE(j.checkpoint_stage().empty());
    }
  const std::string listed =
      cli_text(dir_, "status_checkpoint.txt", {"status", std::to_string(id), "--jobs"}, channel_);
  EXPECT_NE(listed.find("job " + std::to_string(job.job_id()) + " "), std::string::npos) << listed;
  EXPECT_NE(listed.find("checkpoint '" + kept.stage + "' (kept 20"), std::string::npos) << listed;
  EXPECT_NE(listed.find(" s simulated, " + std::to_string(kept_clock.steps) + " steps)"),
            std::string::npos)
      << listed;
  // A real worker leases the job again with its checkpoint and goes on from it, sending every
  // checkpoint it passes with the run's clock, which goes on from the kept one's.
  Process& second =
      start_worker("second", kToken, {"--max-jobs", "1", "--checkpoint-seconds", "0"});
  std::optional<v1::JobResult> stored;
  ASSERT_TRUE(wait_until(
      [&] {
        const auto now = results(id);
        for (const auto& j : now.jobs())
          if (j.job_id() == job.job_id() && j.state() == "done") stored = j;
        return stored.has_value();
      },
      120))
      << second.log();
  EXPECT_NE(second.log().find("going on from checkpoint '" + kept.stage + "'"), std::string::npos)
      << second.log();
  const std::regex sent(
      R"(checkpoint '[^']+' sent \(\d+ bytes, at \S+ s simulated, (\d+) steps\))");
  std::vector<std::int64_t> sent_steps;
  const std::string log = second.log();
  for (auto it = std::sregex_iterator(log.begin(), log.end(), sent); it != std::sregex_iterator();
       ++it)
    sent_steps.push_back(std::stoll((*it)[1].str()));
  ASSERT_FALSE(sent_steps.empty()) << log;
  for (const auto steps : sent_steps) EXPECT_GT(steps, kept_clock.steps) << log;
  EXPECT_EQ(stored->attempt(), 2);
  ASSERT_EQ(stored->metrics().size(), whole.metrics.size());
  for (const auto& [name, value] : whole.metrics)
    EXPECT_EQ(stored->metrics().at(name), value) << name;  // exact: the same bits
  // The phases up to the stage are the first run's (their wall times carried in the checkpoint),
  // those after it the second's.
  ASSERT_EQ(stored->cost().phases_size(), static_cast<int>(whole.cost.phases.size()));
  EXPECT_EQ(stored->cost().phases(0).name(), "fill");
  EXPECT_EQ(stored->cost().phases(0).wall_seconds(), whole.cost.phases[0].wall_seconds);
  const int turned = static_cast<int>(whole.cost.phases.size()) - 1 -
                     2 * static_cast<int>(turns - 1);  // the first turn's phase
  EXPECT_EQ(stored->cost().phases(turned).name(), kept.stage);
  EXPECT_EQ(stored->cost().phases(turned).wall_seconds(), whole.cost.phases[turned].wall_seconds);
  EXPECT_EQ(stored->cost().steps(), whole.cost.steps);
  EXPECT_TRUE(stored->checkpoint_stage().empty());
  // A stored result drops its job's checkpoint.
  int checkpoints = -1;
  each_row(path("c.db"), "SELECT COUNT(*) FROM checkpoints",
           [&](sqlite3_stmt* st) { checkpoints = sqlite3_column_int(st, 0); });
  EXPECT_EQ(checkpoints, 0);
}

// With --yield-after, a lease that has run past its share while a job waits is asked to yield:
// the job is given back at the checkpoint its run keeps next and goes behind the jobs that
// yielded fewer times, so the short runs finish first; a real worker does so by itself. A job
// that yielded by hand, and then went on under the worker (which may make it yield again), ends
// with the result of a run never interrupted, to the bit.
TEST_F(Service, ALongRunYieldsAtACheckpointAndEndsWithTheUninterruptedResult) {
  start_server(/*lease=*/30, /*heartbeat=*/0.3, 0, {"--yield-after", "1"});
  std::int64_t id = 0;
  // Three runs of 20 particles, a few seconds each: a 2^1 in the wall's friction and a centre run.
  std::string spec = wall_friction_spec("yielding", "");
  spec.replace(spec.find("particles: 30"), std::string("particles: 30").size(), "particles: 20");
  spec.replace(spec.find("  - {path: wall_law.tangential.mu_s, low: 0.2, high: 0.4}\n"),
               std::string("  - {path: wall_law.tangential.mu_s, low: 0.2, high: 0.4}\n").size(),
               "");
  spec.replace(spec.find("design: {type: full_factorial}"),
               std::string("design: {type: full_factorial}").size(),
               "design: {type: full_factorial, centre_points: 1}");
  ASSERT_TRUE(submit(spec, &id).ok());
  v1::LeaseReply first;
  ASSERT_NO_FATAL_FAILURE(lease_as("first", first));
  ASSERT_TRUE(first.has_job());
  const v1::JobSpec job = first.job();
  const auto beat = [&](const std::string& worker) {
    v1::HeartbeatRequest h;
    h.set_job_id(job.job_id());
    h.set_attempt(job.attempt());
    h.set_worker(worker);
    v1::HeartbeatReply hr;
    EXPECT_TRUE(workers_stub_->Heartbeat(ctx().get(), h, &hr).ok());
    return hr.yield_at_checkpoint();
  };
  EXPECT_FALSE(beat("first"));  // within its share
  // Its run as the worker runs it, keeping the checkpoints it offers.
  lab::RunOptions options;
  options.seed = job.seed() ? job.seed() : 1;
  std::vector<lab::Checkpoint> offered;
  options.checkpoint = [&offered](const std::string& stage, const lab::CheckpointClock&,
                                  const std::function<std::string()>& record) {
    offered.push_back({stage, record()});
  };
  const auto started = std::chrono::steady_clock::now();
  const lab::LabOutput whole = lab::run_lab_test(job.test(), rpc::job_material(job),
                                                 rpc::to_settings(job.settings()), options);
  std::this_thread::sleep_until(started + std::chrono::milliseconds(1200));
  EXPECT_TRUE(beat("first"));  // past its second, two jobs waiting
  ASSERT_GE(offered.size(), 2u);
  v1::CheckpointRequest cp;
  cp.set_job_id(job.job_id());
  cp.set_attempt(job.attempt());
  cp.set_worker("first");
  cp.set_stage(offered.front().stage);
  cp.set_state(offered.front().state);
  v1::CheckpointReply cpr;
  ASSERT_TRUE(workers_stub_->Checkpoint(ctx().get(), cp, &cpr).ok());
  v1::FailRequest yielded = give_back_request(job, "first");
  yielded.set_yielded(true);
  yielded.set_give_back(false);
  v1::FailReply fr;
  EXPECT_EQ(workers_stub_->Fail(ctx().get(), yielded, &fr).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);  // a yield gives the lease back
  yielded.set_give_back(true);
  ASSERT_TRUE(workers_stub_->Fail(ctx().get(), yielded, &fr).ok());
  // The next lease passes it by; held here until a real worker runs the third job, then given
  // back (not yielded), so that the worker's job has one waiting that never yielded.
  v1::LeaseReply second;
  ASSERT_NO_FATAL_FAILURE(lease_as("second", second));
  ASSERT_TRUE(second.has_job());
  EXPECT_NE(second.job().job_id(), job.job_id());
  Process& worker = start_worker("real", kToken, {"--checkpoint-seconds", "60"});
  ASSERT_TRUE(wait_until(
      [&] {
        const auto now = results(id);
        for (const auto& j : now.jobs())
          if (j.state() == "leased" && j.job_id() != second.job().job_id()) return true;
        return false;
      },
      30))
      << worker.log();
  ASSERT_TRUE(
      workers_stub_->Fail(ctx().get(), give_back_request(second.job(), "second"), &fr).ok());
  ASSERT_TRUE(wait_until([&] { return campaign_done(id); }, 180)) << worker.log();
  // The worker yielded: its job once, and then one of the two that had yielded once.
  const std::string log = worker.log();
  std::size_t yields = 0;
  for (auto at = log.find("yielded at its checkpoint"); at != std::string::npos;
       at = log.find("yielded at its checkpoint", at + 1))
    ++yields;
  EXPECT_GE(yields, 2u) << log;
  std::map<std::int64_t, double> finished;
  each_row(path("c.db"), "SELECT id, finished FROM jobs", [&](sqlite3_stmt* st) {
    finished[sqlite3_column_int64(st, 0)] = sqlite3_column_double(st, 1);
  });
  // The job the second lease passed over finished first; the one yielded by hand goes on from
  // its checkpoints to the uninterrupted result. The results say how often each yielded.
  std::map<std::int64_t, v1::JobResult> done;
  const auto stored = results(id);
  for (const auto& j : stored.jobs()) done[j.job_id()] = j;
  ASSERT_EQ(done.size(), 3u);
  EXPECT_GE(done.at(job.job_id()).yields(), 1);
  EXPECT_EQ(done.at(second.job().job_id()).yields(), 0);  // given back, never yielded
  for (const auto& [jid, j] : done) {
    EXPECT_EQ(j.state(), "done");
    if (jid != second.job().job_id()) {
      EXPECT_GT(finished.at(jid), finished.at(second.job().job_id()));
    }
  }
  const v1::JobResult& resumed = done.at(job.job_id());
  ASSERT_EQ(resumed.metrics().size(), whole.metrics.size());
  for (const auto& [name, value] : whole.metrics)
    EXPECT_EQ(resumed.metrics().at(name), value) << name;  // exact: the same bits
  EXPECT_EQ(resumed.cost().steps(), whole.cost.steps);
}

TEST_F(Service, LateCompleteFromAnExpiredLeaseIsRejectedAndNotStored) {
  start_server(/*lease=*/1.0, /*heartbeat=*/0.2);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(30), &id).ok());
  v1::LeaseReply first;
  ASSERT_NO_FATAL_FAILURE(lease_as("slow", first));
  ASSERT_TRUE(first.has_job());
  const auto job = first.job().job_id();
  std::this_thread::sleep_for(std::chrono::milliseconds(1600));  // lease lapses, reaper runs
  v1::CompleteRequest late;
  late.set_job_id(job);
  late.set_attempt(1);
  late.set_worker("slow");
  (*late.mutable_metrics())["solid_fraction"] = 0.1;
  (*late.mutable_metrics())["coordination_number"] = 1.0;
  v1::CompleteReply cr;
  EXPECT_EQ(workers_stub_->Complete(ctx().get(), late, &cr).error_code(),
            grpc::StatusCode::FAILED_PRECONDITION);
  v1::HeartbeatRequest hb;
  hb.set_job_id(job);
  hb.set_attempt(1);
  v1::HeartbeatReply hr;
  EXPECT_EQ(workers_stub_->Heartbeat(ctx().get(), hb, &hr).error_code(),
            grpc::StatusCode::FAILED_PRECONDITION);
  // The job is handed out again, with the next attempt number.
  v1::LeaseReply second;
  ASSERT_NO_FATAL_FAILURE(lease_as("fast", second));
  ASSERT_EQ(second.job().job_id(), job);
  EXPECT_EQ(second.job().attempt(), 2);
  EXPECT_EQ(workers_stub_->Complete(ctx().get(), late, &cr).error_code(),
            grpc::StatusCode::FAILED_PRECONDITION);
  v1::CompleteRequest good = late;
  good.set_attempt(2);
  good.set_worker("fast");
  (*good.mutable_metrics())["solid_fraction"] = 0.58;
  // A non-finite metric or wall time is refused and the lease stays the worker's.
  v1::CompleteRequest nan_metric = good, nan_time = good;
  (*nan_metric.mutable_metrics())["solid_fraction"] = std::nan("");
  nan_time.set_wall_seconds(std::numeric_limits<double>::infinity());
  for (const auto* bad : {&nan_metric, &nan_time}) {
    const auto st = workers_stub_->Complete(ctx().get(), *bad, &cr);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << st.error_message();
  }
  // Only the lease's holder may report it; another worker is denied and changes nothing.
  v1::CompleteRequest intruder = good;
  intruder.set_worker("intruder");
  EXPECT_EQ(workers_stub_->Complete(ctx().get(), intruder, &cr).error_code(),
            grpc::StatusCode::PERMISSION_DENIED);
  v1::FailRequest intruder_fail;
  intruder_fail.set_job_id(job);
  intruder_fail.set_attempt(2);
  intruder_fail.set_worker("intruder");
  v1::FailReply fr;
  EXPECT_EQ(workers_stub_->Fail(ctx().get(), intruder_fail, &fr).error_code(),
            grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_TRUE(workers_stub_->Complete(ctx().get(), good, &cr).ok());
  // A retry of the stored result (its answer lost on the way) succeeds; another result does not.
  EXPECT_TRUE(workers_stub_->Complete(ctx().get(), good, &cr).ok());
  v1::CompleteRequest other = good;
  (*other.mutable_metrics())["solid_fraction"] = 0.59;
  EXPECT_EQ(workers_stub_->Complete(ctx().get(), other, &cr).error_code(),
            grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_EQ(stored_results().at(job), 1);
  const auto after = results(id);
  for (const auto& j : after.jobs())
    if (j.job_id() == job) {
      EXPECT_EQ(j.state(), "done");
      EXPECT_EQ(j.attempt(), 2);
      EXPECT_EQ(j.worker(), "fast");
      EXPECT_DOUBLE_EQ(j.metrics().at("solid_fraction"), 0.58);
    }
}

// A result's curves: checked at the door (the field named, the lease kept), stored with the
// result, and exported with it on request (json only).
TEST_F(Service, AResultsCurvesAreCheckedStoredAndExported) {
  start_server();
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(30), &id).ok());
  v1::JobSpec job;
  v1::CompleteRequest good;
  ASSERT_NO_FATAL_FAILURE(lease_request("w", job, good));
  (*good.mutable_metrics())["solid_fraction"] = 0.6;
  auto* curve = good.add_series();
  curve->set_name("stress_strain");
  for (const char* c : {"strain", "stress_kPa"}) curve->add_columns(c);
  for (double v : {0.0, 0.0, 0.01, 5.0, 0.02, 15.0}) curve->add_values(v);

  const std::vector<std::pair<std::function<void(v1::Series&)>, std::string>> spoiled = {
      {[](v1::Series& s) { s.set_values(3, std::nan("")); }, "series[0].values[3]"},
      {[](v1::Series& s) { s.add_values(1.0); }, "series[0].values"},
      {[](v1::Series& s) { s.set_name("a b"); }, "series[0].name"},
      {[](v1::Series& s) { s.clear_columns(); }, "series[0].columns"},
      {[](v1::Series& s) {
         for (int r = 0; r < 2001; ++r) s.add_values(0.0), s.add_values(0.0);
       },
       "series[0].values"},
  };
  v1::CompleteReply cr;
  for (const auto& [spoil, field] : spoiled) {
    v1::CompleteRequest bad = good;
    spoil(*bad.mutable_series(0));
    const auto st = workers_stub_->Complete(ctx().get(), bad, &cr);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << field;
    EXPECT_NE(st.error_message().find(field), std::string::npos) << st.error_message();
  }
  v1::CompleteRequest twice = good;
  *twice.add_series() = good.series(0);
  EXPECT_EQ(workers_stub_->Complete(ctx().get(), twice, &cr).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
  ASSERT_TRUE(workers_stub_->Complete(ctx().get(), good, &cr).ok()) << "the lease was kept";

  std::string content;
  ASSERT_TRUE(cli::read_export(*campaigns_, channel_, id, "json", content, true).ok());
  bool found = false;
  const auto exported = nlohmann::json::parse(content);
  for (const auto& row : exported.at("jobs")) {
    ASSERT_TRUE(row.contains("series"));
    if (row["job_id"] != good.job_id()) continue;
    found = true;
    const auto& s = row["series"]["stress_strain"];
    EXPECT_EQ(s["columns"], nlohmann::json({"strain", "stress_kPa"}));
    EXPECT_EQ(s["rows"], nlohmann::json({{0.0, 0.0}, {0.01, 5.0}, {0.02, 15.0}}));
  }
  EXPECT_TRUE(found);
  ASSERT_TRUE(cli::read_export(*campaigns_, channel_, id, "json", content).ok());
  EXPECT_EQ(content.find("\"series\""), std::string::npos) << "curves only when asked for";
  const auto csv = cli::read_export(*campaigns_, channel_, id, "csv", content, true);
  EXPECT_EQ(csv.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

TEST_F(Service, AResultFinishedWhileTheCoordinatorWasDownLongerThanTheLeaseIsAccepted) {
  // With one attempt per job, a lease expired by the coordinator's own downtime would fail the
  // job although its simulation succeeded, and a second attempt would run it again.
  const std::vector<std::string> one_attempt{"--max-attempts", "1"};
  start_server(/*lease=*/2, /*heartbeat=*/0.3, 0, one_attempt);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(400), &id).ok());  // 4 jobs of ~1 s
  start_worker("w");
  ASSERT_NE(wait_for_job(id, "leased", 30), 0);
  const int port = port_;
  server_->signal(SIGTERM);
  ASSERT_EQ(server_->wait_exit(20), 0) << server_->log();
  std::this_thread::sleep_for(std::chrono::milliseconds(3500));  // down longer than the lease
  start_server(2, 0.3, port, one_attempt);
  ASSERT_TRUE(wait_until([&] { return campaign_done(id); }, 120)) << workers_[0]->log();
  const auto r = results(id);
  const auto stored = stored_results();
  ASSERT_EQ(r.jobs_size(), 4);
  for (const auto& j : r.jobs()) {
    EXPECT_EQ(j.state(), "done") << j.error();
    EXPECT_EQ(j.attempt(), 1) << "job " << j.job_id() << " ran again";
    EXPECT_EQ(stored.count(j.job_id()), 1u);
  }
  EXPECT_EQ(workers_[0]->log().find("refused the report"), std::string::npos) << workers_[0]->log();
}

TEST_F(Service, CancellingACampaignStopsTheWorkersSimulationAndFreesTheWorker) {
  start_server(/*lease=*/30, /*heartbeat=*/0.3);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(kLongJobParticles), &id).ok());  // jobs of minutes
  auto& worker = start_worker("w");
  ASSERT_NE(wait_for_job(id, "leased", 30), 0);
  std::this_thread::sleep_for(std::chrono::seconds(1));  // well into the simulation
  v1::CancelRequest cancel;
  cancel.set_id(id);
  v1::Campaign c;
  ASSERT_TRUE(campaigns_->Cancel(ctx().get(), cancel, &c).ok());
  ASSERT_TRUE(
      wait_until([&] { return worker.log().find("simulation stopped") != std::string::npos; }, 60))
      << worker.log();
  // The worker is free again: it runs the next campaign's jobs.
  std::int64_t next = 0;
  ASSERT_TRUE(submit(tiny_spec(30), &next).ok());
  ASSERT_TRUE(wait_until([&] { return campaign_done(next); }, 90)) << worker.log();
  const auto next_results = results(next);
  for (const auto& j : next_results.jobs()) EXPECT_EQ(j.state(), "done") << j.error();
  EXPECT_EQ(stored_results().size(), 4u) << "the cancelled job reported nothing";
}

// Giving up the job a worker runs stops its simulation and fails it with the reason; the worker
// goes on to the next job. Given up one by one (by the CLI, then by RPC), the campaign ends.
// Giving up a job that has ended, of another campaign or without a reason is refused.
TEST_F(Service, GivingUpARunningJobStopsItsSimulationAndTheCampaignGoesOnWithoutIt) {
  start_server(/*lease=*/30, /*heartbeat=*/0.3);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(kLongJobParticles), &id).ok());  // jobs of minutes
  auto& worker = start_worker("w");
  const std::int64_t running = wait_for_job(id, "leased", 30);
  ASSERT_NE(running, 0);
  std::this_thread::sleep_for(std::chrono::seconds(1));  // well into the simulation
  const std::string printed =
      cli_text(dir_, "give-up.out",
               {"give-up", std::to_string(id), "--job", std::to_string(running), "--reason",
                "creeps toward its step limit"},
               channel_);
  EXPECT_NE(printed.find("job " + std::to_string(running)), std::string::npos) << printed;
  EXPECT_NE(printed.find("failed"), std::string::npos) << printed;
  ASSERT_TRUE(
      wait_until([&] { return worker.log().find("simulation stopped") != std::string::npos; }, 60))
      << worker.log();

  v1::GiveUpRequest req;
  req.set_campaign_id(id);
  req.set_job_id(running);
  req.set_reason("again");
  v1::GiveUpReply j;
  EXPECT_EQ(campaigns_->GiveUp(ctx().get(), req, &j).error_code(),
            grpc::StatusCode::FAILED_PRECONDITION);
  req.set_campaign_id(id + 1);
  EXPECT_EQ(campaigns_->GiveUp(ctx().get(), req, &j).error_code(), grpc::StatusCode::NOT_FOUND);
  req.set_campaign_id(id);
  req.set_job_id(running + 100);
  EXPECT_EQ(campaigns_->GiveUp(ctx().get(), req, &j).error_code(), grpc::StatusCode::NOT_FOUND);
  // The rest, queued or leased by the freed worker, one by one; a reason is required.
  const auto before = results(id);
  for (const auto& job : before.jobs()) {
    if (job.state() != "queued" && job.state() != "leased") continue;
    req.set_job_id(job.job_id());
    req.set_reason("");
    EXPECT_EQ(campaigns_->GiveUp(ctx().get(), req, &j).error_code(),
              grpc::StatusCode::INVALID_ARGUMENT);
    req.set_reason("not needed");
    const auto st = campaigns_->GiveUp(ctx().get(), req, &j);
    EXPECT_TRUE(st.ok() || st.error_code() == grpc::StatusCode::FAILED_PRECONDITION)
        << st.error_message();
  }
  ASSERT_TRUE(wait_until([&] { return campaign_done(id); }, 30));
  const auto after = results(id);
  for (const auto& job : after.jobs()) {
    EXPECT_EQ(job.state(), "failed") << job.job_id();
    const std::string reason =
        job.job_id() == running ? "creeps toward its step limit" : "not needed";
    EXPECT_EQ(job.error(), "given up: " + reason);
  }
  EXPECT_TRUE(stored_results().empty()) << "a job given up reported a result";
}

// Giving up a row's compression names the tensile job that waited for it (it conditions its own
// bed now), over gRPC and in the CLI's words.
TEST_F(Service, GivingUpACompressionNamesTheTensileJobThatWaitedForIt) {
  start_server(/*lease=*/30, /*heartbeat=*/0.3);
  std::int64_t id = 0;
  // Planned only, never run: spheres without cohesion do for the jobs' order.
  ASSERT_TRUE(submit(R"(name: waits
material:
  particle_law:
    normal: {model: hertz, youngs_modulus: 2.0e6, restitution: 0.4}
    tangential: {model: history, mu_s: 0.3}
  sizes: {monodisperse: {radius: 5.0e-4}}
  density: 2000
tests:
  - {test: tensile, settings: {particles: 100}}
  - {test: confined_compression, settings: {particles: 100}}
factors:
  - {path: particle_law.tangential.mu_s, low: 0.2, high: 0.4}
  - {path: particle_law.normal.restitution, low: 0.3, high: 0.5}
design: {type: full_factorial}
)",
                     &id)
                  .ok());
  std::map<int, std::int64_t> compression, tensile;  // design row -> job
  const auto jobs = results(id);
  for (const auto& j : jobs.jobs())
    (j.test() == "tensile" ? tensile : compression)[j.std_order()] = j.job_id();
  ASSERT_EQ(compression.size(), 4u);
  v1::GiveUpRequest req;
  req.set_campaign_id(id);
  req.set_job_id(compression[1]);
  req.set_reason("creeping");
  v1::GiveUpReply reply;
  ASSERT_TRUE(campaigns_->GiveUp(ctx().get(), req, &reply).ok());
  EXPECT_EQ(reply.job().state(), "failed");
  ASSERT_EQ(reply.released_size(), 1);
  EXPECT_EQ(reply.released(0).job_id(), tensile[1]);
  EXPECT_EQ(reply.released(0).state(), "queued");
  // A tensile job waits for nothing: giving it up releases none.
  req.set_job_id(tensile[2]);
  ASSERT_TRUE(campaigns_->GiveUp(ctx().get(), req, &reply).ok());
  EXPECT_EQ(reply.released_size(), 0);
  const std::string printed = cli_text(
      dir_, "give-up.out",
      {"give-up", std::to_string(id), "--job", std::to_string(compression[3]), "--reason", "x"},
      channel_);
  EXPECT_NE(printed.find("job " + std::to_string(tensile[3]) + " (tensile) waited for it"),
            std::string::npos)
      << printed;
}

TEST_F(Service, AJobOverTheWorkersLimitsFailsWithTheLimitNamed) {
  start_server(/*lease=*/30, /*heartbeat=*/0.3, 0, {"--max-attempts", "1"});
  // More particles than --max-particles: refused unrun.
  std::int64_t big = 0;
  ASSERT_TRUE(submit(tiny_spec(400), &big).ok());
  auto& small = start_worker("small", kToken, {"--max-particles", "300"});
  ASSERT_TRUE(wait_until([&] { return campaign_done(big); }, 60)) << small.log();
  const auto refused = results(big);
  for (const auto& j : refused.jobs()) {
    EXPECT_EQ(j.state(), "failed");
    EXPECT_NE(j.error().find("400 particles, more than this worker's --max-particles 300"),
              std::string::npos)
        << j.error();
  }
  small.signal(SIGKILL);
  small.wait_exit(10);
  // Longer than --max-job-seconds: the simulation is stopped and the job failed.
  std::int64_t slow = 0;
  ASSERT_TRUE(submit(tiny_spec(kLongJobParticles), &slow).ok());
  auto& hasty = start_worker("hasty", kToken, {"--max-job-seconds", "2"});
  ASSERT_NE(wait_for_job(slow, "failed", 90), 0) << hasty.log();
  bool named = false;
  const auto stopped = results(slow);
  for (const auto& j : stopped.jobs())
    named |= j.error().find("--max-job-seconds 2") != std::string::npos;
  EXPECT_TRUE(named) << hasty.log();
}

TEST_F(Service, ASpecAskingForMoreThreadsThanTheWorkerHasRunsOnTheWorkersThreads) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::string spec = tiny_spec(30);
  spec.replace(spec.find("  - test: packing\n"), 18, "  - test: packing\n    threads: 16\n");
  std::int64_t id = 0;
  ASSERT_TRUE(submit(spec, &id).ok());
  auto& worker = start_worker("w");  // --threads 1
  ASSERT_TRUE(wait_until([&] { return campaign_done(id); }, 90)) << worker.log();
  EXPECT_NE(worker.log().find("on 1 thread(s)"), std::string::npos) << worker.log();
  EXPECT_EQ(worker.log().find("on 16 thread(s)"), std::string::npos) << worker.log();
}

// A result's metric values are finite and within 1e100 in magnitude.
TEST_F(Service, AResultWithAMetricBeyondTheBoundIsRefused) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  ASSERT_TRUE(submit(tiny_spec(30)).ok());
  v1::JobSpec job;
  v1::CompleteRequest c;
  ASSERT_NO_FATAL_FAILURE(lease_request("w1", job, c));
  const std::vector<std::pair<std::map<std::string, double>, std::string>> cases = {
      {{{"solid_fraction", 1e308}}, "metrics.solid_fraction"},
      {{{"solid_fraction", -2e100}}, "metrics.solid_fraction"},
  };
  for (const auto& [metrics, field] : cases) {
    v1::CompleteRequest bad = c;
    for (const auto& [k, v] : metrics) (*bad.mutable_metrics())[k] = v;
    v1::CompleteReply cr;
    const auto st = workers_stub_->Complete(ctx().get(), bad, &cr);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << field;
    EXPECT_NE(st.error_message().find(field), std::string::npos) << st.error_message();
  }
  (*c.mutable_metrics())["solid_fraction"] = 0.6;
  (*c.mutable_metrics())["coordination_number"] = 4.0;
  v1::CompleteReply cr;
  const auto st = workers_stub_->Complete(ctx().get(), c, &cr);
  EXPECT_TRUE(st.ok()) << st.error_message();
}

// A result names only metrics its test reports (its catalogue entry: the metrics and what the
// test also reports): another name is refused naming it, and nothing is stored.
TEST_F(Service, AResultWithAMetricItsTestDoesNotReportIsRefused) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  ASSERT_TRUE(submit(tiny_spec(30)).ok());
  v1::JobSpec job;
  v1::CompleteRequest c;
  ASSERT_NO_FATAL_FAILURE(lease_request("w1", job, c));
  (*c.mutable_metrics())["solid_fraction"] = 0.6;
  (*c.mutable_metrics())["coordination_number"] = 4.0;
  v1::CompleteRequest bad = c;
  (*bad.mutable_metrics())["centrifuging_116"] = 1.0;  // the drum's, not the packing's
  v1::CompleteReply cr;
  auto st = workers_stub_->Complete(ctx().get(), bad, &cr);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(st.error_message().find("metrics.centrifuging_116"), std::string::npos)
      << st.error_message();
  st = workers_stub_->Complete(ctx().get(), c, &cr);
  EXPECT_TRUE(st.ok()) << st.error_message();
}

// A worker of another build (other lab protocol versions, or none named) is refused its lease:
// its results would be stored under run keys that claim this build's protocol.
TEST_F(Service, AWorkerOfOtherLabProtocolVersionsIsRefusedItsLease) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(30), &id).ok());
  v1::LeaseRequest older = rpc::lease_request("old");
  (*older.mutable_protocols())["shear_cell"] -= 1;
  v1::LeaseReply lease;
  auto st = workers_stub_->Lease(ctx().get(), older, &lease);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(st.error_message().find("protocols.shear_cell: the worker simulates it under lab "
                                    "protocol version " +
                                    std::to_string(lab::protocol_version("shear_cell") - 1) +
                                    ", this coordinator keys its runs under " +
                                    std::to_string(lab::protocol_version("shear_cell"))),
            std::string::npos)
      << st.error_message();
  v1::LeaseRequest unnamed;
  unnamed.set_worker("older");
  st = workers_stub_->Lease(ctx().get(), unnamed, &lease);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(st.error_message().find("names no protocol version for lab test"), std::string::npos)
      << st.error_message();
  EXPECT_FALSE(lease.has_job());
  // Nothing was leased: the job goes to a worker of this build.
  ASSERT_NO_FATAL_FAILURE(lease_as("this", lease));
  ASSERT_TRUE(lease.has_job());
  EXPECT_EQ(lease.job().attempt(), 1);
}

TEST_F(Service, WorkersRacingNeverShareAJob) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(30, /*centre=*/4), &id).ok());  // 8 jobs
  std::mutex m;
  std::multiset<std::int64_t> leased;
  std::vector<std::thread> racers;
  for (int t = 0; t < 6; ++t)
    racers.emplace_back([&, t] {
      auto stub = v1::WorkerService::NewStub(rpc::make_channel(channel_));
      for (int k = 0; k < 4; ++k) {
        const v1::LeaseRequest lr = rpc::lease_request("racer" + std::to_string(t));
        v1::LeaseReply r;
        if (stub->Lease(rpc::make_context(channel_, 10).get(), lr, &r).ok() && r.has_job()) {
          std::lock_guard lock(m);
          leased.insert(r.job().job_id());
        }
      }
    });
  for (auto& r : racers) r.join();
  EXPECT_EQ(leased.size(), 8u);
  for (const auto j : leased) EXPECT_EQ(leased.count(j), 1u) << "job " << j << " leased twice";

  // Two real workers finish a second campaign between them.
  std::int64_t id2 = 0;
  ASSERT_TRUE(submit(tiny_spec(30, 2), &id2).ok());
  v1::CancelRequest cancel;
  cancel.set_id(id);
  v1::Campaign c;
  ASSERT_TRUE(campaigns_->Cancel(ctx().get(), cancel, &c).ok());
  start_worker("w1");
  start_worker("w2");
  ASSERT_TRUE(wait_until([&] { return campaign_done(id2); }, 90)) << workers_[0]->log();
  const auto r = results(id2);
  const auto stored = stored_results();
  for (const auto& j : r.jobs()) {
    EXPECT_EQ(j.state(), "done");
    EXPECT_EQ(j.attempt(), 1) << "job " << j.job_id();
    EXPECT_EQ(stored.at(j.job_id()), 1);
  }
}

TEST_F(Service, WorkerKilledMidJobLeasedAgainAndStoredOnce) {
  start_server(/*lease=*/1.5, /*heartbeat=*/0.3);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(400), &id).ok());  // 4 jobs of ~1 s
  auto& victim = start_worker("victim");
  std::int64_t killed_job = 0;
  ASSERT_TRUE(wait_until(
      [&] {
        const auto now = results(id);
        for (const auto& j : now.jobs())
          if (j.state() == "leased") killed_job = j.job_id();
        return killed_job != 0;
      },
      30));
  victim.signal(SIGKILL);
  EXPECT_EQ(victim.wait_exit(10), 128 + SIGKILL);
  start_worker("rescuer");
  ASSERT_TRUE(wait_until([&] { return campaign_done(id); }, 120)) << workers_.back()->log();
  const auto stored = stored_results();
  const auto r = results(id);
  for (const auto& j : r.jobs()) {
    EXPECT_EQ(j.state(), "done") << j.error();
    EXPECT_EQ(stored.at(j.job_id()), 1);
    if (j.job_id() == killed_job) {
      EXPECT_GE(j.attempt(), 2);
      EXPECT_EQ(j.worker(), "rescuer");
    }
  }
  EXPECT_NE(server_->log().find("expired"), std::string::npos);
}

TEST_F(Service, CoordinatorKilledAndRestartedCampaignCompletesNothingLostOrDuplicated) {
  start_server(/*lease=*/3, /*heartbeat=*/0.3);
  std::int64_t id = 0;
  ASSERT_TRUE(submit(tiny_spec(200, 2), &id).ok());  // 6 jobs
  start_worker("w");
  ASSERT_TRUE(wait_until(
      [&] {
        int done = 0;
        const auto now = results(id);
        for (const auto& j : now.jobs()) done += j.state() == "done";
        return done >= 2;
      },
      60));
  const int port = port_;
  server_->signal(SIGKILL);
  EXPECT_EQ(server_->wait_exit(10), 128 + SIGKILL);
  std::this_thread::sleep_for(std::chrono::milliseconds(800));  // the worker is now backing off
  start_server(3, 0.3, port);
  ASSERT_TRUE(wait_until([&] { return campaign_done(id); }, 120)) << workers_[0]->log();
  const auto r = results(id);
  const auto stored = stored_results();
  EXPECT_EQ(r.jobs_size(), 6);
  EXPECT_EQ(stored.size(), 6u);
  for (const auto& j : r.jobs()) {
    EXPECT_EQ(j.state(), "done") << j.error();
    EXPECT_EQ(stored.at(j.job_id()), 1);
    EXPECT_EQ(j.metrics().size(), 2u);
  }
  EXPECT_NE(server_->log().find("resuming campaign"), std::string::npos);
}

}  // namespace
}  // namespace demcal::test
