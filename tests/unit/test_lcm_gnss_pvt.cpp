// GNSS_PVT (sdins.gnss_pvt_t, hal::GnssPvtSample): bit-exact round trip through the encoded
// bytes, rejection of bad values by reason, the CSV/info type table, and LcmReplayReader
// delivering solutions in time order with the other inputs (only when the channel is named).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "hal/lcm_channels.hpp"
#include "hal/lcm_convert.hpp"
#include "hal/lcm_log_sink.hpp"
#include "hal/lcm_types.hpp"
#include "lcm_test_util.hpp"
#include "test_util.hpp"

namespace {

using fsw::Vec3;
using lcm_test::bits_equal;
using lcm_test::encode;
using Kind = fsw::InputEvent::Kind;
using test_util::kInf;
using test_util::kNaN;

bool same_pvt(const hal::GnssPvtSample& a, const hal::GnssPvtSample& b) {
  bool eq = bits_equal(a.t_s, b.t_s) && a.gps_week == b.gps_week && bits_equal(a.gps_tow_s, b.gps_tow_s) &&
            a.quality == b.quality && a.n_sat == b.n_sat;
  for (int i = 0; i < 3; ++i)
    eq = eq && bits_equal(a.llh[i], b.llh[i]) && bits_equal(a.vel_enu_mps[i], b.vel_enu_mps[i]) &&
         bits_equal(a.pos_sigma_enu_m[i], b.pos_sigma_enu_m[i]) && bits_equal(a.vel_sigma_enu_mps[i], b.vel_sigma_enu_mps[i]);
  return eq;
}

/// A solution like a line of the drive data set's .pos file, with awkward low bits.
hal::GnssPvtSample sample_pvt(int k) {
  hal::GnssPvtSample p;
  p.t_s = 243258.499 + 0.25 * k;
  p.gps_week = 2374;
  p.gps_tow_s = 243258.499 + 0.25 * k;
  p.llh = Vec3(40.0966268 * fsw::kDegToRad, -105.1474483 * fsw::kDegToRad, 1601.474 + 1e-9 * k);
  p.vel_enu_mps = Vec3(-0.002, 0.01, 0.009 * k);
  p.pos_sigma_enu_m = Vec3(0.0098995, 0.0098995 + 1e-17, 0.01);
  p.vel_sigma_enu_mps = Vec3(0.0586899, 0.0586899, -0.0 + 0.0586899);
  p.quality = 1 + k % 2;
  p.n_sat = 21;
  return p;
}

hal::LcmInputStatus through_bytes(const sdins::gnss_pvt_t& m, hal::GnssPvtSample& out) {
  const std::vector<std::uint8_t> bytes = encode(m);
  sdins::gnss_pvt_t d;
  const hal::LcmInputStatus st = hal::decode_exact(bytes.data(), bytes.size(), d);
  if (st != hal::LcmInputStatus::kOk) return st;
  return hal::from_msg(d, out);
}

}  // namespace

TEST(LcmGnssPvt, RoundTripIsBitExact) {
  for (int k = 0; k < 16; ++k) {
    const hal::GnssPvtSample in = sample_pvt(k);
    sdins::gnss_pvt_t m{};
    hal::to_msg(in, m);
    EXPECT_EQ(m.utime, std::llround(in.t_s * 1e6));
    hal::GnssPvtSample out;
    ASSERT_EQ(through_bytes(m, out), hal::LcmInputStatus::kOk) << k;
    EXPECT_TRUE(same_pvt(in, out)) << k;
    EXPECT_TRUE(out.has_velocity());
  }
  // Without velocity: sigmas negative, velocity 0.
  hal::GnssPvtSample nv = sample_pvt(0);
  nv.vel_enu_mps = Vec3::Zero();
  nv.vel_sigma_enu_mps = Vec3::Constant(hal::kGnssPvtNoVelocity);
  sdins::gnss_pvt_t m{};
  hal::to_msg(nv, m);
  hal::GnssPvtSample out;
  ASSERT_EQ(through_bytes(m, out), hal::LcmInputStatus::kOk);
  EXPECT_FALSE(out.has_velocity());
  EXPECT_TRUE(same_pvt(nv, out));
}

