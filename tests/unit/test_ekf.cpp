// The error-state EKF: layout, transition matrix against the nonlinear mechanization, the
// measurement update against the batch Kalman formula, and the filter on static and
// constant-velocity flights with known answers (GNSS from fixed synthetic satellites, so these
// tests do not depend on the almanac or the simulated receiver).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <cstdio>
#include <functional>
#include <random>
#include <vector>

#include "fsw/ekf.hpp"
#include "fsw/executive.hpp"
#include "sim/scenario.hpp"
#include "sim/trajectory.hpp"

namespace {

using fsw::Block;
using fsw::kArcsecToRad;
using fsw::kRadToArcsec;
using fsw::Layout15;
using fsw::Layout24;
using fsw::Mat3;
using fsw::Vec3;

fsw::NavState nav_from_truth(const sim::TruthSample& t) {
  fsw::NavState s;
  s.t_s = t.t_s;
  s.llh = t.llh;
  s.vel_enu_mps = t.vel_enu_mps;
  s.q_b_n = fsw::Quat(t.C_b_n);
  return s;
}

/// Applies an error (estimate minus truth) to a solution.
fsw::NavState perturb(fsw::NavState s, const Vec3& dp_enu_m, const Vec3& dv_enu_mps, const Vec3& phi_rad) {
  s.llh += fsw::llh_delta_from_enu(s.llh, dp_enu_m);
  s.vel_enu_mps += dv_enu_mps;
  s.q_b_n = fsw::quat_from_rotvec(-phi_rad) * s.q_b_n;
  return s;
}

Eigen::Matrix<double, 9, 1> nav_difference(const fsw::NavState& hat, const fsw::NavState& ref) {
  Eigen::Matrix<double, 9, 1> d;
  d.segment<3>(0) = fsw::enu_difference_m(hat.llh, ref.llh);
  d.segment<3>(3) = hat.vel_enu_mps - ref.vel_enu_mps;
  d.segment<3>(6) = fsw::attitude_error_enu(hat.C_b_n(), ref.C_b_n());
  return d;
}

/// Truth samples of the default bank-to-turn flight in [t0, t1] (1 kHz).
std::vector<sim::TruthSample> truth_window(double t0, double t1) {
  sim::Scenario sc;
  sc.duration_s = t1 + 1.0;
  std::string err;
  auto motion = sim::FlightMotion::create(sc, err);
  EXPECT_TRUE(motion) << err;
  std::vector<sim::TruthSample> out;
  sim::TruthGenerator gen(*motion, 1000.0);
  if (gen.current().t_s >= t0 - 1e-9) out.push_back(gen.current());
  while (gen.current().t_s < t1 - 1e-9) {
    const sim::TruthSample& s = gen.next();
    if (s.t_s >= t0 - 1e-9) out.push_back(s);
  }
  return out;
}

fsw::ImuSample ideal_imu(const sim::TruthSample& t) {
  fsw::ImuSample s;
  s.t_s = t.t_s;
  s.dt_s = t.dt_s;
  s.dtheta_rad = t.dtheta_rad;
  s.dv_mps = t.dv_mps;
  return s;
}

}  // namespace

TEST(ErrorStateLayout, OffsetsAndSizes) {
  EXPECT_EQ(Layout15::kSize, 17);
  EXPECT_EQ(Layout24::kSize, 26);
  EXPECT_EQ(Layout15::offset(Block::kGyroBias), 12);
  EXPECT_EQ(Layout15::offset(Block::kClock), 15);
  EXPECT_EQ(Layout15::offset(Block::kGyroMisalign), -1);
  EXPECT_EQ(Layout24::offset(Block::kAccelMisalign), 15);
  EXPECT_EQ(Layout24::offset(Block::kGyroMisalign), 18);
  EXPECT_EQ(Layout24::offset(Block::kClock), 24);
  EXPECT_TRUE(Layout24::has(Block::kGyroMisalign));
  EXPECT_FALSE(Layout15::has(Block::kAccelMisalign));
}

