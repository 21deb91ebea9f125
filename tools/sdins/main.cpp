// sdins: the one user-facing command line of the project.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "commands.hpp"
#include "cfg/data_dir.hpp"
#include "tools/interrupt.hpp"
#include "numeric_options.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "sdins: SDINS/GPS integrated navigation for bank-to-turn aircraft.\n"
      "Flight-software core (200 Hz strapdown mechanization), truth simulator and analysis tools."};
  app.require_subcommand(1);
  app.fallthrough();  // --data-dir may follow the subcommand
  app.set_version_flag("--version", "sdins " SDINS_VERSION);
  // Set while parsing (before --help prints the footer that names the data directory).
  app.add_option_function<std::string>(
      "--data-dir", [](const std::string& dir) { cfg::set_data_dir_override(dir); },
                 "the product's data directory (almanac, scenarios, filter configurations, DBC, LCM definitions, "
                 "plot scripts; default: $SDINS_DATA_DIR, else ../share/sdins beside the executable)");
  app.footer([] {
    const cfg::DataDirLookup d = cfg::find_data_dir();
    return d.ok() ? "Data directory: " + d.path + " (" + cfg::to_string(d.source) + ")"
                  : "Data directory: " + d.error;
  });
  sdins::register_analyze(app);
  sdins::register_scenario(app);
  sdins::register_fly(app);
  sdins::register_montecarlo(app);
  sdins::register_paper(app);
  sdins::register_sil(app);
  sdins::register_replay(app);
  sdins::register_log(app);
  sdins::register_can(app);
  sdins::register_audit(app);
  sdins::register_bus_sim(app);
  sdins::register_fsw(app);
  sdins::register_diagnose(app);
  sdins::register_sim(app);
  sdins::register_import(app);
  sdins::register_noise(app);
  tools::require_finite_numbers(app);  // docs/faults.md: NaN / infinities refused by every option
  tools::install_interrupt_handlers();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    return sdins::run_selected(app);
  } catch (const tools::Interrupted& e) {
    std::fprintf(stderr, "sdins: interrupted: %s\n", e.what());
    return tools::interrupt_exit_code();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sdins: error: %s\n", e.what());
    return 1;
  }
}
