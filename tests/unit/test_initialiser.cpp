// The flight application's initialisation unit (fsw::Initialiser) on its own, without the
// executive: what it counts while it waits, and the initial state it reports (InitMode::kTrack
// from a solution: heading from the track, roll and pitch from levelling, the antenna moved back
// by the lever arm). The modes end to end are test_flight_app_init.cpp's.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "fsw/flight_app.hpp"
#include "fsw/initialiser.hpp"

namespace {

using fsw::Vec3;

/// A level, stationary IMU sample (body z down: f_b = (0, 0, -g)).
fsw::ImuSample level_sample(double t_s) {
  fsw::ImuSample s;
  s.t_s = t_s;
  s.dt_s = 0.001;
  s.dv_mps = Vec3(0.0, 0.0, -9.8 * s.dt_s);
  s.dtheta_rad = Vec3::Zero();
  return s;
}

fsw::GnssPvtMeasurement solution(const Vec3& vel_enu_mps) {
  fsw::GnssPvtMeasurement m;
  m.t_s = 1.0;
  m.llh = Vec3(0.6, 2.1, 150.0);
  m.vel_enu_mps = vel_enu_mps;
  m.pos_sigma_enu_m = Vec3::Constant(0.5);
  m.vel_sigma_enu_mps = Vec3::Constant(0.1);
  m.has_velocity = true;
  m.quality = 1;
  m.n_sat = 9;
  return m;
}

}  // namespace

TEST(Initialiser, TrackModeWaitsForLevellingAndSpeedThenReportsTheInitialState) {
  fsw::FlightAppConfig cfg;
  cfg.init_mode = fsw::InitMode::kTrack;
  cfg.levelling_samples = 50;
  cfg.min_init_speed_mps = 20.0;
  cfg.exec.ekf.lever_arm_b_m = Vec3(1.5, 0.0, -0.5);
  fsw::FlightAppHealth health;
  static fsw::Initialiser init;  // the levelling buffer: 24 KiB, not on the test's stack
  init.reset(cfg);
  fsw::InitialState out;
  bool ready = true;
  const fsw::GnssPvtMeasurement fast = solution(Vec3(10.0, 30.0, 0.5));
  ASSERT_EQ(init.on_pvt(fast, cfg, health, out, ready), fsw::Status::kOk);
  EXPECT_FALSE(ready);
  EXPECT_EQ(health.init_not_level, 1u);
  EXPECT_EQ(health.pvt_before_init, 1u);

  for (int k = 0; k < 50; ++k) ASSERT_EQ(init.on_imu(level_sample(0.001 * k), cfg, health), fsw::Status::kOk);
  ASSERT_EQ(init.on_pvt(solution(Vec3(3.0, 4.0, 0.0)), cfg, health, out, ready), fsw::Status::kOk);
  EXPECT_FALSE(ready);
  EXPECT_EQ(health.init_too_slow, 1u);

  ASSERT_EQ(init.on_pvt(fast, cfg, health, out, ready), fsw::Status::kOk);
  ASSERT_TRUE(ready);
  EXPECT_EQ(health.pvt_before_init, 3u);
  const double heading = std::atan2(10.0, 30.0);
  const Vec3 euler = fsw::euler_from_C_b_n(out.nav.C_b_n());
  EXPECT_NEAR(euler.x(), 0.0, 1e-12);
  EXPECT_NEAR(euler.y(), 0.0, 1e-12);
  EXPECT_NEAR(euler.z(), heading, 1e-12);
  EXPECT_EQ(out.nav.t_s, fast.t_s);
  EXPECT_TRUE(out.nav.vel_enu_mps == fast.vel_enu_mps);
  // The IMU is the antenna moved back by the lever arm (body x along the track).
  const Vec3 l_n = out.nav.C_b_n() * cfg.exec.ekf.lever_arm_b_m;
  EXPECT_LT((fsw::enu_difference_m(fast.llh, out.nav.llh) - l_n).norm(), 1e-6);
  EXPECT_NEAR(l_n.x(), 1.5 * std::sin(heading), 1e-9);
  EXPECT_TRUE(out.att_sigma_rad == cfg.init_att_sigma_rad);
  EXPECT_EQ(out.align_s, 0.0);
  EXPECT_FALSE(out.vm_biases);
  EXPECT_EQ(out.fix.n_used, 9);
  EXPECT_LT((out.fix.r_ecef_m - fsw::ecef_from_llh(fast.llh)).norm(), 1e-6);
}

// kGiven never initialises from an input (the harness calls FlightApp::start_given()); a
// non-finite IMU sample is rejected and counted.
TEST(Initialiser, GivenModeWaitsAndBadSamplesAreCounted) {
  fsw::FlightAppConfig cfg;
  cfg.init_mode = fsw::InitMode::kGiven;
  fsw::FlightAppHealth health;
  static fsw::Initialiser init;
  init.reset(cfg);
  fsw::InitialState out;
  bool ready = true;
  for (int k = 0; k < 300; ++k) ASSERT_EQ(init.on_imu(level_sample(0.001 * k), cfg, health), fsw::Status::kOk);
  ASSERT_EQ(init.on_pvt(solution(Vec3(10.0, 30.0, 0.0)), cfg, health, out, ready), fsw::Status::kOk);
  EXPECT_FALSE(ready);
  EXPECT_EQ(health.pvt_before_init, 1u);
  fsw::GnssEpoch ep;
  ASSERT_EQ(init.on_gnss(ep, cfg, health, out, ready), fsw::Status::kOk);
  EXPECT_FALSE(ready);
  EXPECT_EQ(health.gnss_before_init, 1u);
  EXPECT_EQ(health.init_no_fix + health.init_not_level + health.init_too_slow, 0u);
  fsw::ImuSample bad = level_sample(1.0);
  bad.dv_mps.y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(init.on_imu(bad, cfg, health), fsw::Status::kBadInput);
  EXPECT_EQ(health.imu_rejected, 1u);
}
