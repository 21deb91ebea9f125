// The fsw core must not touch the heap after initialisation. This binary replaces malloc/free and
// the global operator new/delete with counting versions; every steady-state fsw step runs with
// counting armed and the test fails on any allocation.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <memory>
#include <new>
#include <vector>

#include <unistd.h>

#include <cstdio>
#include <string>

#include "fsw/driver.hpp"
#include "fsw/alignment.hpp"
#include "fsw/ekf.hpp"
#include "fsw/executive.hpp"
#include "fsw/flight_app.hpp"
#include "sim/imu_model.hpp"
#include "fsw/gps_orbit.hpp"
#include "fsw/strapdown.hpp"
#include "hal/lcm_convert.hpp"
#include "hal/lcm_log_sink.hpp"
#include "sim/almanac.hpp"
#include "sim/gps_model.hpp"
#include "hal/can_protocol.hpp"
#include "hal/can_rx_assembler.hpp"
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

/// 120 s of the bank-to-turn flight (a whole turn) as the flight software receives it: 1 kHz IMU
/// samples and 1 Hz raw GPS epochs, prepared before counting is armed.
struct FlightInputs {
  std::vector<fsw::ImuSample> imu;
  std::vector<fsw::GnssRawEpoch> raw;  ///< raw[k] arrives with the frame ending at k + 1 s
  std::vector<sim::AlmanacEntry> almanac;
  std::vector<fsw::GnssPvtMeasurement> pvt;  ///< pvt[k]: the antenna at (k + 1) * 0.25 s
  fsw::NavState init{};
};

const FlightInputs& flight_inputs() {
  static const FlightInputs in = [] {
    FlightInputs f;
    sim::Scenario sc;
    sc.duration_s = 121.0;
    std::string err;
    auto motion = sim::FlightMotion::create(sc, err);
    EXPECT_TRUE(motion) << err;
    const sim::AlmanacParseResult alm = sim::parse_yuma_file(sim::default_almanac_path());
    EXPECT_TRUE(alm.ok()) << alm.error;
    f.almanac = *alm.almanac;
    sim::GpsModel gps(sc.gps, f.almanac, sc.effects, 1);
    sim::TruthGenerator gen(*motion, 1000.0);
    f.init.t_s = gen.current().t_s;
    f.init.llh = gen.current().llh;
    f.init.vel_enu_mps = gen.current().vel_enu_mps;
    f.init.q_b_n = fsw::Quat(gen.current().C_b_n);
    for (int i = 0; i < 120000; ++i) {
      const sim::TruthSample& t = gen.next();
      f.imu.push_back({t.t_s, t.dt_s, t.dtheta_rad, t.dv_mps});
      if ((i + 1) % 1000 == 0) {
        fsw::GnssEpoch e;
        gps.measure(t, e);
        fsw::GnssRawEpoch r;
        gps.raw(e, r);
        f.raw.push_back(r);
      }
      if ((i + 1) % 250 == 0) {
        fsw::GnssPvtMeasurement m;
        m.t_s = t.t_s;
        sim::antenna_truth(t, fsw::Vec3::Zero(), m.llh, m.vel_enu_mps);
        m.pos_sigma_enu_m = fsw::Vec3::Constant(0.5);
        m.vel_sigma_enu_mps = fsw::Vec3::Constant(0.05);
        m.has_velocity = true;
        m.quality = 5;
        m.n_sat = 8;
        f.pvt.push_back(m);
      }
    }
    return f;
  }();
  return in;
}

/// Loads table with the flight's almanac and ticks exec through its IMU samples five to a frame,
/// with the raw epoch of each whole second converted (the executive's position as the hint) and
/// delivered in the frame that ends at it. add(fi, ms) may add to the frame that ends at ms
/// milliseconds before its tick; done(out) sees each tick's output. Counted: runs armed.
template <class Layout, class Add, class Done>
void tick_flight(const FlightInputs& in, fsw::Executive<Layout>& exec, fsw::GpsAlmanacTable& table, Add add, Done done) {
  table.clear();
  for (const auto& e : in.almanac) table.set(e);
  fsw::GnssEpoch epoch;
  fsw::GnssConversionStats conv;
  fsw::FrameOutput out;
  for (std::size_t k = 0; k + 5 <= in.imu.size(); k += 5) {
    fsw::FrameInput fi;
    fi.imu = &in.imu[k];
    fi.n_imu = 5;
    const std::size_t ms = k + 5;
    if (ms % 1000 == 0) {
      const fsw::Vec3 hint = exec.ins().state().llh;
      if (fsw::gnss_epoch_from_raw(in.raw[ms / 1000 - 1], table, &hint, epoch, conv) == fsw::Status::kOk)
        fi.gnss = &epoch;
    }
    add(fi, ms);
    exec.tick(fi, out);
    done(out);
  }
}

