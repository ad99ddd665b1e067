// `demcal submit SPEC.yaml [--watch] [--journal FILE]`: validates the spec locally (YAML -> JSON ->
// proto, errors with file:line: field), submits it, and prints the campaign id and the design
// summary. With a journal (docs/journal.md) its runs are offered to the coordinator first, and the
// campaign is followed to its end, each finished job appended to the journal.
#include <iostream>
#include <memory>
#include <optional>

#include "client/campaign_journal.hpp"
#include "client/commands.hpp"
#include "client/service_client.hpp"
#include "client/spec_yaml.hpp"
#include "core/common/error.hpp"

namespace demcal::cli {

void add_submit_command(CLI::App& app) {
  struct Options {
    rpc::ChannelOptions channel;
    std::string spec;
    bool watch = false;
    std::string journal;
  };
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("submit", "Submit a campaign spec to a coordinator");
  add_connection_options(*cmd, o->channel);
  cmd->add_option("spec", o->spec, "campaign YAML")->required()->check(CLI::ExistingFile);
  cmd->add_flag("--watch", o->watch, "follow the campaign's progress");
  cmd->add_option("--journal", o->journal,
                  "campaign journal: its runs are taken instead of simulated; follows the "
                  "campaign, appending each job finished (docs/journal.md)");
  cmd->callback([o] {
    const SpecFile file = read_campaign_spec(o->spec);
    std::optional<CampaignJournal> journal;
    if (!o->journal.empty()) journal.emplace(o->journal);
    auto stub = campaign_stub(o->channel);
    if (journal) import_journal(*stub, o->channel, *journal, file.spec, std::cout);
    v1::SubmitRequest req;
    *req.mutable_spec() = file.spec;
    v1::SubmitReply reply;
    const auto s = stub->Submit(rpc::make_context(o->channel, 120).get(), req, &reply);
    if (s.error_code() == grpc::StatusCode::INVALID_ARGUMENT)
      throw InputError("", file.locate(s.error_message()));
    check(s, "submit");
    std::cout << "campaign " << reply.id() << " submitted\n";
    print_design_summary(std::cout, reply.design());
    std::optional<JournalKeeper> keeper;
    if (journal) keeper.emplace(*journal, *stub, o->channel, reply.id());
    if (o->watch || keeper) watch_campaign(*stub, o->channel, reply.id(), std::cerr);
  });
}

}  // namespace demcal::cli
