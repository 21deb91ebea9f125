// sdins montecarlo: N seeded runs of a scenario through the fsw executive with the 15- and/or
// 24-state filter; per-epoch statistics across runs (CSV), consistency (NEES) and a JSON summary.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "commands.hpp"
#include "montecarlo_case.hpp"

namespace sdins {
namespace {

struct Options {
  ScenarioOptions scenario;
  int runs = 100;
  std::string models = "15,24";
  int threads = 0;
  std::string out = "out/montecarlo";
} opt;

}  // namespace

std::vector<tools::Model> parse_models(const std::string& text) {
  std::vector<tools::Model> models;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (item == "15")
      models.push_back(tools::Model::k15);
    else if (item == "24")
      models.push_back(tools::Model::k24);
    else if (item == "15c")
      models.push_back(tools::Model::k15c);
    else if (item == "15t")
      models.push_back(tools::Model::k15t);
    else
      throw std::runtime_error("--models: unknown model '" + item + "' (use 15, 15c, 15t, 24 or a list such as 15,24)");
  }
  if (models.empty()) throw std::runtime_error("--models: no model given");
  return models;
}

void register_montecarlo(CLI::App& app) {
  CLI::App* sub = app.add_subcommand(
      "montecarlo",
      "Monte Carlo of the tightly coupled GPS/INS filters: N seeded runs (seed = scenario seed + run index) of the "
      "scenario through the fsw executive, on all cores; writes per-epoch statistics across runs (residual attitude "
      "error mean and 1-sigma, filter sigma, position/velocity RMS, NEES) and summary.json."
#if SDINS_WITH_MPI
      " Under mpirun -np K the runs are split across the K ranks and rank 0 writes the (identical) results."
#endif
      );
  add_scenario_options(sub, opt.scenario);
  sub->add_option("--runs", opt.runs, "number of runs")->check(CLI::Range(1, 100000));
  sub->add_option("--models", opt.models, "filters to run on the same data: 15, 24 or 15,24");
  sub->add_option("--threads", opt.threads,
                  "worker threads per process (0: all cores; under mpirun with more than one rank: 1 per rank)")
      ->check(CLI::Range(0, 1024));
  sub->add_option("--out", opt.out, "output directory");
}

int run_montecarlo() {
  // Under MPI every rank runs this; an error on any of them aborts the whole job.
  return run_guarded([] {
    const sim::Scenario sc = opt.scenario.load();
    tools::MonteCarloConfig mc;
    mc.runs = opt.runs;
    mc.models = parse_models(opt.models);
    mc.threads = opt.threads;
    if (mpi_world().rank == 0) std::filesystem::create_directories(opt.out);
    const CaseResult r = run_case(sc, mc, opt.out, "");
    if (!r.written) return 0;  // a non-root MPI rank: rank 0 writes everything
    nlohmann::json j;
    j["scenario"] = sc.name;
    j["duration_s"] = sc.duration_s;
    j["runs"] = mc.runs;
    j["models"] = r.models;
    j["timing"] = r.timing;
    std::ofstream f(std::filesystem::path(opt.out) / "summary.json");
    if (!f) throw std::runtime_error("cannot write summary.json in " + opt.out);
    f << j.dump(2) << "\n";
    print_case(r);
    std::printf("outputs in %s\n", opt.out.c_str());
    return 0;
  });
}

}  // namespace sdins
