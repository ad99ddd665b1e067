// demcal: the command-line entry point. main only wires the subcommands; each lives in cmd_*.cpp.
#include <iostream>

#include "client/commands.hpp"
#include "core/common/error.hpp"
#include "core/sim/threads.hpp"

int main(int argc, char** argv) {
  demcal::sim::wait_passively(argv);
  CLI::App app{"demcal - calibrate DEM contact models against measured bulk tests"};
  app.require_subcommand(1);
  demcal::cli::add_contact_command(app);
  demcal::cli::add_simulate_command(app);
  demcal::cli::add_models_command(app);
  demcal::cli::add_lab_command(app);
  demcal::cli::add_design_command(app);
  demcal::cli::add_analyze_command(app);
  demcal::cli::add_submit_command(app);
  demcal::cli::add_campaign_commands(app);
  demcal::cli::add_analysis_commands(app);
  demcal::cli::add_run_command(app);
  demcal::cli::add_diagnose_command(app);
  demcal::cli::add_report_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const demcal::InputError& e) {
    std::cerr << "demcal: invalid input: " << e.what() << "\n";
    return 2;
  } catch (const demcal::SimulationFailure& e) {
    std::cerr << "demcal: simulation failed (" << demcal::to_string(e.reason()) << "): " << e.what()
              << "\n";
    return 3;
  } catch (const std::exception& e) {
    std::cerr << "demcal: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
