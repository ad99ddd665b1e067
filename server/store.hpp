#pragma once
// The coordinator's SQLite store: all SQL of demcal lives in this class. WAL journal with
// synchronous=NORMAL by default: a commit reaches the operating system before it is
// acknowledged, so it survives the coordinator's crash or SIGKILL, but the write-ahead log is
// synced only at checkpoints, so a power cut or kernel crash can lose the last commits (never
// corrupt the file: https://www.sqlite.org/pragma.html#pragma_synchronous, "WAL mode is always
// consistent with synchronous=NORMAL, but WAL mode does lose durability"). With
// StoreLimits::fsync_every_commit, synchronous=FULL: every commit is synced (an acknowledged
// result survives a power cut) at an fsync per Lease and per Complete. Versioned schema
// migrations (PRAGMA user_version), RAII transactions that roll back unless committed, and
// BEGIN IMMEDIATE for every write so that two writers never deadlock on a lock upgrade.
//
// Job state machine:  queued --Lease--> leased --Complete--> done
//                      queued --Lease finds a finished run of its run key--> done (reused)
//                                       leased --Fail(retryable) / lease expired--> queued
//                                                  (failed once the attempt cap is reached)
//                                       leased --Fail(not retryable)--> failed
//                                       leased --Fail(give_back)--> queued (attempt not counted;
//                                                  with `yielded`, the job's yields + 1)
//                      queued|leased --Cancel--> cancelled
//                      queued|leased --GiveUp--> failed (error "given up: <reason>")
// Every lease increments the job's attempt number; Heartbeat, Complete and Fail name
// (job, attempt, worker) and change nothing unless that lease is the current one, has not
// expired and is the caller's. A result is stored at most once per job (results.job_id is the
// primary key); a retried Complete of the stored result is answered as a success.
//
// Lease deadlines live in memory on a monotonic clock (the `now` of lease, heartbeat, complete,
// fail and reap is steady_seconds()), never in the file: a wall-clock jump cannot expire them,
// a coordinator restart gives every lease found in the file a fresh deadline (opening + lease),
// and time the store's lock is held by one long operation is added to every deadline.
#include <sqlite3.h>

#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "server/store_lock.hpp"

