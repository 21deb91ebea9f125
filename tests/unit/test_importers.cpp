// Readers and conversions of `sdins import` (tools/importers.hpp, tools/gps_ephemeris.hpp) against
// hand-made inputs and hand-computed values; the broadcast-ephemeris orbit against RTKLIB's.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "fsw/gps_orbit.hpp"
#include "tools/gps_ephemeris.hpp"
#include "tools/importers.hpp"

namespace {

using fsw::Vec3;

/// A RINEX header line: content padded to 60 columns, then the label.
std::string hdr(const std::string& content, const std::string& label) {
  std::string s = content;
  s.resize(60, ' ');
  return s + label + "\n";
}

std::vector<std::uint8_t> tag_bytes(const std::string& label, std::uint32_t tick_f, std::uint32_t t, double frac,
                                    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& recs) {
  std::vector<std::uint8_t> b(60, 0);
  std::memcpy(b.data(), label.data(), label.size());
  const auto put32 = [&](std::uint32_t v) {
    for (int i = 0; i < 4; ++i) b.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  };
  put32(tick_f);
  put32(t);
  std::uint64_t bits = 0;
  std::memcpy(&bits, &frac, 8);
  for (int i = 0; i < 8; ++i) b.push_back(static_cast<std::uint8_t>(bits >> (8 * i)));
  for (const auto& [tick, off] : recs) {
    put32(tick);
    put32(off);
  }
  return b;
}

const char* kPosHeader =
    "% program   : RTKPOST ver.demo5\n"
    "%\n"
    "%  GPST            latitude(deg) longitude(deg) height(m) Q         ns        sdn(m)    sde(m)    sdu(m)    "
    "sdne(m)   sdeu(m)   sdun(m)  age(s)     ratio     vn(m/s)   ve(m/s)    vu(m/s)    sdvn      sdve     sdvu       "
    "sdvne    sdveu      sdvun\n";

}  // namespace

// ---------------------------------------------------------------------------------------------
TEST(ImportTime, GpsWeekAndTowFromCalendarAndGtime) {
  tools::GpsTime t;
  ASSERT_TRUE(tools::gps_time_from_calendar(1980, 1, 6, 0, 0, 0.0, t));
  EXPECT_EQ(t.week, 0);
  EXPECT_EQ(t.tow_s, 0.0);
  ASSERT_TRUE(tools::gps_time_from_calendar(1999, 8, 22, 0, 0, 0.0, t));  // first rollover
  EXPECT_EQ(t.week, 1024);
  EXPECT_EQ(t.tow_s, 0.0);
  // Tuesday 2025-07-08 (week 2374 began on Sunday 2025-07-06): 2 d 19 h 34 min 18.499 s.
  ASSERT_TRUE(tools::gps_time_from_calendar(2025, 7, 8, 19, 34, 18.499, t));
  EXPECT_EQ(t.week, 2374);
  EXPECT_NEAR(t.tow_s, 2 * 86400 + 19 * 3600 + 34 * 60 + 18.499, 1e-9);
  // Thursday 2025-08-28 17:30:39.749: week 2381.
  ASSERT_TRUE(tools::gps_time_from_calendar(2025, 8, 28, 17, 30, 39.749, t));
  EXPECT_EQ(t.week, 2381);
  EXPECT_NEAR(t.tow_s, 4 * 86400 + 17 * 3600 + 30 * 60 + 39.749, 1e-9);
  EXPECT_FALSE(tools::gps_time_from_calendar(2025, 2, 29, 0, 0, 0.0, t));
  EXPECT_FALSE(tools::gps_time_from_calendar(2025, 13, 1, 0, 0, 0.0, t));
  // RTKLIB gtime_t: 1752003261 s after 1970 on the GPS scale = 1436038461 s after the GPS epoch
  // = 2374 weeks (1435795200 s) + 243261 s.
  t = tools::gps_time_from_gtime(1752003261, 0.854);
  EXPECT_EQ(t.week, 2374);
  EXPECT_NEAR(t.tow_s, 243261.854, 1e-9);
  const tools::ImportTimeScale ts{2374};
  EXPECT_EQ(ts.t_s(tools::GpsTime{2374, 12.5}), 12.5);
  EXPECT_EQ(ts.t_s(tools::GpsTime{2375, 1.0}), 604801.0);  // keeps counting past the week
}

