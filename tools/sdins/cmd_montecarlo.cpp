// sdins montecarlo: N seeded runs of a scenario through the fsw executive with the 15- and/or
// 24-state filter; per-epoch statistics across runs (CSV), consistency (NEES) and a JSON summary.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "commands.hpp"
#include "montecarlo_case.hpp"
#include "tools/interrupt.hpp"
#include "tools/output_file.hpp"

namespace sdins {
namespace {

struct MontecarloOptions {
  ScenarioOptions scenario;
  int runs = 100;
  std::string models = "15,24";
  int threads = 0;
  std::string out = "out/montecarlo";
  std::string flight_config;
} montecarlo_opt;

}  // namespace

std::vector<fsw::FilterModel> parse_models(const std::string& text) {
  std::vector<fsw::FilterModel> models;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const fsw::FilterModel m = parse_model(item, "--models", kMonteCarloModels);
    if (std::find(models.begin(), models.end(), m) != models.end())  // it would be flown and written twice
      throw std::runtime_error("--models: model '" + item + "' is given twice in '" + text + "'");
    models.push_back(m);
  }
  if (models.empty()) throw std::runtime_error("--models: no model given");
  return models;
}

void register_montecarlo(CLI::App& app) {
  CLI::App* sub = app.add_subcommand(
      "montecarlo",
      "Monte Carlo of the tightly coupled GPS/INS filters: N seeded runs (seed = scenario seed + run index) of the "
      "scenario through the fsw executive, on all cores; writes per-epoch statistics across runs (residual attitude "
      "error mean and 1-sigma, filter sigma, position/velocity RMS, NEES) and summary.json. In a build with MPI, "
      "under mpirun -np K the runs are split across the K ranks and rank 0 writes the (identical) results.");
  add_scenario_options(sub, montecarlo_opt.scenario);
  sub->add_option("--runs", montecarlo_opt.runs, "number of runs")->check(CLI::Range(1, 100000))->capture_default_str();
  sub->add_option("--models", montecarlo_opt.models,
                  "filters to run on the same data, a comma-separated list of: " + model_help(kMonteCarloModels))
      ->capture_default_str();
  sub->add_option("--threads", montecarlo_opt.threads,
                  "worker threads per process (0: all cores; under mpirun with more than one rank: 1 per rank)")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  sub->add_option("--out", montecarlo_opt.out, "output directory")->capture_default_str();
  add_mc_flight_config_option(sub, montecarlo_opt.flight_config);
}

int run_montecarlo() {
  // Under MPI every rank runs this; an error on any of them aborts the whole job.
  return run_guarded([] {
    const sim::Scenario sc = montecarlo_opt.scenario.load();
    tools::MonteCarloConfig mc;
    mc.runs = montecarlo_opt.runs;
    mc.models = parse_models(montecarlo_opt.models);
    mc.threads = montecarlo_opt.threads;
    mc.flight = tools::monte_carlo_flight_config(montecarlo_opt.flight_config);
    tools::validate_overlay(sc, mc);  // before any output: the overlaid configuration meets the rules
    // docs/faults.md: summary.json marks a complete run; removed now, written last.
    tools::require_distinct({montecarlo_opt.out}, {montecarlo_opt.scenario.file, montecarlo_opt.flight_config});
    std::optional<tools::RunDirectory> dir;
    if (mpi_world().rank == 0) dir.emplace(montecarlo_opt.out);
    const tools::InterruptPolling polling;
    const CaseResult r = run_case(sc, mc, montecarlo_opt.out, "");
    if (!r.written) return 0;  // a non-root MPI rank: rank 0 writes everything
    nlohmann::json j;
    j["scenario"] = sc.name;
    j["duration_s"] = sc.duration_s;
    j["runs"] = mc.runs;
    j["filter_config"] = montecarlo_opt.flight_config.empty() ? std::string("shipped") : montecarlo_opt.flight_config;
    j["models"] = r.models;
    j["timing"] = r.timing;
    // docs/faults.md: a run in which no pseudorange was used (e.g. every satellite unhealthy) has a
    // NEES that says nothing about the aided filter: said so, and the exit code is 2.
    bool gnss_used = true;
    for (const auto& m : r.models) gnss_used = gnss_used && m["health"]["pr_used"].get<double>() > 0.0;
    j["gnss_used"] = gnss_used;
    dir->finish(j);
    print_case(r);
    std::printf("outputs in %s\n", montecarlo_opt.out.c_str());
    if (!gnss_used) {
      std::fprintf(stderr, "sdins montecarlo: no pseudorange was used by a filter in any run (no healthy satellite "
                           "in view?): the statistics describe unaided inertial navigation\n");
      return 2;
    }
    return 0;
  });
}

}  // namespace sdins