namespace demcal::server {

struct CampaignRow {
  std::int64_t id = 0;
  std::string name;
  std::string state;  ///< running | done | cancelled
  std::string spec_json, design_json;
  double created = 0.0, finished = 0.0;  ///< unix seconds; finished 0 while running
};

/// What identifies a job's result (server/run_key.hpp): a hash of everything that determines it,
/// and the lab protocol version it was computed under.
struct RunKey {
  std::string key;   ///< empty: none (the job is never reused)
  int protocol = 0;  ///< 0: none
  bool operator==(const RunKey&) const = default;
};

struct NewJob {
  int std_order = 0;  ///< 1-based design row; 0 for a verification job
  int run_order = 0;
  std::string test;
  std::string kind = "design";  ///< design | verify | stage:<n> | diagnose:<group>
  std::string payload;          ///< JobSpec as JSON (without id and attempt)
  RunKey run_key = {};
  /// The test (instance name) of the same campaign, kind and row whose job this one is leased
  /// after, once that job has ended; empty: none.
  std::string waits_for = {};
};

struct JobRow {
  std::int64_t id = 0, campaign_id = 0;
  int std_order = 0, run_order = 0;
  std::string test, kind, state, payload, worker, error;
  int attempt = 0;  ///< leases handed out so far (the current lease's number)
  int counted = 0;  ///< attempts counted against the cap (give-backs are not)
  int yields = 0;   ///< leases given back at a checkpoint to shorter runs (--yield-after)
  double lease_deadline = 0.0;
  std::optional<std::string> metrics_json;  ///< the stored result
  double wall_seconds = 0.0;
  double finished = 0.0;
  std::string flags_json = "{}";  ///< metric -> why it cannot be trusted
  std::string cost_json = "{}";   ///< the run's cost block (demcal.v1.RunCost as JSON)
  RunKey run_key;
  int result_attempt = 0;        ///< the lease that ran the stored result (a reused one's source's)
  std::int64_t reused_from = 0;  ///< the result was taken from this job's (0: not from a job)
  std::string reused_journal;    ///< the result was taken from this journal line (FILE:LINE)
  bool reused() const { return reused_from != 0 || !reused_journal.empty(); }
};

/// A finished run read from a journal, kept for the jobs with its run key.
struct FinishedRun {
  std::string run_key;
  int attempt = 0;  ///< the lease that ran it
  std::string metrics_json;
  double wall_seconds = 0.0;
  std::string flags_json = "{}", cost_json = "{}";
  std::string series_json;  ///< empty: none
  std::string source;       ///< where it was read: FILE:LINE
  /// What it stands for besides its key: its lab test, seed (decimal) and parameters (JSON).
  std::string test, seed, parameters_json = "{}";
};

/// A journal run the store holds: its run key and the parameters of the point it was simulated
/// at (a JSON object of path -> value).
struct HeldRun {
  std::string run_key, parameters_json;
};

/// One round of the sequential calibration: its proposal as JSON (server/stored_columns.hpp).
struct CalibrationRoundRow {
  int round = 0;  ///< 1-based; its verification jobs have kind 'verify' and std_order = round
  int stage = 1;
  std::string proposal_json;
  double created = 0.0;
};

/// A second (or later) stage of the calibration: its box as JSON; its design jobs have kind
/// 'stage:<stage>'.
struct CalibrationStageRow {
  int stage = 2;
  std::string box_json;
  double created = 0.0;
};

/// The latest checkpoint of a job's simulation (proto CheckpointRequest).
struct CheckpointRow {
  int attempt = 0;  ///< the lease that sent it
  std::string stage, state;
};

/// The run's clock at a checkpoint, as the worker sent it: simulated seconds and steps.
struct CheckpointClock {
  double simulated_seconds = 0.0;
  std::int64_t steps = 0;
};

/// Where a job's latest checkpoint stands, without its state: the stage, when it was kept and
/// the run's clock there.
struct CheckpointMark {
  std::string stage;
  double stored = 0.0;
  CheckpointClock clock;
};

struct Counts {
  std::int64_t queued = 0, leased = 0, done = 0, failed = 0, cancelled = 0;
  std::int64_t reused = 0;  ///< of done: results taken from an earlier run with the same run key
  /// The window a rate is measured over: the jobs simulated (done or failed, not taken from an
  /// earlier run nor given up) since the store was opened (or since StoreLimits::rate_since), and
  /// the wall-clock time of that opening. A campaign resumed after days away is rated on this run
  /// of its coordinator only.
  std::int64_t simulated_since_opening = 0;
  double opening = 0.0;
  std::int64_t total() const { return queued + leased + done + failed + cancelled; }
};

struct StoreLimits {
  double lease_seconds = 60.0;
  int max_attempts = 3;
  /// A lease found in the file at opening expires no sooner than this after the opening (nor
  /// sooner than a lease): workers that ran on while the coordinator was down need time to
  /// reconnect (gRPC's reconnection back-off) and report.
  double restart_grace_seconds = 0.0;
  /// The monotonic clock that measures how long the lock is held (empty: steady_seconds);
  /// tests give a fake one.
  std::function<double()> clock = {};
  /// synchronous=FULL instead of NORMAL: every commit survives a power cut (see the top).
  bool fsync_every_commit = false;
  /// The leases found in the file at opening go back to the queue at once, the attempt not
  /// counted: for a coordinator whose workers lived in the process that wrote the file (the
  /// embedded default), so that none of them can still be working on its job.
  bool give_back_leases_at_opening = false;
  /// The wall-clock time (s) the jobs' rate is measured from (Counts::opening); 0: this opening.
  /// A copy of a store that a running coordinator holds is rated from that holder's opening.
  double rate_since = 0.0;
};

/// Seconds on the monotonic clock the store's lease deadlines are kept on.
double steady_seconds();
/// Seconds since the Unix epoch, for the records (created, finished, stored).
double wall_seconds();

/// What became of a call naming a lease (Heartbeat, Complete, Fail).
enum class LeaseAnswer {
  kOk,         ///< done; for Complete also a retry of the result already stored
  kStale,      ///< not the current, unexpired lease of a leased job: nothing changed
  kNotHolder,  ///< the current lease, but another worker's: nothing changed
};

class Store {
 public:
  /// Opens (creating if needed) and migrates; path ":memory:" for tests. Refused (naming the
  /// file and the holder's pid) while another store has the file open (store_lock.hpp). Leases
  /// found in the
  /// file get the deadline `opened + max(lease, restart grace)` (opened: steady_seconds()
  /// unless given), or are given back (StoreLimits::give_back_leases_at_opening).
  explicit Store(const std::string& path, StoreLimits limits = {},
                 std::optional<double> opened = std::nullopt);
  ~Store();
  Store(const Store&) = delete;
  Store& operator=(const Store&) = delete;

