// The PX4 ULog reader (tools/ulog.hpp) on handcrafted bytes, damaged ones included, the leap-second
// table, the boot-clock fit, and the ULog import (tools/ulog_import.hpp) on a handcrafted flight
// whose every value is known. The two real logs: UlogData.* (label recordings).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "fsw/frames.hpp"
#include "hal/lcm_channels.hpp"
#include "hal/lcm_convert.hpp"
#include "hal/lcm_log.hpp"
#include "hal/time_tag_gate.hpp"
#include "recordings.hpp"
#include "tools/gps_utc.hpp"
#include "tools/ulog.hpp"
#include "tools/ulog_import.hpp"
#include "ulog_builder.hpp"

namespace {

using test::Pack;
using test::UlogBuilder;
using tools::ulog::Damage;

constexpr const char* kImuFormat =
    "sensor_combined:uint64_t timestamp;float[3] gyro_rad;uint32_t gyro_integral_dt;int32_t "
    "accelerometer_timestamp_relative;float[3] accelerometer_m_s2;uint32_t accelerometer_integral_dt;uint8_t "
    "accelerometer_clipping;uint8_t[3] _padding0;";

/// One sensor_combined message (without its trailing padding, as PX4's logger writes it: 45 bytes).
std::vector<std::uint8_t> imu_fields(std::uint64_t t_us, float g = 0.01f, float a = -9.8f) {
  return Pack().u64(t_us).f32(g).f32(-2 * g).f32(3 * g).u32(5000).i32(0).f32(0.1f).f32(0.2f).f32(a).u32(5000).u8(0).bytes;
}

UlogBuilder small_log(int n_imu) {
  UlogBuilder b;
  b.info_text("sys_name", "PX4");
  b.info_text("ver_hw", "TEST_HW");
  b.format(kImuFormat);
  b.param_float("EKF2_GPS_DELAY", 110.0f);
  b.param_int("SYS_AUTOSTART", 4001);
  b.add(0, 7, "sensor_combined");
  for (int k = 0; k < n_imu; ++k) {
    b.data(7, imu_fields(1000000 + 5000 * static_cast<std::uint64_t>(k)));
    if (k % 10 == 9) b.sync();
  }
  return b;
}

TEST(Ulog, ReadsAHandcraftedLog) {
  UlogBuilder b = small_log(25);
  b.multi_info(false, "char[5] perf", "hello");
  b.multi_info(true, "char[0] perf", "");
  b.multi_info(true, "char[6] perf", " world");
  b.dropout(30);
  b.text(1200000, "armed");
  const tools::ulog::File f = tools::ulog::parse(b.bytes);
  EXPECT_EQ(f.version, 1);
  EXPECT_EQ(f.start_timestamp_us, 1000u);
  EXPECT_EQ(f.info_text("sys_name"), "PX4");
  EXPECT_EQ(f.info_text("ver_hw"), "TEST_HW");
  EXPECT_DOUBLE_EQ(f.parameters.at("EKF2_GPS_DELAY"), 110.0);
  EXPECT_DOUBLE_EQ(f.parameters.at("SYS_AUTOSTART"), 4001.0);
  ASSERT_EQ(f.multi_info.count("perf"), 1u);
  const auto& parts = f.multi_info.at("perf");
  ASSERT_EQ(parts.size(), 1u);
  EXPECT_EQ(std::string(parts[0].begin(), parts[0].end()), "hello world");
  EXPECT_EQ(f.damage.total(), 0u);
  EXPECT_EQ(f.sync_messages, 2u);
  ASSERT_EQ(f.dropouts.size(), 1u);
  EXPECT_EQ(f.dropout_ms, 30u);
  ASSERT_EQ(f.texts.size(), 1u);
  EXPECT_EQ(f.texts[0].text, "armed");
  const tools::ulog::Subscription* s = f.find("sensor_combined");
  ASSERT_NE(s, nullptr);
  ASSERT_EQ(s->data.size(), 25u);
  ASSERT_NE(s->format, nullptr);
  EXPECT_EQ(s->format->size, 48u);
  EXPECT_EQ(s->format->min_size, 45u);  // the trailing padding is not logged
  const tools::ulog::Field* g = s->format->field("gyro_rad");
  ASSERT_NE(g, nullptr);
  EXPECT_EQ(g->offset, 8u);
  EXPECT_EQ(g->count, 3u);
  EXPECT_FLOAT_EQ(static_cast<float>(tools::ulog::value(f, s->data[3], *g, 1)), -0.02f);
  EXPECT_TRUE(std::isnan(tools::ulog::value(f, s->data[3], *g, 3)));  // past the array
  EXPECT_EQ(tools::ulog::value_u64(f, s->data[3], *s->format->field("timestamp")), 1015000u);
}

TEST(Ulog, RefusesWhatIsNotAULog) {
  EXPECT_THROW(tools::ulog::parse({0x55, 0x4c, 0x6f}), std::runtime_error);
  UlogBuilder b;
  b.bytes[3] = 'X';
  EXPECT_THROW(tools::ulog::parse(b.bytes), std::runtime_error);
  UlogBuilder c;
  c.flag_bits(0x02);  // an incompatible flag nobody defined: must not be parsed
  EXPECT_THROW(tools::ulog::parse(c.bytes), std::runtime_error);
  UlogBuilder d;
  d.flag_bits(0x00);
  EXPECT_NO_THROW(tools::ulog::parse(d.bytes));
}

TEST(Ulog, ATruncatedLastMessageIsCountedAndTheRestKept) {
  UlogBuilder b = small_log(20);
  const std::size_t full = b.bytes.size();
  b.bytes.resize(full - 15);  // the last sync message gone and the last data message cut
  const tools::ulog::File f = tools::ulog::parse(b.bytes);
  EXPECT_EQ(f.damage.count(Damage::kTruncated), 1u);
  EXPECT_EQ(f.damage.total(), 1u);
  EXPECT_EQ(f.find("sensor_combined")->data.size(), 19u);
  EXPECT_GT(f.damage.bytes_skipped, 0u);
}

TEST(Ulog, ACorruptSizeIsSkippedAndTheReaderResynchronises) {
  UlogBuilder b = small_log(0);
  for (int k = 0; k < 10; ++k) b.data(7, imu_fields(1000000 + 5000 * static_cast<std::uint64_t>(k)));
  const std::size_t damaged = b.bytes.size();
  for (int k = 10; k < 30; ++k) b.data(7, imu_fields(1000000 + 5000 * static_cast<std::uint64_t>(k)));
  b.bytes[damaged] = 0xff;  // the 11th message's size: 65535 + its own bytes
  b.bytes[damaged + 1] = 0xf0;
  const tools::ulog::File f = tools::ulog::parse(b.bytes);
  EXPECT_EQ(f.damage.count(Damage::kBadFraming), 1u);
  const auto& d = f.find("sensor_combined")->data;
  // 10 before the damaged one, 19 after it.
  EXPECT_EQ(d.size(), 29u);
  EXPECT_EQ(tools::ulog::value_u64(f, d.back(), *f.find("sensor_combined")->format->field("timestamp")), 1145000u);
  EXPECT_EQ(f.damage.bytes_skipped, 3u + 2 + 45);
}

TEST(Ulog, GarbageBetweenMessagesIsSkippedAndCounted) {
  UlogBuilder b = small_log(10);
  std::mt19937 rng(7);
  for (int i = 0; i < 1000; ++i) b.bytes.push_back(static_cast<std::uint8_t>(rng()));
  for (int k = 0; k < 10; ++k) b.data(7, imu_fields(2000000 + 5000 * static_cast<std::uint64_t>(k)));
  const tools::ulog::File f = tools::ulog::parse(b.bytes);
  EXPECT_GE(f.damage.count(Damage::kBadFraming), 1u);
  EXPECT_GE(f.damage.bytes_skipped, 1000u - 60u);  // a chance chain of plausible bytes may be taken
  EXPECT_GE(f.find("sensor_combined")->data.size(), 19u);
}

TEST(Ulog, ContentErrorsAreCountedPerReason) {
  UlogBuilder b = small_log(3);
  b.data(99, imu_fields(2000000));                    // nobody subscribed msg_id 99
  b.data(7, Pack().u64(2005000).f32(1).bytes);         // shorter than the format's fields
  b.message('S', {1, 2, 3, 4, 5, 6, 7, 8});            // a sync message without the magic
  b.format("bad format without colon");
  b.format("nested:uint64_t timestamp;missing_t[2] x;");  // a nested type nobody defined
  b.format("loop:uint64_t timestamp;loop inner;");       // recursive
  b.add(0, 8, "nested");
  b.data(8, Pack().u64(1).bytes);
  b.info("float EKF2_X", {1, 2});                      // a float of 2 bytes
  b.add(0, 7, "sensor_combined");                      // msg_id 7 taken
  const tools::ulog::File f = tools::ulog::parse(b.bytes);
  EXPECT_EQ(f.damage.count(Damage::kUnknownMsgId), 2u);  // msg_id 99, and the data of "nested"
  EXPECT_EQ(f.damage.count(Damage::kDataSize), 1u);
  EXPECT_EQ(f.damage.count(Damage::kBadSync), 1u);
  EXPECT_EQ(f.damage.count(Damage::kBadFormat), 1u);
  EXPECT_EQ(f.damage.count(Damage::kUnresolvedFormat), 2u);
  EXPECT_EQ(f.damage.count(Damage::kBadInfo), 1u);
  EXPECT_EQ(f.damage.count(Damage::kBadSubscription), 1u);
  EXPECT_EQ(f.find("sensor_combined")->data.size(), 3u);
  EXPECT_EQ(f.find("nested"), nullptr);
}

TEST(Ulog, NestedFormatsGetTheirSizes) {
  UlogBuilder b;
  b.format("inner:float x;uint8_t[3] _padding0;");
  b.format("outer:uint64_t timestamp;inner[2] items;uint8_t flag;uint8_t[7] _padding0;");
  b.add(0, 1, "outer");
  b.data(1, Pack().u64(5).f32(1).u8(0).u8(0).u8(0).f32(2).u8(0).u8(0).u8(0).u8(9).bytes);
  const tools::ulog::File f = tools::ulog::parse(b.bytes);
  const tools::ulog::Subscription* s = f.find("outer");
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->format->size, 8u + 2 * 7 + 1 + 7);
  EXPECT_EQ(s->format->min_size, 8u + 14 + 1);
  EXPECT_EQ(s->format->field("flag")->offset, 22u);
  EXPECT_EQ(tools::ulog::value(f, s->data[0], *s->format->field("flag")), 9.0);
  EXPECT_TRUE(std::isnan(tools::ulog::value(f, s->data[0], *s->format->field("items"))));  // nested: not a number
}