// The transition matrix the filter builds from the 200 Hz data must predict how a small initial
// error grows in the real (nonlinear) mechanization, including the misalignment columns that
// the turn excites. 5 s in the middle of a 60-degree bank turn.
TEST(Ekf, TransitionMatrixMatchesNonlinearMechanizationInATurn) {
  const double t0 = 75.0, T = 5.0;
  const auto truth = truth_window(t0, t0 + T);
  ASSERT_GT(truth.size(), 4000u);
  ASSERT_GT(std::abs(truth.front().omega_ib_b_radps.z()), 0.01) << "not in the turn";

  using Ekf = fsw::Ekf<Layout24>;
  constexpr int N = Layout24::kSize;
  fsw::EkfConfig cfg;
  Ekf ekf;
  ASSERT_EQ(ekf.init(cfg), fsw::Status::kOk);

  // Each column: one error alone, sized like the paper's errors (a bit larger for resolution).
  struct Case {
    const char* name;
    int state;
    double size;
  };
  const int oab = Layout24::offset(Block::kAccelBias), ogb = Layout24::offset(Block::kGyroBias);
  const int oam = Layout24::offset(Block::kAccelMisalign), ogm = Layout24::offset(Block::kGyroMisalign);
  const std::vector<Case> cases = {
      {"pos N", 1, 20.0},          {"pos U", 2, 20.0},           {"vel E", 3, 0.5},
      {"vel N", 4, 0.5},           {"phi E", 6, 60 * kArcsecToRad}, {"phi N", 7, 60 * kArcsecToRad},
      {"phi U", 8, 300 * kArcsecToRad}, {"accel bias x", oab, 1e-3},  {"accel bias z", oab + 2, 1e-3},
      {"gyro bias x", ogb, 1e-5},  {"gyro bias z", ogb + 2, 1e-5}, {"accel mis yx", oam, 20 * kArcsecToRad},
      {"accel mis zy", oam + 2, 20 * kArcsecToRad}, {"gyro mis xy", ogm, 20 * kArcsecToRad},
      {"gyro mis yz", ogm + 3, 20 * kArcsecToRad},  {"gyro mis zy", ogm + 5, 20 * kArcsecToRad},
  };

  // Reference run: the filter accumulates along it.
  fsw::FrameBuilder fb;
  fb.configure(5);
  fsw::Strapdown ref;
  ref.init(nav_from_truth(truth.front()));
  Eigen::Matrix<double, N, N> Phi = Eigen::Matrix<double, N, N>::Identity();
  int frames = 0;
  for (std::size_t k = 1; k < truth.size(); ++k) {
    if (fb.add(ideal_imu(truth[k])) != fsw::Status::kOk) continue;
    ref.step(fb.frame());
    ekf.accumulate(fb.frame(), ref.state());
    if (++frames % 200 == 0) {
      ekf.propagate();
      Phi = (ekf.last_transition() * Phi).eval();
    }
  }
  ASSERT_EQ(frames, 1000);

  for (const Case& c : cases) {
    Eigen::Matrix<double, N, 1> dx0 = Eigen::Matrix<double, N, 1>::Zero();
    dx0(c.state) = c.size;
    fsw::ImuCompensation comp;  // residual error = -(compensation)
    comp.accel_bias_mps2 = -dx0.segment<3>(oab);
    comp.gyro_bias_radps = -dx0.segment<3>(ogb);
    for (int k = 0; k < 3; ++k)
      comp.accel_error(fsw::kAccelMisalignmentAxes[k].i, fsw::kAccelMisalignmentAxes[k].j) = -dx0(oam + k);
    for (int k = 0; k < 6; ++k)
      comp.gyro_error(fsw::kGyroMisalignmentAxes[k].i, fsw::kGyroMisalignmentAxes[k].j) = -dx0(ogm + k);
    fsw::FrameBuilder fb2;
    fb2.configure(5);
    fsw::Strapdown pert;
    pert.init(perturb(nav_from_truth(truth.front()), dx0.segment<3>(0), dx0.segment<3>(3), dx0.segment<3>(6)));
    fsw::Strapdown ref2;
    ref2.init(nav_from_truth(truth.front()));
    fsw::FrameBuilder fb3;
    fb3.configure(5);
    for (std::size_t k = 1; k < truth.size(); ++k) {
      if (fb2.add(comp.apply(ideal_imu(truth[k]))) == fsw::Status::kOk) pert.step(fb2.frame());
      if (fb3.add(ideal_imu(truth[k])) == fsw::Status::kOk) ref2.step(fb3.frame());
    }
    const Eigen::Matrix<double, 9, 1> actual = nav_difference(pert.state(), ref2.state());
    const Eigen::Matrix<double, 9, 1> predicted = Phi.topRows<9>() * dx0;
    // Compare in units of each block's scale: m, m/s, arcsec.
    Eigen::Matrix<double, 9, 1> w;
    w << 1, 1, 1, 100, 100, 100, kRadToArcsec, kRadToArcsec, kRadToArcsec;  // 1 cm/s ~ 1 m ~ 1 arcsec
    const double err = (actual - predicted).cwiseProduct(w).cwiseAbs().maxCoeff();
    const double mag = actual.cwiseProduct(w).cwiseAbs().maxCoeff();
    EXPECT_LT(err, 0.02 * mag + 0.01) << c.name << "\nactual    " << actual.transpose()
                                      << "\npredicted " << predicted.transpose();
  }
}