TEST(LcmGnssPvt, BadValuesAreRejectedByReason) {
  struct Case {
    const char* what;
    void (*edit)(sdins::gnss_pvt_t&);
    hal::LcmInputStatus expected;
  };
  const Case cases[] = {
      {"NaN t_s", [](sdins::gnss_pvt_t& m) { m.t_s = kNaN; }, hal::LcmInputStatus::kNonFinite},
      {"NaN latitude", [](sdins::gnss_pvt_t& m) { m.llh[0] = kNaN; }, hal::LcmInputStatus::kNonFinite},
      {"Inf velocity", [](sdins::gnss_pvt_t& m) { m.vel_enu_mps[2] = kInf; }, hal::LcmInputStatus::kNonFinite},
      {"NaN sigma", [](sdins::gnss_pvt_t& m) { m.pos_sigma_enu_m[1] = kNaN; }, hal::LcmInputStatus::kNonFinite},
      {"NaN velocity sigma", [](sdins::gnss_pvt_t& m) { m.vel_sigma_enu_mps[0] = kNaN; }, hal::LcmInputStatus::kNonFinite},
      {"negative week", [](sdins::gnss_pvt_t& m) { m.gps_week = -1; }, hal::LcmInputStatus::kOutOfRange},
      {"tow = 1 week", [](sdins::gnss_pvt_t& m) { m.gps_tow_s = 604800.0; }, hal::LcmInputStatus::kOutOfRange},
      {"negative tow", [](sdins::gnss_pvt_t& m) { m.gps_tow_s = -0.25; }, hal::LcmInputStatus::kOutOfRange},
      {"latitude beyond the pole", [](sdins::gnss_pvt_t& m) { m.llh[0] = 1.5708; }, hal::LcmInputStatus::kOutOfRange},
      {"longitude beyond pi", [](sdins::gnss_pvt_t& m) { m.llh[1] = 3.1416; }, hal::LcmInputStatus::kOutOfRange},
      {"height below -1000 m", [](sdins::gnss_pvt_t& m) { m.llh[2] = -1000.5; }, hal::LcmInputStatus::kOutOfRange},
      {"height above 100 km", [](sdins::gnss_pvt_t& m) { m.llh[2] = 1.0e5 + 1.0; }, hal::LcmInputStatus::kOutOfRange},
      {"speed above 10 km/s", [](sdins::gnss_pvt_t& m) { m.vel_enu_mps[0] = 1.0e4 + 1.0; }, hal::LcmInputStatus::kOutOfRange},
      {"negative position sigma", [](sdins::gnss_pvt_t& m) { m.pos_sigma_enu_m[2] = -0.01; }, hal::LcmInputStatus::kOutOfRange},
      {"some velocity sigmas negative", [](sdins::gnss_pvt_t& m) { m.vel_sigma_enu_mps[1] = -1.0; }, hal::LcmInputStatus::kOutOfRange},
      {"no velocity but a velocity",
       [](sdins::gnss_pvt_t& m) {
         for (double& s : m.vel_sigma_enu_mps) s = -1.0;
       },
       hal::LcmInputStatus::kOutOfRange},
      {"quality 8", [](sdins::gnss_pvt_t& m) { m.quality = 8; }, hal::LcmInputStatus::kOutOfRange},
      {"quality -1", [](sdins::gnss_pvt_t& m) { m.quality = -1; }, hal::LcmInputStatus::kOutOfRange},
      {"n_sat -1", [](sdins::gnss_pvt_t& m) { m.n_sat = -1; }, hal::LcmInputStatus::kOutOfRange},
      {"n_sat 256", [](sdins::gnss_pvt_t& m) { m.n_sat = 256; }, hal::LcmInputStatus::kOutOfRange},
  };
  for (const Case& c : cases) {
    sdins::gnss_pvt_t m{};
    hal::to_msg(sample_pvt(1), m);
    c.edit(m);
    hal::GnssPvtSample out = sample_pvt(5);
    const hal::GnssPvtSample before = out;
    EXPECT_EQ(through_bytes(m, out), c.expected) << c.what;
    EXPECT_TRUE(same_pvt(out, before)) << c.what << ": a rejected message must not change the output";
  }
  // Edges that are valid.
  sdins::gnss_pvt_t m{};
  hal::to_msg(sample_pvt(1), m);
  m.gps_tow_s = 0.0;
  m.quality = 0;
  m.n_sat = 255;
  m.llh[0] = -0.5 * fsw::kPi;
  m.pos_sigma_enu_m[0] = 0.0;
  hal::GnssPvtSample out;
  EXPECT_EQ(through_bytes(m, out), hal::LcmInputStatus::kOk);
  // Bytes: another type's fingerprint, a truncated message.
  sdins::truth_t t{};
  const std::vector<std::uint8_t> tb = encode(t);
  sdins::gnss_pvt_t d;
  EXPECT_EQ(hal::decode_exact(tb.data(), tb.size(), d), hal::LcmInputStatus::kWrongType);
  hal::to_msg(sample_pvt(1), m);
  std::vector<std::uint8_t> b = encode(m);
  b.pop_back();
  EXPECT_EQ(hal::decode_exact(b.data(), b.size(), d), hal::LcmInputStatus::kDecodeFailed);
}

