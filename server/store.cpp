#include "server/store.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string_view>
#include <tuple>

namespace demcal::server {

double steady_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

double wall_seconds() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

namespace schema {
/// The schema migrations, server/schema/NNN_name.sql in the order of their numbers (built into
/// the binary by cmake/EmbedFiles.cmake): migration i + 1 takes user_version i to i + 1. Never
/// edit a released one: its statements keep their text byte for byte (SQLite stores the text of
/// each CREATE in sqlite_schema).
const std::vector<std::string_view>& migrations();
}  // namespace schema

/// A prepared statement, taken from the store's cache of idle statements (SQLite's parsing and
/// planning was 14 % of the coordinator's time in bench/coordinator.sh when every call prepared
/// its statements anew) and given back, reset, when it goes out of scope. A statement whose SQL
/// is already in use (a nested query) is prepared on its own and finalised after use.
class Store::Statement {
 public:
  Statement(Store& store, const std::string& sql) : store_(store), db_(store.db_), sql_(sql) {
    const auto it = store_.idle_statements_.find(sql_);
    if (it != store_.idle_statements_.end()) {
      stmt_ = it->second;
      store_.idle_statements_.erase(it);
      return;
    }
    if (sqlite3_prepare_v3(db_, sql_.c_str(), -1, SQLITE_PREPARE_PERSISTENT, &stmt_, nullptr) !=
        SQLITE_OK)
      throw std::runtime_error(std::string("sqlite prepare: ") + sqlite3_errmsg(db_) + " in " +
                               sql_);
  }
  ~Statement() {
    // Reset first: a statement left stepping holds its read transaction open.
    sqlite3_reset(stmt_);
    sqlite3_clear_bindings(stmt_);
    if (!store_.idle_statements_.emplace(sql_, stmt_).second) sqlite3_finalize(stmt_);
  }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  Statement& bind(int i, std::int64_t v) {
    sqlite3_bind_int64(stmt_, i, v);
    return *this;
  }
  Statement& bind(int i, int v) { return bind(i, static_cast<std::int64_t>(v)); }
  Statement& bind(int i, double v) {
    sqlite3_bind_double(stmt_, i, v);
    return *this;
  }
  Statement& bind(int i, const std::string& v) {
    sqlite3_bind_text(stmt_, i, v.c_str(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
    return *this;
  }
  Statement& bind_blob(int i, const std::string& v) {
    sqlite3_bind_blob(stmt_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
    return *this;
  }
  /// Ready to run again with new bindings.
  void reset() {
    sqlite3_reset(stmt_);
    sqlite3_clear_bindings(stmt_);
  }
  /// True while there is a row.
  bool step() {
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    throw std::runtime_error(std::string("sqlite step: ") + sqlite3_errmsg(db_));
  }
  std::int64_t i64(int c) const { return sqlite3_column_int64(stmt_, c); }
  int i32(int c) const { return sqlite3_column_int(stmt_, c); }
  double f64(int c) const { return sqlite3_column_double(stmt_, c); }
  bool is_null(int c) const { return sqlite3_column_type(stmt_, c) == SQLITE_NULL; }
  std::string text(int c) const {
    const auto* p = sqlite3_column_text(stmt_, c);
    return p ? std::string(reinterpret_cast<const char*>(p)) : std::string();
  }
  std::string blob(int c) const {
    const auto* p = static_cast<const char*>(sqlite3_column_blob(stmt_, c));
    return p ? std::string(p, static_cast<std::size_t>(sqlite3_column_bytes(stmt_, c)))
             : std::string();
  }

 private:
  Store& store_;
  sqlite3* db_;
  std::string sql_;
  sqlite3_stmt* stmt_ = nullptr;
};

/// BEGIN IMMEDIATE ... COMMIT; rolls back unless committed.
class Store::Transaction {
 public:
  explicit Transaction(Store& s) : s_(s) { s_.exec("BEGIN IMMEDIATE"); }
  ~Transaction() {
    if (!done_) sqlite3_exec(s_.db_, "ROLLBACK", nullptr, nullptr, nullptr);
  }
  void commit() {
    s_.exec("COMMIT");
    done_ = true;
  }

 private:
  Store& s_;
  bool done_ = false;
};

/// The store's lock. A hold longer than a quarter second (a large insert, a slow disk) is added
/// to every lease deadline, so workers whose heartbeats waited for the lock keep their leases.
class Store::Guard {
 public:
  explicit Guard(Store& s) : s_(s), lock_(s.mutex_), start_(s.clock_now()) {}
  ~Guard() {
    constexpr double kStallSeconds = 0.25;
    if (const double held = s_.clock_now() - start_; held > kStallSeconds)
      s_.extend_deadlines(held);
  }
  Guard(const Guard&) = delete;
  Guard& operator=(const Guard&) = delete;

 private:
  Store& s_;
  std::lock_guard<std::mutex> lock_;
  double start_;
};

void Store::drop_checkpoint(std::int64_t job_id) {
  Statement d(*this, "DELETE FROM checkpoints WHERE job_id = ?");
  d.bind(1, job_id).step();
}

void Store::extend_deadlines(double seconds) {
  for (auto& [job, lease] : leases_) {
    lease.began += seconds;
    lease.deadline += seconds;
  }
}

namespace {
/// Creates a new database file readable by its owner only (0600): it holds every spec and result.
/// SQLite gives the -wal and -shm files the main file's permissions. An existing file is left as
/// it is; ":memory:" and "" (temporary databases) have no file.
void create_private_file(const std::string& path) {
  if (path.empty() || path == ":memory:") return;
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd >= 0) ::close(fd);
}

/// A connection to the SQLite file `path` opened with `flags`, waiting up to 10 s for a lock
/// another connection holds. Throws std::runtime_error naming the file when it cannot open it.
sqlite3* open_connection(const std::string& path, int flags) {
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(path.c_str(), &db, flags, nullptr) != SQLITE_OK) {
    const std::string msg = db ? sqlite3_errmsg(db) : "out of memory";
    sqlite3_close(db);
    throw std::runtime_error("cannot open " + path + ": " + msg);
  }
  sqlite3_busy_timeout(db, 10000);
  return db;
}
}  // namespace

Store::Store(const std::string& path, StoreLimits limits, std::optional<double> opened)
    : lock_(path),
      limits_(limits),
      opened_wall_(limits.rate_since > 0.0 ? limits.rate_since : wall_seconds()) {
  create_private_file(path);
  db_ = open_connection(path, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX);
  try {
    // Checked before the first write (switching to WAL rewrites the header, migrations and the
    // clean-up write tables): a damaged file is left exactly as it was found, for recovery.
    require_intact(path);
    exec("PRAGMA journal_mode=WAL");
    require_wal(path);
    exec(limits_.fsync_every_commit ? "PRAGMA synchronous=FULL" : "PRAGMA synchronous=NORMAL");
    // Foreign keys are enforced from here on; migrations that rebuild a table run before.
    migrate(path);
    exec("PRAGMA foreign_keys=ON");
    drop_unfinished_campaigns();
    restore_leases(opened.value_or(steady_seconds()));
  } catch (...) {
    // Closing the last connection would otherwise copy the write-ahead log into the file.
    sqlite3_db_config(db_, SQLITE_DBCONFIG_NO_CKPT_ON_CLOSE, 1, nullptr);
    close();
    throw;
  }
}

void Store::close() {
  // sqlite3_close refuses (SQLITE_BUSY) while a prepared statement is left.
  for (auto& [sql, stmt] : idle_statements_) sqlite3_finalize(stmt);
  idle_statements_.clear();
  sqlite3_close(db_);
}

void Store::require_intact(const std::string& path) {
  // quick_check reads every page and checks the b-trees' structure and the records' formats
  // (not that indexes match their tables, which integrity_check adds at several times the
  // cost); it answers one row "ok" or up to 100 rows each naming a problem
  // (https://www.sqlite.org/pragma.html#pragma_quick_check). A file that is no database at all
  // fails already at preparing it.
  sqlite3_stmt* stmt = nullptr;
  std::vector<std::string> problems;
  int rc = sqlite3_prepare_v2(db_, "PRAGMA quick_check(10)", -1, &stmt, nullptr);
  if (rc == SQLITE_OK) {
    while ((rc = sqlite3_step(stmt)) == SQLITE_ROW) {
      const auto* row = sqlite3_column_text(stmt, 0);
      std::string problem = row ? reinterpret_cast<const char*>(row) : "";
      std::replace(problem.begin(), problem.end(), '\n', ' ');  // one log line
      problems.push_back(std::move(problem));
    }
  }
  if (rc != SQLITE_DONE) problems.emplace_back(sqlite3_errmsg(db_));
  sqlite3_finalize(stmt);
  if (problems.size() == 1 && problems.front() == "ok") return;
  std::string what;
  for (const auto& p : problems) what += (what.empty() ? "" : "; ") + p;
  throw std::runtime_error(
      "refusing to open " + (path.empty() ? std::string("the temporary database") : path) +
      ": SQLite's quick_check finds it damaged (" + what +
      "); the file is left unchanged: restore it from a backup, or try the sqlite3 shell's "
      ".recover on a copy");
}

void Store::require_wal(const std::string& path) {
  // SQLite keeps the old journal mode, silently, where WAL is impossible (a file system without
  // shared memory, a read-only directory): the crash guarantees in the header would not hold.
  if (path.empty() || path == ":memory:") return;  // no file: nothing to recover after a crash
  const std::string mode = journal_mode_unlocked();
  if (mode != "wal")
    throw std::runtime_error("cannot put " + path + " in WAL mode (journal_mode is " + mode +
                             "): use a local file system the coordinator can write to");
}

void Store::restore_leases(double opened) {
  if (limits_.give_back_leases_at_opening) {
    Statement u(*this,
                "UPDATE jobs SET state = 'queued', counted = counted - 1, lease_deadline = 0, "
                "error = 'given back: leased by a worker of an earlier run of this process' "
                "WHERE state = 'leased'");
    u.step();
    return;
  }
  // The deadlines of the previous run are gone with its clock: a worker still running a job
  // leased before a restart has a whole lease from the opening to report or heartbeat again.
  Statement s(*this, "SELECT id FROM jobs WHERE state = 'leased'");
  const double deadline = opened + std::max(limits_.lease_seconds, limits_.restart_grace_seconds);
  while (s.step()) leases_[s.i64(0)] = {opened, deadline};
}

std::optional<double> Store::lease_deadline(std::int64_t job_id) {
  Guard lock(*this);
  const auto it = leases_.find(job_id);
  if (it == leases_.end()) return std::nullopt;
  return it->second.deadline;
}

void Store::copy_file(const std::string& from, const std::string& to) {
  // Both connections close however the copy ends.
  using Connection = std::unique_ptr<sqlite3, decltype(&sqlite3_close)>;
  if (!std::filesystem::is_regular_file(from)) throw std::runtime_error("no store file " + from);
  const Connection source(open_connection(from, SQLITE_OPEN_READONLY), &sqlite3_close);
  if (std::filesystem::exists(to)) throw std::runtime_error("refusing to overwrite " + to);
  create_private_file(to);
  const Connection target(open_connection(to, SQLITE_OPEN_READWRITE), &sqlite3_close);
  sqlite3_backup* backup = sqlite3_backup_init(target.get(), "main", source.get(), "main");
  if (!backup)
    throw std::runtime_error("cannot copy " + from + " to " + to + ": " +
                             sqlite3_errmsg(target.get()));
  // All pages in one step: one read transaction on the source, so one state of it (a lock the
  // source's writer holds is waited for by the connection's busy timeout).
  const int rc = sqlite3_backup_step(backup, -1);
  sqlite3_backup_finish(backup);
  if (rc != SQLITE_DONE)
    throw std::runtime_error("cannot copy " + from + " to " + to + ": " + sqlite3_errstr(rc));
}

int Store::file_schema_version(const std::string& path) {
  using Connection = std::unique_ptr<sqlite3, decltype(&sqlite3_close)>;
  const Connection db(open_connection(path, SQLITE_OPEN_READONLY), &sqlite3_close);
  sqlite3_stmt* st = nullptr;
  int version = -1;
  if (sqlite3_prepare_v2(db.get(), "PRAGMA user_version", -1, &st, nullptr) == SQLITE_OK &&
      sqlite3_step(st) == SQLITE_ROW)
    version = sqlite3_column_int(st, 0);
  sqlite3_finalize(st);
  if (version < 0)
    throw std::runtime_error("cannot read the schema version of " + path + ": " +
                             sqlite3_errmsg(db.get()));
  return version;
}

Store::~Store() {
  close();
}

void Store::exec(const char* sql) {
  char* err = nullptr;
  if (sqlite3_exec(db_, sql, nullptr, nullptr, &err) != SQLITE_OK) {
    const std::string msg = err ? err : "?";
    sqlite3_free(err);
    throw std::runtime_error("sqlite: " + msg);
  }
}

int Store::latest_schema_version() {
  return static_cast<int>(schema::migrations().size());
}

int Store::schema_version() {
  Guard lock(*this);
  Statement s(*this, "PRAGMA user_version");
  s.step();
  return s.i32(0);
}

std::string Store::journal_mode() {
  Guard lock(*this);
  return journal_mode_unlocked();
}

std::string Store::journal_mode_unlocked() {
  Statement s(*this, "PRAGMA journal_mode");
  s.step();
  return s.text(0);
}

void Store::migrate(const std::string& path) {
  Transaction tx(*this);
  // Read through schema_version(): its statement is finalised before a migration drops a table.
  const int version = schema_version();
  if (version > latest_schema_version())
    throw std::runtime_error("database schema version " + std::to_string(version) +
                             " is newer than this coordinator's " +
                             std::to_string(latest_schema_version()));
  for (int i = version; i < latest_schema_version(); ++i) {
    exec(std::string(schema::migrations()[std::size_t(i)]).c_str());
    exec(("PRAGMA user_version=" + std::to_string(i + 1)).c_str());
  }
  require_foreign_keys(path, version);
  tx.commit();
}

void Store::require_foreign_keys(const std::string& path, int version_found) {
  // Each row of foreign_key_check names a child table, the child's rowid, the parent table and
  // the constraint's number (https://www.sqlite.org/pragma.html#pragma_foreign_key_check).
  constexpr int kNamed = 5;
  Statement fk(*this, "PRAGMA foreign_key_check");
  std::string rows;
  int broken = 0;
  while (fk.step()) {
    if (++broken > kNamed) continue;
    rows += (rows.empty() ? "" : "; ") + std::string("row ") +
            (fk.is_null(1) ? std::string("?") : std::to_string(fk.i64(1))) + " of " + fk.text(0) +
            " refers to a " + fk.text(2) + " row that does not exist";
  }
  if (broken == 0) return;
  const bool migrated = version_found < latest_schema_version();
  throw std::runtime_error(
      "refusing to open " + (path.empty() ? std::string("the temporary database") : path) + ": " +
      std::to_string(broken) + " row(s) break a foreign key (" + rows +
      (broken > kNamed ? "; ..." : "") + ")" +
      (migrated
           ? ", after migrating it from schema version " + std::to_string(version_found) + " to " +
                 std::to_string(latest_schema_version()) + "; the migration is rolled back"
           : "; the file was changed outside the coordinator") +
      ": restore it from a backup, or mend the rows named in the sqlite3 shell");
}

std::int64_t Store::create_campaign(const std::string& name, const std::string& spec_json,
                                    const std::string& design_json, const std::vector<NewJob>& jobs,
                                    double now, const std::string& owner) {
  std::int64_t id = 0;
  {
    Guard lock(*this);
    Transaction tx(*this);
    Statement c(
        *this,
        "INSERT INTO campaigns (name, state, spec_json, design_json, created, ready, owner) "
        "VALUES (?, 'running', ?, ?, ?, 0, ?)");
    c.bind(1, name).bind(2, spec_json).bind(3, design_json).bind(4, now).bind(5, owner).step();
    id = sqlite3_last_insert_rowid(db_);
    tx.commit();
  }
  // Between two batches the lock is free for heartbeats, leases and results of other campaigns.
  for (std::size_t first = 0; first < jobs.size(); first += kInsertBatch) {
    Guard lock(*this);
    Transaction tx(*this);
    insert_job_rows(id, jobs, first, std::min(jobs.size(), first + kInsertBatch));
    tx.commit();
  }
  Guard lock(*this);
  Transaction tx(*this);
  Statement r(*this, "UPDATE campaigns SET ready = 1 WHERE id = ?");
  r.bind(1, id).step();
  tx.commit();
  return id;
}

std::int64_t Store::unfinished_jobs(const std::optional<std::string>& owner) {
  Guard lock(*this);
  Statement s(*this,
              "SELECT COUNT(*) FROM jobs j JOIN campaigns c ON c.id = j.campaign_id "
              "WHERE j.state IN ('queued', 'leased') AND (? OR c.owner = ?)");
  s.bind(1, owner ? 0 : 1).bind(2, owner.value_or(std::string()));
  s.step();
  return s.i64(0);
}

std::vector<std::int64_t> Store::insert_job_rows(std::int64_t campaign_id,
                                                 const std::vector<NewJob>& jobs, std::size_t first,
                                                 std::size_t end) {
  std::vector<std::int64_t> ids;
  Statement s(*this,
              "INSERT INTO jobs (campaign_id, std_order, run_order, test, kind, payload, state, "
              "run_key, run_protocol, waits_for) VALUES (?, ?, ?, ?, ?, ?, 'queued', ?, ?, ?)");
  for (std::size_t i = first; i < end; ++i) {
    const auto& job = jobs[i];
    s.bind(1, campaign_id).bind(2, job.std_order).bind(3, job.run_order).bind(4, job.test);
    s.bind(5, job.kind).bind(6, job.payload).bind(7, job.run_key.key);
    s.bind(8, job.run_key.protocol).bind(9, job.waits_for).step();
    s.reset();
    ids.push_back(sqlite3_last_insert_rowid(db_));
  }
  return ids;
}

void Store::drop_unfinished_campaigns() {
  // A coordinator stopped while inserting a campaign's jobs: the submission never answered, so
  // nobody knows the campaign; it goes with its jobs.
  Transaction tx(*this);
  exec("DELETE FROM jobs WHERE campaign_id IN (SELECT id FROM campaigns WHERE ready = 0)");
  exec("DELETE FROM campaigns WHERE ready = 0");
  tx.commit();
}

namespace {
constexpr const char* kCampaignColumns =
    "SELECT id, name, state, spec_json, design_json, created, finished FROM campaigns WHERE "
    "ready = 1";
}

std::optional<CampaignRow> Store::campaign(std::int64_t id) {
  Guard lock(*this);
  Statement s(*this, (std::string(kCampaignColumns) + " AND id = ?").c_str());
  s.bind(1, id);
  if (!s.step()) return std::nullopt;
  return CampaignRow{s.i64(0), s.text(1), s.text(2), s.text(3), s.text(4), s.f64(5), s.f64(6)};
}

void Store::set_campaign_plan(std::int64_t id, const std::string& spec_json,
                              const std::string& design_json) {
  Guard lock(*this);
  Statement s(*this, "UPDATE campaigns SET spec_json = ?, design_json = ? WHERE id = ?");
  s.bind(1, spec_json).bind(2, design_json).bind(3, id).step();
}

std::vector<CampaignRow> Store::campaigns() {
  Guard lock(*this);
  Statement s(*this, (std::string(kCampaignColumns) + " ORDER BY id").c_str());
  std::vector<CampaignRow> out;
  while (s.step())
    out.push_back({s.i64(0), s.text(1), s.text(2), s.text(3), s.text(4), s.f64(5), s.f64(6)});
  return out;
}

Counts Store::counts(std::int64_t campaign_id, const std::string& kind) {
  Guard lock(*this);
  // `reused`: the job's result was taken from an earlier run (0 for the states without results).
  Statement s(*this,
              "SELECT state, COUNT(*), SUM(reused), "
              "SUM(state IN ('done', 'failed') AND finished >= ? AND NOT reused "
              "    AND error NOT LIKE 'given up:%') "
              "FROM (SELECT j.state, j.finished, j.error, "
              "      COALESCE(r.reused_from != 0 OR r.reused_journal != '', 0) AS reused "
              "      FROM jobs j LEFT JOIN results r ON r.job_id = j.id "
              "      WHERE j.campaign_id = ? AND (? = '' OR j.kind = ?)) "
              "GROUP BY state");
  s.bind(1, opened_wall_).bind(2, campaign_id).bind(3, kind).bind(4, kind);
  Counts c;
  c.opening = opened_wall_;
  while (s.step()) {
    const std::string st = s.text(0);
    const std::int64_t n = s.i64(1);
    c.reused += s.i64(2);
    c.simulated_since_opening += s.i64(3);
    if (st == "queued") c.queued = n;
    if (st == "leased") c.leased = n;
    if (st == "done") c.done = n;
    if (st == "failed") c.failed = n;
    if (st == "cancelled") c.cancelled = n;
  }
  return c;
}

namespace {
constexpr const char* kJobColumns =
    "SELECT j.id, j.campaign_id, j.std_order, j.run_order, j.test, j.kind, j.state, j.payload, "
    "j.worker, j.error, j.attempt, j.counted, j.lease_deadline, r.metrics_json, "
    "COALESCE(r.wall_seconds, 0), j.finished, COALESCE(r.flags_json, '{}'), "
    "COALESCE(r.cost_json, '{}'), COALESCE(j.run_key, ''), COALESCE(r.attempt, 0), "
    "COALESCE(r.reused_from, 0), COALESCE(r.reused_journal, ''), j.run_protocol, j.yields "
    "FROM jobs j LEFT JOIN results r ON r.job_id = j.id";
}

template <class S>
JobRow read_job(const S& s) {
  JobRow j;
  j.id = s.i64(0);
  j.campaign_id = s.i64(1);
  j.std_order = s.i32(2);
  j.run_order = s.i32(3);
  j.test = s.text(4);
  j.kind = s.text(5);
  j.state = s.text(6);
  j.payload = s.text(7);
  j.worker = s.text(8);
  j.error = s.text(9);
  j.attempt = s.i32(10);
  j.counted = s.i32(11);
  j.lease_deadline = s.f64(12);
  if (!s.is_null(13)) j.metrics_json = s.text(13);
  j.wall_seconds = s.f64(14);
  j.finished = s.f64(15);
  j.flags_json = s.text(16);
  j.cost_json = s.text(17);
  j.run_key = {s.text(18), s.i32(22)};
  j.result_attempt = s.i32(19);
  j.reused_from = s.i64(20);
  j.reused_journal = s.text(21);
  j.yields = s.i32(23);
  return j;
}

std::vector<JobRow> Store::jobs(std::int64_t campaign_id) {
  Guard lock(*this);
  Statement s(*this, (std::string(kJobColumns) + " WHERE j.campaign_id = ? ORDER BY j.id").c_str());
  s.bind(1, campaign_id);
  std::vector<JobRow> out;
  while (s.step()) out.push_back(read_job(s));
  return out;
}

std::map<std::int64_t, std::string> Store::series(std::int64_t campaign_id) {
  Guard lock(*this);
  Statement s(*this,
              "SELECT c.job_id, c.series_json FROM result_series c JOIN jobs j ON j.id = c.job_id "
              "WHERE j.campaign_id = ?");
  s.bind(1, campaign_id);
  std::map<std::int64_t, std::string> out;
  while (s.step()) out.emplace(s.i64(0), s.text(1));
  return out;
}

std::optional<JobRow> Store::job(std::int64_t job_id) {
  Guard lock(*this);
  Statement s(*this, (std::string(kJobColumns) + " WHERE j.id = ?").c_str());
  s.bind(1, job_id);
  if (!s.step()) return std::nullopt;
  return read_job(s);
}

bool Store::cancel(std::int64_t campaign_id, double now) {
  Guard lock(*this);
  Transaction tx(*this);
  // Only a running campaign is cancelled. A done one stays done: its results are complete, and
  // a later verification or diagnosis reopens it (add_jobs) rather than finding it cancelled.
  Statement c(*this,
              "UPDATE campaigns SET state = 'cancelled', finished = ? WHERE id = ? AND state = "
              "'running'");
  c.bind(1, now).bind(2, campaign_id).step();
  if (sqlite3_changes(db_) == 0) return false;
  Statement j(*this,
              "UPDATE jobs SET state = 'cancelled', finished = ? "
              "WHERE campaign_id = ? AND state IN ('queued', 'leased')");
  j.bind(1, now).bind(2, campaign_id).step();
  tx.commit();
  return true;
}

std::optional<std::vector<std::int64_t>> Store::give_up(std::int64_t campaign_id,
                                                        std::int64_t job_id,
                                                        const std::string& reason) {
  Guard lock(*this);
  Transaction tx(*this);
  const double at = wall_seconds();
  Statement u(*this,
              "UPDATE jobs SET state = 'failed', error = ?, finished = ?, lease_deadline = 0 "
              "WHERE id = ? AND campaign_id = ? AND state IN ('queued', 'leased')");
  u.bind(1, "given up: " + reason).bind(2, at).bind(3, job_id).bind(4, campaign_id).step();
  if (sqlite3_changes(db_) == 0) return std::nullopt;
  drop_checkpoint(job_id);
  finish_campaigns(at);
  Statement w(*this,
              "SELECT w.id FROM jobs w JOIN jobs g ON g.id = ? WHERE w.campaign_id = g.campaign_id "
              "AND w.kind = g.kind AND w.std_order = g.std_order AND w.waits_for = g.test AND "
              "w.state = 'queued' ORDER BY w.id");
  w.bind(1, job_id);
  std::vector<std::int64_t> waited;
  while (w.step()) waited.push_back(w.i64(0));
  tx.commit();
  leases_.erase(job_id);
  return waited;
}

std::vector<std::int64_t> Store::insert_jobs(std::int64_t campaign_id,
                                             const std::vector<NewJob>& jobs) {
  auto ids = insert_job_rows(campaign_id, jobs, 0, jobs.size());
  Statement c(
      *this,
      "UPDATE campaigns SET state = 'running', finished = 0 WHERE id = ? AND state = 'done'");
  c.bind(1, campaign_id).step();
  return ids;
}

std::vector<std::int64_t> Store::add_jobs(std::int64_t campaign_id,
                                          const std::vector<NewJob>& jobs) {
  Guard lock(*this);
  Transaction tx(*this);
  auto ids = insert_jobs(campaign_id, jobs);
  tx.commit();
  return ids;
}

std::vector<std::int64_t> Store::add_calibration_round(std::int64_t campaign_id,
                                                       const CalibrationRoundRow& round,
                                                       const std::vector<NewJob>& jobs) {
  Guard lock(*this);
  Transaction tx(*this);
  Statement s(*this,
              "INSERT INTO calibration_rounds (campaign_id, round, stage, proposal_json, created) "
              "VALUES (?, ?, ?, ?, ?)");
  s.bind(1, campaign_id).bind(2, round.round).bind(3, round.stage);
  s.bind(4, round.proposal_json).bind(5, round.created).step();
  auto ids = insert_jobs(campaign_id, jobs);
  tx.commit();
  return ids;
}

std::vector<std::int64_t> Store::add_calibration_stage(std::int64_t campaign_id,
                                                       const CalibrationStageRow& stage,
                                                       const std::vector<NewJob>& jobs) {
  Guard lock(*this);
  Transaction tx(*this);
  Statement s(*this,
              "INSERT INTO calibration_stages (campaign_id, stage, box_json, created) "
              "VALUES (?, ?, ?, ?)");
  s.bind(1, campaign_id).bind(2, stage.stage).bind(3, stage.box_json).bind(4, stage.created);
  s.step();
  auto ids = insert_jobs(campaign_id, jobs);
  tx.commit();
  return ids;
}

std::vector<CalibrationRoundRow> Store::calibration_rounds(std::int64_t campaign_id) {
  Guard lock(*this);
  Statement s(*this,
              "SELECT round, stage, proposal_json, created FROM calibration_rounds "
              "WHERE campaign_id = ? ORDER BY round");
  s.bind(1, campaign_id);
  std::vector<CalibrationRoundRow> out;
  while (s.step()) out.push_back({s.i32(0), s.i32(1), s.text(2), s.f64(3)});
  return out;
}

std::vector<CalibrationStageRow> Store::calibration_stages(std::int64_t campaign_id) {
  Guard lock(*this);
  Statement s(*this,
              "SELECT stage, box_json, created FROM calibration_stages "
              "WHERE campaign_id = ? ORDER BY stage");
  s.bind(1, campaign_id);
  std::vector<CalibrationStageRow> out;
  while (s.step()) out.push_back({s.i32(0), s.text(1), s.f64(2)});
  return out;
}

std::optional<Store::NextJob> Store::next_queued() {
  // The jobs that yielded fewest times first (yield_due), then run order within a campaign and
  // kind, except that a job whose wait has ended goes first: it starts from the bed its row's
  // other job conditioned, so it is short, and a row's tensile strength is known before the
  // campaign's later shear cells have run. jobs.wait_ended (set by a trigger,
  // server/schema/012_job_wait_ended.sql) puts those jobs first in the jobs_queue index, so the
  // walk meets them without testing the jobs still waiting.
  Statement s(*this,
              "SELECT j.id, COALESCE(j.run_key, ''), j.yields FROM jobs j "
              "JOIN campaigns c ON c.id = j.campaign_id "
              "WHERE j.state = 'queued' AND c.state = 'running' AND c.ready = 1 AND "
              "(COALESCE(j.run_key, '') = '' OR NOT EXISTS (SELECT 1 FROM jobs t "
              "WHERE t.run_key = j.run_key AND t.state = 'leased')) AND "
              "(j.waits_for = '' OR NOT EXISTS (SELECT 1 FROM jobs w WHERE w.campaign_id = "
              "j.campaign_id AND w.kind = j.kind AND w.std_order = j.std_order AND w.test = "
              "j.waits_for AND w.state IN ('queued', 'leased'))) "
              "ORDER BY j.yields, j.campaign_id, j.kind, j.wait_ended DESC, j.run_order, j.id "
              "LIMIT 1");
  if (!s.step()) return std::nullopt;
  return NextJob{s.i64(0), s.text(1), s.i32(2)};
}

bool Store::take_finished_run(std::int64_t job_id, const std::string& key) {
  const double stored = server::wall_seconds();
  // The first job that finished the run, in any campaign: its result, series and provenance
  // (attempt, worker) are copied, the source named.
  std::int64_t source = 0;
  {
    Statement s(*this,
                "SELECT id FROM jobs WHERE run_key = ? AND state = 'done' AND id != ? "
                "ORDER BY id LIMIT 1");
    s.bind(1, key).bind(2, job_id);
    if (s.step()) source = s.i64(0);
  }
  if (source != 0) {
    Statement r(*this,
                "INSERT INTO results (job_id, attempt, worker, metrics_json, wall_seconds, stored, "
                "flags_json, cost_json, reused_from) SELECT ?, attempt, worker, metrics_json, "
                "wall_seconds, ?, flags_json, cost_json, ? FROM results WHERE job_id = ?");
    r.bind(1, job_id).bind(2, stored).bind(3, source).bind(4, source).step();
    Statement c(*this,
                "INSERT INTO result_series (job_id, series_json) SELECT ?, series_json "
                "FROM result_series WHERE job_id = ?");
    c.bind(1, job_id).bind(2, source).step();
  } else {
    Statement r(*this,
                "INSERT INTO results (job_id, attempt, worker, metrics_json, wall_seconds, stored, "
                "flags_json, cost_json, reused_journal) SELECT ?, attempt, '', metrics_json, "
                "wall_seconds, ?, flags_json, cost_json, source FROM journal_runs "
                "WHERE run_key = ?");
    r.bind(1, job_id).bind(2, stored).bind(3, key).step();
    if (sqlite3_changes(db_) == 0) return false;
    Statement c(*this,
                "INSERT INTO result_series (job_id, series_json) SELECT ?, series_json "
                "FROM journal_runs WHERE run_key = ? AND series_json != ''");
    c.bind(1, job_id).bind(2, key).step();
  }
  Statement u(*this, "UPDATE jobs SET state = 'done', finished = ?, error = '' WHERE id = ?");
  u.bind(1, stored).bind(2, job_id).step();
  drop_checkpoint(job_id);
  return true;
}

std::optional<JobRow> Store::lease(const std::string& worker, double now) {
  Guard lock(*this);
  Transaction tx(*this);
  bool reused = false;
  auto next = next_queued();
  for (; next && !next->run_key.empty() && take_finished_run(next->id, next->run_key);
       next = next_queued())
    reused = true;
  if (reused) finish_campaigns(server::wall_seconds());
  if (!next) {
    tx.commit();
    return std::nullopt;
  }
  const std::int64_t id = next->id;
  Statement u(*this,
              "UPDATE jobs SET state = 'leased', attempt = attempt + 1, counted = counted + 1, "
              "worker = ? WHERE id = ? AND state = 'queued'");
  u.bind(1, worker).bind(2, id).step();
  Statement r(*this, (std::string(kJobColumns) + " WHERE j.id = ?").c_str());
  r.bind(1, id);
  r.step();
  JobRow job = read_job(r);
  tx.commit();
  const LeaseClock clock{now, now + limits_.lease_seconds};
  leases_[id] = clock;
  job.lease_deadline = clock.deadline;
  return job;
}

int Store::import_runs(const std::vector<FinishedRun>& runs) {
  Guard lock(*this);
  Transaction tx(*this);
  const double imported = server::wall_seconds();
  int added = 0;
  Statement s(*this,
              "INSERT OR IGNORE INTO journal_runs (run_key, attempt, metrics_json, wall_seconds, "
              "flags_json, cost_json, series_json, source, imported, test, seed, "
              "parameters_json) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  // A run imported before its point was kept (schema 14) gets it now; nothing else changes.
  Statement point(*this,
                  "UPDATE journal_runs SET test = ?, seed = ?, parameters_json = ? "
                  "WHERE run_key = ? AND test = ''");
  for (const auto& run : runs) {
    s.bind(1, run.run_key).bind(2, run.attempt).bind(3, run.metrics_json);
    s.bind(4, run.wall_seconds).bind(5, run.flags_json).bind(6, run.cost_json);
    s.bind(7, run.series_json).bind(8, run.source).bind(9, imported).bind(10, run.test);
    s.bind(11, run.seed).bind(12, run.parameters_json).step();
    const int changed = sqlite3_changes(db_);
    added += changed;
    s.reset();
    if (changed == 0) {
      point.bind(1, run.test).bind(2, run.seed).bind(3, run.parameters_json).bind(4, run.run_key);
      point.step();
      point.reset();
    }
  }
  tx.commit();
  return added;
}

bool Store::holds_run(const std::string& run_key) {
  Guard lock(*this);
  Statement s(*this,
              "SELECT 1 FROM jobs WHERE run_key = ? AND state = 'done' UNION ALL "
              "SELECT 1 FROM journal_runs WHERE run_key = ? LIMIT 1");
  s.bind(1, run_key).bind(2, run_key);
  return s.step();
}

std::vector<HeldRun> Store::journal_runs_at(const std::string& test, const std::string& seed) {
  Guard lock(*this);
  Statement s(*this,
              "SELECT run_key, parameters_json FROM journal_runs WHERE test = ? AND seed = ? "
              "ORDER BY rowid");
  s.bind(1, test).bind(2, seed);
  std::vector<HeldRun> out;
  while (s.step()) out.push_back({s.text(0), s.text(1)});
  return out;
}

void Store::refresh_run_keys(const std::function<RunKey(const std::string& payload)>& key_of) {
  Guard lock(*this);
  Transaction tx(*this);
  struct Change {
    std::int64_t id;
    RunKey key;
    bool had_key;  // and now another: its checkpoint goes
  };
  std::vector<Change> changed;
  {
    Statement s(
        *this,
        "SELECT id, payload, COALESCE(run_key, ''), run_protocol, run_key IS NULL FROM jobs "
        "WHERE run_key IS NULL OR state != 'done'");
    while (s.step()) {
      RunKey key = key_of(s.text(1));
      const bool had_key = s.i64(4) == 0;
      if (!had_key || key.key != s.text(2) || key.protocol != s.i64(3))
        changed.push_back({s.i64(0), std::move(key), had_key});
    }
  }
  Statement u(*this, "UPDATE jobs SET run_key = ?, run_protocol = ? WHERE id = ?");
  for (const auto& [id, key, had_key] : changed) {
    u.bind(1, key.key).bind(2, key.protocol).bind(3, id).step();
    u.reset();
    if (had_key) drop_checkpoint(id);
  }
  tx.commit();
}

LeaseAnswer Store::check_lease(std::int64_t job_id, int attempt, const std::string& worker,
                               double now) {
  Statement s(*this, "SELECT worker FROM jobs WHERE id = ? AND attempt = ? AND state = 'leased'");
  s.bind(1, job_id).bind(2, attempt);
  if (!s.step()) return LeaseAnswer::kStale;
  const auto it = leases_.find(job_id);
  if (it == leases_.end() || it->second.deadline < now) return LeaseAnswer::kStale;
  return s.text(0) == worker ? LeaseAnswer::kOk : LeaseAnswer::kNotHolder;
}

std::optional<Store::StoredResult> Store::stored_result(std::int64_t job_id, int attempt,
                                                        const std::string& worker) {
  Statement s(*this,
              "SELECT r.metrics_json, r.wall_seconds FROM results r JOIN jobs j ON j.id = r.job_id "
              "WHERE r.job_id = ? AND r.attempt = ? AND r.worker = ? AND j.state = 'done'");
  s.bind(1, job_id).bind(2, attempt).bind(3, worker);
  if (!s.step()) return std::nullopt;
  return StoredResult{s.text(0), s.f64(1)};
}

LeaseAnswer Store::heartbeat(std::int64_t job_id, int attempt, const std::string& worker,
                             double now) {
  Guard lock(*this);
  const LeaseAnswer answer = check_lease(job_id, attempt, worker, now);
  if (answer == LeaseAnswer::kOk) leases_[job_id].deadline = now + limits_.lease_seconds;
  if (answer == LeaseAnswer::kStale && stored_result(job_id, attempt, worker))
    return LeaseAnswer::kOk;
  return answer;
}

LeaseAnswer Store::complete(std::int64_t job_id, int attempt, const std::string& worker,
                            const std::string& metrics_json, double wall_seconds, double now,
                            const std::string& flags_json, const std::string& cost_json,
                            const std::string& series_json) {
  Guard lock(*this);
  Transaction tx(*this);
  // A retry of the result already stored for this lease (its answer was lost) is a success.
  if (const auto r = stored_result(job_id, attempt, worker);
      r && r->metrics_json == metrics_json && r->wall_seconds == wall_seconds)
    return LeaseAnswer::kOk;
  if (const auto answer = check_lease(job_id, attempt, worker, now); answer != LeaseAnswer::kOk)
    return answer;
  const double stored = server::wall_seconds();
  Statement u(*this, "UPDATE jobs SET state = 'done', finished = ?, error = '' WHERE id = ?");
  u.bind(1, stored).bind(2, job_id).step();
  Statement r(*this,
              "INSERT INTO results (job_id, attempt, worker, metrics_json, wall_seconds, stored, "
              "flags_json, cost_json) VALUES (?, ?, ?, ?, ?, ?, ?, ?)");
  r.bind(1, job_id).bind(2, attempt).bind(3, worker).bind(4, metrics_json);
  r.bind(5, wall_seconds).bind(6, stored).bind(7, flags_json).bind(8, cost_json).step();
  if (!series_json.empty()) {
    Statement c(*this, "INSERT INTO result_series (job_id, series_json) VALUES (?, ?)");
    c.bind(1, job_id).bind(2, series_json).step();
  }
  drop_checkpoint(job_id);
  finish_campaigns(stored);
  tx.commit();
  leases_.erase(job_id);
  return LeaseAnswer::kOk;
}

LeaseAnswer Store::save_checkpoint(std::int64_t job_id, int attempt, const std::string& worker,
                                   const std::string& stage, const std::string& state, double now,
                                   const CheckpointClock& clock) {
  Guard lock(*this);
  Transaction tx(*this);
  if (const auto answer = check_lease(job_id, attempt, worker, now); answer != LeaseAnswer::kOk)
    return answer;
  Statement s(*this,
              "INSERT OR REPLACE INTO checkpoints (job_id, attempt, worker, stage, state, stored, "
              "simulated_seconds, steps) VALUES (?, ?, ?, ?, ?, ?, ?, ?)");
  s.bind(1, job_id).bind(2, attempt).bind(3, worker).bind(4, stage).bind_blob(5, state);
  s.bind(6, server::wall_seconds()).bind(7, clock.simulated_seconds).bind(8, clock.steps).step();
  tx.commit();
  return LeaseAnswer::kOk;
}

std::optional<CheckpointRow> Store::checkpoint(std::int64_t job_id) {
  Guard lock(*this);
  Statement s(*this, "SELECT attempt, stage, state FROM checkpoints WHERE job_id = ?");
  s.bind(1, job_id);
  if (!s.step()) return std::nullopt;
  return CheckpointRow{s.i32(0), s.text(1), s.blob(2)};
}

std::map<std::int64_t, CheckpointMark> Store::checkpoint_marks(std::int64_t campaign_id) {
  Guard lock(*this);
  Statement s(*this,
              "SELECT c.job_id, c.stage, c.stored, c.simulated_seconds, c.steps FROM checkpoints c "
              "JOIN jobs j ON j.id = c.job_id WHERE j.campaign_id = ?");
  s.bind(1, campaign_id);
  std::map<std::int64_t, CheckpointMark> out;
  while (s.step())
    out.emplace(s.i64(0), CheckpointMark{s.text(1), s.f64(2), CheckpointClock{s.f64(3), s.i64(4)}});
  return out;
}

bool Store::requeue_or_fail(std::int64_t job_id, int counted, const std::string& reason,
                            bool retryable, double now) {
  const bool fail_now = !retryable || counted >= limits_.max_attempts;
  Statement u(*this, fail_now ? "UPDATE jobs SET state = 'failed', error = ?, finished = ?, "
                                "lease_deadline = 0 WHERE id = ?"
                              : "UPDATE jobs SET state = 'queued', error = ?, finished = ?, "
                                "lease_deadline = 0 WHERE id = ?");
  u.bind(1, reason).bind(2, fail_now ? now : 0.0).bind(3, job_id).step();
  return fail_now;
}

LeaseAnswer Store::fail(std::int64_t job_id, int attempt, const std::string& worker,
                        const std::string& reason, bool retryable, bool give_back, double now,
                        bool yielded) {
  Guard lock(*this);
  Transaction tx(*this);
  if (const auto answer = check_lease(job_id, attempt, worker, now); answer != LeaseAnswer::kOk)
    return answer;
  Statement s(*this, "SELECT counted FROM jobs WHERE id = ?");
  s.bind(1, job_id).step();
  const int counted = s.i32(0);
  const double at = wall_seconds();
  if (give_back) {
    Statement u(*this,
                "UPDATE jobs SET state = 'queued', counted = counted - 1, lease_deadline = 0, "
                "error = ?, yields = yields + ? WHERE id = ?");
    u.bind(1, "given back: " + reason).bind(2, yielded ? 1 : 0).bind(3, job_id).step();
  } else {
    requeue_or_fail(job_id, counted, reason, retryable, at);
  }
  finish_campaigns(at);
  tx.commit();
  leases_.erase(job_id);
  return LeaseAnswer::kOk;
}

bool Store::yield_due(std::int64_t job_id, double now, double yield_after) {
  if (yield_after <= 0.0) return false;
  Guard lock(*this);
  const auto lease = leases_.find(job_id);
  if (lease == leases_.end()) return false;
  Statement s(*this, "SELECT yields FROM jobs WHERE id = ? AND state = 'leased'");
  s.bind(1, job_id);
  if (!s.step()) return false;
  const int yields = s.i32(0);
  // Each yield doubles the job's share of a lease, so that a long run still ends.
  if (now - lease->second.began <= std::ldexp(yield_after, std::min(yields, 30))) return false;
  const auto next = next_queued();
  return next && next->yields <= yields;
}

int Store::reap(double now) {
  Guard lock(*this);
  std::vector<std::int64_t> due;
  for (const auto& [job, lease] : leases_)
    if (lease.deadline < now) due.push_back(job);
  if (due.empty()) return 0;
  Transaction tx(*this);
  const double at = wall_seconds();
  int reaped = 0;
  for (const auto id : due) {
    Statement s(*this, "SELECT counted, worker FROM jobs WHERE id = ? AND state = 'leased'");
    s.bind(1, id);
    if (!s.step()) continue;  // completed, failed or cancelled meanwhile
    const int counted = s.i32(0);
    requeue_or_fail(id, counted,
                    "lease of worker '" + s.text(1) + "' expired (attempt " +
                        std::to_string(counted) + " of " + std::to_string(limits_.max_attempts) +
                        ")",
                    true, at);
    ++reaped;
  }
  if (reaped > 0) finish_campaigns(at);
  tx.commit();
  for (const auto id : due) leases_.erase(id);
  return reaped;
}

void Store::finish_campaigns(double now) {
  Statement u(*this,
              "UPDATE campaigns SET state = 'done', finished = ? WHERE state = 'running' AND "
              "ready = 1 AND "
              "NOT EXISTS (SELECT 1 FROM jobs j WHERE j.campaign_id = campaigns.id AND "
              "j.state IN ('queued', 'leased'))");
  u.bind(1, now).step();
}

int Store::result_count(std::int64_t job_id) {
  Guard lock(*this);
  Statement s(*this, "SELECT COUNT(*) FROM results WHERE job_id = ?");
  s.bind(1, job_id);
  s.step();
  return s.i32(0);
}

}  // namespace demcal::server
