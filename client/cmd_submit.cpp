// `demcal submit SPEC.yaml [--watch]`: validates the spec locally (YAML -> JSON -> proto, errors
// with file:line: field), submits it, and prints the campaign id and the design summary.
#include <iostream>
#include <memory>

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
  };
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("submit", "Submit a campaign spec to a coordinator");
  add_connection_options(*cmd, o->channel);
  cmd->add_option("spec", o->spec, "campaign YAML")->required()->check(CLI::ExistingFile);
  cmd->add_flag("--watch", o->watch, "follow the campaign's progress");
  cmd->callback([o] {
    const SpecFile file = read_campaign_spec(o->spec);
    auto stub = campaign_stub(o->channel);
    v1::SubmitRequest req;
    *req.mutable_spec() = file.spec;
    v1::SubmitReply reply;
    const auto s = stub->Submit(rpc::make_context(o->channel, 120).get(), req, &reply);
    if (s.error_code() == grpc::StatusCode::INVALID_ARGUMENT)
      throw InputError("", file.locate(s.error_message()));
    check(s, "submit");
    std::cout << "campaign " << reply.id() << " submitted\n";
    print_design_summary(std::cout, reply.design());
    if (o->watch) watch_campaign(*stub, o->channel, reply.id(), std::cerr);
  });
}

}  // namespace demcal::cli
