// The loosely coupled (GNSS position/velocity) update of the EKF: the measurement model against
// finite differences, one update against the scalar Kalman formula, gating and invalid input,
// the gating runaway on solutions, and the executive's routing of solutions next to raw epochs.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "fsw/ekf.hpp"
#include "fsw/executive.hpp"

namespace {

using fsw::Block;
using fsw::InnovationOutcome;
using fsw::kDegToRad;
using fsw::Mat3;
using fsw::Vec3;

/// A state of the model's 13 columns: position, velocity, attitude, lever arm, time offset.
struct ModelState {
  fsw::NavState nav;
  Vec3 lever_b = Vec3::Zero();
  double tau_s = 0.0;
};

/// Applies an error dx (estimate minus truth) in the model's column order.
ModelState perturbed(ModelState s, const Eigen::Matrix<double, 13, 1>& dx) {
  s.nav.llh += fsw::llh_delta_from_enu(s.nav.llh, dx.segment<3>(0));
  s.nav.vel_enu_mps += dx.segment<3>(3);
  s.nav.q_b_n = fsw::quat_from_rotvec(-Vec3(dx.segment<3>(6))) * s.nav.q_b_n;  // C_hat = (I - [phi x]) C
  s.lever_b += dx.segment<3>(9);
  s.tau_s += dx(12);
  return s;
}

Eigen::Matrix<double, 6, 1> innovation(const fsw::GnssPvtMeasurement& m, const ModelState& s, const Vec3& w,
                                       const Vec3& a_n) {
  const fsw::PvtModel p = fsw::pvt_measurement_model(m, s.nav, w, s.lever_b, s.tau_s, a_n);
  Eigen::Matrix<double, 6, 1> y;
  y << p.pos_innovation_m, p.vel_innovation_mps;
  return y;
}

fsw::NavState static_nav() {
  fsw::NavState nav;
  nav.t_s = 100.0;
  nav.llh = Vec3(35.0 * kDegToRad, 127.0 * kDegToRad, 100.0);
  nav.q_b_n = fsw::Quat(fsw::C_b_n_from_euler(0.02, -0.01, 0.7));
  return nav;
}

/// A solution equal to the prediction of `nav` with zero lever arm (antenna = IMU), then offset.
fsw::GnssPvtMeasurement solution_at(const fsw::NavState& nav, const Vec3& pos_offset_enu_m, const Vec3& vel_offset) {
  fsw::GnssPvtMeasurement m;
  m.t_s = nav.t_s;
  m.llh = nav.llh + fsw::llh_delta_from_enu(nav.llh, pos_offset_enu_m);
  m.vel_enu_mps = nav.vel_enu_mps + vel_offset;
  m.pos_sigma_enu_m = Vec3(1.0, 2.0, 3.0);
  m.vel_sigma_enu_mps = Vec3(0.1, 0.2, 0.3);
  m.has_velocity = true;
  m.quality = 1;
  m.n_sat = 9;
  return m;
}

/// A solution pos_offset_enu_m away from nav (velocity of nav) with a 0.1 m position sigma: the
/// gate rejects an offset of a few metres.
fsw::GnssPvtMeasurement precise_solution_at(const fsw::NavState& nav, const Vec3& pos_offset_enu_m) {
  fsw::GnssPvtMeasurement m = solution_at(nav, pos_offset_enu_m, Vec3::Zero());
  m.pos_sigma_enu_m = Vec3::Constant(0.1);
  return m;
}

}  // namespace