  /// Jobs a campaign's creation inserts per transaction: the lock is held for milliseconds.
  static constexpr std::size_t kInsertBatch = 256;

  static int latest_schema_version();
  /// Writes a copy of the store file `from` to the new file `to` (owner-only), taken in one read
  /// transaction by SQLite's online backup: a consistent state of the store, also while another
  /// store has `from` open and writes it. `from` is only read (its lock is not taken).
  static void copy_file(const std::string& from, const std::string& to);
  /// The schema version (PRAGMA user_version) of the store file `path`, read without opening it
  /// as a store: nothing is migrated and its lock is not taken. Throws naming the file when it
  /// cannot be read.
  static int file_schema_version(const std::string& path);
  int schema_version();
  std::string journal_mode();
  const StoreLimits& limits() const { return limits_; }

  /// A new running campaign with its jobs, inserted in batches of kInsertBatch (each its own
  /// transaction, the lock free in between); the campaign is leased from, listed and finished
  /// only once all of them are in, and dropped on opening if the coordinator stopped before.
  /// `owner` names the token it was submitted with (auth.hpp, token_name).
  std::int64_t create_campaign(const std::string& name, const std::string& spec_json,
                               const std::string& design_json, const std::vector<NewJob>& jobs,
                               double now, const std::string& owner = "");
  /// Jobs queued or leased, of the campaigns of `owner` (all campaigns without one).
  std::int64_t unfinished_jobs(const std::optional<std::string>& owner = std::nullopt);
  std::optional<CampaignRow> campaign(std::int64_t id);
  /// Replaces campaign `id`'s stored spec and plan (an option changed on a running or finished
  /// campaign); its jobs and results are kept.
  void set_campaign_plan(std::int64_t id, const std::string& spec_json,
                         const std::string& design_json);
  std::vector<CampaignRow> campaigns();
  Counts counts(std::int64_t campaign_id, const std::string& kind = "");
  std::vector<JobRow> jobs(std::int64_t campaign_id);
  std::optional<JobRow> job(std::int64_t job_id);
  /// Cancels every queued or leased job of a running campaign; false when the campaign does not
  /// exist or is not running (done or already cancelled).
  bool cancel(std::int64_t campaign_id, double now);
  /// Gives up job `job_id` of campaign `campaign_id`, queued or leased: it fails with the error
  /// "given up: <reason>", its checkpoint is dropped, its lease (if any) ends and its campaign
  /// finishes when no other job is left. Returns the queued jobs of its row that waited for it
  /// (NewJob::waits_for), leasable now; nothing, changing nothing, when the campaign has no such
  /// job or the job has ended (done, failed or cancelled).
  std::optional<std::vector<std::int64_t>> give_up(std::int64_t campaign_id, std::int64_t job_id,
                                                   const std::string& reason);
  /// Adds jobs to an existing campaign (verification runs); the campaign runs again.
  std::vector<std::int64_t> add_jobs(std::int64_t campaign_id, const std::vector<NewJob>& jobs);
  /// Stores a calibration round and queues its jobs in one transaction.
  std::vector<std::int64_t> add_calibration_round(std::int64_t campaign_id,
                                                  const CalibrationRoundRow& round,
                                                  const std::vector<NewJob>& jobs);
  /// Stores a calibration stage and queues its design jobs in one transaction.
  std::vector<std::int64_t> add_calibration_stage(std::int64_t campaign_id,
                                                  const CalibrationStageRow& stage,
                                                  const std::vector<NewJob>& jobs);
  std::vector<CalibrationRoundRow> calibration_rounds(std::int64_t campaign_id);
  std::vector<CalibrationStageRow> calibration_stages(std::int64_t campaign_id);

