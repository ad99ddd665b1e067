// Campaign journals and runs reused by run key (docs/journal.md), with real processes: a second
// campaign in one store takes the first's results instead of leasing its jobs; `demcal run
// --journal` interrupted and resumed in a fresh work directory gives the uninterrupted run's
// effects to the bit with no run simulated twice, and a store snapshot behind its journal takes the
// journal's runs before it leases a job; a journal of another spec gives exactly the runs
// whose keys match; runs of another version of their test's protocol, or of a material the build
// refuses, are not taken; lines cut short are dropped and malformed lines refused with their file
// and line.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "core/lab/protocol.hpp"
#include "server/run_key.hpp"
#include "server/store.hpp"
#include "server/store_lock.hpp"
#include "server/stored_columns.hpp"
#include "tests/service/service_fixture.hpp"

namespace demcal::test {
namespace {

/// A 2^2 packing campaign of 200-particle beds (a fraction of a second each), without
/// measurements (no calibration): the restitution's high level sets which runs it shares with
/// another spec. The bounds are sums of powers of two, so that a level is the same double in
/// every box that has it (a level is computed as centre -+ half the range).
std::string packing_spec(const std::string& name, double restitution_high) {
  return "name: " + name + packing_material(200) + R"(factors:
  - {path: particle_law.tangential.mu_s, low: 0.125, high: 0.5}
  - {path: particle_law.normal.restitution, low: 0.25, high: )" +
         std::to_string(restitution_high) + R"(}
design: {type: full_factorial}
)";
}

std::vector<std::string> file_lines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

void write_lines(const std::string& path, const std::vector<std::string>& lines) {
  std::ofstream out(path, std::ios::trunc);
  for (const auto& line : lines) out << line << "\n";
}

/// The run keys of a journal's run lines, in order.
std::vector<std::string> journal_keys(const std::string& path) {
  std::vector<std::string> keys;
  for (const auto& line : file_lines(path)) {
    const auto j = nlohmann::json::parse(line);
    if (j.contains("run_key")) keys.push_back(j.at("run_key"));
  }
  return keys;
}

/// Each job of a campaign's file: its run key, whether its result was simulated (not reused),
/// and its attempts.
struct StoredJob {
  std::string run_key;
  bool reused = false;
  int attempt = 0;
  std::string metrics;
};

class Journal : public Service {
 protected:
  /// `demcal run SPEC --workdir WORK [--journal J] --format json` on one worker of one thread;
  /// its standard output (the JSON document) in NAME.json, its standard error in NAME.err.
  std::vector<std::string> run_argv(const std::string& spec, const std::string& work,
                                    const std::string& journal) {
    std::vector<std::string> argv{DEMCAL_CLI_BIN, "run", spec,        "--workdir", path(work),
                                  "--workers",    "1",   "--threads", "1",         "--format",
                                  "json"};
    if (!journal.empty()) argv.insert(argv.end(), {"--journal", journal});
    return argv;
  }

  /// Runs it to its end; the exit status, with standard error in `err`.
  int run(const std::string& spec, const std::string& work, const std::string& journal,
          std::string& err) {
    Process p(run_argv(spec, work, journal), path(work + ".json"), path(work + ".err"));
    const int status = p.wait_exit(120);
    std::ifstream in(path(work + ".err"));
    err.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    return status;
  }

  /// Spec a (packing_spec) run in the work directory "a" with the journal a.jsonl, which then
  /// holds its header and its four runs.
  void run_a() {
    std::ofstream(path("a.yaml")) << packing_spec("a", 0.75);
    std::string err;
    ASSERT_EQ(run(path("a.yaml"), "a", path("a.jsonl"), err), 0) << err;
    ASSERT_EQ(file_lines(path("a.jsonl")).size(), 5u);
  }

  /// `demcal run` (run_argv) stopped with SIGINT (Ctrl-C) once `results` runs are stored in WORK.
  void run_until_interrupted(const std::string& spec, const std::string& work,
                             const std::string& journal, int results) {
    Process p(run_argv(spec, work, journal), path(work + ".json"), path(work + ".err"));
    ASSERT_TRUE(wait_until([&] { return results_stored(work) >= results; }, 90));
    p.signal(SIGINT);
    EXPECT_EQ(p.wait_exit(40), 128 + SIGINT);
  }

  nlohmann::json output(const std::string& work) {
    return nlohmann::json::parse(std::ifstream(path(work + ".json")));
  }

  /// A packing campaign with two measurements and the curvature candidate, in diag.yaml.
  std::string diagnosis_spec() {
    const std::string spec = path("diag.yaml");
    std::ofstream(spec) << packing_spec("diag", 0.75) << R"(measurements:
  - {metric: solid_fraction, value: 0.6, uncertainty: 0.02}
  - {metric: coordination_number, value: 5.5}
diagnose: {candidates: [curvature]}
)";
    return spec;
  }

  /// `demcal diagnose SPEC --workdir WORK --format json` on one worker of one thread, with the
  /// journal when one is given, with --no-wait when not `wait`; its standard output in
  /// WORK.json, its standard error in WORK.err. The exit status.
  int diagnose(const std::string& spec, const std::string& work, const std::string& journal,
               bool wait = true) {
    std::vector<std::string> argv{DEMCAL_CLI_BIN, "diagnose", spec,        "--workdir", path(work),
                                  "--workers",    "1",        "--threads", "1",         "--format",
                                  "json"};
    if (!journal.empty()) argv.insert(argv.end(), {"--journal", journal});
    if (!wait) argv.push_back("--no-wait");
    Process p(argv, path(work + ".json"), path(work + ".err"));
    return p.wait_exit(120);
  }

