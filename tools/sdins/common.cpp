#include <cstdlib>
#include <limits>
#include <stdexcept>

#include "commands.hpp"

namespace sdins {

sim::Scenario ScenarioOptions::load() const {
  sim::Scenario sc;
  if (!file.empty()) {
    sim::ScenarioParseResult r = sim::parse_scenario_file(file);
    if (!r.ok()) throw std::runtime_error(r.error);
    sc = *r.scenario;
  }
  if (duration_s > 0.0) sc.duration_s = duration_s;
  if (seed >= 0) sc.seed = static_cast<std::uint64_t>(seed);
  return sc;
}

void add_scenario_options(CLI::App* sub, ScenarioOptions& opt) {
  sub->add_option("--scenario", opt.file, "scenario TOML file (default: built-in bank-to-turn)");
  sub->add_option("--duration", opt.duration_s, "override the scenario duration [s]")->check(CLI::Range(0.001, 86400.0));
  sub->add_option("--seed", opt.seed, "override the scenario seed")
      ->check(CLI::Range(0LL, std::numeric_limits<long long>::max()));
}

int run_plot_script(const std::string& script, const std::string& args) {
  const std::string cmd = std::string(SDINS_PYTHON) + " " + SDINS_PLOT_DIR + "/" + script + " " + args;
  const int rc = std::system(cmd.c_str());
  return rc == 0 ? 0 : 1;
}

int run_selected(CLI::App& app) {
  if (app.got_subcommand("analyze")) return run_analyze();
  if (app.got_subcommand("scenario")) return run_scenario_check();
  if (app.got_subcommand("fly")) return run_fly();
  if (app.got_subcommand("montecarlo")) return run_montecarlo();
  if (app.got_subcommand("paper")) return run_paper();
  if (app.got_subcommand("log")) return run_log();
  if (app.got_subcommand("can")) return run_can();
  if (app.got_subcommand("bus-sim")) return run_bus_sim();
  if (app.got_subcommand("fsw")) return run_fsw();
  return 1;
}

}  // namespace sdins