// ---------------------------------------------------------------------------------------------
TEST(ImportTimeTag, ParsesHeaderStartAndRecords) {
  std::vector<std::uint8_t> b =
      tag_bytes("TIMETAG RTKLIB demo5", 1132621244u, 1752003261u, 0.854, {{131, 37}, {146, 99}, {162, 180}, {150, 200}});
  b.push_back(7);  // a cut record: 3 trailing bytes
  b.push_back(0);
  b.push_back(0);
  const tools::TimeTag t = tools::parse_time_tag(b);
  EXPECT_EQ(t.label, "TIMETAG RTKLIB demo5");
  EXPECT_EQ(t.tick_f, 1132621244u);
  EXPECT_EQ(t.start_gtime_s, 1752003261);
  EXPECT_EQ(t.start_fraction_s, 0.854);
  ASSERT_EQ(t.records.size(), 4u);
  EXPECT_EQ(t.records[1].tick_ms, 146u);
  EXPECT_EQ(t.records[1].offset, 99u);
  EXPECT_EQ(t.trailing_bytes, 3u);
  EXPECT_EQ(t.non_monotonic, 1u);  // 150 after 162
  EXPECT_EQ(t.last_tick_s(), 0.150);
  EXPECT_EQ(t.start().week, 2374);
  EXPECT_NEAR(t.start().tow_s, 243261.854, 1e-9);

  EXPECT_THROW(tools::parse_time_tag(std::vector<std::uint8_t>(70, 0)), std::runtime_error);  // too short
  EXPECT_THROW(tools::parse_time_tag(tag_bytes("NOT A TAG", 0, 1752003261u, 0.5, {})), std::runtime_error);
  EXPECT_THROW(tools::parse_time_tag(tag_bytes("TIMETAG RTKLIB", 0, 1752003261u, 1.5, {})), std::runtime_error);
}

// ---------------------------------------------------------------------------------------------
TEST(ImportPos, ReadsSolutionsAndRejectsBadLines) {
  std::string text = kPosHeader;
  // 1: the drive data set's first line.
  text += "2025/07/08 19:34:18.499 40.0966268 -105.1474483 1601.4740000 1.0000000 21.0000000 0.0098995 0.0098995 "
          "0.0100000 0.0000000 0.0000000 0.0000000 0.0000000 0.0000000 0.0100000 -0.0020000 0.0090000 0.0586899 "
          "0.0586899 0.0586899 0.0000000 0.0000000 0.0000000\n";
  // 2: distinct N/E/U values to check the reordering to E/N/U.
  text += "2025/07/08 19:34:18.749 40.0966269 -105.1474480 1601.4760000 2.0000000 9.0000000 0.0100000 0.0200000 "
          "0.0300000 0 0 0 1.5 3.2 0.0010000 0.0020000 -0.0060000 0.0400000 0.0500000 0.0600000 0 0 0\n";
  // 3: NaN; 4: cut short; 5: time not increasing; 6: latitude 95 deg; 7: bad date.
  text += "2025/07/08 19:34:18.999 nan -105.1474483 1601.47 1 21 0.01 0.01 0.01 0 0 0 0 0 0 0 0 0.05 0.05 0.05 0 0 0\n";
  text += "2025/07/08 19:34:19.249 40.0966268 -105.1474483 1601.47 1 21 0.01 0.01\n";
  text += "2025/07/08 19:34:18.749 40.0966268 -105.1474483 1601.47 1 21 0.01 0.01 0.01 0 0 0 0 0 0 0 0 0.05 0.05 0.05 0 0 0\n";
  text += "2025/07/08 19:34:19.499 95.0 -105.1474483 1601.47 1 21 0.01 0.01 0.01 0 0 0 0 0 0 0 0 0.05 0.05 0.05 0 0 0\n";
  text += "2025/02/30 19:34:19.749 40.0966268 -105.1474483 1601.47 1 21 0.01 0.01 0.01 0 0 0 0 0 0 0 0 0.05 0.05 0.05 0 0 0\n";
  // 8: good; 9: cut off without a newline.
  text += "2025/07/08 19:34:20.000 40.0966268 -105.1474483 1601.47 1 21 0.01 0.01 0.01 0 0 0 0 0 0 0 0 0.05 0.05 0.05 0 0 0\n";
  text += "2025/07/08 19:34:20.250 40.0966268 -105.1474483 1601.47 1 21 0.01 0.01 0.01 0 0 0 0 0 0 0 0 0.05 0.05 0.05 0 0 0";
  std::istringstream in(text);
  const tools::PosFile f = tools::read_rtklib_pos(in);
  EXPECT_EQ(f.time_system, "GPST");
  EXPECT_TRUE(f.has_velocity);
  EXPECT_EQ(f.lines.lines, 9u);
  EXPECT_EQ(f.lines.accepted, 3u);
  EXPECT_EQ(f.lines.rejected, 6u);
  EXPECT_EQ(f.lines.by_reason.at("non-finite value"), 1u);
  EXPECT_EQ(f.lines.by_reason.at("wrong field count"), 1u);
  EXPECT_EQ(f.lines.by_reason.at("time not increasing"), 1u);
  EXPECT_EQ(f.lines.by_reason.at("implausible solution (GNSS_PVT validation: out_of_range)"), 1u);
  EXPECT_EQ(f.lines.by_reason.at("bad time"), 1u);
  EXPECT_EQ(f.lines.by_reason.at("partial last line (no newline)"), 1u);
  ASSERT_EQ(f.lines.examples.size(), 6u);
  EXPECT_EQ(f.lines.examples[0].first, 6u);  // file line of the NaN (3 header lines)
  ASSERT_EQ(f.samples.size(), 3u);
  const hal::GnssPvtSample& a = f.samples[0];
  EXPECT_EQ(a.gps_week, 2374);
  EXPECT_NEAR(a.gps_tow_s, 243258.499, 1e-9);
  EXPECT_DOUBLE_EQ(a.llh.x(), 40.0966268 * fsw::kDegToRad);
  EXPECT_DOUBLE_EQ(a.llh.y(), -105.1474483 * fsw::kDegToRad);
  EXPECT_EQ(a.llh.z(), 1601.474);
  EXPECT_EQ(a.quality, 1);
  EXPECT_EQ(a.n_sat, 21);
  EXPECT_EQ(a.vel_enu_mps, Vec3(-0.002, 0.010, 0.009));  // ve, vn, vu
  const hal::GnssPvtSample& b = f.samples[1];
  EXPECT_EQ(b.quality, 2);
  EXPECT_EQ(b.n_sat, 9);
  EXPECT_EQ(b.vel_enu_mps, Vec3(0.002, 0.001, -0.006));
  EXPECT_EQ(b.pos_sigma_enu_m, Vec3(0.02, 0.01, 0.03));      // sde, sdn, sdu
  EXPECT_EQ(b.vel_sigma_enu_mps, Vec3(0.05, 0.04, 0.06));    // sdve, sdvn, sdvu
  EXPECT_NEAR(f.samples[2].gps_tow_s, 243260.0, 1e-9);

  // Week/tow time format, no velocity columns.
  std::istringstream wk(
      "%  GPST                  latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)   sdu(m)  sdne(m)  "
      "sdeu(m)  sdun(m) age(s)  ratio\n"
      "2374 243258.499   40.096626800 -105.147448300  1601.4740   5   8   1.2000   0.9000   2.5000  0.1 0.1 0.1 0.0 0.0\n");
  const tools::PosFile w = tools::read_rtklib_pos(wk);
  ASSERT_EQ(w.samples.size(), 1u);
  EXPECT_FALSE(w.has_velocity);
  EXPECT_FALSE(w.samples[0].has_velocity());
  EXPECT_EQ(w.samples[0].vel_enu_mps, Vec3::Zero());
  EXPECT_EQ(w.samples[0].pos_sigma_enu_m, Vec3(0.9, 1.2, 2.5));
  EXPECT_EQ(w.samples[0].quality, 5);
  EXPECT_NEAR(w.samples[0].gps_tow_s, 243258.499, 1e-9);

  // Unsupported files are errors, not silently empty imports.
  std::istringstream utc("%  UTC             latitude(deg) longitude(deg) height(m) Q ns sdn(m) sde(m) sdu(m)\n");
  EXPECT_THROW(tools::read_rtklib_pos(utc), std::runtime_error);
  std::istringstream xyz("%  GPST            x-ecef(m)      y-ecef(m)      z-ecef(m)   Q  ns\n");
  EXPECT_THROW(tools::read_rtklib_pos(xyz), std::runtime_error);
  std::istringstream none("2025/07/08 19:34:18.499 40.0966268 -105.1474483 1601.4740000 1 21\n");
  EXPECT_THROW(tools::read_rtklib_pos(none), std::runtime_error);
}

