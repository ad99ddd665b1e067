#pragma once
// A campaign's journal file as `demcal run --journal FILE` and `demcal submit --journal FILE` keep
// it (docs/journal.md; its lines: rpc/journal_line.hpp): the runs it holds are offered to the
// coordinator before the campaign starts, so that every job whose run key it holds takes that
// run's result instead of being simulated, and every job the campaign finishes is appended as it
// finishes.
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <optional>
#include <ostream>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "client/jsonl_file.hpp"
#include "demcal/v1/campaign.grpc.pb.h"
#include "rpc/channel.hpp"

namespace demcal::cli {

class CampaignJournal {
 public:
  /// Reads the file (a new one holds nothing). A last line cut short is dropped from it; any
  /// other line that is not a journal line, or a first line that is not a journal's header, is
  /// an InputError naming the file and line; so is a file whose directory does not exist.
  explicit CampaignJournal(std::filesystem::path path);

  const std::filesystem::path& path() const { return file_.path(); }
  /// The runs read, each with its source (FILE:LINE).
  const std::vector<v1::JournalRun>& runs() const { return runs_; }
  /// The spec of the campaign that wrote runs()[i]: its segment's header's; null when that
  /// header's spec cannot be read as a campaign spec (another build's, say).
  const v1::CampaignSpec* spec_of(std::size_t i) const {
    const auto& spec = specs_[run_segment_[i]];
    return spec ? &*spec : nullptr;
  }
  /// Whether the journal has a line of this run key written under this lab protocol version.
  bool holds(const std::string& run_key, int protocol) const {
    return held_.count({run_key, protocol}) > 0;
  }

  /// Appends a journal export of the coordinator (Export, format journal): its header line when
  /// it differs from the latest header of the file (another campaign or build writes on), then
  /// its runs the file does not hold.
  void append_export(const std::string& content);

 private:
  void take(const std::string& text, std::size_t line);

  JsonLinesFile file_;
  std::vector<v1::JournalRun> runs_;
  std::vector<std::optional<v1::CampaignSpec>> specs_;  ///< of each header line, in order
  std::vector<std::size_t> run_segment_;                ///< of each run: its header's index
  std::set<std::pair<std::string, int>> held_;          ///< run key, protocol of every run line
  std::string header_;                                  ///< the latest header line of the file
};

/// Offers the journal's runs to the coordinator (ImportRuns, in batches of about 1 MiB) and says
/// on `out` what became of them: how many were new or held already, how many were not taken
/// because they were simulated under another lab protocol version, and how many were not offered
/// because this build refuses their material (a run of an instance of `spec` whose material fails
/// lab::check_contact_range: a result an older build simulated is not used where this one would
/// fail the run).
void import_journal(v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel,
                    const CampaignJournal& journal, const v1::CampaignSpec& spec,
                    std::ostream& out);

/// Keeps the journal of campaign `id` up to date while it lives: following the campaign's
/// progress (Watch, again every half second once the campaign no longer runs, since a calibration
/// or diagnosis may reopen it), whenever its count of finished jobs changes, and once more when it
/// ends, the finished jobs the journal does not hold are appended (exported by the coordinator in
/// the journal format). A failed update is reported on standard error and tried again at the next.
class JournalKeeper {
 public:
  JournalKeeper(CampaignJournal& journal, v1::CampaignService::Stub& stub,
                const rpc::ChannelOptions& channel, std::int64_t id);
  ~JournalKeeper();
  JournalKeeper(const JournalKeeper&) = delete;
  JournalKeeper& operator=(const JournalKeeper&) = delete;

  /// Appends the finished jobs the journal does not hold yet; false (the error reported, not
  /// thrown) when it could not.
  bool sync();

 private:
  void follow();
  void append_finished();

  CampaignJournal& journal_;
  v1::CampaignService::Stub& stub_;
  const rpc::ChannelOptions& channel_;
  std::int64_t id_;
  std::mutex sync_mutex_;   ///< one update at a time (the keeper's thread, a stop signal's)
  std::string last_error_;  ///< of the latest update; empty when it succeeded
  std::mutex mutex_;
  std::condition_variable cv_;
  bool stopped_ = false;
  grpc::ClientContext* watching_ = nullptr;  ///< the Watch call under way, cancelled at the end
  std::thread thread_;                       ///< last: started once the members it uses exist
};

}  // namespace demcal::cli
