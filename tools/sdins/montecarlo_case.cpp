#include "montecarlo_case.hpp"

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <optional>
#include <thread>
#include <type_traits>

#include "sim/almanac.hpp"
#include "tools/interrupt.hpp"

#if SDINS_WITH_MPI
#include <mpi.h>
#endif

namespace sdins {
namespace {

using nlohmann::json;

// ---- RunResult <-> flat bytes (MPI gather). Ranks run the same binary on the same kind of
// machine, so PODs travel as their bytes; the header and the exact length catch a mismatch.

static_assert(std::is_trivially_copyable_v<tools::EpochRecord>);
static_assert(std::is_trivially_copyable_v<fsw::ExecutiveHealth>);
constexpr std::uint64_t kPackMagic = 0x31434d534e494453ULL;  // "SDINSMC1"

class Packer {
 public:
  explicit Packer(std::vector<char>& buf) : buf_(buf) {}
  void bytes(const void* p, std::size_t n) {
    const char* c = static_cast<const char*>(p);
    buf_.insert(buf_.end(), c, c + n);
  }
  template <class T>
  void pod(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes(&v, sizeof v);
  }
  void str(const std::string& v) {
    pod(static_cast<std::uint64_t>(v.size()));
    bytes(v.data(), v.size());
  }

 private:
  std::vector<char>& buf_;
};

class Unpacker {
 public:
  Unpacker(const char* p, std::size_t n) : p_(p), end_(p + n) {}
  void bytes(void* out, std::size_t n) {
    if (static_cast<std::size_t>(end_ - p_) < n) throw std::runtime_error("MPI gather: truncated run results");
    if (n) std::memcpy(out, p_, n);
    p_ += n;
  }
  template <class T>
  T pod() {
    static_assert(std::is_trivially_copyable_v<T>);
    T v;
    bytes(&v, sizeof v);
    return v;
  }
  std::uint64_t count(std::size_t elem_size) {  // an element count that must fit in what is left
    const auto n = pod<std::uint64_t>();
    if (elem_size && n > static_cast<std::uint64_t>(end_ - p_) / elem_size)
      throw std::runtime_error("MPI gather: corrupt run results (count out of range)");
    return n;
  }
  std::string str() {
    std::string v(count(1), '\0');
    bytes(v.data(), v.size());
    return v;
  }
  bool done() const { return p_ == end_; }