// One epoch of sequential scalar updates (Joseph form) equals the batch Kalman update.
TEST(Ekf, SequentialUpdateEqualsBatchKalmanFormula) {
  using Ekf = fsw::Ekf<Layout15>;
  constexpr int N = Layout15::kSize;
  fsw::EkfConfig cfg;
  cfg.gate_chi2 = 1e9;
  Ekf ekf;
  ASSERT_EQ(ekf.init(cfg), fsw::Status::kOk);
  fsw::NavState nav;
  nav.llh = Vec3(35.0 * fsw::kDegToRad, 127.0 * fsw::kDegToRad, 5000.0);
  nav.vel_enu_mps = Vec3(0.0, 250.0, 0.0);
  nav.q_b_n = fsw::Quat(fsw::C_b_n_from_euler(0.0, 0.0, 0.0));
  const Vec3 r_rx = fsw::ecef_from_llh(nav.llh);
  const Mat3 Cne = fsw::C_n_e(nav.llh.x(), nav.llh.y());
  fsw::GnssEpoch ep;
  ep.t_s = nav.t_s;
  const double az[6] = {0.3, 1.4, 2.5, 3.6, 4.7, 5.8}, el[6] = {0.3, 0.6, 0.9, 1.2, 0.5, 0.8};
  ep.n_obs = 6;
  for (int k = 0; k < 6; ++k) {
    const Vec3 u_n(std::cos(el[k]) * std::sin(az[k]), std::cos(el[k]) * std::cos(az[k]), std::sin(el[k]));
    auto& o = ep.obs[k];
    o.prn = static_cast<std::uint8_t>(k + 1);
    o.sat_pos_ecef_m = r_rx + Cne * u_n * 2.2e7;
    o.sat_vel_ecef_mps = Vec3(1000.0 * k, -500.0, 2000.0);
    const fsw::GnssGeometry g = fsw::gnss_geometry(o.sat_pos_ecef_m, o.sat_vel_ecef_mps, r_rx, Cne * nav.vel_enu_mps);
    o.pseudorange_m = g.range_m + 100.0 + 3.0 * (k - 2.5);  // clock 100 m, noise
    o.pseudorange_rate_mps = g.range_rate_mps + 2.0 + 0.1 * (k - 2.5);
  }
  fsw::EkfUpdateReport rep;
  ASSERT_EQ(ekf.update(ep, nav, Vec3::Zero(), rep), fsw::Status::kOk);
  EXPECT_TRUE(rep.clock_initialised);
  // Move the clock estimate off so the second epoch has innovations on the clock too.
  const Eigen::Matrix<double, N, N> P0 = ekf.P();
  const double b0 = ekf.clock_bias_m(), d0 = ekf.clock_drift_mps();
  for (int k = 0; k < 6; ++k) {
    ep.obs[k].pseudorange_m += 5.0 * std::sin(k);
    ep.obs[k].pseudorange_rate_mps += 0.2 * std::cos(k);
  }
  ASSERT_EQ(ekf.update(ep, nav, Vec3::Zero(), rep), fsw::Status::kOk);
  EXPECT_EQ(rep.pr_used, 6);
  EXPECT_EQ(rep.prr_used, 6);

  // Batch: stack all 12 rows, y = z_hat - z.
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(12, N);
  Eigen::VectorXd y(12), r(12);
  for (int k = 0; k < 6; ++k) {
    const auto& o = ep.obs[k];
    const fsw::GnssGeometry g = fsw::gnss_geometry(o.sat_pos_ecef_m, o.sat_vel_ecef_mps, r_rx, Cne * nav.vel_enu_mps);
    const Vec3 e_n = Cne.transpose() * g.los_ecef;
    H.block<1, 3>(2 * k, 0) = -e_n.transpose();
    H(2 * k, 15) = 1.0;
    y(2 * k) = g.range_m + b0 - o.pseudorange_m;
    r(2 * k) = 64.0;
    H.block<1, 3>(2 * k + 1, 3) = -e_n.transpose();
    H(2 * k + 1, 16) = 1.0;
    y(2 * k + 1) = g.range_rate_mps + d0 - o.pseudorange_rate_mps;
    r(2 * k + 1) = 0.04;
  }
  const Eigen::MatrixXd P0d = P0;
  const Eigen::MatrixXd S = H * P0d * H.transpose() + Eigen::MatrixXd(r.asDiagonal());
  const Eigen::MatrixXd K = P0d * H.transpose() * S.inverse();
  const Eigen::VectorXd x = K * y;
  const Eigen::MatrixXd P = (Eigen::MatrixXd::Identity(N, N) - K * H) * P0d;
  for (int i = 0; i < N; ++i) {
    EXPECT_NEAR(ekf.x()(i), x(i), 1e-9 * (1.0 + std::abs(x(i)))) << "state " << i;
    for (int j = 0; j < N; ++j)
      EXPECT_NEAR(ekf.P()(i, j), P(i, j), 1e-9 * std::sqrt(P0(i, i) * P0(j, j))) << i << "," << j;
  }
  EXPECT_EQ((ekf.P() - ekf.P().transpose()).cwiseAbs().maxCoeff(), 0.0);
}

