// `demcal run SPEC [--workdir DIR] [--workers N] [--threads N] [--no-verify] [--journal FILE]`: the
// embedded default (client/embedded.hpp). The campaign runs to the end over real gRPC; the effect
// tables and the sequential calibration (verified by simulation round by round, docs/doe.md) are
// printed. Running it again with the same work directory resumes the campaign of the same name
// instead of starting over; with a journal (docs/journal.md) it goes on in any work directory
// from the runs the journal holds.
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "client/commands.hpp"
#include "client/embedded.hpp"

namespace demcal::cli {
namespace {

struct RunOptions {
  std::string spec;
  std::string workdir;
  LocalWorkers local;
  bool verify = true;
  bool verbose = false;
  std::string format = "table";
  std::string http;     ///< HOST:PORT of the live report page; empty: none
  std::string journal;  ///< the campaign journal taken from and kept; empty: none
};

/// With `--format json` the one JSON document is all that goes to standard output: the
/// design summary, progress and notes go to standard error.
void run_embedded(const RunOptions& opt) {
  const bool json = opt.format == "json";
  std::ostream& text = json ? std::cerr : std::cout;
  const SpecFile file = read_campaign_spec(opt.spec);
  // Read before anything starts: a journal with a bad line refuses the run.
  std::optional<CampaignJournal> journal;
  if (!opt.journal.empty()) journal.emplace(opt.journal);
  const auto workdir = work_directory(opt.spec, opt.workdir);
  EmbeddedService service(workdir, opt.local, opt.verbose);
  auto* stub = &service.stub();
  const auto& channel = service.channel();
  text << "work directory: " << workdir.string() << " (SQLite: " << service.db() << ")\n";
  const std::int64_t id = service.submit_or_resume(file, text, journal ? &*journal : nullptr);
  if (!opt.http.empty())
    std::cerr << "live report page: " << service.serve_http(opt.http, id) << std::endl;
  text << std::flush;
  const v1::Progress p = watch_campaign(*stub, channel, id, std::cerr);
  text << "\n" << progress_line(p) << "\n";

  v1::EffectsRequest ereq;
  ereq.set_id(id);
  v1::EffectsReply effects;
  check(stub->GetEffects(rpc::make_context(channel, 300).get(), ereq, &effects), "effects");
  v1::GetRequest dreq;
  dreq.set_id(id);
  v1::DesignReply design;
  check(stub->GetDesign(rpc::make_context(channel, 60).get(), dreq, &design), "design");
  nlohmann::json doc = {{"campaign", id},
                        {"work_directory", workdir.string()},
                        {"design", nlohmann::json::parse(message_json(design.summary()))},
                        {"effects", nlohmann::json::parse(message_json(effects))},
                        {"calibration", nullptr}};
  if (!json) print_effects(std::cout, effects, opt.format);

  if (file.spec.measurements_size() == 0) {
    text << "\nno measurements in the spec: nothing to calibrate against\n";
  } else {
    v1::CalibrateRequest creq;
    creq.set_id(id);
    creq.set_verify(opt.verify);
    const v1::CalibrateReply cal = drive_calibration(*stub, channel, creq, std::cerr);
    doc["calibration"] = nlohmann::json::parse(message_json(cal));
    if (!json) {
      std::cout << "\n";
      print_calibration(std::cout, cal, "table");
    }
  }
  if (json) std::cout << doc.dump(2) << "\n";
}

}  // namespace

void add_run_command(CLI::App& app) {
  auto o = std::make_shared<RunOptions>();
  auto* cmd = app.add_subcommand(
      "run", "Run a campaign here: embedded coordinator + local worker, to the end");
  cmd->add_option("spec", o->spec, "campaign YAML")->required()->check(CLI::ExistingFile);
  cmd->add_option("--workdir", o->workdir,
                  "directory of the SQLite file (default demcal-work/<spec>)");
  add_local_worker_options(*cmd, o->local);
  cmd->add_flag("!--no-verify", o->verify, "do not simulate the proposed set");
  cmd->add_flag("-v,--verbose", o->verbose, "coordinator and worker logs");
  cmd->add_option("--journal", o->journal,
                  "campaign journal (JSON lines, .gz read and written as gzip): its runs are taken "
                  "instead of simulated, each job finished is appended (docs/journal.md)");
  cmd->add_option("--http", o->http,
                  "HOST:PORT: serve the live report page while the campaign runs (docs/report.md)");
  cmd->add_option("--format", o->format,
                  "table, csv (effects) or json (one document: design, effects, calibration)")
      ->check(CLI::IsMember({"table", "csv", "json"}));
  cmd->callback([o] { run_embedded(*o); });
}

}  // namespace demcal::cli
