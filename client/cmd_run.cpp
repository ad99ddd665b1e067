// `demcal run SPEC [--workdir DIR] [--threads N] [--no-verify]`: the embedded default. A
// coordinator (SQLite file in the work directory, loopback only, a random token) and a local
// worker run in this process; the campaign runs to the end over real gRPC; the effect tables
// and the proposed calibration (verified by simulation) are printed. Running it again with the
// same work directory resumes an unfinished campaign of the same name instead of starting over.
#include <spdlog/spdlog.h>

#include <filesystem>
#include <iostream>
#include <memory>
#include <random>
#include <thread>

#include "client/commands.hpp"
#include "client/service_client.hpp"
#include "client/spec_yaml.hpp"
#include "core/common/error.hpp"
#include "server/coordinator.hpp"
#include "worker/worker.hpp"

namespace demcal::cli {
namespace {

struct RunOptions {
  std::string spec;
  std::string workdir;
  int threads = 2;
  bool verify = true;
  bool verbose = false;
  std::string format = "table";
};

std::string random_token() {
  std::random_device rd;
  std::string t;
  for (int i = 0; i < 32; ++i) t += "0123456789abcdef"[rd() % 16];
  return t;
}

void run_embedded(const RunOptions& opt) {
  const SpecFile file = read_campaign_spec(opt.spec);
  const std::filesystem::path workdir =
      opt.workdir.empty()
          ? std::filesystem::path("demcal-work") / std::filesystem::path(opt.spec).stem()
          : std::filesystem::path(opt.workdir);
  std::filesystem::create_directories(workdir);
  spdlog::set_level(opt.verbose ? spdlog::level::info : spdlog::level::warn);

  server::CoordinatorOptions co;
  co.listen = "127.0.0.1:0";
  co.db = (workdir / "campaign.db").string();
  co.token = random_token();
  server::Coordinator coordinator(co);

  proto::ChannelOptions channel;
  channel.address = "127.0.0.1:" + std::to_string(coordinator.port());
  channel.token = co.token;
  worker::WorkerOptions wo;
  wo.channel = channel;
  wo.threads = opt.threads;
  wo.id = "embedded";
  worker::StopFlags flags;
  std::thread worker_thread([&] { worker::run_worker(wo, flags); });
  struct Joiner {
    worker::StopFlags& f;
    std::thread& t;
    server::Coordinator& c;
    ~Joiner() {
      f.stop = true;
      if (t.joinable()) t.join();
      c.shutdown();
    }
  } joiner{flags, worker_thread, coordinator};

  auto stub = campaign_stub(channel);
  std::int64_t id = 0;
  {
    v1::ListReply list;
    check(stub->List(proto::make_context(channel, 30).get(), {}, &list), "list");
    for (const auto& c : list.campaigns())
      if (c.name() == file.spec.name() && c.state() == v1::RUNNING) id = c.id();
  }
  std::cout << "work directory: " << workdir.string() << " (SQLite: " << co.db << ")\n";
  if (id) {
    std::cout << "resuming campaign " << id << " '" << file.spec.name() << "'\n";
  } else {
    v1::SubmitRequest req;
    *req.mutable_spec() = file.spec;
    v1::SubmitReply reply;
    const auto s = stub->Submit(proto::make_context(channel, 120).get(), req, &reply);
    if (s.error_code() == grpc::StatusCode::INVALID_ARGUMENT)
      throw InputError("", file.locate(s.error_message()));
    check(s, "submit");
    id = reply.id();
    std::cout << "campaign " << id << " '" << file.spec.name() << "'\n";
    print_design_summary(std::cout, reply.design());
  }
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
  cmd->add_option("--threads", o->threads, "simulation threads of the local worker")
      ->capture_default_str();
  cmd->add_flag("!--no-verify", o->verify, "do not simulate the proposed set");
  cmd->add_flag("-v,--verbose", o->verbose, "coordinator and worker logs");
  cmd->add_option("--format", o->format, "table, csv or json (effects)")
      ->check(CLI::IsMember({"table", "csv", "json"}));
  cmd->callback([o] { run_embedded(*o); });
}

}  // namespace demcal::cli
