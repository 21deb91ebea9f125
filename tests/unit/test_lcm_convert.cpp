// fsw <-> LCM message conversions: bit-exact round trips of the raw inputs through the encoded
// bytes, rejection of bad input, and the content of the output messages.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "fsw/ekf.hpp"
#include "fsw/executive.hpp"
#include "hal/lcm_convert.hpp"
#include "hal/lcm_channels.hpp"
#include "hal/lcm_types.hpp"
#include "lcm_test_util.hpp"
#include "test_util.hpp"

namespace {

using fsw::Vec3;
using test_util::kInf;
using test_util::kNaN;

using lcm_test::bits_equal;
using lcm_test::encode;

/// Awkward doubles: negative zero, subnormal, extremes, values that print badly in decimal.
const double kAwkward[] = {-0.0, 4.9406564584124654e-324, 1.7976931348623157e308, 0.1, -1.0 / 3.0,
                           2.2250738585072014e-308, 123456789.123456789, -7.25e-9};

hal::ImuRecord sample_imu(int k) {
  hal::ImuRecord r;
  r.sample.t_s = 12.345 + 0.001 * k;
  r.sample.dt_s = 0.001;
  r.sample.dtheta_rad = Vec3(1e-4 * std::sin(k), kAwkward[k % 8] * 1e-320 + 3.1e-5, -2.7e-6);
  r.sample.dv_mps = Vec3(0.0098, -0.0 * k, 9.80665e-3 + kAwkward[(k + 3) % 8] * 1e-312);
  r.counter = static_cast<std::int32_t>(2147483600u + static_cast<std::uint32_t>(k));  // wraps past INT32_MAX
  r.status = static_cast<std::int16_t>(k % 2 == 0 ? 0 : sdins::imu_sample_t::STATUS_GYRO_SATURATED);
  return r;
}

fsw::GpsAlmanac sample_almanac(int prn) {
  fsw::GpsAlmanac a;
  a.prn = prn;
  a.health = 0;
  a.eccentricity = 0.0123456789;
  a.toa_s = 319488.0;
  a.inclination_rad = 0.9599310886;
  a.omega_dot_radps = -7.80032e-9;
  a.sqrt_a_sqrtm = 5153.6;
  a.omega0_rad = -1.23456789;
  a.arg_perigee_rad = 0.7853981634;
  a.mean_anomaly_rad = -2.1;
  a.af0_s = 1.23e-4;
  a.af1_sps = -3.6e-12;
  a.week_mod_1024 = 199;
  return a;
}

fsw::GnssRawEpoch sample_epoch(int n) {
  fsw::GnssRawEpoch e;
  e.t_s = 100.000123;
  e.gps_week = 2290;
  e.gps_tow_s = 345600.000123;
  e.n_meas = n;
  for (int k = 0; k < fsw::kMaxGnssChannels; ++k) {
    auto& m = e.meas[static_cast<std::size_t>(k)];
    m.prn = static_cast<std::uint8_t>(k < n ? 1 + 2 * k : 0);
    m.pseudorange_m = k < n ? 2.1e7 + 1234.567891 * k + kAwkward[k % 8] * 1e-300 : 0.0;
    m.pseudorange_rate_mps = k < n ? -512.25 + 3.3 * k : 0.0;
    m.cn0_dbhz = k < n ? 40.0 + 0.1 * k : 0.0;
  }
  return e;
}

}  // namespace

