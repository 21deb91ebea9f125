// YUMA almanac reader and almanac orbit propagation: the shipped week-431 almanac, rejection of
// malformed files, orbit invariants (vis-viva, angular momentum, Kepler radius), analytic vs
// finite-difference velocity, a closed-form circular equatorial orbit, look angles, visibility.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <string>
#include <vector>

#include "sim/almanac.hpp"
#include "sim/scenario.hpp"
#include "test_util.hpp"

using namespace sim;
using fsw::kDegToRad;
using fsw::kPi;
using fsw::Vec3;

namespace {

using test_util::shipped_almanac;

constexpr int kFullWeek = 1455;
constexpr double kToa = 589824.0;


/// A valid record (lines 1..14) for PRN `prn`, ending with a blank line.
std::string record(int prn) {
  return "******** Week 431 almanac for PRN-" + std::to_string(prn) +
         " ********\n"
         "ID:                         " +
         std::to_string(prn) +
         "\n"
         "Health:                     000\n"
         "Eccentricity:               0.7102489471E-002\n"
         "Time of Applicability(s):   589824.0000\n"
         "Orbital Inclination(rad):   0.9908943176\n"
         "Rate of Right Ascen(r/s):  -0.7632479537E-008\n"
         "SQRT(A)  (m 1/2):           5153.553711\n"
         "Right Ascen at Week(rad):  -0.1041447520E+001\n"
         "Argument of Perigee(rad):  -1.798838139\n"
         "Mean Anom(rad):            -0.2883712769E+001\n"
         "Af0(s):                     0.1697540283E-003\n"
         "Af1(s/s):                   0.3637978807E-011\n"
         "week:                        431\n"
         "\n";
}

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto pos = s.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  if (pos != std::string::npos) s.replace(pos, from.size(), to);
  return s;
}

std::string parse_error(const std::string& text) {
  const AlmanacParseResult r = parse_yuma_text(text, "t.alm");
  EXPECT_FALSE(r.ok());
  return r.error;
}

Vec3 omega_e() { return Vec3(0.0, 0.0, kGpsOmegaE_radps); }

}  // namespace

TEST(AlmanacParse, ShippedFile) {
  const std::vector<AlmanacEntry> alm = shipped_almanac();
  ASSERT_EQ(alm.size(), 31u);
  for (const AlmanacEntry& s : alm) {
    EXPECT_NE(s.prn, 29);
    EXPECT_EQ(s.week_mod_1024, 431);
    EXPECT_DOUBLE_EQ(s.toa_s, kToa);
    EXPECT_EQ(s.health, s.prn == 32 ? 63 : 0) << s.prn;
  }
  EXPECT_EQ(alm.front().prn, 1);
  EXPECT_EQ(alm.back().prn, 32);
  const AlmanacEntry& p1 = alm.front();
  EXPECT_DOUBLE_EQ(p1.eccentricity, 0.7102489471E-002);
  EXPECT_DOUBLE_EQ(p1.inclination_rad, 0.9908943176);
  EXPECT_DOUBLE_EQ(p1.omega_dot_radps, -0.7632479537E-008);
  EXPECT_DOUBLE_EQ(p1.sqrt_a_sqrtm, 5153.553711);
  EXPECT_DOUBLE_EQ(p1.omega0_rad, -0.1041447520E+001);
  EXPECT_DOUBLE_EQ(p1.arg_perigee_rad, -1.798838139);
  EXPECT_DOUBLE_EQ(p1.mean_anomaly_rad, -0.2883712769E+001);
  EXPECT_DOUBLE_EQ(p1.af0_s, 0.1697540283E-003);
  EXPECT_DOUBLE_EQ(p1.af1_sps, 0.3637978807E-011);
}