// The report carries every observation's outcome and innovation: the clock-initialising epoch
// processes nothing, then an outlier is gated, a non-finite observation is invalid, and the first
// scalar update's innovation and variance are the prior ones (x = 0, P0).
TEST(Ekf, ReportsPerObservationInnovations) {
  using Ekf = fsw::Ekf<Layout15>;
  fsw::EkfConfig cfg;
  Ekf ekf;
  ASSERT_EQ(ekf.init(cfg), fsw::Status::kOk);
  fsw::NavState nav;
  nav.llh = Vec3(35.0 * fsw::kDegToRad, 127.0 * fsw::kDegToRad, 5000.0);
  nav.vel_enu_mps = Vec3(0.0, 250.0, 0.0);
  const Vec3 r_rx = fsw::ecef_from_llh(nav.llh);
  const Mat3 Cne = fsw::C_n_e(nav.llh.x(), nav.llh.y());
  fsw::GnssEpoch ep;
  const double az[6] = {0.3, 1.4, 2.5, 3.6, 4.7, 5.8}, el[6] = {0.3, 0.6, 0.9, 1.2, 0.5, 0.8};
  ep.n_obs = 6;
  for (int k = 0; k < 6; ++k) {
    const Vec3 u_n(std::cos(el[k]) * std::sin(az[k]), std::cos(el[k]) * std::cos(az[k]), std::sin(el[k]));
    auto& o = ep.obs[k];
    o.prn = static_cast<std::uint8_t>(10 + k);
    o.sat_pos_ecef_m = r_rx + Cne * u_n * 2.2e7;
    o.sat_vel_ecef_mps = Vec3(1000.0 * k, -500.0, 2000.0);
    const fsw::GnssGeometry g = fsw::gnss_geometry(o.sat_pos_ecef_m, o.sat_vel_ecef_mps, r_rx, Cne * nav.vel_enu_mps);
    o.pseudorange_m = g.range_m + 100.0 + 2.0 * (k - 2.5);
    o.pseudorange_rate_mps = g.range_rate_mps + 2.0 + 0.05 * (k - 2.5);
  }
  fsw::EkfUpdateReport rep;
  ASSERT_EQ(ekf.update(ep, nav, Vec3::Zero(), rep), fsw::Status::kOk);
  ASSERT_TRUE(rep.clock_initialised);
  ASSERT_EQ(rep.n_obs, 6);
  for (int k = 0; k < 6; ++k) {
    EXPECT_EQ(rep.obs[k].prn, 10 + k);
    EXPECT_EQ(rep.obs[k].pr_outcome, fsw::InnovationOutcome::kNotProcessed);
    EXPECT_EQ(rep.obs[k].prr_outcome, fsw::InnovationOutcome::kNotProcessed);
  }
  const double b0 = ekf.clock_bias_m();
  const double p_pos = ekf.P()(0, 0), p_clk = ekf.P()(15, 15);
  ep.obs[2].pseudorange_m += 2000.0;  // far outside the gate
  ep.obs[4].pseudorange_m = std::numeric_limits<double>::quiet_NaN();
  ASSERT_EQ(ekf.update(ep, nav, Vec3::Zero(), rep), fsw::Status::kOk);
  EXPECT_EQ(rep.pr_used, 4);
  EXPECT_EQ(rep.pr_rejected, 1);
  EXPECT_EQ(rep.obs_invalid, 1);
  EXPECT_EQ(rep.obs[0].pr_outcome, fsw::InnovationOutcome::kUsed);
  EXPECT_EQ(rep.obs[2].pr_outcome, fsw::InnovationOutcome::kGated);
  EXPECT_EQ(rep.obs[2].prr_outcome, fsw::InnovationOutcome::kUsed);
  EXPECT_EQ(rep.obs[4].pr_outcome, fsw::InnovationOutcome::kInvalid);
  EXPECT_EQ(rep.obs[4].prr_outcome, fsw::InnovationOutcome::kInvalid);
  const double nu2 = rep.obs[2].pr_innovation_m;
  EXPECT_GT(nu2 * nu2, cfg.gate_chi2 * rep.obs[2].pr_variance_m2);
  EXPECT_LT(nu2, -1900.0);  // predicted minus measured: the measurement is 2000 m long
  // First scalar update of the epoch: prior innovation and variance.
  const auto& o0 = ep.obs[0];
  const fsw::GnssGeometry g0 = fsw::gnss_geometry(o0.sat_pos_ecef_m, o0.sat_vel_ecef_mps, r_rx, Cne * nav.vel_enu_mps);
  EXPECT_NEAR(rep.obs[0].pr_innovation_m, g0.range_m + b0 - o0.pseudorange_m, 1e-6);
  const Vec3 e_n = Cne.transpose() * g0.los_ecef;
  const double var0 = e_n.squaredNorm() * p_pos + p_clk + cfg.pseudorange_sigma_m * cfg.pseudorange_sigma_m;
  EXPECT_NEAR(rep.obs[0].pr_variance_m2, var0, 1e-9 * var0);
  for (int k = 0; k < 6; ++k)
    if (k != 4) EXPECT_GT(rep.obs[k].prr_variance_m2ps2, 0.0);
}