// Every column of H (position, velocity, attitude in the phi convention of frames.hpp, lever arm,
// time offset) against central differences of the predicted measurement, at a state with a body
// rate, an acceleration, a lever arm, a time offset and a solution time 3 ms after the INS time.
TEST(EkfPvt, MeasurementModelMatchesFiniteDifferences) {
  ModelState truth;
  truth.nav.t_s = 50.0;
  truth.nav.llh = Vec3(35.0 * kDegToRad, 127.0 * kDegToRad, 120.0);
  truth.nav.vel_enu_mps = Vec3(3.0, 7.0, 0.2);
  truth.nav.q_b_n = fsw::Quat(fsw::C_b_n_from_euler(0.05, -0.03, 0.4));
  truth.lever_b = Vec3(0.5, -0.3, -1.2);
  truth.tau_s = 0.02;
  const Vec3 w(0.02, -0.01, 0.3), a_n(0.5, -1.0, 0.1);
  fsw::GnssPvtMeasurement m;
  m.t_s = truth.nav.t_s + 0.003;
  const fsw::PvtModel at_truth = fsw::pvt_measurement_model(m, truth.nav, w, truth.lever_b, truth.tau_s, a_n);
  m.llh = at_truth.llh_ant;  // a noise-free solution of the truth: zero innovation there
  m.vel_enu_mps = at_truth.vel_ant_enu_mps;
  EXPECT_LT(innovation(m, truth, w, a_n).norm(), 1e-8);
  const Eigen::Matrix<double, 6, 13> H = fsw::pvt_measurement_model(m, truth.nav, w, truth.lever_b, truth.tau_s, a_n).H;
  // Fourth-order central differences (error O(h^4)), steps well above the rounding of the inputs.
  const double step[13] = {1.0, 1.0, 1.0, 0.1, 0.1, 0.1, 3e-3, 3e-3, 3e-3, 0.1, 0.1, 0.1, 0.01};
  double worst = 0.0;
  for (int j = 0; j < 13; ++j) {
    Eigen::Matrix<double, 13, 1> dx = Eigen::Matrix<double, 13, 1>::Zero();
    dx(j) = step[j];
    const auto y = [&](double k) { return innovation(m, perturbed(truth, k * dx), w, a_n); };
    const Eigen::Matrix<double, 6, 1> fd = (-y(2.0) + 8.0 * y(1.0) - 8.0 * y(-1.0) + y(-2.0)) / (12.0 * step[j]);
    for (int i = 0; i < 6; ++i) {
      EXPECT_NEAR(H(i, j), fd(i), 1e-6 * (1.0 + std::abs(fd(i)))) << "row " << i << " column " << j;
      worst = std::max(worst, std::abs(H(i, j) - fd(i)));
    }
  }
  std::printf("PVT H against central differences: worst |H - dz/dx| %.2e\n", worst);
  // The sign convention of the pseudorange's attitude term: rho = -e^T p_a, so its H_att is
  // -e^T times the position rows' attitude block [(C_b_n l) x].
  // (The position rows also carry dt = t_meas + tau_hat - t_nav times the velocity rows' terms.)
  const Vec3 l_n = truth.nav.C_b_n() * truth.lever_b;
  const double dt = m.t_s + truth.tau_s - truth.nav.t_s;
  EXPECT_LT((H.block<3, 3>(0, 6) - (fsw::skew(l_n) + dt * H.block<3, 3>(3, 6))).norm(), 1e-12);
  // Every layout maps the columns: LayoutDiag carries lever arm and time offset.
  fsw::EkfConfig cfg;
  cfg.lever_arm_sigma_m = 1.0;
  cfg.time_offset_sigma_s = 0.01;
  cfg.gate_chi2 = 1e-300;  // gate everything: the report then holds the prior innovations y = z_hat - z
  cfg.lever_arm_b_m = truth.lever_b;
  static fsw::Ekf<fsw::LayoutDiag> ekf;
  ASSERT_EQ(ekf.init(cfg), fsw::Status::kOk);
  fsw::GnssPvtMeasurement m2 = m;
  m2.pos_sigma_enu_m = m2.vel_sigma_enu_mps = Vec3::Constant(0.5);
  m2.has_velocity = true;
  m2.quality = 1;
  m2.llh = fsw::pvt_measurement_model(m, truth.nav, w, truth.lever_b, 0.0, Vec3::Zero()).llh_ant +
           fsw::llh_delta_from_enu(truth.nav.llh, Vec3(1.0, -2.0, 3.0));
  m2.vel_enu_mps = fsw::pvt_measurement_model(m, truth.nav, w, truth.lever_b, 0.0, Vec3::Zero()).vel_ant_enu_mps +
                   Vec3(0.1, -0.2, 0.3);
  fsw::EkfUpdateReport rep;
  ASSERT_EQ(ekf.update_pvt(m2, truth.nav, w, rep), fsw::Status::kOk);
  EXPECT_TRUE(rep.pvt);
  EXPECT_EQ(rep.pos_rejected, 3);
  EXPECT_EQ(rep.vel_rejected, 3);
  EXPECT_NEAR(rep.pvt_obs[0].innovation, -1.0, 1e-4);
  EXPECT_NEAR(rep.pvt_obs[1].innovation, 2.0, 1e-4);
  EXPECT_NEAR(rep.pvt_obs[2].innovation, -3.0, 1e-4);
  // The variance uses the mapped H row: position E with lever arm and time offset columns.
  const fsw::PvtModel p2 = fsw::pvt_measurement_model(m2, truth.nav, w, truth.lever_b, 0.0,
                                                      Vec3(0.0, 0.0, -fsw::normal_gravity_mps2(truth.nav.llh.x(), 120.0)));
  constexpr int ol = fsw::LayoutDiag::offset(Block::kLeverArm), ot = fsw::LayoutDiag::offset(Block::kTimeOffset);
  for (int i = 0; i < 6; ++i) {
    Eigen::Matrix<double, 1, fsw::LayoutDiag::kSize> h = Eigen::Matrix<double, 1, fsw::LayoutDiag::kSize>::Zero();
    h.head<9>() = p2.H.block<1, 9>(i, 0);
    h.segment<3>(ol) = p2.H.block<1, 3>(i, 9);
    h(ot) = p2.H(i, 12);
    const double S = (h * ekf.P() * h.transpose())(0, 0) + 0.25;
    EXPECT_NEAR(rep.pvt_obs[static_cast<std::size_t>(i)].variance, S, 1e-9 * S) << i;
    EXPECT_NEAR(rep.pvt_obs[static_cast<std::size_t>(i)].innovation, (i < 3 ? p2.pos_innovation_m(i) : p2.vel_innovation_mps(i - 3)),
                1e-9);
  }
}