 private:
  const char* p_;
  const char* end_;
};

std::vector<char> pack_results(const std::vector<tools::RunResult>& rs) {
  std::vector<char> buf;
  Packer w(buf);
  w.pod(kPackMagic);
  w.pod(static_cast<std::uint64_t>(rs.size()));
  for (const auto& r : rs) {
    w.pod(static_cast<std::int64_t>(r.run));
    w.pod(r.seed);
    w.pod(static_cast<std::uint64_t>(r.epochs.size()));
    for (const auto& e : r.epochs) {
      w.pod(static_cast<std::uint64_t>(e.size()));
      w.bytes(e.data(), e.size() * sizeof(tools::EpochRecord));
    }
    w.pod(static_cast<std::uint64_t>(r.sensors.size()));
    for (const auto& model : r.sensors) {
      w.pod(static_cast<std::uint64_t>(model.size()));
      for (const auto& x : model) {
        w.str(x.name);
        w.pod(x.residual);
        w.pod(x.initial_sigma);
        w.pod(x.sigma);
        w.str(x.unit);
        w.pod(static_cast<std::uint8_t>(x.estimated));
      }
    }
    w.pod(static_cast<std::uint64_t>(r.sensor_cov.size()));
    for (const auto& c : r.sensor_cov) {
      w.pod(static_cast<std::uint64_t>(c.size()));
      w.bytes(c.data(), c.size() * sizeof(double));
    }
    w.pod(static_cast<std::uint64_t>(r.health.size()));
    for (const auto& h : r.health) w.pod(h);
    w.pod(r.wall_sim_s);
    w.pod(r.wall_mech_s);
    w.pod(r.wall_ekf_s);
  }
  return buf;
}

/// Appends the results packed in [data, data + n) to out.
void unpack_results(const char* data, std::size_t n, std::vector<tools::RunResult>& out) {
  Unpacker u(data, n);
  if (u.pod<std::uint64_t>() != kPackMagic) throw std::runtime_error("MPI gather: not a packed run result");
  const std::uint64_t nr = u.count(8);
  for (std::uint64_t i = 0; i < nr; ++i) {
    tools::RunResult r;
    r.run = static_cast<int>(u.pod<std::int64_t>());
    r.seed = u.pod<std::uint64_t>();
    r.epochs.resize(u.count(8));
    for (auto& e : r.epochs) {
      e.resize(u.count(sizeof(tools::EpochRecord)));
      u.bytes(e.data(), e.size() * sizeof(tools::EpochRecord));
    }
    r.sensors.resize(u.count(8));
    for (auto& model : r.sensors) {
      model.resize(u.count(8));
      for (auto& x : model) {
        x.name = u.str();
        x.residual = u.pod<double>();
        x.initial_sigma = u.pod<double>();
        x.sigma = u.pod<double>();
        x.unit = u.str();
        x.estimated = u.pod<std::uint8_t>() != 0;
      }
    }
    r.sensor_cov.resize(u.count(8));
    for (auto& c : r.sensor_cov) {
      c.resize(u.count(sizeof(double)));
      u.bytes(c.data(), c.size() * sizeof(double));
    }
    r.health.resize(u.count(sizeof(fsw::ExecutiveHealth)));
    for (auto& h : r.health) h = u.pod<fsw::ExecutiveHealth>();
    r.wall_sim_s = u.pod<double>();
    r.wall_mech_s = u.pod<double>();
    r.wall_ekf_s = u.pod<double>();
    out.push_back(std::move(r));
  }
  if (!u.done()) throw std::runtime_error("MPI gather: trailing bytes after the run results");
}

/// First run index (relative) of a rank's contiguous block.
int block_begin(int runs, int size, int rank) {
  return static_cast<int>(static_cast<long long>(runs) * rank / size);
}

#if SDINS_WITH_MPI
constexpr int kTagSize = 7301, kTagData = 7302;
constexpr std::size_t kChunk = std::size_t{1} << 30;  // MPI counts are int

void mpi_check(int rc, const char* what) {
  if (rc != MPI_SUCCESS) throw std::runtime_error(std::string("MPI error in ") + what);
}

/// Waits for a request without spinning a core: a rank that finished its block early (or rank 0
/// waiting for a slower rank) would otherwise busy-poll in MPI_Send/MPI_Recv and, with more ranks
/// than cores, slow down the ranks still flying.
void wait_gently(MPI_Request& req, const char* what) {
  auto pause = std::chrono::microseconds(50);
  for (;;) {
    int done = 0;
    mpi_check(MPI_Test(&req, &done, MPI_STATUS_IGNORE), what);
    if (done) return;
    // A rank that was interrupted sends nothing: the others must not wait for it.
    tools::throw_if_interrupted(std::string("stopped while exchanging results (") + what + ")");
    std::this_thread::sleep_for(pause);
    pause = std::min(pause * 2, std::chrono::microseconds(5000));
  }
}

void send_bytes(const std::vector<char>& buf, int dest) {
  const std::uint64_t n = buf.size();
  MPI_Request req;
  mpi_check(MPI_Isend(&n, 1, MPI_UINT64_T, dest, kTagSize, MPI_COMM_WORLD, &req), "MPI_Isend");
  wait_gently(req, "MPI_Isend");
  for (std::size_t off = 0; off < buf.size(); off += kChunk) {
    const int len = static_cast<int>(std::min(kChunk, buf.size() - off));
    mpi_check(MPI_Isend(buf.data() + off, len, MPI_BYTE, dest, kTagData, MPI_COMM_WORLD, &req), "MPI_Isend");
    wait_gently(req, "MPI_Isend");
  }
}

std::vector<char> recv_bytes(int src) {
  std::uint64_t n = 0;
  MPI_Request req;
  mpi_check(MPI_Irecv(&n, 1, MPI_UINT64_T, src, kTagSize, MPI_COMM_WORLD, &req), "MPI_Irecv");
  wait_gently(req, "MPI_Irecv");
  std::vector<char> buf(static_cast<std::size_t>(n));
  for (std::size_t off = 0; off < buf.size(); off += kChunk) {
    const int len = static_cast<int>(std::min(kChunk, buf.size() - off));
    mpi_check(MPI_Irecv(buf.data() + off, len, MPI_BYTE, src, kTagData, MPI_COMM_WORLD, &req), "MPI_Irecv");
    wait_gently(req, "MPI_Irecv");
  }
  return buf;
}
#endif

/// Rank 0: every rank's results, in rank (= run) order; other ranks: sends theirs, returns {}.
/// Rank 0's own results take the same pack/unpack path, so every run goes through it.
std::vector<tools::RunResult> gather_results(std::vector<tools::RunResult> local, const MpiWorld& w) {
  std::vector<char> mine = pack_results(local);
  local.clear();
  local.shrink_to_fit();
  std::vector<tools::RunResult> all;
#if SDINS_WITH_MPI
  if (w.size > 1) {
    if (w.rank != 0) {
      send_bytes(mine, 0);
      return all;
    }
    unpack_results(mine.data(), mine.size(), all);
    mine = {};
    for (int src = 1; src < w.size; ++src) {
      const std::vector<char> buf = recv_bytes(src);
      unpack_results(buf.data(), buf.size(), all);
    }
    return all;
  }
#else
  (void)w;
#endif
  unpack_results(mine.data(), mine.size(), all);
  return all;
}

/// Test hook: SDINS_TEST_FAIL_RANK=r makes rank r fail after flying its runs (tests the abort path).
void maybe_inject_failure(const MpiWorld& w) {
  const char* v = std::getenv("SDINS_TEST_FAIL_RANK");
  if (v && *v && std::atoi(v) == w.rank)
    throw std::runtime_error("injected failure (SDINS_TEST_FAIL_RANK=" + std::string(v) + ")");
}

json enu(const std::array<double, 3>& v, double scale) {
  return json{{"E", v[0] * scale}, {"N", v[1] * scale}, {"U", v[2] * scale}};
}

/// Index of the first epoch after the first turn has ended, or the last epoch.
std::size_t after_first_turn(const tools::ModelStats& s) {
  bool seen = false;
  for (std::size_t e = 0; e < s.turning.size(); ++e) {
    if (s.turning[e]) seen = true;
    if (seen && !s.turning[e]) return e;
  }
  return s.turning.empty() ? 0 : s.turning.size() - 1;
}

json health_json(const fsw::ExecutiveHealth& h) {
  return json{{"ekf_runs", h.ekf_runs},         {"ekf_updates", h.ekf_updates}, {"ekf_without_gnss", h.ekf_without_gnss},
              {"imu_rejected", h.imu_rejected}, {"gnss_epochs", h.gnss_epochs}, {"gnss_stale", h.gnss_stale},
              {"pr_used", h.pr_used},           {"prr_used", h.prr_used},       {"pr_rejected", h.pr_rejected},
              {"prr_rejected", h.prr_rejected}, {"obs_invalid", h.obs_invalid}, {"fsw_errors", h.fsw_errors},
              {"cov_checks", h.ekf.cov_checks}, {"cov_repairs", h.ekf.cov_repairs},
              {"nonfinite_rejected", h.ekf.nonfinite_rejected}, {"nis_divergence_windows", h.ekf.divergence_windows},
              {"gating_runaway_epochs", h.ekf.gating_runaway_epochs}, {"filter_resets", h.ekf.resets}};
}

/// A case's truth: the one given, or its own, integrated on a thread beside the runs
/// (sim::TruthTrack::prepare/fill: a run reading ahead of it waits), so the cores are not idle
/// for the integration's second or so. complete() joins it once the runs have read it all; on an
/// error the destructor stops it first.
class CaseTruth {
 public:
  CaseTruth(const sim::Scenario& sc, const sim::TruthTrack* given) : given_(given) {
    if (given_ != nullptr) return;
    own_ = sim::TruthTrack::prepare(sc);
    fill_.emplace(*own_);
  }
  CaseTruth(const CaseTruth&) = delete;
  CaseTruth& operator=(const CaseTruth&) = delete;
  const sim::TruthTrack& track() const { return given_ != nullptr ? *given_ : *own_; }
  void complete() {
    if (fill_) fill_->complete();
  }