// ---------------------------------------------------------------------------------------------
TEST(ImportImuCsv, ReadsLinesAndCountsEveryBadOne) {
  std::istringstream in(
      "0.007,1.011,0.038,-0.160,0.160,3326339\n"        // 1: partial first line (6 fields)
      "0.119,0.027,1.013,-0.671,3.082,0.198,261906\n"   // 2: good
      "0.116,nan,0.985,-0.359,0.946,0.168,261916\n"     // 3: NaN
      "0.116,0.031,0.985,-0.359,0.946,0.168,2619x6\n"   // 4: unparsable tick
      "19.5,0.031,0.985,-0.359,0.946,0.168,261926\n"    // 5: 19.5 g
      "0.114,0.032,1.009,0.999,-3.815,0.191,261906\n"   // 6: tick repeated
      "\n"                                               // 7: empty
      "0.128,0.023,1.017,-0.526,1.640,0.031,261937\n"   // 8: good
      "0.120,0.026,0.991,-0.458,2.14");                 // 9: partial last line
  tools::LineStats st;
  const std::vector<tools::ImuCsvSample> s = tools::read_gnss_imu_csv(in, st);
  EXPECT_EQ(st.lines, 9u);
  EXPECT_EQ(st.accepted, 2u);
  EXPECT_EQ(st.rejected, 7u);
  EXPECT_EQ(st.by_reason.at("wrong field count (6, expected 7)"), 1u);
  EXPECT_EQ(st.by_reason.at("non-finite value"), 1u);
  EXPECT_EQ(st.by_reason.at("unparsable number"), 1u);
  EXPECT_EQ(st.by_reason.at("value beyond the sensor range"), 1u);
  EXPECT_EQ(st.by_reason.at("time not increasing"), 1u);
  EXPECT_EQ(st.by_reason.at("empty line"), 1u);
  EXPECT_EQ(st.by_reason.at("partial last line (no newline)"), 1u);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].line, 2u);
  EXPECT_EQ(s[0].tick_ms, 261906);
  EXPECT_EQ(s[0].accel_g[2], 1.013);
  EXPECT_EQ(s[0].gyro_dps[1], 3.082);
  EXPECT_EQ(s[1].line, 8u);
  EXPECT_EQ(s[1].gyro_dps[0], -0.526);

  // Tick -> GPS time: first sample at the tag's start, last at start + last tag tick (62 ms for
  // 31 IMU-clock ms: 2 ms per tick).
  const tools::TimeTag tag =
      tools::parse_time_tag(tag_bytes("TIMETAG RTKLIB demo5", 0, 1752003261u, 0.854, {{10, 0}, {62, 100}}));
  const tools::TickToGps m = tools::tick_to_gps(tag, s);
  EXPECT_EQ(m.start.week, 2374);
  EXPECT_NEAR(m.start.tow_s, 243261.854, 1e-9);
  EXPECT_EQ(m.tick0_ms, 261906);
  EXPECT_DOUBLE_EQ(m.seconds_per_tick, 0.002);
  EXPECT_DOUBLE_EQ(m.offset_s(261937), 0.062);
  EXPECT_THROW(tools::tick_to_gps(tag, std::vector<tools::ImuCsvSample>(1)), std::runtime_error);
}