// Static, a position offset and a velocity offset, diagonal P, no lever arm: each axis is an
// independent scalar problem, so the posterior is the scalar Kalman formula per axis; the floor
// and the scale of R apply.
TEST(EkfPvt, UpdateEqualsScalarKalmanFormula) {
  fsw::EkfConfig cfg;
  cfg.pos_sigma_m = 10.0;
  cfg.vel_sigma_mps = 0.5;
  cfg.pvt_sigma_scale = 1.5;
  cfg.pvt_pos_sigma_floor_m = 0.02;
  cfg.pvt_vel_sigma_floor_mps = 0.01;
  fsw::Ekf<fsw::Layout15> ekf;
  ASSERT_EQ(ekf.init(cfg), fsw::Status::kOk);
  const fsw::NavState nav = static_nav();
  const Vec3 dp(3.0, -2.0, 1.0), dv(0.2, -0.1, 0.05);
  fsw::GnssPvtMeasurement m = solution_at(nav, dp, dv);
  m.pos_sigma_enu_m = Vec3(1.0, 2.0, 0.005);  // U below the 0.02 m floor
  m.vel_sigma_enu_mps = Vec3(0.1, 0.004, 0.3);  // N below the 0.01 m/s floor
  fsw::EkfUpdateReport rep;
  ASSERT_EQ(ekf.update_pvt(m, nav, Vec3::Zero(), rep), fsw::Status::kOk);
  EXPECT_EQ(rep.pos_used, 3);
  EXPECT_EQ(rep.vel_used, 3);
  EXPECT_EQ(rep.nis_dof, 6);
  double nis = 0.0;
  for (int i = 0; i < 6; ++i) {
    const bool pos = i < 3;
    const double p0 = pos ? 100.0 : 0.25;
    const double sig = pos ? std::max(m.pos_sigma_enu_m(i), 0.02) : std::max(m.vel_sigma_enu_mps(i - 3), 0.01);
    const double r = 1.5 * 1.5 * sig * sig;
    const double y = pos ? -dp(i) : -dv(i - 3);  // predicted minus measured
    EXPECT_NEAR(rep.pvt_obs[static_cast<std::size_t>(i)].innovation, y, 1e-9) << i;
    EXPECT_NEAR(rep.pvt_obs[static_cast<std::size_t>(i)].variance, p0 + r, 1e-9 * (p0 + r)) << i;
    EXPECT_EQ(rep.pvt_obs[static_cast<std::size_t>(i)].outcome, InnovationOutcome::kUsed);
    // (y itself carries the rounding of the llh sum that built the solution, about 4e-10 m.)
    EXPECT_NEAR(ekf.x()(i), p0 / (p0 + r) * y, 1e-9) << i;
    EXPECT_NEAR(ekf.P()(i, i), p0 * r / (p0 + r), 1e-12 * p0) << i;
    nis += y * y / (p0 + r);
  }
  EXPECT_NEAR(rep.nis_sum, nis, 1e-9 * nis);
  // Attitude and the rest untouched (no lever arm, static: H has only the position/velocity blocks).
  EXPECT_EQ(ekf.x().tail<fsw::Layout15::kSize - 6>().cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(ekf.health().nis_window_dof, 6);

  // Position only.
  ASSERT_EQ(ekf.init(cfg), fsw::Status::kOk);
  m.has_velocity = false;
  ASSERT_EQ(ekf.update_pvt(m, nav, Vec3::Zero(), rep), fsw::Status::kOk);
  EXPECT_EQ(rep.pos_used, 3);
  EXPECT_EQ(rep.vel_used + rep.vel_rejected + rep.obs_invalid, 0);
  EXPECT_EQ(rep.pvt_obs[3].outcome, InnovationOutcome::kNotProcessed);
  EXPECT_EQ(ekf.x().segment<3>(3).cwiseAbs().maxCoeff(), 0.0);
}

// A 100-sigma outlier is gated and counted and leaves the state alone; NaN in the solution is
// invalid (counted, state untouched); NaN in the navigation state is a bad input.
TEST(EkfPvt, OutlierAndNonFiniteInputAreRejectedAndCounted) {
  fsw::EkfConfig cfg;
  fsw::Ekf<fsw::Layout24> ekf;
  ASSERT_EQ(ekf.init(cfg), fsw::Status::kOk);
  const fsw::NavState nav = static_nav();
  const auto x0 = ekf.x();
  const auto P0 = ekf.P();
  fsw::EkfUpdateReport rep;
  // S = P + R = 100 + sigma^2 per axis; 100 sigma of it in every axis.
  fsw::GnssPvtMeasurement out = solution_at(nav, Vec3(100.0 * std::sqrt(101.0), -100.0 * std::sqrt(104.0),
                                                      100.0 * std::sqrt(109.0)), Vec3::Zero());
  out.has_velocity = false;
  ASSERT_EQ(ekf.update_pvt(out, nav, Vec3::Zero(), rep), fsw::Status::kOk);
  EXPECT_EQ(rep.pos_rejected, 3);
  EXPECT_EQ(rep.pos_used, 0);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(rep.pvt_obs[static_cast<std::size_t>(i)].outcome, InnovationOutcome::kGated);
    EXPECT_NEAR(std::abs(rep.pvt_obs[static_cast<std::size_t>(i)].innovation) /
                    std::sqrt(rep.pvt_obs[static_cast<std::size_t>(i)].variance), 100.0, 1e-6);
  }
  EXPECT_EQ(rep.nis_dof, 0);
  EXPECT_EQ(ekf.x(), x0);
  EXPECT_EQ(ekf.P(), P0);

  // One axis an outlier, the others used.
  fsw::GnssPvtMeasurement one = solution_at(nav, Vec3(1.0, 100.0 * std::sqrt(104.0), -1.0), Vec3::Zero());
  ASSERT_EQ(ekf.update_pvt(one, nav, Vec3::Zero(), rep), fsw::Status::kOk);
  EXPECT_EQ(rep.pos_used, 2);
  EXPECT_EQ(rep.pos_rejected, 1);
  EXPECT_EQ(rep.pvt_obs[1].outcome, InnovationOutcome::kGated);
  EXPECT_EQ(rep.vel_used, 3);

  ASSERT_EQ(ekf.init(cfg), fsw::Status::kOk);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  fsw::GnssPvtMeasurement bad = solution_at(nav, Vec3(1.0, 2.0, 3.0), Vec3::Zero());
  bad.llh.y() = nan;
  bad.vel_enu_mps.z() = nan;
  ASSERT_EQ(ekf.update_pvt(bad, nav, Vec3::Zero(), rep), fsw::Status::kOk);
  EXPECT_EQ(rep.obs_invalid, 2);
  for (const auto& o : rep.pvt_obs) EXPECT_EQ(o.outcome, InnovationOutcome::kInvalid);
  EXPECT_EQ(rep.pos_used + rep.vel_used + rep.pos_rejected + rep.vel_rejected, 0);
  EXPECT_EQ(ekf.x(), x0);
  EXPECT_EQ(ekf.P(), P0);
  fsw::GnssPvtMeasurement zero_sigma = solution_at(nav, Vec3(1.0, 2.0, 3.0), Vec3::Zero());
  zero_sigma.pos_sigma_enu_m.x() = 0.0;
  ASSERT_EQ(ekf.update_pvt(zero_sigma, nav, Vec3::Zero(), rep), fsw::Status::kOk);
  EXPECT_EQ(rep.obs_invalid, 1);
  EXPECT_EQ(rep.pos_used, 0);
  EXPECT_EQ(rep.vel_used, 3);

  ASSERT_EQ(ekf.init(cfg), fsw::Status::kOk);
  fsw::NavState bad_nav = nav;
  bad_nav.vel_enu_mps.x() = nan;
  EXPECT_EQ(ekf.update_pvt(solution_at(nav, Vec3::Ones(), Vec3::Zero()), bad_nav, Vec3::Zero(), rep),
            fsw::Status::kBadInput);
  fsw::GnssPvtMeasurement bad_t = solution_at(nav, Vec3::Ones(), Vec3::Zero());
  bad_t.t_s = nan;
  EXPECT_EQ(ekf.update_pvt(bad_t, nav, Vec3::Zero(), rep), fsw::Status::kBadInput);
  EXPECT_EQ(ekf.health().nonfinite_rejected, 2u);
  EXPECT_EQ(ekf.x(), x0);
  EXPECT_EQ(ekf.P(), P0);
}