TEST(Ulog, AppendedDataAfterACutMessageIsRead) {
  UlogBuilder b;
  b.flag_bits(tools::ulog::kIncompatDataAppended, 0);
  b.format(kImuFormat);
  b.add(0, 7, "sensor_combined");
  for (int k = 0; k < 5; ++k) b.data(7, imu_fields(1000000 + 5000 * static_cast<std::uint64_t>(k)));
  b.bytes.resize(b.bytes.size() - 20);  // the logger stopped inside a message ...
  const std::uint64_t appended = b.bytes.size();
  for (int k = 5; k < 10; ++k) b.data(7, imu_fields(1000000 + 5000 * static_cast<std::uint64_t>(k)));  // ... and appended later
  for (int i = 0; i < 8; ++i) b.bytes[16 + 3 + 16 + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(appended >> (8 * i));
  const tools::ulog::File f = tools::ulog::parse(b.bytes);
  EXPECT_EQ(f.find("sensor_combined")->data.size(), 9u);
  EXPECT_EQ(f.damage.count(Damage::kTruncated), 1u);
  EXPECT_EQ(f.damage.total(), 1u);
}

TEST(Ulog, RandomDamageNeverCrashesAndNeverInventsData) {
  const UlogBuilder clean = small_log(200);
  std::mt19937 rng(2026);
  int read_back = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<std::uint8_t> bytes = clean.bytes;
    const int flips = 1 + static_cast<int>(rng() % 20);
    for (int i = 0; i < flips; ++i) bytes[16 + rng() % (bytes.size() - 16)] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
    if (rng() % 3 == 0) bytes.resize(16 + rng() % (bytes.size() - 16));
    const tools::ulog::File f = tools::ulog::parse(bytes);
    const tools::ulog::Subscription* s = f.find("sensor_combined");
    if (s == nullptr) continue;  // the format or the subscription was hit
    ++read_back;
    EXPECT_LE(s->data.size(), 200u + 3u);  // a flip may turn a sync into a data message at most
    for (const auto& d : s->data) {
      EXPECT_LE(d.offset + d.size, bytes.size());
      EXPECT_GE(d.size, s->format->min_size);
    }
  }
  EXPECT_GT(read_back, 200);  // most damage leaves the topic readable
}