  /// The next queued job (oldest campaign first, then run order), leased to `worker` until
  /// `now + lease` (`now` on the monotonic clock, as for the calls below). A queued job whose run
  /// key has a finished run (a done job of any campaign, else a run kept by import_runs) is not
  /// leased: it takes that result, marked as reused, and the next is looked at. A queued job whose
  /// run key another job is running waits for that run's result.
  std::optional<JobRow> lease(const std::string& worker, double now);
  /// Keeps runs read from a journal for the jobs with their run keys; a key held already keeps
  /// the run it has (its test, seed and parameters filled in when it had none). Returns how many
  /// were new.
  int import_runs(const std::vector<FinishedRun>& runs);
  /// Whether a finished run of this key is held: a done job's, or a journal run.
  bool holds_run(const std::string& run_key);
  /// The journal runs held of lab test `test` at seed `seed` (decimal).
  std::vector<HeldRun> journal_runs_at(const std::string& test, const std::string& seed);
  /// Sets the run key of every job that has none yet (jobs of a file from before run keys) and of
  /// every job not done to `key_of(payload)`: a job planned under another version of its test's
  /// protocol is simulated under this one and must be known by this one's key. A done job keeps
  /// the key its result was simulated under. An empty key marks a job that is never reused. A
  /// job whose key changes loses its checkpoint: the state was simulated as another run (another
  /// protocol version of its test) and goes on as none under this one.
  void refresh_run_keys(const std::function<RunKey(const std::string& payload)>& key_of);
  /// Extends the current, unexpired lease held by `worker`. A beat of a lease whose result that
  /// worker has stored (a beat sent while its Complete was being answered) is kOk and extends
  /// nothing: the lease ended by its own result, not lost.
  LeaseAnswer heartbeat(std::int64_t job_id, int attempt, const std::string& worker, double now);
  /// Stores the result of the current, unexpired lease held by `worker` exactly once; a retry
  /// with the result already stored for that lease (same metrics and wall time) is kOk too.
  /// `series_json` (the run's curves; empty: none) goes to its own table in the same transaction.
  LeaseAnswer complete(std::int64_t job_id, int attempt, const std::string& worker,
                       const std::string& metrics_json, double wall_seconds, double now,
                       const std::string& flags_json = "{}", const std::string& cost_json = "{}",
                       const std::string& series_json = "");
  /// The stored curves of the campaign's finished jobs: job id -> series JSON.
  std::map<std::int64_t, std::string> series(std::int64_t campaign_id);
  /// See the state machine above; only the current lease's holder may fail it.
  /// A give-back that `yielded` (at the coordinator's request, yield_due) counts in the job's
  /// yields, which order the queue.
  LeaseAnswer fail(std::int64_t job_id, int attempt, const std::string& worker,
                   const std::string& reason, bool retryable, bool give_back, double now,
                   bool yielded = false);
  /// Whether the current lease of `job_id` is to yield at its run's next checkpoint: it began
  /// more than `yield_after` x 2^yields seconds before `now` (the job's yields so far) and a job
  /// that yielded no more often is queued and leasable. Always false when `yield_after` is 0.
  bool yield_due(std::int64_t job_id, double now, double yield_after);
  /// Keeps a checkpoint of the current, unexpired lease held by `worker`, in place of the job's
  /// earlier one; a stored result drops it.
  LeaseAnswer save_checkpoint(std::int64_t job_id, int attempt, const std::string& worker,
                              const std::string& stage, const std::string& state, double now,
                              const CheckpointClock& clock = {});
  /// The job's latest checkpoint, if any.
  std::optional<CheckpointRow> checkpoint(std::int64_t job_id);
  /// Per job of the campaign with a checkpoint, its stage, when it was kept and its clock.
  std::map<std::int64_t, CheckpointMark> checkpoint_marks(std::int64_t campaign_id);
  /// Expired leases go back to the queue, or fail at the attempt cap. Returns jobs reaped.
  int reap(double now);
  /// The current lease's deadline on the monotonic clock, if the job has one (for tests).
  std::optional<double> lease_deadline(std::int64_t job_id);
  /// Results stored for a job (0 or 1: the primary key makes 2 impossible), for tests.
  int result_count(std::int64_t job_id);