// A position jump (every position gated, velocities fine) for runaway_epochs updates in a row is
// a gating runaway: the position and velocity variances are re-opened and the next solution is
// taken ungated (re-acquisition), after which the solutions pass the gate again.
TEST(EkfPvt, PositionJumpRunawayReopensTheFilter) {
  fsw::EkfConfig cfg;
  cfg.pos_sigma_m = 30.0;
  fsw::Ekf<fsw::Layout15> ekf;
  ASSERT_EQ(ekf.init(cfg), fsw::Status::kOk);
  const fsw::NavState nav = static_nav();
  fsw::EkfUpdateReport rep;
  const fsw::GnssPvtMeasurement good = precise_solution_at(nav, Vec3::Zero());
  for (int k = 0; k < 3; ++k) ASSERT_EQ(ekf.update_pvt(good, nav, Vec3::Zero(), rep), fsw::Status::kOk);
  EXPECT_EQ(rep.pos_used, 3);
  const fsw::GnssPvtMeasurement jump = precise_solution_at(nav, Vec3(5.0, -5.0, 5.0));
  for (int k = 0; k < 5; ++k) {
    ASSERT_EQ(ekf.update_pvt(jump, nav, Vec3::Zero(), rep), fsw::Status::kOk);
    EXPECT_EQ(rep.pos_rejected, 3) << k;
    EXPECT_EQ(rep.vel_used, 3) << k;
  }
  EXPECT_EQ(ekf.health().resets, 1u);
  EXPECT_EQ(ekf.health().gating_runaway_epochs, 5u);
  EXPECT_NEAR(ekf.P()(0, 0), 1.0e6, 1e-9);
  ASSERT_EQ(ekf.update_pvt(jump, nav, Vec3::Zero(), rep), fsw::Status::kOk);
  EXPECT_EQ(rep.pos_used, 3);
  // The error state took the jump nearly whole (estimate = INS minus truth = -offset).
  EXPECT_NEAR(ekf.x()(0), -5.0, 0.01);
  EXPECT_NEAR(ekf.x()(1), 5.0, 0.01);
  ASSERT_EQ(ekf.update_pvt(jump, nav, Vec3::Zero(), rep), fsw::Status::kOk);
  EXPECT_EQ(rep.pos_used, 3);
}

