// `demcal report CAMPAIGN -o DIR`: one self-contained report.html (docs/report.md) of a
// campaign on a coordinator (an id) or of a spec on the embedded default (its design is run
// first when the work directory has no finished campaign of that name). The page carries its
// data and its charting libraries inline: it opens without network.
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include "client/commands.hpp"
#include "client/embedded.hpp"
#include "report/report_data.hpp"
#include "report/report_html.hpp"

namespace demcal::cli {
namespace {

struct ReportOptions {
  rpc::ChannelOptions channel;
  std::string campaign;
  std::string out_dir = ".";
  std::string workdir;
  LocalWorkers local;
  bool verbose = false;
  bool data = false;
};

std::filesystem::path write_report(v1::CampaignService::Stub& stub,
                                   const rpc::ChannelOptions& channel, std::int64_t id,
                                   const ReportOptions& o) {
  const nlohmann::json data = report::report_data(stub, channel, id);
  std::filesystem::create_directories(o.out_dir);
  const auto html = std::filesystem::path(o.out_dir) / "report.html";
  std::ofstream(html) << report::static_report_html(data);
  if (o.data) std::ofstream(std::filesystem::path(o.out_dir) / "report.json") << data.dump(1);
  return html;
}

void run(const ReportOptions& o) {
  with_campaign(
      o.campaign, o.workdir, o.local, o.verbose, o.channel,
      [&](v1::CampaignService::Stub& stub, const rpc::ChannelOptions& channel, std::int64_t id) {
        const auto html = write_report(stub, channel, id, o);
        std::cout << std::filesystem::absolute(html).string() << "\n";
      });
}

}  // namespace

void add_report_command(CLI::App& app) {
  auto o = std::make_shared<ReportOptions>();
  auto* cmd =
      app.add_subcommand("report",
                         "Write a self-contained report.html: design, effect plots, envelopes, "
                         "calibration, diagnosis");
  add_connection_options(*cmd, o->channel);
  add_campaign_options(*cmd, o->campaign, o->workdir);
  cmd->add_option("-o,--output", o->out_dir, "directory for report.html")->capture_default_str();
  cmd->add_flag("--data", o->data, "also write the report's data as report.json");
  add_local_worker_options(*cmd, o->local);
  cmd->add_flag("-v,--verbose", o->verbose, "embedded: coordinator and worker logs");
  cmd->callback([o] { run(*o); });
}

}  // namespace demcal::cli
