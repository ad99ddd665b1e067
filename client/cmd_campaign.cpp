// `demcal list | status ID|SPEC | watch ID | cancel ID | give-up ID|SPEC`: campaigns on a
// coordinator (status and give-up also of a spec's campaign on the embedded default).
#include <algorithm>
#include <ctime>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "client/commands.hpp"
#include "client/embedded.hpp"
#include "client/service_client.hpp"

namespace demcal::cli {
namespace {

void print_campaign_row(const v1::Campaign& c) {
  std::cout << std::setw(5) << c.id() << "  " << std::left << std::setw(28) << c.name()
            << std::setw(10) << state_name(c.state()) << std::right
            << progress_line(c.progress(), 20) << "\n";
}

/// A Unix time as "YYYY-MM-DD HH:MM:SS UTC".
std::string utc_time(double unix_seconds) {
  const auto t = static_cast<std::time_t>(unix_seconds);
  std::tm tm{};
  gmtime_r(&t, &tm);
  std::ostringstream s;
  s << std::put_time(&tm, "%Y-%m-%d %H:%M:%S UTC");
  return s.str();
}

/// One job of `demcal status --jobs`: its state, how often it yielded, metrics (a flagged one
/// marked '!', its reason on a line of its own), cost, error, reuse, and its checkpoint with the
/// run's clock there.
void print_job_line(const v1::JobResult& j) {
  std::cout << "  job " << j.job_id() << " " << j.kind() << " run " << j.std_order() << " "
            << j.test() << " " << j.state() << " attempt " << j.attempt();
  if (j.yields() > 0)
    std::cout << " yielded " << j.yields() << (j.yields() == 1 ? " time" : " times");
  for (const auto& [k, v] : j.metrics())
    std::cout << " " << k << "=" << v << (j.flags().contains(k) ? "!" : "");
  if (j.has_cost() && j.cost().wall_seconds() > 0.0)
    std::cout << "  [" << j.cost().steps() << " steps, " << j.cost().wall_seconds() << " s]";
  if (!j.error().empty()) std::cout << "  (" << j.error() << ")";
  if (j.reused_from() != 0) std::cout << "  reused from job " << j.reused_from();
  if (!j.reused_journal().empty()) std::cout << "  reused from " << j.reused_journal();
  if (!j.checkpoint_stage().empty()) {
    std::cout << "  checkpoint '" << j.checkpoint_stage() << "' (kept "
              << utc_time(j.checkpoint_saved());
    if (j.checkpoint_steps() > 0) {
      std::ostringstream clock;
      clock << ", at " << std::setprecision(4) << j.checkpoint_simulated_seconds()
            << " s simulated, " << j.checkpoint_steps() << " steps";
      std::cout << clock.str();
    }
    std::cout << ")";
  }
  std::cout << "\n";
  for (const auto& [k, why] : j.flags()) std::cout << "    ! " << k << ": " << why << "\n";
}

/// `demcal status`: the campaign's row, its rounds and flagged results, and with `jobs` every job
/// (a flagged metric marked '!', its reason on the next line; a checkpoint with its clock).
void print_status(v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel,
                  std::int64_t id, bool jobs, const std::string& format) {
  v1::GetRequest req;
  req.set_id(id);
  v1::Campaign c;
  check(stub.Get(rpc::make_context(channel, 30).get(), req, &c), "status");
  v1::ResultsReply r;
  check(stub.GetResults(rpc::make_context(channel, 30).get(), req, &r), "results");
  if (format == "json") {
    nlohmann::json doc = nlohmann::json::parse(message_json(c));
    if (jobs) doc["jobs"] = nlohmann::json::parse(message_json(r))["jobs"];
    std::cout << doc.dump(2) << "\n";
    return;
  }
  print_campaign_row(c);
  if (c.has_fidelity_cost()) print_fidelity_cost(std::cout, c.fidelity_cost());
  print_rounds(std::cout, c.calibration_rounds());
  const auto flagged = std::count_if(r.jobs().begin(), r.jobs().end(),
                                     [](const v1::JobResult& j) { return j.flags_size() > 0; });
  if (flagged > 0)
    std::cout << "  " << flagged
              << " result(s) with flagged metrics: a phase did not reach its target (--jobs)\n";
  if (!jobs) return;
  for (const auto& j : r.jobs()) print_job_line(j);
}

}  // namespace

void add_campaign_commands(CLI::App& app) {
  struct Options {
    rpc::ChannelOptions channel;
    std::int64_t id = 0;
    std::string campaign;  ///< status: an id, or a spec YAML on the embedded default
    std::string workdir;   ///< status of a spec: its work directory
    bool jobs = false;
    std::string format = "table";
    std::int64_t job = 0;  ///< give-up: the job
    std::string reason;    ///< give-up: why
  };
  auto o = std::make_shared<Options>();

  auto* list = app.add_subcommand("list", "List the coordinator's campaigns");
  add_connection_options(*list, o->channel);
  list->callback([o] {
    v1::ListReply reply;
    check(campaign_stub(o->channel)
              ->List(rpc::make_context(o->channel, 30).get(), v1::ListRequest{}, &reply),
          "list");
    for (const auto& c : reply.campaigns()) print_campaign_row(c);
  });

  auto* status = app.add_subcommand("status", "A campaign's state and progress (--jobs: each job)");
  add_connection_options(*status, o->channel);
  add_campaign_options(*status, o->campaign, o->workdir);
  status->add_flag("--jobs", o->jobs, "list every job with its state, attempt and metrics");
  status
      ->add_option("--format", o->format,
                   "table or json (one document: the campaign, its calibration rounds, jobs)")
      ->check(CLI::IsMember({"table", "json"}));
  status->callback([o] {
    // A spec's store is read as it stands, from a copy when a coordinator holds it: a look at a
    // campaign running in another process (a worker's checkpoints and their clocks included).
    with_campaign(
        o->campaign, o->workdir, LocalWorkers{}, false, o->channel,
        [&](v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel, std::int64_t id) {
          print_status(stub, channel, id, o->jobs, o->format);
        },
        {}, Reach::kLook);
  });

  auto* watch = app.add_subcommand("watch", "Follow a campaign with a progress bar and ETA");
  add_connection_options(*watch, o->channel);
  watch->add_option("id", o->id, "campaign id")->required();
  watch->callback([o] {
    auto stub = campaign_stub(o->channel);
    watch_campaign(*stub, o->channel, o->id, std::cerr);
  });

  auto* cancel = app.add_subcommand("cancel", "Cancel a campaign's queued and running jobs");
  add_connection_options(*cancel, o->channel);
  cancel->add_option("id", o->id, "campaign id")->required();
  cancel->callback([o] {
    v1::CancelRequest req;
    req.set_id(o->id);
    v1::Campaign c;
    check(campaign_stub(o->channel)->Cancel(rpc::make_context(o->channel, 30).get(), req, &c),
          "cancel");
    print_campaign_row(c);
  });

  auto* give_up = app.add_subcommand(
      "give-up", "Give up one queued or running job: it fails, the campaign goes on without it");
  add_connection_options(*give_up, o->channel);
  add_campaign_options(*give_up, o->campaign, o->workdir);
  give_up->add_option("--job", o->job, "the job's id (demcal status --jobs)")
      ->required()
      ->check(CLI::PositiveNumber);
  give_up->add_option("--reason", o->reason, "why, kept as the job's error")->required();
  give_up->callback([o] {
    // A spec's store is changed in place, never in a copy: refused while a coordinator holds it.
    with_campaign(
        o->campaign, o->workdir, LocalWorkers{}, false, o->channel,
        [&](v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel, std::int64_t id) {
          v1::GiveUpRequest req;
          req.set_campaign_id(id);
          req.set_job_id(o->job);
          req.set_reason(o->reason);
          v1::GiveUpReply reply;
          check(stub.GiveUp(rpc::make_context(channel, 30).get(), req, &reply), "give-up");
          print_job_line(reply.job());
          for (const auto& j : reply.released())
            std::cout << "  job " << j.job_id() << " (" << j.test()
                      << ") waited for it and runs now, without what it would have left (a "
                         "tensile run conditions its own bed): give it up "
                         "too if that costs what this one did\n";
        },
        {}, Reach::kChange);
  });
}

}  // namespace demcal::cli
