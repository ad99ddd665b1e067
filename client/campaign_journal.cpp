#include "client/campaign_journal.hpp"

#include <chrono>
#include <iostream>
#include <map>
#include <variant>

#include "client/service_client.hpp"
#include "core/common/error.hpp"
#include "core/lab/bed.hpp"
#include "rpc/journal_line.hpp"
#include "rpc/material_convert.hpp"
#include "server/stored_columns.hpp"

namespace demcal::cli {
namespace {

/// The version of `test`'s protocol the coordinator runs (its reply to ImportRuns).
int coordinator_protocol(const v1::ImportRunsReply& reply, const std::string& test) {
  const auto own = reply.test_protocol().find(test);
  return own == reply.test_protocol().end() ? reply.protocol() : own->second;
}

/// "3 shear_cell runs of version 2 (the coordinator runs 3), 1 tensile run of version 1 (2)": the
/// journal's runs of each test and version the coordinator does not run.
std::string other_protocols(const std::vector<v1::JournalRun>& runs,
                            const v1::ImportRunsReply& reply) {
  std::map<std::pair<std::string, int>, int> count;
  for (const auto& run : runs)
    if (run.protocol() != coordinator_protocol(reply, run.test()))
      ++count[{run.test(), run.protocol()}];
  std::string text;
  for (const auto& [test_version, n] : count) {
    const auto& [test, version] = test_version;
    text += (text.empty() ? "" : ", ") + std::to_string(n) + " " + test + " run" +
            (n == 1 ? "" : "s") + " of version " + std::to_string(version) +
            (text.empty() ? " (the coordinator runs " : " (") +
            std::to_string(coordinator_protocol(reply, test)) + ")";
  }
  return text;
}

/// The spec a header line names (the coordinator's stored spec JSON), or none when this build
/// cannot read it (another build's fields).
std::optional<v1::CampaignSpec> header_spec(const v1::JournalHeader& header) {
  try {
    return server::spec_from_json(header.spec());
  } catch (const InputError&) {
    return std::nullopt;
  }
}

/// Whether the current build refuses to simulate `run`'s material (lab::check_contact_range),
/// built as the campaign that wrote it built it (`own`, its header's spec), or else as `spec`
/// builds it, for the run's test instance; its reason, or empty. A run of an instance neither
/// spec has, or whose parameters do not apply to that spec's material, is not checked: its
/// material cannot be rebuilt here.
std::string refusal(const v1::JournalRun& run, const v1::CampaignSpec* own,
                    const v1::CampaignSpec& spec) {
  const v1::LabTest* instance = own ? rpc::find_instance(*own, run.instance()) : nullptr;
  const v1::CampaignSpec& from = instance ? *own : spec;
  if (!instance) instance = rpc::find_instance(spec, run.instance());
  if (!instance || instance->test() != run.test()) return "";
  try {
    lab::check_contact_range(
        rpc::job_material(from, instance, {run.parameters().begin(), run.parameters().end()}));
  } catch (const SimulationFailure& e) {
    return e.what();
  } catch (const InputError&) {
    return "";
  }
  return "";
}

}  // namespace

CampaignJournal::CampaignJournal(std::filesystem::path path) : file_(std::move(path)) {
  // Refused now rather than at the first job finished, which could not be appended.
  const auto directory = file_.path().parent_path();
  if (!directory.empty() && !std::filesystem::is_directory(directory))
    throw InputError(file_.path().string(), "its directory does not exist");
  file_.read([this](const std::string& text, std::size_t line) { take(text, line); },
             "a line of a campaign journal");
}

void CampaignJournal::take(const std::string& text, std::size_t line) {
  auto parsed = rpc::parse_journal_line(text);
  if (std::holds_alternative<v1::JournalHeader>(parsed)) {
    header_ = text;
    specs_.push_back(header_spec(std::get<v1::JournalHeader>(parsed)));
    return;
  }
  if (line == 1)
    throw InputError(file_.where(line),
                     "not a campaign journal: its first line is not a journal's header");
  auto& run = std::get<v1::JournalRun>(parsed);
  // The first run of a key is the one taken, as the coordinator keeps the first it is offered.
  if (!held_.insert({run.run_key(), run.protocol()}).second) return;
  run.set_source(file_.where(line));
  runs_.push_back(std::move(run));
  run_segment_.push_back(specs_.size() - 1);
}

void CampaignJournal::append_export(const std::string& content) {
  std::vector<std::string> lines;
  std::string header;  ///< the export's header, written before its first new run
  for (const auto& text : split_lines(content)) {
    const auto parsed = rpc::parse_journal_line(text);
    if (std::holds_alternative<v1::JournalHeader>(parsed)) {
      header = text;
      continue;
    }
    const auto& run = std::get<v1::JournalRun>(parsed);
    if (!held_.insert({run.run_key(), run.protocol()}).second) continue;
    if (!header.empty() && header != header_) {
      lines.push_back(header);
      header_ = header;
    }
    lines.push_back(text);
  }
  if (!lines.empty()) file_.append(lines);
}

void import_journal(v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel,
                    const CampaignJournal& journal, const v1::CampaignSpec& spec,
                    std::ostream& out) {
  std::vector<const v1::JournalRun*> offered;
  std::size_t refused = 0;
  std::string reason;
  for (std::size_t i = 0; i < journal.runs().size(); ++i) {
    const auto& run = journal.runs()[i];
    const std::string why = refusal(run, journal.spec_of(i), spec);
    if (why.empty()) {
      offered.push_back(&run);
    } else if (refused++ == 0) {
      reason = run.source() + ": " + why;
    }
  }
  constexpr std::size_t kBatchBytes = std::size_t(1) << 20;
  v1::ImportRunsReply total;
  for (std::size_t first = 0; first < offered.size();) {
    v1::ImportRunsRequest batch;
    std::size_t bytes = 0;
    for (; first < offered.size() && bytes < kBatchBytes; ++first) {
      bytes += offered[first]->ByteSizeLong();
      *batch.add_runs() = *offered[first];
    }
    v1::ImportRunsReply reply;
    check(stub.ImportRuns(rpc::make_context(channel, 120).get(), batch, &reply), "import");
    total.set_kept(total.kept() + reply.kept());
    total.set_known(total.known() + reply.known());
    total.set_other_protocol(total.other_protocol() + reply.other_protocol());
    total.set_protocol(reply.protocol());
    *total.mutable_test_protocol() = reply.test_protocol();
  }
  out << "journal " << journal.path().string() << ": " << journal.runs().size() << " run(s) read, "
      << total.kept() << " new to the coordinator, " << total.known() << " held already\n";
  if (total.other_protocol() > 0)
    out << "journal " << journal.path().string() << ": " << total.other_protocol()
        << " run(s) not taken: simulated under another version of their test's protocol ("
        << other_protocols(journal.runs(), total) << "), whose results may differ\n";
  if (refused > 0)
    out << "journal " << journal.path().string() << ": " << refused
        << " run(s) not taken: their material is one this build refuses to simulate (the first, "
        << reason << ")\n";
}

JournalKeeper::JournalKeeper(CampaignJournal& journal, v1::CampaignService::Stub& stub,
                             const rpc::ChannelOptions& channel, std::int64_t id)
    : journal_(journal), stub_(stub), channel_(channel), id_(id), thread_([this] { follow(); }) {}

JournalKeeper::~JournalKeeper() {
  {
    std::lock_guard lock(mutex_);
    stopped_ = true;
    if (watching_) watching_->TryCancel();
  }
  cv_.notify_all();
  thread_.join();
  sync();
}

void JournalKeeper::follow() {
  std::int64_t synced = -1;  ///< the count of finished jobs the journal is up to date with
  std::unique_lock lock(mutex_);
  while (!stopped_) {
    const auto context = rpc::make_context(channel_, 7 * 24 * 3600.0);
    watching_ = context.get();
    lock.unlock();
    v1::WatchRequest req;
    req.set_id(id_);
    const auto reader = stub_.Watch(context.get(), req);
    for (v1::Progress p; reader->Read(&p);)
      if (p.done() != synced && sync()) synced = p.done();
    reader->Finish();  // the campaign no longer runs, the coordinator is away, or stopped
    lock.lock();
    watching_ = nullptr;
    cv_.wait_for(lock, std::chrono::milliseconds(500), [this] { return stopped_; });
  }
}

bool JournalKeeper::sync() {
  std::lock_guard lock(sync_mutex_);
  try {
    append_finished();
    last_error_.clear();
    return true;
  } catch (const std::exception& e) {
    // Said once per cause, not at every try: the next update tries again.
    if (e.what() != last_error_)
      std::cerr << "journal " << journal_.path().string() << ": not updated: " << e.what() << "\n";
    last_error_ = e.what();
    return false;
  }
}

void JournalKeeper::append_finished() {
  v1::GetRequest req;
  req.set_id(id_);
  v1::ResultsReply results;
  check(stub_.GetResults(rpc::make_context(channel_, 60).get(), req, &results), "results");
  std::vector<std::int64_t> fresh;
  for (const auto& job : results.jobs())
    if (job.state() == "done" && !job.run_key().empty() &&
        !journal_.holds(job.run_key(), job.run_protocol()))
      fresh.push_back(job.job_id());
  if (fresh.empty()) return;
  std::string content;
  check(read_export(stub_, channel_, id_, "journal", content, false, fresh), "export");
  journal_.append_export(content);
}

}  // namespace demcal::cli