 private:
  const sim::TruthTrack* given_;
  std::optional<sim::TruthTrack> own_;
  std::optional<sim::TruthFillThread> fill_;  ///< declared after own_: stopped and joined before it goes
};

CaseResult run_case_impl(const sim::Scenario& sc, const sim::TruthTrack* given_truth, const tools::MonteCarloConfig& mc,
                         const std::string& out_dir, const std::string& prefix) {
  const auto t0 = std::chrono::steady_clock::now();
  const MpiWorld& w = mpi_world();
  const sim::AlmanacParseResult alm = sim::parse_yuma_file(sim::almanac_path(sc.gps));
  if (!alm.ok()) throw std::runtime_error(alm.error);
  CaseTruth case_truth(sc, given_truth);
  const sim::TruthTrack& truth = case_truth.track();
  // This rank's block of runs; with one rank, all of them.
  tools::MonteCarloConfig local = mc;
  const int begin = block_begin(mc.runs, w.size, w.rank), end = block_begin(mc.runs, w.size, w.rank + 1);
  local.first_run = mc.first_run + begin;
  local.runs = end - begin;
  if (local.threads == 0 && w.size > 1) local.threads = 1;  // ranks, not threads, fill the cores
  std::vector<tools::RunResult> results;
  if (local.runs > 0) results = tools::run_many(sc, truth, *alm.almanac, local);
  case_truth.complete();
  maybe_inject_failure(w);
  const auto tg = std::chrono::steady_clock::now();
  double gather_s = 0.0;
  if (w.size > 1) {
    results = gather_results(std::move(results), w);
    gather_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - tg).count();
    if (w.rank != 0) return CaseResult{};  // written = false
    if (results.size() != static_cast<std::size_t>(std::max(mc.runs, 0)))
      throw std::runtime_error("MPI gather: " + std::to_string(results.size()) + " run results, expected " +
                               std::to_string(mc.runs));
    for (std::size_t k = 0; k < results.size(); ++k)
      if (results[k].run != mc.first_run + static_cast<int>(k))
        throw std::runtime_error("MPI gather: run " + std::to_string(results[k].run) + " at position " +
                                 std::to_string(k));
  }
  CaseResult r;
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.written = true;
  r.models = json::array();
  double sim_s = 0, mech_s = 0, ekf_s = 0;
  for (const auto& x : results) {
    sim_s += x.wall_sim_s;
    mech_s += x.wall_mech_s;
    ekf_s += x.wall_ekf_s;
  }
  for (std::size_t m = 0; m < mc.models.size(); ++m) {
    tools::ModelStats s = tools::reduce(results, m, mc.models[m], truth);
    const std::string csv = prefix + "stats_" + fsw::to_string(mc.models[m]) + ".csv";
    tools::write_stats_csv(s, (std::filesystem::path(out_dir) / csv).string());
    const std::size_t last = s.t_s.size() - 1, aft = after_first_turn(s);
    json sensors = json::array();
    for (const auto& x : s.sensors) {
      sensors.push_back({{"name", x.name},
                         {"unit", x.unit},
                         {"initial_sigma", x.initial_sigma},
                         {"rms_residual", x.residual},
                         {"filter_sigma", x.sigma},
                         {"estimated", x.estimated},
                         {"converged", x.residual <= 0.5 * x.initial_sigma}});
    }
    json combos = json::array();
    for (const auto& c : tools::misalignment_combinations(s)) {
      json terms = json::array();
      for (const auto& t : c.terms) terms.push_back({{"state", t.first}, {"coef", t.second}});
      combos.push_back({{"label", c.label},
                        {"terms", terms},
                        {"unit", "arcsec"},
                        {"initial_sigma", c.initial_sigma},
                        {"filter_sigma", c.final_sigma},
                        {"rms_residual", c.rms_residual},
                        {"observable", c.observable}});
    }
    r.models.push_back({{"model", fsw::to_string(mc.models[m])},
                        {"runs", s.runs},
                        {"final_residual_sigma_deg", enu(s.att_std_rad[last], fsw::kRadToDeg)},
                        {"final_residual_mean_deg", enu(s.att_mean_rad[last], fsw::kRadToDeg)},
                        {"final_filter_sigma_deg", enu(s.att_filter_sigma_rad[last], fsw::kRadToDeg)},
                        {"u_sigma_after_first_turn_deg", s.att_std_rad[aft][2] * fsw::kRadToDeg},
                        {"first_turn_end_s", s.t_s[aft]},
                        {"mean_nees", s.nees_measured() ? json(s.mean_nees) : json(nullptr)},
                        {"nees_measured", s.nees_measured()},
                        {"nees_epochs", s.nees_epochs},
                        {"nees_bounds", {s.nees_bounds[0], s.nees_bounds[1]}},
                        {"nees_dof", 9},
                        {"mean_nees_att", s.nees_measured() ? json(s.mean_nees_att) : json(nullptr)},
                        {"nees_att_bounds", {s.nees_att_bounds[0], s.nees_att_bounds[1]}},
                        {"nees_from_s", s.nees_from_s},
                        {"final_pos_rms_m", s.pos_rms_m[last]},
                        {"final_vel_rms_mps", s.vel_rms_mps[last]},
                        {"sensors", sensors},
                        {"misalignment_combinations", combos},
                        {"health", health_json(s.health)},
                        {"csv", csv}});
    r.stats.push_back(std::move(s));
  }
  const double flown_s = sc.duration_s * mc.runs;
  r.timing = {{"wall_s", r.wall_s},
              {"truth_generation_s", truth.generate_wall_s},
              {"imu_gps_models_cpu_s", sim_s},
              {"mechanization_cpu_s", mech_s},
              {"ekf_cpu_s", ekf_s},
              {"models_flown", mc.models.size()},
              {"real_time_factor", flown_s / r.wall_s},
              {"mpi_ranks", w.size},
              {"threads_per_rank", local.threads > 0 ? local.threads
                                                     : static_cast<int>(std::thread::hardware_concurrency())},
              {"mpi_gather_s", gather_s}};
  return r;
}

/// Whether an MPI launcher started this process (or SDINS_MPI forces the answer).
bool launched_by_mpi() {
  if (const char* f = std::getenv("SDINS_MPI"); f && *f) return std::strcmp(f, "0") != 0;
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMI_RANK", "PMIX_RANK"})
    if (std::getenv(v)) return true;
  return false;
}

/// The number of processes the launcher says it started (0: unknown).
int launcher_size() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"})
    if (const char* s = std::getenv(v)) return std::atoi(s);
  return 0;
}

