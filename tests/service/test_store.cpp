// The coordinator's store on :memory: and on a real file: migrations, WAL, the lease state
// machine, exactly-once results, the retry cap, give-back, giving a job up and cancellation. Lease
// times are seconds of a fake monotonic clock passed in as `now`.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "server/convert.hpp"
#include "server/store.hpp"

namespace demcal::server {
namespace schema {
// The store's migrations as built into the binary (server/store.cpp).
const std::vector<std::string_view>& migrations();
}  // namespace schema
namespace {

constexpr auto kOk = LeaseAnswer::kOk;
constexpr auto kStale = LeaseAnswer::kStale;
constexpr auto kNotHolder = LeaseAnswer::kNotHolder;

std::vector<NewJob> jobs(int n) {
  std::vector<NewJob> out;
  for (int i = 0; i < n; ++i) out.push_back({i + 1, n - i, "packing", "design", "{}"});
  return out;
}

/// Runs SQL on a raw connection (a store written by an older coordinator, or by hand).
void exec_sql(sqlite3* db, const char* sql) {
  char* err = nullptr;
  const int rc = sqlite3_exec(db, sql, nullptr, nullptr, &err);
  const std::string msg = err ? err : "";
  sqlite3_free(err);
  ASSERT_EQ(rc, SQLITE_OK) << msg << " in " << sql;
}

/// A store's file in the temporary directory, named for the test and this process; it, its
/// write-ahead log, its shared memory and its lock file are removed before and after.
class TempStoreFile {
 public:
  explicit TempStoreFile(const std::string& name)
      : path_(std::filesystem::temp_directory_path() /
              ("demcal_store_" + name + "_" + std::to_string(::getpid()) + ".db")) {
    remove_all();
  }
  ~TempStoreFile() { remove_all(); }
  TempStoreFile(const TempStoreFile&) = delete;
  TempStoreFile& operator=(const TempStoreFile&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  void remove_all() const {
    for (const char* suffix : {"", "-wal", "-shm", ".lock"})
      std::filesystem::remove(path_.string() + suffix);
  }
  std::filesystem::path path_;
};

TEST(Store, FileIsWalAtTheLatestSchemaAndKeepsDataAcrossReopen) {
  const TempStoreFile file("reopen");
  const auto& path = file.path();
  std::int64_t leased = 0;
  {
    Store s(path.string());
    EXPECT_EQ(s.journal_mode(), "wal");
    EXPECT_EQ(s.schema_version(), Store::latest_schema_version());
    s.create_campaign("c", "{}", "{}", jobs(3), 0.0);
    const auto job = s.lease("w", 1.0);
    ASSERT_TRUE(job);
    leased = job->id;
    // Specs and results are the owner's alone: the file and its write-ahead log are 0600.
    namespace fs = std::filesystem;
    const auto others = fs::perms::group_all | fs::perms::others_all;
    for (const std::string& name : {path.string(), path.string() + "-wal"}) {
      ASSERT_TRUE(fs::exists(name)) << name;
      EXPECT_EQ(fs::status(name).permissions() & others, fs::perms::none) << name;
    }
  }
  {
    // Migrations are not re-run; the lease survived, with a whole lease from the reopening (at
    // 1000 s of the monotonic clock) however long the coordinator was down: the worker that
    // ran on meanwhile reports in time, and the reaper finds nothing expired.
    Store s(path.string(), {10.0, 1}, /*opened=*/1000.0);
    EXPECT_EQ(s.schema_version(), Store::latest_schema_version());
    ASSERT_EQ(s.campaigns().size(), 1u);
    const auto c = s.counts(1);
    EXPECT_EQ(c.leased, 1);
    EXPECT_EQ(c.queued, 2);
    ASSERT_TRUE(s.lease_deadline(leased));
    EXPECT_EQ(*s.lease_deadline(leased), 1010.0);
    EXPECT_EQ(s.reap(1009.0), 0);
    EXPECT_EQ(s.complete(leased, 1, "w", "{}", 1.0, 1009.5), LeaseAnswer::kOk);
    EXPECT_EQ(s.job(leased)->state, "done");
  }
}

TEST(Store, ASecondStoreOnTheSameFileIsRefusedNamingTheFileAndTheHolderUntilTheFirstCloses) {
  const TempStoreFile file("lock");
  const auto& path = file.path();
  {
    Store first(path.string());
    first.create_campaign("c", "{}", "{}", jobs(2), 0.0);
    try {
      Store second(path.string());
      ADD_FAILURE() << "two stores opened one file";
    } catch (const std::runtime_error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("refusing to open " + path.string()), std::string::npos) << what;
      EXPECT_NE(what.find("(pid " + std::to_string(::getpid()) + ")"), std::string::npos) << what;
    }
    // The refused store changed nothing: the first one goes on leasing.
    EXPECT_TRUE(first.lease("w", 1.0));
  }
  Store again(path.string());  // the lock went with the first store
  EXPECT_EQ(again.counts(1).total(), 2);
}

TEST(Store, LeasesOfAnEarlierRunOfTheEmbeddedDefaultGoBackUncountedAtOpening) {
  const TempStoreFile file("give_back");
  const auto& path = file.path();
  StoreLimits embedded{10.0, 1};
  embedded.give_back_leases_at_opening = true;
  std::int64_t leased = 0;
  {
    Store s(path.string(), embedded);
    s.create_campaign("c", "{}", "{}", jobs(2), 0.0);
    leased = s.lease("embedded", 1.0)->id;
    EXPECT_EQ(s.save_checkpoint(leased, 1, "embedded", "piston bed", "bed", 2.0), kOk);
  }  // the process ends with the job leased (killed)
  {
    // One attempt allowed: counted, the lease's expiry would fail the job; given back, it is
    // leased again with its checkpoint.
    Store s(path.string(), embedded, /*opened=*/1000.0);
    EXPECT_EQ(s.counts(1).leased, 0);
    const auto job = s.job(leased);
    EXPECT_EQ(job->state, "queued");
    EXPECT_NE(job->error.find("given back"), std::string::npos) << job->error;
    EXPECT_EQ(s.reap(2000.0), 0);
    const auto again = s.lease("embedded", 1001.0);
    ASSERT_TRUE(again);
    EXPECT_EQ(again->id, leased);
    EXPECT_EQ(again->attempt, 2);
    ASSERT_TRUE(s.checkpoint(leased));
    EXPECT_EQ(s.checkpoint(leased)->stage, "piston bed");
    EXPECT_EQ(s.complete(leased, 2, "embedded", "{}", 1.0, 1002.0), kOk);
  }
}

std::string file_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(Store, ADamagedFileIsRefusedNamingTheFileAndTheDamageAndIsLeftUnchanged) {
  const TempStoreFile file("damaged");
  const auto& path = file.path();
  {
    // A real store with enough jobs to fill several pages; closing it copies the write-ahead
    // log into the file and removes the log.
    Store s(path.string());
    s.create_campaign("c", "{}", "{}", jobs(500), 0.0);
  }
  ASSERT_FALSE(std::filesystem::exists(path.string() + "-wal"));
  // The page of the jobs table's root (an interior page: 500 jobs fill several leaves).
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_stmt* stmt = nullptr;
  sqlite3_prepare_v2(db, "SELECT rootpage FROM sqlite_schema WHERE name = 'jobs'", -1, &stmt,
                     nullptr);
  ASSERT_EQ(sqlite3_step(stmt), SQLITE_ROW);
  const auto root = static_cast<std::size_t>(sqlite3_column_int(stmt, 0));
  sqlite3_finalize(stmt);
  sqlite3_close(db);
  std::string bytes = file_bytes(path);
  constexpr std::size_t kPage = 4096;  // SQLite's default page size
  ASSERT_GE(bytes.size(), root * kPage);
  // Garbage over most of that page, as a torn write or a bad sector would leave it.
  for (std::size_t i = (root - 1) * kPage + 8; i < root * kPage - 64; ++i)
    bytes[i] = static_cast<char>(0xA5 ^ (i * 131));
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
  try {
    Store s(path.string());
    FAIL() << "a damaged file was opened";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path.string()), std::string::npos) << what;
    EXPECT_NE(what.find("quick_check"), std::string::npos) << what;
  }
  EXPECT_EQ(file_bytes(path), bytes) << "the damaged file was modified";
}