TEST(LcmConvert, ImuRoundTripIsBitExact) {
  for (int k = 0; k < 64; ++k) {
    const hal::ImuRecord in = sample_imu(k);
    sdins::imu_sample_t m{};
    hal::to_msg(in, m);
    const std::vector<std::uint8_t> bytes = encode(m);
    sdins::imu_sample_t d;
    ASSERT_EQ(hal::decode_exact(bytes.data(), bytes.size(), d), hal::LcmInputStatus::kOk);
    hal::ImuRecord out;
    ASSERT_EQ(hal::from_msg(d, out), hal::LcmInputStatus::kOk) << k;
    EXPECT_TRUE(bits_equal(out.sample.t_s, in.sample.t_s));
    EXPECT_TRUE(bits_equal(out.sample.dt_s, in.sample.dt_s));
    for (int i = 0; i < 3; ++i) {
      EXPECT_TRUE(bits_equal(out.sample.dtheta_rad[i], in.sample.dtheta_rad[i])) << k << " " << i;
      EXPECT_TRUE(bits_equal(out.sample.dv_mps[i], in.sample.dv_mps[i])) << k << " " << i;
    }
    EXPECT_EQ(out.counter, in.counter);
    EXPECT_EQ(out.status, in.status);
    EXPECT_EQ(m.utime, std::llround(in.sample.t_s * 1e6));
  }
}

TEST(LcmConvert, GnssRawEpochRoundTripIsBitExact) {
  for (int n : {0, 1, 7, 16}) {
    const fsw::GnssRawEpoch in = sample_epoch(n);
    sdins::gnss_raw_epoch_t m{};
    hal::to_msg(in, m);
    const std::vector<std::uint8_t> bytes = encode(m);
    sdins::gnss_raw_epoch_t d;
    ASSERT_EQ(hal::decode_exact(bytes.data(), bytes.size(), d), hal::LcmInputStatus::kOk);
    fsw::GnssRawEpoch out;
    out.meas[3].pseudorange_m = 99.0;  // must be overwritten
    int dropped = -1;
    ASSERT_EQ(hal::from_msg(d, out, dropped), hal::LcmInputStatus::kOk);
    EXPECT_EQ(dropped, 0);
    EXPECT_TRUE(bits_equal(out.t_s, in.t_s));
    EXPECT_EQ(out.gps_week, in.gps_week);
    EXPECT_TRUE(bits_equal(out.gps_tow_s, in.gps_tow_s));
    EXPECT_EQ(out.n_meas, in.n_meas);
    for (std::size_t k = 0; k < in.meas.size(); ++k) {
      EXPECT_EQ(out.meas[k].prn, in.meas[k].prn);
      EXPECT_TRUE(bits_equal(out.meas[k].pseudorange_m, in.meas[k].pseudorange_m)) << k;
      EXPECT_TRUE(bits_equal(out.meas[k].pseudorange_rate_mps, in.meas[k].pseudorange_rate_mps)) << k;
      EXPECT_TRUE(bits_equal(out.meas[k].cn0_dbhz, in.meas[k].cn0_dbhz)) << k;
    }
  }
}

TEST(LcmConvert, AlmanacRoundTripIsBitExact) {
  for (int prn = 1; prn <= 32; ++prn) {
    const fsw::GpsAlmanac in = sample_almanac(prn);
    sdins::gps_almanac_t m{};
    hal::to_msg(in, -0.5, m);
    const std::vector<std::uint8_t> bytes = encode(m);
    sdins::gps_almanac_t d;
    ASSERT_EQ(hal::decode_exact(bytes.data(), bytes.size(), d), hal::LcmInputStatus::kOk);
    fsw::GpsAlmanac out;
    ASSERT_EQ(hal::from_msg(d, out), hal::LcmInputStatus::kOk);
    EXPECT_EQ(std::memcmp(&out, &in, sizeof(in)), 0) << "PRN " << prn;  // plain struct: every byte
    EXPECT_EQ(d.t_s, -0.5);
  }
}

