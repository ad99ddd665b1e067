#pragma once
// The embedded default: a coordinator (SQLite file in a work directory, loopback only, a random
// token) and local workers in this process, talking real gRPC. Used by `demcal run` and
// `demcal diagnose SPEC`.
#include <CLI/CLI.hpp>
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "client/campaign_journal.hpp"
#include "client/service_client.hpp"
#include "client/spec_yaml.hpp"
#include "server/coordinator.hpp"
#include "server/http_page.hpp"
#include "worker/worker.hpp"

namespace demcal::cli {

/// The local workers: `workers` worker loops in this process, each running one job at a time on
/// `threads` simulation threads (which to choose: docs/worker.md).
struct LocalWorkers {
  int workers = 1;
  int threads = 2;
  double yield_after = 0.0;  ///< the embedded coordinator's --yield-after (s; 0: never)
};

/// `--workers`, `--threads` and `--yield-after` of a command that runs the embedded default.
void add_local_worker_options(CLI::App& cmd, LocalWorkers& local);

/// The campaign a command names (required: an id, or a spec YAML on the embedded default) and
/// `--workdir`, the spec's work directory (with_campaign).
void add_campaign_options(CLI::App& cmd, std::string& campaign, std::string& workdir);

class EmbeddedService {
 public:
  /// `held_since`: the store in `workdir` is a copy of one that a running coordinator has held
  /// since then (wall-clock s): the copy keeps that one's leases (its jobs in flight show as
  /// running) and rates its jobs from that time.
  EmbeddedService(const std::filesystem::path& workdir, const LocalWorkers& local, bool verbose,
                  std::optional<double> held_since = std::nullopt);
  ~EmbeddedService();
  EmbeddedService(const EmbeddedService&) = delete;
  EmbeddedService& operator=(const EmbeddedService&) = delete;

  /// The campaign's SQLite file in work directory `workdir`.
  static std::filesystem::path store_path(const std::filesystem::path& workdir) {
    return workdir / "campaign.db";
  }

  const rpc::ChannelOptions& channel() const { return channel_; }
  v1::CampaignService::Stub& stub() { return *stub_; }
  std::string db() const { return db_; }

  /// The campaign of the spec's name in this work directory (the newest one not cancelled),
  /// or the spec submitted now (its design summary printed to `out`). Returns its id. A campaign
  /// of that name submitted with another spec (other than in its diagnosis's rounds) is not
  /// resumed: InputError naming the directory.
  /// With a `journal`, its runs are offered to the coordinator first (import_journal, its report
  /// on `out`), and it is kept up to date with the campaign's finished jobs while this service
  /// lives (JournalKeeper), with a last update once its workers have stopped, also on a stop
  /// signal.
  std::int64_t submit_or_resume(const SpecFile& file, std::ostream& out,
                                CampaignJournal* journal = nullptr);
  /// The campaign of the spec's name in this work directory, as submit_or_resume finds it;
  /// InputError naming the directory when there is none (nothing is submitted).
  std::int64_t resume(const SpecFile& file, std::ostream& out);

  /// Serves the live report page on `address` (HOST:PORT, loopback or with the embedded
  /// token) while this service lives. Returns the page's URL of campaign `id`, the token in
  /// its fragment (never sent to the server by a browser).
  std::string serve_http(const std::string& address, std::int64_t id);

  /// SIGINT or SIGTERM `sig` (Ctrl-C, the end of a batch allocation): the workers give their
  /// leases back at once, uncounted, and return; the journal kept, if any, is brought up to
  /// date; the caller then ends the process. The next run of the same command goes on from the
  /// jobs' latest checkpoints.
  void stop_on_signal(int sig);

 private:
  /// Removes the address it left in its work directory (a holder's; a copy left none).
  void take_address_away();
  /// Starts the local workers (once). Not before the campaign is reached: a worker leases at
  /// once, and a job leased before the journal's runs are offered would simulate a run the
  /// journal holds.
  void start_local_workers();
  /// submit_or_resume without a journal.
  std::int64_t submit_or_resume_campaign(const SpecFile& file, std::ostream& out);
  /// The newest campaign not cancelled of the spec's name in this work directory; 0 when there
  /// is none. InputError unless it was submitted with the spec of `file`, up to its diagnosis's
  /// rounds.
  std::int64_t resumable_campaign(const SpecFile& file);

  std::filesystem::path workdir_;
  std::string db_;
  std::unique_ptr<server::Coordinator> coordinator_;
  std::unique_ptr<server::HttpPage> http_;
  rpc::ChannelOptions channel_;
  LocalWorkers local_;
  worker::StopFlags flags_;
  std::vector<std::thread> workers_;
  std::atomic<int> running_{0};  ///< workers that have not returned
  std::unique_ptr<v1::CampaignService::Stub> stub_;
  std::unique_ptr<JournalKeeper> keeper_;
  bool holds_store_ = false;  ///< not a copy: it left its address in the work directory
};

/// demcal-work/<spec stem> unless a directory is given.
std::filesystem::path work_directory(const std::string& spec, const std::string& workdir);

/// What a command does with a campaign once it is reached: its stub, channel and id.
using CampaignAction = std::function<void(v1::CampaignService::Stub& stub,
                                          const rpc::ChannelOptions& channel, std::int64_t id)>;

/// What a command does to a campaign's store on the embedded default.
/// A coordinator that holds a store (a `demcal run` or `demcal diagnose` going on) leaves its
/// loopback address and token in the work directory, its user's alone: a look or a change there
/// is made through it.
enum class Reach {
  kRun,         ///< runs its jobs on local workers, watched until they end
  kLook,        ///< runs nothing and reads the store as it stands: through the running
                ///< coordinator that holds it, else from a copy taken now (one that left no
                ///< address, or a store of a schema older than this build's)
  kLookAtCopy,  ///< as kLook, but from a copy whenever a running coordinator holds the store:
                ///< for a look that queues runs, which the copy throws away
  kChange,      ///< runs nothing and changes the store: through the running coordinator that
                ///< holds it; refused when one that left no address holds it (a copy's change
                ///< would be thrown away) or there is none yet
};

/// Reaches the campaign a command names and runs `act` on it: a spec YAML file on the embedded
/// default (submitted or resumed in `workdir`, as `reach` says), otherwise a campaign id on the
/// coordinator of `channel`. With a `journal` (spec files only, kRun) its runs are taken first and
/// every job finished meanwhile is appended to it, as `demcal run --journal` does (not in a copy:
/// the journal is its holder's). CLI::ValidationError for text that is neither, or for a journal
/// with a campaign id; InputError naming the store for a change it cannot take.
void with_campaign(const std::string& campaign, const std::string& workdir,
                   const LocalWorkers& local, bool verbose, const rpc::ChannelOptions& channel,
                   const CampaignAction& act, const std::string& journal = {},
                   Reach reach = Reach::kRun);

}  // namespace demcal::cli
