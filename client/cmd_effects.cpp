// `demcal effects ID [--format table|csv|json]`, `demcal calibrate ID [--verify [--wait]]`,
// `demcal export ID|SPEC [--format csv|json|journal|liggghts] [-o FILE]`: analysis on the
// coordinator, on demand. The journal format writes the finished jobs as a campaign journal
// (docs/journal.md), the liggghts format the calibrated material as a LIGGGHTS input fragment.
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <thread>

#include "client/commands.hpp"
#include "client/embedded.hpp"
#include "client/jsonl_file.hpp"
#include "client/liggghts_fragment.hpp"
#include "client/service_client.hpp"
#include "rpc/material_convert.hpp"

namespace demcal::cli {
namespace {

/// The spec's fixed parameters, then the calibrated set, as a LIGGGHTS fragment; what it
/// cannot export exactly is warned about on standard error.
std::string liggghts_export(v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel,
                            std::int64_t id) {
  v1::GetRequest get;
  get.set_id(id);
  v1::Campaign campaign;
  check(stub.Get(rpc::make_context(channel, 60).get(), get, &campaign), "campaign");
  v1::CalibrateRequest req;
  req.set_id(id);
  v1::CalibrateReply cal;
  check(stub.Calibrate(rpc::make_context(channel, 300).get(), req, &cal), "calibrate");
  std::map<std::string, double> proposed;
  for (int i = 0; i < cal.factor_paths_size(); ++i)
    proposed[cal.factor_paths(i)] = cal.proposed_values(i);
  const auto parameters = rpc::run_parameters(campaign.spec(), proposed);
  const std::string title =
      "demcal campaign " + std::to_string(id) + " '" + campaign.name() + "': the calibrated set (" +
      (cal.conclusion().empty() ? cal.verification_state() : cal.conclusion()) + ")";
  const LiggghtsFragment f = liggghts_fragment(campaign.spec().material(), parameters, title);
  for (const auto& w : f.warnings) std::cerr << "demcal: warning: " << w << "\n";
  return f.text;
}

struct ExportOptions {
  rpc::ChannelOptions channel;
  std::string campaign;  ///< a campaign id, or a spec on the embedded default
  std::string format = "json";
  std::string out;
  bool series = false;  ///< json: each finished job's curves too
  std::string workdir;  ///< of a spec: its work directory
  LocalWorkers local;
  bool verbose = false;
};

/// Writes the export of campaign `id` to the output file or standard output. Nothing is written
/// unless the whole document arrived; a journal to a file is written as JSON lines (gzip when
/// its name ends in .gz), as a kept journal is.
void write_export(v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel,
                  std::int64_t id, const ExportOptions& o) {
  std::string content;
  if (o.format == "liggghts")
    content = liggghts_export(stub, channel, id);
  else
    check(read_export(stub, channel, id, o.format, content, o.series), "export");
  if (o.out.empty()) {
    std::cout << content;
    return;
  }
  if (o.format == "journal") {
    JsonLinesFile(o.out).write(split_lines(content));
  } else {
    std::ofstream(o.out) << content;
  }
  std::cerr << "wrote " << o.out << "\n";
}

}  // namespace

void add_analysis_commands(CLI::App& app) {
  struct Options {
    rpc::ChannelOptions channel;
    std::int64_t id = 0;
    std::string format = "table";
    std::string model = "2fi";
    std::string calibrate_model;  ///< empty: the spec's calibration.model
    double alpha = 0.05;
    bool verify = false, wait = false;
  };
  auto o = std::make_shared<Options>();

  auto* effects =
      app.add_subcommand("effects", "Effects per metric with alias chains and Lenth significance");
  add_connection_options(*effects, o->channel);
  effects->add_option("id", o->id, "campaign id")->required();
  effects->add_option("--format", o->format, "table, csv or json")
      ->check(CLI::IsMember({"table", "csv", "json"}));
  effects->add_option("--model", o->model, "main, 2fi or quadratic")
      ->check(CLI::IsMember({"main", "2fi", "quadratic"}));
  effects->add_option("--alpha", o->alpha, "significance level");
  effects->callback([o] {
    v1::EffectsRequest req;
    req.set_id(o->id);
    req.set_model(o->model);
    req.set_alpha(o->alpha);
    v1::EffectsReply reply;
    check(campaign_stub(o->channel)
              ->GetEffects(rpc::make_context(o->channel, 120).get(), req, &reply),
          "effects");
    print_effects(std::cout, reply, o->format);
  });

  auto* calibrate = app.add_subcommand(
      "calibrate", "Propose a parameter set from the fitted models and the measurements");
  add_connection_options(*calibrate, o->channel);
  calibrate->add_option("id", o->id, "campaign id")->required();
  calibrate->add_flag("--verify", o->verify,
                      "advance the sequential calibration: queue the next round or stage");
  calibrate->add_flag("--wait", o->wait,
                      "with --verify: run the loop to its end (within tolerance or budget)");
  calibrate->add_option("--model", o->calibrate_model, "main or 2fi (default: the spec's)")
      ->check(CLI::IsMember({"main", "2fi"}));
  calibrate->add_option("--format", o->format, "table or json")
      ->check(CLI::IsMember({"table", "json"}));
  calibrate->callback([o] {
    auto stub = campaign_stub(o->channel);
    v1::CalibrateRequest req;
    req.set_id(o->id);
    req.set_verify(o->verify);
    req.set_model(o->calibrate_model);
    v1::CalibrateReply reply;
    if (o->verify && o->wait) {
      reply = drive_calibration(*stub, o->channel, req, std::cerr);
    } else {
      check(stub->Calibrate(rpc::make_context(o->channel, 300).get(), req, &reply), "calibrate");
    }
    print_calibration(std::cout, reply, o->format);
  });

  auto e = std::make_shared<ExportOptions>();
  auto* exp = app.add_subcommand(
      "export",
      "The campaign's design and results (csv or json), its finished jobs as a campaign journal "
      "(journal), or its calibrated material as a LIGGGHTS input fragment (liggghts)");
  add_connection_options(*exp, e->channel);
  exp->add_option("campaign", e->campaign, "campaign id, or a spec YAML (embedded default)")
      ->required();
  exp->add_option("--format", e->format, "csv, json, journal or liggghts")
      ->check(CLI::IsMember({"csv", "json", "journal", "liggghts"}));
  exp->add_option("-o,--output", e->out,
                  "file (default: standard output); a journal to FILE.gz is written as gzip");
  exp->add_flag("--series", e->series,
                "json: each finished job's curves (stress-strain, yield points, drum surface, "
                "mass-time; docs/lab-tests.md) under jobs[].series");
  exp->add_option("--workdir", e->workdir, "embedded: directory of the SQLite file");
  add_local_worker_options(*exp, e->local);
  exp->add_flag("-v,--verbose", e->verbose, "embedded: coordinator and worker logs");
  exp->callback([e] {
    with_campaign(e->campaign, e->workdir, e->local, e->verbose, e->channel,
                  [&](v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel,
                      std::int64_t id) { write_export(stub, channel, id, *e); });
  });
}

}  // namespace demcal::cli