TEST(AlmanacParse, ValidSmallTextAndCrLf) {
  std::string text = record(5) + record(3);
  AlmanacParseResult r = parse_yuma_text(text, "t.alm");
  ASSERT_TRUE(r.ok()) << r.error;
  ASSERT_EQ(r.almanac->size(), 2u);
  EXPECT_EQ((*r.almanac)[0].prn, 3);  // sorted by PRN
  EXPECT_EQ((*r.almanac)[1].prn, 5);
  std::string crlf;
  for (char c : text) {
    if (c == '\n') crlf += '\r';
    crlf += c;
  }
  r = parse_yuma_text(crlf, "t.alm");
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(r.almanac->size(), 2u);
}

TEST(AlmanacParse, RejectsMalformedWithLineNumbers) {
  const std::string good = record(1) + record(2);  // record 2 starts on line 16
  EXPECT_EQ(parse_error(""), "t.alm:1: no almanac records");
  EXPECT_EQ(parse_error("\n\n"), "t.alm:2: no almanac records");
  EXPECT_EQ(parse_error(replace(good, "Af1(s/s)", "Af2(s/s)")), "t.alm:13: unknown field 'Af2(s/s)'");
  EXPECT_EQ(parse_error(replace(good, "Health:                     000\n", "")),
            "t.alm:1: record misses field 'health'");
  // Missing field in the last record (no following header).
  std::string last_missing = good;
  last_missing.replace(last_missing.rfind("week:"), std::string("week:                        431\n").size(), "");
  EXPECT_EQ(parse_error(last_missing), "t.alm:16: record misses field 'week'");
  EXPECT_EQ(parse_error(replace(good, "5153.553711", "5153.55x")),
            "t.alm:8: field 'sqrt(a) (m 1/2)': not a finite number: '5153.55x'");
  EXPECT_EQ(parse_error(replace(good, "0.9908943176", "nan")),
            "t.alm:6: field 'orbital inclination(rad)': not a finite number: 'nan'");
  EXPECT_EQ(parse_error(replace(good, "-1.798838139", "")),
            "t.alm:10: field 'argument of perigee(rad)': not a finite number: ''");
  EXPECT_EQ(parse_error(replace(good, "0.7102489471E-002", "1.0")), "t.alm:4: eccentricity outside [0, 1)");
  EXPECT_EQ(parse_error(replace(good, "0.7102489471E-002", "-0.001")), "t.alm:4: eccentricity outside [0, 1)");
  EXPECT_EQ(parse_error(replace(good, "5153.553711", "0.0")), "t.alm:8: sqrt(A) not positive");
  EXPECT_EQ(parse_error(record(7) + record(7)), "t.alm:17: duplicate PRN 7");
  EXPECT_EQ(parse_error(record(33)), "t.alm:2: PRN 33 outside 1..32");
  EXPECT_EQ(parse_error(record(0)), "t.alm:2: PRN 0 outside 1..32");
  EXPECT_EQ(parse_error(replace(good, "ID:                         1\n", "ID:                         1.5\n")),
            "t.alm:2: field 'id': not an integer: '1.5'");
  EXPECT_EQ(parse_error(replace(good, "week:                        431", "week:                        431\nweek: 431")),
            "t.alm:15: duplicate field 'week' (first on line 14)");
  EXPECT_EQ(parse_error("ID: 1\n" + good), "t.alm:1: field 'ID' before the first record header");
  EXPECT_EQ(parse_error(replace(good, "Af0(s):", "Af0(s)")), "t.alm:12: expected 'field: value', got 'Af0(s)                     0.1697540283E-003'");
  const AlmanacParseResult missing = parse_yuma_file("/nonexistent/x.alm");
  EXPECT_FALSE(missing.ok());
  EXPECT_EQ(missing.error, "/nonexistent/x.alm:0: cannot open almanac file: No such file or directory");
}

