#include "client/embedded.hpp"

#include <fcntl.h>
#include <google/protobuf/util/message_differencer.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>

#include "core/common/error.hpp"
#include "rpc/material_convert.hpp"
#include "rpc/stop_signals.hpp"
#include "server/limits.hpp"
#include "server/store.hpp"
#include "server/store_lock.hpp"

namespace demcal::cli {
namespace {

std::string random_token() {
  std::random_device rd;
  std::string t;
  for (int i = 0; i < 32; ++i) t += "0123456789abcdef"[rd() % 16];
  return t;
}

/// The service whose workers a stop signal ends (one at a time per process).
std::atomic<EmbeddedService*> signalled_service{nullptr};

/// Takes SIGINT and SIGTERM for the whole process, in one thread started once: they are blocked
/// in the calling thread before any other starts, so every later thread inherits the block.
void watch_stop_signals() {
  static const bool started = [] {
    const sigset_t set = rpc::block_stop_signals();
    std::thread([set] {
      int sig = 0;
      sigwait(&set, &sig);
      if (EmbeddedService* service = signalled_service.load()) service->stop_on_signal(sig);
      std::fflush(nullptr);
      std::_Exit(128 + sig);
    }).detach();
    return true;
  }();
  (void)started;
}

/// A copy of a store another coordinator holds, in a private temporary directory removed with
/// it: what a look at a running campaign reads instead of the store itself.
class StoreCopy {
 public:
  explicit StoreCopy(const std::filesystem::path& db) {
    std::string tmpl = (std::filesystem::temp_directory_path() / "demcal-look-XXXXXX").string();
    if (!::mkdtemp(tmpl.data()))
      throw std::runtime_error("cannot make a directory for a copy of " + db.string() + ": " +
                               std::strerror(errno));
    dir_ = tmpl;
    try {
      server::Store::copy_file(db.string(), (dir_ / db.filename()).string());
    } catch (...) {
      std::filesystem::remove_all(dir_);
      throw;
    }
  }
  ~StoreCopy() {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
  StoreCopy(const StoreCopy&) = delete;
  StoreCopy& operator=(const StoreCopy&) = delete;
  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path dir_;
};

/// "held by a running coordinator (pid N)": who holds a store, for the messages below.
std::string held_by(const server::StoreLock::Holder& holder) {
  return "held by a running coordinator" + (holder.pid.empty() ? "" : " (pid " + holder.pid + ")");
}

/// Where a coordinator that holds the store of a work directory leaves its loopback address and
/// token for the commands of its user.
std::filesystem::path coordinator_file(const std::filesystem::path& workdir) {
  return workdir / "coordinator.json";
}

/// Writes the coordinator file of `workdir`: its owner's alone (0600), as the store is, written to
/// a temporary file and renamed. A failure to write is reported and otherwise ignored: the other
/// commands then read a copy of the store or are refused, as without it.
void leave_coordinator_file(const std::filesystem::path& workdir,
                            const rpc::ChannelOptions& channel) {
  const auto file = coordinator_file(workdir);
  const std::string temporary = file.string() + ".tmp";
  const std::string text = nlohmann::json{
      {"pid", std::to_string(::getpid())},
      {"address", channel.address},
      {"token", channel.token}}.dump();
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  const bool written =
      fd >= 0 && ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  if (fd >= 0) ::close(fd);
  if (!written || std::rename(temporary.c_str(), file.c_str()) != 0) {
    std::cerr << "could not write " << file.string() << " (" << std::strerror(errno)
              << "): other commands will read a copy of the store while this one runs\n";
    std::filesystem::remove(temporary);
  }
}

/// The coordinator holding the store of `workdir` as `holder`, where it left its address: its
/// file is this user's, readable by no one else, and names the holder's pid. Anything else
/// (no file, another owner or mode, another pid, a file that does not parse) reaches nothing.
std::optional<rpc::ChannelOptions> live_coordinator(const std::filesystem::path& workdir,
                                                    const server::StoreLock::Holder& holder) {
  const auto file = coordinator_file(workdir);
  struct stat st {};
  if (::lstat(file.c_str(), &st) != 0 || !S_ISREG(st.st_mode) || st.st_uid != ::geteuid() ||
      (st.st_mode & 077) != 0)
    return std::nullopt;
  std::ifstream in(file);
  const auto j = nlohmann::json::parse(in, nullptr, false);
  if (!j.is_object() || !j.contains("pid") || !j.contains("address") || !j.contains("token") ||
      j["pid"] != holder.pid || !j["address"].is_string() || !j["token"].is_string())
    return std::nullopt;
  rpc::ChannelOptions channel;
  channel.address = j["address"];
  channel.token = j["token"];
  return channel;
}

/// Why a look (a command that runs no job) reads a copy of a store taken now instead of the
/// file, and, for a store a running coordinator holds, since when that one holds it.
struct CopyToLookAt {
  std::string why;
  std::optional<double> held_since;
};

/// Whether a look at the store file `store` reads a copy, and why; nothing when it reads the
/// file. A store a running coordinator holds (e.g. a diagnosis going on in another process) is
/// not touched, nor is one of an older schema version: opened as a store, it would be migrated,
/// and the build that wrote it (a campaign's own, going on from it) would refuse it after.
std::optional<CopyToLookAt> copy_to_look_at(const std::filesystem::path& store) {
  if (const auto held = server::StoreLock::holder(store.string()))
    return CopyToLookAt{"is " + held_by(*held) + ": reporting from a copy of it taken now",
                        held->since};
  if (!std::filesystem::is_regular_file(store)) return std::nullopt;
  const int found = server::Store::file_schema_version(store.string());
  const int latest = server::Store::latest_schema_version();
  if (found >= latest) return std::nullopt;
  return CopyToLookAt{"is at schema version " + std::to_string(found) + ", this build's is " +
                          std::to_string(latest) +
                          ": reporting from a copy migrated from it, the store left at " +
                          std::to_string(found),
                      std::nullopt};
}

/// Throws InputError unless store file `store` exists and no running coordinator holds it: a
/// change is made to the file itself, never to a copy.
void require_a_store_to_change(const std::filesystem::path& store) {
  if (const auto held = server::StoreLock::holder(store.string()))
    throw InputError("", "the store " + store.string() + " is " + held_by(*held) +
                             ": stop it first (SIGTERM gives its leases back), or make the change "
                             "through that coordinator by campaign id");
  if (!std::filesystem::is_regular_file(store))
    throw InputError("", "no campaign store " + store.string() +
                             " (run the spec there first, or name its --workdir)");
}

/// The spec as a campaign is resumed by: canonical, without the diagnosis's rounds, which
/// `demcal diagnose` may change on a stored campaign (its runs kept).
v1::CampaignSpec resumed_as(const v1::CampaignSpec& spec) {
  v1::CampaignSpec out = rpc::canonical_spec(spec);
  if (out.has_diagnose()) out.mutable_diagnose()->clear_rounds();
  if (out.has_diagnose() && out.diagnose().ByteSizeLong() == 0) out.clear_diagnose();
  return out;
}

/// Throws InputError unless campaign `id` was submitted with the spec of `file`, up to its
/// diagnosis's rounds.
void refuse_if_another_spec(v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel,
                            std::int64_t id, const SpecFile& file,
                            const std::filesystem::path& workdir) {
  v1::GetRequest req;
  req.set_id(id);
  v1::Campaign stored;
  check(stub.Get(rpc::make_context(channel, 60).get(), req, &stored), "get");
  if (google::protobuf::util::MessageDifferencer::Equals(resumed_as(stored.spec()),
                                                         resumed_as(file.spec)))
    return;
  throw InputError("", "campaign " + std::to_string(id) + " '" + file.spec.name() + "' in " +
                           workdir.string() + " was submitted with another spec than " + file.name +
                           ": give another --workdir (or another name) to run it, "
                           "or the spec it was submitted with to resume it");
}

/// The newest campaign not cancelled of the spec's name on a coordinator of work directory
/// `workdir`; 0 when there is none. InputError as refuse_if_another_spec.
std::int64_t campaign_of_spec(v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel,
                              const SpecFile& file, const std::filesystem::path& workdir) {
  v1::ListReply list;
  check(stub.List(rpc::make_context(channel, 30).get(), {}, &list), "list");
  std::int64_t id = 0;
  for (const auto& c : list.campaigns())
    if (c.name() == file.spec.name() && c.state() != v1::CANCELLED) id = std::max(id, c.id());
  if (id) refuse_if_another_spec(stub, channel, id, file, workdir);
  return id;
}

/// InputError naming the spec and the work directory: no campaign of the spec there.
[[noreturn]] void no_campaign(const SpecFile& file, const std::filesystem::path& workdir) {
  throw InputError(
      "", "no campaign '" + file.spec.name() + "' of " + file.name + " in " + workdir.string());
}

}  // namespace

std::filesystem::path work_directory(const std::string& spec, const std::string& workdir) {
  return workdir.empty() ? std::filesystem::path("demcal-work") / std::filesystem::path(spec).stem()
                         : std::filesystem::path(workdir);
}

void with_campaign(const std::string& campaign, const std::string& workdir,
                   const LocalWorkers& local, bool verbose, const rpc::ChannelOptions& channel,
                   const CampaignAction& act, const std::string& journal, Reach reach) {
  if (std::filesystem::is_regular_file(campaign)) {
    const SpecFile file = read_campaign_spec(campaign);
    std::filesystem::path dir = work_directory(campaign, workdir);
    std::optional<StoreCopy> copy;
    std::optional<double> held_since;
    const std::filesystem::path store = EmbeddedService::store_path(dir);
    if (reach == Reach::kLook || reach == Reach::kChange)
      if (const auto held = server::StoreLock::holder(store.string()))
        if (const auto live = live_coordinator(dir, *held)) {
          std::cerr << "the store " << store.string() << " is " << held_by(*held)
                    << ": reaching it at " << live->address << "\n";
          const auto stub = campaign_stub(*live);
          const std::int64_t id = campaign_of_spec(*stub, *live, file, dir);
          if (!id) no_campaign(file, dir);
          act(*stub, *live, id);
          return;
        }
    if (reach == Reach::kChange) require_a_store_to_change(store);
    if (reach == Reach::kLook || reach == Reach::kLookAtCopy)
      if (const auto look = copy_to_look_at(store)) {
        copy.emplace(store);
        std::cerr << "the store " << store.string() << " " << look->why
                  << " (what the copy queues is thrown away with it)\n";
        dir = copy->dir();
        held_since = look->held_since;
      }
    // Read before anything starts: a journal with a bad line refuses the command.
    std::optional<CampaignJournal> runs;
    if (!journal.empty() && !copy) runs.emplace(journal);
    const bool run_jobs = reach == Reach::kRun;
    const LocalWorkers workers = run_jobs ? local : LocalWorkers{.workers = 0};
    EmbeddedService service(dir, workers, verbose, held_since);
    const std::int64_t id = reach == Reach::kChange ? service.resume(file, std::cerr)
                                                    : service.submit_or_resume(
                                                          file, std::cerr, runs ? &*runs : nullptr);
    if (run_jobs) watch_campaign(service.stub(), service.channel(), id, std::cerr);
    act(service.stub(), service.channel(), id);
    return;
  }
  if (!journal.empty())
    throw CLI::ValidationError("--journal", "only with a spec file (the embedded default)");
  std::int64_t id = 0;
  try {
    id = std::stoll(campaign);
  } catch (const std::exception&) {
    throw CLI::ValidationError("campaign",
                               "'" + campaign + "' is neither a spec file nor a campaign id");
  }
  act(*campaign_stub(channel), channel, id);
}

void add_campaign_options(CLI::App& cmd, std::string& campaign, std::string& workdir) {
  cmd.add_option("campaign", campaign, "campaign id, or a spec YAML (embedded default)")
      ->required();
  cmd.add_option("--workdir", workdir, "embedded: directory of the SQLite file");
}

void add_local_worker_options(CLI::App& cmd, LocalWorkers& local) {
  cmd.add_option("--workers", local.workers, "embedded: local workers (jobs run side by side)")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  cmd.add_option("--threads", local.threads, "embedded: simulation threads of each local worker")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  cmd.add_option("--yield-after", local.yield_after,
                 "embedded: a run that has held its worker this long (doubled per earlier yield) "
                 "gives it back at its next checkpoint when a run that yielded no more often "
                 "waits, so short runs finish first (s, 1-86400; 0: never)")
      ->check(CLI::Validator(
          [](const std::string& text) -> std::string {
            double v = -1.0;
            try {
              v = std::stod(text);
            } catch (const std::exception&) {
            }
            return server::yield_after_admitted(v) ? "" : "0 (never) or 1-86400 s";
          },
          "0 or 1-86400"))
      ->capture_default_str();
}

EmbeddedService::EmbeddedService(const std::filesystem::path& workdir, const LocalWorkers& local,
                                 bool verbose, std::optional<double> held_since)
    : workdir_(workdir), local_(local) {
  watch_stop_signals();
  // The work directory holds the campaign's database: a new one is its owner's alone (0700).
  if (std::filesystem::create_directories(workdir))
    std::filesystem::permissions(workdir, std::filesystem::perms::owner_all);
  // Logs of the embedded coordinator and workers go to standard error: standard output is the
  // command's result (one JSON document with --format json).
  static const auto logger = [] {
    auto l = spdlog::stderr_color_mt("demcal-embedded");
    spdlog::set_default_logger(l);
    return l;
  }();
  (void)logger;
  spdlog::set_level(verbose ? spdlog::level::info : spdlog::level::warn);
  server::CoordinatorOptions co;
  co.listen = "127.0.0.1:0";
  co.db = db_ = store_path(workdir).string();
  co.token = random_token();
  // Its workers die with it: no lease of an earlier run is still worked on, and none was the
  // job's fault (the run was stopped), so the jobs go back to the queue uncounted, to go on
  // from their latest checkpoint. A copy of a store another coordinator holds keeps that one's
  // leases, which are running there, and rates its jobs from that one's start.
  co.give_back_leases_at_start = !held_since;
  co.rate_since = held_since.value_or(0.0);
  // Its workers ask over loopback, where an empty poll costs microseconds: a worker that found
  // the queue empty takes a job a tenth of a second after it appears, not a second (with jobs
  // of a fraction of a second, one worker would otherwise run them all while the other waits).
  co.idle_retry_seconds = 0.1;
  co.yield_after_seconds = local.yield_after;
  coordinator_ = std::make_unique<server::Coordinator>(co);
  channel_.address = "127.0.0.1:" + std::to_string(coordinator_->port());
  channel_.token = co.token;
  holds_store_ = !held_since;
  if (holds_store_) leave_coordinator_file(workdir, channel_);
  stub_ = campaign_stub(channel_);
  signalled_service = this;
}

void EmbeddedService::start_local_workers() {
  if (!workers_.empty()) return;
  for (int i = 1; i <= local_.workers; ++i) {
    worker::WorkerOptions wo;
    wo.channel = channel_;
    wo.threads = local_.threads;
    wo.id = local_.workers == 1 ? "embedded" : "embedded-" + std::to_string(i);
    // The local workers share the stages runs can start from (docs/lab-tests.md, "Work done
    // once"), kept beside the campaign's database.
    wo.stage_cache_dir = (workdir_ / "stages").string();
    ++running_;
    workers_.emplace_back([this, wo] {
      worker::run_worker(wo, flags_);
      --running_;
    });
  }
}

void EmbeddedService::stop_on_signal(int sig) {
  std::cerr << "\nsignal " << sig
            << ": giving the running jobs back; the same command goes on from their latest "
               "checkpoints"
            << std::endl;
  flags_.abort = true;
  // A worker gives its lease back within its Fail deadline (seconds); the simulations it
  // leaves end with the process.
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (running_ > 0 && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  if (keeper_) keeper_->sync();
  take_address_away();
}

EmbeddedService::~EmbeddedService() {
  signalled_service = nullptr;
  if (http_) http_->stop();
  flags_.stop = true;
  for (auto& w : workers_) w.join();
  keeper_.reset();  // its last update, with every job the workers finished
  take_address_away();
  coordinator_->shutdown();
}

void EmbeddedService::take_address_away() {
  if (!holds_store_) return;
  std::error_code ignored;
  std::filesystem::remove(coordinator_file(workdir_), ignored);
}

std::int64_t EmbeddedService::submit_or_resume(const SpecFile& file, std::ostream& out,
                                               CampaignJournal* journal) {
  if (journal) import_journal(*stub_, channel_, *journal, file.spec, out);
  const std::int64_t id = submit_or_resume_campaign(file, out);
  if (journal) keeper_ = std::make_unique<JournalKeeper>(*journal, *stub_, channel_, id);
  start_local_workers();
  return id;
}

namespace {

/// Says that campaign `id` of `file` is resumed; returns `id`.
std::int64_t resuming(std::int64_t id, const SpecFile& file, std::ostream& out) {
  out << "resuming campaign " << id << " '" << file.spec.name() << "'\n";
  return id;
}

}  // namespace

std::int64_t EmbeddedService::resumable_campaign(const SpecFile& file) {
  return campaign_of_spec(*stub_, channel_, file, workdir_);
}

std::int64_t EmbeddedService::resume(const SpecFile& file, std::ostream& out) {
  const std::int64_t id = resumable_campaign(file);
  if (!id) no_campaign(file, workdir_);
  start_local_workers();
  return resuming(id, file, out);
}

std::int64_t EmbeddedService::submit_or_resume_campaign(const SpecFile& file, std::ostream& out) {
  if (const std::int64_t id = resumable_campaign(file)) return resuming(id, file, out);
  v1::SubmitRequest req;
  *req.mutable_spec() = file.spec;
  v1::SubmitReply reply;
  const auto s = stub_->Submit(rpc::make_context(channel_, 120).get(), req, &reply);
  if (s.error_code() == grpc::StatusCode::INVALID_ARGUMENT)
    throw InputError("", file.locate(s.error_message()));
  check(s, "submit");
  out << "campaign " << reply.id() << " '" << file.spec.name() << "'\n";
  print_design_summary(out, reply.design());
  return reply.id();
}

}  // namespace demcal::cli

namespace demcal::cli {

std::string EmbeddedService::serve_http(const std::string& address, std::int64_t id) {
  server::HttpPageOptions options;
  options.listen = address;
  options.token = channel_.token;
  http_ = std::make_unique<server::HttpPage>(coordinator_->in_process_channel(), options);
  const std::string host = address.substr(0, address.rfind(':'));
  return "http://" + host + ":" + std::to_string(http_->port()) + "/campaigns/" +
         std::to_string(id) + "#token=" + channel_.token;
}

}  // namespace demcal::cli
