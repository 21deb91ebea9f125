// Receiver-side conversion of raw measurements (fsw/gps_orbit.hpp): the simulator's raw output
// (satellite clock put back) converted by the flight code gives back the simulator's epoch;
// almanac validation; every rejected measurement is counted, never silently dropped.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "fsw/gps_orbit.hpp"
#include "sim/almanac.hpp"
#include "sim/gps_model.hpp"
#include "sim/scenario.hpp"
#include "sim/trajectory.hpp"
#include "test_util.hpp"

namespace {

using test_util::shipped_almanac;

using fsw::kDegToRad;
using fsw::Vec3;


fsw::GpsAlmanacTable table_of(const std::vector<sim::AlmanacEntry>& alm) {
  fsw::GpsAlmanacTable t;
  for (const auto& a : alm) EXPECT_EQ(t.set(a), fsw::Status::kOk) << a.prn;
  return t;
}

sim::TruthSample at_site(double t_s) {
  sim::TruthSample s;
  s.t_s = t_s;
  s.llh = Vec3(35.0 * kDegToRad, 127.0 * kDegToRad, 5000.0);
  s.C_b_n = fsw::Mat3::Identity();
  s.vel_enu_mps = Vec3(180.0, 170.0, 0.0);
  return s;
}

TEST(GnssRaw, RoundTripThroughTheReceiverConversionGivesTheSimulatorsEpoch) {
  const auto alm = shipped_almanac();
  ASSERT_FALSE(alm.empty());
  // Make the satellite clocks large enough to matter (1 ms, 1e-9 s/s) so the test sees them.
  std::vector<sim::AlmanacEntry> alm_clk = alm;
  for (auto& a : alm_clk) {
    a.af0_s = 1e-3 * (a.prn % 3 - 1);
    a.af1_sps = 1e-9 * (a.prn % 2 ? 1 : -1);
  }
  sim::GpsModel model(sim::GpsConfig{}, alm_clk, sim::EffectSet{}, 7);
  const fsw::GpsAlmanacTable table = table_of(alm_clk);
  for (double t : {0.0, 1.0, 600.0}) {
    fsw::GnssEpoch truth_epoch;
    model.measure(at_site(t), truth_epoch);
    ASSERT_GE(truth_epoch.n_obs, 5);
    fsw::GnssRawEpoch raw;
    model.raw(truth_epoch, raw);
    ASSERT_EQ(raw.n_meas, truth_epoch.n_obs);
    // The raw pseudorange really carries the satellite clock.
    bool differs = false;
    for (int i = 0; i < raw.n_meas; ++i) {
      differs |= std::abs(raw.meas[i].pseudorange_m - truth_epoch.obs[i].pseudorange_m) > 1e4;
    }
    EXPECT_TRUE(differs);
    fsw::GnssEpoch back;
    fsw::GnssConversionStats stats;
    const Vec3 hint = at_site(t).llh;
    ASSERT_EQ(fsw::gnss_epoch_from_raw(raw, table, &hint, back, stats), fsw::Status::kOk);
    ASSERT_EQ(back.n_obs, truth_epoch.n_obs);
    EXPECT_EQ(back.gps_week, truth_epoch.gps_week);
    // The raw time tag is on the receiver clock: GPS time + bias / c.
    EXPECT_NEAR(back.gps_tow_s, truth_epoch.gps_tow_s + model.clock().bias_m / fsw::kSpeedOfLight_mps, 1e-12);
    EXPECT_NE(back.gps_tow_s, truth_epoch.gps_tow_s);
    for (int i = 0; i < back.n_obs; ++i) {
      const auto& a = truth_epoch.obs[i];
      const auto& b = back.obs[i];
      EXPECT_EQ(a.prn, b.prn);
      // Transmit time from tow - rho/c instead of the exact flight time: the receiver clock bias
      // (tens of m) moves the satellite by far less than a millimetre.
      EXPECT_LT((a.sat_pos_ecef_m - b.sat_pos_ecef_m).norm(), 1e-3) << int(a.prn);
      EXPECT_LT((a.sat_vel_ecef_mps - b.sat_vel_ecef_mps).norm(), 1e-6);
      // af1 (here 1e-9 s/s, real ones are < 1e-11) times the 1 ms shift of the clock epoch.
      EXPECT_NEAR(a.pseudorange_m, b.pseudorange_m, 1e-3);
      EXPECT_NEAR(a.pseudorange_rate_mps, b.pseudorange_rate_mps, 1e-6);
      // Informational elevation: the flight code does not rotate the transmit-time position into
      // the receive-time frame (Earth rotation during ~70 ms flight: ~5 urad).
      EXPECT_NEAR(a.elevation_rad, b.elevation_rad, 1e-5);
    }
    EXPECT_EQ(stats.invalid + stats.no_almanac + stats.unhealthy + stats.duplicate_prn, 0u);
  }
}

TEST(GnssRaw, EveryUnusableMeasurementIsCountedAndTheRestKept) {
  const auto alm = shipped_almanac();
  fsw::GpsAlmanacTable table = table_of(alm);
  sim::GpsModel model(sim::GpsConfig{}, alm, sim::EffectSet{}, 3);
  fsw::GnssEpoch e;
  model.measure(at_site(10.0), e);
  fsw::GnssRawEpoch raw;
  model.raw(e, raw);
  ASSERT_GE(raw.n_meas, 6);
  const int n0 = raw.n_meas;
  raw.meas[0].pseudorange_m = std::numeric_limits<double>::quiet_NaN();
  raw.meas[1].pseudorange_rate_mps = std::numeric_limits<double>::infinity();
  raw.meas[2].prn = 0;
  raw.meas[n0] = raw.meas[3];  // duplicate PRN
  raw.n_meas = n0 + 1;
  // A PRN with no almanac and an unhealthy one.
  fsw::GpsAlmanacTable partial;
  for (const auto& a : alm) {
    if (a.prn == raw.meas[4].prn) continue;
    sim::AlmanacEntry b = a;
    if (a.prn == raw.meas[5].prn) b.health = 63;
    ASSERT_EQ(partial.set(b), fsw::Status::kOk);
  }
  fsw::GnssEpoch out;
  fsw::GnssConversionStats st;
  ASSERT_EQ(fsw::gnss_epoch_from_raw(raw, partial, nullptr, out, st), fsw::Status::kOk);
  EXPECT_EQ(st.invalid, 3u);
  EXPECT_EQ(st.duplicate_prn, 1u);
  EXPECT_EQ(st.no_almanac, 1u);
  EXPECT_EQ(st.unhealthy, 1u);
  EXPECT_EQ(out.n_obs, n0 - 5);
  for (int i = 0; i < out.n_obs; ++i) EXPECT_EQ(out.obs[i].elevation_rad, 0.0);  // no hint given

  // Malformed epochs: rejected whole, output empty.
  for (int bad = 0; bad < 4; ++bad) {
    fsw::GnssRawEpoch r = raw;
    if (bad == 0) r.n_meas = fsw::kMaxGnssChannels + 1;
    if (bad == 1) r.n_meas = -1;
    if (bad == 2) r.gps_tow_s = std::numeric_limits<double>::quiet_NaN();
    if (bad == 3) r.gps_tow_s = fsw::kSecondsPerWeek;
    EXPECT_EQ(fsw::gnss_epoch_from_raw(r, table, nullptr, out, st), fsw::Status::kBadInput) << bad;
    EXPECT_EQ(out.n_obs, 0);
  }
}

TEST(GnssRaw, TransmitTimeBeforeTheWeekStartUsesThePreviousWeek) {
  const auto alm = shipped_almanac();
  const fsw::GpsAlmanacTable table = table_of(alm);
  fsw::GnssRawEpoch raw;
  raw.gps_week = 2000;
  raw.gps_tow_s = 0.01;  // signal sent about 70 ms earlier: in week 1999
  raw.n_meas = 1;
  raw.meas[0].prn = static_cast<std::uint8_t>(alm.front().prn);
  raw.meas[0].pseudorange_m = 2.1e7;
  fsw::GnssEpoch out;
  fsw::GnssConversionStats st;
  ASSERT_EQ(fsw::gnss_epoch_from_raw(raw, table, nullptr, out, st), fsw::Status::kOk);
  ASSERT_EQ(out.n_obs, 1);
  Vec3 r, v;
  const double tow_tx = fsw::kSecondsPerWeek + 0.01 - 2.1e7 / fsw::kSpeedOfLight_mps -
                        fsw::satellite_clock_bias_s(alm.front(), 1999, fsw::kSecondsPerWeek - 0.06);
  fsw::satellite_pv_ecef(alm.front(), 1999, tow_tx, r, v);
  EXPECT_LT((r - out.obs[0].sat_pos_ecef_m).norm(), 1e-3);
}

// The one week wrap (fsw::gps_time): the flight software's transmit times and the simulator's
// receive times, receiver time tags and transmit times.
TEST(GpsTime, WithinAWeekUnchanged) {
  const fsw::GpsTime a = fsw::gps_time(1455, 12345.678);
  EXPECT_EQ(a.week, 1455);
  EXPECT_EQ(a.tow_s, 12345.678);  // bit for bit: the digests depend on it
  const fsw::GpsTime b = fsw::gps_time(1455, 0.0);
  EXPECT_EQ(b.week, 1455);
  EXPECT_EQ(b.tow_s, 0.0);
  const double last = std::nextafter(fsw::kSecondsPerWeek, 0.0);
  const fsw::GpsTime c = fsw::gps_time(1455, last);
  EXPECT_EQ(c.week, 1455);
  EXPECT_EQ(c.tow_s, last);
}

TEST(GpsTime, CrossingTheWeekEndCarriesIntoTheNextWeek) {
  constexpr double kW = fsw::kSecondsPerWeek;
  const fsw::GpsTime end = fsw::gps_time(1455, kW);  // the week's end is the next week's start
  EXPECT_EQ(end.week, 1456);
  EXPECT_EQ(end.tow_s, 0.0);
  const fsw::GpsTime after = fsw::gps_time(1455, kW + 0.05);
  EXPECT_EQ(after.week, 1456);
  EXPECT_NEAR(after.tow_s, 0.05, 1e-9);
  const fsw::GpsTime weeks = fsw::gps_time(1023, 3.0 * kW + 5.0);  // across the 1024-week rollover too
  EXPECT_EQ(weeks.week, 1026);
  EXPECT_EQ(weeks.tow_s, 5.0);
}

TEST(GpsTime, NegativeTimeBelongsToThePreviousWeeks) {
  constexpr double kW = fsw::kSecondsPerWeek;
  // A transmit time 70 ms before the week's start (tow - rho / c at tow 0.01 s).
  const fsw::GpsTime tx = fsw::gps_time(2000, 0.01 - 0.08);
  EXPECT_EQ(tx.week, 1999);
  EXPECT_NEAR(tx.tow_s, kW - 0.07, 1e-9);
  const fsw::GpsTime two = fsw::gps_time(2000, -2.0 * kW + 5.0);
  EXPECT_EQ(two.week, 1998);
  EXPECT_EQ(two.tow_s, 5.0);
  const fsw::GpsTime more = fsw::gps_time(2000, -2.0 * kW - 5.0);
  EXPECT_EQ(more.week, 1997);
  EXPECT_EQ(more.tow_s, kW - 5.0);
}

TEST(GpsTime, RoundingAtTheBoundaryStaysInsideTheWeek) {
  constexpr double kW = fsw::kSecondsPerWeek;
  // -1e-12 s plus a week rounds to 604800.0: the time is the week's start at this resolution.
  const fsw::GpsTime tiny = fsw::gps_time(100, -1e-12);
  EXPECT_EQ(tiny.week, 100);
  EXPECT_EQ(tiny.tow_s, 0.0);
  for (const double x : {-1e-12, -1e-300, -std::numeric_limits<double>::denorm_min(), -0.0, std::nextafter(kW, 0.0),
                         std::nextafter(2.0 * kW, 0.0), std::nextafter(-kW, 0.0), -kW, 52.0 * kW - 1e-6}) {
    const fsw::GpsTime t = fsw::gps_time(100, x);
    EXPECT_GE(t.tow_s, 0.0) << x;
    EXPECT_LT(t.tow_s, kW) << x;
    EXPECT_NEAR((t.week - 100) * kW + t.tow_s, x, 1e-6) << x;  // the same instant
  }
}

TEST(GnssRaw, AlmanacTableRejectsCorruptElements) {
  const auto alm = shipped_almanac();
  fsw::GpsAlmanacTable t;
  sim::AlmanacEntry a = alm.front();
  EXPECT_EQ(t.set(a), fsw::Status::kOk);
  EXPECT_EQ(t.count(), 1);
  EXPECT_EQ(t.set(a), fsw::Status::kOk);  // replacing keeps the count
  EXPECT_EQ(t.count(), 1);
  const auto reject = [&](auto mutate) {
    sim::AlmanacEntry b = alm.back();
    mutate(b);
    EXPECT_EQ(t.set(b), fsw::Status::kBadInput);
  };
  reject([](auto& b) { b.prn = 33; });
  reject([](auto& b) { b.prn = 0; });
  reject([](auto& b) { b.eccentricity = 1.0; });
  reject([](auto& b) { b.sqrt_a_sqrtm = 100.0; });
  reject([](auto& b) { b.mean_anomaly_rad = std::numeric_limits<double>::quiet_NaN(); });
  reject([](auto& b) { b.toa_s = -1.0; });
  reject([](auto& b) { b.af0_s = 1.0; });
  EXPECT_EQ(t.count(), 1);
  EXPECT_EQ(t.find(alm.back().prn), nullptr);
  ASSERT_NE(t.find(a.prn), nullptr);
  EXPECT_EQ(t.find(a.prn)->sqrt_a_sqrtm, a.sqrt_a_sqrtm);
  EXPECT_EQ(t.find(0), nullptr);
  EXPECT_EQ(t.find(99), nullptr);
  t.clear();
  EXPECT_EQ(t.count(), 0);
  EXPECT_EQ(t.find(a.prn), nullptr);
}

}  // namespace