// ---------------------------------------------------------------------------------------------
// Time

TEST(GpsUtc, LeapSecondsMatchTheSystemList) {
  // tzdata's copy of the IERS list: NTP seconds (from 1900) and TAI-UTC; GPS-UTC = TAI-UTC - 19.
  std::ifstream in("/usr/share/zoneinfo/leap-seconds.list");
  if (!in) GTEST_SKIP() << "/usr/share/zoneinfo/leap-seconds.list absent (Debian package tzdata)";
  constexpr std::int64_t kNtpToUnix = 2208988800;
  std::string line;
  int checked = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    std::int64_t ntp = 0;
    int tai_utc = 0;
    ls >> ntp >> tai_utc;
    const std::int64_t unix_s = ntp - kNtpToUnix;
    if (unix_s < tools::kGpsEpochUnix_s) continue;
    EXPECT_EQ(tools::gps_minus_utc_s(unix_s), tai_utc - 19) << "at " << unix_s;
    EXPECT_EQ(tools::gps_minus_utc_s(unix_s - 1), tai_utc - 20) << "just before " << unix_s;
    ++checked;
  }
  EXPECT_EQ(checked, 18);
  EXPECT_EQ(tools::gps_minus_utc_s(tools::kGpsEpochUnix_s), 0);
  // 2024-03-18 12:00:00 UTC = GPS week 2306, 129618 s of the week (Monday 12:00 + 18 s).
  const std::int64_t g = tools::gps_us_from_utc_us(1710763200LL * 1000000);
  EXPECT_EQ(g / (604800LL * 1000000), 2306);
  EXPECT_EQ(g % (604800LL * 1000000), 129618LL * 1000000);
}