TEST(AlmanacWeek, RolloverNearestReference) {
  EXPECT_EQ(full_week(431, 1455), 1455);
  EXPECT_EQ(full_week(431, 1000), 1455);  // 1455 is 455 away, 431 is 569 away
  EXPECT_EQ(full_week(431, 900), 431);
  EXPECT_EQ(full_week(431, 2400), 2479);
  EXPECT_EQ(full_week(1023, 1025), 1023);
  EXPECT_EQ(full_week(0, 1023), 1024);
  EXPECT_EQ(full_week(5, 2050), 2053);
}

TEST(AlmanacOrbit, RadiusSpeedAndInvariantsForAllSatellites) {
  const std::vector<AlmanacEntry> alm = shipped_almanac();
  ASSERT_FALSE(alm.empty());
  for (const AlmanacEntry& s : alm) {
    const double a = s.sqrt_a_sqrtm * s.sqrt_a_sqrtm;
    EXPECT_NEAR(a, 26560e3, 100e3) << s.prn;
    for (double dt : {0.0, 3600.0, 20000.0, -43200.0}) {
      Vec3 r, v;
      satellite_pv_ecef(s, kFullWeek, kToa + dt, r, v);
      const double rn = r.norm();
      EXPECT_GE(rn, a * (1.0 - s.eccentricity) - 1e-3) << s.prn;
      EXPECT_LE(rn, a * (1.0 + s.eccentricity) + 1e-3) << s.prn;
      const Vec3 v_inertial = v + omega_e().cross(r);  // ECEF-frame components of the inertial velocity
      const double speed = v_inertial.norm();
      // Circular speed ~3.87 km/s, scaled by the perigee/apogee factor sqrt((1 +- e) / (1 -+ e)).
      const double v_circ = std::sqrt(kGpsGM_m3ps2 / a);
      EXPECT_NEAR(v_circ, 3874.0, 10.0) << s.prn;
      const double ecc = s.eccentricity;
      EXPECT_GE(speed, v_circ * std::sqrt((1.0 - ecc) / (1.0 + ecc)) - 0.5) << s.prn;
      EXPECT_LE(speed, v_circ * std::sqrt((1.0 + ecc) / (1.0 - ecc)) + 0.5) << s.prn;
      // In the frame co-rotating with the regressing node (rate Omega_dot) the orbit is a fixed
      // Kepler ellipse: vis-viva, angular momentum and inclination hold exactly (IS-GPS-200 GM).
      const Vec3 v_kep = v + Vec3(0.0, 0.0, kGpsOmegaE_radps - s.omega_dot_radps).cross(r);
      const double vk2 = v_kep.squaredNorm();
      EXPECT_NEAR(vk2, kGpsGM_m3ps2 * (2.0 / rn - 1.0 / a), 1e-10 * vk2) << s.prn;
      EXPECT_NEAR(r.cross(v_kep).norm(), std::sqrt(kGpsGM_m3ps2 * a * (1.0 - s.eccentricity * s.eccentricity)),
                  1e-10 * std::sqrt(kGpsGM_m3ps2 * a))
          << s.prn;
      const Vec3 h = r.cross(v_kep).normalized();
      EXPECT_NEAR(std::acos(h.z()), s.inclination_rad, 1e-9) << s.prn;
    }
  }
}

TEST(AlmanacOrbit, VelocityEqualsCentralFiniteDifference) {
  const std::vector<AlmanacEntry> alm = shipped_almanac();
  ASSERT_FALSE(alm.empty());
  const double h = 0.5;
  double worst = 0.0;
  for (const AlmanacEntry& s : alm) {
    for (double dt : {0.0, 7000.0, -30000.0}) {
      const double t = kToa + dt;
      Vec3 r, v, rp, vp, rm, vm;
      satellite_pv_ecef(s, kFullWeek, t, r, v);
      satellite_pv_ecef(s, kFullWeek, t + h, rp, vp);
      satellite_pv_ecef(s, kFullWeek, t - h, rm, vm);
      const double err = ((rp - rm) / (2.0 * h) - v).norm();
      worst = std::max(worst, err);
      EXPECT_LT(err, 1e-3) << s.prn << " dt " << dt;
    }
  }
  RecordProperty("worst_fd_velocity_error_mps", std::to_string(worst));
}

