// `demcal effects ID [--format table|csv|json]`, `demcal calibrate ID [--verify [--wait]]`,
// `demcal export ID [--format csv|json] [-o FILE]`: analysis on the coordinator, on demand.
#include <fstream>
#include <iostream>
#include <memory>
#include <thread>

#include "client/commands.hpp"
#include "client/service_client.hpp"

namespace demcal::cli {

void add_analysis_commands(CLI::App& app) {
  struct Options {
    proto::ChannelOptions channel;
    std::int64_t id = 0;
    std::string format = "table";
    std::string model = "2fi";
    std::string calibrate_model;  ///< empty: the spec's calibration.model
    double alpha = 0.05;
    bool verify = false, wait = false;
    std::string out;
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
              ->GetEffects(proto::make_context(o->channel, 120).get(), req, &reply),
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
      check(stub->Calibrate(proto::make_context(o->channel, 300).get(), req, &reply), "calibrate");
    }
    print_calibration(std::cout, reply, o->format);
  });

  auto* exp = app.add_subcommand("export", "The campaign's design and results (csv or json)");
  add_connection_options(*exp, o->channel);
  exp->add_option("id", o->id, "campaign id")->required();
  exp->add_option("--format", o->format, "csv or json")->check(CLI::IsMember({"csv", "json"}));
  exp->add_option("-o,--output", o->out, "file (default: standard output)");
  exp->callback([o] {
    v1::ExportRequest req;
    req.set_id(o->id);
    req.set_format(o->format == "table" ? "json" : o->format);
    // The document arrives in pieces (it may exceed a gRPC message); nothing is written unless
    // all of it arrived.
    const auto context = proto::make_context(o->channel, 600);
    auto reader = campaign_stub(o->channel)->Export(context.get(), req);
    std::string content;
    v1::ExportReply piece;
    while (reader->Read(&piece)) content += piece.content();
    check(reader->Finish(), "export");
    if (o->out.empty()) {
      std::cout << content;
    } else {
      std::ofstream(o->out) << content;
      std::cerr << "wrote " << o->out << "\n";
    }
  });
}

}  // namespace demcal::cli