TEST(LcmConvert, ImuRejectsNonFiniteOutOfRangeAndFlaggedSamples) {
  hal::LcmInputStats stats;
  const auto check = [&](const hal::ImuRecord& r, hal::LcmInputStatus want) {
    sdins::imu_sample_t m{};
    hal::to_msg(r, m);
    hal::ImuRecord out;
    out.counter = -77;
    const hal::LcmInputStatus st = hal::from_msg(m, out);
    stats.record(st);
    EXPECT_EQ(st, want);
    if (st != hal::LcmInputStatus::kOk) EXPECT_EQ(out.counter, -77) << "rejected input must not be written";
  };
  const hal::ImuRecord good = sample_imu(1);
  check(good, hal::LcmInputStatus::kOk);
  for (int field = 0; field < 8; ++field) {
    for (double bad : {kNaN, kInf, -kInf}) {
      hal::ImuRecord r = good;
      if (field == 0) r.sample.t_s = bad;
      if (field == 1) r.sample.dt_s = bad;
      if (field >= 2 && field < 5) r.sample.dtheta_rad[field - 2] = bad;
      if (field >= 5) r.sample.dv_mps[field - 5] = bad;
      check(r, hal::LcmInputStatus::kNonFinite);
    }
  }
  hal::ImuRecord r = good;
  r.sample.dt_s = 0.0;
  check(r, hal::LcmInputStatus::kOutOfRange);
  r.sample.dt_s = -0.001;
  check(r, hal::LcmInputStatus::kOutOfRange);
  r.sample.dt_s = 2.0;
  check(r, hal::LcmInputStatus::kOutOfRange);
  r = good;
  r.sample.dtheta_rad.x() = 0.2;  // 200 rad/s over 1 ms
  check(r, hal::LcmInputStatus::kOutOfRange);
  r = good;
  r.sample.dv_mps.z() = 3.0;  // 3000 m/s^2
  check(r, hal::LcmInputStatus::kOutOfRange);
  r = good;
  r.status = sdins::imu_sample_t::STATUS_GYRO_INVALID;
  check(r, hal::LcmInputStatus::kSensorFlagged);
  r.status = sdins::imu_sample_t::STATUS_ACCEL_INVALID | sdins::imu_sample_t::STATUS_ACCEL_SATURATED;
  check(r, hal::LcmInputStatus::kSensorFlagged);
  r.status = sdins::imu_sample_t::STATUS_BUILT_IN_TEST_FAILED;  // passed on, not rejected
  check(r, hal::LcmInputStatus::kOk);
  EXPECT_EQ(stats.accepted(), 2u);
  EXPECT_EQ(stats.count(hal::LcmInputStatus::kNonFinite), 24u);
  EXPECT_EQ(stats.count(hal::LcmInputStatus::kOutOfRange), 5u);
  EXPECT_EQ(stats.count(hal::LcmInputStatus::kSensorFlagged), 2u);
  EXPECT_EQ(stats.rejected(), 31u);
}

TEST(LcmConvert, GnssRejectsBadEpochsAndDropsNonFiniteMeasurements) {
  const auto convert = [](const fsw::GnssRawEpoch& e, fsw::GnssRawEpoch& out, int& dropped) {
    sdins::gnss_raw_epoch_t m{};
    hal::to_msg(e, m);
    return hal::from_msg(m, out, dropped);
  };
  fsw::GnssRawEpoch out;
  int dropped = 0;
  fsw::GnssRawEpoch e = sample_epoch(6);
  e.t_s = kNaN;
  EXPECT_EQ(convert(e, out, dropped), hal::LcmInputStatus::kNonFinite);
  e = sample_epoch(6);
  e.gps_tow_s = kInf;
  EXPECT_EQ(convert(e, out, dropped), hal::LcmInputStatus::kNonFinite);
  e = sample_epoch(6);
  e.n_meas = 17;
  EXPECT_EQ(convert(e, out, dropped), hal::LcmInputStatus::kOutOfRange);
  e.n_meas = -1;
  EXPECT_EQ(convert(e, out, dropped), hal::LcmInputStatus::kOutOfRange);
  e = sample_epoch(6);
  e.gps_tow_s = 604800.0;
  EXPECT_EQ(convert(e, out, dropped), hal::LcmInputStatus::kOutOfRange);
  e = sample_epoch(6);
  e.gps_week = -3;
  EXPECT_EQ(convert(e, out, dropped), hal::LcmInputStatus::kOutOfRange);
  // A PRN that does not fit fsw's uint8 (only reachable through a foreign message).
  sdins::gnss_raw_epoch_t m{};
  hal::to_msg(sample_epoch(6), m);
  m.meas[2].prn = 300;
  EXPECT_EQ(hal::from_msg(m, out, dropped), hal::LcmInputStatus::kOutOfRange);

  // Measurement level: entries 1 and 4 are removed, the others keep their order.
  e = sample_epoch(6);
  e.meas[1].pseudorange_m = kNaN;
  e.meas[4].cn0_dbhz = -kInf;
  ASSERT_EQ(convert(e, out, dropped), hal::LcmInputStatus::kMeasurementsDropped);
  EXPECT_EQ(dropped, 2);
  ASSERT_EQ(out.n_meas, 4);
  const int kept[] = {0, 2, 3, 5};
  for (int k = 0; k < 4; ++k) {
    EXPECT_EQ(out.meas[static_cast<std::size_t>(k)].prn, e.meas[static_cast<std::size_t>(kept[k])].prn);
    EXPECT_TRUE(bits_equal(out.meas[static_cast<std::size_t>(k)].pseudorange_m,
                           e.meas[static_cast<std::size_t>(kept[k])].pseudorange_m));
  }
  for (std::size_t k = 4; k < out.meas.size(); ++k) EXPECT_EQ(out.meas[k].pseudorange_m, 0.0);
  // NaN beyond n_meas is not the epoch's business.
  e = sample_epoch(6);
  e.meas[10].pseudorange_m = kNaN;
  EXPECT_EQ(convert(e, out, dropped), hal::LcmInputStatus::kOk);
}