TEST(Store, AFileWithARowBreakingAForeignKeyIsRefusedNamingTheFileAndTheRowAndKeepsIt) {
  const TempStoreFile file("foreign_key");
  const auto& path = file.path();
  {
    Store s(path.string());
    s.create_campaign("c", "{}", "{}", jobs(1), 0.0);
  }
  // A checkpoint of a job that does not exist, written by hand with foreign keys off (SQLite's
  // default for a connection).
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr), SQLITE_OK);
  exec_sql(db,
           "INSERT INTO checkpoints (job_id, attempt, worker, stage, state, stored) "
           "VALUES (77, 1, 'w', 'bed', x'00', 0)");
  sqlite3_close(db);
  try {
    Store s(path.string());
    FAIL() << "a store with a broken foreign key was opened";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path.string()), std::string::npos) << what;
    EXPECT_NE(what.find("row 77 of checkpoints refers to a jobs row that does not exist"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("changed outside the coordinator"), std::string::npos) << what;
  }
  // Nothing was deleted: the row is still there to be mended.
  ASSERT_EQ(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_stmt* stmt = nullptr;
  sqlite3_prepare_v2(db, "SELECT count(*) FROM checkpoints WHERE job_id = 77", -1, &stmt, nullptr);
  ASSERT_EQ(sqlite3_step(stmt), SQLITE_ROW);
  EXPECT_EQ(sqlite3_column_int(stmt, 0), 1);
  sqlite3_finalize(stmt);
  sqlite3_close(db);
}

TEST(Store, LeasesInRunOrderAndStoresAResultExactlyOnce) {
  Store s(":memory:");
  const auto id = s.create_campaign("c", "{}", "{}", jobs(2), 0.0);
  const auto a = s.lease("w1", 1.0);
  ASSERT_TRUE(a);
  EXPECT_EQ(a->run_order, 1);  // std_order 2 runs first
  EXPECT_EQ(a->attempt, 1);
  EXPECT_EQ(s.complete(a->id, 1, "w1", R"({"x":1})", 0.5, 2.0), kOk);
  EXPECT_EQ(s.complete(a->id, 1, "w1", R"({"x":2})", 0.5, 2.1), kStale);  // a repeat is refused
  EXPECT_EQ(s.result_count(a->id), 1);
  EXPECT_EQ(*s.job(a->id)->metrics_json, R"({"x":1})");
  EXPECT_EQ(s.campaign(id)->state, "running");
  const auto b = s.lease("w2", 3.0);
  ASSERT_TRUE(b);
  EXPECT_FALSE(s.lease("w3", 3.0));  // nothing left
  EXPECT_EQ(s.complete(b->id, 1, "w2", "{}", 0.5, 4.0), kOk);
  EXPECT_EQ(s.campaign(id)->state, "done");
}

TEST(Store, KeepsTheLatestCheckpointOfTheLeaseHolderUntilTheResultIsStored) {
  Store s(":memory:", {10.0, 3});
  s.create_campaign("c", "{}", "{}", jobs(1), 0.0);
  const auto a = s.lease("w1", 0.0);
  const std::string state("\0binary\xff", 9);
  EXPECT_EQ(s.save_checkpoint(a->id, 1, "intruder", "bed", state, 1.0), kNotHolder);
  EXPECT_FALSE(s.checkpoint(a->id));
  EXPECT_EQ(s.save_checkpoint(a->id, 1, "w1", "bed", "old", 1.0, {0.5, 1000}), kOk);
  EXPECT_EQ(s.save_checkpoint(a->id, 1, "w1", "bed", state, 2.0, {0.75, 1500}), kOk);
  // The latest checkpoint's clock is the one the job list shows.
  const auto marks = s.checkpoint_marks(1);
  ASSERT_EQ(marks.count(a->id), 1u);
  EXPECT_EQ(marks.at(a->id).clock.simulated_seconds, 0.75);
  EXPECT_EQ(marks.at(a->id).clock.steps, 1500);
  // The lease lapses: the next one is handed the latest checkpoint, bytes intact; the lapsed
  // lease can no longer replace it.
  EXPECT_EQ(s.reap(20.0), 1);
  EXPECT_EQ(s.save_checkpoint(a->id, 1, "w1", "bed", "late", 20.5), kStale);
  const auto b = s.lease("w2", 21.0);
  ASSERT_TRUE(b);
  const auto kept = s.checkpoint(b->id);
  ASSERT_TRUE(kept);
  EXPECT_EQ(kept->stage, "bed");
  EXPECT_EQ(kept->state, state);
  EXPECT_EQ(kept->attempt, 1);
  EXPECT_EQ(s.complete(b->id, 2, "w2", "{}", 0.5, 22.0), kOk);
  EXPECT_FALSE(s.checkpoint(b->id));
}

// A build that raises a test's protocol version re-keys its jobs not done: a job's checkpoint was
// simulated under the old protocol, so a re-keyed job starts afresh; a job whose key stays keeps
// its checkpoint.
TEST(Store, AJobReKeyedUnderAnotherProtocolLosesItsCheckpoint) {
  Store s(":memory:", {10.0, 3});
  s.create_campaign(
      "c", "{}", "{}",
      {{1, 1, "shear_cell", "design", R"({"row":1})"}, {2, 2, "packing", "design", R"({"row":2})"}},
      0.0);
  s.refresh_run_keys([](const std::string& payload) { return RunKey{"v4 " + payload, 4}; });
  const auto a = s.lease("w1", 0.0);
  const auto b = s.lease("w2", 0.0);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(s.save_checkpoint(a->id, 1, "w1", "settling", "a", 1.0), kOk);
  EXPECT_EQ(s.save_checkpoint(b->id, 1, "w2", "settling", "b", 1.0), kOk);
  EXPECT_EQ(s.reap(20.0), 2);
  s.refresh_run_keys([](const std::string& payload) { return RunKey{"v4 " + payload, 4}; });
  EXPECT_TRUE(s.checkpoint(a->id));
  EXPECT_TRUE(s.checkpoint(b->id));
  // The shear cell's protocol goes to 5; the packing's stays.
  s.refresh_run_keys([](const std::string& payload) {
    return payload == R"({"row":1})" ? RunKey{"v5 " + payload, 5} : RunKey{"v4 " + payload, 4};
  });
  EXPECT_EQ(s.job(a->id)->run_key, (RunKey{R"(v5 {"row":1})", 5}));
  EXPECT_FALSE(s.checkpoint(a->id));
  ASSERT_TRUE(s.checkpoint(b->id));
  EXPECT_EQ(s.checkpoint(b->id)->state, "b");
  const auto again = s.lease("w3", 21.0);
  ASSERT_TRUE(again);
  EXPECT_EQ(again->id, a->id);  // run order 1 first
  EXPECT_FALSE(s.checkpoint(again->id));
}

