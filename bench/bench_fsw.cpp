// Google Benchmark of the flight-software tasks on realistic inputs.
//
// Inputs: 30 s of the default scenario's first bank-to-turn (t = 70 ... 100 s, 60 deg bank),
// perfect-IMU increments from the truth simulator at 1 kHz, mechanized once before any timing;
// GNSS epochs of 10 fixed synthetic satellites about 20,000 km up around the receiver, with
// pseudoranges and rates from fsw::gnss_geometry (plus a receiver clock and a small deterministic
// error), so that every measurement passes the innovation gate.
//
// Benchmarks (see README.md, "Benchmarks"):
//   mech/...                  FrameBuilder::add and Strapdown::step, one 200 Hz frame per iteration
//   ekf_accumulate/<layout>   Ekf::accumulate, one frame per iteration (every 10th flushes a sub-step)
//   ekf_propagate/<layout>    Ekf::propagate after 200 accumulated frames (the 1 Hz step)
//   ekf_update/<layout>       Ekf::update with a 10-satellite epoch (20 scalar measurements)
//   ekf_update_1sat/<layout>  Ekf::update with one satellite (pseudorange + rate: 2 scalar measurements)
//   ekf_update_12sat/<layout> Ekf::update with 12 satellites (24 scalar measurements: a full receiver)
//   exec_tick/<layout>/nav    Executive::tick, a minor frame without the 1 Hz group
//   exec_tick/<layout>/ekf    Executive::tick, the minor frame that runs the 1 Hz group
//                             (propagate + update + feedback)
// Work that changes the filter state is re-run on a copy of a prepared state for every iteration;
// those benchmarks time the call itself by hand (UseManualTime), so the copy is not counted.
//
// Counters: frame_budget_pct = time per iteration / 5 ms minor frame * 100; allocs_per_iter =
// heap allocations inside the timing loop per iteration (replaced malloc / operator new, as in
// tests/noalloc; must be 0 for fsw code).
#include <benchmark/benchmark.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "fsw/ekf.hpp"
#include "fsw/error_state.hpp"
#include "fsw/executive.hpp"
#include "fsw/frames.hpp"
#include "fsw/gnss.hpp"
#include "fsw/strapdown.hpp"
#include "sim/scenario.hpp"
#include "sim/trajectory.hpp"