/// Feeds app the flight's IMU samples, each solution 20 ms after its time (before the first IMU
/// sample that late). Counted: runs armed.
template <class App>
void feed_app(const FlightInputs& in, App& app) {
  fsw::FrameOutput out;
  std::size_t next = 0;
  for (const fsw::ImuSample& s : in.imu) {
    while (next < in.pvt.size() && in.pvt[next].t_s <= s.t_s - 0.02) app.on_gnss_pvt(in.pvt[next++]);
    app.on_imu(s, out);
  }
}

template <class Layout>
void fly_executive_without_allocating() {
  const FlightInputs& in = flight_inputs();
  ASSERT_EQ(in.raw.size(), 120u);
  // The executive and the almanac table are static storage, as on the target.
  static fsw::Executive<Layout> exec;
  static fsw::GpsAlmanacTable table;
  ASSERT_EQ(exec.init(fsw::ExecutiveConfig{}, in.init), fsw::Status::kOk);
  fsw::ImuSample bad = in.imu[0];
  bad.dtheta_rad.y() = std::nan("");
  fsw::GnssRawEpoch bad_epoch = in.raw[0];
  bad_epoch.n_meas = 99;
  int updates = 0;
  {
    Armed a;
    tick_flight(
        in, exec, table, [](fsw::FrameInput&, std::size_t) {},
        [&updates](const fsw::FrameOutput& out) {
          if (out.ekf_updated) ++updates;
        });
    // Rejection paths.
    fsw::FrameInput fi;
    fi.imu = &bad;
    fi.n_imu = 1;
    fsw::FrameOutput out;
    exec.tick(fi, out);
    fsw::GnssEpoch epoch;
    fsw::GnssConversionStats conv;
    fsw::gnss_epoch_from_raw(bad_epoch, table, nullptr, epoch, conv);
  }
  EXPECT_GE(updates, 110);
  EXPECT_EQ(exec.health().fsw_errors, 0u);
  EXPECT_EQ(g_allocs.load(), 0) << "executive (" << Layout::kSize << " states) allocated " << g_allocs.load()
                                << " times";
}

/// The loosely coupled path: 4 Hz solutions (frames_per_ekf 50) and 1 Hz raw epochs through the
/// executive (solution updates, raw epochs winning over simultaneous solutions, an invalid one),
/// then the flight application initialising from a solution and updating with the rest.
template <class Layout>
void fly_pvt_without_allocating() {
  const FlightInputs& in = flight_inputs();
  ASSERT_EQ(in.pvt.size(), 480u);
  static fsw::Executive<Layout> exec;
  static fsw::GpsAlmanacTable table;
  fsw::ExecutiveConfig cfg;
  cfg.frames_per_ekf = 50;
  ASSERT_EQ(exec.init(cfg, in.init), fsw::Status::kOk);
  fsw::GnssPvtMeasurement bad = in.pvt[0];
  bad.t_s = std::nan("");
  int pvt_updates = 0;
  long n_exec = 0;
  {
    Armed a;
    tick_flight(
        in, exec, table,
        [&in, &bad](fsw::FrameInput& fi, std::size_t ms) {
          if (ms % 250 == 0) fi.pvt = &in.pvt[ms / 250 - 1];
          if (ms == 60000) fi.pvt = &bad;
        },
        [&pvt_updates](const fsw::FrameOutput& out) {
          if (out.ekf_updated && out.report.pvt) ++pvt_updates;
        });
    n_exec = g_allocs;
  }
  EXPECT_GE(pvt_updates, 300);
  EXPECT_GE(exec.health().pvt_unused, 100u);
  EXPECT_EQ(exec.health().pvt_invalid, 1u);
  EXPECT_EQ(exec.health().fsw_errors, 0u);
  EXPECT_EQ(n_exec, 0) << "executive with solutions (" << Layout::kSize << " states) allocated " << n_exec << " times";
}