  /// The jobs of the campaign in WORK/campaign.db, in job order.
  std::vector<StoredJob> stored_jobs(const std::string& work) {
    std::vector<StoredJob> out;
    each_row(path(work + "/campaign.db"),
             "SELECT j.run_key, r.reused_from != 0 OR r.reused_journal != '', j.attempt, "
             "COALESCE(r.metrics_json, '') FROM jobs j LEFT JOIN results r ON r.job_id = j.id "
             "ORDER BY j.id",
             [&](sqlite3_stmt* st) {
               out.push_back({reinterpret_cast<const char*>(sqlite3_column_text(st, 0)),
                              sqlite3_column_int(st, 1) != 0, sqlite3_column_int(st, 2),
                              reinterpret_cast<const char*>(sqlite3_column_text(st, 3))});
             });
    return out;
  }

  /// How many jobs of the campaign in WORK were simulated, and how many took a result.
  std::pair<int, int> simulated_and_reused(const std::string& work) {
    int simulated = 0, reused = 0;
    for (const auto& job : stored_jobs(work)) (job.reused ? reused : simulated) += 1;
    return {simulated, reused};
  }

  /// Results stored in WORK/campaign.db so far (0 while the file or its tables do not exist).
  int results_stored(const std::string& work) {
    const std::string db = path(work + "/campaign.db");
    int n = 0;
    sqlite3* file = nullptr;
    sqlite3_stmt* st = nullptr;
    if (fs::exists(db) &&
        sqlite3_open_v2(db.c_str(), &file, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK &&
        sqlite3_prepare_v2(file, "SELECT COUNT(*) FROM results", -1, &st, nullptr) == SQLITE_OK &&
        sqlite3_step(st) == SQLITE_ROW)
      n = sqlite3_column_int(st, 0);
    sqlite3_finalize(st);
    sqlite3_close(file);
    return n;
  }
};

TEST_F(Journal, ASecondCampaignInTheStoreTakesTheFirstsResultsInsteadOfSimulatingThem) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  std::int64_t first = 0, second = 0;
  ASSERT_TRUE(submit(tiny_spec(30), &first).ok());
  std::map<std::string, double> by_key;  // the result of each run key, as completed
  for (int i = 0; i < 4; ++i)
    ASSERT_NO_FATAL_FAILURE(complete_fake_job([&](const v1::JobSpec&, v1::CompleteRequest& c) {
      (*c.mutable_metrics())["solid_fraction"] = 0.55 + 0.01 * i;
      (*c.mutable_metrics())["coordination_number"] = 4.0;
      c.set_wall_seconds(1.0 + i);
    }));
  const auto first_jobs = results(first);
  for (const auto& j : first_jobs.jobs()) by_key[j.run_key()] = j.metrics().at("solid_fraction");
  ASSERT_EQ(by_key.size(), 4u);  // four runs, four keys
  // The same spec again: the worker's lease finds nothing to simulate, and the campaign is done
  // with every result taken from the first campaign's job of its key.
  ASSERT_TRUE(submit(tiny_spec(30), &second).ok());
  v1::LeaseReply lease;
  ASSERT_NO_FATAL_FAILURE(lease_as("w", lease));
  EXPECT_FALSE(lease.has_job());
  EXPECT_TRUE(campaign_done(second));
  std::map<std::int64_t, std::string> first_keys;
  for (const auto& j : first_jobs.jobs()) first_keys[j.job_id()] = j.run_key();
  const auto second_jobs = results(second);
  for (const auto& j : second_jobs.jobs()) {
    EXPECT_EQ(j.state(), "done");
    EXPECT_EQ(j.attempt(), 0) << "never leased";
    ASSERT_TRUE(first_keys.count(j.reused_from())) << j.reused_from();
    EXPECT_EQ(first_keys[j.reused_from()], j.run_key());
    EXPECT_EQ(j.metrics().at("solid_fraction"), by_key[j.run_key()]);
  }
  // Counted and shown as reused: Get's progress, `demcal status` and `demcal export`.
  v1::GetRequest get;
  get.set_id(second);
  v1::Campaign c;
  ASSERT_TRUE(campaigns_->Get(ctx().get(), get, &c).ok());
  EXPECT_EQ(c.progress().reused(), 4);
  EXPECT_EQ(c.progress().done(), 4);
  const std::string id = std::to_string(second);
  Process status({DEMCAL_CLI_BIN, "status", id, "--jobs", "--coordinator", channel_.address,
                  "--token", kToken},
                 path("status.log"));
  ASSERT_EQ(status.wait_exit(30), 0) << status.log();
  EXPECT_NE(status.log().find("4/4 done (4 reused)"), std::string::npos) << status.log();
  EXPECT_NE(status.log().find("reused from job "), std::string::npos) << status.log();
  const auto exported = cli_json(dir_, "export", {"export", id, "--format", "json"}, channel_);
  EXPECT_EQ(exported.at("reused"), 4);
  EXPECT_NE(exported.at("jobs").at(0).at("reused_from"), 0);
  // A journal of the second campaign names the first's runs by the same keys.
  Process journal({DEMCAL_CLI_BIN, "export", id, "--format", "journal", "-o", path("second.jsonl"),
                   "--coordinator", channel_.address, "--token", kToken},
                  path("journal.log"));
  ASSERT_EQ(journal.wait_exit(30), 0) << journal.log();
  const auto keys = journal_keys(path("second.jsonl"));
  EXPECT_EQ(std::set<std::string>(keys.begin(), keys.end()).size(), 4u);
  for (const auto& key : keys) EXPECT_TRUE(by_key.count(key)) << key;
}