// ---------------------------------------------------------------------------------------------
TEST(ImportAxes, SignedPermutationsToTheBodyFrame) {
  const tools::AxisMap drive = tools::parse_axis_map(tools::kAxesGnssImu);  // x back, y right, z up
  EXPECT_EQ(drive.text(), "-x,y,-z");
  EXPECT_EQ(drive.apply(Vec3(1, 2, 3)), Vec3(-1, 2, -3));
  // At rest the sensor's z (up) reads +1 g: in FRD body axes the specific force points up, -z.
  EXPECT_EQ(drive.apply(Vec3(0, 0, 9.80665)), Vec3(0, 0, -9.80665));
  // Braking (deceleration along the car's forward axis) reads +x on a backward-pointing x axis:
  // specific force -x body (backward).
  EXPECT_EQ(drive.apply(Vec3(2.0, 0, 0)), Vec3(-2.0, 0, 0));
  EXPECT_DOUBLE_EQ(drive.matrix().determinant(), 1.0);

  const tools::AxisMap psins = tools::parse_axis_map(tools::kAxesPsins);  // Right-Front-Up
  EXPECT_EQ(psins.apply(Vec3(1, 2, 3)), Vec3(2, 1, -3));  // forward = front (y), right = right (x), down = -up
  EXPECT_DOUBLE_EQ(psins.matrix().determinant(), 1.0);
  EXPECT_EQ(tools::parse_axis_map(" +x , -y , -z ").apply(Vec3(1, 2, 3)), Vec3(1, -2, -3));

  EXPECT_THROW(tools::parse_axis_map("x,y,-z"), std::runtime_error);  // reflection
  EXPECT_THROW(tools::parse_axis_map("y,x,z"), std::runtime_error);   // reflection
  EXPECT_THROW(tools::parse_axis_map("x,x,z"), std::runtime_error);
  EXPECT_THROW(tools::parse_axis_map("x,y"), std::runtime_error);
  EXPECT_THROW(tools::parse_axis_map("a,b,c"), std::runtime_error);
  EXPECT_THROW(tools::parse_axis_map("--x,y,z"), std::runtime_error);
}

TEST(ImportAxes, TrapezoidIncrementsFromRateSamples) {
  std::vector<tools::RateSample> s(3);
  s[0] = {100.00, Vec3(1, 0, 0), Vec3(0, 0, -10), 5};
  s[1] = {100.01, Vec3(3, 0, 0), Vec3(1, 0, -10), 6};
  s[2] = {100.03, Vec3(3, 2, 0), Vec3(1, 0, -12), 8};
  const std::vector<hal::ImuRecord> r = tools::increments_from_rates(s);
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[0].sample.t_s, 100.01);
  EXPECT_NEAR(r[0].sample.dt_s, 0.01, 1e-12);
  EXPECT_NEAR(r[0].sample.dtheta_rad.x(), 0.02, 1e-12);  // (1 + 3) / 2 * 0.01
  EXPECT_NEAR(r[0].sample.dv_mps.x(), 0.005, 1e-12);
  EXPECT_NEAR(r[0].sample.dv_mps.z(), -0.1, 1e-12);
  EXPECT_EQ(r[0].counter, 6);
  EXPECT_NEAR(r[1].sample.dt_s, 0.02, 1e-12);
  EXPECT_NEAR(r[1].sample.dtheta_rad.x(), 0.06, 1e-12);
  EXPECT_NEAR(r[1].sample.dtheta_rad.y(), 0.02, 1e-12);
  EXPECT_NEAR(r[1].sample.dv_mps.z(), -0.22, 1e-12);
  EXPECT_EQ(r[1].counter, 8);
  EXPECT_TRUE(tools::increments_from_rates(std::vector<tools::RateSample>(1)).empty());
}

