// CAN protocol codec: bit-exact round trips, quantization bounds, residual carry, range handling.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "fsw/gps_orbit.hpp"
#include "hal/can_protocol.hpp"
#include "sim/almanac.hpp"
#include "sim/scenario.hpp"
#include "sim/rng.hpp"
#include "sim/sensor_stream.hpp"

namespace {

using hal::CanFrame;
using namespace hal::can;

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
bool same_sample(const fsw::ImuSample& a, const fsw::ImuSample& b) {
  bool s = same_bits(a.t_s, b.t_s) && same_bits(a.dt_s, b.dt_s);
  for (int i = 0; i < 3; ++i) s = s && same_bits(a.dtheta_rad(i), b.dtheta_rad(i)) && same_bits(a.dv_mps(i), b.dv_mps(i));
  return s;
}

std::vector<fsw::GpsAlmanac> default_almanac() {
  const sim::AlmanacParseResult r = sim::parse_yuma_file(sim::default_almanac_path());
  EXPECT_TRUE(r.ok()) << r.error;
  return r.ok() ? *r.almanac : std::vector<fsw::GpsAlmanac>{};
}

TEST(CanProtocol, Crc16CcittFalseCheckValue) {
  const char* s = "123456789";
  EXPECT_EQ(crc16_ccitt(reinterpret_cast<const std::uint8_t*>(s), 9), 0x29B1);
}

// The definition bit by bit (the register shifted through the polynomial once per message bit),
// against the table implementation (eight bytes at a time, then byte by byte): every length of a
// CAN FD payload, random bytes, and the continuation from a running CRC (frame_crc continues from the identifier's two bytes).
std::uint16_t crc16_ccitt_bitwise(const std::uint8_t* data, int n, std::uint16_t crc) {
  for (int i = 0; i < n; ++i)
    for (int b = 7; b >= 0; --b) {
      const bool top = ((crc >> 15) ^ (data[i] >> b)) & 1u;
      crc = static_cast<std::uint16_t>(crc << 1);
      if (top) crc ^= 0x1021u;
    }
  return crc;
}

TEST(CanProtocol, Crc16TableMatchesTheBitwiseDefinition) {
  std::mt19937 rng(20261207);
  std::array<std::uint8_t, 64> buf{};
  for (int trial = 0; trial < 2000; ++trial) {
    for (auto& b : buf) b = static_cast<std::uint8_t>(rng());
    const int n = static_cast<int>(rng() % 65);
    const auto start = static_cast<std::uint16_t>(trial == 0 ? 0xFFFFu : rng());
    ASSERT_EQ(crc16_ccitt(buf.data(), n, start), crc16_ccitt_bitwise(buf.data(), n, start)) << "trial " << trial;
  }
  // A single flipped bit anywhere in a 48-byte IMU payload changes the CRC.
  const std::uint16_t ref = crc16_ccitt(buf.data(), 48);
  for (int bit = 0; bit < 48 * 8; ++bit) {
    buf[static_cast<std::size_t>(bit / 8)] ^= static_cast<std::uint8_t>(1u << (bit % 8));
    EXPECT_NE(crc16_ccitt(buf.data(), 48), ref) << "bit " << bit;
    buf[static_cast<std::size_t>(bit / 8)] ^= static_cast<std::uint8_t>(1u << (bit % 8));
  }
}

TEST(CanProtocol, FrameCrcIsTheDefinitionOverTheIdentifierAndThePayload) {
  // frame_crc: the identifier's two bytes (little-endian), then the payload up to the CRC field,
  // from 0xFFFF, bit by bit; every CAN FD length.
  std::mt19937 rng(7);
  for (int len : {0, 1, 2, 3, 8, 12, 16, 20, 24, 32, 48, 64})
    for (int trial = 0; trial < 50; ++trial) {
      hal::CanFrame f;
      f.id = static_cast<std::uint32_t>(rng() & 0x7FFu);
      f.len = static_cast<std::uint8_t>(len);
      for (auto& b : f.data) b = static_cast<std::uint8_t>(rng());
      const std::uint8_t id_le[2] = {static_cast<std::uint8_t>(f.id & 0xFFu), static_cast<std::uint8_t>(f.id >> 8)};
      std::uint16_t want = crc16_ccitt_bitwise(id_le, 2, 0xFFFF);
      if (len >= 2) want = crc16_ccitt_bitwise(f.data.data(), len - 2, want);
      ASSERT_EQ(hal::can::frame_crc(f), want) << "len " << len << " trial " << trial;
    }
}

TEST(CanProtocol, DlcTable) {
  for (int len : {0, 1, 8, 12, 16, 20, 24, 32, 48, 64}) EXPECT_EQ(hal::can_dlc_to_len(hal::can_len_to_dlc(len)), len);
  EXPECT_EQ(hal::can_len_to_dlc(9), -1);
  EXPECT_FALSE(hal::can_fd_len_valid(33));
}

TEST(CanProtocol, ImuFrameLayoutAndScaling) {
  ImuEncoder enc(7);
  fsw::ImuSample s;
  s.t_s = 12.345;
  s.dt_s = 0.001;
  s.dtheta_rad = fsw::Vec3(1e-11, -2e-11, 0.0123);
  s.dv_mps = fsw::Vec3(1e-9, -0.5, 0.0098);
  CanFrame f;
  ASSERT_EQ(enc.encode(s, f), CodecStatus::kOk);
  EXPECT_EQ(f.id, kIdImuSample);
  EXPECT_TRUE(f.fd && f.brs && !f.extended);
  EXPECT_EQ(f.len, kLenImuSample);
  // Little-endian fields at the DBC's offsets.
  EXPECT_EQ(f.data[0], 7);
  std::int64_t t_ns;
  std::memcpy(&t_ns, &f.data[4], 8);
  EXPECT_EQ(t_ns, 12345000000LL);
  std::int32_t dth_x, dth_y, dth_z;
  std::memcpy(&dth_x, &f.data[16], 4);
  std::memcpy(&dth_y, &f.data[20], 4);
  std::memcpy(&dth_z, &f.data[24], 4);
  EXPECT_EQ(dth_x, 1);
  EXPECT_EQ(dth_y, -2);
  EXPECT_EQ(dth_z, 1230000000);
  std::int32_t dv_y;
  std::memcpy(&dv_y, &f.data[32], 4);
  EXPECT_EQ(dv_y, -500000000);
  ImuFrame d;
  ASSERT_EQ(decode_imu(f, d), CodecStatus::kOk);
  EXPECT_EQ(d.counter, 7u);
  EXPECT_EQ(d.sample.t_s, 12.345);
  EXPECT_EQ(d.sample.dt_s, 0.001);
  EXPECT_EQ(enc.next_counter(), 8u);
}

TEST(CanProtocol, ImuRoundTripIsBitExactOnTheGrid) {
  // Decoded samples lie on the protocol grid: encoding them again reproduces the frame byte for
  // byte and the decoded fsw struct bit for bit (what makes SIL and HIL inputs identical).
  sim::Scenario sc;
  sc.duration_s = 2.0;
  sim::SensorStream stream(sc);
  sim::SensorStep step;
  ImuEncoder enc, enc2;
  int n = 0;
  while (stream.next(step))
    for (const fsw::ImuSample& s : step.imu) {
      CanFrame f1, f2;
      ASSERT_EQ(enc.encode(s, f1), CodecStatus::kOk);
      ImuFrame d1, d2;
      ASSERT_EQ(decode_imu(f1, d1), CodecStatus::kOk);
      ASSERT_EQ(enc2.encode(d1.sample, f2), CodecStatus::kOk);
      ASSERT_TRUE(hal::can_frame_equal(f1, f2)) << "sample " << n;
      ASSERT_EQ(decode_imu(f2, d2), CodecStatus::kOk);
      ASSERT_TRUE(same_sample(d1.sample, d2.sample)) << "sample " << n;
      // The time tag is the nearest double to the integer nanoseconds.
      EXPECT_EQ(d1.sample.t_s, static_cast<double>(d1.time_ns) / 1e9);
      EXPECT_LE(std::abs(d1.sample.t_s - s.t_s), 0.5e-9 + 1e-15);
      ++n;
    }
  EXPECT_EQ(n, 2000);
}

TEST(CanProtocol, ImuQuantizationErrorWithinOneLsbPerSample) {
  sim::Rng rng(42, 1);
  ImuEncoder enc;
  const double lsb_th = 1.0 / kDthetaPerRad, lsb_dv = 1.0 / kDvPerMps;
  for (int k = 0; k < 20000; ++k) {
    fsw::ImuSample s;
    s.t_s = 1e-3 * (k + 1);
    s.dt_s = 1e-3;
    for (int i = 0; i < 3; ++i) {
      s.dtheta_rad(i) = 1e-3 * rng.normal();
      s.dv_mps(i) = 1e-2 * rng.normal();
    }
    CanFrame f;
    ASSERT_EQ(enc.encode(s, f), CodecStatus::kOk);
    ImuFrame d;
    ASSERT_EQ(decode_imu(f, d), CodecStatus::kOk);
    for (int i = 0; i < 3; ++i) {
      ASSERT_LE(std::abs(d.sample.dtheta_rad(i) - s.dtheta_rad(i)), lsb_th * 1.000001);
      ASSERT_LE(std::abs(d.sample.dv_mps(i) - s.dv_mps(i)), lsb_dv * 1.000001);
      ASSERT_LE(std::abs(enc.dtheta_residual_lsb()[i]), 0.5 + 1e-6);
      ASSERT_LE(std::abs(enc.dv_residual_lsb()[i]), 0.5 + 1e-6);
    }
  }
}

TEST(CanProtocol, ResidualCarryKeepsTheSumOf1e5SamplesWithinOneLsb) {
  // 1e5 samples (100 s at 1 kHz): a random-walk motion plus a constant rate of 0.37 LSB per
  // sample (a bias below the resolution, which plain rounding would lose completely).
  const double lsb_th = 1.0 / kDthetaPerRad, lsb_dv = 1.0 / kDvPerMps;
  sim::Rng rng(7, 3);
  ImuEncoder enc;
  long double sum_in_th[3] = {0, 0, 0}, sum_out_th[3] = {0, 0, 0}, sum_in_dv[3] = {0, 0, 0}, sum_out_dv[3] = {0, 0, 0};
  long double naive_th = 0;
  for (int k = 0; k < 100000; ++k) {
    fsw::ImuSample s;
    s.t_s = 1e-3 * (k + 1);
    s.dt_s = 1e-3;
    s.dtheta_rad = fsw::Vec3(0.37 * lsb_th, 2e-4 * rng.normal(), 1e-5 * std::sin(1e-3 * k) + 3e-7 * rng.normal());
    s.dv_mps = fsw::Vec3(9.81e-3 + 1e-5 * rng.normal(), -0.43 * lsb_dv, 1e-4 * rng.normal());
    CanFrame f;
    ASSERT_EQ(enc.encode(s, f), CodecStatus::kOk);
    ImuFrame d;
    ASSERT_EQ(decode_imu(f, d), CodecStatus::kOk);
    for (int i = 0; i < 3; ++i) {
      sum_in_th[i] += s.dtheta_rad(i);
      sum_out_th[i] += d.sample.dtheta_rad(i);
      sum_in_dv[i] += s.dv_mps(i);
      sum_out_dv[i] += d.sample.dv_mps(i);
    }
    naive_th += std::nearbyint(s.dtheta_rad(0) * kDthetaPerRad) / kDthetaPerRad;
  }
  for (int i = 0; i < 3; ++i) {
    EXPECT_LE(std::abs(static_cast<double>(sum_out_th[i] - sum_in_th[i])), lsb_th) << "dtheta axis " << i;
    EXPECT_LE(std::abs(static_cast<double>(sum_out_dv[i] - sum_in_dv[i])), lsb_dv) << "dv axis " << i;
  }
  // Plain rounding of the sub-LSB rate loses all of it: 37000 LSB over the run.
  EXPECT_GT(std::abs(static_cast<double>(naive_th - sum_in_th[0])), 30000 * lsb_th);
}

TEST(CanProtocol, ImuSaturationAndInvalidInput) {
  ImuEncoder enc;
  fsw::ImuSample s;
  s.t_s = 1.0;
  s.dt_s = 1e-3;
  s.dtheta_rad = fsw::Vec3(0.05, 0.0, 0.0);  // 50 rad/s: beyond the +-0.0215 rad field
  s.dv_mps = fsw::Vec3(0.0, -3.0, 0.0);      // beyond +-2.147 m/s
  CanFrame f;
  ASSERT_EQ(enc.encode(s, f), CodecStatus::kOk);
  ImuFrame d;
  ASSERT_EQ(decode_imu(f, d), CodecStatus::kOk);
  EXPECT_TRUE(d.status & kImuDthetaSaturated);
  EXPECT_TRUE(d.status & kImuDvSaturated);
  EXPECT_NEAR(d.sample.dtheta_rad(0), 2147483647.0 / kDthetaPerRad, 1e-15);
  EXPECT_NEAR(d.sample.dv_mps(1), -2147483648.0 / kDvPerMps, 1e-15);
  EXPECT_EQ(enc.dtheta_residual_lsb()[0], 0.0);

  // Non-finite increments: a frame flagged invalid (the counter slot is used, zeros sent).
  s.dtheta_rad(1) = std::nan("");
  ASSERT_EQ(enc.encode(s, f), CodecStatus::kFlagged);
  ASSERT_EQ(decode_imu(f, d), CodecStatus::kOk);
  EXPECT_TRUE(d.status & kImuSampleInvalid);
  EXPECT_EQ(d.counter, 1u);
  EXPECT_EQ(d.sample.dtheta_rad.norm(), 0.0);

  // Non-finite time or dt <= 0: no frame, but the counter advances (the receiver sees a gap).
  s = fsw::ImuSample{};
  s.t_s = std::nan("");
  s.dt_s = 1e-3;
  EXPECT_EQ(enc.encode(s, f), CodecStatus::kBadInput);
  s.t_s = 1.0;
  s.dt_s = 0.0;
  EXPECT_EQ(enc.encode(s, f), CodecStatus::kBadInput);
  s.dt_s = 5.0;  // 5e9 ns does not fit the 32-bit dt field
  EXPECT_EQ(enc.encode(s, f), CodecStatus::kOutOfRange);
  EXPECT_EQ(enc.next_counter(), 5u);
  // IMU built-in-test bits pass through.
  s.dt_s = 1e-3;
  ASSERT_EQ(enc.encode(s, f, kImuGyroFail), CodecStatus::kOk);
  ASSERT_EQ(decode_imu(f, d), CodecStatus::kOk);
  EXPECT_EQ(d.status, kImuGyroFail);
}

TEST(CanProtocol, DecoderRejectsWrongIdLengthAndCorruption) {
  ImuEncoder enc;
  fsw::ImuSample s;
  s.t_s = 1.0;
  s.dt_s = 1e-3;
  CanFrame f;
  ASSERT_EQ(enc.encode(s, f), CodecStatus::kOk);
  ImuFrame d;
  CanFrame g = f;
  g.data[20] ^= 0x04;
  EXPECT_EQ(decode_imu(g, d), CodecStatus::kBadCrc);
  g = f;
  g.len = 32;
  EXPECT_EQ(decode_imu(g, d), CodecStatus::kBadLength);
  g = f;
  g.extended = true;
  EXPECT_EQ(decode_imu(g, d), CodecStatus::kUnknownId);
  g = f;
  g.id = kIdGpsEpoch;  // a valid frame under another ID: the CRC covers the ID
  g.len = kLenGpsEpoch;
  GpsEpochFrame e;
  EXPECT_NE(decode_gps_epoch(g, e), CodecStatus::kOk);
  EXPECT_EQ(decode_gps_epoch(f, e), CodecStatus::kUnknownId);
}

TEST(CanProtocol, GpsEpochRoundTrip) {
  sim::Scenario sc;
  sc.duration_s = 3.0;
  sim::SensorStream stream(sc);
  sim::SensorStep step;
  GpsEncoder enc(65534);  // crosses the 16-bit wrap
  int epochs = 0;
  while (stream.next(step)) {
    ASSERT_TRUE(step.has_epoch);
    const fsw::GnssRawEpoch& e = step.epoch;
    CanFrame frames[GpsEncoder::kMaxFrames];
    int n = 0, skipped = 0;
    ASSERT_EQ(enc.encode(e, frames, n, skipped), CodecStatus::kOk);
    ASSERT_EQ(skipped, 0);
    ASSERT_EQ(n, 1 + e.n_meas);
    GpsEpochFrame h;
    ASSERT_EQ(decode_gps_epoch(frames[0], h), CodecStatus::kOk);
    EXPECT_EQ(h.seq, static_cast<std::uint16_t>(65534 + epochs));
    EXPECT_EQ(h.gps_week, e.gps_week);
    EXPECT_LE(std::abs(h.gps_tow_s - e.gps_tow_s), 0.5e-9 + 1e-10);
    EXPECT_LE(std::abs(h.t_s - e.t_s), 0.5e-9);
    EXPECT_EQ(h.n_meas, e.n_meas);
    EXPECT_TRUE(h.status & kGpsTimeValid);
    for (int i = 0; i < e.n_meas; ++i) {
      GpsMeasFrame m;
      ASSERT_EQ(decode_gps_meas(frames[1 + i], m), CodecStatus::kOk);
      EXPECT_EQ(m.seq, h.seq);
      EXPECT_EQ(m.index, i);
      const fsw::GnssRawMeasurement& o = e.meas[static_cast<std::size_t>(i)];
      EXPECT_EQ(m.meas.prn, o.prn);
      EXPECT_LE(std::abs(m.meas.pseudorange_m - o.pseudorange_m), 0.5e-4 + 1e-8);
      EXPECT_LE(std::abs(m.meas.pseudorange_rate_mps - o.pseudorange_rate_mps), 0.5e-4 + 1e-10);
      EXPECT_LE(std::abs(m.meas.cn0_dbhz - o.cn0_dbhz), 0.5e-2 + 1e-12);
      // Re-encoding the decoded values gives the same frame.
      CanFrame again;
      ASSERT_EQ(encode_gps_meas(m.seq, m.index, m.meas, again), CodecStatus::kOk);
      EXPECT_TRUE(hal::can_frame_equal(again, frames[1 + i]));
    }
    CanFrame again;
    ASSERT_EQ(encode_gps_epoch(h.seq, h.gps_week, h.gps_tow_s, h.t_s, h.n_meas, h.status, again), CodecStatus::kOk);
    EXPECT_TRUE(hal::can_frame_equal(again, frames[0]));
    ++epochs;
  }
  EXPECT_EQ(epochs, 3);
}

TEST(CanProtocol, GpsEncoderLeavesOutUnrepresentableMeasurements) {
  fsw::GnssRawEpoch e;
  e.t_s = 10.0;
  e.gps_week = 2300;
  e.gps_tow_s = 1000.25;
  e.n_meas = 3;
  e.meas[0] = {5, 2.1e7, 100.0, 45.0};
  e.meas[1] = {6, std::nan(""), 100.0, 45.0};
  e.meas[2] = {7, 6e7, 100.0, 45.0};  // beyond the 40-bit field (5.5e7 m)
  CanFrame frames[GpsEncoder::kMaxFrames];
  int n = 0, skipped = 0;
  GpsEncoder enc;
  ASSERT_EQ(enc.encode(e, frames, n, skipped), CodecStatus::kOk);
  EXPECT_EQ(n, 2);
  EXPECT_EQ(skipped, 2);
  GpsEpochFrame h;
  ASSERT_EQ(decode_gps_epoch(frames[0], h), CodecStatus::kOk);
  EXPECT_EQ(h.n_meas, 1);
  e.gps_tow_s = 604800.0;  // tow must be within the week
  EXPECT_EQ(enc.encode(e, frames, n, skipped), CodecStatus::kOutOfRange);
  e.gps_tow_s = 5.0;
  e.t_s = std::nan("");
  EXPECT_EQ(enc.encode(e, frames, n, skipped), CodecStatus::kBadInput);
}

TEST(CanProtocol, AlmanacRoundTripAndSatellitePositions) {
  const std::vector<fsw::GpsAlmanac> alm = default_almanac();
  ASSERT_GE(alm.size(), 24u);
  const double pi = kSemicircle_rad;
  for (const fsw::GpsAlmanac& a : alm) {
    CanFrame f;
    ASSERT_EQ(encode_gps_almanac(a, f), CodecStatus::kOk) << "PRN " << a.prn;
    fsw::GpsAlmanac d;
    ASSERT_EQ(decode_gps_almanac(f, d), CodecStatus::kOk);
    EXPECT_EQ(d.prn, a.prn);
    EXPECT_EQ(d.health, a.health);
    EXPECT_EQ(d.week_mod_1024, a.week_mod_1024);
    EXPECT_EQ(d.toa_s, a.toa_s);
    EXPECT_LE(std::abs(d.eccentricity - a.eccentricity), 0.5 * kAlmEccLsb);
    EXPECT_LE(std::abs(d.inclination_rad - a.inclination_rad), 0.5 * kAlmAngleLsb_sc * pi + 1e-15);
    EXPECT_LE(std::abs(d.omega0_rad - a.omega0_rad), 0.5 * kAlmAngleLsb_sc * pi + 1e-15);
    EXPECT_LE(std::abs(d.arg_perigee_rad - a.arg_perigee_rad), 0.5 * kAlmAngleLsb_sc * pi + 1e-15);
    EXPECT_LE(std::abs(d.mean_anomaly_rad - a.mean_anomaly_rad), 0.5 * kAlmAngleLsb_sc * pi + 1e-15);
    EXPECT_LE(std::abs(d.sqrt_a_sqrtm - a.sqrt_a_sqrtm), 0.5 * kAlmSqrtALsb);
    EXPECT_LE(std::abs(d.omega_dot_radps - a.omega_dot_radps), 0.5 * kAlmOmegaDotLsb_scps * pi);
    EXPECT_LE(std::abs(d.af0_s - a.af0_s), 0.5 * kAlmAf0Lsb_s);
    EXPECT_LE(std::abs(d.af1_sps - a.af1_sps), 0.5 * kAlmAf1Lsb_sps);
    EXPECT_TRUE(fsw::almanac_valid(d));
    // Orbit and clock from the decoded elements: within 1 mm of the original ones, a day later too.
    for (double dt : {0.0, 86400.0}) {
      double tow = a.toa_s + dt;
      int week = 1455;
      if (tow >= 604800.0) {
        tow -= 604800.0;
        ++week;
      }
      fsw::Vec3 r0, v0, r1, v1;
      fsw::satellite_pv_ecef(a, week, tow, r0, v0);
      fsw::satellite_pv_ecef(d, week, tow, r1, v1);
      EXPECT_LT((r0 - r1).norm(), 1e-3) << "PRN " << a.prn << " dt " << dt;
      EXPECT_LT(fsw::kSpeedOfLight_mps *
                    std::abs(fsw::satellite_clock_bias_s(a, week, tow) - fsw::satellite_clock_bias_s(d, week, tow)),
                1e-3);
    }
    // Decoded -> encoded -> decoded is exact.
    CanFrame f2;
    ASSERT_EQ(encode_gps_almanac(d, f2), CodecStatus::kOk);
    EXPECT_TRUE(hal::can_frame_equal(f, f2)) << "PRN " << a.prn;
  }
}

TEST(CanProtocol, AlmanacAnglesWrapAndRangesAreChecked) {
  fsw::GpsAlmanac a = default_almanac().front();
  a.mean_anomaly_rad = 3.5;  // > pi: sent as 3.5 - 2 pi, same orbit
  CanFrame f;
  ASSERT_EQ(encode_gps_almanac(a, f), CodecStatus::kOk);
  fsw::GpsAlmanac d;
  ASSERT_EQ(decode_gps_almanac(f, d), CodecStatus::kOk);
  EXPECT_NEAR(d.mean_anomaly_rad, 3.5 - 2.0 * kSemicircle_rad, 1e-9);
  fsw::Vec3 r0, v0, r1, v1;
  fsw::satellite_pv_ecef(a, 1455, a.toa_s, r0, v0);
  fsw::satellite_pv_ecef(d, 1455, a.toa_s, r1, v1);
  EXPECT_LT((r0 - r1).norm(), 1e-3);
  a.mean_anomaly_rad = kSemicircle_rad;  // exactly +pi rounds to +1 semicircle: wraps to -pi
  ASSERT_EQ(encode_gps_almanac(a, f), CodecStatus::kOk);
  ASSERT_EQ(decode_gps_almanac(f, d), CodecStatus::kOk);
  EXPECT_NEAR(d.mean_anomaly_rad, -kSemicircle_rad, 1e-12);

  fsw::GpsAlmanac b = default_almanac().front();
  b.eccentricity = 0.6;
  EXPECT_EQ(encode_gps_almanac(b, f), CodecStatus::kOutOfRange);
  b = default_almanac().front();
  b.sqrt_a_sqrtm = std::nan("");
  EXPECT_EQ(encode_gps_almanac(b, f), CodecStatus::kBadInput);
  b = default_almanac().front();
  b.prn = 300;
  EXPECT_EQ(encode_gps_almanac(b, f), CodecStatus::kOutOfRange);
}

TEST(CanProtocol, StepEncoderEmitsBusOrderAndMatchesTheSingleEncoders) {
  sim::Scenario sc;
  sc.duration_s = 1.0;
  sim::SensorStream stream(sc);
  sim::SensorStep step;
  ASSERT_TRUE(stream.next(step));
  ASSERT_TRUE(step.has_epoch);
  const std::vector<fsw::GpsAlmanac>& alm = stream.almanac();
  CanStepEncoder step_enc;
  std::vector<CanFrame> out(static_cast<std::size_t>(CanStepEncoder::max_frames(1000, 2)));
  const CanStepEncoder::Result r =
      step_enc.encode(step.imu.data(), static_cast<int>(step.imu.size()), &step.epoch, alm.data(), 2, out.data());
  ASSERT_EQ(r.n_frames, 1000 + 1 + step.epoch.n_meas + 2);
  ImuEncoder imu;
  for (int i = 0; i < 1000; ++i) {
    CanFrame f;
    ASSERT_EQ(imu.encode(step.imu[static_cast<std::size_t>(i)], f), CodecStatus::kOk);
    ASSERT_TRUE(hal::can_frame_equal(f, out[static_cast<std::size_t>(i)])) << i;
  }
  EXPECT_EQ(out[1000].id, kIdGpsEpoch);
  for (int i = 0; i < step.epoch.n_meas; ++i) EXPECT_EQ(out[static_cast<std::size_t>(1001 + i)].id, kIdGpsMeas);
  EXPECT_EQ(out[static_cast<std::size_t>(r.n_frames - 1)].id, kIdGpsAlmanac);
  EXPECT_EQ(step_enc.gps().next_seq(), 1);
}

TEST(CanProtocol, BusTimingOfTheChosenFrames) {
  // 48-byte FD frame, 500 kbit/s / 2 Mbit/s: 34 nominal bits (68 us) + 519 data bits (259.5 us).
  EXPECT_NEAR(can_fd_frame_time_s(48, 500e3, 2e6), 327.5e-6, 1e-9);
  EXPECT_NEAR(can_fd_frame_time_s(48, 1e6, 5e6), 34e-6 + 519.0 / 5e6, 1e-9);
  // Classic 8-byte frame at 1 Mbit/s: 98 stuffable bits + 24 stuff bits + 13 = 135 us.
  EXPECT_NEAR(can_classic_frame_time_s(8, 1e6), 135e-6, 1e-9);
  // The IMU at 1 kHz loads the 500k/2M bus by about a third.
  EXPECT_NEAR(1000.0 * can_fd_frame_time_s(kLenImuSample, 500e3, 2e6), 0.3275, 1e-4);
}

}  // namespace