TEST(NoAlloc, PvtUpdatesDoNotAllocate15) { fly_pvt_without_allocating<fsw::Layout15>(); }
TEST(NoAlloc, PvtUpdatesDoNotAllocate24) { fly_pvt_without_allocating<fsw::Layout24>(); }
TEST(NoAlloc, PvtUpdatesDoNotAllocate24Full) { fly_pvt_without_allocating<fsw::Layout24Full>(); }
TEST(NoAlloc, PvtUpdatesDoNotAllocateDiag) { fly_pvt_without_allocating<fsw::LayoutDiag>(); }

TEST(NoAlloc, FlightAppOnGnssPvtDoesNotAllocate) {
  const FlightInputs& in = flight_inputs();
  static fsw::FlightApp<fsw::Layout24Full> app;
  fsw::FlightAppConfig cfg;
  cfg.exec.frames_per_ekf = 50;
  ASSERT_EQ(app.init(cfg), fsw::Status::kOk);
  fsw::GnssPvtMeasurement bad = in.pvt[0];
  bad.quality = 0;
  {
    Armed a;
    feed_app(in, app);
    app.on_gnss_pvt(bad);
  }
  EXPECT_TRUE(app.initialised());
  EXPECT_EQ(app.health().pvt_rejected, 1u);
  EXPECT_GE(app.executive().health().pos_used, 900u);
  EXPECT_EQ(g_allocs.load(), 0) << "FlightApp::on_gnss_pvt path allocated " << g_allocs.load() << " times";
}

// The one driver loop (fsw/driver.hpp) as the image and the Monte Carlo run it: a batch of events
// per minor frame through a FlightDriver with an observer, nothing allocated.
TEST(NoAlloc, DriverLoopDoesNotAllocate) {
  const FlightInputs& in = flight_inputs();
  static fsw::FlightDriver<fsw::Layout24Full> driver;
  static fsw::EventBatch<16> batch;
  fsw::FlightAppConfig cfg;
  cfg.exec.frames_per_ekf = 50;
  ASSERT_EQ(driver.init(cfg), fsw::Status::kOk);
  std::uint64_t frames = 0;
  auto count = fsw::after_each([&frames](const fsw::InputEvent& ev, fsw::Status, const fsw::FrameOutput& out) {
    if (ev.kind == fsw::InputEvent::Kind::kImu && out.nav_valid) ++frames;  // out is an IMU event's
  });
  std::uint64_t delivered = 0;
  {
    Armed a;
    std::size_t next = 0, k = 0;
    while (k < in.imu.size()) {
      batch.clear();
      for (int n = 0; n < 5 && k < in.imu.size(); ++n) {
        while (next < in.pvt.size() && in.pvt[next].t_s <= in.imu[k].t_s - 0.02 && !batch.full()) {
          *batch.slot() = fsw::InputEvent::of_pvt(in.pvt[next++]);
          batch.commit();
        }
        *batch.slot() = fsw::InputEvent::of_imu(in.imu[k++]);
        batch.commit();
      }
      delivered += fsw::drive(batch, driver, count);
    }
  }
  EXPECT_TRUE(driver.app().initialised());
  EXPECT_GE(driver.app().executive().health().pos_used, 900u);
  EXPECT_EQ(frames, driver.app().executive().health().nav_frames);
  EXPECT_EQ(delivered, in.imu.size() + driver.app().health().pvt_received);
  EXPECT_EQ(g_allocs.load(), 0) << "the driver loop allocated " << g_allocs.load() << " times";
}

// The alignment modes before initialisation: IMU samples into the stationary window and the
// velocity-matching integration, solutions through the rest test, the Wahba solve and the
// initialisation (velocity matching: at the first turn; static: the aircraft never rests).
void fly_app_init_mode_without_allocating(fsw::InitMode mode) {
  const FlightInputs& in = flight_inputs();
  static fsw::FlightApp<fsw::Layout24Full> app;
  fsw::FlightAppConfig cfg;
  cfg.exec.frames_per_ekf = 50;
  cfg.init_mode = mode;
  ASSERT_EQ(app.init(cfg), fsw::Status::kOk);
  {
    Armed a;
    feed_app(in, app);
  }
  if (mode == fsw::InitMode::kVelocityMatching) {
    EXPECT_TRUE(app.initialised());
    EXPECT_GE(app.health().init_align_restarts, 1u);
  } else {
    EXPECT_FALSE(app.initialised());
    EXPECT_GE(app.health().init_moving, 400u);
  }
  EXPECT_EQ(g_allocs.load(), 0) << fsw::to_string(mode) << " initialisation allocated";
}