TEST(Store, KeepsTheFlagsAndTheCostOfAResult) {
  Store s(":memory:");
  s.create_campaign("c", "{}", "{}", jobs(2), 0.0);
  const auto a = s.lease("w1", 1.0);
  ASSERT_TRUE(a);
  const std::string flags = R"({"x":"phase 'load 1' did not reach stress 150 Pa"})";
  const std::string cost = R"({"steps":"12","phases":[{"name":"settle","reached":true}]})";
  EXPECT_EQ(s.complete(a->id, 1, "w1", R"({"x":1})", 0.5, 2.0, flags, cost), kOk);
  EXPECT_EQ(s.job(a->id)->flags_json, flags);
  EXPECT_EQ(s.job(a->id)->cost_json, cost);
  // A result stored without them reads as empty objects.
  const auto b = s.lease("w2", 3.0);
  ASSERT_TRUE(b);
  EXPECT_EQ(s.complete(b->id, 1, "w2", "{}", 0.5, 4.0), kOk);
  EXPECT_EQ(s.job(b->id)->flags_json, "{}");
  EXPECT_EQ(s.job(b->id)->cost_json, "{}");
}

TEST(Store, LateCompleteOfAnExpiredLeaseIsRefusedAndTheNewLeaseWins) {
  Store s(":memory:", {10.0, 3});
  s.create_campaign("c", "{}", "{}", jobs(1), 0.0);
  const auto a = s.lease("w1", 0.0);
  EXPECT_EQ(s.heartbeat(a->id, 1, "w1", 5.0), kOk);  // deadline now 15
  EXPECT_EQ(s.reap(14.0), 0);
  EXPECT_EQ(s.reap(16.0), 1);  // expired: back to the queue
  EXPECT_EQ(s.complete(a->id, 1, "w1", "{}", 1.0, 16.5), kStale);
  EXPECT_EQ(s.heartbeat(a->id, 1, "w1", 16.5), kStale);
  const auto b = s.lease("w2", 17.0);
  ASSERT_TRUE(b);
  EXPECT_EQ(b->id, a->id);
  EXPECT_EQ(b->attempt, 2);
  EXPECT_EQ(s.complete(a->id, 1, "w1", "{}", 1.0, 18.0), kStale);  // stale attempt number
  EXPECT_EQ(s.complete(b->id, 2, "w2", "{}", 1.0, 18.0), kOk);
  EXPECT_EQ(s.result_count(a->id), 1);
}

TEST(Store, ARetriedCompleteOfTheStoredResultSucceedsAndStoresItOnce) {
  // The coordinator stored the result but its answer was lost: the worker's retry is a success,
  // not a refusal that would make it log a lost result.
  Store s(":memory:", {10.0, 3});
  s.create_campaign("c", "{}", "{}", jobs(1), 0.0);
  const auto a = s.lease("w1", 0.0);
  EXPECT_EQ(s.complete(a->id, 1, "w1", R"({"x":1})", 0.5, 1.0), kOk);
  EXPECT_EQ(s.complete(a->id, 1, "w1", R"({"x":1})", 0.5, 30.0), kOk);  // after the deadline too
  EXPECT_EQ(s.result_count(a->id), 1);
  // Another result, another attempt or another worker is no retry of it.
  EXPECT_EQ(s.complete(a->id, 1, "w1", R"({"x":1})", 0.6, 2.0), kStale);
  EXPECT_EQ(s.complete(a->id, 2, "w1", R"({"x":1})", 0.5, 2.0), kStale);
  EXPECT_EQ(s.complete(a->id, 1, "w2", R"({"x":1})", 0.5, 2.0), kStale);
  EXPECT_EQ(*s.job(a->id)->metrics_json, R"({"x":1})");
}

TEST(Store, ABeatTakenAfterItsLeasesResultIsNoLostLease) {
  // A worker beats until its Complete has been answered, so the coordinator may take a beat of
  // a lease whose result it has just stored: the lease ended by its result, it was not lost.
  Store s(":memory:", {10.0, 3});
  s.create_campaign("c", "{}", "{}", jobs(2), 0.0);
  const auto a = s.lease("w1", 0.0);
  ASSERT_TRUE(a);
  EXPECT_EQ(s.complete(a->id, 1, "w1", R"({"x":1})", 0.5, 1.0), kOk);
  EXPECT_EQ(s.heartbeat(a->id, 1, "w1", 2.0), kOk);
  EXPECT_EQ(s.job(a->id)->state, "done");
  // Another worker's or another attempt's beat is refused, as is one of a lease that expired.
  EXPECT_EQ(s.heartbeat(a->id, 1, "w2", 2.0), kStale);
  EXPECT_EQ(s.heartbeat(a->id, 2, "w1", 2.0), kStale);
  const auto b = s.lease("w1", 3.0);
  ASSERT_TRUE(b);
  EXPECT_EQ(s.reap(14.0), 1);
  EXPECT_EQ(s.heartbeat(b->id, 1, "w1", 14.5), kStale);
}

TEST(Store, OnlyTheLeaseHolderMayHeartbeatCompleteOrFailIt) {
  Store s(":memory:", {10.0, 3});
  s.create_campaign("c", "{}", "{}", jobs(1), 0.0);
  const auto a = s.lease("w1", 0.0);
  EXPECT_EQ(s.heartbeat(a->id, 1, "intruder", 1.0), kNotHolder);
  EXPECT_EQ(s.complete(a->id, 1, "intruder", "{}", 0.5, 1.0), kNotHolder);
  EXPECT_EQ(s.fail(a->id, 1, "intruder", "no", false, false, 1.0), kNotHolder);
  EXPECT_EQ(s.fail(a->id, 1, "intruder", "no", true, true, 1.0), kNotHolder);
  EXPECT_EQ(s.job(a->id)->state, "leased");
  EXPECT_EQ(s.result_count(a->id), 0);
  EXPECT_EQ(s.complete(a->id, 1, "w1", "{}", 0.5, 2.0), kOk);
}

/// A design job of run key `key` (a run key stands for what determines the result; here a name).
NewJob keyed_job(int run_order, const std::string& key) {
  return {run_order, run_order, "packing", "design", "{}", {key, 1}};
}

TEST(Store, AQueuedJobTakesTheResultOfAFinishedJobWithItsRunKeyInAnyCampaign) {
  Store s(":memory:");
  const auto first = s.create_campaign("a", "{}", "{}", {keyed_job(1, "k1")}, 0.0);
  const auto a = s.lease("w1", 1.0);
  ASSERT_TRUE(a);
  const std::string flags = R"({"x":"phase 'settle' did not reach rest"})";
  const std::string cost = R"({"steps":"12"})";
  const std::string series = R"({"curve":{"columns":["t"],"rows":[[0.5]]}})";
  EXPECT_EQ(s.complete(a->id, 1, "w1", R"({"x":1})", 2.5, 2.0, flags, cost, series), kOk);
  EXPECT_EQ(s.campaign(first)->state, "done");
  // A second campaign asks for the same run and one of its own: the worker gets only the new one.
  const auto second =
      s.create_campaign("b", "{}", "{}", {keyed_job(1, "k1"), keyed_job(2, "k2")}, 3.0);
  const auto b = s.lease("w2", 4.0);
  ASSERT_TRUE(b);
  EXPECT_EQ(b->run_key.key, "k2");
  const auto jobs = s.jobs(second);
  const JobRow& reused = jobs[0];
  EXPECT_EQ(reused.state, "done");
  EXPECT_EQ(reused.attempt, 0);  // never leased: not simulated
  EXPECT_TRUE(reused.reused());
  EXPECT_EQ(reused.reused_from, a->id);
  EXPECT_EQ(*reused.metrics_json, R"({"x":1})");
  EXPECT_EQ(reused.flags_json, flags);
  EXPECT_EQ(reused.cost_json, cost);
  EXPECT_EQ(reused.wall_seconds, 2.5);
  EXPECT_EQ(reused.result_attempt, 1);  // the source's attempt, which ran it
  EXPECT_EQ(s.series(second).at(reused.id), series);
  EXPECT_EQ(s.counts(second).reused, 1);
  EXPECT_EQ(s.counts(second).done, 1);
  EXPECT_EQ(s.counts(first).reused, 0);
  EXPECT_EQ(s.complete(b->id, 1, "w2", R"({"x":2})", 1.0, 5.0), kOk);
  EXPECT_EQ(s.campaign(second)->state, "done");
  EXPECT_FALSE(s.job(b->id)->reused());
  // A campaign all of whose runs are held is done at the next lease, with nothing leased.
  const auto third = s.create_campaign("c", "{}", "{}", {keyed_job(1, "k2")}, 6.0);
  EXPECT_FALSE(s.lease("w3", 7.0));
  EXPECT_EQ(s.campaign(third)->state, "done");
  EXPECT_EQ(s.jobs(third)[0].reused_from, b->id);
  // A job without a run key is never given another's result.
  s.create_campaign("d", "{}", "{}", {keyed_job(1, "")}, 8.0);
  EXPECT_TRUE(s.lease("w4", 9.0));
}