namespace {

/// Fixed synthetic constellation: 8 satellites 20,200 km up at spread azimuths/elevations as
/// seen from the start point, static in ECEF (the filter does not care).
struct SyntheticSky {
  std::vector<Vec3> sats;
  explicit SyntheticSky(const Vec3& llh0) {
    const Vec3 r0 = fsw::ecef_from_llh(llh0);
    const Mat3 Cne = fsw::C_n_e(llh0.x(), llh0.y());
    const double az[8] = {0.1, 0.9, 1.7, 2.5, 3.3, 4.1, 4.9, 5.7}, el[8] = {0.25, 1.3, 0.6, 0.4, 0.9, 0.3, 0.7, 1.0};
    for (int k = 0; k < 8; ++k) {
      const Vec3 u(std::cos(el[k]) * std::sin(az[k]), std::cos(el[k]) * std::cos(az[k]), std::sin(el[k]));
      sats.push_back(r0 + Cne * u * 2.2e7);
    }
  }
  fsw::GnssEpoch epoch(const sim::TruthSample& t, double clock_b_m, double clock_d_mps) const {
    fsw::GnssEpoch ep;
    ep.t_s = t.t_s;
    ep.n_obs = static_cast<int>(sats.size());
    const Vec3 r = fsw::ecef_from_llh(t.llh);
    const Vec3 v = fsw::C_n_e(t.llh.x(), t.llh.y()) * t.vel_enu_mps;
    for (int k = 0; k < ep.n_obs; ++k) {
      auto& o = ep.obs[k];
      o.prn = static_cast<std::uint8_t>(k + 1);
      o.sat_pos_ecef_m = sats[k];
      const fsw::GnssGeometry g = fsw::gnss_geometry(sats[k], Vec3::Zero(), r, v);
      o.pseudorange_m = g.range_m + clock_b_m;
      o.pseudorange_rate_mps = g.range_rate_mps + clock_d_mps;
    }
    return ep;
  }
};

struct FlightResult {
  Eigen::Matrix<double, 9, 1> err;    ///< final nav error (estimate minus truth)
  Eigen::Matrix<double, 9, 1> sigma;  ///< final filter sigma
  fsw::ExecutiveHealth health;
  fsw::EkfHealth ekf_health;
  int diverging_epochs = 0;           ///< epochs after which EkfHealth::diverging was set
  std::uint32_t pr_used_last_10s = 0;
};

/// Changes an epoch's measurements before the filter sees them (noise, clock jumps).
using EpochMutator = std::function<void(fsw::GnssEpoch&, double t_s)>;

/// Flies `truth` with a perfect IMU through the executive from an initial error, with
/// noise-free GNSS from a synthetic sky, and returns the final error and sigma.
template <class Layout>
FlightResult fly(const std::vector<sim::TruthSample>& truth, const Vec3& dp, const Vec3& dv, const Vec3& phi,
                 const EpochMutator& mutate = {}) {
  fsw::ExecutiveConfig cfg;
  cfg.ekf.pos_sigma_m = 20.0;
  cfg.ekf.vel_sigma_mps = 0.5;
  cfg.ekf.att_sigma_rad = Vec3(60, 60, 600) * kArcsecToRad;
  fsw::Executive<Layout> exec;
  const fsw::NavState init = perturb(nav_from_truth(truth.front()), dp, dv, phi);
  EXPECT_EQ(exec.init(cfg, init), fsw::Status::kOk);
  const SyntheticSky sky(truth.front().llh);
  std::vector<fsw::ImuSample> frame;
  fsw::GnssEpoch ep;
  fsw::FrameOutput out;
  FlightResult r;
  std::uint32_t pr_used_at_end_minus_10 = 0;
  for (std::size_t k = 1; k < truth.size(); ++k) {
    frame.push_back(ideal_imu(truth[k]));
    if (frame.size() < 5) continue;
    fsw::FrameInput in;
    in.imu = frame.data();
    in.n_imu = 5;
    const double t = truth[k].t_s;
    if (std::abs(t - std::round(t)) < 1e-6) {
      ep = sky.epoch(truth[k], 150.0 + 0.3 * t, 0.3);
      if (mutate) mutate(ep, t);
      in.gnss = &ep;
    }
    EXPECT_EQ(exec.tick(in, out), fsw::Status::kOk);
    if (out.ekf_ran && exec.ekf().health().diverging) ++r.diverging_epochs;
    if (truth.back().t_s - t > 10.0) pr_used_at_end_minus_10 = exec.health().pr_used;
    frame.clear();
  }
  r.ekf_health = exec.ekf().health();
  r.pr_used_last_10s = exec.health().pr_used - pr_used_at_end_minus_10;
  r.err = nav_difference(out.nav, nav_from_truth(truth.back()));
  r.sigma = exec.ekf().P().diagonal().template head<9>().cwiseSqrt();
  r.health = exec.health();
  return r;
}

}  // namespace

