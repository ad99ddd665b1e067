#pragma once
// Each `demcal` subcommand registers itself on the CLI11 app in its own cmd_*.cpp file.
#include <CLI/CLI.hpp>

namespace demcal::cli {

void add_contact_command(CLI::App& app);
void add_simulate_command(CLI::App& app);
void add_models_command(CLI::App& app);
void add_lab_command(CLI::App& app);
void add_lab_compare_command(CLI::App& lab);  // `lab compare`, under `lab`
void add_design_command(CLI::App& app);
void add_analyze_command(CLI::App& app);
void add_submit_command(CLI::App& app);
void add_campaign_commands(CLI::App& app);  // list, status, watch, cancel, give-up
void add_analysis_commands(CLI::App& app);  // effects, calibrate, export
void add_run_command(CLI::App& app);
void add_diagnose_command(CLI::App& app);
void add_report_command(CLI::App& app);

}  // namespace demcal::cli
