// LcmLogSink writes a run's log; LcmReplayReader turns it back into time-ordered fsw inputs,
// bit-exact, with every bad input counted by reason.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <random>
#include <vector>

#include "fsw/gps_orbit.hpp"
#include "hal/lcm_log_sink.hpp"
#include "hal/lcm_types.hpp"
#include "lcm_test_util.hpp"
#include "sim/almanac.hpp"
#include "sim/gps_model.hpp"
#include "sim/scenario.hpp"
#include "sim/trajectory.hpp"

namespace {

using fsw::Vec3;
using lcm_test::bits_equal;
using lcm_test::encode;
using Kind = fsw::InputEvent::Kind;

hal::ImuRecord record(const fsw::InputEvent& e) { return hal::ImuRecord{e.imu, e.imu_counter, e.imu_status}; }

bool same_imu(const hal::ImuRecord& a, const hal::ImuRecord& b) {
  bool eq = bits_equal(a.sample.t_s, b.sample.t_s) && bits_equal(a.sample.dt_s, b.sample.dt_s) &&
            a.counter == b.counter && a.status == b.status;
  for (int i = 0; i < 3; ++i)
    eq = eq && bits_equal(a.sample.dtheta_rad[i], b.sample.dtheta_rad[i]) && bits_equal(a.sample.dv_mps[i], b.sample.dv_mps[i]);
  return eq;
}

bool same_gnss(const fsw::GnssRawEpoch& a, const fsw::GnssRawEpoch& b) {
  bool eq = bits_equal(a.t_s, b.t_s) && a.gps_week == b.gps_week && bits_equal(a.gps_tow_s, b.gps_tow_s) &&
            a.n_meas == b.n_meas;
  for (std::size_t k = 0; k < a.meas.size(); ++k)
    eq = eq && a.meas[k].prn == b.meas[k].prn && bits_equal(a.meas[k].pseudorange_m, b.meas[k].pseudorange_m) &&
         bits_equal(a.meas[k].pseudorange_rate_mps, b.meas[k].pseudorange_rate_mps) &&
         bits_equal(a.meas[k].cn0_dbhz, b.meas[k].cn0_dbhz);
  return eq;
}

hal::ImuRecord imu_at(int k) {
  hal::ImuRecord r;
  r.sample.t_s = 0.001 * (k + 1);
  r.sample.dt_s = 0.001;
  r.sample.dtheta_rad = Vec3(1e-5 * std::sin(0.01 * k), 2e-6, -3e-7 * k);
  r.sample.dv_mps = Vec3(1e-3, 2e-4, -9.80665e-3);
  r.counter = k;
  return r;
}

}  // namespace