// Constant velocity (the straight leg before the first turn): position, velocity and tilt
// converge; heading is unobservable without acceleration, so its error and its sigma stay.
TEST(Ekf, ConstantVelocityTiltConvergesHeadingDoesNot) {
  const auto truth = truth_window(0.0, 55.0);
  const Vec3 phi0(40 * kArcsecToRad, -30 * kArcsecToRad, 300 * kArcsecToRad);
  const FlightResult r = fly<Layout15>(truth, Vec3(12, -8, 5), Vec3(0.3, -0.2, 0.1), phi0);
  std::printf("constant velocity 55 s: |pos err| %.2f m, |vel err| %.4f m/s, phi %.1f %.1f %.1f arcsec, sigma U %.1f arcsec\n",
              r.err.head<3>().norm(), r.err.segment<3>(3).norm(), r.err(6) * kRadToArcsec, r.err(7) * kRadToArcsec,
              r.err(8) * kRadToArcsec, r.sigma(8) * kRadToArcsec);
  // t = 1 s sets the clock, 2..54 update the states; the epoch at 55 s lands 10 frames (the rate
  // groups' latency) after the window ends.
  EXPECT_EQ(r.health.ekf_updates, 54u);
  EXPECT_EQ(r.health.pr_rejected + r.health.prr_rejected, 0u);
  EXPECT_LT(r.err.head<3>().norm(), 2.0);
  EXPECT_LT(r.err.segment<3>(3).norm(), 0.02);
  EXPECT_LT(std::abs(r.err(6)) * kRadToArcsec, 10.0);
  EXPECT_LT(std::abs(r.err(7)) * kRadToArcsec, 10.0);
  // Tilt sigma bottoms out near the accelerometer-bias equivalent (100 ug ~ 20 arcsec) in level flight.
  EXPECT_LT(r.sigma(6) * kRadToArcsec, 35.0);
  // Heading: unobservable, stays at its initial error and sigma.
  EXPECT_NEAR(r.err(8) * kRadToArcsec, 300.0, 30.0);
  EXPECT_GT(r.sigma(8) * kRadToArcsec, 0.9 * 600.0);
}