// ---------------------------------------------------------------------------------------------
TEST(ImportPsins, ImuObservationAndEphemerisReaders) {
  std::istringstream imu(
      "gps_tow_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_mps,dv_y_mps,dv_z_mps\n"
      "185492.500000,-3.172542000000e-06,-4.771502500000e-06,-3.170954000000e-06,1.338650000000e-04,-1.647195000000e-03,"
      "4.963829500000e-02\n"
      "185492.505000,-4.762483000000e-06,-6.355745000000e-06,6.829665000000e-09,1.468300000000e-04,1.204000000000e-04,"
      "4.963516000000e-02\n"
      "185492.505000,0,0,0,0,0,0.0496\n"          // time not increasing
      "185492.515000,0,0,0,0,0\n"                 // 6 fields
      "185492.520000,0,0,inf,0,0,0.0496\n");     // Inf
  tools::LineStats st;
  const std::vector<tools::PsinsImuRow> rows = tools::read_psins_imu(imu, st);
  EXPECT_EQ(st.lines, 5u);
  EXPECT_EQ(st.accepted, 2u);
  EXPECT_EQ(st.rejected, 3u);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].tow_s, 185492.5);
  EXPECT_EQ(rows[0].line, 2u);
  EXPECT_EQ(rows[0].dv_mps.z(), 4.9638295e-02);
  // Right-Front-Up -> body: forward = y, right = x, down = -z; at rest +9.93 m/s^2 up -> -z body.
  const tools::AxisMap m = tools::parse_axis_map(tools::kAxesPsins);
  EXPECT_EQ(m.apply(rows[0].dv_mps), Vec3(-1.647195e-03, 1.33865e-04, -4.9638295e-02));
  EXPECT_EQ(m.apply(rows[0].dtheta_rad), Vec3(-4.7715025e-06, -3.172542e-06, 3.170954e-06));

  std::istringstream obs(
      "gps_tow_s,prn,C1_pseudorange_m,L1_carrier_m,col5_unknown,D1_doppler_mps(=-range_rate)\n"
      "183828,5,23327025.9590,23308894.6514,0.0590,-443.663098\n"
      "183828,10,24215523.7130,24142965.6855,0.0550,481.874907\n"
      "183829,5,23327469.6700,23309338.3611,nan,-443.711433\n"  // the unused column may be anything
      "183829,33,23327469.6700,23309338.3611,0.0590,-443.711433\n"
      "183829,13,1000.0,23309338.3611,0.0590,-443.711433\n"
      "183827,5,23327469.6700,23309338.3611,0.0590,-443.711433\n");
  tools::LineStats os;
  const std::vector<tools::PsinsObsRow> o = tools::read_psins_obs(obs, os);
  EXPECT_EQ(os.accepted, 3u);
  EXPECT_EQ(os.by_reason.at("PRN outside 1..32"), 1u);
  EXPECT_EQ(os.by_reason.at("pseudorange outside 1e7..5e7 m"), 1u);
  EXPECT_EQ(os.by_reason.at("time-tag outlier (a jump the following samples did not confirm)"), 1u);
  ASSERT_EQ(o.size(), 3u);
  EXPECT_EQ(o[1].prn, 10);
  EXPECT_EQ(o[1].doppler_mps, 481.874907);
  // The README's sign: Doppler = -range rate. PRN 5's pseudorange grows by 443.711 m in the
  // second between the two epochs: the range rate is +443.7 m/s, the column -443.7.
  EXPECT_NEAR(o[2].pseudorange_m - o[0].pseudorange_m, -o[0].doppler_mps, 0.1);

  std::istringstream eph(
      "PRN,Toc,af0,af1,af2,IODE,Crs,Deltan,M0,Cuc,e,Cus,sqrtA,Toe,Cic,OMEGA0,Cis,i0,Crc,omega,OMEGADot,iDot,L2Cd,WN,L2PF,"
      "URA,SatHl,TGD,IODC,SOW,FitI\n"
      "1,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,255,0,0,0,0\n"
      "5,187200,-6.04419e-05,-1.25056e-12,0,43,-108.5625,4.320894268e-09,2.20221203,-5.707144737e-06,0.0060007086722,"
      "9.629875422e-06,5153.6190167687,187200,-5.587935448e-09,0.83860246341,-9.685754776e-08,0.95822938409,194.34375,"
      "1.015982021,-7.84318384e-09,2.078658013e-10,0,2183,0,nan,0,-1.11758709e-08,0,0,0\n"
      "6,187200,0,0,0,1,0,0,0,0,0.5,0,5153.6,187200,0,0,0,0.95,0,0,0,0,0,2183,0,0,0,0,0,0,0\n"   // e = 0.5
      "nan,187200,0,0,0,1,0,0,0,0,0.01,0,5153.6,187200,0,0,0,0.95,0,0,0,0,0,2183,0,0,0,0,0,0,0\n"  // PRN NaN
      "7,187200,0,0,0,1,0,0,0,0,0.01,0,5153.6,187200,0,0,0,0.95,0,0,0,0,0,1e300,0,0,0,0,0,0,0\n");  // WN 1e300
  tools::LineStats es;
  const std::vector<tools::GpsEphemeris> e = tools::read_psins_eph(eph, es);
  EXPECT_EQ(es.accepted, 1u);
  EXPECT_EQ(es.rejected, 3u);
  EXPECT_EQ(es.by_reason.at("implausible ephemeris"), 1u);
  EXPECT_EQ(es.by_reason.at("PRN, IODE, WN or SatHl not an integer"), 2u);
  EXPECT_EQ(es.skipped.at("absent satellite (health 255, no elements)"), 1u);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].prn, 5);
  EXPECT_EQ(e[0].week, 2183);
  EXPECT_EQ(e[0].toe_s, 187200.0);
  EXPECT_EQ(e[0].toc_s, 187200.0);
  EXPECT_EQ(e[0].sqrt_a_sqrtm, 5153.6190167687);
  EXPECT_EQ(e[0].crs_m, -108.5625);
  EXPECT_EQ(e[0].omega_dot_radps, -7.84318384e-09);
  EXPECT_EQ(e[0].idot_radps, 2.078658013e-10);
  EXPECT_EQ(e[0].tgd_s, -1.11758709e-08);
  EXPECT_EQ(e[0].iode, 43);
  EXPECT_EQ(e[0].health, 0);

  std::istringstream headerless("185492.500000,0,0,0,0,0,0.0496\n185492.505000,0,0,0,0,0,0.0496\n");
  tools::LineStats hs;
  EXPECT_THROW(tools::read_psins_imu(headerless, hs), std::runtime_error);
}

