// `demcal run SPEC [--workdir DIR] [--workers N] [--threads N] [--no-verify]`: the embedded default
// (client/embedded.hpp). The campaign runs to the end over real gRPC; the effect tables and the
// proposed calibration (verified by simulation) are printed. Running it again with the same work
// directory resumes the campaign of the same name instead of starting over.
#include <iostream>
#include <memory>

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
};

void run_embedded(const RunOptions& opt) {
  const SpecFile file = read_campaign_spec(opt.spec);
  const auto workdir = work_directory(opt.spec, opt.workdir);
  EmbeddedService service(workdir, opt.local, opt.verbose);
  auto* stub = &service.stub();
  const auto& channel = service.channel();
  std::cout << "work directory: " << workdir.string() << " (SQLite: " << service.db() << ")\n";
  const std::int64_t id = service.submit_or_resume(file, std::cout);
  std::cout << std::flush;
  const v1::Progress p = watch_campaign(*stub, channel, id, std::cerr);
  std::cout << "\n" << progress_line(p) << "\n";

  v1::EffectsRequest ereq;
  ereq.set_id(id);
  v1::EffectsReply effects;
  check(stub->GetEffects(proto::make_context(channel, 300).get(), ereq, &effects), "effects");
  print_effects(std::cout, effects, opt.format);

  if (file.spec.measurements_size() == 0) {
    std::cout << "\nno measurements in the spec: nothing to calibrate against\n";
    return;
  }
  v1::CalibrateRequest creq;
  creq.set_id(id);
  creq.set_verify(opt.verify);
  v1::CalibrateReply cal;
  check(stub->Calibrate(proto::make_context(channel, 300).get(), creq, &cal), "calibrate");
  if (cal.verification_state() == "running") {
    std::cout << "\nverifying the proposed set by simulation (" << cal.verification_jobs_size()
              << " jobs)\n"
              << std::flush;
    watch_campaign(*stub, channel, id, std::cerr);
    cal.Clear();
    check(stub->Calibrate(proto::make_context(channel, 300).get(), creq, &cal), "calibrate");
  }
  std::cout << "\n";
  print_calibration(std::cout, cal, opt.format == "json" ? "json" : "table");
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
  cmd->add_option("--format", o->format, "table, csv or json (effects)")
      ->check(CLI::IsMember({"table", "csv", "json"}));
  cmd->callback([o] { run_embedded(*o); });
}

}  // namespace demcal::cli
