// GNSS antenna truth from the IMU truth and the body-frame lever arm (antenna_lever_arm effect).
#include <gtest/gtest.h>

#include "sim/imu_model.hpp"

using fsw::kDegToRad;
using fsw::Vec3;

TEST(AntennaTruth, LeverArmRotatesWithAttitude) {
  sim::TruthSample t;
  t.llh = Vec3(35 * kDegToRad, 127 * kDegToRad, 5000.0);
  t.vel_enu_mps = Vec3(0, 250, 0);
  t.C_b_n = fsw::C_b_n_from_euler(0, 0, 0);  // nose North
  Vec3 llh, vel;
  // 2 m above the IMU (body z is down) raises the antenna by 2 m.
  sim::antenna_truth(t, Vec3(0, 0, -2.0), llh, vel);
  EXPECT_NEAR(llh.z() - t.llh.z(), 2.0, 1e-12);
  // 3 m forward moves it 3 m North.
  sim::antenna_truth(t, Vec3(3.0, 0, 0), llh, vel);
  EXPECT_NEAR(fsw::enu_difference_m(llh, t.llh).y(), 3.0, 1e-6);
  EXPECT_NEAR(fsw::enu_difference_m(llh, t.llh).x(), 0.0, 1e-6);
}

TEST(AntennaTruth, RotationAddsLeverArmVelocity) {
  sim::TruthSample t;
  t.llh = Vec3(0.0, 0.0, 0.0);
  t.C_b_n = fsw::C_b_n_from_euler(0, 0, 0);
  // Yaw rate 0.1 rad/s relative to the Earth, antenna 4 m forward: 0.4 m/s toward the right
  // wing (East) on top of the Earth rate part, which omega_ib includes and antenna_truth removes.
  t.omega_ib_b_radps = Vec3(0, 0, 0.1) + t.C_b_n.transpose() * fsw::omega_ie_n(0.0);
  Vec3 llh, vel;
  sim::antenna_truth(t, Vec3(4.0, 0, 0), llh, vel);
  EXPECT_NEAR(vel.x(), 0.4, 1e-12);
  EXPECT_NEAR(vel.y(), 0.0, 1e-12);
  EXPECT_NEAR(vel.z(), 0.0, 1e-12);
}