TEST(UlogClock, FitRecoversOffsetAndDriftAndLeavesOutAnOutlier) {
  std::vector<std::pair<std::int64_t, std::int64_t>> pairs;
  const std::int64_t utc0 = 1710763200LL * 1000000;
  std::mt19937 rng(1);
  std::normal_distribution<double> jitter(0.0, 2000.0);  // 2 ms of time-stamp jitter
  for (int k = 0; k < 1000; ++k) {
    const std::int64_t boot = 5000000 + 1000000LL * k;  // 1 Hz for 1000 s
    const std::int64_t utc = utc0 + static_cast<std::int64_t>(std::llround((boot - 5000000) * (1.0 - 50e-6) + jitter(rng)));
    pairs.emplace_back(boot, utc);
  }
  pairs[500].second += 400000;  // one fix 0.4 s off
  const tools::UlogClockFit c = tools::fit_boot_to_gps(pairs);
  EXPECT_EQ(c.outliers, 1u);
  EXPECT_TRUE(c.drift_significant);
  EXPECT_NEAR(c.drift * 1e6, -50.0, 1.0);
  const double gps_utc0 = 1710763200.0 - 315964800.0 + 18.0;
  EXPECT_NEAR(c.gps_s(5000000), gps_utc0, 3e-4);  // offset_s is relative to the first (jittered) pair
  EXPECT_NEAR(c.residual_rms_s, 2e-3, 3e-4);
  EXPECT_EQ(c.gps_minus_utc_first_s, 18);
  // gps_s at a boot time: GPS seconds of utc0 + 18 s + the drifting clock.
  const double expect = gps_utc0 + 100.0 * (1.0 - 50e-6);
  EXPECT_NEAR(c.gps_s(105000000), expect, 1e-3);

  // Six seconds of jittery fixes (the real log's case): the drift is not significant, not applied.
  std::vector<std::pair<std::int64_t, std::int64_t>> short_log(pairs.begin(), pairs.begin() + 6);
  const tools::UlogClockFit s = tools::fit_boot_to_gps(short_log);
  EXPECT_FALSE(s.drift_significant);
  EXPECT_EQ(s.drift, 0.0);
  EXPECT_THROW(tools::fit_boot_to_gps({}), std::runtime_error);
}