TEST(LcmGnssPvt, ChannelTypeAndCsvColumns) {
  const hal::LcmTypeInfo* t = hal::lcm_channel_type(hal::kLcmChannelGnssPvt);
  ASSERT_NE(t, nullptr);
  EXPECT_EQ(t->name, "sdins.gnss_pvt_t");
  EXPECT_EQ(t->fingerprint, sdins::gnss_pvt_t::getHash());
  EXPECT_LE(sdins::gnss_pvt_t{}.getEncodedSize(), static_cast<int>(hal::kLcmMaxEncodedBytes));
  sdins::gnss_pvt_t m{};
  hal::to_msg(sample_pvt(3), m);
  const std::vector<std::uint8_t> b = encode(m);
  hal::LcmRow row;
  ASSERT_EQ(t->row(b.data(), b.size(), row), hal::LcmInputStatus::kOk);
  const std::vector<std::string> expected = {"utime",
                                             "t_s",
                                             "gps_week",
                                             "gps_tow_s",
                                             "lat_rad",
                                             "lon_rad",
                                             "height_m",
                                             "vel_enu_mps[0]",
                                             "vel_enu_mps[1]",
                                             "vel_enu_mps[2]",
                                             "pos_sigma_enu_m[0]",
                                             "pos_sigma_enu_m[1]",
                                             "pos_sigma_enu_m[2]",
                                             "vel_sigma_enu_mps[0]",
                                             "vel_sigma_enu_mps[1]",
                                             "vel_sigma_enu_mps[2]",
                                             "quality",
                                             "n_sat"};
  EXPECT_EQ(row.names(), expected);
  EXPECT_EQ(row.cells()[16], "2");  // quality of sample 3
  double t_s = 0.0;
  ASSERT_EQ(t->time(b.data(), b.size(), t_s), hal::LcmInputStatus::kOk);
  EXPECT_EQ(t_s, sample_pvt(3).t_s);
}

TEST(LcmGnssPvt, ReferenceOnTruthHasNoAttitude) {
  sdins::truth_t m{};
  hal::reference_to_msg(12.5, Vec3(0.7, -1.8, 1601.0), Vec3(1.0, 2.0, 3.0), m);
  EXPECT_EQ(m.utime, 12500000);
  EXPECT_EQ(m.lat_rad, 0.7);
  EXPECT_EQ(m.height_m, 1601.0);
  EXPECT_EQ(m.vel_enu_mps[1], 2.0);
  for (double q : m.q_b_n_wxyz) EXPECT_TRUE(std::isnan(q));
  EXPECT_TRUE(std::isnan(m.roll_rad) && std::isnan(m.pitch_rad) && std::isnan(m.heading_rad));
}