 private:
  class Transaction;
  class Statement;
  class Guard;
  /// The job's current lease named by (attempt, worker), leased and unexpired at `now`.
  LeaseAnswer check_lease(std::int64_t job_id, int attempt, const std::string& worker, double now);
  /// The result `worker`'s lease `attempt` stored, when the job is done with it.
  struct StoredResult {
    std::string metrics_json;
    double wall_seconds = 0.0;
  };
  std::optional<StoredResult> stored_result(std::int64_t job_id, int attempt,
                                            const std::string& worker);
  void restore_leases(double opened);
  /// Seconds on the clock of limits().clock.
  double clock_now() const { return limits_.clock ? limits_.clock() : steady_seconds(); }
  /// Throws unless the file is in WAL mode (checked at opening).
  void require_wal(const std::string& path);
  /// Throws, naming the file and the damage, unless PRAGMA quick_check finds the file sound
  /// (checked at opening, before anything is written).
  void require_intact(const std::string& path);
  std::string journal_mode_unlocked();
  /// Adds `seconds` to every lease deadline (the lock was held that long).
  void extend_deadlines(double seconds);
  void exec(const char* sql);
  /// Takes the file's schema to the latest version, all in one transaction, and refuses to
  /// commit it where a row then breaks a foreign key.
  void migrate(const std::string& path);
  /// Throws, naming the file and up to five rows that break a foreign key, unless none does;
  /// `version_found` is the schema version the file had (whether a migration ran).
  void require_foreign_keys(const std::string& path, int version_found);
  void finish_campaigns(double now);
  /// Deletes the job's checkpoint, if any (inside the caller's transaction).
  void drop_checkpoint(std::int64_t job_id);
  /// Inserts jobs[first, end) as queued jobs of the campaign; inside a transaction.
  std::vector<std::int64_t> insert_job_rows(std::int64_t campaign_id,
                                            const std::vector<NewJob>& jobs, std::size_t first,
                                            std::size_t end);
  void drop_unfinished_campaigns();
  /// Inserts queued jobs and reopens a finished campaign; inside a transaction.
  std::vector<std::int64_t> insert_jobs(std::int64_t campaign_id, const std::vector<NewJob>& jobs);
  bool requeue_or_fail(std::int64_t job_id, int counted, const std::string& reason, bool retryable,
                       double now);
  /// The next queued job a worker may take (see lease()): its id, run key and yields. Inside the
  /// lock.
  struct NextJob {
    std::int64_t id = 0;
    std::string run_key;
    int yields = 0;
  };
  std::optional<NextJob> next_queued();
  /// Gives the queued job the result of a finished run with run key `key` (see lease()); false
  /// when there is none. Inside a transaction.
  bool take_finished_run(std::int64_t job_id, const std::string& key);

  /// Finalises the cached statements and closes the connection.
  void close();

  StoreLock lock_;  ///< first in, last out: held while the file is open
  sqlite3* db_ = nullptr;
  /// Prepared statements not in use, by their SQL (Statement takes and gives back); guarded by
  /// mutex_ like the connection.
  std::unordered_map<std::string, sqlite3_stmt*> idle_statements_;
  StoreLimits limits_;
  double opened_wall_ = 0.0;  ///< wall-clock seconds of the opening (Counts::opening)
  std::mutex mutex_;
  /// A current lease's clock: when it began and when it expires unless renewed.
  struct LeaseClock {
    double began = 0.0, deadline = 0.0;
  };
  std::unordered_map<std::int64_t, LeaseClock> leases_;  ///< job -> its current lease
};

}  // namespace demcal::server