// ---------------------------------------------------------------------------------------------
// The import on a handcrafted flight

struct Flight {
  UlogBuilder b;
  // Boot 10 s = 2024-03-18 12:00:00 UTC; GNSS at 5 Hz from boot 10 s.
  static constexpr std::int64_t kUtc0_us = 1710763200LL * 1000000;
  static constexpr double kRoll = 10.0, kPitch = -5.0, kYaw = 100.0;  // deg
};

Flight make_flight() {
  Flight fl;
  UlogBuilder& b = fl.b;
  b.info_text("sys_name", "PX4");
  b.info_text("ver_hw", "TEST_HW");
  b.param_float("EKF2_GPS_DELAY", 110.0f);
  b.format(kImuFormat);
  b.format("vehicle_gps_position:uint64_t timestamp;uint64_t time_utc_usec;double latitude_deg;double longitude_deg;"
           "double altitude_ellipsoid_m;float s_variance_m_s;float eph;float epv;float vel_n_m_s;float vel_e_m_s;"
           "float vel_d_m_s;uint8_t fix_type;bool vel_ned_valid;uint8_t satellites_used;uint8_t[1] _padding0;");
  b.format("vehicle_attitude:uint64_t timestamp;float[4] q;uint8_t quat_reset_counter;uint8_t[3] _padding0;");
  b.format("vehicle_global_position:uint64_t timestamp;double lat;double lon;float alt_ellipsoid;uint8_t "
           "lat_lon_reset_counter;uint8_t[3] _padding0;");
  b.format("vehicle_local_position:uint64_t timestamp;float vx;float vy;float vz;bool v_xy_valid;bool v_z_valid;uint8_t[2] _padding0;");
  b.add(0, 1, "sensor_combined");
  b.add(0, 2, "vehicle_gps_position");
  b.add(0, 3, "vehicle_attitude");
  b.add(0, 4, "vehicle_global_position");
  b.add(0, 5, "vehicle_local_position");
  const fsw::Mat3 C_b_ned = fsw::Mat3(Eigen::AngleAxisd(Flight::kYaw * fsw::kDegToRad, fsw::Vec3::UnitZ()) *
                                      Eigen::AngleAxisd(Flight::kPitch * fsw::kDegToRad, fsw::Vec3::UnitY()) *
                                      Eigen::AngleAxisd(Flight::kRoll * fsw::kDegToRad, fsw::Vec3::UnitX()));
  const fsw::Quat q(C_b_ned);
  for (int k = 0; k < 600; ++k) {  // 3 s of 200 Hz IMU from boot 10 s
    const std::uint64_t t = 10000000 + 5000 * static_cast<std::uint64_t>(k);
    b.data(1, imu_fields(t));
    if (k % 40 == 0) {  // 5 Hz GNSS: N 1, E 2, D -0.5 m/s
      const std::int64_t utc = Flight::kUtc0_us + static_cast<std::int64_t>(t) - 10000000;
      b.data(2, Pack().u64(t).u64(static_cast<std::uint64_t>(utc)).f64(47.0).f64(8.0).f64(500.0).f32(0.3f).f32(1.5f)
                    .f32(2.5f).f32(1.0f).f32(2.0f).f32(-0.5f).u8(k == 0 ? 2 : 3).u8(1).u8(12).bytes);
    }
    if (k % 4 == 0)  // 50 Hz estimate
      b.data(3, Pack().u64(t).f32(static_cast<float>(q.w())).f32(static_cast<float>(q.x())).f32(static_cast<float>(q.y()))
                    .f32(static_cast<float>(q.z())).u8(0).bytes);
    if (k % 20 == 0) {
      b.data(4, Pack().u64(t).f64(47.0).f64(8.0).f32(500.5f).u8(0).bytes);
      b.data(5, Pack().u64(t).f32(1.0f).f32(2.0f).f32(-0.5f).u8(1).u8(1).bytes);
    }
  }
  return fl;
}

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("sdins_test_ulog_" + name)).string();
}