// One axis alone stuck at the gate (the car of the gnss-imu-drive data set: its East error grew
// while the filter trusted its position; North and Up kept being used) is a runaway too; an axis
// that passes the gate in between starts its count again.
TEST(EkfPvt, OneAxisGatedEveryUpdateIsARunaway) {
  fsw::EkfConfig cfg;
  fsw::Ekf<fsw::Layout15> ekf;
  ASSERT_EQ(ekf.init(cfg), fsw::Status::kOk);
  const fsw::NavState nav = static_nav();
  fsw::EkfUpdateReport rep;
  const fsw::GnssPvtMeasurement good = precise_solution_at(nav, Vec3::Zero());
  for (int k = 0; k < 5; ++k) ASSERT_EQ(ekf.update_pvt(good, nav, Vec3::Zero(), rep), fsw::Status::kOk);
  const fsw::GnssPvtMeasurement east = precise_solution_at(nav, Vec3(50.0, 0.0, 0.0));
  for (int k = 0; k < 4; ++k) {
    ASSERT_EQ(ekf.update_pvt(east, nav, Vec3::Zero(), rep), fsw::Status::kOk);
    EXPECT_EQ(rep.pos_rejected, 1) << k;
    EXPECT_EQ(rep.pos_used, 2) << k;
  }
  ASSERT_EQ(ekf.update_pvt(good, nav, Vec3::Zero(), rep), fsw::Status::kOk);  // East passes: count restarts
  for (int k = 0; k < 4; ++k) ASSERT_EQ(ekf.update_pvt(east, nav, Vec3::Zero(), rep), fsw::Status::kOk);
  EXPECT_EQ(ekf.health().resets, 0u);
  ASSERT_EQ(ekf.update_pvt(east, nav, Vec3::Zero(), rep), fsw::Status::kOk);
  EXPECT_EQ(ekf.health().resets, 1u);
  ASSERT_EQ(ekf.update_pvt(east, nav, Vec3::Zero(), rep), fsw::Status::kOk);  // re-acquisition, ungated
  EXPECT_EQ(rep.pos_used, 3);
  EXPECT_NEAR(ekf.x()(0), -50.0, 0.05);
}