TEST(AlmanacOrbit, MeanAnomalyAtToaIsM0) {
  const std::vector<AlmanacEntry> alm = shipped_almanac();
  ASSERT_FALSE(alm.empty());
  const AlmanacEntry& s = alm.front();  // PRN 1
  // Independent Kepler solution by fixed-point iteration E = M + e sin E.
  double ecc = s.mean_anomaly_rad;
  for (int i = 0; i < 200; ++i) ecc = s.mean_anomaly_rad + s.eccentricity * std::sin(ecc);
  const double a = s.sqrt_a_sqrtm * s.sqrt_a_sqrtm;
  Vec3 r, v;
  satellite_pv_ecef(s, kFullWeek, kToa, r, v);
  EXPECT_NEAR(r.norm(), a * (1.0 - s.eccentricity * std::cos(ecc)), 1e-6);
  // Radial velocity r_dot = a e sin(E) E_dot (Earth rotation does not change r_dot).
  const double n = std::sqrt(kGpsGM_m3ps2 / (a * a * a));
  const double r_dot = a * s.eccentricity * std::sin(ecc) * n / (1.0 - s.eccentricity * std::cos(ecc));
  EXPECT_NEAR(r.dot(v) / r.norm(), r_dot, 1e-9);
  // Clock bias at toa is af0, and drifts with af1.
  EXPECT_DOUBLE_EQ(satellite_clock_bias_s(s, kFullWeek, kToa), s.af0_s);
  EXPECT_NEAR(satellite_clock_bias_s(s, kFullWeek, kToa + 1000.0), s.af0_s + 1000.0 * s.af1_sps, 1e-18);
}

TEST(AlmanacOrbit, CircularEquatorialOrbitMatchesClosedForm) {
  AlmanacEntry s;
  s.prn = 1;
  s.eccentricity = 0.0;
  s.inclination_rad = 0.0;
  s.sqrt_a_sqrtm = 5153.6;
  s.toa_s = 61440.0;
  s.omega0_rad = 0.3;
  s.arg_perigee_rad = 0.7;
  s.mean_anomaly_rad = -1.1;
  s.omega_dot_radps = -8e-9;
  s.week_mod_1024 = 431;
  const double a = s.sqrt_a_sqrtm * s.sqrt_a_sqrtm;
  const double n = std::sqrt(kGpsGM_m3ps2 / (a * a * a));
  for (double tk : {0.0, 1234.5, 43200.0, -20000.0}) {
    // ECEF longitude of the satellite: node + argument of latitude.
    const double rate = n + s.omega_dot_radps - kGpsOmegaE_radps;
    const double lon = s.omega0_rad - kGpsOmegaE_radps * s.toa_s + s.arg_perigee_rad + s.mean_anomaly_rad + rate * tk;
    const Vec3 r_exp(a * std::cos(lon), a * std::sin(lon), 0.0);
    const Vec3 v_exp(-a * rate * std::sin(lon), a * rate * std::cos(lon), 0.0);
    Vec3 r, v;
    satellite_pv_ecef(s, kFullWeek, s.toa_s + tk, r, v);
    EXPECT_LT((r - r_exp).norm(), 1e-6) << tk;
    EXPECT_LT((v - v_exp).norm(), 1e-9) << tk;
  }
}