TEST(UlogImport, AHandcraftedFlightLandsOnTheNavigationTimeScaleInTheProjectsFrames) {
  const Flight fl = make_flight();
  const tools::ulog::File f = tools::ulog::parse(fl.b.bytes);
  ASSERT_EQ(f.damage.total(), 0u);
  tools::UlogImportOptions opt;
  opt.path = "handcrafted.ulg";
  opt.log_path = temp_path("flight.lcmlog");
  const tools::UlogImportResult r = tools::import_ulog_file(f, opt);
  const nlohmann::json& j = r.summary;
  EXPECT_EQ(j["time_fit"]["pairs"].get<int>(), 14);  // 15 fixes, the first a 2D fix
  EXPECT_EQ(j["gnss_pvt"]["lines"]["rejected_by_reason"]["no 3D fix (fix_type < 3)"].get<int>(), 1);
  EXPECT_NEAR(j["time_fit"]["residual_max_ms"].get<double>(), 0.0, 1e-6);
  EXPECT_EQ(j["time_scale"]["gps_week0"].get<int>(), 2306);
  EXPECT_EQ(j["reference"]["kind"], "autopilot_estimate");
  EXPECT_EQ(j["reference"]["source"], "vehicle_global_position+vehicle_attitude");
  EXPECT_TRUE(j["reference"]["has_attitude"].get<bool>());
  EXPECT_DOUBLE_EQ(j["time_fit"]["px4_ekf2_gps_delay_ms"].get<double>(), 110.0);
  EXPECT_EQ(r.streams.imu.count, 600u);
  EXPECT_NEAR(r.streams.imu.rate_hz, 200.0, 1e-6);
  EXPECT_NEAR(r.streams.gnss.rate_hz, 5.0, 1e-6);
  EXPECT_EQ(r.streams.gnss.count, 14u);
  EXPECT_NEAR(r.streams.imu_gnss_overlap_s, 2.6, 1e-6);

  // Read the log back.
  hal::LcmLogReader rd;
  ASSERT_EQ(rd.open(opt.log_path), hal::LcmLogStatus::kOk);
  hal::LcmLogEvent ev;
  const double tow0 = 129618.0;  // boot 10 s on the navigation time scale
  int imu = 0, pvt = 0, truth = 0, truth_vel = 0;
  while (rd.next(ev) == hal::LcmLogStatus::kOk) {
    if (ev.channel == hal::kLcmChannelImu) {
      sdins::imu_sample_t m{};
      ASSERT_EQ(hal::decode_exact(ev.data, ev.data_len, m), hal::LcmInputStatus::kOk);
      EXPECT_NEAR(m.t_s, tow0 + 0.005 * imu, 1e-9);
      EXPECT_NEAR(m.dt_s, 0.005, 1e-12);
      EXPECT_NEAR(m.dtheta_rad[1], -0.02f * 0.005, 1e-12);
      EXPECT_NEAR(m.dv_mps[2], -9.8f * 0.005, 1e-9);
      EXPECT_EQ(m.counter, imu);
      ++imu;
    } else if (ev.channel == hal::kLcmChannelGnssPvt) {
      sdins::gnss_pvt_t m{};
      ASSERT_EQ(hal::decode_exact(ev.data, ev.data_len, m), hal::LcmInputStatus::kOk);
      EXPECT_EQ(m.gps_week, 2306);
      EXPECT_NEAR(m.t_s, tow0 + 0.2 * (pvt + 1), 1e-9);
      EXPECT_NEAR(m.llh[0], 47.0 * fsw::kDegToRad, 1e-12);
      EXPECT_NEAR(m.llh[2], 500.0, 1e-9);
      EXPECT_NEAR(m.vel_enu_mps[0], 2.0, 1e-6);   // E = vel_e
      EXPECT_NEAR(m.vel_enu_mps[1], 1.0, 1e-6);   // N = vel_n
      EXPECT_NEAR(m.vel_enu_mps[2], 0.5, 1e-6);   // U = -vel_d
      EXPECT_NEAR(m.pos_sigma_enu_m[0], 1.5, 1e-6);
      EXPECT_NEAR(m.pos_sigma_enu_m[2], 2.5, 1e-6);
      EXPECT_NEAR(m.vel_sigma_enu_mps[1], 0.3, 1e-6);
      EXPECT_EQ(m.quality, sdins::gnss_pvt_t::QUALITY_SINGLE);
      EXPECT_EQ(m.n_sat, 12);
      ++pvt;
    } else if (ev.channel == hal::kLcmChannelTruth) {
      sdins::truth_t m{};
      ASSERT_EQ(hal::decode_exact(ev.data, ev.data_len, m), hal::LcmInputStatus::kOk);
      EXPECT_NEAR(m.roll_rad * fsw::kRadToDeg, Flight::kRoll, 1e-4);
      EXPECT_NEAR(m.pitch_rad * fsw::kRadToDeg, Flight::kPitch, 1e-4);
      EXPECT_NEAR(m.heading_rad * fsw::kRadToDeg, Flight::kYaw, 1e-4);
      // Position and velocity where the estimate brackets the attitude's time (not after its last sample).
      if (std::isfinite(m.vel_enu_mps[0])) {
        EXPECT_NEAR(m.vel_enu_mps[0], 2.0, 1e-6);
        EXPECT_NEAR(m.vel_enu_mps[2], 0.5, 1e-6);
        ++truth_vel;
      }
      if (std::isfinite(m.height_m)) EXPECT_NEAR(m.height_m, 500.5, 1e-4);
      ++truth;
    }
  }
  EXPECT_EQ(imu, 600);
  EXPECT_EQ(pvt, 14);
  EXPECT_EQ(truth, 150);
  EXPECT_EQ(truth_vel, 146);  // the estimate's last velocity is at boot 12.9 s
  std::filesystem::remove(opt.log_path);

  // A declared latency moves the IMU (boot clock) against the receiver's own time tags.
  opt.gnss_latency_s = 0.1;
  const tools::UlogImportResult l = tools::import_ulog_file(f, opt);
  EXPECT_NEAR(l.streams.imu.t_first_s, tow0 + 0.1, 1e-9);
  EXPECT_NEAR(l.streams.gnss.t_first_s, tow0 + 0.2, 1e-9);
  std::filesystem::remove(opt.log_path);
}