#include "sim/trajectory.hpp"

namespace {

struct ExecRun {
  fsw::ExecutiveHealth health;
  int updates = 0;
  int pvt_updates = 0;
  double first_update_t = -1.0;
};

/// A static IMU (perfect samples, 1 kHz) through the executive with solutions of the truth at
/// `pvt_rate_hz`, each delivered `latency_s` after its time; raw epochs (without satellites) at
/// 1 Hz when `with_raw`.
ExecRun run_static(int frames_per_ekf, double pvt_rate_hz, double latency_s, bool with_raw, double duration_s) {
  const Vec3 llh(35.0 * kDegToRad, 127.0 * kDegToRad, 100.0);
  sim::TableMotion table(llh, fsw::C_b_n_from_euler(0.0, 0.0, 0.5), Vec3(0, 0, 1), 0.0);
  sim::TruthGenerator gen(table, 1000.0);
  fsw::ExecutiveConfig cfg;
  cfg.frames_per_ekf = frames_per_ekf;
  static fsw::Executive<fsw::Layout15> exec;
  fsw::NavState init;
  init.llh = llh;
  init.q_b_n = fsw::Quat(gen.current().C_b_n);
  EXPECT_EQ(exec.init(cfg, init), fsw::Status::kOk);
  ExecRun r;
  fsw::ImuSample frame[5];
  int n = 0, k_pvt = 1;
  const double T = 1.0 / pvt_rate_hz;
  fsw::GnssPvtMeasurement pvt;
  fsw::GnssEpoch raw;
  fsw::FrameOutput out;
  bool pvt_arrived = false, raw_arrived = false;
  while (gen.current().t_s < duration_s - 1e-9) {
    const sim::TruthSample& t = gen.next();
    frame[n++] = {t.t_s, t.dt_s, t.dtheta_rad, t.dv_mps};
    if (t.t_s >= k_pvt * T + latency_s - 1e-9) {
      pvt = solution_at(init, Vec3::Zero(), Vec3::Zero());
      pvt.t_s = k_pvt * T;
      pvt.pos_sigma_enu_m = Vec3::Constant(0.05);
      pvt.vel_sigma_enu_mps = Vec3::Constant(0.02);
      pvt_arrived = true;
      if (with_raw && std::abs(pvt.t_s - std::round(pvt.t_s)) < 1e-9) {
        raw.t_s = pvt.t_s;
        raw.n_obs = 0;
        raw_arrived = true;
      }
      ++k_pvt;
    }
    if (n < 5) continue;
    fsw::FrameInput in;
    in.imu = frame;
    in.n_imu = 5;
    in.pvt = pvt_arrived ? &pvt : nullptr;
    in.gnss = raw_arrived ? &raw : nullptr;
    pvt_arrived = raw_arrived = false;
    n = 0;
    EXPECT_EQ(exec.tick(in, out), fsw::Status::kOk);
    if (out.ekf_updated) {
      ++r.updates;
      if (out.report.pvt) ++r.pvt_updates;
      if (r.first_update_t < 0.0) r.first_update_t = out.nav.t_s;
    }
  }
  r.health = exec.health();
  return r;
}

}  // namespace

