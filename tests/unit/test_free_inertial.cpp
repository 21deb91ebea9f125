// Acceptance of the mechanization and the truth kinematics together: fed the error-free IMU
// output of the truth simulator, free-inertial navigation must stay on truth.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "sim/imu_model.hpp"
#include "sim/scenario.hpp"
#include "sim/trajectory.hpp"
#include "tools/free_inertial.hpp"

namespace {

using fsw::kRadToArcsec;

struct MaxErrors {
  double horiz_pos_m = 0, horiz_vel_mps = 0, att_arcsec = 0, vert_pos_m = 0, vert_vel_mps = 0;
  int turns = 0;
};

MaxErrors fly_perfect(const sim::Scenario& sc) {
  std::string err;
  auto motion = sim::FlightMotion::create(sc, err);
  EXPECT_TRUE(motion) << err;
  MaxErrors m;
  if (!motion) return m;
  tools::FreeInertialConfig cfg;
  cfg.duration_s = sc.duration_s;
  fsw::Status st = fsw::Status::kOk;
  tools::run_free_inertial(
      *motion, nullptr, cfg,
      [&](const sim::TruthSample& truth, const fsw::NavState& nav) {
        const tools::NavErrors e = tools::nav_errors(nav, truth);
        m.horiz_pos_m = std::max(m.horiz_pos_m, e.pos_enu_m.head<2>().norm());
        m.horiz_vel_mps = std::max(m.horiz_vel_mps, e.vel_enu_mps.head<2>().norm());
        m.att_arcsec = std::max(m.att_arcsec, e.att_phi_enu_rad.cwiseAbs().maxCoeff() * kRadToArcsec);
        m.vert_pos_m = std::max(m.vert_pos_m, std::abs(e.pos_enu_m.z()));
        m.vert_vel_mps = std::max(m.vert_vel_mps, std::abs(e.vel_enu_mps.z()));
        m.turns = std::max(m.turns, truth.phase.turn + 1);
      },
      &st);
  EXPECT_EQ(st, fsw::Status::kOk);
  return m;
}

}  // namespace

TEST(FreeInertial, PerfectImuBankToTurn30MinStaysOnTruth) {
  const sim::Scenario sc;  // built-in default: 1800 s of alternating 60-degree bank turns
  const MaxErrors m = fly_perfect(sc);
  std::printf("perfect IMU, %d turns in %.0f s: max horizontal position %.4f m, horizontal velocity %.6f m/s, "
              "attitude %.4f arcsec; vertical (unaided, reported only) position %.3f m, velocity %.5f m/s\n",
              m.turns, sc.duration_s, m.horiz_pos_m, m.horiz_vel_mps, m.att_arcsec, m.vert_pos_m, m.vert_vel_mps);
  EXPECT_GE(m.turns, 15);
  EXPECT_LT(m.horiz_pos_m, 1.0);
  EXPECT_LT(m.horiz_vel_mps, 0.01);
  EXPECT_LT(m.att_arcsec, 1.0);
}

namespace {

/// Every frame's solution and truth time of a 200 s flight with the paper's IMU errors, the truth
/// read inline or from its own thread.
std::vector<double> frames_of(bool truth_thread) {
  sim::Scenario sc;
  sc.duration_s = 200.0;
  std::string err;
  auto motion = sim::FlightMotion::create(sc, err);
  EXPECT_TRUE(motion) << err;
  std::vector<double> out;
  if (!motion) return out;
  sim::ImuModel imu(sim::draw_imu_errors(sc.imu, sc.effects, 7), 7);
  tools::FreeInertialConfig cfg;
  cfg.duration_s = sc.duration_s;
  cfg.truth_thread = truth_thread;
  fsw::Status st = fsw::Status::kOk;
  tools::run_free_inertial(
      *motion, &imu, cfg,
      [&](const sim::TruthSample& truth, const fsw::NavState& nav) {
        out.insert(out.end(), {truth.t_s, truth.llh.x(), truth.C_b_n(0, 1), nav.llh.x(), nav.llh.y(), nav.llh.z(),
                               nav.vel_enu_mps.x(), nav.q_b_n.w(), nav.q_b_n.z()});
      },
      &st);
  EXPECT_EQ(st, fsw::Status::kOk);
  return out;
}

}  // namespace

TEST(FreeInertial, TheTruthOnItsOwnThreadGivesTheSameFlightBitForBit) {
  const std::vector<double> inline_truth = frames_of(false), threaded = frames_of(true);
  ASSERT_EQ(inline_truth.size(), 40000u * 9u);  // 200 s of 200 Hz frames
  ASSERT_EQ(threaded.size(), inline_truth.size());
  EXPECT_EQ(std::memcmp(threaded.data(), inline_truth.data(), inline_truth.size() * sizeof(double)), 0);
}