TEST(Store, AJobWaitsWhileAnotherJobRunsItsRunKey) {
  Store s(":memory:", {10.0, 3});
  const auto id = s.create_campaign(
      "c", "{}", "{}", {keyed_job(1, "k"), keyed_job(2, "k"), keyed_job(3, "other")}, 0.0);
  const auto a = s.lease("w1", 1.0);
  ASSERT_TRUE(a);
  const auto b = s.lease("w2", 1.0);  // the second "k" waits for the first's result
  ASSERT_TRUE(b);
  EXPECT_EQ(b->run_key.key, "other");
  EXPECT_FALSE(s.lease("w3", 1.0));
  // The running one fails and goes back to the queue: the waiting one may run now.
  EXPECT_EQ(s.fail(a->id, 1, "w1", "worker error", true, false, 2.0), kOk);
  const auto c = s.lease("w3", 3.0);
  ASSERT_TRUE(c);
  EXPECT_EQ(c->run_key.key, "k");
  EXPECT_EQ(s.complete(c->id, c->attempt, "w3", R"({"x":3})", 1.0, 4.0), kOk);
  EXPECT_EQ(s.complete(b->id, 1, "w2", R"({"x":4})", 1.0, 4.0), kOk);
  EXPECT_FALSE(s.lease("w1", 5.0));  // the other "k" takes the result
  EXPECT_EQ(s.campaign(id)->state, "done");
  EXPECT_EQ(s.counts(id).reused, 1);
  EXPECT_EQ(s.counts(id).done, 3);
}

TEST(Store, AJobWaitingForAnotherOfItsRowIsLeasedOnceThatOneHasEnded) {
  Store s(":memory:", {10.0, 3});
  // Row 1: the tensile job (listed first) waits for the compression; row 2 likewise; a verify
  // job of row 1 waits for nothing of the design.
  const std::vector<NewJob> jobs = {
      {1, 1, "tensile", "design", "{}", RunKey{}, "compression"},
      {1, 1, "compression", "design", "{}"},
      {2, 2, "tensile", "design", "{}", RunKey{}, "compression"},
      {2, 2, "compression", "design", "{}"},
  };
  const auto id = s.create_campaign("c", "{}", "{}", jobs, 0.0);
  const auto a = s.lease("w1", 1.0);
  const auto b = s.lease("w2", 1.0);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(std::pair(a->test, a->std_order), std::pair(std::string("compression"), 1));
  EXPECT_EQ(std::pair(b->test, b->std_order), std::pair(std::string("compression"), 2));
  EXPECT_FALSE(s.lease("w3", 1.0));  // both tensile jobs wait for their rows' compressions
  // A failed compression ends its row's wait as a finished one does.
  EXPECT_EQ(s.fail(b->id, b->attempt, "w2", "diverged", false, false, 2.0), kOk);
  const auto c = s.lease("w2", 2.0);
  ASSERT_TRUE(c);
  EXPECT_EQ(std::pair(c->test, c->std_order), std::pair(std::string("tensile"), 2));
  EXPECT_FALSE(s.lease("w3", 2.0));
  EXPECT_EQ(s.complete(a->id, a->attempt, "w1", R"({"x":1})", 1.0, 3.0), kOk);
  const auto d = s.lease("w1", 3.0);
  ASSERT_TRUE(d);
  EXPECT_EQ(std::pair(d->test, d->std_order), std::pair(std::string("tensile"), 1));
  EXPECT_EQ(s.counts(id).leased, 2);
}

TEST(Store, AJobWhoseWaitHasEndedIsLeasedBeforeTheJobsLaterInRunOrder) {
  Store s(":memory:", {10.0, 3});
  // Two rows of three tests in the run order a verification or a diagnosis gives them (by test):
  // the compressions, the shear cells, then the tensile jobs, each after its row's compression.
  std::vector<NewJob> jobs;
  for (int row = 1; row <= 2; ++row) {
    jobs.push_back({row, 1, "compression", "design", "{}"});
    jobs.push_back({row, 2, "shear", "design", "{}"});
    jobs.push_back({row, 3, "tensile", "design", "{}", RunKey{}, "compression"});
  }
  s.create_campaign("c", "{}", "{}", jobs, 0.0);
  const auto row_of = [](const std::optional<JobRow>& job) {
    return std::pair(job->test, job->std_order);
  };
  const auto first = s.lease("w1", 1.0);
  ASSERT_TRUE(first);
  EXPECT_EQ(row_of(first), std::pair(std::string("compression"), 1));
  EXPECT_EQ(s.complete(first->id, first->attempt, "w1", R"({"x":1})", 1.0, 2.0), kOk);
  // Row 1's tensile job goes before row 2's compression and both shear cells.
  const auto second = s.lease("w1", 2.0);
  ASSERT_TRUE(second);
  EXPECT_EQ(row_of(second), std::pair(std::string("tensile"), 1));
  // The rest in run order; row 2's tensile job waits for its compression.
  const auto third = s.lease("w2", 2.0);
  const auto fourth = s.lease("w3", 2.0);
  const auto fifth = s.lease("w4", 2.0);
  ASSERT_TRUE(third && fourth && fifth);
  EXPECT_EQ(row_of(third), std::pair(std::string("compression"), 2));
  EXPECT_EQ(row_of(fourth), std::pair(std::string("shear"), 1));
  EXPECT_EQ(row_of(fifth), std::pair(std::string("shear"), 2));
  EXPECT_FALSE(s.lease("w5", 2.0));
}

