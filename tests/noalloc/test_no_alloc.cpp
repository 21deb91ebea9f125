// The fsw core must not touch the heap after initialisation. This binary replaces malloc/free and
// the global operator new/delete with counting versions; every steady-state fsw step runs with
// counting armed and the test fails on any allocation.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <vector>

#include "fsw/alignment.hpp"
#include "fsw/strapdown.hpp"
#include "hal/can_protocol.hpp"
#include "hal/can_rx_assembler.hpp"
#include "sim/scenario.hpp"
#include "sim/trajectory.hpp"

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

TEST(NoAlloc, CanCodecAndReceiveAssemblerDoNotAllocate) {
  // The flight side of the CAN bus: encoders, decoders and the receive assembler, including the
  // rejection paths (corrupted frame, unknown ID, counter gap, incomplete epoch).
  std::vector<fsw::ImuSample> samples(2000);
  for (std::size_t k = 0; k < samples.size(); ++k) {
    samples[k].t_s = 1e-3 * static_cast<double>(k + 1);
    samples[k].dt_s = 1e-3;
    samples[k].dtheta_rad = fsw::Vec3(1e-5, -2e-6, 3e-7 * static_cast<double>(k % 7));
    samples[k].dv_mps = fsw::Vec3(1e-4, 2e-5, -9.81e-3);
  }
  fsw::GnssRawEpoch epoch;
  epoch.t_s = 1.0;
  epoch.gps_week = 1455;
  epoch.gps_tow_s = 589825.0;
  epoch.n_meas = 8;
  for (int i = 0; i < 8; ++i) epoch.meas[static_cast<std::size_t>(i)] = {static_cast<std::uint8_t>(i + 1), 2.1e7 + i, 10.0, 40.0};
  fsw::GpsAlmanac alm;
  alm.prn = 3;
  alm.eccentricity = 0.01;
  alm.toa_s = 589824.0;
  alm.inclination_rad = 0.95;
  alm.sqrt_a_sqrtm = 5153.6;
  alm.week_mod_1024 = 431;
  auto* rx = new hal::CanRxAssembler();
  hal::can::ImuEncoder imu_enc;
  hal::can::GpsEncoder gps_enc;
  hal::CanFrame f, gps[hal::can::GpsEncoder::kMaxFrames];
  int delivered = 0, epochs = 0, alms = 0;
  {
    Armed a;
    for (std::size_t k = 0; k < samples.size(); ++k) {
      if (imu_enc.encode(samples[k], f) != hal::can::CodecStatus::kOk) continue;
      if (k == 500) f.data[20] ^= 1;  // corrupted
      if (k == 700) continue;         // lost: a counter gap
      if (k == 900) f.id = 0x123;     // unknown
      rx->push(f, 0.0);
      fsw::ImuSample s;
      while (rx->pop_imu(s)) ++delivered;
      if (k % 1000 == 999) {
        int n = 0, skipped = 0;
        gps_enc.encode(epoch, gps, n, skipped);
        for (int i = 0; i < n - (k == 999 ? 1 : 0); ++i) rx->push(gps[i], 0.0);  // first epoch incomplete
        hal::can::encode_gps_almanac(alm, f);
        rx->push(f, 0.0);
      }
    }
    rx->flush();
    fsw::GnssRawEpoch e;
    while (rx->pop_gps(e)) ++epochs;
    fsw::GpsAlmanac x;
    while (rx->pop_almanac(x)) ++alms;
  }
  EXPECT_EQ(g_allocs.load(), 0) << "CAN codec / assembler allocated " << g_allocs.load() << " times";
  EXPECT_EQ(delivered, 1997);
  EXPECT_EQ(epochs, 2);
  EXPECT_EQ(alms, 2);
  EXPECT_EQ(rx->health().bad_crc, 1u);
  EXPECT_EQ(rx->health().imu_missing, 3u);  // the corrupted, lost and unknown-ID samples
  EXPECT_EQ(rx->health().gps_epochs_incomplete, 1u);
  delete rx;
}

}  // namespace