// A simulated run written through LcmLogSink (almanac, 1 kHz IMU, 1 Hz raw GNSS epochs from the
// receiver model written 50 ms late, outputs and truth in between) replays as exactly the inputs
// that were written, in time order.
TEST(LcmReplay, SimulatedRunReplaysBitExactInputsInTimeOrder) {
  const sim::AlmanacParseResult alm = sim::parse_yuma_file(sim::default_almanac_path());
  ASSERT_TRUE(alm.ok()) << alm.error;
  sim::GpsModel gps(sim::GpsConfig{}, *alm.almanac, sim::EffectSet{}, 11);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 1.0);

  const std::string path = lcm_test::scratch("replay_sim.lcmlog");
  hal::LcmLogSink sink;
  ASSERT_EQ(lcm_test::open_log_only(sink, path), hal::LcmLogStatus::kOk);
  EXPECT_FALSE(sink.telemetry().network_active());

  std::vector<fsw::InputEvent> expected;  // in the order they must come back
  for (const fsw::GpsAlmanac& a : gps.almanac()) {
    ASSERT_EQ(sink.write_almanac(a, 0.0), hal::LcmLogStatus::kOk);
    fsw::InputEvent in;
    in.kind = Kind::kAlmanac;
    in.almanac = a;
    expected.push_back(in);
  }
  const int n_imu = 5000;
  std::vector<fsw::GnssRawEpoch> pending;  // written 50 samples after their time
  std::vector<int> pending_due;
  int nav_written = 0;
  for (int k = 0; k < n_imu; ++k) {
    hal::ImuRecord r;
    r.sample.t_s = 0.001 * (k + 1);
    r.sample.dt_s = 0.001;
    r.sample.dtheta_rad = Vec3(1e-6 * noise(rng), 3e-4 + 1e-6 * noise(rng), 1e-6 * noise(rng));
    r.sample.dv_mps = Vec3(2.5e-3 + 1e-5 * noise(rng), 1e-5 * noise(rng), 9.80665e-3 + 1e-5 * noise(rng));
    r.counter = k;
    ASSERT_EQ(sink.write_imu(r.sample), hal::LcmLogStatus::kOk);  // the sink's own counter: 0, 1, ...
    fsw::InputEvent in;
    in.kind = Kind::kImu;
    in.t_s = r.sample.t_s;
    in.imu = r.sample;
    in.imu_counter = r.counter;
    in.imu_status = r.status;
    expected.push_back(in);
    if ((k + 1) % 1000 == 0) {  // a receiver epoch at this sample's time
      sim::TruthSample ts;
      ts.t_s = r.sample.t_s;
      ts.llh = Vec3(0.61, 2.21, 3000.0 + k * 0.01);
      ts.vel_enu_mps = Vec3(200.0, 50.0, 0.0);
      fsw::GnssEpoch ep;
      gps.measure(ts, ep);
      fsw::GnssRawEpoch raw;
      gps.raw(ep, raw);
      raw.t_s = ts.t_s;
      ASSERT_GE(raw.n_meas, 4);
      pending.push_back(raw);
      pending_due.push_back(k + 50);
      fsw::InputEvent g;
      g.kind = Kind::kGnssRaw;
      g.t_s = raw.t_s;
      g.gnss = raw;
      expected.push_back(g);
    }
    for (std::size_t p = 0; p < pending.size(); ++p)
      if (pending_due[p] == k) ASSERT_EQ(sink.write_gnss(pending[p]), hal::LcmLogStatus::kOk);
    if (k % 5 == 4) {
      fsw::NavState nav;
      nav.t_s = r.sample.t_s;
      ASSERT_EQ(sink.write_nav(nav, true, false), hal::LcmLogStatus::kOk);
      ASSERT_EQ(sink.write_truth(nav.t_s, nav.llh, nav.vel_enu_mps, fsw::Mat3::Identity()), hal::LcmLogStatus::kOk);
      nav_written += 2;
    }
  }
  for (std::size_t p = 0; p < pending.size(); ++p)  // the last epoch is written after the last sample
    if (pending_due[p] >= n_imu) ASSERT_EQ(sink.write_gnss(pending[p]), hal::LcmLogStatus::kOk);
  ASSERT_EQ(sink.close(), hal::LcmLogStatus::kOk);
  // Equal times keep the written order (stable): expected is already in that order except for
  // the epochs, which were written after samples of the same or later time.
  std::stable_sort(expected.begin(), expected.end(),
                   [](const fsw::InputEvent& a, const fsw::InputEvent& b) { return a.t_s < b.t_s; });

  hal::LcmReplayReader rd;
  ASSERT_EQ(rd.open(path), hal::LcmLogStatus::kOk);
  fsw::InputEvent in;
  std::size_t n = 0;
  double last_t = -1.0;
  while (rd.next(in) == hal::LcmLogStatus::kOk) {
    ASSERT_LT(n, expected.size());
    const fsw::InputEvent& e = expected[n];
    ASSERT_GE(in.t_s, last_t) << "not time ordered at " << n;
    last_t = in.t_s;
    ASSERT_EQ(in.kind, e.kind) << "input " << n << " at t " << in.t_s;
    if (e.kind == Kind::kImu) ASSERT_TRUE(same_imu(record(in), record(e))) << n;
    if (e.kind == Kind::kGnssRaw) ASSERT_TRUE(same_gnss(in.gnss, e.gnss)) << n;
    if (e.kind == Kind::kAlmanac) ASSERT_EQ(std::memcmp(&in.almanac, &e.almanac, sizeof(e.almanac)), 0) << n;
    ++n;
  }
  EXPECT_EQ(n, expected.size());
  const hal::LcmReplayStats& st = rd.stats();
  EXPECT_EQ(st.imu.accepted(), static_cast<std::uint64_t>(n_imu));
  EXPECT_EQ(st.gnss.accepted(), 5u);
  EXPECT_EQ(st.almanac.accepted(), gps.almanac().size());
  EXPECT_EQ(st.other_events, static_cast<std::uint64_t>(nav_written));
  EXPECT_EQ(st.rejected(), 0u);
  EXPECT_EQ(st.imu_counter_gaps, 0u);
  EXPECT_EQ(rd.log_stats().total_rejections(), 0u);
  std::remove(path.c_str());
}