TEST(Store, AStoreOfSchemaElevenMarksTheJobsWhoseWaitHasEndedAndLeasesThemFirst) {
  const TempStoreFile file("v11");
  const auto& path = file.path();
  {
    // A store as the coordinator of schema version 11 left it: row 1's compression done, its
    // tensile job queued behind row 2's compression in run order; row 2's tensile job waiting.
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(path.string().c_str(), &db), SQLITE_OK);
    for (int i = 0; i < 11; ++i) exec_sql(db, std::string(schema::migrations()[i]).c_str());
    exec_sql(db, "PRAGMA user_version=11");
    exec_sql(db,
             "INSERT INTO campaigns (name, state, spec_json, design_json, created, finished) "
             "VALUES ('c', 'running', '{}', '{}', 1.0, 0.0)");
    exec_sql(db,
             "INSERT INTO jobs (campaign_id, std_order, run_order, test, kind, payload, state, "
             "waits_for) VALUES (1, 1, 1, 'compression', 'design', '{}', 'done', ''), "
             "(1, 2, 2, 'compression', 'design', '{}', 'queued', ''), "
             "(1, 1, 3, 'tensile', 'design', '{}', 'queued', 'compression'), "
             "(1, 2, 4, 'tensile', 'design', '{}', 'queued', 'compression')");
    ASSERT_EQ(sqlite3_close(db), SQLITE_OK);
  }
  Store s(path.string());
  EXPECT_EQ(s.schema_version(), Store::latest_schema_version());
  const auto first = s.lease("w", 1.0);
  ASSERT_TRUE(first);
  EXPECT_EQ(first->id, 3);  // row 1's tensile job, before row 2's compression
  const auto second = s.lease("w", 1.0);
  ASSERT_TRUE(second);
  EXPECT_EQ(second->id, 2);
  EXPECT_FALSE(s.lease("w", 1.0));  // row 2's tensile job waits for its compression
  EXPECT_EQ(s.complete(second->id, second->attempt, "w", "{}", 1.0, 2.0), kOk);
  const auto third = s.lease("w", 2.0);
  ASSERT_TRUE(third);
  EXPECT_EQ(third->id, 4);
}

TEST(Store, RunsOfAJournalAreTakenByTheJobsOfTheirKeysAndNeverReplaceARunHeld) {
  Store s(":memory:");
  const std::string series = R"({"curve":{"columns":["t"],"rows":[[1.0]]}})";
  // Imported as a store before schema 14 kept it: without its point.
  const FinishedRun run{"k1",          2,  R"({"x":7})", 3.0, "{}", R"({"steps":"5"})", series,
                        "old.jsonl:2", "", "",           "{}"};
  EXPECT_EQ(s.import_runs({run}), 1);
  EXPECT_TRUE(s.holds_run("k1"));
  EXPECT_FALSE(s.holds_run("k2"));
  EXPECT_TRUE(s.journal_runs_at("packing", "1").empty());
  FinishedRun other = run;
  other.metrics_json = R"({"x":8})";
  other.source = "new.jsonl:2";
  other.test = "packing";
  other.seed = "1";
  other.parameters_json = R"({"particle_law.tangential.mu_s":0.3})";
  EXPECT_EQ(s.import_runs({other}), 0);  // the key is held: the run held stays, its point added
  const auto at = s.journal_runs_at("packing", "1");
  ASSERT_EQ(at.size(), 1u);
  EXPECT_EQ(at[0].run_key, "k1");
  EXPECT_EQ(at[0].parameters_json, other.parameters_json);
  EXPECT_TRUE(s.journal_runs_at("packing", "2").empty());
  const auto id = s.create_campaign("c", "{}", "{}", {keyed_job(1, "k1")}, 0.0);
  EXPECT_FALSE(s.lease("w", 1.0));
  const JobRow job = s.jobs(id)[0];
  EXPECT_EQ(job.state, "done");
  EXPECT_EQ(job.reused_from, 0);
  EXPECT_EQ(job.reused_journal, "old.jsonl:2");
  EXPECT_EQ(*job.metrics_json, R"({"x":7})");
  EXPECT_EQ(job.result_attempt, 2);
  EXPECT_EQ(job.cost_json, R"({"steps":"5"})");
  EXPECT_EQ(s.series(id).at(job.id), series);
  EXPECT_EQ(s.campaign(id)->state, "done");
  // A later job of that key takes it from the job that holds it now.
  const auto later = s.create_campaign("d", "{}", "{}", {keyed_job(1, "k1")}, 2.0);
  EXPECT_FALSE(s.lease("w", 3.0));
  EXPECT_EQ(s.jobs(later)[0].reused_from, job.id);
}

TEST(Store, ACampaignOfManyBatchesIsInsertedWholeInRunOrder) {
  Store s(":memory:");
  const int n = 3 * static_cast<int>(Store::kInsertBatch) + 5;
  const auto id = s.create_campaign("big", "{}", "{}", jobs(n), 0.0);
  EXPECT_EQ(s.counts(id).queued, n);
  ASSERT_EQ(s.campaigns().size(), 1u);
  EXPECT_EQ(s.lease("w", 0.0)->run_order, 1);
}

TEST(Store, ACampaignWhoseJobsWereNotAllInsertedIsDroppedOnOpening) {
  // A coordinator stopped between two batches of a submission it never answered.
  const TempStoreFile file("partial");
  const auto& path = file.path();
  {
    Store s(path.string());
    s.create_campaign("whole", "{}", "{}", jobs(2), 0.0);
  }
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db,
                         "INSERT INTO campaigns (name, state, spec_json, design_json, created, "
                         "ready) VALUES ('partial', 'running', '{}', '{}', 0, 0);"
                         "INSERT INTO jobs (campaign_id, std_order, run_order, test, kind, "
                         "payload, state) VALUES (2, 1, 1, 'packing', 'design', '{}', 'queued');",
                         nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(db);
  {
    Store s(path.string());
    ASSERT_EQ(s.campaigns().size(), 1u);
    EXPECT_EQ(s.campaigns()[0].name, "whole");
    EXPECT_FALSE(s.campaign(2));
    EXPECT_EQ(s.counts(2).total(), 0);
  }
}

TEST(Store, TimeTheLockIsHeldByOneLongWriteIsAddedToEveryLeaseDeadline) {
  // A write holding the store's lock for 100 s (a stalled disk; here the lock-hold clock jumps
  // while the write holds it): the workers whose heartbeats waited behind it keep their leases.
  double t = 0.0;
  int reads_until_jump = 0;
  StoreLimits limits{10.0, 3};
  limits.clock = [&] {
    if (reads_until_jump > 0 && --reads_until_jump == 0) t += 100.0;
    return t;
  };
  Store s(":memory:", limits);
  s.create_campaign("c", "{}", "{}", jobs(1), 0.0);
  const auto a = s.lease("w", 0.0);
  ASSERT_EQ(*s.lease_deadline(a->id), 10.0);
  reads_until_jump = 2;  // the second reading is the end of the next hold: held 100 s
  s.create_campaign("d", "{}", "{}", jobs(1), 0.0);
  EXPECT_EQ(*s.lease_deadline(a->id), 110.0);
  EXPECT_EQ(s.reap(105.0), 0);
  EXPECT_EQ(s.heartbeat(a->id, 1, "w", 105.0), kOk);
  // A short hold adds nothing.
  s.create_campaign("e", "{}", "{}", jobs(1), 0.0);
  EXPECT_EQ(*s.lease_deadline(a->id), 115.0);
}

TEST(Store, ExpiredBeforeTheReaperRunsIsAlsoRefused) {
  Store s(":memory:", {10.0, 3});
  s.create_campaign("c", "{}", "{}", jobs(1), 0.0);
  const auto a = s.lease("w1", 0.0);
  EXPECT_EQ(s.complete(a->id, 1, "w1", "{}", 1.0, 10.5), kStale);
  EXPECT_EQ(s.result_count(a->id), 0);
}

TEST(Store, RetryCapFailsTheJobAndGiveBackDoesNotCount) {
  Store s(":memory:", {10.0, 2});
  const auto id = s.create_campaign("c", "{}", "{}", jobs(1), 0.0);
  auto a = s.lease("w", 0.0);
  EXPECT_EQ(s.fail(a->id, 1, "w", "stopping", true, true, 1.0), kOk);  // given back
  a = s.lease("w", 2.0);
  EXPECT_EQ(a->attempt, 2);
  EXPECT_EQ(s.fail(a->id, 2, "w", "io error", true, false, 3.0), kOk);  // counted: 1 of 2
  EXPECT_EQ(s.job(a->id)->state, "queued");
  a = s.lease("w", 4.0);
  EXPECT_EQ(s.reap(20.0), 1);  // counted: 2 of 2 -> failed
  EXPECT_EQ(s.job(a->id)->state, "failed");
  EXPECT_NE(s.job(a->id)->error.find("expired"), std::string::npos);
  EXPECT_EQ(s.campaign(id)->state, "done");
}