// ------------------------------------------------------------------------------------------------
// Heap-allocation counting (only while a timing loop runs)
// ------------------------------------------------------------------------------------------------
namespace {
std::atomic<bool> g_count_allocs{false};
std::atomic<long> g_allocs{0};
[[maybe_unused]] inline void count_alloc() {
  if (g_count_allocs.load(std::memory_order_relaxed)) g_allocs.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

#if defined(SDINS_BENCH_COUNT_ALLOCS)
extern "C" void* __libc_malloc(std::size_t);
extern "C" void* __libc_calloc(std::size_t, std::size_t);
extern "C" void* __libc_realloc(void*, std::size_t);
extern "C" void __libc_free(void*);

extern "C" void* malloc(std::size_t n) {
  count_alloc();
  return __libc_malloc(n);
}
extern "C" void* calloc(std::size_t a, std::size_t b) {
  count_alloc();
  return __libc_calloc(a, b);
}
extern "C" void* realloc(void* p, std::size_t n) {
  count_alloc();
  return __libc_realloc(p, n);
}
extern "C" void free(void* p) { __libc_free(p); }

void* operator new(std::size_t n) {
  count_alloc();
  void* p = __libc_malloc(n ? n : 1);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
void* operator new[](std::size_t n) { return operator new(n); }
void* operator new(std::size_t n, std::align_val_t al) {
  count_alloc();
  const std::size_t a = static_cast<std::size_t>(al);
  void* p = std::aligned_alloc(a, (n + a - 1) / a * a);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
void* operator new[](std::size_t n, std::align_val_t al) { return operator new(n, al); }
void operator delete(void* p) noexcept { __libc_free(p); }
void operator delete[](void* p) noexcept { __libc_free(p); }
void operator delete(void* p, std::size_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::size_t) noexcept { __libc_free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
#endif

namespace {

using fsw::Status;
using fsw::Vec3;
using Clock = std::chrono::steady_clock;

constexpr double kFrameBudget_s = 0.005;  // 200 Hz minor frame
constexpr int kSamplesPerFrame = 5;       // 1 kHz IMU / 200 Hz
constexpr int kFramesPerEkf = 200;        // 200 Hz / 1 Hz
constexpr double kImuRate_hz = 1000.0;
constexpr double kStart_s = 70.0;         // inside the first turn (roll-in ends at 65 s)
constexpr double kEnd_s = 100.0;
constexpr int kSatellites = 10;
constexpr int kMaxSatellites = 12;        // the constellation; the standard epochs use the first 10
constexpr double kClockBias0_m = 120.0;   // receiver clock of the synthetic epochs
constexpr double kClockDrift_mps = 0.4;

bool g_setup_failed = false;  // any benchmark's set-up check failed: non-zero exit status

void fail(benchmark::State& state, const std::string& what) {
  g_setup_failed = true;
  state.SkipWithError(what.c_str());
}

// ------------------------------------------------------------------------------------------------
// Flight data, prepared once
// ------------------------------------------------------------------------------------------------
struct Satellite {
  std::uint8_t prn = 0;
  Vec3 pos_ecef_m = Vec3::Zero();
  Vec3 vel_ecef_mps = Vec3::Zero();
  double elevation_rad = 0.0;
};

struct FlightData {
  std::string error;                       ///< non-empty: preparation failed
  fsw::NavState init{};                    ///< truth at kStart_s
  std::vector<fsw::ImuSample> imu;         ///< perfect IMU samples over (kStart_s, kEnd_s]
  std::vector<fsw::FrameIncrement> inc;    ///< per navigation frame
  std::vector<fsw::NavState> nav;          ///< mechanized solution at each frame end
  std::vector<Vec3> omega_ib_b;            ///< body rate of each frame
  std::vector<Vec3> truth_llh, truth_vel;  ///< truth at each frame end
  std::vector<Satellite> sats;
  std::vector<fsw::GnssEpoch> epochs;      ///< epochs[s]: at the end of frame epoch_frame(s), t = kStart_s + s + 1
  std::vector<fsw::GnssEpoch> epochs1;     ///< the same epochs with only the first satellite
  std::vector<fsw::GnssEpoch> epochs12;    ///< ... with all 12 satellites

  int frames() const { return static_cast<int>(inc.size()); }
  static int epoch_frame(int s) { return kFramesPerEkf * (s + 1) - 1; }
  const fsw::ImuSample* frame_imu(int f) const { return &imu[static_cast<std::size_t>(f * kSamplesPerFrame)]; }
};

/// 10 satellites on a 26,560 km orbit radius, spread in azimuth and elevation around llh.
std::vector<Satellite> make_constellation(const Vec3& llh) {
  static constexpr double kElevationDeg[kMaxSatellites] = {15, 62, 35, 80, 25, 50, 20, 70, 40, 30, 55, 45};
  static constexpr std::uint8_t kPrn[kMaxSatellites] = {2, 5, 7, 9, 13, 16, 21, 24, 27, 30, 31, 32};
  const Vec3 r0 = fsw::ecef_from_llh(llh);
  const fsw::Mat3 Cne = fsw::C_n_e(llh.x(), llh.y());
  const double orbit_m = 26'560e3;
  std::vector<Satellite> sats;
  for (int k = 0; k < kMaxSatellites; ++k) {
    const double az = (10.0 + 36.0 * k + 17.0 * (k / 10)) * fsw::kDegToRad, el = kElevationDeg[k] * fsw::kDegToRad;
    const Vec3 u = Cne * Vec3(std::cos(el) * std::sin(az), std::cos(el) * std::cos(az), std::sin(el));
    const double b = r0.dot(u);
    const double rho = -b + std::sqrt(b * b - (r0.squaredNorm() - orbit_m * orbit_m));
    Satellite s;
    s.prn = kPrn[k];
    s.pos_ecef_m = r0 + rho * u;
    s.vel_ecef_mps = 3870.0 * Vec3(std::cos(1.3 * k), std::sin(1.3 * k), 0.6).cross(s.pos_ecef_m).normalized();
    s.elevation_rad = el;
    sats.push_back(s);
  }
  return sats;
}

/// Epoch of the fixed constellation seen from the true receiver state at t.
fsw::GnssEpoch make_epoch(double t_s, const Vec3& llh, const Vec3& vel_enu, const std::vector<Satellite>& all_sats,
                          int n_sats) {
  const std::vector<Satellite> sats(all_sats.begin(), all_sats.begin() + n_sats);
  fsw::GnssEpoch e;
  e.t_s = t_s;
  e.gps_week = 1455;
  e.gps_tow_s = 589824.0 + t_s;
  const Vec3 r_rx = fsw::ecef_from_llh(llh);
  const Vec3 v_rx = fsw::C_n_e(llh.x(), llh.y()) * vel_enu;
  const double clk_b = kClockBias0_m + kClockDrift_mps * (t_s - kStart_s);
  for (const Satellite& s : sats) {
    const int k = e.n_obs++;
    const fsw::GnssGeometry g = fsw::gnss_geometry(s.pos_ecef_m, s.vel_ecef_mps, r_rx, v_rx);
    fsw::GnssObservation& o = e.obs[static_cast<std::size_t>(k)];
    o.prn = s.prn;
    o.sat_pos_ecef_m = s.pos_ecef_m;
    o.sat_vel_ecef_mps = s.vel_ecef_mps;
    o.pseudorange_m = g.range_m + clk_b + 0.8 * std::sin(1.7 * k + t_s);  // small, gate-passing errors
    o.pseudorange_rate_mps = g.range_rate_mps + kClockDrift_mps + 0.02 * std::cos(2.3 * k + t_s);
    o.elevation_rad = s.elevation_rad;
  }
  return e;
}

FlightData prepare_flight() {
  FlightData d;
  sim::Scenario sc{};
  auto motion = sim::FlightMotion::create(sc, d.error);
  if (!motion) return d;
  if (sc.imu.rate_hz != static_cast<int>(kImuRate_hz)) {
    d.error = "the default scenario's IMU rate is no longer 1 kHz";
    return d;
  }
  sim::TruthGenerator gen(*motion, kImuRate_hz);
  const long long n_skip = std::llround(kStart_s * kImuRate_hz);
  const long long n_take = std::llround((kEnd_s - kStart_s) * kImuRate_hz);
  for (long long i = 0; i < n_skip; ++i) gen.next();
  const sim::TruthSample& t0 = gen.current();
  if (!t0.phase.turning) {
    d.error = "t = 70 s is no longer inside a turn of the default scenario";
    return d;
  }
  d.init.t_s = t0.t_s;
  d.init.llh = t0.llh;
  d.init.vel_enu_mps = t0.vel_enu_mps;
  d.init.q_b_n = fsw::Quat(t0.C_b_n);
  d.imu.reserve(static_cast<std::size_t>(n_take));
  for (long long i = 0; i < n_take; ++i) {
    const sim::TruthSample& t = gen.next();
    d.imu.push_back({t.t_s, t.dt_s, t.dtheta_rad, t.dv_mps});
    if ((i + 1) % kSamplesPerFrame == 0) {
      d.truth_llh.push_back(t.llh);
      d.truth_vel.push_back(t.vel_enu_mps);
    }
  }
  fsw::FrameBuilder fb;
  fsw::Strapdown sd;
  if (fb.configure(kSamplesPerFrame) != Status::kOk || sd.init(d.init) != Status::kOk) {
    d.error = "mechanization set-up failed";
    return d;
  }
  for (const fsw::ImuSample& s : d.imu) {
    if (fb.add(s) != Status::kOk) continue;
    if (sd.step(fb.frame()) != Status::kOk) {
      d.error = "Strapdown::step failed on the truth data";
      return d;
    }
    d.inc.push_back(fb.frame());
    d.nav.push_back(sd.state());
    d.omega_ib_b.push_back(sd.omega_ib_b_radps());
  }
  if (d.inc.size() != d.truth_llh.size()) {
    d.error = "frame count mismatch";
    return d;
  }
  const int mid = d.frames() / 2;
  d.sats = make_constellation(d.truth_llh[static_cast<std::size_t>(mid)]);
  for (int s = 0; FlightData::epoch_frame(s) < d.frames(); ++s) {
    const auto f = static_cast<std::size_t>(FlightData::epoch_frame(s));
    d.epochs.push_back(make_epoch(kStart_s + s + 1, d.truth_llh[f], d.truth_vel[f], d.sats, kSatellites));
    d.epochs1.push_back(make_epoch(kStart_s + s + 1, d.truth_llh[f], d.truth_vel[f], d.sats, 1));
    d.epochs12.push_back(make_epoch(kStart_s + s + 1, d.truth_llh[f], d.truth_vel[f], d.sats, kMaxSatellites));
  }
  return d;
}

const FlightData& flight() {
  static const FlightData data = prepare_flight();
  return data;
}

template <class L>
struct LayoutName;
template <>
struct LayoutName<fsw::Layout15> {
  static constexpr const char* value = "Layout15";
};
template <>
struct LayoutName<fsw::Layout24> {
  static constexpr const char* value = "Layout24";
};
template <>
struct LayoutName<fsw::Layout15Full> {
  static constexpr const char* value = "Layout15Full";
};
template <>
struct LayoutName<fsw::Layout24Full> {
  static constexpr const char* value = "Layout24Full";
};

// ------------------------------------------------------------------------------------------------
// Measurement helpers
// ------------------------------------------------------------------------------------------------

/// Counts heap allocations while alive (wrap the timing loop only).
class AllocScope {
 public:
  AllocScope() {
    g_allocs.store(0);
    g_count_allocs.store(true);
  }
  ~AllocScope() { g_count_allocs.store(false); }
  long count() const { return g_allocs.load(); }
};

/// Sets allocs_per_iter, frame_budget_pct and the items processed. timed_s: the wall-clock time of
/// the timed work over all iterations (the hand-timed total, or the whole loop for the others).
/// frame_budget_pct is a plain counter: Google Benchmark's inverted rate counters would print as
/// seconds ("1.6ms") in the console table.
void finish(benchmark::State& state, const AllocScope& allocs, double items_per_iter, double timed_s) {
  const double n = static_cast<double>(state.iterations());
#if defined(SDINS_BENCH_COUNT_ALLOCS)
  state.counters["allocs_per_iter"] = benchmark::Counter(static_cast<double>(allocs.count()), benchmark::Counter::kAvgIterations);
#else
  (void)allocs;
#endif
  state.counters["frame_budget_pct"] = n > 0.0 ? timed_s / n / kFrameBudget_s * 100.0 : 0.0;
  // Rates use the manual time of UseManualTime benchmarks and the real time of UseRealTime ones.
  if (items_per_iter > 0.0) state.SetItemsProcessed(static_cast<std::int64_t>(n * items_per_iter));
}

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// ------------------------------------------------------------------------------------------------
// 1. 200 Hz mechanization
// ------------------------------------------------------------------------------------------------

/// One frame of the data per iteration, the whole loop timed: step(f) for frames 0, 1, ... and,
/// on wrapping to the start of the data (once in 6000 frames), restart() first. items: what one
/// step counts for in the rate (1 frame; 2 for two solutions stepped).
template <class Restart, class Step>
void time_over_frames(benchmark::State& state, const FlightData& d, Restart restart, Step step, double items = 1.0) {
  const int nf = d.frames();
  int f = 0;
  AllocScope allocs;
  const auto t_loop = Clock::now();
  for (auto _ : state) {
    if (f == nf) {
      f = 0;
      restart();
    }
    step(f++);
    benchmark::ClobberMemory();
  }
  finish(state, allocs, items, seconds_since(t_loop));
}

/// FrameBuilder::add for the 5 samples of a frame and Strapdown::step: one navigation frame.
void BM_MechFrame(benchmark::State& state) {
  const FlightData& d = flight();
  fsw::FrameBuilder fb;
  fsw::Strapdown sd;
  fb.configure(kSamplesPerFrame);
  sd.init(d.init);
  time_over_frames(
      state, d,
      [&] {
        fb.reset();
        sd.init(d.init);
      },
      [&](int f) {
        const fsw::ImuSample* s = d.frame_imu(f);
        Status st = Status::kOk;
        for (int k = 0; k < kSamplesPerFrame; ++k) st = fb.add(s[k]);
        benchmark::DoNotOptimize(st);
        st = sd.step(fb.frame());
        benchmark::DoNotOptimize(st);
      });
}

/// FrameBuilder::add alone, 5 samples (one frame's coning/sculling).
void BM_FrameBuilderAdd5(benchmark::State& state) {
  const FlightData& d = flight();
  fsw::FrameBuilder fb;
  fb.configure(kSamplesPerFrame);
  time_over_frames(
      state, d, [] {},
      [&](int f) {
        const fsw::ImuSample* s = d.frame_imu(f);
        for (int k = 0; k < kSamplesPerFrame; ++k) {
          Status st = fb.add(s[k]);
          benchmark::DoNotOptimize(st);
        }
      });
}

/// Strapdown::step alone on the precomputed frame increments.
void BM_StrapdownStep(benchmark::State& state) {
  const FlightData& d = flight();
  fsw::Strapdown sd;
  sd.init(d.init);
  time_over_frames(
      state, d, [&] { sd.init(d.init); },
      [&](int f) {
        Status st = sd.step(d.inc[static_cast<std::size_t>(f)]);
        benchmark::DoNotOptimize(st);
      });
}

/// Strapdown::step of two independent solutions on the same increments, one after the other in
/// each iteration (items: steps). The step is a chain of dependent operations (latitude -> radius
/// -> latitude -> sine -> rate -> rotation); when the second chain overlaps the first in the
/// core's out-of-order window, a step here costs less than mech/strapdown_step (docs/performance.md:
/// "A navigation frame, term by term").
void BM_StrapdownStepTwoStates(benchmark::State& state) {
  const FlightData& d = flight();
  fsw::Strapdown a, b;
  fsw::NavState other = d.init;
  other.llh.x() += 1e-4;  // another solution: no shared values the compiler could reuse
  a.init(d.init);
  b.init(other);
  time_over_frames(
      state, d,
      [&] {
        a.init(d.init);
        b.init(other);
      },
      [&](int f) {
        const fsw::FrameIncrement& inc = d.inc[static_cast<std::size_t>(f)];
        Status st = a.step(inc);
        benchmark::DoNotOptimize(st);
        st = b.step(inc);
        benchmark::DoNotOptimize(st);
      },
      2.0);
}

/// The latency of one libm sine against its throughput (items: sines): each argument depends on
/// the sine before it (sin_dependent) or none does (sin_independent). The strapdown step's sines
/// are of the first kind.
void BM_SinDependent(benchmark::State& state) {
  double x = 0.7;
  AllocScope allocs;
  const auto t_loop = Clock::now();
  for (auto _ : state) {
    for (int k = 0; k < 64; ++k) x = 0.7 + 1e-3 * std::sin(x);
    benchmark::DoNotOptimize(x);
  }
  finish(state, allocs, 64.0, seconds_since(t_loop));
}

void BM_SinIndependent(benchmark::State& state) {
  std::array<double, 64> x{};
  for (std::size_t k = 0; k < x.size(); ++k) x[k] = 0.7 + 1e-3 * static_cast<double>(k);
  AllocScope allocs;
  const auto t_loop = Clock::now();
  for (auto _ : state) {
    double sum = 0.0;
    for (double v : x) sum += std::sin(v);
    benchmark::DoNotOptimize(sum);
    benchmark::ClobberMemory();
  }
  finish(state, allocs, 64.0, seconds_since(t_loop));
}

// ------------------------------------------------------------------------------------------------
// 2./3. EKF
// ------------------------------------------------------------------------------------------------

fsw::EkfConfig ekf_config() {
  fsw::EkfConfig c{};
  c.clock_bias_psd_m2ps = 0.1;  // a TCXO-like clock; the defaults are zero
  c.clock_drift_psd_m2ps3 = 0.04;
  return c;
}

/// Runs the filter through kCycles 1 Hz cycles (accumulate 200 frames, propagate, update,
/// feedback) so that the clock is initialised and the receiver channels are bound: the state of a
/// filter in steady operation, at the end of frame epoch_frame(kCycles - 1).
constexpr int kWarmCycles = 3;
template <class L>
bool warm_up(const FlightData& d, fsw::Ekf<L>& ekf, std::string& err, const std::vector<fsw::GnssEpoch>* epochs = nullptr) {
  const std::vector<fsw::GnssEpoch>& ep = epochs != nullptr ? *epochs : d.epochs;
  if (ekf.init(ekf_config()) != Status::kOk) {
    err = "Ekf::init failed";
    return false;
  }
  fsw::Strapdown ins;  // feedback target (the data's solution is not corrected: it is near-perfect)
  fsw::ImuCompensation comp;
  ins.init(d.init);
  for (int s = 0; s < kWarmCycles; ++s) {
    for (int f = kFramesPerEkf * s; f < kFramesPerEkf * (s + 1); ++f)
      if (ekf.accumulate(d.inc[static_cast<std::size_t>(f)], d.nav[static_cast<std::size_t>(f)]) != Status::kOk) {
        err = "Ekf::accumulate failed";
        return false;
      }
    const auto fe = static_cast<std::size_t>(FlightData::epoch_frame(s));
    fsw::EkfUpdateReport rep;
    if (ekf.propagate() != Status::kOk ||
        ekf.update(ep[static_cast<std::size_t>(s)], d.nav[fe], d.omega_ib_b[fe], rep) != Status::kOk ||
        ekf.feedback(ins, comp) != Status::kOk) {
      err = "EKF warm-up cycle failed";
      return false;
    }
  }
  if (!ekf.clock_initialised()) {
    err = "receiver clock not initialised after the warm-up";
    return false;
  }
  return true;
}

/// Times work(*copy) on a fresh copy of pre each iteration (the copy untimed); the timed total.
template <class T, class Work>
double time_on_fresh_copies(benchmark::State& state, const T& pre, T& copy, Work work) {
  double total_s = 0.0;
  for (auto _ : state) {
    copy = pre;
    benchmark::ClobberMemory();
    const auto t0 = Clock::now();
    work(copy);
    benchmark::ClobberMemory();
    const double dt = seconds_since(t0);
    total_s += dt;
    state.SetIterationTime(dt);
  }
  return total_s;
}

/// Accumulates the frames of cycle kWarmCycles (the next 200 frames) into ekf.
template <class L>
bool accumulate_next_cycle(const FlightData& d, fsw::Ekf<L>& ekf) {
  for (int f = kFramesPerEkf * kWarmCycles; f < kFramesPerEkf * (kWarmCycles + 1); ++f)
    if (ekf.accumulate(d.inc[static_cast<std::size_t>(f)], d.nav[static_cast<std::size_t>(f)]) != Status::kOk)
      return false;
  return true;
}

/// Ekf::accumulate, one frame per iteration. After every 200 frames (one 1 Hz interval) the filter
/// is restored to its state at the start of the interval, untimed, so the transition matrix never
/// grows beyond one second's worth; each block of 200 frames is timed by hand.
template <class L>
void BM_EkfAccumulate(benchmark::State& state) {
  const FlightData& d = flight();
  auto fresh = std::make_unique<fsw::Ekf<L>>();
  auto ekf = std::make_unique<fsw::Ekf<L>>();
  std::string err;
  if (!d.error.empty() || !warm_up(d, *fresh, err)) return fail(state, d.error.empty() ? err : d.error);
  const int f0 = kFramesPerEkf * kWarmCycles;
  int k = 0;
  double total_s = 0.0;
  Clock::time_point t0;
  AllocScope allocs;
  for (auto _ : state) {
    if (k == 0) {
      *ekf = *fresh;
      t0 = Clock::now();
    }
    const auto f = static_cast<std::size_t>(f0 + k);
    Status st = ekf->accumulate(d.inc[f], d.nav[f]);
    benchmark::DoNotOptimize(st);
    if (++k == kFramesPerEkf) {
      benchmark::ClobberMemory();
      const double dt = seconds_since(t0);
      total_s += dt;
      state.SetIterationTime(dt);  // the whole block's time, on its last iteration
      k = 0;
    } else {
      state.SetIterationTime(0.0);
    }
  }
  // A partly finished last block is not counted in total_s: its iterations were charged 0 s.
  finish(state, allocs, 1.0, total_s);
}

/// Ekf::propagate (the 1 Hz step) after 200 accumulated frames, on a fresh copy each iteration.
template <class L>
void BM_EkfPropagate(benchmark::State& state) {
  const FlightData& d = flight();
  auto pre = std::make_unique<fsw::Ekf<L>>();
  auto ekf = std::make_unique<fsw::Ekf<L>>();
  std::string err;
  if (!d.error.empty() || !warm_up(d, *pre, err)) return fail(state, d.error.empty() ? err : d.error);
  if (!accumulate_next_cycle(d, *pre)) return fail(state, "Ekf::accumulate failed");
  AllocScope allocs;
  const double total_s = time_on_fresh_copies(state, *pre, *ekf, [](fsw::Ekf<L>& e) {
    Status st = e.propagate();
    benchmark::DoNotOptimize(st);
  });
  finish(state, allocs, 0.0, total_s);
}

/// Ekf::update with a 10-satellite epoch (pseudorange and rate: 20 scalar updates) after the
/// propagation, on a fresh copy each iteration. The clock was initialised and the channels bound
/// in the warm-up, so this is the steady-state update.
template <class L>
void BM_EkfUpdate(benchmark::State& state) {
  const FlightData& d = flight();
  auto pre = std::make_unique<fsw::Ekf<L>>();
  auto ekf = std::make_unique<fsw::Ekf<L>>();
  std::string err;
  if (!d.error.empty() || !warm_up(d, *pre, err)) return fail(state, d.error.empty() ? err : d.error);
  if (!accumulate_next_cycle(d, *pre) || pre->propagate() != Status::kOk) return fail(state, "propagation failed");
  const auto fe = static_cast<std::size_t>(FlightData::epoch_frame(kWarmCycles));
  const fsw::GnssEpoch& epoch = d.epochs[static_cast<std::size_t>(kWarmCycles)];
  const fsw::NavState& nav = d.nav[fe];
  const Vec3& omega = d.omega_ib_b[fe];
  fsw::EkfUpdateReport rep;
  {  // check once that every measurement is used
    *ekf = *pre;
    if (ekf->update(epoch, nav, omega, rep) != Status::kOk || rep.pr_used != kSatellites ||
        rep.prr_used != kSatellites || rep.obs_no_channel != 0 || rep.clock_initialised)
      return fail(state, "the benchmark epoch is not fully used: pr " + std::to_string(rep.pr_used) + ", prr " +
                             std::to_string(rep.prr_used));
  }
  AllocScope allocs;
  const double total_s = time_on_fresh_copies(state, *pre, *ekf, [&](fsw::Ekf<L>& e) {
    Status st = e.update(epoch, nav, omega, rep);
    benchmark::DoNotOptimize(st);
  });
  finish(state, allocs, 2.0 * kSatellites, total_s);  // items: scalar measurements
}

/// Ekf::update with an epoch of n_sats satellites (1: the cost of one satellite's pseudorange and
/// rate; 12: a full receiver), after a warm-up on epochs of the same satellites, on a fresh copy
/// each iteration.
template <class L, int n_sats>
void BM_EkfUpdateSats(benchmark::State& state) {
  static_assert(n_sats == 1 || n_sats == kMaxSatellites);
  const FlightData& d = flight();
  const std::vector<fsw::GnssEpoch>& epochs = n_sats == 1 ? d.epochs1 : d.epochs12;
  auto pre = std::make_unique<fsw::Ekf<L>>();
  auto ekf = std::make_unique<fsw::Ekf<L>>();
  std::string err;
  if (!d.error.empty() || !warm_up(d, *pre, err, &epochs)) return fail(state, d.error.empty() ? err : d.error);
  if (!accumulate_next_cycle(d, *pre) || pre->propagate() != Status::kOk) return fail(state, "propagation failed");
  const auto fe = static_cast<std::size_t>(FlightData::epoch_frame(kWarmCycles));
  const fsw::GnssEpoch& epoch = epochs[static_cast<std::size_t>(kWarmCycles)];
  fsw::EkfUpdateReport rep;
  {
    *ekf = *pre;
    if (ekf->update(epoch, d.nav[fe], d.omega_ib_b[fe], rep) != Status::kOk || rep.pr_used != n_sats ||
        rep.prr_used != n_sats || rep.obs_no_channel != 0 || rep.clock_initialised)
      return fail(state, "the " + std::to_string(n_sats) + "-satellite epoch is not fully used: pr " +
                             std::to_string(rep.pr_used) + ", prr " + std::to_string(rep.prr_used));
  }
  AllocScope allocs;
  const double total_s = time_on_fresh_copies(state, *pre, *ekf, [&](fsw::Ekf<L>& e) {
    Status st = e.update(epoch, d.nav[fe], d.omega_ib_b[fe], rep);
    benchmark::DoNotOptimize(st);
  });
  finish(state, allocs, 2.0 * n_sats, total_s);
}

// ------------------------------------------------------------------------------------------------
// 4. Executive
// ------------------------------------------------------------------------------------------------

fsw::FrameInput frame_input(const FlightData& d, int f, const fsw::GnssEpoch* gnss) {
  fsw::FrameInput in;
  in.imu = d.frame_imu(f);
  in.n_imu = kSamplesPerFrame;
  in.gnss = gnss;
  return in;
}

/// Initialises ex at the data start and ticks frames [0, f_end), delivering each epoch in the
/// tick of the frame that ends at its time tag.
template <class L>
bool run_executive(const FlightData& d, fsw::Executive<L>& ex, int f_end, std::string& err) {
  fsw::ExecutiveConfig cfg{};
  cfg.ekf = ekf_config();
  if (ex.init(cfg, d.init) != Status::kOk) {
    err = "Executive::init failed";
    return false;
  }
  fsw::FrameOutput out;
  for (int f = 0; f < f_end; ++f) {
    const bool epoch = (f + 1) % kFramesPerEkf == 0;
    const fsw::GnssEpoch* g = epoch ? &d.epochs[static_cast<std::size_t>((f + 1) / kFramesPerEkf - 1)] : nullptr;
    if (ex.tick(frame_input(d, f, g), out) != Status::kOk) {
      err = "Executive::tick failed";
      return false;
    }
  }
  // Every release's correction lands cfg.ekf_latency_frames later (fsw/executive.hpp).
  if (ex.health().fsw_errors != 0 ||
      ex.health().ekf_updates != static_cast<std::uint32_t>((f_end - cfg.ekf_latency_frames) / kFramesPerEkf)) {
    err = "executive warm-up: fsw errors or missed EKF updates";
    return false;
  }
  return true;
}

/// Executive::tick, a minor frame with 5 IMU samples and no 1 Hz group. The 199 frames between two
/// EKF steps are ticked in turn from a snapshot taken just after an EKF step; every block of 199
/// ticks is timed by hand and the snapshot restored (untimed) before the next.
template <class L>
void BM_ExecTickNav(benchmark::State& state) {
  const FlightData& d = flight();
  auto snap = std::make_unique<fsw::Executive<L>>();
  auto ex = std::make_unique<fsw::Executive<L>>();
  std::string err;
  // From just after the last correction landed to just before the next release.
  const int latency = fsw::ExecutiveConfig{}.ekf_latency_frames;
  const int f0 = kFramesPerEkf * kWarmCycles + latency;
  if (!d.error.empty() || !run_executive(d, *snap, f0, err)) return fail(state, d.error.empty() ? err : d.error);
  const int kBlock = kFramesPerEkf - 1 - latency;
  int k = 0;
  double total_s = 0.0;
  Clock::time_point t0;
  fsw::FrameOutput out;
  AllocScope allocs;
  for (auto _ : state) {
    if (k == 0) {
      *ex = *snap;
      t0 = Clock::now();
    }
    Status st = ex->tick(frame_input(d, f0 + k, nullptr), out);
    benchmark::DoNotOptimize(st);
    benchmark::DoNotOptimize(out);
    if (++k == kBlock) {
      benchmark::ClobberMemory();
      const double dt = seconds_since(t0);
      total_s += dt;
      state.SetIterationTime(dt);
      k = 0;
    } else {
      state.SetIterationTime(0.0);
    }
  }
  if (ex->health().ekf_runs != snap->health().ekf_runs) return fail(state, "the 1 Hz group ran in a nav-only tick");
  finish(state, allocs, 1.0, total_s);
}

/// Executive::tick for the minor frame in which the 1 Hz group runs: 5 IMU samples + mechanization
/// + accumulate, then propagate, update with the 10-satellite epoch delivered in this tick, and
/// feedback. On a fresh copy of the executive each iteration.
template <class L>
void BM_ExecTickEkf(benchmark::State& state) {
  const FlightData& d = flight();
  auto snap = std::make_unique<fsw::Executive<L>>();
  auto ex = std::make_unique<fsw::Executive<L>>();
  std::string err;
  const int f = FlightData::epoch_frame(kWarmCycles);  // the frame that closes the next 1 Hz interval
  if (!d.error.empty() || !run_executive(d, *snap, f, err)) return fail(state, d.error.empty() ? err : d.error);
  const fsw::GnssEpoch* g = &d.epochs[static_cast<std::size_t>(kWarmCycles)];
  const fsw::FrameInput in = frame_input(d, f, g);
  fsw::FrameOutput out;
  {
    // This tick releases the 1 Hz group and runs it inline; its correction (with the update's
    // report) lands ekf_latency_frames later.
    *ex = *snap;
    if (ex->tick(in, out) != Status::kOk || !out.ekf_released || ex->ekf_group_busy())
      return fail(state, "the EKF tick did not release and run the 1 Hz group");
    const int latency = fsw::ExecutiveConfig{}.ekf_latency_frames;
    for (int k = 1; k <= latency; ++k)
      if (ex->tick(frame_input(d, f + k, nullptr), out) != Status::kOk) return fail(state, "tick failed");
    if (!out.ekf_ran || !out.ekf_updated || out.report.pr_used != kSatellites || out.report.prr_used != kSatellites)
      return fail(state, "the EKF tick did not use the whole epoch");
  }
  AllocScope allocs;
  const double total_s = time_on_fresh_copies(state, *snap, *ex, [&](fsw::Executive<L>& e) {
    Status st = e.tick(in, out);
    benchmark::DoNotOptimize(st);
    benchmark::DoNotOptimize(out);
  });
  finish(state, allocs, 0.0, total_s);
}

// ------------------------------------------------------------------------------------------------

template <class L>
void register_layout() {
  const std::string n = LayoutName<L>::value;
  benchmark::RegisterBenchmark(("ekf_accumulate/" + n).c_str(), BM_EkfAccumulate<L>)->UseManualTime();
  benchmark::RegisterBenchmark(("ekf_propagate/" + n).c_str(), BM_EkfPropagate<L>)
      ->UseManualTime()
      ->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark(("ekf_update/" + n).c_str(), BM_EkfUpdate<L>)
      ->UseManualTime()
      ->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark(("ekf_update_1sat/" + n).c_str(), BM_EkfUpdateSats<L, 1>)
      ->UseManualTime()
      ->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark(("ekf_update_12sat/" + n).c_str(), BM_EkfUpdateSats<L, kMaxSatellites>)
      ->UseManualTime()
      ->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark(("exec_tick/" + n + "/nav").c_str(), BM_ExecTickNav<L>)->UseManualTime();
  benchmark::RegisterBenchmark(("exec_tick/" + n + "/ekf").c_str(), BM_ExecTickEkf<L>)
      ->UseManualTime()
      ->Unit(benchmark::kMicrosecond);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  // Wall-clock time everywhere (the hand-timed benchmarks use steady_clock): a frame budget is a
  // deadline in real time.
  benchmark::RegisterBenchmark("mech/frame_builder_add_x5", BM_FrameBuilderAdd5)->UseRealTime();
  benchmark::RegisterBenchmark("mech/strapdown_step", BM_StrapdownStep)->UseRealTime();
  benchmark::RegisterBenchmark("mech/frame", BM_MechFrame)->UseRealTime();
  benchmark::RegisterBenchmark("mech/strapdown_step_two_states", BM_StrapdownStepTwoStates)->UseRealTime();
  benchmark::RegisterBenchmark("libm/sin_dependent_x64", BM_SinDependent)->UseRealTime();
  benchmark::RegisterBenchmark("libm/sin_independent_x64", BM_SinIndependent)->UseRealTime();
  register_layout<fsw::Layout15>();
  register_layout<fsw::Layout24>();
  register_layout<fsw::Layout15Full>();
  register_layout<fsw::Layout24Full>();
  const FlightData& d = flight();  // prepared before any benchmark runs
  if (!d.error.empty()) {
    std::fprintf(stderr, "sdins_bench: flight data: %s\n", d.error.c_str());
    return 1;
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return g_setup_failed ? 1 : 0;
}