// ---------------------------------------------------------------------------------------------
namespace {

// Two GPS broadcast ephemerides exactly as convbin wrote them from the walk data set's u-blox log.
const char* kNavG10 =
    "G10 2025 08 28 18 00 00 -.516209285706D-03 -.818545231596D-11  .000000000000D+00\n"
    "      .970000000000D+02 -.139687500000D+02  .378730061342D-08 -.226070087556D+01\n"
    "     -.929459929466D-06  .104180137860D-01  .881403684616D-05  .515364910889D+04\n"
    "      .410400000000D+06  .160187482834D-06  .121533091086D+01 -.521540641785D-07\n"
    "      .990331316097D+00  .223000000000D+03 -.231957460341D+01 -.750959851921D-08\n"
    "      .493591988659D-09  .100000000000D+01  .238100000000D+04  .000000000000D+00\n"
    "      .200000000000D+01  .000000000000D+00  .232830643654D-08  .970000000000D+02\n"
    "      .408756000000D+06  .400000000000D+01\n";
const char* kNavG23 =
    "G23 2025 08 28 18 00 00  .534086022526D-03  .591171556152D-11  .000000000000D+00\n"
    "      .130000000000D+03 -.191562500000D+02  .389373361821D-08 -.108574725417D+01\n"
    "     -.959262251854D-06  .559549743775D-02  .908225774765D-05  .515367185974D+04\n"
    "      .410400000000D+06  .912696123123D-07  .118412836480D+01 -.260770320892D-07\n"
    "      .985403132762D+00  .215281250000D+03 -.283982775802D+01 -.768710591310D-08\n"
    "      .431089385175D-09  .100000000000D+01  .238100000000D+04  .000000000000D+00\n"
    "      .200000000000D+01  .000000000000D+00 -.838190317154D-08  .130000000000D+03\n"
    "      .408726000000D+06  .400000000000D+01\n";

std::vector<tools::GpsEphemeris> walk_ephemerides(tools::LineStats& st) {
  std::string text = hdr("     3.04           N: GNSS NAV DATA    M: Mixed", "RINEX VERSION / TYPE") +
                     hdr("", "END OF HEADER") + kNavG10;
  // A GLONASS record (4 lines) and a Galileo record (8 lines) between the GPS ones.
  text += "R05 2025 08 28 17 45 00  .123456789012D-03  .000000000000D+00  .162000000000D+05\n"
          "      .100000000000D+05  .100000000000D+01  .000000000000D+00  .000000000000D+00\n"
          "      .100000000000D+05  .100000000000D+01  .000000000000D+00  .100000000000D+01\n"
          "      .100000000000D+05  .100000000000D+01  .000000000000D+00  .000000000000D+00\n";
  std::string gal = kNavG23;
  gal[0] = 'E';
  text += gal + kNavG23;
  std::istringstream in(text);
  return tools::read_rinex3_nav(in, st);
}

}  // namespace

TEST(ImportRinex, NavigationGpsRecords) {
  tools::LineStats st;
  const std::vector<tools::GpsEphemeris> e = walk_ephemerides(st);
  EXPECT_EQ(st.lines, 4u);
  EXPECT_EQ(st.accepted, 2u);
  EXPECT_EQ(st.skipped.at("other system (R)"), 1u);
  EXPECT_EQ(st.skipped.at("other system (E)"), 1u);
  ASSERT_EQ(e.size(), 2u);
  const tools::GpsEphemeris& g = e[0];
  EXPECT_EQ(g.prn, 10);
  EXPECT_EQ(g.week, 2381);
  EXPECT_EQ(g.toe_s, 410400.0);
  EXPECT_EQ(g.toc_s, 4 * 86400.0 + 18 * 3600.0);  // 2025-08-28 18:00:00 = Thursday of week 2381
  EXPECT_EQ(g.af0_s, -.516209285706e-03);
  EXPECT_EQ(g.af1_sps, -.818545231596e-11);
  EXPECT_EQ(g.iode, 97);
  EXPECT_EQ(g.crs_m, -13.96875);
  EXPECT_EQ(g.delta_n_radps, .378730061342e-08);
  EXPECT_EQ(g.m0_rad, -2.26070087556);
  EXPECT_EQ(g.eccentricity, .104180137860e-01);
  EXPECT_EQ(g.sqrt_a_sqrtm, .515364910889e+04);
  EXPECT_EQ(g.i0_rad, .990331316097);
  EXPECT_EQ(g.crc_m, 223.0);
  EXPECT_EQ(g.idot_radps, .493591988659e-09);
  EXPECT_EQ(g.health, 0);
  EXPECT_EQ(g.tgd_s, .232830643654e-08);
  EXPECT_EQ(e[1].prn, 23);

  std::istringstream obs_file(hdr("     3.04           OBSERVATION DATA    M: Mixed", "RINEX VERSION / TYPE") +
                              hdr("", "END OF HEADER"));
  tools::LineStats s2;
  EXPECT_THROW(tools::read_rinex3_nav(obs_file, s2), std::runtime_error);
}