// Every kind of bad input in one log: each is counted under its reason, every good input is
// delivered in time order, nothing crashes.
TEST(LcmReplay, BadInputsAreCountedAndEveryGoodInputDelivered) {
  const std::string path = lcm_test::scratch("replay_bad.lcmlog");
  hal::LcmLogWriter w;
  ASSERT_EQ(w.open(path), hal::LcmLogStatus::kOk);
  const auto put = [&](const char* ch, const std::vector<std::uint8_t>& b) {
    ASSERT_EQ(w.write(ch, b.data(), b.size(), 0), hal::LcmLogStatus::kOk);
  };
  std::vector<int> good_counters;
  int counter = 0;
  for (int k = 0; k < 100; ++k) {
    hal::ImuRecord r = imu_at(k);
    r.counter = counter++;
    if (k == 60) counter += 3;  // three samples lost after this one
    sdins::imu_sample_t m{};
    hal::to_msg(r, m);
    std::vector<std::uint8_t> b = encode(m);
    if (k == 10) {
      m.dtheta_rad[1] = std::numeric_limits<double>::quiet_NaN();
      b = encode(m);
    } else if (k == 20) {
      sdins::nav_solution_t nav{};
      b = encode(nav);  // wrong type on the IMU channel
    } else if (k == 30) {
      b.resize(b.size() - 2);  // cut message
    } else if (k == 40) {
      m.status = sdins::imu_sample_t::STATUS_GYRO_INVALID;
      b = encode(m);
    } else if (k == 50) {
      m.dt_s = -0.001;
      b = encode(m);
    } else {
      good_counters.push_back(r.counter);
    }
    put(hal::kLcmChannelImu, b);
  }
  // GNSS: one epoch with n_meas out of range, one with a NaN measurement (kept, 1 dropped).
  fsw::GnssRawEpoch e;
  e.t_s = 0.05;
  e.gps_week = 2200;
  e.gps_tow_s = 1000.0;
  e.n_meas = 3;
  for (int k = 0; k < 3; ++k) {
    e.meas[static_cast<std::size_t>(k)].prn = static_cast<std::uint8_t>(k + 1);
    e.meas[static_cast<std::size_t>(k)].pseudorange_m = 2.2e7;
  }
  sdins::gnss_raw_epoch_t gm{};
  hal::to_msg(e, gm);
  gm.meas[1].pseudorange_rate_mps = std::numeric_limits<double>::infinity();
  put(hal::kLcmChannelGnssRaw, encode(gm));
  gm.n_meas = 20;
  put(hal::kLcmChannelGnssRaw, encode(gm));
  // Almanac: PRN 40 is out of range.
  sdins::gps_almanac_t am{};
  fsw::GpsAlmanac a;
  a.prn = 40;
  a.sqrt_a_sqrtm = 5153.6;
  hal::to_msg(a, 0.0, am);
  put(hal::kLcmChannelGpsAlmanac, encode(am));
  a.prn = 4;
  hal::to_msg(a, 0.0, am);
  put(hal::kLcmChannelGpsAlmanac, encode(am));
  // One more good sample after all the damage.
  hal::ImuRecord late = imu_at(200);
  late.counter = counter;
  sdins::imu_sample_t lm{};
  hal::to_msg(late, lm);
  put(hal::kLcmChannelImu, encode(lm));
  put("FOREIGN_CHANNEL", std::vector<std::uint8_t>(20, 0x42));
  ASSERT_EQ(w.close(), hal::LcmLogStatus::kOk);
  // A truncated last event.
  std::vector<std::uint8_t> bytes = lcm_test::read_bytes(path);
  const std::vector<std::uint8_t> first_event_start(bytes.begin(), bytes.begin() + 50);
  bytes.insert(bytes.end(), first_event_start.begin(), first_event_start.end());
  lcm_test::write_bytes(path, bytes);

  hal::LcmReplayReader rd;
  ASSERT_EQ(rd.open(path), hal::LcmLogStatus::kOk);
  fsw::InputEvent in;
  std::vector<int> got_counters;
  int gnss = 0, almanac = 0;
  double last_t = -1.0;
  while (rd.next(in) == hal::LcmLogStatus::kOk) {
    EXPECT_GE(in.t_s, last_t);
    last_t = in.t_s;
    if (in.kind == Kind::kImu) got_counters.push_back(in.imu_counter);
    if (in.kind == Kind::kGnssRaw) {
      ++gnss;
      EXPECT_EQ(in.gnss.n_meas, 2);
      EXPECT_EQ(in.gnss.meas[1].prn, 3);
    }
    if (in.kind == Kind::kAlmanac) {
      ++almanac;
      EXPECT_EQ(in.almanac.prn, 4);
    }
  }
  good_counters.push_back(late.counter);
  EXPECT_EQ(got_counters, good_counters);
  EXPECT_EQ(gnss, 1);
  EXPECT_EQ(almanac, 1);
  const hal::LcmReplayStats& st = rd.stats();
  EXPECT_EQ(st.imu.count(hal::LcmInputStatus::kNonFinite), 1u);
  EXPECT_EQ(st.imu.count(hal::LcmInputStatus::kWrongType), 1u);
  EXPECT_EQ(st.imu.count(hal::LcmInputStatus::kDecodeFailed), 1u);
  EXPECT_EQ(st.imu.count(hal::LcmInputStatus::kSensorFlagged), 1u);
  EXPECT_EQ(st.imu.count(hal::LcmInputStatus::kOutOfRange), 1u);
  EXPECT_EQ(st.imu.accepted(), 96u);
  EXPECT_EQ(st.gnss.count(hal::LcmInputStatus::kMeasurementsDropped), 1u);
  EXPECT_EQ(st.gnss.measurements_dropped, 1u);
  EXPECT_EQ(st.gnss.count(hal::LcmInputStatus::kOutOfRange), 1u);
  EXPECT_EQ(st.almanac.count(hal::LcmInputStatus::kOutOfRange), 1u);
  EXPECT_EQ(st.other_events, 1u);
  // Counter jumps: the three lost samples (after 60) and the holes of the five rejected ones.
  EXPECT_EQ(st.imu_counter_gaps, 6u);
  EXPECT_EQ(st.imu_counter_missing, 8u);
  EXPECT_EQ(rd.log_stats().count(hal::LcmLogRejection::kTruncatedEvent), 1u);
  std::remove(path.c_str());
}