TEST_F(Journal, ImportRunsRefusesAnInvalidRunNamingItsLineAndKeepsNothingOfTheCall) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  v1::ImportRunsRequest req;
  auto* good = req.add_runs();
  good->set_run_key(std::string(64, 'a'));
  good->set_protocol(lab::kProtocolVersion);
  (*good->mutable_metrics())["solid_fraction"] = 0.6;
  good->set_source("j.jsonl:2");
  auto* bad = req.add_runs();
  *bad = *good;
  bad->set_run_key(std::string(64, 'b'));
  (*bad->mutable_metrics())["solid_fraction"] = std::numeric_limits<double>::infinity();
  bad->set_source("j.jsonl:3");
  v1::ImportRunsReply reply;
  auto s = campaigns_->ImportRuns(ctx().get(), req, &reply);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(s.error_message(), "j.jsonl:3: metrics.solid_fraction: must be finite");
  req.mutable_runs()->RemoveLast();
  auto* other = req.add_runs();
  *other = *good;
  other->set_run_key(std::string(64, 'c'));
  other->set_protocol(lab::kProtocolVersion + 1);
  ASSERT_TRUE(campaigns_->ImportRuns(ctx().get(), req, &reply).ok());
  EXPECT_EQ(reply.kept(), 1);  // the good run: the call refused before kept nothing
  EXPECT_EQ(reply.known(), 0);
  EXPECT_EQ(reply.other_protocol(), 1);
  EXPECT_EQ(reply.protocol(), lab::kProtocolVersion);
  // A test with a version of its own: its runs of the common version are another protocol's.
  EXPECT_EQ(reply.test_protocol().at("shear_cell"), lab::protocol_version("shear_cell"));
  EXPECT_NE(lab::protocol_version("shear_cell"), lab::kProtocolVersion);
  v1::ImportRunsRequest shear;
  *shear.add_runs() = *good;
  shear.mutable_runs(0)->set_run_key(std::string(64, 'd'));
  shear.mutable_runs(0)->set_test("shear_cell");
  ASSERT_TRUE(campaigns_->ImportRuns(ctx().get(), shear, &reply).ok());
  EXPECT_EQ(reply.other_protocol(), 1);
  EXPECT_EQ(reply.kept(), 0);
  shear.mutable_runs(0)->set_protocol(lab::protocol_version("shear_cell"));
  ASSERT_TRUE(campaigns_->ImportRuns(ctx().get(), shear, &reply).ok());
  EXPECT_EQ(reply.kept(), 1);
  ASSERT_TRUE(campaigns_->ImportRuns(ctx().get(), req, &reply).ok());
  EXPECT_EQ(reply.kept(), 0);
  EXPECT_EQ(reply.known(), 1);
}

TEST_F(Journal, AnInterruptedCampaignGoesOnElsewhereFromItsJournalToTheSameEffects) {
  const std::string spec = path("moved.yaml");
  std::ofstream(spec) << wall_friction_spec("moved", "");
  const std::string journal = path("moved.jsonl");
  // Stopped (Ctrl-C) once two of its four runs are finished, a few seconds each.
  ASSERT_NO_FATAL_FAILURE(run_until_interrupted(spec, "first", journal, 2));
  // The journal holds its header and every run the interrupted campaign finished.
  const int finished = results_stored("first");
  ASSERT_LT(finished, 4);
  EXPECT_EQ(file_lines(journal).size(), 1u + unsigned(finished));
  // Moved with the spec to a fresh work directory, the same command goes on from it: the
  // journal's runs are taken, the others simulated, each run simulated once over the two.
  std::string err;
  ASSERT_EQ(run(spec, "second", journal, err), 0) << err;
  EXPECT_NE(err.find(std::to_string(finished) + " run(s) read, " + std::to_string(finished) +
                     " new to the coordinator"),
            std::string::npos)
      << err;
  const auto [simulated, reused] = simulated_and_reused("second");
  EXPECT_EQ(reused, finished);
  EXPECT_EQ(simulated, 4 - finished);
  for (const auto& job : stored_jobs("second")) EXPECT_EQ(job.attempt, job.reused ? 0 : 1);
  const auto keys = journal_keys(journal);
  EXPECT_EQ(keys.size(), 4u);
  EXPECT_EQ(std::set<std::string>(keys.begin(), keys.end()).size(), 4u);
  // An uninterrupted run gives the same effect tables, to the bit.
  ASSERT_EQ(run(spec, "whole", "", err), 0) << err;
  EXPECT_EQ(output("second").at("effects"), output("whole").at("effects"));
}