// The turn makes heading observable (horizontal acceleration): the same heading error is removed.
TEST(Ekf, TurnMakesHeadingObservable) {
  const auto truth = truth_window(55.0, 110.0);
  const Vec3 phi0(40 * kArcsecToRad, -30 * kArcsecToRad, 300 * kArcsecToRad);
  const FlightResult r = fly<Layout24>(truth, Vec3(12, -8, 5), Vec3(0.3, -0.2, 0.1), phi0);
  std::printf("turn 55 s: heading err %.2f arcsec (sigma %.2f)\n", r.err(8) * kRadToArcsec, r.sigma(8) * kRadToArcsec);
  EXPECT_LT(std::abs(r.err(8)) * kRadToArcsec, 10.0);
  EXPECT_LT(r.sigma(8) * kRadToArcsec, 40.0);
  EXPECT_LT(r.err.head<3>().norm(), 2.0);
}

// Static (zero velocity, on the ground): position, velocity, tilt converge; heading does not.
TEST(Ekf, StaticPositionConvergesHeadingUnobservable) {
  const Vec3 llh(35.0 * fsw::kDegToRad, 127.0 * fsw::kDegToRad, 100.0);
  sim::TableMotion table(llh, fsw::C_b_n_from_euler(0.01, -0.02, 0.5), Vec3(0, 0, 1), 0.0);
  sim::TruthGenerator gen(table, 1000.0);
  std::vector<sim::TruthSample> truth{gen.current()};
  while (gen.current().t_s < 60.0 - 1e-9) truth.push_back(gen.next());
  const FlightResult r = fly<Layout15>(truth, Vec3(15, 10, -5), Vec3(0.2, 0.2, -0.1), Vec3(0, 0, 200 * kArcsecToRad));
  EXPECT_LT(r.err.head<3>().norm(), 2.0);
  EXPECT_LT(r.err.segment<3>(3).norm(), 0.02);
  EXPECT_NEAR(r.err(8) * kRadToArcsec, 200.0, 20.0);
}

// A 1 ms receiver clock jump (300 km in every pseudorange, as receivers do when they steer their
// clock) fails every pseudorange gate. The divergence guard sees the runaway, re-opens the
// navigation and clock covariance and re-initialises the clock; the filter then uses the data again.
TEST(EkfHealth, ClockJumpGatingRunawayIsDetectedAndTheFilterRecovers) {
  const auto truth = truth_window(0.0, 50.0);
  const FlightResult r = fly<Layout15>(truth, Vec3(5, -5, 3), Vec3(0.1, -0.1, 0.05), Vec3::Zero(),
                                       [](fsw::GnssEpoch& ep, double t) {
                                         if (t < 20.0) return;
                                         for (int k = 0; k < ep.n_obs; ++k) ep.obs[k].pseudorange_m += 299792.458;
                                       });
  EXPECT_EQ(r.ekf_health.resets, 1u);
  EXPECT_GE(r.ekf_health.gating_runaway_epochs, 5u);
  EXPECT_EQ(r.pr_used_last_10s % 8, 0u);  // 8 satellites in each of the last epochs ...
  EXPECT_GE(r.pr_used_last_10s, 80u);     // ... all accepted again
  EXPECT_LT(r.err.head<3>().norm(), 3.0);
  EXPECT_LT(r.err.segment<3>(3).norm(), 0.05);
  EXPECT_EQ(r.ekf_health.cov_repairs, 0u);
}

