// One Monte Carlo case (a scenario, a set of models, N runs) as the montecarlo and paper commands
// run it: truth once, runs on all cores (or split across MPI ranks), statistics, CSV and JSON.
#pragma once

#include <functional>
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

/// The MPI world of this process: rank 0 of 1 unless sdins was built with MPI (SDINS_WITH_MPI) and
/// started by an MPI launcher (mpirun/mpiexec/srun: OMPI_COMM_WORLD_SIZE, PMI_SIZE, PMI_RANK or
/// PMIX_RANK in the environment; SDINS_MPI=1 forces MPI on, SDINS_MPI=0 off). The first call
/// initialises MPI in that case (MPI_Finalize runs at exit); a plain run never touches MPI.
struct MpiWorld {
  int rank = 0;
  int size = 1;
  bool active = false;  ///< MPI was initialised (also true for mpirun -np 1)
};
const MpiWorld& mpi_world();

/// Runs body(). With more than one MPI rank an exception escaping body() on any rank prints
/// "sdins: error on MPI rank r of n: ..." and aborts the whole job (MPI_Abort, exit code 1), so no
/// rank is left waiting for it; otherwise the exception propagates unchanged.
int run_guarded(const std::function<int()>& body);

/// Runs the case and writes <out_dir>/<prefix>stats_<model>.csv. Throws std::runtime_error.
/// Under MPI with K ranks the runs are split into K contiguous blocks, each rank flies its block
/// (1 thread unless mc.threads says otherwise), rank 0 gathers every RunResult, reduces them in run
/// order and writes the files: its statistics are bit-identical to a single process. The other
/// ranks write nothing and get written == false. An error on any rank aborts the job.
CaseResult run_case(const sim::Scenario& sc, const tools::MonteCarloConfig& mc, const std::string& out_dir,
                    const std::string& prefix);
/// The same with the truth given: sim::TruthTrack::generate of a scenario that flies as sc does
/// (the same start, segments, duration and IMU and GNSS rates, what the truth depends on), for
/// cases that differ only in their sensor errors (`sdins paper`'s levels share one).
CaseResult run_case(const sim::Scenario& sc, const sim::TruthTrack& truth, const tools::MonteCarloConfig& mc,
                    const std::string& out_dir, const std::string& prefix);

/// Prints the per-model table of a case.
void print_case(const CaseResult& r);

/// "15,24" -> the models (commands.hpp parse_model: the names of fsw/filter_model.hpp). Throws naming --models.
std::vector<fsw::FilterModel> parse_models(const std::string& text);

}  // namespace sdins