TEST_F(Journal, AStoreSnapshotBehindItsJournalTakesTheJournalsRunsBeforeItsWorkerLeasesOne) {
  const std::string spec = path("behind.yaml");
  std::ofstream(spec) << wall_friction_spec("behind", "");
  const std::string journal = path("behind.jsonl");
  ASSERT_NO_FATAL_FAILURE(run_until_interrupted(spec, "first", journal, 1));
  const int finished = results_stored("first");
  ASSERT_LT(finished, 4);
  // The stopped store is kept as a snapshot; the campaign then goes on to its end in its own
  // work directory, so the journal holds runs the snapshot has queued.
  fs::create_directories(path("snapshot"));
  for (const auto& entry : fs::directory_iterator(path("first")))
    if (entry.path().filename().string().starts_with("campaign.db"))
      fs::copy_file(entry.path(), fs::path(path("snapshot")) / entry.path().filename());
  std::string err;
  ASSERT_EQ(run(spec, "first", journal, err), 0) << err;
  ASSERT_EQ(journal_keys(journal).size(), 4u);
  // Going on from the snapshot with the journal simulates nothing: its local worker starts
  // once the journal's runs are offered, so each queued job takes its run's result.
  ASSERT_EQ(run(spec, "snapshot", journal, err), 0) << err;
  const auto [simulated, reused] = simulated_and_reused("snapshot");
  EXPECT_EQ(simulated, finished);
  EXPECT_EQ(reused, 4 - finished);
  std::map<std::string, std::string> metrics_of_key;
  for (const auto& job : stored_jobs("first")) metrics_of_key[job.run_key] = job.metrics;
  for (const auto& job : stored_jobs("snapshot"))
    EXPECT_EQ(job.metrics, metrics_of_key.at(job.run_key)) << job.run_key;
}