// The ephemeris orbit and clock against RTKLIB 2.4.3 (rnx2rtkp -p 0 -x 5 on the walk data set's
// convbin output: the satposs trace at the epoch 17:30:59.998), at the transmit times RTKLIB
// printed (microseconds); RTKLIB's dts includes the relativistic term but not TGD.
TEST(ImportEphemeris, OrbitAndClockAgreeWithRtklib) {
  tools::LineStats st;
  const std::vector<tools::GpsEphemeris> e = walk_ephemerides(st);
  ASSERT_EQ(e.size(), 2u);
  const double day4 = 4 * 86400.0 + 17 * 3600.0 + 30 * 60.0;
  struct Ref {
    const tools::GpsEphemeris* eph;
    double tow, x, y, z, dts_ns;
  } refs[] = {{&e[0], day4 + 59.929894, -7847053.570, -12771949.047, 22197588.552, -516181.163},
              {&e[1], day4 + 59.928486, 8210663.447, -16400802.630, 19164519.099, 534088.222}};
  for (const Ref& r : refs) {
    Vec3 pos;
    double clk = 0.0;
    tools::ephemeris_position_clock(*r.eph, 2381, r.tow, pos, clk);
    // 0.5 us of printed time is 2 mm of satellite motion; 1 mm of printed position.
    EXPECT_NEAR(pos.x(), r.x, 0.005) << r.eph->prn;
    EXPECT_NEAR(pos.y(), r.y, 0.005) << r.eph->prn;
    EXPECT_NEAR(pos.z(), r.z, 0.005) << r.eph->prn;
    EXPECT_NEAR((clk + r.eph->tgd_s) * 1e9, r.dts_ns, 0.002) << r.eph->prn;
  }
}

TEST(ImportEphemeris, KeplerianEphemerisIsTheAlmanacModel) {
  // Without harmonic corrections, delta-n, IDOT, af2, TGD and with e = 0 (no relativistic term),
  // the ephemeris and the flight software's almanac orbit are the same equations.
  tools::GpsEphemeris k;
  k.prn = 7;
  k.week = 2381;
  k.toe_s = 410400.0;
  k.toc_s = 410400.0;
  k.af0_s = 1.5e-4;
  k.af1_sps = -2e-12;
  k.sqrt_a_sqrtm = 5153.65;
  k.i0_rad = 0.96;
  k.omega0_rad = 1.2;
  k.omega_dot_radps = -7.9e-9;
  k.arg_perigee_rad = 0.4;
  k.m0_rad = -2.0;
  fsw::GpsAlmanac a;
  a.prn = 7;
  a.toa_s = k.toe_s;
  a.week_mod_1024 = 2381 % 1024;
  a.sqrt_a_sqrtm = k.sqrt_a_sqrtm;
  a.inclination_rad = k.i0_rad;
  a.omega0_rad = k.omega0_rad;
  a.omega_dot_radps = k.omega_dot_radps;
  a.arg_perigee_rad = k.arg_perigee_rad;
  a.mean_anomaly_rad = k.m0_rad;
  a.af0_s = k.af0_s;
  a.af1_sps = k.af1_sps;
  for (double dt : {-3600.0, -1.0, 0.0, 1234.5, 7200.0}) {
    Vec3 pe, pa, va;
    double ce = 0.0;
    tools::ephemeris_position_clock(k, 2381, k.toe_s + dt, pe, ce);
    fsw::satellite_pv_ecef(a, 2381, k.toe_s + dt, pa, va);
    EXPECT_LT((pe - pa).norm(), 1e-6) << dt;
    EXPECT_DOUBLE_EQ(ce, k.af0_s + k.af1_sps * dt);
  }
}

