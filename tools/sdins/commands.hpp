// Subcommand registration for the sdins CLI. Each subcommand keeps its options in a static
// struct and runs through run_selected() after parsing.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "sim/scenario.hpp"

namespace sdins {

void register_analyze(CLI::App& app);
void register_scenario(CLI::App& app);
void register_fly(CLI::App& app);
int run_selected(CLI::App& app);

int run_analyze();
int run_scenario_check();
int run_fly();

/// Loads --scenario FILE (or the built-in default when empty) and applies --duration/--seed
/// overrides (negative: keep). Throws std::runtime_error with the parser's message.
sim::Scenario load_scenario(const std::string& path, double duration_s, long long seed);

/// Runs a plotting script with the Python that has matplotlib (SDINS_PYTHON). Returns its exit code.
int run_plot_script(const std::string& script, const std::string& args);

}  // namespace sdins