TEST(UlogImport, AWildTimeTagCostsOnlyItsOwnSample) {
  Flight fl = make_flight();
  // The 100th IMU message's timestamp with its top byte flipped (a bit error in the file).
  tools::ulog::File f = tools::ulog::parse(fl.b.bytes);
  const tools::ulog::Subscription* s = f.find("sensor_combined");
  ASSERT_NE(s, nullptr);
  std::vector<std::uint8_t> bytes = fl.b.bytes;
  bytes[s->data[100].offset + 5] ^= 0x40;
  f = tools::ulog::parse(bytes);
  tools::UlogImportOptions opt;
  opt.path = "wild.ulg";
  opt.log_path = temp_path("wild.lcmlog");
  const tools::UlogImportResult r = tools::import_ulog_file(f, opt);
  EXPECT_EQ(r.summary["imu"]["lines"]["accepted"].get<int>(), 599);
  EXPECT_EQ(r.summary["imu"]["lines"]["rejected"].get<int>(), 1);
  EXPECT_EQ(r.summary["imu"]["lines"]["rejected_by_reason"].value(hal::to_string(hal::TimeTagRejection::kOutlier), 0), 1);
  EXPECT_EQ(r.streams.imu.gaps, 1u);  // the interval over the lost sample
  std::filesystem::remove(opt.log_path);
}