TEST_F(Journal, ADiagnosisKeepsItsRunsInTheJournalAndGoesOnFromItElsewhere) {
  const std::string spec = diagnosis_spec();
  const std::string journal = path("diag.jsonl");
  ASSERT_EQ(diagnose(spec, "first", journal), 0) << file_lines(path("first.err")).back();
  // The design's four runs, the baseline, the candidate's axial and centre runs and its
  // verifications: every run the diagnosis simulated is a run of the journal (a verification at
  // a point already run takes that run's result).
  const auto first = stored_jobs("first");
  std::set<std::string> distinct;
  for (const auto& job : first) distinct.insert(job.run_key);
  const auto keys = journal_keys(journal);
  EXPECT_GE(first.size(), 4u + 1u + 5u + 1u);
  EXPECT_EQ(std::set<std::string>(keys.begin(), keys.end()), distinct);
  EXPECT_EQ(simulated_and_reused("first").first, static_cast<int>(distinct.size()));

  // Elsewhere, from the journal: nothing is simulated again and the report is the same.
  ASSERT_EQ(diagnose(spec, "second", journal), 0);
  const auto [simulated, reused] = simulated_and_reused("second");
  EXPECT_EQ(simulated, 0);
  EXPECT_EQ(reused, static_cast<int>(first.size()));
  EXPECT_EQ(output("second"), output("first"));
  EXPECT_EQ(journal_keys(journal), keys);

  // A journal is the embedded default's: with a campaign id it is refused.
  Process by_id({DEMCAL_CLI_BIN, "diagnose", "1", "--journal", journal}, path("id.out"),
                path("id.err"));
  EXPECT_NE(by_id.wait_exit(30), 0);
  std::ifstream in(path("id.err"));
  const std::string err((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(err.find("--journal"), std::string::npos) << err;
}

TEST_F(Journal, ADiagnosisLookedAtWithoutWaitingSimulatesNothingAlsoWhileItsStoreIsHeld) {
  const std::string spec = diagnosis_spec();
  // A new campaign: its design is queued, no local worker starts, nothing is simulated.
  ASSERT_EQ(diagnose(spec, "look", "", false), 0) << file_lines(path("look.err")).back();
  EXPECT_EQ(output("look").at("state"), "waiting");
  EXPECT_EQ(stored_jobs("look").size(), 4u);
  EXPECT_EQ(results_stored("look"), 0);
  // Driven to its end in the same work directory.
  fs::remove(path("look.json"));  // a process's output is appended to its file
  ASSERT_EQ(diagnose(spec, "look", ""), 0) << file_lines(path("look.err")).back();
  const nlohmann::json done = output("look");
  ASSERT_EQ(done.at("state"), "done");
  const auto jobs = stored_jobs("look");
  // Its store held, as a diagnosis still running holds it: a look reads a copy taken in the
  // temporary directory and removed after, and gives the same report; the store is not touched.
  // Without --no-wait the store is refused, naming its holder.
  const auto err_has = [&](const std::string& text) {
    const auto lines = file_lines(path("look.err"));
    return std::any_of(lines.begin(), lines.end(),
                       [&](const std::string& l) { return l.find(text) != std::string::npos; });
  };
  const std::string pid = "(pid " + std::to_string(::getpid()) + ")";
  fs::create_directories(path("tmp"));
  ASSERT_EQ(setenv("TMPDIR", path("tmp").c_str(), 1), 0);
  {
    const server::StoreLock held(path("look/campaign.db"));
    fs::remove(path("look.json"));
    fs::remove(path("look.err"));
    ASSERT_EQ(diagnose(spec, "look", "", false), 0) << file_lines(path("look.err")).back();
    EXPECT_EQ(output("look"), done);
    EXPECT_TRUE(err_has("held by a running coordinator " + pid));
    fs::remove(path("look.err"));
    EXPECT_NE(diagnose(spec, "look", ""), 0);
    EXPECT_TRUE(err_has("another coordinator " + pid));
  }
  ASSERT_EQ(unsetenv("TMPDIR"), 0);
  EXPECT_TRUE(fs::is_empty(path("tmp")));
  const auto after = stored_jobs("look");
  ASSERT_EQ(after.size(), jobs.size());
  for (std::size_t k = 0; k < jobs.size(); ++k) {
    EXPECT_EQ(after[k].run_key, jobs[k].run_key);
    EXPECT_EQ(after[k].metrics, jobs[k].metrics);
  }
}

// A store an older build wrote (here a finished campaign's, its latest migration undone, as the
// build before left it) is looked at from a migrated copy: `demcal status` reports its jobs and
// the file is left as it was, byte for byte, so the build that wrote it goes on with it. A run of
// this build then migrates it and simulates nothing again.
TEST_F(Journal, ALookAtAStoreOfAnOlderSchemaReadsAMigratedCopyAndLeavesTheFileAsItWas) {
  run_a();
  const std::string db = path("a/campaign.db");
  const auto schema_version = [&] {
    int version = -1;
    each_row(db, "PRAGMA user_version",
             [&](sqlite3_stmt* st) { version = sqlite3_column_int(st, 0); });
    return version;
  };
  // The reverse of the latest migration (server/schema/015_job_yields.sql); a new migration
  // brings its own here.
  const int latest = server::Store::latest_schema_version();
  ASSERT_EQ(latest, 15) << "undo migration " << latest << " here";
  const int older = latest - 1;
  {
    sqlite3* file = nullptr;
    ASSERT_EQ(sqlite3_open(db.c_str(), &file), SQLITE_OK);
    for (const char* sql :
         {"DROP INDEX jobs_queue", "ALTER TABLE jobs DROP COLUMN yields",
          "CREATE INDEX jobs_queue ON jobs (state, campaign_id, kind, wait_ended DESC, run_order)",
          "PRAGMA user_version=14", "PRAGMA wal_checkpoint(TRUNCATE)"})
      ASSERT_EQ(sqlite3_exec(file, sql, nullptr, nullptr, nullptr), SQLITE_OK)
          << sql << ": " << sqlite3_errmsg(file);
    ASSERT_EQ(sqlite3_close(file), SQLITE_OK);
  }
  ASSERT_EQ(schema_version(), older);
  const auto bytes = [&] {
    std::ifstream in(db, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  const std::string before = bytes();
  const auto jobs = stored_jobs("a");

  Process status({DEMCAL_CLI_BIN, "status", path("a.yaml"), "--workdir", path("a"), "--jobs",
                  "--format", "json"},
                 path("status.json"), path("status.err"));
  ASSERT_EQ(status.wait_exit(60), 0) << file_lines(path("status.err")).back();
  const auto doc = nlohmann::json::parse(std::ifstream(path("status.json")));
  ASSERT_EQ(doc.at("jobs").size(), jobs.size());
  for (const auto& job : doc.at("jobs")) EXPECT_EQ(job.at("state"), "done") << job.dump();
  const auto err = file_lines(path("status.err"));
  EXPECT_TRUE(std::any_of(err.begin(), err.end(), [&](const std::string& l) {
    return l.find("is at schema version " + std::to_string(older) + ", this build's is " +
                  std::to_string(latest)) != std::string::npos;
  }));
  EXPECT_EQ(schema_version(), older);
  EXPECT_TRUE(bytes() == before) << "a look wrote to the store";

  std::string run_err;
  ASSERT_EQ(run(path("a.yaml"), "a", "", run_err), 0) << run_err;
  EXPECT_EQ(schema_version(), latest);
  const auto after = stored_jobs("a");
  ASSERT_EQ(after.size(), jobs.size());
  for (std::size_t k = 0; k < jobs.size(); ++k) {
    EXPECT_EQ(after[k].attempt, jobs[k].attempt);
    EXPECT_EQ(after[k].metrics, jobs[k].metrics);
  }
}

// A diagnosis run to its end, its spec then given more verification rounds: the same command in
// the same work directory goes on from the runs the campaign has (every job kept with its result,
// only the added round simulated). A spec changed in anything else is still refused there.
TEST_F(Journal, ASpecGivenMoreDiagnosisRoundsGoesOnFromTheRunsItsCampaignHas) {
  const auto rounds_done = [&](const std::string& work) {
    return output(work).at("candidates").at(0).at("rounds").get<int>();
  };
  // A solid fraction no poured bed of the box reaches: no round meets it within 1 %.
  const auto diagnosis_spec = [&](const std::string& options) {
    const std::string spec = path("rounds.yaml");
    std::ofstream(spec) << packing_spec("rounds", 0.75) << R"(measurements:
  - {metric: solid_fraction, value: 0.7, uncertainty: 0.02}
diagnose: {candidates: [curvature])"
                        << options << "}\n";
    return spec;
  };
  std::string spec = diagnosis_spec(", rounds: 1");
  ASSERT_EQ(diagnose(spec, "r", ""), 0) << file_lines(path("r.err")).back();
  ASSERT_EQ(rounds_done("r"), 1);
  ASSERT_GT(output("r").at("candidates").at(0).at("verified_rms").get<double>(), 0.01);
  const auto first = stored_jobs("r");

  spec = diagnosis_spec(", rounds: 2");
  fs::remove(path("r.json"));  // a process's output is appended to its file
  ASSERT_EQ(diagnose(spec, "r", ""), 0) << file_lines(path("r.err")).back();
  EXPECT_EQ(rounds_done("r"), 2);
  const auto second = stored_jobs("r");
  ASSERT_EQ(second.size(), first.size() + 1);  // the candidate's second verification
  for (std::size_t k = 0; k < first.size(); ++k) {
    EXPECT_EQ(second[k].run_key, first[k].run_key);
    EXPECT_EQ(second[k].metrics, first[k].metrics);
    EXPECT_EQ(second[k].attempt, first[k].attempt);
  }

  spec = diagnosis_spec(", rounds: 2, margin: 0.5");
  EXPECT_NE(diagnose(spec, "r", ""), 0);
  EXPECT_NE(file_lines(path("r.err")).back().find("was submitted with another spec"),
            std::string::npos)
      << file_lines(path("r.err")).back();
  EXPECT_EQ(stored_jobs("r").size(), second.size());
}

// A journal written by a build whose calibration proposed the diagnosis's baseline a hair away
// (every parameter 1e-9 off, relative) serves the campaign planned again: the baseline takes the
// journal run's point and its result. A run 1e-4 off is another point, and is simulated. Results
// through the real worker protocol, no physics.
TEST_F(Journal, AProposalAHairFromAJournalRunTakesThatRun) {
  start_server(/*lease=*/30, /*heartbeat=*/5);
  const std::string spec = tiny_spec(
      30, 0, "",
      "calibration: {rounds: 1, stages: 1}\ndiagnose: {candidates: [curvature], rounds: 1}\n");
  const auto fill = [](const v1::JobSpec& job, v1::CompleteRequest& c) {
    (*c.mutable_metrics())["solid_fraction"] =
        0.5 + 0.25 * job.parameters().at("particle_law.tangential.mu_s");
    (*c.mutable_metrics())["coordination_number"] = 4.0;
  };
  const auto diagnose = [&](std::int64_t id) {
    v1::DiagnoseRequest req;
    req.set_id(id);
    v1::DiagnoseReply reply;
    const auto st = campaigns_->Diagnose(ctx().get(), req, &reply);
    EXPECT_TRUE(st.ok()) << st.error_message();
  };
  const auto cancel = [&](std::int64_t id) {
    v1::CancelRequest req;
    req.set_id(id);
    v1::Campaign c;
    ASSERT_TRUE(campaigns_->Cancel(ctx().get(), req, &c).ok());
  };
  // The baseline job of a campaign: its payload and run key, and the journal line its result
  // was taken from ('' when none), read from the store's file.
  struct Baseline {
    v1::JobSpec job;
    std::string key, reused_journal, state;
  };
  const auto baseline = [&](std::int64_t id) {
    Baseline b;
    each_row(path("c.db"),
             ("SELECT j.payload, j.run_key, COALESCE(r.reused_journal, ''), j.state FROM jobs j "
              "LEFT JOIN results r ON r.job_id = j.id WHERE j.kind = 'diagnose:baseline' AND "
              "j.campaign_id = " +
              std::to_string(id))
                 .c_str(),
             [&](sqlite3_stmt* st) {
               b.job = server::job_from_payload(
                   reinterpret_cast<const char*>(sqlite3_column_text(st, 0)));
               b.key = reinterpret_cast<const char*>(sqlite3_column_text(st, 1));
               b.reused_journal = reinterpret_cast<const char*>(sqlite3_column_text(st, 2));
               b.state = reinterpret_cast<const char*>(sqlite3_column_text(st, 3));
             });
    return b;
  };
  // A journal line of the baseline's run at its point with every parameter (1 + shift) times.
  const auto journal_run = [](const v1::JobSpec& job, double shift, const std::string& source) {
    v1::JobSpec shifted = job;
    for (auto& [path, value] : *shifted.mutable_parameters()) value *= 1.0 + shift;
    v1::ImportRunsRequest req;
    auto* run = req.add_runs();
    run->set_run_key(server::run_key(shifted).key);
    run->set_protocol(lab::protocol_version(job.test()));
    run->set_test(job.test());
    run->set_instance(job.test());
    *run->mutable_parameters() = shifted.parameters();
    run->set_seed(job.seed());
    (*run->mutable_metrics())["solid_fraction"] = 0.6;
    (*run->mutable_metrics())["coordination_number"] = 4.0;
    run->set_source(source);
    return std::pair{req, shifted};
  };
  // A campaign of the spec whose design takes the first's results (at the first lease), then
  // its diagnosis queued.
  const auto planned_again = [&] {
    std::int64_t id = 0;
    EXPECT_TRUE(submit(spec, &id).ok());
    v1::LeaseReply none;
    lease_as("fake", none);
    EXPECT_FALSE(none.has_job());
    diagnose(id);
    return id;
  };

  std::int64_t first = 0;
  ASSERT_TRUE(submit(spec, &first).ok());
  for (int k = 0; k < 4; ++k) ASSERT_NO_FATAL_FAILURE(complete_fake_job(fill));
  diagnose(first);
  const Baseline planned = baseline(first);
  ASSERT_FALSE(planned.key.empty());
  ASSERT_EQ(planned.state, "queued");
  ASSERT_NO_FATAL_FAILURE(cancel(first));

  v1::ImportRunsReply imported;
  const auto far = journal_run(planned.job, 1e-4, "far.jsonl:2");
  ASSERT_TRUE(campaigns_->ImportRuns(ctx().get(), far.first, &imported).ok());
  ASSERT_EQ(imported.kept(), 1);
  const std::int64_t second = planned_again();
  const Baseline apart = baseline(second);
  EXPECT_EQ(apart.key, planned.key);
  EXPECT_EQ(apart.state, "queued");
  ASSERT_NO_FATAL_FAILURE(cancel(second));

  const auto near = journal_run(planned.job, 1e-9, "near.jsonl:2");
  ASSERT_TRUE(campaigns_->ImportRuns(ctx().get(), near.first, &imported).ok());
  ASSERT_EQ(imported.kept(), 1);
  const std::int64_t third = planned_again();
  v1::LeaseReply next;  // the baseline takes the journal run; the candidate's runs are leased
  ASSERT_NO_FATAL_FAILURE(lease_as("fake", next));
  const Baseline taken = baseline(third);
  EXPECT_EQ(taken.key, near.first.runs(0).run_key());
  EXPECT_NE(taken.key, planned.key);
  EXPECT_EQ(taken.state, "done");
  EXPECT_EQ(taken.reused_journal, "near.jsonl:2");
  for (const auto& [path, value] : near.second.parameters())
    EXPECT_EQ(taken.job.parameters().at(path), value) << path;
}

TEST_F(Journal, AJournalOfAnotherSpecGivesExactlyTheRunsWhoseKeysMatch) {
  ASSERT_NO_FATAL_FAILURE(run_a());
  const std::string journal = path("a.jsonl");
  std::ofstream(path("b.yaml")) << packing_spec("b", 0.5);
  std::string err;
  ASSERT_EQ(run(path("b.yaml"), "b", journal, err), 0) << err;
  // b shares a's runs at the restitution's low level (its design rows 1 and 2, same seeds): those
  // and only those are taken, with a's results.
  std::map<std::string, std::string> a_metrics;
  for (const auto& job : stored_jobs("a")) a_metrics[job.run_key] = job.metrics;
  int taken = 0;
  for (const auto& job : stored_jobs("b")) {
    EXPECT_EQ(job.reused, a_metrics.count(job.run_key) > 0) << job.run_key;
    if (job.reused) {
      EXPECT_EQ(job.metrics, a_metrics[job.run_key]);
    }
    taken += job.reused;
  }
  EXPECT_EQ(taken, 2);
  // b's two runs of its own follow a's under a header naming b.
  const auto lines = file_lines(journal);
  ASSERT_EQ(lines.size(), 1u + 4u + 1u + 2u);
  EXPECT_EQ(nlohmann::json::parse(lines[5]).at("campaign"), "b");
  EXPECT_EQ(nlohmann::json::parse(lines[0]).at("campaign"), "a");
}

TEST_F(Journal, RunsOfAnotherLabProtocolVersionAreNotTaken) {
  ASSERT_NO_FATAL_FAILURE(run_a());
  const std::string journal = path("a.jsonl");
  auto lines = file_lines(journal);
  std::string err;
  auto changed = nlohmann::json::parse(lines[2]);
  const std::string test = changed.at("test");
  const int version = lab::protocol_version(test);
  changed["protocol"] = version + 1;
  lines[2] = changed.dump();
  write_lines(journal, lines);
  ASSERT_EQ(run(path("a.yaml"), "again", journal, err), 0) << err;
  EXPECT_NE(err.find("1 run(s) not taken: simulated under another version of their test's "
                     "protocol (1 " +
                     test + " run of version " + std::to_string(version + 1) +
                     " (the coordinator runs " + std::to_string(version) + "))"),
            std::string::npos)
      << err;
  for (const auto& job : stored_jobs("again"))
    EXPECT_EQ(job.reused, job.run_key != changed.at("run_key")) << job.run_key;
  // The run simulated again is kept under this version: a third directory takes all four.
  EXPECT_EQ(file_lines(journal).size(), 6u);
  ASSERT_EQ(run(path("a.yaml"), "third", journal, err), 0) << err;
  EXPECT_EQ(simulated_and_reused("third"), std::make_pair(0, 4));
}

// A run an older build simulated of a material this build refuses (lab::check_contact_range) is
// not offered to the coordinator: the journal's packing run is changed to A_H 1e-14 J on its
// 0.5 mm Hertz spheres (their van der Waals attraction at contact pressing a pair 7.4 radii
// deep) and to an impossible solid fraction; a campaign going on from that journal simulates the
// job again instead of taking it, and says why, naming the line.
TEST_F(Journal, RunsOfAMaterialThisBuildRefusesAreNotTaken) {
  std::string spec = packing_spec("a", 0.75);
  const std::string friction = "    tangential: {model: history, mu_s: 0.3}\n";
  spec.replace(
      spec.find(friction), friction.size(),
      friction + "    cohesion: {model: van_der_waals, hamaker: 1.0e-20, d_max: 1.0e-7}\n");
  std::ofstream(path("a.yaml")) << spec;
  const std::string journal = path("a.jsonl");
  std::string err;
  ASSERT_EQ(run(path("a.yaml"), "a", journal, err), 0) << err;
  auto lines = file_lines(journal);
  ASSERT_EQ(lines.size(), 5u);
  auto changed = nlohmann::json::parse(lines[2]);
  changed["parameters"]["particle_law.cohesion.hamaker"] = 1e-14;
  changed["metrics"]["solid_fraction"] = 0.999;
  lines[2] = changed.dump();
  write_lines(journal, lines);
  ASSERT_EQ(run(path("a.yaml"), "again", journal, err), 0) << err;
  EXPECT_NE(err.find("1 run(s) not taken: their material is one this build refuses to simulate "
                     "(the first, " +
                     journal + ":3: the particle-particle law of the material: its attraction"),
            std::string::npos)
      << err;
  for (const auto& job : stored_jobs("again")) {
    EXPECT_EQ(job.reused, job.run_key != changed.at("run_key")) << job.run_key;
    EXPECT_EQ(job.metrics.find("0.999"), std::string::npos) << job.metrics;
  }
  // A spec that names its instance otherwise plans the same runs (an instance's name is no part
  // of a run key) but has no instance of the journal's name: the run is checked against the spec
  // its journal segment was written by, and is not taken either.
  std::string renamed = spec;
  const std::string instance = "  - test: packing\n";
  renamed.replace(renamed.find(instance), instance.size(), instance + "    name: bed\n");
  std::ofstream(path("b.yaml")) << renamed;
  ASSERT_EQ(run(path("b.yaml"), "renamed", journal, err), 0) << err;
  EXPECT_NE(err.find("1 run(s) not taken: their material is one this build refuses"),
            std::string::npos)
      << err;
  for (const auto& job : stored_jobs("renamed")) {
    EXPECT_EQ(job.reused, job.run_key != changed.at("run_key")) << job.run_key;
    EXPECT_EQ(job.metrics.find("0.999"), std::string::npos) << job.metrics;
  }
}

// A run whose parameters do not apply to this spec's material (a path of another spec's laws)
// cannot be checked here and is offered as it is: the run goes on and takes it by its key.
TEST_F(Journal, ARunWhoseMaterialThisSpecCannotBuildIsOfferedUnchecked) {
  ASSERT_NO_FATAL_FAILURE(run_a());
  const std::string journal = path("a.jsonl");
  auto lines = file_lines(journal);
  auto changed = nlohmann::json::parse(lines[2]);
  changed["parameters"]["particle_law.cohesion.hamaker"] = 1e-14;
  lines[2] = changed.dump();
  write_lines(journal, lines);
  std::string err;
  ASSERT_EQ(run(path("a.yaml"), "again", journal, err), 0) << err;
  EXPECT_EQ(err.find("refuses to simulate"), std::string::npos) << err;
  EXPECT_EQ(simulated_and_reused("again"), std::make_pair(0, 4));
}

TEST_F(Journal, ALineCutShortIsDroppedAndAMalformedLineIsRefusedWithItsFileAndLine) {
  ASSERT_NO_FATAL_FAILURE(run_a());
  const std::string journal = path("a.jsonl");
  const auto whole = file_lines(journal);
  std::string err;
  // The writer killed during its last line: the line is dropped, its run simulated again and
  // appended whole.
  {
    std::ofstream cut(journal, std::ios::trunc);
    for (int i = 0; i < 4; ++i) cut << whole[std::size_t(i)] << "\n";
    cut << whole[4].substr(0, 40);
  }
  ASSERT_EQ(run(path("a.yaml"), "cut", journal, err), 0) << err;
  EXPECT_NE(err.find(journal + ":5: a line cut short while it was written, dropped"),
            std::string::npos)
      << err;
  EXPECT_EQ(simulated_and_reused("cut"), std::make_pair(1, 3));
  EXPECT_EQ(file_lines(journal).size(), 5u);
  // A line in the middle that is no run, or a run with a number that is not finite: refused
  // before anything starts, naming the file and line, the file left as it is.
  const auto kept = file_lines(journal);
  auto nan = nlohmann::json::parse(kept[1]);
  nan["metrics"]["solid_fraction"] = "NaN";  // how protobuf's JSON writes a NaN
  const std::pair<std::string, std::string> malformed[] = {
      {R"({"run_key": "abc"})",
       ":2: not a line of a campaign journal: run_key: 64 lower-case "
       "hex digits expected"},
      {nan.dump(), ":2: not a line of a campaign journal: metrics.solid_fraction: must be finite"},
      {"{\"run_key\": ", ":2: not a line of a campaign journal: "}};
  for (const auto& [line, message] : malformed) {
    auto lines = kept;
    lines[1] = line;
    write_lines(journal, lines);
    ASSERT_NE(run(path("a.yaml"), "refused", journal, err), 0);
    EXPECT_NE(err.find(journal + message), std::string::npos) << err;
    EXPECT_EQ(file_lines(journal), lines);
    EXPECT_FALSE(fs::exists(path("refused")));  // nothing started
  }
  // A journal that could not be written is refused as well.
  ASSERT_EQ(run(path("a.yaml"), "refused", path("missing/a.jsonl"), err), 2);
  EXPECT_NE(err.find(path("missing/a.jsonl") + ": its directory does not exist"), std::string::npos)
      << err;
  EXPECT_FALSE(fs::exists(path("refused")));
  // A gzip journal cut short: the damaged end is dropped, every whole line is read, and the
  // journal is written whole again.
  const std::string gz = path("a.jsonl.gz");
  write_lines(journal, kept);
  Process exported({DEMCAL_CLI_BIN, "export", path("a.yaml"), "--workdir", path("a"), "--format",
                    "journal", "-o", gz},
                   path("export.log"));
  ASSERT_EQ(exported.wait_exit(60), 0) << exported.log();
  fs::resize_file(gz, fs::file_size(gz) - 12);
  ASSERT_EQ(run(path("a.yaml"), "gzip", gz, err), 0) << err;
  EXPECT_NE(err.find(gz + ": its gzip end was cut short while it was written"), std::string::npos)
      << err;
  const auto [simulated, reused] = simulated_and_reused("gzip");
  EXPECT_EQ(simulated + reused, 4);
  EXPECT_GE(reused, 3);
  Process unzip({"/bin/gzip", "-dc", gz}, path("unzipped.jsonl"));
  ASSERT_EQ(unzip.wait_exit(30), 0);
  EXPECT_EQ(journal_keys(path("unzipped.jsonl")).size(), 4u);
}

}  // namespace
}  // namespace demcal::test