TEST(AlmanacOrbit, WeekCrossoverIsContinuous) {
  const std::vector<AlmanacEntry> alm = shipped_almanac();
  ASSERT_FALSE(alm.empty());
  const AlmanacEntry& s = alm[3];
  // 30000 s after toa lies in week 1456: both week/tow spellings give the same state.
  Vec3 r1, v1, r2, v2;
  satellite_pv_ecef(s, kFullWeek, kToa + 30000.0, r1, v1);
  satellite_pv_ecef(s, kFullWeek + 1, kToa + 30000.0 - kSecondsPerWeek, r2, v2);
  EXPECT_LT((r1 - r2).norm(), 1e-6);
  EXPECT_LT((v1 - v2).norm(), 1e-9);
  EXPECT_NEAR(time_from_applicability_s(s, kFullWeek + 1, 100.0), 100.0 + kSecondsPerWeek - kToa, 1e-9);
  // After the 1024-week rollover the same almanac week-mod-1024 resolves to week 1455 + 1024.
  EXPECT_NEAR(time_from_applicability_s(s, kFullWeek + 1024, kToa + 5.0), 5.0, 1e-9);
}

TEST(AlmanacLook, OverheadNorthAndEast) {
  const Vec3 rx(35.0 * kDegToRad, 127.0 * kDegToRad, 120.0);
  const Vec3 overhead = fsw::ecef_from_llh(Vec3(rx.x(), rx.y(), 20200e3));
  EXPECT_NEAR(look_angles(rx, overhead).elevation_rad, kPi / 2, 1e-12);
  // Points along the local ENU axes.
  const Vec3 r0 = fsw::ecef_from_llh(rx);
  const fsw::Mat3 c = fsw::C_n_e(rx.x(), rx.y());
  const LookAngles north = look_angles(rx, r0 + c * Vec3(0.0, 1000.0, 1000.0));
  EXPECT_NEAR(north.elevation_rad, kPi / 4, 1e-9);
  EXPECT_NEAR(north.azimuth_rad, 0.0, 1e-9);
  const LookAngles east = look_angles(rx, r0 + c * Vec3(1000.0, 0.0, -10.0));
  EXPECT_NEAR(east.azimuth_rad, kPi / 2, 1e-9);
  EXPECT_LT(east.elevation_rad, 0.0);
  const LookAngles west = look_angles(rx, r0 + c * Vec3(-1000.0, 0.0, 0.0));
  EXPECT_NEAR(west.azimuth_rad, 1.5 * kPi, 1e-9);
  // The Earth's centre is straight down.
  EXPECT_NEAR(look_angles(Vec3(0.0, 0.5, 0.0), Vec3::Zero()).elevation_rad, -kPi / 2, 1e-12);
}

TEST(AlmanacVisible, SeoulAtToa) {
  const std::vector<AlmanacEntry> alm = shipped_almanac();
  ASSERT_FALSE(alm.empty());
  const Vec3 rx(35.0 * kDegToRad, 127.0 * kDegToRad, 0.0);
  std::vector<Visible> vis;
  visible_satellites(alm, kFullWeek, kToa, rx, 10.0 * kDegToRad, vis);
  EXPECT_GE(vis.size(), 6u);
  EXPECT_LE(vis.size(), 14u);
  std::string prns;
  for (const Visible& v : vis) {
    EXPECT_NE(v.prn, 32);  // unhealthy
    EXPECT_GE(v.elevation_rad, 10.0 * kDegToRad);
    EXPECT_LE(v.elevation_rad, kPi / 2);
    EXPECT_GE(v.azimuth_rad, 0.0);
    EXPECT_LT(v.azimuth_rad, 2.0 * kPi);
    const LookAngles la = look_angles(rx, v.r_ecef_m);
    EXPECT_DOUBLE_EQ(la.elevation_rad, v.elevation_rad);
    prns += " " + std::to_string(v.prn);
  }
  RecordProperty("visible_count", static_cast<int>(vis.size()));
  RecordProperty("visible_prns", prns);
  std::cout << "visible above 10 deg at 35N 127E, week 1455 tow 589824: " << vis.size() << " PRNs" << prns << "\n";
  // A -90 deg mask keeps every healthy satellite.
  visible_satellites(alm, kFullWeek, kToa, rx, -kPi / 2, vis);
  EXPECT_EQ(vis.size(), 30u);
}
