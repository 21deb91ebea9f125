// Subcommand registration for the sdins CLI. Each subcommand keeps its options in a static
// struct and runs through run_selected() after parsing.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "fsw/filter_model.hpp"
#include "hal/fsw_node.hpp"
#include "cfg/flight_config.hpp"
#include "sim/scenario.hpp"

namespace sdins {

void register_analyze(CLI::App& app);
void register_scenario(CLI::App& app);
void register_fly(CLI::App& app);
void register_montecarlo(CLI::App& app);
void register_paper(CLI::App& app);
void register_log(CLI::App& app);
void register_can(CLI::App& app);
void register_sil(CLI::App& app);
void register_replay(CLI::App& app);
void register_audit(CLI::App& app);
void register_bus_sim(CLI::App& app);
void register_fsw(CLI::App& app);
void register_diagnose(CLI::App& app);
void register_sim(CLI::App& app);
void register_import(CLI::App& app);
void register_noise(CLI::App& app);
int run_selected(CLI::App& app);

int run_analyze();
/// The section-II analyses of a scenario into out_dir (used by analyze and paper).
int run_analysis(const sim::Scenario& sc, const std::string& out_dir, double gamma_arcsec, bool plots);
int run_scenario_check();
int run_fly();
int run_sil();
int run_replay();
int run_montecarlo();
int run_paper();
int run_log();
int run_can();
int run_audit();
int run_bus_sim();
int run_fsw();
int run_diagnose();
int run_sim();
int run_import();
int run_noise();

/// The options every command that flies a scenario takes: --scenario FILE, --duration S, --seed N.
struct ScenarioOptions {
  std::string file;         ///< empty: the built-in bank-to-turn scenario
  double duration_s = -1.0;  ///< negative: keep the scenario's
  long long seed = -1;       ///< negative: keep the scenario's
  /// Loads the file (or the default) and applies the overrides. Throws std::runtime_error with
  /// the parser's message.
  sim::Scenario load() const;
};
void add_scenario_options(CLI::App* sub, ScenarioOptions& opt);

/// The filter models (fsw/filter_model.hpp) a command accepts: their names for CLI::IsMember, the
/// --help text that lists them with their meaning, and the parser (throws naming the option and
/// the accepted names). Every command's --model / --models / --baseline goes through these.
using ModelSet = std::vector<fsw::FilterModel>;
/// What the flight-software node flies (sil, replay, fsw) and the diagnosis' baselines.
inline const ModelSet kFlightModels{fsw::FilterModel::k15, fsw::FilterModel::k24};
/// What the Monte Carlo flies: every model.
inline const ModelSet kMonteCarloModels{fsw::FilterModel::k15, fsw::FilterModel::k24, fsw::FilterModel::k15c,
                                        fsw::FilterModel::k15t};
std::vector<std::string> model_names(const ModelSet& accepted);
std::string model_help(const ModelSet& accepted);
fsw::FilterModel parse_model(const std::string& name, const std::string& option, const ModelSet& accepted);

/// The options of every command that runs the flight software (sil, replay, fsw): --model,
/// --log, --lcm-url, --nav-decimation, --json, --flight-config.
struct FswRunOptions {
  std::string model = "24";
  std::string log;
  std::string lcm_url;  ///< "": $LCM_DEFAULT_URL or LCM's default group; "none": no network
  std::string json;
  int nav_decimation = 10;
  std::string flight_config;  ///< --flight-config FILE: applied on top of the shipped config/default.toml
  /// The flight configuration: the shipped config/default.toml with --flight-config applied and
  /// validated (cfg::flight_config); throws with the file's error.
  cfg::FlightConfig flight() const;
  /// The flight-software node's configuration (filter()); throws on a bad model or configuration.
  hal::FswNodeConfig node_config() const { return node_config(flight()); }
  /// The same with a filter configuration already read (one parse per run).
  hal::FswNodeConfig node_config(const cfg::FlightConfig& f) const;
};
/// --flight-config of montecarlo and paper (tools::monte_carlo_flight_config reads it).
void add_mc_flight_config_option(CLI::App* sub, std::string& path);
void add_fsw_run_options(CLI::App* sub, FswRunOptions& opt, const std::string& default_lcm_url);

/// s quoted for a POSIX shell.
std::string shell_quote(const std::string& s);
/// Runs a plotting script (<data dir>/plot/SCRIPT) with the Python that has matplotlib
/// (SDINS_PYTHON). Returns 0 on success, 1 when the script is missing or fails.
int run_plot_script(const std::string& script, const std::string& args);

}  // namespace sdins