#if SDINS_WITH_MPI
void finalize_mpi() {
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (!finalized) MPI_Finalize();
}
#endif

}  // namespace

const MpiWorld& mpi_world() {
  static const MpiWorld world = [] {
    MpiWorld w;
    if (!launched_by_mpi()) return w;
#if SDINS_WITH_MPI
    int initialized = 0;
    MPI_Initialized(&initialized);
    if (!initialized) {
      int provided = 0;  // only the main thread calls MPI; the run threads never do
      if (MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS)
        throw std::runtime_error("MPI_Init_thread failed");
      std::atexit(finalize_mpi);
    }
    MPI_Comm_rank(MPI_COMM_WORLD, &w.rank);
    MPI_Comm_size(MPI_COMM_WORLD, &w.size);
    w.active = true;
    if (w.size == 1 && launcher_size() > 1)
      std::fprintf(stderr,
                   "sdins: warning: the launcher started %d processes but MPI sees a world of 1 (an mpirun of a "
                   "different MPI implementation than the one sdins was built with?); each process runs alone\n",
                   launcher_size());
#else
    if (launcher_size() > 1)
      std::fprintf(stderr,
                   "sdins: warning: started by an MPI launcher as one of %d processes, but sdins was built without "
                   "MPI: each process runs everything alone\n",
                   launcher_size());
#endif
    return w;
  }();
  return world;
}