// A lease that has run past the coordinator's --yield-after while a job waits is asked to yield;
// a job that yielded goes behind the queued jobs that yielded fewer times, and each yield doubles
// the time its next lease runs before it is asked again. A give-back does not count as an attempt.
TEST(Store, ALongLeaseYieldsToTheQueuedJobsAndItsJobGoesBehindThem) {
  Store s(":memory:", {100.0, 2});
  s.create_campaign("c", "{}", "{}", jobs(3), 0.0);
  const auto a = s.lease("w", 0.0);
  ASSERT_TRUE(a);
  EXPECT_FALSE(s.yield_due(a->id, 5.0, 0.0));  // 0: never
  EXPECT_FALSE(s.yield_due(a->id, 1.5, 2.0));  // within its share
  EXPECT_TRUE(s.yield_due(a->id, 2.5, 2.0));   // past it, two jobs waiting
  EXPECT_EQ(s.fail(a->id, 1, "w", "yielded at its checkpoint 'settling'", true, true, 3.0, true),
            kOk);
  EXPECT_EQ(s.job(a->id)->state, "queued");
  const auto b = s.lease("w", 3.0);
  ASSERT_TRUE(b);
  EXPECT_NE(b->id, a->id);                    // a comes first in run order, but it yielded
  EXPECT_TRUE(s.yield_due(b->id, 5.5, 2.0));  // the third job waits, never yielded
  EXPECT_EQ(s.fail(b->id, 1, "w", "yielded", true, true, 6.0, true), kOk);
  const auto c = s.lease("w", 6.0);
  ASSERT_TRUE(c);
  EXPECT_NE(c->id, a->id);
  EXPECT_NE(c->id, b->id);
  EXPECT_FALSE(s.yield_due(c->id, 100.0, 2.0));  // the jobs waiting yielded more often
  EXPECT_EQ(s.complete(c->id, 1, "w", "{}", 1.0, 100.0), kOk);
  EXPECT_FALSE(s.yield_due(c->id, 200.0, 2.0));  // no lease
  // a and b yielded once each: a first again by run order, with twice the share (4 s).
  const auto a2 = s.lease("w", 100.0);
  ASSERT_TRUE(a2);
  EXPECT_EQ(a2->id, a->id);
  EXPECT_EQ(a2->attempt, 2);
  EXPECT_EQ(a2->counted, 1);  // the yield was not counted against the cap of 2
  EXPECT_EQ(a2->yields, 1);
  EXPECT_EQ(s.job(c->id)->yields, 0);
  EXPECT_FALSE(s.yield_due(a->id, 103.0, 2.0));
  EXPECT_TRUE(s.yield_due(a->id, 104.5, 2.0));  // b waits, yielded as often
  // Once b runs too, nothing waits: a runs on.
  const auto b2 = s.lease("w", 104.5);
  ASSERT_TRUE(b2);
  EXPECT_EQ(b2->id, b->id);
  EXPECT_FALSE(s.yield_due(a->id, 1000.0, 2.0));
}

TEST(Store, SimulationFailureFailsAtOnce) {
  Store s(":memory:");
  s.create_campaign("c", "{}", "{}", jobs(1), 0.0);
  const auto a = s.lease("w", 0.0);
  EXPECT_EQ(s.fail(a->id, 1, "w", "simulation failed (not finite)", false, false, 1.0), kOk);
  EXPECT_EQ(s.job(a->id)->state, "failed");
  EXPECT_FALSE(s.lease("w", 2.0));
}

TEST(Store, CancelStopsLeasingAndRefusesResults) {
  Store s(":memory:");
  const auto id = s.create_campaign("c", "{}", "{}", jobs(3), 0.0);
  const auto a = s.lease("w", 0.0);
  EXPECT_TRUE(s.cancel(id, 1.0));
  EXPECT_FALSE(s.cancel(id, 1.5));  // only a running campaign is cancelled
  EXPECT_FALSE(s.cancel(999, 1.0));
  EXPECT_FALSE(s.lease("w", 2.0));
  EXPECT_EQ(s.complete(a->id, 1, "w", "{}", 1.0, 2.0), kStale);
  EXPECT_EQ(s.counts(id).cancelled, 3);
  EXPECT_EQ(s.campaign(id)->state, "cancelled");
  // A done campaign is not cancelled: it stays done with its results.
  const auto done = s.create_campaign("d", "{}", "{}", jobs(1), 3.0);
  const auto b = s.lease("w", 3.0);
  ASSERT_EQ(s.complete(b->id, 1, "w", "{}", 1.0, 4.0), kOk);
  EXPECT_FALSE(s.cancel(done, 5.0));
  EXPECT_EQ(s.campaign(done)->state, "done");
  EXPECT_EQ(s.counts(done).done, 1);
}

// A job given up fails with its reason, loses its checkpoint and its lease (the worker's next
// beat and result are refused), and the campaign goes on to its end without it.
TEST(Store, AJobGivenUpFailsWithItsReasonAndTheCampaignEndsWithoutIt) {
  Store s(":memory:", {10.0, 3});
  const auto id = s.create_campaign("c", "{}", "{}", jobs(3), 0.0);
  const auto creeping = s.lease("w", 0.0);
  ASSERT_EQ(s.save_checkpoint(creeping->id, 1, "w", "settling", "state", 1.0), kOk);
  EXPECT_FALSE(s.give_up(id + 1, creeping->id, "another campaign's job"));
  const auto released = s.give_up(id, creeping->id, "creeps toward its step limit");
  ASSERT_TRUE(released);
  EXPECT_TRUE(released->empty());                      // no job waits for it
  EXPECT_FALSE(s.give_up(id, creeping->id, "twice"));  // it has ended
  const auto row = s.job(creeping->id);
  EXPECT_EQ(row->state, "failed");
  EXPECT_EQ(row->error, "given up: creeps toward its step limit");
  EXPECT_FALSE(s.checkpoint(creeping->id));
  EXPECT_FALSE(s.lease_deadline(creeping->id));
  EXPECT_EQ(s.heartbeat(creeping->id, 1, "w", 2.0), kStale);
  EXPECT_EQ(s.complete(creeping->id, 1, "w", "{}", 1.0, 2.0), kStale);
  EXPECT_EQ(s.result_count(creeping->id), 0);
  // A queued job is given up too; a done one is not.
  const auto next = s.lease("w", 3.0);
  ASSERT_TRUE(next);
  ASSERT_EQ(s.complete(next->id, 1, "w", "{}", 1.0, 4.0), kOk);
  EXPECT_FALSE(s.give_up(id, next->id, "done already"));
  EXPECT_EQ(s.job(next->id)->state, "done");
  const auto all = s.jobs(id);
  const auto queued =
      std::find_if(all.begin(), all.end(), [](const JobRow& j) { return j.state == "queued"; });
  ASSERT_NE(queued, all.end());
  EXPECT_EQ(s.campaign(id)->state, "running");
  ASSERT_TRUE(s.give_up(id, queued->id, "not needed"));
  EXPECT_FALSE(s.lease("w", 5.0));
  const Counts c = s.counts(id);
  EXPECT_EQ(c.done, 1);
  EXPECT_EQ(c.failed, 2);
  // A job given up did not end by simulating: the ETA's rate counts the one done only.
  EXPECT_EQ(c.simulated_since_opening, 1);
  EXPECT_EQ(s.campaign(id)->state, "done");
}