// An input logged more than the reorder window after later inputs is dropped and counted; one
// within the window is put back in order.
TEST(LcmReplay, ReorderWindowSortsLateInputsAndCountsTooLateOnes) {
  const std::string path = lcm_test::scratch("replay_window.lcmlog");
  hal::LcmLogSink sink;
  ASSERT_EQ(lcm_test::open_log_only(sink, path), hal::LcmLogStatus::kOk);
  for (int k = 0; k < 3000; ++k) {
    if (k == 1500) {  // written at t = 1.5 s: epoch at 1.2 s (in the window), epoch at 0.3 s (too late)
      for (double t : {1.2, 0.3}) {
        fsw::GnssRawEpoch e;
        e.t_s = t;
        e.gps_tow_s = 100.0 + t;
        ASSERT_EQ(sink.write_gnss(e), hal::LcmLogStatus::kOk);
      }
    }
    ASSERT_EQ(sink.write_imu(imu_at(k).sample), hal::LcmLogStatus::kOk);
  }
  ASSERT_EQ(sink.close(), hal::LcmLogStatus::kOk);
  hal::LcmReplayReader rd;
  hal::LcmReplayConfig rc;
  rc.reorder_window_s = 1.0;
  ASSERT_EQ(rd.open(path, rc), hal::LcmLogStatus::kOk);
  fsw::InputEvent in;
  double last_t = -1.0;
  int n = 0;
  bool saw_epoch = false;
  while (rd.next(in) == hal::LcmLogStatus::kOk) {
    ASSERT_GE(in.t_s, last_t);
    last_t = in.t_s;
    if (in.kind == Kind::kGnssRaw) {
      EXPECT_EQ(in.t_s, 1.2);
      saw_epoch = true;
    }
    ++n;
  }
  EXPECT_TRUE(saw_epoch);
  EXPECT_EQ(n, 3001);
  EXPECT_EQ(rd.stats().time_tag_rejected, 1u);  // 1.2 s behind the newest: a backward time-tag outlier
  EXPECT_EQ(rd.stats().rejected(), 1u);
  std::remove(path.c_str());
}