TEST(LcmConvert, AlmanacRejectsNonFiniteAndImplausibleElements) {
  const auto convert = [](const fsw::GpsAlmanac& a) {
    sdins::gps_almanac_t m{};
    hal::to_msg(a, 0.0, m);
    fsw::GpsAlmanac out;
    return hal::from_msg(m, out);
  };
  fsw::GpsAlmanac a = sample_almanac(5);
  EXPECT_EQ(convert(a), hal::LcmInputStatus::kOk);
  a.sqrt_a_sqrtm = kNaN;
  EXPECT_EQ(convert(a), hal::LcmInputStatus::kNonFinite);
  a = sample_almanac(5);
  a.af1_sps = kInf;
  EXPECT_EQ(convert(a), hal::LcmInputStatus::kNonFinite);
  for (int prn : {0, 33, -1}) EXPECT_EQ(convert(sample_almanac(prn)), hal::LcmInputStatus::kOutOfRange) << prn;
  a = sample_almanac(5);
  a.eccentricity = 1.2;
  EXPECT_EQ(convert(a), hal::LcmInputStatus::kOutOfRange);
  a = sample_almanac(5);
  a.sqrt_a_sqrtm = 100.0;
  EXPECT_EQ(convert(a), hal::LcmInputStatus::kOutOfRange);
}

TEST(LcmConvert, DecodeRejectsWrongFingerprintAndWrongLength) {
  sdins::nav_solution_t nav{};
  const std::vector<std::uint8_t> nav_bytes = encode(nav);
  sdins::imu_sample_t imu;
  EXPECT_EQ(hal::decode_exact(nav_bytes.data(), nav_bytes.size(), imu), hal::LcmInputStatus::kWrongType);
  hal::to_msg(sample_imu(3), imu);
  std::vector<std::uint8_t> b = encode(imu);
  sdins::imu_sample_t d;
  EXPECT_EQ(hal::decode_exact(b.data(), b.size() - 1, d), hal::LcmInputStatus::kDecodeFailed);
  EXPECT_EQ(hal::decode_exact(b.data(), 7, d), hal::LcmInputStatus::kDecodeFailed);
  b.push_back(0);
  EXPECT_EQ(hal::decode_exact(b.data(), b.size(), d), hal::LcmInputStatus::kDecodeFailed);
  b.pop_back();
  b[3] ^= 0x01;  // fingerprint bit
  EXPECT_EQ(hal::decode_exact(b.data(), b.size(), d), hal::LcmInputStatus::kWrongType);
  EXPECT_EQ(hal::lcm_fingerprint(nav_bytes.data(), nav_bytes.size()), sdins::nav_solution_t::getHash());
}