// A job waiting for another of its row is named when that one is given up, and leased.
TEST(Store, AJobWaitingForAJobGivenUpIsNamedAndLeased) {
  Store s(":memory:");
  std::vector<NewJob> row = {{1, 1, "confined_compression", "design", "{}"},
                             {1, 2, "tensile", "design", "{}", RunKey{}, "confined_compression"}};
  const auto id = s.create_campaign("c", "{}", "{}", row, 0.0);
  const auto first = s.lease("w", 0.0);
  ASSERT_EQ(first->test, "confined_compression");
  EXPECT_FALSE(s.lease("w2", 1.0));  // the tensile run waits
  const auto released = s.give_up(id, first->id, "creeping");
  ASSERT_TRUE(released);
  ASSERT_EQ(released->size(), 1u);
  const auto second = s.lease("w2", 2.0);
  ASSERT_TRUE(second);
  EXPECT_EQ(second->test, "tensile");
  EXPECT_EQ(second->id, released->front());
}

TEST(Store, VerificationJobsReopenADoneCampaign) {
  Store s(":memory:");
  const auto id = s.create_campaign("c", "{}", "{}", jobs(1), 0.0);
  const auto a = s.lease("w", 0.0);
  s.complete(a->id, 1, "w", "{}", 1.0, 1.0);
  EXPECT_EQ(s.campaign(id)->state, "done");
  const auto ids = s.add_jobs(id, {{0, 1, "packing", "verify", "{}"}});
  ASSERT_EQ(ids.size(), 1u);
  EXPECT_EQ(s.campaign(id)->state, "running");
  EXPECT_EQ(s.counts(id, "verify").queued, 1);
}

// Migration 1's SQL as released (server/store.cpp): the schema of a version-1 database.
constexpr const char* kSchemaV1 = R"sql(
      CREATE TABLE campaigns (
        id INTEGER PRIMARY KEY AUTOINCREMENT,
        name TEXT NOT NULL,
        state TEXT NOT NULL CHECK (state IN ('running', 'done', 'cancelled')),
        spec_json TEXT NOT NULL,
        design_json TEXT NOT NULL,
        created REAL NOT NULL,
        finished REAL NOT NULL DEFAULT 0);
      CREATE TABLE jobs (
        id INTEGER PRIMARY KEY AUTOINCREMENT,
        campaign_id INTEGER NOT NULL REFERENCES campaigns(id),
        std_order INTEGER NOT NULL,
        run_order INTEGER NOT NULL,
        test TEXT NOT NULL,
        kind TEXT NOT NULL CHECK (kind IN ('design', 'verify')),
        payload TEXT NOT NULL,
        state TEXT NOT NULL
          CHECK (state IN ('queued', 'leased', 'done', 'failed', 'cancelled')),
        attempt INTEGER NOT NULL DEFAULT 0,
        counted INTEGER NOT NULL DEFAULT 0,
        lease_deadline REAL NOT NULL DEFAULT 0,
        worker TEXT NOT NULL DEFAULT '',
        error TEXT NOT NULL DEFAULT '',
        finished REAL NOT NULL DEFAULT 0);
      CREATE INDEX jobs_queue ON jobs (state, campaign_id, kind, run_order);
      CREATE INDEX jobs_campaign ON jobs (campaign_id);
      CREATE TABLE results (
        job_id INTEGER PRIMARY KEY REFERENCES jobs(id),
        attempt INTEGER NOT NULL,
        worker TEXT NOT NULL,
        metrics_json TEXT NOT NULL,
        wall_seconds REAL NOT NULL,
        stored REAL NOT NULL);
      )sql";

TEST(Store, VersionOneDatabaseMigratesKeepingJobsAndResultsAndAdmitsDiagnosisJobs) {
  const TempStoreFile file("v1");
  const auto& path = file.path();
  {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(path.string().c_str(), &db), SQLITE_OK);
    exec_sql(db, kSchemaV1);
    exec_sql(db, "PRAGMA user_version=1");
    exec_sql(db,
             "INSERT INTO campaigns (name, state, spec_json, design_json, created, finished) "
             "VALUES ('old', 'done', '{\"spec\":1}', '{}', 100.0, 200.0)");
    exec_sql(db,
             "INSERT INTO jobs (campaign_id, std_order, run_order, test, kind, payload, state, "
             "attempt, counted, worker, finished) "
             "VALUES (1, 1, 1, 'packing', 'design', '{\"p\":1}', 'done', 1, 1, 'w1', 150.0)");
    exec_sql(db,
             "INSERT INTO results (job_id, attempt, worker, metrics_json, wall_seconds, stored) "
             "VALUES (1, 1, 'w1', '{\"solid_fraction\":0.61}', 12.5, 150.0)");
    // Version 1 refuses a diagnosis job: the migration is what admits them.
    char* err = nullptr;
    EXPECT_NE(sqlite3_exec(db,
                           "INSERT INTO jobs (campaign_id, std_order, run_order, test, kind, "
                           "payload, state) VALUES (1, 1, 1, 'packing', 'diagnose:shape', '{}', "
                           "'queued')",
                           nullptr, nullptr, &err),
              SQLITE_OK);
    sqlite3_free(err);
    ASSERT_EQ(sqlite3_close(db), SQLITE_OK);
  }
  {
    Store s(path.string());
    EXPECT_EQ(Store::latest_schema_version(), 15);
    EXPECT_EQ(s.schema_version(), Store::latest_schema_version());
    ASSERT_EQ(s.campaigns().size(), 1u);
    const auto campaign = s.campaign(1);
    ASSERT_TRUE(campaign);
    EXPECT_EQ(campaign->name, "old");
    EXPECT_EQ(campaign->spec_json, R"({"spec":1})");
    auto js = s.jobs(1);
    ASSERT_EQ(js.size(), 1u);
    EXPECT_EQ(js[0].id, 1);
    EXPECT_EQ(js[0].kind, "design");
    EXPECT_EQ(js[0].state, "done");
    EXPECT_EQ(js[0].payload, R"({"p":1})");
    EXPECT_EQ(js[0].worker, "w1");
    EXPECT_EQ(js[0].attempt, 1);
    ASSERT_TRUE(js[0].metrics_json);
    EXPECT_EQ(*js[0].metrics_json, R"({"solid_fraction":0.61})");
    EXPECT_DOUBLE_EQ(js[0].wall_seconds, 12.5);
    EXPECT_EQ(js[0].flags_json, "{}");  // a result from before flags and costs: none recorded
    EXPECT_EQ(js[0].cost_json, "{}");
    EXPECT_TRUE(s.series(1).empty());  // a result from before curves: none stored
    EXPECT_EQ(s.result_count(1), 1);
    EXPECT_FALSE(js[0].reused());  // a result from before reuse: simulated
    // A job from before run keys gets its key when the coordinator computes it (here: a name).
    s.refresh_run_keys([](const std::string& payload) {
      return RunKey{payload == R"({"p":1})" ? "old-key" : "", 1};
    });
    EXPECT_EQ(s.job(1)->run_key, (RunKey{"old-key", 1}));
    s.refresh_run_keys([](const std::string&) { return RunKey{"not asked", 1}; });
    EXPECT_EQ(s.job(1)->run_key.key, "old-key");  // a done job keeps the key of its result

    const auto ids = s.add_jobs(1, {{1, 1, "packing", "diagnose:shape", "{}"}});
    ASSERT_EQ(ids.size(), 1u);
    EXPECT_GT(ids[0], 1);  // a new id after the migrated job's
    EXPECT_EQ(s.counts(1, "diagnose:shape").queued, 1);
    // A job still to run takes the key of the build that runs it (another version of its test's
    // protocol: another key); the done job keeps the key its result was simulated under.
    s.refresh_run_keys([](const std::string& payload) {
      return RunKey{payload == "{}" ? "this-build" : "not asked", 3};
    });
    EXPECT_EQ(s.job(ids[0])->run_key, (RunKey{"this-build", 3}));
    EXPECT_EQ(s.job(1)->run_key, (RunKey{"old-key", 1}));
    EXPECT_EQ(s.campaign(1)->state, "running");
    EXPECT_ANY_THROW(s.add_jobs(1, {{1, 1, "packing", "bogus", "{}"}}));
    js = s.jobs(1);
    ASSERT_EQ(js.size(), 2u);  // the rejected job left nothing behind
    EXPECT_EQ(js[1].kind, "diagnose:shape");
    // The migrated table admits a multi-fidelity campaign's high rows, and keeps run keys.
    EXPECT_EQ(s.add_jobs(1, {{1, 1, "packing", "design:high", "{}"}}).size(), 1u);
    EXPECT_EQ(s.job(1)->run_key.key, "old-key");
  }
  {
    Store s(path.string());  // reopening does not migrate again
    EXPECT_EQ(s.schema_version(), Store::latest_schema_version());  // 5: campaigns.ready
    EXPECT_EQ(s.jobs(1).size(), 3u);
    // Version 4 admits the calibration's stage designs and stores rounds and stages with them.
    const auto round_jobs = s.add_calibration_round(1, {1, 1, R"({"natural":[0.3]})", 300.0},
                                                    {{1, 1, "packing", "verify", "{}"}});
    EXPECT_EQ(round_jobs.size(), 1u);
    s.add_calibration_stage(1, {2, R"({"box":[]})", 310.0}, {{1, 1, "packing", "stage:2", "{}"}});
    EXPECT_EQ(s.counts(1, "stage:2").queued, 1);
    ASSERT_EQ(s.calibration_rounds(1).size(), 1u);
    EXPECT_EQ(s.calibration_rounds(1)[0].proposal_json, R"({"natural":[0.3]})");
    ASSERT_EQ(s.calibration_stages(1).size(), 1u);
    EXPECT_EQ(s.calibration_stages(1)[0].stage, 2);
    // A round stored twice is refused and leaves no job behind.
    EXPECT_ANY_THROW(
        s.add_calibration_round(1, {1, 1, "{}", 320.0}, {{1, 1, "packing", "verify", "{}"}}));
    EXPECT_EQ(s.jobs(1).size(), 5u);
  }
}

