#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>

#include "commands.hpp"
#include "cfg/data_dir.hpp"
#include "cfg/flight_config.hpp"
#include "hal/output_file.hpp"

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
  sub->add_option("--duration", opt.duration_s, "override the scenario duration [s] (default: the scenario's)")->check(CLI::Range(0.001, 86400.0));
  sub->add_option("--seed", opt.seed, "override the scenario seed (default: the scenario's)")
      ->check(CLI::Range(0LL, std::numeric_limits<long long>::max()));
}

std::vector<std::string> model_names(const ModelSet& accepted) {
  std::vector<std::string> names;
  for (fsw::FilterModel m : accepted) names.emplace_back(fsw::to_string(m));
  return names;
}

std::string model_help(const ModelSet& accepted) {
  std::string h;
  for (std::size_t i = 0; i < accepted.size(); ++i) {
    const fsw::FilterModelInfo& m = fsw::filter_model_info(accepted[i]);
    h += (i == 0 ? "" : ", ") + std::string(m.name) + " (" + m.description + ")";
  }
  return h;
}

fsw::FilterModel parse_model(const std::string& name, const std::string& option, const ModelSet& accepted) {
  fsw::FilterModel m{};
  if (fsw::parse_filter_model(name.c_str(), m) && std::find(accepted.begin(), accepted.end(), m) != accepted.end())
    return m;
  std::string names;
  for (const std::string& n : model_names(accepted)) names += (names.empty() ? "" : ", ") + n;
  throw std::runtime_error(option + ": unknown model '" + name + "' (use " + names + ")");
}

cfg::FlightConfig FswRunOptions::flight() const { return cfg::flight_config(flight_config); }

hal::FswNodeConfig FswRunOptions::node_config(const cfg::FlightConfig& f) const {
  hal::FswNodeConfig cfg;
  cfg.model = parse_model(model, "--model", kFlightModels);
  cfg.app = f.app;
  cfg.telemetry.lcm_url = lcm_url;
  cfg.telemetry.log_path = log;
  cfg.nav_decimation = nav_decimation;
  return cfg;
}

void add_fsw_run_options(CLI::App* sub, FswRunOptions& opt, const std::string& default_lcm_url) {
  opt.lcm_url = default_lcm_url;
  sub->add_option("--model", opt.model, "filter model: " + model_help(kFlightModels))
      ->check(CLI::IsMember(model_names(kFlightModels)))
      ->capture_default_str();
  sub->add_option("--log", opt.log, "write an LCM log of the run (inputs and outputs)");
  sub->add_option("--lcm-url", opt.lcm_url,
                  "LCM URL for live telemetry (empty: $LCM_DEFAULT_URL or udpm://239.255.76.67:7667?ttl=0; "
                  "'none': no network)")
      ->capture_default_str();
  sub->add_option("--nav-decimation", opt.nav_decimation, "NAV_SOLUTION every n-th 200 Hz frame [frames]")
      ->check(CLI::Range(1, 200))
      ->capture_default_str();
  sub->add_option("--json", opt.json, "write the end-of-run summary as JSON");
  sub->add_option("--flight-config,--filter-config", opt.flight_config,
                  "flight configuration TOML (config/README.md; e.g. config/datasets/gnss-imu-drive.toml) applied on "
                  "top of the shipped flight configuration <data dir>/config/default.toml (default: none, the "
                  "shipped file alone)");
}

void add_mc_flight_config_option(CLI::App* sub, std::string& path) {
  sub->add_option("--flight-config,--filter-config", path,
                  "flight configuration TOML (config/README.md) applied on top of the shipped flight configuration "
                  "<data dir>/config/default.toml, under the scenario overlay the Monte Carlo applies (config/README.md; "
                  "gnss.source must be \"raw\"; default: none, the shipped file alone)");
}

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

int run_plot_script(const std::string& script, const std::string& args) {
  const std::string path = cfg::data_file("plot/" + script);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    std::fprintf(stderr, "sdins: plot script %s not found\n", path.c_str());
    return 1;
  }
  // The script names each figure it puts in place in a note file; they become outputs of this run
  // (hal::note_output: tools::RunDirectory's summary names them, docs/faults.md).
  char note[] = "/tmp/sdins-plot-outputs.XXXXXX";
  const int nfd = ::mkstemp(note);
  if (nfd >= 0) ::close(nfd);
  const std::string env = nfd >= 0 ? "SDINS_OUTPUTS_NOTE=" + shell_quote(note) + " " : std::string();
  const std::string cmd = env + std::string(SDINS_PYTHON) + " " + shell_quote(path) + " " + args;
  const int rc = std::system(cmd.c_str());
  if (nfd >= 0) {
    std::ifstream in(note);
    for (std::string line; std::getline(in, line);)
      if (!line.empty()) hal::note_output(line);
    ::unlink(note);
  }
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
  if (app.got_subcommand("sil")) return run_sil();
  if (app.got_subcommand("replay")) return run_replay();
  if (app.got_subcommand("audit")) return run_audit();
  if (app.got_subcommand("bus-sim")) return run_bus_sim();
  if (app.got_subcommand("fsw")) return run_fsw();
  if (app.got_subcommand("diagnose")) return run_diagnose();
  if (app.got_subcommand("sim")) return run_sim();
  if (app.got_subcommand("import")) return run_import();
  if (app.got_subcommand("noise")) return run_noise();
  return 1;
}

}  // namespace sdins