// The windowed NIS test (false-alarm rate 1e-3 per window) is quiet on measurements with the
// noise the filter assumes and flags noise 2.5 times larger in nearly every window.
TEST(EkfHealth, NisWindowFlagsNoiseTheModelDoesNotHaveAndStaysQuietOtherwise) {
  const auto truth = truth_window(0.0, 60.0);
  for (double noise_scale : {1.0, 2.5}) {
    std::mt19937_64 gen(42);
    std::normal_distribution<double> n01(0.0, 1.0);
    const FlightResult r = fly<Layout15>(truth, Vec3(5, -5, 3), Vec3(0.1, -0.1, 0.05), Vec3::Zero(),
                                         [&](fsw::GnssEpoch& ep, double) {
                                           for (int k = 0; k < ep.n_obs; ++k) {
                                             ep.obs[k].pseudorange_m += noise_scale * 8.0 * n01(gen);
                                             ep.obs[k].pseudorange_rate_mps += noise_scale * 0.2 * n01(gen);
                                           }
                                         });
    std::printf("noise x%.1f: windowed NIS %.1f over %d dof (bound %.1f), diverging epochs %d, resets %u\n", noise_scale,
                r.ekf_health.nis_window_sum, r.ekf_health.nis_window_dof, r.ekf_health.nis_window_bound,
                r.diverging_epochs, r.ekf_health.resets);
    EXPECT_EQ(r.ekf_health.nis_window_dof > 100, true);
    if (noise_scale == 1.0) {
      EXPECT_EQ(r.diverging_epochs, 0);
      EXPECT_EQ(r.ekf_health.divergence_windows, 0u);
      EXPECT_LT(r.ekf_health.nis_window_sum, r.ekf_health.nis_window_bound);
    } else {
      EXPECT_GT(r.diverging_epochs, 30);  // of 50 full windows
      EXPECT_TRUE(r.ekf_health.diverging);
    }
    EXPECT_EQ(r.ekf_health.cov_repairs, 0u);
  }
}

// A covariance that is not positive definite (a correlation above 1) is repaired and counted; a
// NaN one is rejected before it reaches the filter.
TEST(EkfHealth, CovarianceRepairAndNonFiniteRejection) {
  fsw::Ekf<Layout24> ekf;
  ASSERT_EQ(ekf.init(fsw::EkfConfig{}), fsw::Status::kOk);
  fsw::Ekf<Layout24>::Mat P = ekf.P();
  const double s0 = std::sqrt(P(0, 0)), s6 = std::sqrt(P(6, 6));
  P(0, 6) = P(6, 0) = 1.5 * s0 * s6;  // correlation 1.5
  ASSERT_EQ(ekf.set_covariance(P), fsw::Status::kOk);
  EXPECT_EQ(ekf.health().cov_repairs, 1u);
  const double corr = ekf.P()(0, 6) / std::sqrt(ekf.P()(0, 0) * ekf.P()(6, 6));
  EXPECT_LT(std::abs(corr), 1.0);
  EXPECT_EQ(ekf.P()(0, 0), P(0, 0));  // variances kept
  Eigen::LLT<Eigen::MatrixXd> llt{Eigen::MatrixXd(ekf.P())};
  EXPECT_EQ(llt.info(), Eigen::Success);

  // A valid P passes untouched.
  const fsw::Ekf<Layout24>::Mat good = ekf.P();
  ASSERT_EQ(ekf.set_covariance(good), fsw::Status::kOk);
  EXPECT_EQ(ekf.health().cov_repairs, 1u);
  EXPECT_EQ(ekf.P(), good);

  // Negative variance: falls back to the initial variance of that state, correlations dropped.
  P = good;
  P(3, 3) = -1.0;
  ASSERT_EQ(ekf.set_covariance(P), fsw::Status::kOk);
  EXPECT_EQ(ekf.health().cov_repairs, 2u);
  EXPECT_DOUBLE_EQ(ekf.P()(3, 3), fsw::EkfConfig{}.vel_sigma_mps * fsw::EkfConfig{}.vel_sigma_mps);

  P = good;
  P(2, 5) = std::nan("");
  EXPECT_EQ(ekf.set_covariance(P), fsw::Status::kBadInput);
  EXPECT_EQ(ekf.health().nonfinite_rejected, 1u);
  EXPECT_TRUE(ekf.P().allFinite());
}