// The ETA of a campaign resumed from its journal: 30 of its 51 jobs taken at once, one simulated
// in the 10 minutes since, 20 to go: 200 minutes, not the 6.5 the 31 finished jobs would say.
TEST(Progress, TheEtaIsRatedOnTheJobsSimulatedNotOnTheResultsTaken) {
  CampaignRow row;
  row.created = 1000.0;
  Counts c;
  c.done = 31;
  c.reused = 30;
  c.simulated_since_opening = 1;
  c.leased = 2;
  c.queued = 18;
  EXPECT_DOUBLE_EQ(progress_message(row, c, 1600.0).eta_seconds(), 600.0 * 20);
  c.done = c.reused;  // nothing simulated yet: no rate, no estimate
  c.simulated_since_opening = 0;
  EXPECT_EQ(progress_message(row, c, 1600.0).eta_seconds(), -1.0);
  c.queued = c.leased = 0;
  EXPECT_EQ(progress_message(row, c, 1600.0).eta_seconds(), 0.0);
}

// A campaign created three days ago whose coordinator ran again an hour ago and has simulated two
// jobs since: the ETA is that hour's rate, not the three days' (whose jobs ran in other runs).
TEST(Progress, TheEtaOfACampaignResumedAfterDaysIsRatedOnItsCoordinatorsCurrentRun) {
  CampaignRow row;
  row.created = 1000.0;
  Counts c;
  c.done = 12;
  c.simulated_since_opening = 2;
  c.opening = row.created + 3 * 86400.0;
  c.leased = 1;
  c.queued = 9;
  const double now = c.opening + 3600.0;
  const auto p = progress_message(row, c, now);
  EXPECT_DOUBLE_EQ(p.elapsed_seconds(), now - row.created);
  EXPECT_DOUBLE_EQ(p.eta_seconds(), 3600.0 / 2 * 10);
}

// The store counts a job as simulated in its current opening only if it ended after that opening
// and its result was simulated, not taken from another job with its run key.
TEST(Store, CountsTheJobsSimulatedSinceItWasOpened) {
  const TempStoreFile file("simulated_since_opening");
  double first_finished = 0.0;
  {
    Store s(file.path().string());
    const auto id = s.create_campaign(
        "c", "{}", "{}", {keyed_job(1, "k1"), keyed_job(2, "k2"), keyed_job(3, "k1")}, 0.0);
    const auto a = s.lease("w", 1.0);
    ASSERT_TRUE(a);
    EXPECT_EQ(s.complete(a->id, 1, "w", "{}", 1.0, 2.0), kOk);
    EXPECT_EQ(s.counts(id).simulated_since_opening, 1);
    first_finished = s.job(a->id)->finished;
  }
  Store s(file.path().string());
  EXPECT_EQ(s.counts(1).simulated_since_opening, 0);  // it ended before this opening
  EXPECT_GT(s.counts(1).opening, first_finished);
  const auto b = s.lease("w", 1.0);
  ASSERT_TRUE(b);
  EXPECT_EQ(b->run_key.key, "k2");
  EXPECT_EQ(s.complete(b->id, 1, "w", "{}", 1.0, 2.0), kOk);
  EXPECT_FALSE(s.lease("w", 3.0));  // run 3 takes run 1's result instead of a lease
  const auto c = s.counts(1);
  EXPECT_EQ(c.done, 3);
  EXPECT_EQ(c.reused, 1);
  EXPECT_EQ(c.simulated_since_opening, 1);
}

// A look at a store a running coordinator holds reads a copy; the copy rates its jobs from the
// holder's opening, which the holder's lock file dates, so the jobs the holder ended count.
TEST(Store, ACopyOfAHeldStoreIsRatedFromItsHoldersOpening) {
  const TempStoreFile file("held"), copy("held_copy");
  const double before = wall_seconds();
  Store held(file.path().string());
  const double after = wall_seconds();
  const auto id = held.create_campaign("c", "{}", "{}", jobs(2), 0.0);
  const auto a = held.lease("w", 1.0);
  ASSERT_TRUE(a);
  ASSERT_EQ(held.complete(a->id, 1, "w", "{}", 1.0, 2.0), kOk);
  const auto holder = StoreLock::holder(file.path().string());
  ASSERT_TRUE(holder);
  EXPECT_EQ(holder->pid, std::to_string(::getpid()));
  EXPECT_GE(holder->since, before - 0.01);  // file times and the wall clock, to their resolution
  EXPECT_LE(holder->since, after + 0.01);
  Store::copy_file(file.path().string(), copy.path().string());
  {
    Store look(copy.path().string(), {.rate_since = holder->since});
    const Counts c = look.counts(id);
    EXPECT_EQ(c.opening, holder->since);
    EXPECT_EQ(c.simulated_since_opening, 1);
  }
  Store look(copy.path().string());  // rated from its own opening, it has simulated nothing
  EXPECT_EQ(look.counts(id).simulated_since_opening, 0);
}

}  // namespace
}  // namespace demcal::server