// 4 Hz solutions with frames_per_ekf = 50 (and 30 ms latency): one EKF update per solution, none
// replaced or stale; at 1 Hz EKF rate three of four are replaced.
TEST(ExecutivePvt, FourHertzSolutionsGiveAFourHertzEkf) {
  const ExecRun r = run_static(50, 4.0, 0.03, false, 20.0);
  std::printf("4 Hz solutions, frames_per_ekf 50: %d updates in 20 s, replaced %u, stale %u, without gnss %u\n", r.updates,
              r.health.pvt_replaced, r.health.pvt_stale, r.health.ekf_without_gnss);
  EXPECT_EQ(r.health.pvt_received, 79u);  // t = 0.25 ... 19.75 arrive before 20 s
  EXPECT_GE(r.updates, 78);
  EXPECT_EQ(r.pvt_updates, r.updates);
  EXPECT_EQ(r.health.pvt_replaced, 0u);
  EXPECT_EQ(r.health.pvt_stale, 0u);
  EXPECT_EQ(r.health.ekf_without_gnss, 0u);
  EXPECT_EQ(r.health.pos_used, 3u * static_cast<unsigned>(r.updates));
  EXPECT_EQ(r.health.vel_used, 3u * static_cast<unsigned>(r.updates));
  EXPECT_EQ(r.health.pos_rejected + r.health.vel_rejected + r.health.fsw_errors, 0u);
  const ExecRun slow = run_static(200, 4.0, 0.03, false, 20.0);
  EXPECT_GE(slow.updates, 19);
  EXPECT_GE(slow.health.pvt_replaced, 50u);
}

// A raw epoch and a solution ready together: the raw epoch is used, the solution counted unused.
TEST(ExecutivePvt, RawEpochWinsOverASimultaneousSolution) {
  const ExecRun r = run_static(200, 1.0, 0.01, true, 10.5);
  EXPECT_EQ(r.updates, 10);
  EXPECT_EQ(r.pvt_updates, 0);
  EXPECT_EQ(r.health.pvt_unused, 10u);
  EXPECT_EQ(r.health.pos_used, 0u);
}

// Invalid and stale solutions are counted and not used.
TEST(ExecutivePvt, InvalidAndStaleSolutionsAreCounted) {
  fsw::ExecutiveConfig cfg;
  static fsw::Executive<fsw::Layout15> exec;
  fsw::NavState init = static_nav();
  init.t_s = 0.0;
  ASSERT_EQ(exec.init(cfg, init), fsw::Status::kOk);
  fsw::GnssPvtMeasurement bad = solution_at(init, Vec3::Zero(), Vec3::Zero());
  bad.t_s = std::numeric_limits<double>::quiet_NaN();
  fsw::GnssPvtMeasurement old = solution_at(init, Vec3::Zero(), Vec3::Zero());
  old.t_s = 0.5;  // used only at t = 1 s: 0.5 s old
  fsw::FrameOutput out;
  fsw::ImuSample frame[5];
  const Mat3 C = init.C_b_n();
  const Vec3 f_b = C.transpose() * Vec3(0.0, 0.0, fsw::normal_gravity_mps2(init.llh.x(), init.llh.z()));
  for (int k = 0; k < 250; ++k) {  // the run without GNSS is released at frame 240, lands at 250
    for (int i = 0; i < 5; ++i) frame[i] = {(5 * k + i + 1) * 1e-3, 1e-3, Vec3::Zero(), f_b * 1e-3};
    fsw::FrameInput in;
    in.imu = frame;
    in.n_imu = 5;
    if (k == 10) in.pvt = &bad;
    if (k == 20) in.pvt = &old;
    ASSERT_EQ(exec.tick(in, out), fsw::Status::kOk);
  }
  EXPECT_EQ(exec.health().pvt_received, 2u);
  EXPECT_EQ(exec.health().pvt_invalid, 1u);
  EXPECT_EQ(exec.health().pvt_stale, 1u);
  EXPECT_EQ(exec.health().ekf_updates, 0u);
  EXPECT_EQ(exec.health().ekf_without_gnss, 1u);
}