TEST(NoAlloc, FlightAppVelocityMatchingDoesNotAllocate) {
  fly_app_init_mode_without_allocating(fsw::InitMode::kVelocityMatching);
}
TEST(NoAlloc, FlightAppStaticAlignmentDoesNotAllocate) { fly_app_init_mode_without_allocating(fsw::InitMode::kStatic); }

TEST(NoAlloc, ExecutiveWithEkfDoesNotAllocate15) { fly_executive_without_allocating<fsw::Layout15>(); }
TEST(NoAlloc, ExecutiveWithEkfDoesNotAllocate24) { fly_executive_without_allocating<fsw::Layout24>(); }
TEST(NoAlloc, ExecutiveWithEkfDoesNotAllocate15Full) { fly_executive_without_allocating<fsw::Layout15Full>(); }
TEST(NoAlloc, ExecutiveWithEkfDoesNotAllocate24Full) { fly_executive_without_allocating<fsw::Layout24Full>(); }

// The flight side of LCM telemetry: encoding every output message into the sink's buffer,
// publishing it on udpm (when multicast can be created here) and writing it to the log, and the
// input side's decode + validation, all without touching the heap once the sink is open and
// warmed up (the first write allocates stdio's file buffer).
TEST(NoAlloc, LcmSinkAndInputDecodingDoNotAllocate) {
  const std::string log = "/tmp/sdins_noalloc_" + std::to_string(::getpid()) + ".lcmlog";
  hal::LcmLogSink sink;
  hal::LcmTelemetryConfig cfg;
  cfg.lcm_url = "udpm://239.255.76.67:" + std::to_string(23000 + ::getpid() % 20000) + "?ttl=0";
  cfg.log_path = log;
  ASSERT_EQ(sink.open(cfg), hal::LcmLogStatus::kOk);
  fsw::Ekf<fsw::Layout24Full> ekf;
  ASSERT_EQ(ekf.init(fsw::EkfConfig{}), fsw::Status::kOk);
  fsw::ImuCompensation comp;
  fsw::NavState nav;
  nav.llh = fsw::Vec3(0.6, 2.2, 1000.0);
  fsw::ExecutiveHealth health;
  fsw::FrameOutput frame;
  frame.report.n_obs = 8;
  fsw::GnssRawEpoch raw;
  raw.n_meas = 8;
  raw.gps_tow_s = 1000.0;
  fsw::ImuSample imu{0.001, 0.001, fsw::Vec3(1e-5, 2e-5, 3e-5), fsw::Vec3(1e-3, 0.0, -9.8e-3)};
  sdins::imu_sample_t imu_msg{};
  hal::to_msg(hal::ImuRecord{imu, 0, 0}, imu_msg);
  std::uint8_t imu_bytes[256];
  const int imu_len = imu_msg.encode(imu_bytes, 0, sizeof(imu_bytes));
  ASSERT_GT(imu_len, 0);
  const auto one_round = [&]() {
    sink.write_imu(imu);
    sink.write_gnss(raw);
    sink.write_nav(nav, true, false);
    sink.write_ekf(ekf, comp, nav.t_s);
    sink.write_health(nav.t_s, health, fsw::GnssConversionStats{}, frame, 10.83);
    sink.write_truth(nav.t_s, nav.llh, nav.vel_enu_mps, fsw::Mat3::Identity());
    sdins::imu_sample_t in{};
    hal::ImuRecord rec;
    hal::decode_exact(imu_bytes, static_cast<std::size_t>(imu_len), in);
    hal::from_msg(in, rec);
  };
  one_round();  // warm-up: stdio buffer, LCM's first send
  long n = 0;
  {
    Armed a;
    for (int k = 0; k < 200; ++k) one_round();
    n = g_allocs;
  }
  EXPECT_EQ(n, 0) << "LCM sink / input decoding allocated " << n << " times (network "
                  << (sink.telemetry().network_active() ? "on" : "off") << ")";
  EXPECT_EQ(sink.telemetry().logged(), 201u * 6u);
  std::printf("LCM sink: udpm %s, %llu messages published, %llu logged\n",
              sink.telemetry().network_active() ? "on" : "unavailable (log only)",
              static_cast<unsigned long long>(sink.telemetry().published()),
              static_cast<unsigned long long>(sink.telemetry().logged()));
  sink.close();
  std::remove(log.c_str());
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