int run_guarded(const std::function<int()>& body) {
  const MpiWorld& w = mpi_world();
  if (w.size <= 1) return body();
  try {
    return body();
  } catch (const tools::Interrupted& e) {
    // mpirun forwards SIGINT/SIGTERM to every rank as SIGTERM and kills them 1 s later: each rank
    // says how far it got, and the job ends with the signal's exit code (128 + signal) through
    // MPI_Abort, which the launcher returns; no rank writes results (docs/faults.md).
    std::fprintf(stderr, "sdins: MPI rank %d of %d: %s\n", w.rank, w.size, e.what());
    std::fflush(stderr);
    std::fflush(stdout);
#if SDINS_WITH_MPI
    // The launcher kills the whole job as soon as one rank exits non-zero: wait (at most 0.5 s, half
    // of its grace period) until every rank has said how far it got, so no message is cut off.
    MPI_Request req;
    if (MPI_Ibarrier(MPI_COMM_WORLD, &req) == MPI_SUCCESS) {
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
      int done = 0;
      while (!done && std::chrono::steady_clock::now() < deadline) {
        if (MPI_Test(&req, &done, MPI_STATUS_IGNORE) != MPI_SUCCESS) break;
        if (!done) std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
    }
#endif
    std::_Exit(tools::interrupt_exit_code());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sdins: error on MPI rank %d of %d: %s\n", w.rank, w.size, e.what());
  } catch (...) {
    std::fprintf(stderr, "sdins: error on MPI rank %d of %d: unknown exception\n", w.rank, w.size);
  }
  std::fflush(stderr);
  std::fflush(stdout);
#if SDINS_WITH_MPI
  MPI_Abort(MPI_COMM_WORLD, 1);
#endif
  std::_Exit(1);
}

CaseResult run_case(const sim::Scenario& sc, const tools::MonteCarloConfig& mc, const std::string& out_dir,
                    const std::string& prefix) {
  CaseResult r;
  run_guarded([&] {
    r = run_case_impl(sc, nullptr, mc, out_dir, prefix);
    return 0;
  });
  return r;
}

CaseResult run_case(const sim::Scenario& sc, const sim::TruthTrack& truth, const tools::MonteCarloConfig& mc,
                    const std::string& out_dir, const std::string& prefix) {
  CaseResult r;
  run_guarded([&] {
    r = run_case_impl(sc, &truth, mc, out_dir, prefix);
    return 0;
  });
  return r;
}

void print_case(const CaseResult& r) {
  std::printf("%-6s %5s %28s %10s %8s %17s\n", "model", "runs", "final residual 1-sigma E/N/U", "U@turn1", "NEES",
              "95% bounds");
  for (const auto& m : r.models) {
    const auto& f = m["final_residual_sigma_deg"];
    char nees[32];
    if (m["mean_nees"].is_number())
      std::snprintf(nees, sizeof nees, "%8.2f", m["mean_nees"].get<double>());
    else
      std::snprintf(nees, sizeof nees, "%8s", "-");
    std::printf("%-6s %5d %8.5f %8.5f %8.5f deg %10.5f %s [%6.2f, %6.2f]\n", m["model"].get<std::string>().c_str(),
                m["runs"].get<int>(), f["E"].get<double>(), f["N"].get<double>(), f["U"].get<double>(),
                m["u_sigma_after_first_turn_deg"].get<double>(), nees, m["nees_bounds"][0].get<double>(),
                m["nees_bounds"][1].get<double>());
  }
  for (const auto& m : r.models)
    if (!m["nees_measured"].get<bool>()) {
      std::printf("NEES not measured: the flight ends before the NEES window starts (t >= %.0f s)\n",
                  m["nees_from_s"].get<double>());
      break;
    }
  const auto& t = r.timing;
  std::printf("wall %.1f s (truth %.2f s; cpu: IMU/GPS models %.1f s, mechanization %.1f s, EKF %.1f s), %.0fx real time\n",
              t["wall_s"].get<double>(), t["truth_generation_s"].get<double>(), t["imu_gps_models_cpu_s"].get<double>(),
              t["mechanization_cpu_s"].get<double>(), t["ekf_cpu_s"].get<double>(), t["real_time_factor"].get<double>());
  if (t.value("mpi_ranks", 1) > 1)
    std::printf("MPI: %d ranks x %d threads, gathering the runs on rank 0 took %.2f s\n", t["mpi_ranks"].get<int>(),
                t["threads_per_rank"].get<int>(), t["mpi_gather_s"].get<double>());
}

}  // namespace sdins
