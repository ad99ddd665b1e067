// `demcal models`: the contact-law slots, their models and every parameter with unit, valid range
// and default, printed from the same tables that parse and validate specs.
#include <iostream>

#include "client/commands.hpp"
#include "client/markdown.hpp"
#include "core/contact/contact_law.hpp"

namespace demcal::cli {
namespace {

void print_models() {
  for (const auto& slot : contact::slot_names()) {
    std::cout << "### Slot: " << slot << "\n\n";
    for (const auto& model : contact::model_names(slot)) {
      std::cout << "#### `" << model << "`\n\n";
      const auto params = contact::model_params(slot, model);
      if (params.empty()) {
        std::cout << "No parameters.\n\n";
        continue;
      }
      print_param_table(std::cout, params, "parameter");
      std::cout << "\n";
    }
  }
}

}  // namespace

void add_models_command(CLI::App& app) {
  auto* cmd =
      app.add_subcommand("models", "List the contact-law models and their parameters (Markdown)");
  cmd->callback(print_models);
}

}  // namespace demcal::cli