TEST(LcmConvert, NavSolutionCarriesPositionVelocityAttitudeAndFlags) {
  fsw::NavState nav;
  nav.t_s = 61.005;
  nav.llh = Vec3(0.6108652381980153, 2.2165681500327987, 5012.25);
  nav.vel_enu_mps = Vec3(-120.5, 218.25, 3.125);
  const double roll = 1.0471975511965976, pitch = 0.0593411945678072, heading = 5.1;
  nav.q_b_n = fsw::Quat(fsw::C_b_n_from_euler(roll, pitch, heading));
  sdins::nav_solution_t m{};
  hal::to_msg(nav, true, false, m);
  EXPECT_EQ(m.utime, 61005000);
  EXPECT_EQ(m.t_s, nav.t_s);
  EXPECT_EQ(m.lat_rad, nav.llh.x());
  EXPECT_EQ(m.lon_rad, nav.llh.y());
  EXPECT_EQ(m.height_m, nav.llh.z());
  for (int i = 0; i < 3; ++i) EXPECT_EQ(m.vel_enu_mps[i], nav.vel_enu_mps[i]);
  EXPECT_NEAR(m.roll_rad, roll, 1e-12);
  EXPECT_NEAR(m.pitch_rad, pitch, 1e-12);
  EXPECT_NEAR(m.heading_rad, heading, 1e-12);
  const fsw::Quat q(m.q_b_n_wxyz[0], m.q_b_n_wxyz[1], m.q_b_n_wxyz[2], m.q_b_n_wxyz[3]);
  EXPECT_LT((q.toRotationMatrix() - nav.C_b_n()).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_EQ(m.valid, 1);
  EXPECT_EQ(m.ekf_updated, 0);
  // Truth uses the same conventions from a C_b_n matrix.
  sdins::truth_t t;
  hal::truth_to_msg(nav.t_s, nav.llh, nav.vel_enu_mps, nav.C_b_n(), t);
  EXPECT_NEAR(t.roll_rad, roll, 1e-12);
  EXPECT_NEAR(t.heading_rad, heading, 1e-12);
  const fsw::Quat qt(t.q_b_n_wxyz[0], t.q_b_n_wxyz[1], t.q_b_n_wxyz[2], t.q_b_n_wxyz[3]);
  EXPECT_LT((qt.toRotationMatrix() - nav.C_b_n()).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_GE(t.q_b_n_wxyz[0], 0.0);
}

TEST(LcmConvert, EkfStateHoldsModelSigmasAndEstimates) {
  fsw::EkfConfig cfg;
  fsw::Ekf<fsw::Layout24> ekf24;
  ASSERT_EQ(ekf24.init(cfg), fsw::Status::kOk);
  fsw::ImuCompensation comp;
  comp.accel_bias_mps2 = Vec3(1e-3, -2e-3, 3e-3);
  comp.gyro_bias_radps = Vec3(1e-7, 2e-7, -3e-7);
  comp.gyro_error(1, 2) = 7e-5;  // gamma_yz
  comp.gyro_error(2, 2) = 1e-4;  // z scale factor
  comp.accel_error(2, 1) = -4e-5;  // gamma_zy
  sdins::ekf_state_t m{};
  hal::to_msg(ekf24, comp, 10.0, m);
  EXPECT_EQ(m.n_states, 26);
  EXPECT_EQ(m.block_offset[sdins::ekf_state_t::BLOCK_POSITION], 0);
  EXPECT_EQ(m.block_offset[sdins::ekf_state_t::BLOCK_ATTITUDE], 6);
  EXPECT_EQ(m.block_offset[sdins::ekf_state_t::BLOCK_GYRO_MISALIGN], 18);
  EXPECT_EQ(m.block_offset[sdins::ekf_state_t::BLOCK_CLOCK], 24);
  EXPECT_EQ(m.block_offset[sdins::ekf_state_t::BLOCK_ACCEL_SCALE], -1);
  EXPECT_EQ(m.consider_mask, 0);
  for (int i = 0; i < 26; ++i) EXPECT_EQ(m.sigma[i], std::sqrt(ekf24.P()(i, i))) << i;
  for (int i = 26; i < 64; ++i) EXPECT_EQ(m.sigma[i], 0.0);
  EXPECT_DOUBLE_EQ(m.sigma[0], cfg.pos_sigma_m);
  EXPECT_DOUBLE_EQ(m.sigma[8], cfg.att_sigma_rad.z());
  EXPECT_DOUBLE_EQ(m.sigma[24], cfg.clock_bias_sigma_m);
  EXPECT_EQ(m.accel_bias_mps2[2], 3e-3);
  EXPECT_EQ(m.gyro_bias_radps[1], 2e-7);
  EXPECT_EQ(m.gyro_misalign_rad[3], 7e-5);  // xy, xz, yx, yz, ...
  EXPECT_EQ(m.gyro_scale_factor[2], 1e-4);
  EXPECT_EQ(m.accel_misalign_rad[2], -4e-5);  // yx, zx, zy
  EXPECT_EQ(m.clock_initialised, 0);

  fsw::Ekf<fsw::Layout15Full> ekf15f;
  ASSERT_EQ(ekf15f.init(cfg), fsw::Status::kOk);
  hal::to_msg(ekf15f, comp, 10.0, m);
  EXPECT_EQ(m.n_states, 56);
  const int consider = (1 << sdins::ekf_state_t::BLOCK_ACCEL_MISALIGN) | (1 << sdins::ekf_state_t::BLOCK_GYRO_MISALIGN) |
                       (1 << sdins::ekf_state_t::BLOCK_ACCEL_SCALE) | (1 << sdins::ekf_state_t::BLOCK_GYRO_SCALE);
  EXPECT_EQ(m.consider_mask, consider);
  EXPECT_EQ(m.block_offset[sdins::ekf_state_t::BLOCK_RANGE_RATE_ERROR], 44);

  // CSV names of the sigma columns come from the block offsets.
  const std::vector<std::uint8_t> b = encode(m);
  const hal::LcmTypeInfo* t = hal::find_lcm_type(sdins::ekf_state_t::getHash());
  ASSERT_NE(t, nullptr);
  hal::LcmRow row;
  ASSERT_EQ(t->row(b.data(), b.size(), row), hal::LcmInputStatus::kOk);
  const auto& names = row.names();
  const auto at = [&](const std::string& n) { return std::find(names.begin(), names.end(), n) - names.begin(); };
  EXPECT_LT(at("sigma_att_U_rad"), static_cast<long>(names.size()));
  EXPECT_LT(at("sigma_gyro_mis_zy_rad"), static_cast<long>(names.size()));
  EXPECT_LT(at("sigma_range_rate_err_ch11_mps"), static_cast<long>(names.size()));
  EXPECT_EQ(at("sigma[0]"), static_cast<long>(names.size()));  // every state has a name
  EXPECT_EQ(row.cells()[static_cast<std::size_t>(at("sigma_pos_E_m"))], "10");
}

TEST(LcmConvert, HealthCarriesCountersAndPerObservationInnovations) {
  fsw::ExecutiveHealth h;
  h.ticks = 4000000000u;  // above int32: must survive in the int64 field
  h.ekf_updates = 17;
  h.pr_rejected = 3;
  h.worst_tick_s = 0.0042;
  fsw::GnssConversionStats conv;
  conv.no_almanac = 2;
  conv.duplicate_prn = 1;
  fsw::FrameOutput frame;
  frame.ekf_updated = true;
  auto& r = frame.report;
  r.pr_used = 1;
  r.pr_rejected = 1;
  r.obs_invalid = 1;
  r.n_obs = 3;
  r.obs[0] = {5, fsw::InnovationOutcome::kUsed, fsw::InnovationOutcome::kUsed, -3.0, 16.0, 0.1, 0.04};
  r.obs[1] = {9, fsw::InnovationOutcome::kGated, fsw::InnovationOutcome::kUsed, 400.0, 100.0, -0.2, 0.01};
  r.obs[2] = {12, fsw::InnovationOutcome::kInvalid, fsw::InnovationOutcome::kInvalid, 0.0, 0.0, 0.0, 0.0};
  sdins::filter_health_t m{};
  hal::to_msg(77.0, h, conv, frame, 10.83, m);
  EXPECT_EQ(m.ticks, 4000000000LL);
  EXPECT_EQ(m.ekf_updates, 17);
  EXPECT_EQ(m.pr_rejected, 3);
  EXPECT_EQ(m.worst_tick_s, 0.0042);
  EXPECT_EQ(m.conv_no_almanac, 2);
  EXPECT_EQ(m.conv_duplicate_prn, 1);
  EXPECT_EQ(m.ekf_updated, 1);
  EXPECT_EQ(m.gate_chi2, 10.83);
  EXPECT_EQ(m.epoch_pr_rejected, 1);
  ASSERT_EQ(m.n_obs, 3);
  EXPECT_EQ(m.prn[1], 9);
  EXPECT_EQ(m.pr_outcome[0], sdins::filter_health_t::OUTCOME_USED);
  EXPECT_EQ(m.pr_outcome[1], sdins::filter_health_t::OUTCOME_GATED);
  EXPECT_EQ(m.pr_outcome[2], sdins::filter_health_t::OUTCOME_INVALID);
  EXPECT_EQ(m.pr_innovation_m[0], -3.0);
  EXPECT_EQ(m.pr_innovation_sigma_m[0], 4.0);
  EXPECT_EQ(m.pr_normalised[0], -0.75);
  EXPECT_EQ(m.pr_normalised[1], 40.0);  // 40^2 > 10.83: gated
  EXPECT_EQ(m.prr_innovation_sigma_mps[1], 0.1);
  EXPECT_EQ(m.prr_normalised[1], -2.0);
  EXPECT_EQ(m.pr_innovation_m[2], 0.0);
  EXPECT_EQ(m.prn[3], 0);
}

TEST(LcmConvert, HealthCarriesTheLooselyCoupledUpdate) {
  fsw::ExecutiveHealth h;
  h.pvt_received = 40;
  h.pvt_stale = 2;
  h.pvt_unused = 1;
  h.pos_used = 111;
  h.vel_rejected = 4;
  fsw::FrameOutput frame;
  frame.ekf_updated = true;
  auto& r = frame.report;
  r.pvt = true;
  r.pos_used = 3;
  r.vel_used = 1;
  r.vel_rejected = 1;
  r.pvt_obs[0] = {fsw::InnovationOutcome::kUsed, 0.3, 0.09};
  r.pvt_obs[1] = {fsw::InnovationOutcome::kUsed, -0.2, 0.04};
  r.pvt_obs[2] = {fsw::InnovationOutcome::kUsed, 0.0, 0.25};
  r.pvt_obs[3] = {fsw::InnovationOutcome::kGated, 1.5, 0.01};
  r.pvt_obs[4] = {fsw::InnovationOutcome::kUsed, 0.05, 0.0025};
  r.pvt_obs[5] = {fsw::InnovationOutcome::kNotProcessed, 0.0, 0.0};
  sdins::filter_health_t m{};
  hal::to_msg(12.5, h, fsw::GnssConversionStats{}, frame, 9.0, m);
  EXPECT_EQ(m.pvt_received, 40);
  EXPECT_EQ(m.pvt_stale, 2);
  EXPECT_EQ(m.pvt_unused, 1);
  EXPECT_EQ(m.pos_used, 111);
  EXPECT_EQ(m.vel_rejected, 4);
  EXPECT_EQ(m.pvt_update, 1);
  EXPECT_EQ(m.epoch_pos_used, 3);
  EXPECT_EQ(m.epoch_vel_used, 1);
  EXPECT_EQ(m.epoch_vel_rejected, 1);
  EXPECT_EQ(m.n_obs, 0);  // no pseudoranges in a PVT update
  EXPECT_EQ(m.pvt_outcome[0], sdins::filter_health_t::OUTCOME_USED);
  EXPECT_EQ(m.pvt_outcome[3], sdins::filter_health_t::OUTCOME_GATED);
  EXPECT_EQ(m.pvt_outcome[5], sdins::filter_health_t::OUTCOME_NOT_PROCESSED);
  EXPECT_DOUBLE_EQ(m.pvt_innovation_sigma[0], 0.3);
  EXPECT_DOUBLE_EQ(m.pvt_normalised[0], 1.0);
  EXPECT_DOUBLE_EQ(m.pvt_normalised[1], -1.0);
  EXPECT_DOUBLE_EQ(m.pvt_normalised[3], 15.0);  // 15^2 > 9: gated
  EXPECT_EQ(m.pvt_innovation[5], 0.0);
  EXPECT_EQ(m.pvt_innovation_sigma[5], 0.0);

  // A raw-epoch update leaves the PVT part empty.
  fsw::FrameOutput raw;
  raw.ekf_updated = true;
  raw.report.n_obs = 1;
  raw.report.obs[0] = {5, fsw::InnovationOutcome::kUsed, fsw::InnovationOutcome::kUsed, -3.0, 16.0, 0.1, 0.04};
  hal::to_msg(13.0, h, fsw::GnssConversionStats{}, raw, 9.0, m);
  EXPECT_EQ(m.pvt_update, 0);
  EXPECT_EQ(m.pvt_outcome[0], sdins::filter_health_t::OUTCOME_NOT_PROCESSED);
  EXPECT_EQ(m.pvt_innovation[0], 0.0);
  EXPECT_EQ(m.n_obs, 1);

  // The CSV export has the six scalars as columns, filled for a PVT update, empty otherwise.
  const hal::LcmTypeInfo* t = hal::find_lcm_type(sdins::filter_health_t::getHash());
  ASSERT_NE(t, nullptr);
  const auto cell = [&](const sdins::filter_health_t& msg, const std::string& name) {
    const std::vector<std::uint8_t> b = encode(msg);
    hal::LcmRow row;
    EXPECT_EQ(t->row(b.data(), b.size(), row), hal::LcmInputStatus::kOk);
    const auto& names = row.names();
    const auto i = static_cast<std::size_t>(std::find(names.begin(), names.end(), name) - names.begin());
    EXPECT_LT(i, names.size()) << name;
    return i < names.size() ? row.cells()[i] : std::string("<missing>");
  };
  EXPECT_EQ(cell(m, "pvt_normalised[0]"), "");
  EXPECT_EQ(cell(m, "pos_used"), "111");
  hal::to_msg(12.5, h, fsw::GnssConversionStats{}, frame, 9.0, m);
  EXPECT_EQ(cell(m, "pvt_normalised[3]"), "15");
  EXPECT_EQ(cell(m, "pvt_outcome[3]"), "2");
}

TEST(LcmConvert, EveryTypeHasAUniqueFingerprintAndEveryChannelAType) {
  const auto& types = hal::lcm_types();
  ASSERT_EQ(types.size(), 8u);  // 7 + gnss_pvt_t
  for (std::size_t i = 0; i < types.size(); ++i)
    for (std::size_t j = i + 1; j < types.size(); ++j) EXPECT_NE(types[i].fingerprint, types[j].fingerprint);
  for (const hal::LcmChannelInfo& c : hal::kLcmChannels) {
    const hal::LcmTypeInfo* t = hal::lcm_channel_type(c.channel);
    ASSERT_NE(t, nullptr) << c.channel;
    EXPECT_EQ(t->name, c.type_name);
  }
  EXPECT_EQ(hal::lcm_channel_type("SOMETHING_ELSE"), nullptr);
}