TEST(ImportEphemeris, AlmanacFitReproducesTheEphemerisOverAShortArcOnly) {
  tools::LineStats st;
  const std::vector<tools::GpsEphemeris> e = walk_ephemerides(st);
  ASSERT_EQ(e.size(), 2u);
  const double t0 = 408630.0;
  // The walk: 154 s.
  const tools::AlmanacFit f = tools::fit_almanac(e[0], 2381, t0, 154.0);
  EXPECT_TRUE(f.converged);
  EXPECT_TRUE(fsw::almanac_valid(f.almanac));
  EXPECT_EQ(f.almanac.prn, 10);
  EXPECT_EQ(f.almanac.toa_s, t0 + 77.0);
  EXPECT_EQ(f.almanac.week_mod_1024, 2381 % 1024);
  EXPECT_LT(f.max_pos_err_m, 0.1);
  EXPECT_LT(f.max_clock_err_m, 0.01);  // relativistic term and TGD absorbed in af0/af1
  EXPECT_LT(f.max_vel_err_mps, 0.01);
  // Check the reported error independently at one instant.
  Vec3 pe, pa, va;
  double ce = 0.0;
  tools::ephemeris_position_clock(e[0], 2381, t0 + 100.0, pe, ce);
  fsw::satellite_pv_ecef(f.almanac, 2381, t0 + 100.0, pa, va);
  EXPECT_LE((pe - pa).norm(), f.max_pos_err_m + 1e-9);
  EXPECT_LT(std::abs(fsw::satellite_clock_bias_s(f.almanac, 2381, t0 + 100.0) - ce) * 299792458.0, 0.01);
  // Half an hour: the missing harmonic corrections show (meters), which is why the importer
  // splits long recordings into segments.
  const tools::AlmanacFit g = tools::fit_almanac(e[0], 2381, t0, 1800.0);
  EXPECT_GT(g.max_pos_err_m, 1.0);
  EXPECT_LT(g.max_pos_err_m, 50.0);
}

TEST(ImportRinex, ObservationEpochs) {
  const auto sat = [](const char* id, const std::vector<double>& v, const std::vector<bool>& present) {
    std::string s = id;
    for (std::size_t i = 0; i < v.size(); ++i) {
      char f[32];
      if (present[i])
        std::snprintf(f, sizeof(f), "%14.3f  ", v[i]);
      else
        std::snprintf(f, sizeof(f), "%16s", "");
      s += f;
    }
    return s + "\n";
  };
  std::string text = hdr("     3.04           OBSERVATION DATA    M: Mixed", "RINEX VERSION / TYPE") +
                     hdr("G    8 C1C L1C D1C S1C C2L L2L D2L S2L", "SYS / # / OBS TYPES") +
                     hdr("E    4 C1C L1C D1C S1C", "SYS / # / OBS TYPES") + hdr("", "END OF HEADER");
  text += "> 2025 08 28 17 30 39.7480000  0  4\n";
  text += sat("G10", {20576396.770, 108129693.934, 1064.326, 51.0, 20576399.569, 84256913.850, 829.762, 40.0},
              {true, true, true, true, true, true, true, true});
  text += sat("G02", {0, 0, 0, 0, 21000000.0, 0, -100.0, 30.0}, {false, false, false, false, true, false, true, true});
  text += sat("G18", {21875361.121, 114955809.983, 0, 36.0}, {true, true, false, true});
  text += sat("E07", {23205808.406, 121947341.562, -585.078, 48.0}, {true, true, true, true});
  text += "> 2025 08 28 17 30 39.9980000  3  1\n";  // event: one header line follows
  text += "                                                            COMMENT\n";
  text += "> 2025 08 28 17 30 40.2480000  0  1\n";
  text += sat("G10", {20576130.612, 108128295.213, 1064.500, 51.0}, {true, true, true, true});
  text += "> 2025 08 28 17 30 40.2480000  0  1\n";  // the same time again
  text += sat("G10", {20576130.612, 108128295.213, 1064.500, 51.0}, {true, true, true, true});
  text += "> 2025 08 28 17 30 40.4980000  0  1\n";
  text += "G10  20576130.612   108128";  // cut off
  std::istringstream in(text);
  tools::RinexObsStats st;
  const std::vector<tools::RinexObsEpoch> ep = tools::read_rinex3_obs(in, st);
  EXPECT_EQ(st.version, "3.04");
  EXPECT_EQ(st.event_epochs, 1u);
  ASSERT_EQ(ep.size(), 2u);
  EXPECT_EQ(ep[0].time.week, 2381);
  EXPECT_NEAR(ep[0].time.tow_s, 408639.748, 1e-9);
  ASSERT_EQ(ep[0].sats.size(), 4u);
  const tools::RinexObsSat& g10 = ep[0].sats[0];
  EXPECT_EQ(g10.sys, 'G');
  EXPECT_EQ(g10.prn, 10);
  EXPECT_TRUE(g10.has_c1c && g10.has_d1c && g10.has_s1c);
  EXPECT_EQ(g10.c1c_m, 20576396.770);
  EXPECT_EQ(g10.d1c_hz, 1064.326);
  EXPECT_EQ(g10.s1c_dbhz, 51.0);
  EXPECT_FALSE(ep[0].sats[1].has_c1c);  // L2 only
  EXPECT_TRUE(ep[0].sats[2].has_c1c);
  EXPECT_FALSE(ep[0].sats[2].has_d1c);
  EXPECT_EQ(ep[0].sats[3].sys, 'E');
  EXPECT_EQ(ep[0].sats[3].d1c_hz, -585.078);
  EXPECT_NEAR(ep[1].time.tow_s, 408640.248, 1e-9);
  EXPECT_EQ(st.lines.by_reason.at("partial last line (no newline)"), 1u);
  EXPECT_EQ(st.lines.by_reason.at("time not increasing"), 1u);
  // Pseudorange rate from Doppler: -D * lambda_L1 (a satellite coming closer has a positive
  // Doppler and a falling range).
  EXPECT_NEAR(-g10.d1c_hz * tools::kGpsL1Wavelength_m, -202.54, 0.01);
}