// fuzz_lcm_log (fuzz/regressions/lcm_log/): a sample with a wild time tag (-1.5e305 s) logged
// after samples up to 0.1 s, before anything was returned. It lags far more than the window behind
// the newest input, so it is dropped and counted; it must not jump ahead of the good samples (it
// used to be returned first, because nothing had been returned yet when it was read).
TEST(LcmReplay, WildTimeTagBehindTheWindowIsDroppedEvenBeforeAnythingWasReturned) {
  const std::string path = lcm_test::scratch("replay_wild_time.lcmlog");
  hal::LcmLogSink sink;
  ASSERT_EQ(lcm_test::open_log_only(sink, path), hal::LcmLogStatus::kOk);
  for (int k = 0; k <= 100; ++k) ASSERT_EQ(sink.write_imu(imu_at(k)), hal::LcmLogStatus::kOk);
  hal::ImuRecord wild = imu_at(101);
  wild.sample.t_s = -1.4873979575313448e305;
  ASSERT_EQ(sink.write_imu(wild), hal::LcmLogStatus::kOk);
  hal::ImuRecord late_ok = imu_at(50);  // 0.05 s behind the newest: inside the 1 s window
  late_ok.counter = 102;
  ASSERT_EQ(sink.write_imu(late_ok), hal::LcmLogStatus::kOk);
  ASSERT_EQ(sink.close(), hal::LcmLogStatus::kOk);
  hal::LcmReplayReader rd;
  const std::vector<double> t = lcm_test::replayed_times(rd, path);
  ASSERT_EQ(t.size(), 102u);
  EXPECT_TRUE(std::is_sorted(t.begin(), t.end()));
  EXPECT_EQ(t.front(), imu_at(0).sample.t_s);
  EXPECT_EQ(rd.stats().time_tag_rejected, 1u);
  std::remove(path.c_str());
}

