// The fsw core must not touch the heap after initialisation. This binary replaces malloc/free and
// the global operator new/delete with counting versions; every steady-state fsw step runs with
// counting armed and the test fails on any allocation.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <memory>
#include <new>
#include <vector>

#include "fsw/alignment.hpp"
#include "fsw/executive.hpp"
#include "fsw/strapdown.hpp"
#include "sim/almanac.hpp"
#include "sim/gps_model.hpp"
#include "sim/imu_model.hpp"
#include "sim/scenario.hpp"
#include "sim/trajectory.hpp"
#include "tools/montecarlo.hpp"

extern "C" void* __libc_malloc(std::size_t);
extern "C" void* __libc_calloc(std::size_t, std::size_t);
extern "C" void* __libc_realloc(void*, std::size_t);
extern "C" void __libc_free(void*);

namespace {
std::atomic<bool> g_armed{false};
std::atomic<long> g_allocs{0};
inline void count() {
  if (g_armed.load(std::memory_order_relaxed)) g_allocs.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

extern "C" void* malloc(std::size_t n) {
  count();
  return __libc_malloc(n);
}
extern "C" void* calloc(std::size_t a, std::size_t b) {
  count();
  return __libc_calloc(a, b);
}
extern "C" void* realloc(void* p, std::size_t n) {
  count();
  return __libc_realloc(p, n);
}
extern "C" void free(void* p) { __libc_free(p); }

void* operator new(std::size_t n) {
  count();
  void* p = __libc_malloc(n ? n : 1);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
void* operator new[](std::size_t n) { return operator new(n); }
void operator delete(void* p) noexcept { __libc_free(p); }
void operator delete[](void* p) noexcept { __libc_free(p); }
void operator delete(void* p, std::size_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::size_t) noexcept { __libc_free(p); }

namespace {

struct Armed {
  Armed() {
    g_allocs = 0;
    g_armed = true;
  }
  ~Armed() { g_armed = false; }
};

TEST(NoAlloc, CountingAllocatorSeesAllocations) {
  // The instrument itself must work, or the other tests prove nothing.
  long n = 0;
  {
    Armed a;
    std::vector<int>* v = new std::vector<int>(100);
    void* m = std::malloc(16);
    std::free(m);
    delete v;
    n = g_allocs;
  }
  EXPECT_GE(n, 3);
}

TEST(NoAlloc, MechanizationAndAlignmentStepsDoNotAllocate) {
  // Inputs are prepared before arming: 20 s of the bank-to-turn flight, including a turn.
  sim::Scenario sc;
  sc.duration_s = 120.0;
  std::string err;
  auto motion = sim::FlightMotion::create(sc, err);
  ASSERT_TRUE(motion) << err;
  sim::TruthGenerator gen(*motion, 1000.0);
  std::vector<fsw::ImuSample> samples;
  samples.reserve(120000);
  for (int i = 0; i < 120000; ++i) {
    const sim::TruthSample& t = gen.next();
    samples.push_back({t.t_s, t.dt_s, t.dtheta_rad, t.dv_mps});
  }
  fsw::NavState init;
  init.llh = gen.current().llh;  // any valid state
  init.q_b_n = fsw::Quat::Identity();

  fsw::FrameBuilder fb;
  fsw::Strapdown sd;
  fsw::CoarseAlignment align;
  fsw::Mat3 C;
  ASSERT_EQ(fb.configure(5), fsw::Status::kOk);
  ASSERT_EQ(sd.init(init), fsw::Status::kOk);
  int frames = 0;
  fsw::ImuSample bad = samples[0];
  bad.dv_mps.x() = std::nan("");
  {
    Armed a;
    for (const fsw::ImuSample& s : samples) {
      align.add(s);
      if (fb.add(s) == fsw::Status::kOk) {
        sd.step(fb.frame());
        ++frames;
      }
    }
    fb.add(bad);  // the rejection path too
    align.solve(0.6, C);
    sd.correct(fsw::Vec3(1, 2, 3), fsw::Vec3(0.1, 0.1, 0.1), fsw::Vec3(1e-5, 1e-5, 1e-5));
  }
  EXPECT_EQ(frames, 24000);
  EXPECT_EQ(g_allocs.load(), 0) << "fsw steps allocated " << g_allocs.load() << " times";
}

// The whole executive (200 Hz and 1 Hz groups: mechanization, EKF accumulate, propagate, update
// with real GPS epochs, feedback) for every layout, on 60 s of the SIL inputs (truth -> IMU and GPS
// error models) prepared before arming.
struct SilInputs {
  std::vector<std::vector<fsw::ImuSample>> frames;
  std::vector<fsw::GnssEpoch> epochs;  ///< per frame; n_obs < 0: no epoch in that frame
  fsw::ExecutiveConfig cfg15, cfg24, cfg15full, cfg24full;
  fsw::NavState init;
};

SilInputs prepare_sil(double duration_s) {
  sim::Scenario sc;
  sc.duration_s = duration_s;
  const tools::TruthTrack truth = tools::TruthTrack::generate(sc);
  const sim::AlmanacParseResult alm = sim::parse_yuma_file(sim::almanac_path(sc.gps));
  EXPECT_TRUE(alm.ok()) << alm.error;
  SilInputs in;
  tools::MonteCarloConfig mc;
  mc.model_gps_errors = false;
  in.cfg15 = in.cfg24 = tools::executive_config(sc, mc);
  mc.model_gps_errors = true;
  in.cfg15full = in.cfg24full = tools::executive_config(sc, mc);
  const sim::ImuErrors errors = sim::draw_imu_errors(sc.imu, sc.effects, sc.seed);
  sim::ImuModel imu(errors, sc.seed);
  sim::GpsModel gps(sc.gps, *alm.almanac, sc.effects, sc.seed);
  in.init = tools::initial_nav_state(truth, errors, mc, sc.seed);
  const int spf = in.cfg15.imu_samples_per_frame;
  std::vector<fsw::ImuSample> frame;
  fsw::GnssEpoch none;
  none.n_obs = -1;
  for (std::size_t j = 0; j < truth.imu.size(); ++j) {
    sim::TruthSample ts;
    ts.t_s = truth.imu[j].t_s;
    ts.dt_s = truth.imu[j].dt_s;
    ts.dtheta_rad = truth.imu[j].dtheta_rad;
    ts.dv_mps = truth.imu[j].dv_mps;
    frame.push_back(imu.measure(ts));
    const bool is_epoch = (j + 1) % static_cast<std::size_t>(truth.samples_per_epoch) == 0;
    fsw::GnssEpoch e = none;
    if (is_epoch) gps.measure(truth.epochs[(j + 1) / static_cast<std::size_t>(truth.samples_per_epoch)], e);
    if (static_cast<int>(frame.size()) < spf) continue;
    in.frames.push_back(frame);
    in.epochs.push_back(e);
    frame.clear();
  }
  return in;
}

template <class Layout>
void fly_armed(const SilInputs& sil, const fsw::ExecutiveConfig& cfg, const char* name) {
  auto exec = std::make_unique<fsw::Executive<Layout>>();
  ASSERT_EQ(exec->init(cfg, sil.init), fsw::Status::kOk) << name;
  fsw::FrameOutput out;
  long ticks_ok = 0;
  {
    Armed a;
    for (std::size_t f = 0; f < sil.frames.size(); ++f) {
      fsw::FrameInput in;
      in.imu = sil.frames[f].data();
      in.n_imu = static_cast<int>(sil.frames[f].size());
      in.gnss = sil.epochs[f].n_obs >= 0 ? &sil.epochs[f] : nullptr;
      in.prev_tick_exec_s = 1e-6;
      if (exec->tick(in, out) == fsw::Status::kOk) ++ticks_ok;
    }
  }
  EXPECT_EQ(g_allocs.load(), 0) << name << ": the executive allocated " << g_allocs.load() << " times";
  EXPECT_EQ(ticks_ok, static_cast<long>(sil.frames.size())) << name;
  EXPECT_EQ(exec->health().fsw_errors, 0u) << name;
  EXPECT_GE(exec->health().ekf_updates, 59u) << name;  // every path really ran
  EXPECT_GT(exec->health().pr_used, 100u) << name;
  EXPECT_GT(exec->health().prr_used, 100u) << name;
}

TEST(NoAlloc, ExecutiveTicksWithEkfDoNotAllocateForAnyLayout) {
  const SilInputs sil = prepare_sil(60.0);
  ASSERT_EQ(sil.frames.size(), 12000u);
  fly_armed<fsw::Layout15>(sil, sil.cfg15, "Layout15");
  fly_armed<fsw::Layout24>(sil, sil.cfg24, "Layout24");
  fly_armed<fsw::Layout15Full>(sil, sil.cfg15full, "Layout15Full");
  fly_armed<fsw::Layout24Full>(sil, sil.cfg24full, "Layout24Full");
}

}  // namespace