TEST(UlogImport, ALogWithoutGnssTimeIsRefusedWithTheReason) {
  UlogBuilder b = small_log(20);
  const tools::ulog::File f = tools::ulog::parse(b.bytes);
  tools::UlogImportOptions opt;
  opt.path = "imu_only.ulg";
  opt.log_path = temp_path("imu_only.lcmlog");
  try {
    tools::import_ulog_file(f, opt);
    FAIL() << "imported a log without GNSS";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no GNSS messages"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(opt.log_path));
}

TEST(UlogImport, FixesWithoutAnEllipsoidalHeightAreRefusedWithTheReason) {
  UlogBuilder b = small_log(50);
  b.format("vehicle_gps_position:uint64_t timestamp;uint64_t time_utc_usec;double latitude_deg;double longitude_deg;"
           "double altitude_msl_m;double altitude_ellipsoid_m;float s_variance_m_s;float eph;float epv;uint8_t fix_type;"
           "uint8_t[7] _padding0;");
  b.add(0, 9, "vehicle_gps_position");
  for (int k = 0; k < 5; ++k)
    b.data(9, Pack().u64(1000000 + 50000 * static_cast<std::uint64_t>(k)).u64(1710763200000000ULL + 50000 * k).f64(47.0)
                  .f64(8.0).f64(450.0).f64(0.0).f32(0.3f).f32(1.5f).f32(2.5f).u8(3).bytes);
  const tools::ulog::File f = tools::ulog::parse(b.bytes);
  ASSERT_EQ(f.damage.total(), 0u);
  tools::UlogImportOptions opt;
  opt.path = "msl_only.ulg";
  opt.log_path = temp_path("msl_only.lcmlog");
  try {
    tools::import_ulog_file(f, opt);
    FAIL() << "imported fixes without an ellipsoidal height";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no ellipsoidal height (alt_ellipsoid 0 beside an MSL altitude): 5"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(opt.log_path));
}

// ---------------------------------------------------------------------------------------------
// The two real logs (../shared/data/px4-ulog; skipped without them)

std::string ulog_fixture(const char* name) { return test::recordings_dir() + "/px4-ulog/" + name; }

TEST(UlogData, TheRealLogsParseWithoutDamageAndSayWhatTheyAre) {
  const std::string small = ulog_fixture("sample_log_small.ulg"), sitl = ulog_fixture("sample_px4_events.ulg");
  if (!std::filesystem::exists(small) || !std::filesystem::exists(sitl))
    GTEST_SKIP() << "PX4 ULog fixtures absent under " << test::recordings_dir() << "/px4-ulog (SDINS_RECORDINGS_DIR)";
  const tools::ulog::File a = tools::ulog::read(small);
  EXPECT_EQ(a.damage.total(), 0u);
  EXPECT_EQ(a.info_text("sys_name"), "PX4");
  EXPECT_EQ(a.info_text("ver_hw"), "CUBEPILOT_CUBEORANGE");
  EXPECT_EQ(a.find("sensor_combined")->data.size(), 1298u);
  EXPECT_EQ(a.find("vehicle_gps_position")->data.size(), 32u);
  EXPECT_EQ(a.dropouts.size(), 1u);
  const tools::ulog::File b = tools::ulog::read(sitl);
  EXPECT_EQ(b.damage.total(), 0u);
  EXPECT_EQ(b.info_text("ver_hw"), "PX4_SITL");
  EXPECT_EQ(b.find("sensor_combined")->data.size(), 7783u);
  EXPECT_EQ(b.find("vehicle_global_position")->data.size(), 109u);
}

}  // namespace