// The sink's log holds exactly the encoded message per channel, stamped with its utime.
TEST(LcmReplay, SinkWritesEncodedMessagesStampedWithNavigationTime) {
  const std::string path = lcm_test::scratch("sink.lcmlog");
  hal::LcmLogSink sink;
  ASSERT_EQ(lcm_test::open_log_only(sink, path), hal::LcmLogStatus::kOk);
  fsw::NavState nav;
  nav.t_s = 12.25;
  nav.llh = Vec3(0.5, 1.5, 100.0);
  ASSERT_EQ(sink.write_nav(nav, true, true), hal::LcmLogStatus::kOk);
  fsw::ExecutiveHealth h;
  h.ekf_runs = 12;
  fsw::FrameOutput frame;
  ASSERT_EQ(sink.write_health(12.25, h, fsw::GnssConversionStats{}, frame, 10.83), hal::LcmLogStatus::kOk);
  fsw::Ekf<fsw::Layout24Full> ekf;
  ASSERT_EQ(ekf.init(fsw::EkfConfig{}), fsw::Status::kOk);
  ASSERT_EQ(sink.write_ekf(ekf, fsw::ImuCompensation{}, 12.25), hal::LcmLogStatus::kOk);
  ASSERT_EQ(sink.close(), hal::LcmLogStatus::kOk);
  EXPECT_EQ(sink.telemetry().logged(), 3u);

  hal::LcmLogReader r;
  ASSERT_EQ(r.open(path), hal::LcmLogStatus::kOk);
  hal::LcmLogEvent ev;
  const char* channels[] = {hal::kLcmChannelNavSolution, hal::kLcmChannelFilterHealth, hal::kLcmChannelEkfState};
  for (const char* ch : channels) {
    ASSERT_EQ(r.next(ev), hal::LcmLogStatus::kOk);
    EXPECT_EQ(ev.channel, ch);
    EXPECT_EQ(ev.timestamp_us, 12250000);
    const hal::LcmTypeInfo* t = hal::lcm_channel_type(ch);
    ASSERT_NE(t, nullptr);
    double t_s = 0.0;
    EXPECT_EQ(t->time(ev.data, ev.data_len, t_s), hal::LcmInputStatus::kOk) << ch;
    EXPECT_EQ(t_s, 12.25);
  }
  EXPECT_EQ(r.next(ev), hal::LcmLogStatus::kEndOfLog);
  // Every message type fits the sink's encode buffer.
  EXPECT_LE(sdins::imu_sample_t{}.getEncodedSize(), static_cast<int>(hal::kLcmMaxEncodedBytes));
  EXPECT_LE(sdins::gnss_raw_epoch_t{}.getEncodedSize(), static_cast<int>(hal::kLcmMaxEncodedBytes));
  EXPECT_LE(sdins::gps_almanac_t{}.getEncodedSize(), static_cast<int>(hal::kLcmMaxEncodedBytes));
  EXPECT_LE(sdins::nav_solution_t{}.getEncodedSize(), static_cast<int>(hal::kLcmMaxEncodedBytes));
  EXPECT_LE(sdins::ekf_state_t{}.getEncodedSize(), static_cast<int>(hal::kLcmMaxEncodedBytes));
  EXPECT_LE(sdins::filter_health_t{}.getEncodedSize(), static_cast<int>(hal::kLcmMaxEncodedBytes));
  EXPECT_LE(sdins::truth_t{}.getEncodedSize(), static_cast<int>(hal::kLcmMaxEncodedBytes));
  EXPECT_EQ(sink.encode_failures(), 0u);
  std::remove(path.c_str());
}

// The heap orders by (time, arrival): inputs with the same time tag come out in the order they
// were written, whatever the heap does with its entries (a thousand pending inputs, the reorder
// window's). max_imu_samples is exact for a log of IMU samples alone.
TEST(LcmReplay, EqualTimeTagsKeepTheirWrittenOrderAndTheImuBoundIsExact) {
  const std::string path = lcm_test::scratch("replay_ties.lcmlog");
  ASSERT_NO_FATAL_FAILURE(lcm_test::write_imu_log(path, 2500, [](int k) {
    hal::ImuRecord r = imu_at(k);
    r.sample.t_s = 0.01 * (k / 10);  // ten samples to a time tag, told apart by their counters
    return r;
  }));
  EXPECT_EQ(hal::max_imu_samples(std::filesystem::file_size(path), hal::kLcmChannelImu), 2500u);
  hal::LcmReplayReader rd;
  hal::LcmReplayConfig rc;
  rc.reorder_window_s = 1.0;
  ASSERT_EQ(rd.open(path, rc), hal::LcmLogStatus::kOk);
  fsw::InputEvent in;
  int n = 0;
  while (rd.next(in) == hal::LcmLogStatus::kOk) {
    ASSERT_EQ(in.imu_counter, n) << "delivered out of written order";
    ++n;
  }
  EXPECT_EQ(n, 2500);
  EXPECT_EQ(rd.stats().rejected(), 0u);
  std::remove(path.c_str());
}
