// `demcal diagnose CAMPAIGN`: what the calibrated model gets wrong and why (docs/diagnosis.md).
// CAMPAIGN is a campaign id on a coordinator, or a spec YAML run on the embedded default (its
// design is run first if the work directory has no campaign of that name). The diagnosis
// advances as its simulations finish; this command drives it to the end and prints the report
// as tables, or as JSON with --format json. With --no-wait it reports the state as it stands and
// queues the next runs, and on the embedded default runs none.
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "client/commands.hpp"
#include "client/embedded.hpp"
#include "core/diagnose/diagnosis.hpp"

namespace demcal::cli {
namespace {

struct DiagnoseOptions {
  rpc::ChannelOptions channel;
  std::string campaign;
  std::string workdir;
  LocalWorkers local;
  bool verbose = false, wait = true;
  std::string format = "table";
  std::uint64_t seed = 1;
  std::string journal;  ///< embedded: the campaign journal taken from and kept; empty: none
  int rounds = 0;       ///< --rounds: the campaign's diagnose.rounds from now on; 0: as stored
};

/// The verification rounds a candidate to ask for: `--rounds` with a campaign id; with a spec
/// file its `diagnose.rounds` (the default where it has none), so that a spec whose rounds were
/// changed goes on from the runs its campaign has.
int rounds_to_ask(const DiagnoseOptions& o) {
  if (!std::filesystem::is_regular_file(o.campaign)) return o.rounds;
  if (o.rounds != 0)
    throw CLI::ValidationError("--rounds",
                               "only with a campaign id: a spec file's are its diagnose.rounds");
  const int rounds = read_campaign_spec(o.campaign).spec.diagnose().rounds();
  return rounds != 0 ? rounds : diagnose::Options{}.rounds;
}

/// A relative error as a percentage; "-" while it waits for a simulation.
std::string pct(bool known, double v) {
  if (!known) return "-";
  std::ostringstream s;
  s << std::fixed << std::setprecision(1) << 100.0 * v << " %";
  return s.str();
}

std::string num(bool known, double v) {
  if (!known) return "-";
  std::ostringstream s;
  s << std::setprecision(4) << v;
  return s.str();
}

void print_metrics(std::ostream& out, const v1::DiagnosisReport& r) {
  out << "\nmeasured metrics against the factor box and the best calibration "
         "(seed 000 Tables 10-15)\n";
  out << std::left << std::setw(38) << "metric" << std::right << std::setw(11) << "target"
      << std::setw(11) << "env min" << std::setw(11) << "env max" << std::setw(11) << "predicted"
      << std::setw(11) << "simulated" << std::setw(10) << "error" << std::setw(10) << "curv. p"
      << "\n";
  for (const auto& m : r.metrics()) {
    const std::string name = m.response() + (m.holdout() ? " (held out)" : "");
    out << std::left << std::setw(38) << name << std::right << std::setw(11)
        << num(true, m.target()) << std::setw(11) << num(true, m.envelope_min()) << std::setw(11)
        << num(true, m.envelope_max()) << std::setw(11) << num(true, m.predicted()) << std::setw(11)
        << num(m.has_simulated(), m.simulated()) << std::setw(10)
        << pct(m.has_relative_error(), m.relative_error()) << std::setw(10)
        << num(m.has_curvature_p(), m.curvature_p()) << "\n";
    if (!m.reachable()) out << "    " << m.statement() << "\n";
    for (const auto& note : m.notes()) out << "    " << note << "\n";
  }
  const auto& b = r.baseline();
  out << "baseline RMS error: predicted " << pct(b.has_predicted_rms(), b.predicted_rms())
      << ", verified " << pct(b.has_verified_rms(), b.verified_rms())
      << (b.has_verified_rms_se() ? " +- " + pct(true, b.verified_rms_se()) : "") << ", held out "
      << pct(b.has_holdout_rms(), b.holdout_rms())
      << (b.has_holdout_rms_se() ? " +- " + pct(true, b.holdout_rms_se()) : "") << "\n";
}

void print_candidates(std::ostream& out, const v1::DiagnosisReport& r) {
  out << "\ncandidate causes, each tested by simulation (best first)\n";
  out << std::left << std::setw(14) << "candidate" << std::right << std::setw(6) << "runs"
      << std::setw(13) << "mispredicted" << std::setw(11) << "predicted" << std::setw(10)
      << "verified" << std::setw(8) << "round" << std::setw(10) << "held out" << std::setw(8)
      << "gain" << std::setw(10) << "explains"
      << "\n";
  for (const auto& c : r.candidates()) {
    out << std::left << std::setw(14) << c.id() << std::right << std::setw(6) << c.runs()
        << std::setw(13) << pct(c.has_design_misprediction(), c.design_misprediction())
        << std::setw(11) << pct(c.has_predicted_rms(), c.predicted_rms()) << std::setw(10)
        << pct(c.has_verified_rms(), c.verified_rms()) << std::setw(8)
        << (std::to_string(c.best_round()) + "/" + std::to_string(c.rounds())) << std::setw(10)
        << pct(c.has_holdout_rms(), c.holdout_rms()) << std::setw(8)
        << pct(c.has_holdout_gain(), c.holdout_gain()) << std::setw(10) << c.explains_label()
        << "\n";
    out << "    " << c.cause() << " [" << c.state() << "]";
    if (!c.evidence().empty()) out << ": " << c.evidence();
    out << "\n";
  }
}

void print_report(std::ostream& out, const v1::DiagnosisReport& r) {
  print_metrics(out, r);
  out << "\nmetrics that pull against each other\n";
  if (r.conflicts().empty()) out << "  none (each metric's own best fit keeps the others near)\n";
  for (const auto& c : r.conflicts()) out << "  " << c.statement() << "\n";
  print_candidates(out, r);
  out << "\n" << r.conclusion() << "\n";
}

/// Calls Diagnose until it is done, running the campaign's jobs in between (or once, without
/// waiting). Returns the last reply.
v1::DiagnoseReply drive(v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel,
                        std::int64_t id, const DiagnoseOptions& o) {
  v1::DiagnoseRequest req;
  req.set_id(id);
  req.set_seed(o.seed);
  req.set_rounds(rounds_to_ask(o));
  for (;;) {
    v1::DiagnoseReply reply;
    check(stub.Diagnose(rpc::make_context(channel, 600).get(), req, &reply), "diagnose");
    if (reply.state() == "done" || !o.wait) return reply;
    std::cerr << "diagnosis: " << reply.conclusion();
    if (reply.jobs_queued()) std::cerr << " (" << reply.jobs_queued() << " jobs queued)";
    std::cerr << "\n";
    watch_campaign(stub, channel, id, std::cerr);
  }
}

void report(const v1::DiagnoseReply& reply, const std::string& format) {
  if (format == "json") {
    std::cout << (reply.has_report()
                      ? message_json(reply.report())
                      : nlohmann::json{{"state", reply.state()}, {"conclusion", reply.conclusion()}}
                            .dump(2))
              << "\n";
    return;
  }
  if (!reply.has_report()) {
    std::cout << reply.state() << ": " << reply.conclusion() << "\n";
    return;
  }
  print_report(std::cout, reply.report());
}

void run(const DiagnoseOptions& o) {
  with_campaign(
      o.campaign, o.workdir, o.local, o.verbose, o.channel,
      [&](v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel, std::int64_t id) {
        report(drive(stub, channel, id, o), o.format);
      },
      o.journal, o.wait ? Reach::kRun : Reach::kLookAtCopy);
}

}  // namespace

void add_diagnose_command(CLI::App& app) {
  auto o = std::make_shared<DiagnoseOptions>();
  auto* cmd =
      app.add_subcommand("diagnose",
                         "What the calibrated model gets wrong, the candidate causes tested by "
                         "simulation, the named cause and the gain");
  add_connection_options(*cmd, o->channel);
  add_campaign_options(*cmd, o->campaign, o->workdir);
  add_local_worker_options(*cmd, o->local);
  cmd->add_flag("!--no-wait", o->wait, "report the current state and queue the next runs only");
  cmd->add_option("--seed", o->seed, "calibration multi-start seed")->capture_default_str();
  cmd->add_option("--rounds", o->rounds,
                  "campaign id: verification rounds a candidate from now on (the runs done are "
                  "kept)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--format", o->format, "table or json")->check(CLI::IsMember({"table", "json"}));
  cmd->add_flag("-v,--verbose", o->verbose, "embedded: coordinator and worker logs");
  cmd->add_option("--journal", o->journal,
                  "embedded: campaign journal whose runs are taken instead of simulated, each job "
                  "finished appended (docs/journal.md)");
  cmd->callback([o] { run(*o); });
}

}  // namespace demcal::cli
