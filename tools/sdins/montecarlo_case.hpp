// One Monte Carlo case (a scenario, a set of models, N runs) as the montecarlo and paper commands
// run it: truth once, runs on all cores (or split across MPI ranks), statistics, CSV and JSON.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "sim/scenario.hpp"
#include "tools/montecarlo.hpp"

namespace sdins {

struct CaseResult {
  bool written = false;                 ///< false on non-root MPI ranks (they only compute)
  std::vector<tools::ModelStats> stats; ///< one per model, in the order asked for
  nlohmann::json models;                ///< array: one summary object per model
  nlohmann::json timing;
  double wall_s = 0.0;
};

/// Runs the case and writes <out_dir>/<prefix>stats_<model>.csv. Throws std::runtime_error.
CaseResult run_case(const sim::Scenario& sc, const tools::MonteCarloConfig& mc, const std::string& out_dir,
                    const std::string& prefix);

/// Prints the per-model table of a case.
void print_case(const CaseResult& r);

std::vector<tools::Model> parse_models(const std::string& text);

}  // namespace sdins