// A log of IMU samples, raw epochs, PVT solutions (written up to 0.5 s late, as a receiver's
// solution is), references and a bad solution: with the GNSS_PVT channel named, the reader
// delivers every solution bit-exact and in time order among the other inputs and counts the bad
// one; without it, the solutions are other events and nothing else changes.
TEST(LcmGnssPvt, ReplayReaderDeliversSolutionsInTimeOrderWhenAsked) {
  const std::string path = lcm_test::scratch("gnss_pvt_replay.lcmlog");
  hal::LcmLogSink sink;
  ASSERT_EQ(lcm_test::open_log_only(sink, path), hal::LcmLogStatus::kOk);
  std::vector<hal::GnssPvtSample> pvts;
  std::vector<std::size_t> pending;  // index into pvts, written 50 samples late
  int n_imu = 0, n_truth = 0, n_gnss = 0;
  for (int k = 0; k < 1000; ++k) {
    hal::ImuRecord r;
    r.sample.t_s = 100.0 + 0.01 * (k + 1);
    r.sample.dt_s = 0.01;
    r.sample.dv_mps = Vec3(0.0, 0.0, -0.0980665);
    r.counter = k;
    ASSERT_EQ(sink.write_imu(r), hal::LcmLogStatus::kOk);
    ++n_imu;
    if (k % 25 == 24) {  // 4 Hz solutions at the sample's time
      hal::GnssPvtSample p = sample_pvt(k);
      p.t_s = r.sample.t_s;
      pvts.push_back(p);
      pending.push_back(pvts.size() - 1);
    }
    if (k % 100 == 99) {
      fsw::GnssRawEpoch e;
      e.t_s = r.sample.t_s;
      e.gps_week = 2374;
      e.gps_tow_s = 243258.0 + e.t_s;
      ASSERT_EQ(sink.write_gnss(e), hal::LcmLogStatus::kOk);
      ++n_gnss;
    }
    while (!pending.empty() && pvts[pending.front()].t_s <= r.sample.t_s - 0.5) {
      const hal::GnssPvtSample& p = pvts[pending.front()];
      ASSERT_EQ(sink.write_pvt(p), hal::LcmLogStatus::kOk);
      ASSERT_EQ(sink.write_reference(p.t_s, p.llh, p.vel_enu_mps), hal::LcmLogStatus::kOk);
      ++n_truth;
      pending.erase(pending.begin());
    }
  }
  for (std::size_t i : pending) ASSERT_EQ(sink.write_pvt(pvts[i]), hal::LcmLogStatus::kOk);
  hal::GnssPvtSample bad = sample_pvt(0);
  bad.t_s = 105.0;
  bad.llh.x() = kNaN;
  ASSERT_EQ(sink.write_pvt(bad), hal::LcmLogStatus::kOk);
  ASSERT_EQ(sink.close(), hal::LcmLogStatus::kOk);

  {
    hal::LcmReplayConfig rc;
    rc.gnss_pvt_channel = hal::kLcmChannelGnssPvt;
    hal::LcmReplayReader rd;
    ASSERT_EQ(rd.open(path, rc), hal::LcmLogStatus::kOk);
    fsw::InputEvent in;
    double last = -1.0;
    std::size_t n_pvt = 0;
    int imu = 0, gnss = 0;
    while (rd.next(in) == hal::LcmLogStatus::kOk) {
      ASSERT_GE(in.t_s, last);
      last = in.t_s;
      if (in.kind == Kind::kGnssPvt) {
        ASSERT_LT(n_pvt, pvts.size());
        EXPECT_TRUE(same_pvt(hal::from_fsw(in.pvt), pvts[n_pvt])) << n_pvt;
        EXPECT_EQ(in.t_s, pvts[n_pvt].t_s);
        ++n_pvt;
      }
      imu += in.kind == Kind::kImu ? 1 : 0;
      gnss += in.kind == Kind::kGnssRaw ? 1 : 0;
    }
    EXPECT_EQ(n_pvt, pvts.size());
    EXPECT_EQ(imu, n_imu);
    EXPECT_EQ(gnss, n_gnss);
    const hal::LcmReplayStats& st = rd.stats();
    EXPECT_EQ(st.gnss_pvt.accepted(), pvts.size());
    EXPECT_EQ(st.gnss_pvt.count(hal::LcmInputStatus::kNonFinite), 1u);
    EXPECT_EQ(st.rejected(), 1u);
    EXPECT_EQ(st.other_events, static_cast<std::uint64_t>(n_truth));  // TRUTH is never an input
    EXPECT_EQ(st.delivered, static_cast<std::uint64_t>(n_imu + n_gnss) + pvts.size());
  }
  {
    hal::LcmReplayReader rd;  // default: GNSS_PVT is not read
    ASSERT_EQ(rd.open(path), hal::LcmLogStatus::kOk);
    fsw::InputEvent in;
    while (rd.next(in) == hal::LcmLogStatus::kOk) EXPECT_NE(in.kind, Kind::kGnssPvt);
    const hal::LcmReplayStats& st = rd.stats();
    EXPECT_EQ(st.gnss_pvt.accepted() + st.gnss_pvt.rejected(), 0u);
    EXPECT_EQ(st.other_events, static_cast<std::uint64_t>(n_truth) + pvts.size() + 1);
    EXPECT_EQ(st.rejected(), 0u);
    EXPECT_EQ(st.delivered, static_cast<std::uint64_t>(n_imu + n_gnss));
  }
  std::remove(path.c_str());
}
