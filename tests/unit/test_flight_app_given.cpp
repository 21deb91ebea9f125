// InitMode::kGiven (fsw/flight_app.hpp): the harness that knows the truth (Monte Carlo, paper,
// timing audit) starts the flight application from a given state, and from there the flight
// application is the executive it wraps: the same minor frames, bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "fsw/flight_app.hpp"

namespace {

using fsw::Vec3;

fsw::NavState start_state() {
  fsw::NavState s;
  s.t_s = 0.0;
  s.llh = Vec3(35.0 * fsw::kDegToRad, 127.0 * fsw::kDegToRad, 100.0);
  s.vel_enu_mps = Vec3(1.0, -2.0, 0.5);
  s.q_b_n = fsw::quat_from_rotvec(Vec3(0.01, -0.02, 0.3));
  return s;
}

fsw::FlightAppConfig given_config() {
  fsw::FlightAppConfig c;
  c.init_mode = fsw::InitMode::kGiven;
  c.init_pos_sigma_m = 5.0;
  c.init_vel_sigma_mps = 0.1;
  c.init_att_sigma_rad = Vec3(1e-4, 1e-4, 1e-3);
  return c;
}

/// IMU sample k (1 kHz): a slow, changing rotation and specific force near gravity.
fsw::ImuSample sample(int k) {
  fsw::ImuSample s;
  s.dt_s = 0.001;
  s.t_s = (k + 1) * s.dt_s;
  s.dtheta_rad = Vec3(1e-5 * std::sin(0.01 * k), 2e-6, 5e-5) * 1.0;
  s.dv_mps = Vec3(0.002 * std::cos(0.003 * k), 0.001, -9.79) * s.dt_s;
  return s;
}

}  // namespace

TEST(FlightAppGiven, StartsOnlyFromTheGivenStateInItsOwnMode) {
  auto app = std::make_unique<fsw::FlightApp<fsw::Layout15Full>>();
  EXPECT_EQ(app->start_given(start_state()), fsw::Status::kBadConfig);  // before init()
  fsw::FlightAppConfig track = given_config();
  track.init_mode = fsw::InitMode::kTrack;
  ASSERT_EQ(app->init(track), fsw::Status::kOk);
  EXPECT_EQ(app->start_given(start_state()), fsw::Status::kBadConfig);  // another mode initialises itself
  EXPECT_FALSE(app->initialised());

  ASSERT_EQ(app->init(given_config()), fsw::Status::kOk);
  fsw::NavState bad = start_state();
  bad.llh.x() = std::nan("");
  EXPECT_EQ(app->start_given(bad), fsw::Status::kBadInput);
  EXPECT_FALSE(app->initialised());
  // A raw epoch before the start neither initialises nor is lost silently.
  fsw::GnssRawEpoch raw;
  raw.t_s = 0.0;
  raw.gps_week = 2200;
  raw.gps_tow_s = 1000.0;
  EXPECT_EQ(app->on_gnss(raw), fsw::Status::kOk);
  EXPECT_EQ(app->health().gnss_before_init, 1u);
  EXPECT_FALSE(app->initialised());

  ASSERT_EQ(app->start_given(start_state()), fsw::Status::kOk);
  EXPECT_TRUE(app->initialised());
  EXPECT_EQ(app->health().init_mode, fsw::InitMode::kGiven);
  EXPECT_EQ(app->health().init_t_s, 0.0);
  EXPECT_EQ(app->health().init_att_sigma_rad, given_config().init_att_sigma_rad);
  EXPECT_STREQ(fsw::to_string(fsw::InitMode::kGiven), "given");
  EXPECT_EQ(app->start_given(start_state()), fsw::Status::kBadInput);  // once
}

TEST(FlightAppGiven, FliesTheSameFramesAsTheExecutiveItWraps) {
  const fsw::FlightAppConfig cfg = given_config();
  auto app = std::make_unique<fsw::FlightApp<fsw::Layout15Full>>();
  ASSERT_EQ(app->init(cfg), fsw::Status::kOk);
  ASSERT_EQ(app->start_given(start_state()), fsw::Status::kOk);
  // The executive as the Monte Carlo drove it before: the config with the initial sigmas, frames
  // of imu_samples_per_frame samples.
  fsw::ExecutiveConfig ecfg = cfg.exec;
  ecfg.ekf.pos_sigma_m = cfg.init_pos_sigma_m;
  ecfg.ekf.vel_sigma_mps = cfg.init_vel_sigma_mps;
  ecfg.ekf.att_sigma_rad = cfg.init_att_sigma_rad;
  auto exec = std::make_unique<fsw::Executive<fsw::Layout15Full>>();
  ASSERT_EQ(exec->init(ecfg, start_state()), fsw::Status::kOk);

  const int spf = ecfg.imu_samples_per_frame;
  fsw::ImuSample frame[fsw::FrameBuilder::kMaxSamplesPerFrame];
  fsw::FrameOutput a, b;
  int frames = 0, ekf_runs = 0;
  for (int k = 0; k < 2500; ++k) {  // 2.5 s: two EKF runs without GNSS (propagation only)
    frame[k % spf] = sample(k);
    ASSERT_EQ(app->on_imu(sample(k), a), fsw::Status::kOk);
    if ((k + 1) % spf != 0) {
      EXPECT_FALSE(a.nav_valid);
      continue;
    }
    fsw::FrameInput in;
    in.imu = frame;
    in.n_imu = spf;
    ASSERT_EQ(exec->tick(in, b), fsw::Status::kOk);
    ASSERT_TRUE(a.nav_valid);
    ++frames;
    ekf_runs += a.ekf_ran ? 1 : 0;
    EXPECT_EQ(a.ekf_ran, b.ekf_ran);
    EXPECT_EQ(a.nav.t_s, b.nav.t_s);
    EXPECT_EQ(a.nav.llh, b.nav.llh) << "frame " << frames;
    EXPECT_EQ(a.nav.vel_enu_mps, b.nav.vel_enu_mps);
    EXPECT_EQ(a.nav.q_b_n.coeffs(), b.nav.q_b_n.coeffs());
  }
  EXPECT_EQ(frames, 500);
  EXPECT_GE(ekf_runs, 1);
  EXPECT_EQ(app->executive().ekf().P(), exec->ekf().P());
  EXPECT_EQ(app->executive().health().ekf_runs, exec->health().ekf_runs);
}
