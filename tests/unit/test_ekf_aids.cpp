// The EKF's aid units on hand-made cases: the raw-GNSS aid's observation (the antenna at the
// epoch, the usability test, the predicted range with and without the modelled delays), the
// position/velocity aid's usability test, and the core's fuse step both aids share (gate,
// innovation record, counts, NIS sum), through Ekf::update / update_pvt.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "fsw/ekf.hpp"
#include "fsw/ekf/aid_gnss_pvt.hpp"
#include "fsw/ekf/aid_gnss_raw.hpp"
#include "fsw/gnss_delays.hpp"

namespace {

using fsw::Mat3;
using fsw::Vec3;

fsw::NavState level_nav() {
  fsw::NavState nav;
  nav.t_s = 100.0;
  nav.llh = Vec3(35.0 * fsw::kDegToRad, 127.0 * fsw::kDegToRad, 500.0);
  nav.vel_enu_mps = Vec3(10.0, 20.0, -1.0);
  nav.q_b_n = fsw::Quat(fsw::C_b_n_from_euler(0.1, -0.05, 0.7));
  return nav;
}

/// A satellite 22,000 km from the receiver along ENU azimuth az and elevation el.
fsw::GnssObservation satellite(const fsw::NavState& nav, double az, double el) {
  const Vec3 u_n(std::cos(el) * std::sin(az), std::cos(el) * std::cos(az), std::sin(el));
  fsw::GnssObservation o;
  o.prn = 7;
  o.sat_pos_ecef_m = fsw::ecef_from_llh(nav.llh) + fsw::C_n_e(nav.llh.x(), nav.llh.y()) * u_n * 2.2e7;
  o.sat_vel_ecef_mps = Vec3(1000.0, -500.0, 2000.0);
  o.pseudorange_m = 2.2e7;
  o.pseudorange_rate_mps = 100.0;
  return o;
}

}  // namespace

// At the solution's own time and without a time offset, the antenna is the INS position moved by
// C_b_n l (ECEF), its velocity the INS velocity plus C_b_n (w x l), w the body rate relative to
// the Earth; its height the INS height plus the lever arm's Up component.
TEST(GnssRawAid, AntennaIsTheInsMovedByTheLeverArm) {
  const fsw::NavState nav = level_nav();
  const Vec3 lever_b(1.0, -0.5, -2.0), w_ib_b(0.01, -0.02, 0.3);
  const fsw::GnssRawAntenna a =
      fsw::gnss_raw_antenna(nav.t_s, nav, w_ib_b, lever_b, 0.0, Vec3(0.0, 0.0, 9.8), false);
  const Mat3 C = nav.C_b_n();
  const Mat3 Cne = fsw::C_n_e(nav.llh.x(), nav.llh.y());
  const Vec3 l_n = C * lever_b;
  const Vec3 w_rel_b = w_ib_b - C.transpose() * fsw::omega_ie_n(nav.llh.x());
  EXPECT_LT((a.r_ecef_m - (fsw::ecef_from_llh(nav.llh) + Cne * l_n)).norm(), 1e-6);
  EXPECT_LT((a.v_ecef_mps - Cne * (nav.vel_enu_mps + C * w_rel_b.cross(lever_b))).norm(), 1e-9);
  EXPECT_NEAR(a.h_m, nav.llh.z() + l_n.z(), 1e-12);
  EXPECT_LT((a.lever_enu_m - l_n).norm(), 1e-12);
  // Without a lever arm the antenna is the INS itself.
  const fsw::GnssRawAntenna a0 = fsw::gnss_raw_antenna(nav.t_s, nav, w_ib_b, Vec3::Zero(), 0.0, Vec3::Zero(), false);
  EXPECT_LT((a0.r_ecef_m - fsw::ecef_from_llh(nav.llh)).norm(), 1e-9);
  EXPECT_LT((a0.v_ecef_mps - Cne * nav.vel_enu_mps).norm(), 1e-12);
}

// An epoch 0.2 s after the solution, with a time offset of 0.05 s: the antenna moves on by the
// velocity over 0.25 s; only with offset_moves_velocity does the acceleration times the offset
// enter its velocity (the layouts with time-offset states).
TEST(GnssRawAid, AntennaIsReadAtTheEpochPlusTheTimeOffset) {
  const fsw::NavState nav = level_nav();
  const Vec3 f_enu(0.5, -0.2, 9.9);
  const fsw::GnssRawAntenna a = fsw::gnss_raw_antenna(nav.t_s + 0.2, nav, Vec3::Zero(), Vec3::Zero(), 0.05, f_enu, false);
  const fsw::GnssRawAntenna b = fsw::gnss_raw_antenna(nav.t_s + 0.2, nav, Vec3::Zero(), Vec3::Zero(), 0.05, f_enu, true);
  const Mat3 Cne = fsw::C_n_e(nav.llh.x(), nav.llh.y());
  // w_rel = -w_ie_b moves a zero lever arm by nothing.
  EXPECT_LT((a.r_ecef_m - (fsw::ecef_from_llh(nav.llh) + Cne * nav.vel_enu_mps * 0.25)).norm(), 1e-6);
  EXPECT_LT((a.r_ecef_m - b.r_ecef_m).norm(), 1e-12);
  const Vec3 accel = f_enu - Vec3(0.0, 0.0, fsw::normal_gravity_mps2(nav.llh.x(), nav.llh.z()));
  EXPECT_LT((a.accel_enu_mps2 - accel).norm(), 1e-12);
  EXPECT_LT((b.v_ecef_mps - a.v_ecef_mps - Cne * accel * 0.05).norm(), 1e-9);
}

// Usable: finite data and a satellite radius within 1e7..1e8 m.
TEST(GnssRawAid, ObservationUsability) {
  const fsw::NavState nav = level_nav();
  fsw::GnssObservation o = satellite(nav, 0.5, 0.8);
  EXPECT_TRUE(fsw::gnss_observation_usable(o));
  fsw::GnssObservation near = o;
  near.sat_pos_ecef_m = Vec3(5.0e6, 0.0, 0.0);
  EXPECT_FALSE(fsw::gnss_observation_usable(near));
  fsw::GnssObservation far = o;
  far.sat_pos_ecef_m = Vec3(2.0e8, 0.0, 0.0);
  EXPECT_FALSE(fsw::gnss_observation_usable(far));
  fsw::GnssObservation nan_pr = o;
  nan_pr.pseudorange_rate_mps = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(fsw::gnss_observation_usable(nan_pr));
  fsw::GnssObservation inf_vel = o;
  inf_vel.sat_vel_ecef_mps.x() = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(fsw::gnss_observation_usable(inf_vel));
}

// The prediction is gnss_geometry() from the antenna; with the delays asked for, the modelled
// tropospheric and ionospheric delays (Saastamoinen, Klobuchar at the INS latitude / longitude,
// the antenna height and the predicted line of sight) are reported and join the range scaled.
TEST(GnssRawAid, PredictionAddsTheScaledModelDelays) {
  const fsw::NavState nav = level_nav();
  const fsw::GnssRawAntenna a = fsw::gnss_raw_antenna(nav.t_s, nav, Vec3::Zero(), Vec3::Zero(), 0.0, Vec3::Zero(), false);
  const double az = 0.5, el = 0.4;
  const fsw::GnssObservation o = satellite(nav, az, el);
  const fsw::GnssGeometry g = fsw::gnss_geometry(o.sat_pos_ecef_m, o.sat_vel_ecef_mps, a.r_ecef_m, a.v_ecef_mps);
  const fsw::GnssRawPrediction plain = fsw::gnss_raw_predict(o, a, 3600.0, false, 1.0, 1.0);
  EXPECT_EQ(plain.geo.range_m, g.range_m);
  EXPECT_EQ(plain.geo.range_rate_mps, g.range_rate_mps);
  EXPECT_EQ(plain.tropo_delay_m, 0.0);
  EXPECT_EQ(plain.iono_delay_m, 0.0);
  // The line of sight: the satellite's direction, turned by light time and Sagnac (< 1e-5).
  EXPECT_LT((fsw::gnss_los_enu(plain, a) -
             Vec3(std::cos(el) * std::sin(az), std::cos(el) * std::cos(az), std::sin(el))).norm(), 1e-5);
  const fsw::GnssRawPrediction d = fsw::gnss_raw_predict(o, a, 3600.0, true, 0.5, 2.0);
  const double el_hat = std::asin(fsw::gnss_los_enu(plain, a).z());
  const double az_hat = std::atan2(fsw::gnss_los_enu(plain, a).x(), fsw::gnss_los_enu(plain, a).y());
  EXPECT_NEAR(d.tropo_delay_m, fsw::saastamoinen_delay_m(nav.llh.x(), a.h_m, el_hat), 1e-9);
  EXPECT_NEAR(d.iono_delay_m,
              fsw::klobuchar_delay_m(fsw::kKlobucharDefault, 3600.0, nav.llh.x(), nav.llh.y(), az_hat, el_hat), 1e-9);
  EXPECT_GT(d.tropo_delay_m, 2.0);
  EXPECT_GT(d.iono_delay_m, 0.5);
  EXPECT_NEAR(d.geo.range_m, g.range_m + 0.5 * d.tropo_delay_m + 2.0 * d.iono_delay_m, 1e-6);
  EXPECT_EQ(d.geo.range_rate_mps, g.range_rate_mps);  // the delays' rates are left out
}

// The position part needs a finite position within +-90 deg latitude and positive sigmas; the
// velocity part a velocity (has_velocity), finite, with positive sigmas.
TEST(GnssPvtAid, Usability) {
  fsw::GnssPvtMeasurement m;
  m.t_s = 1.0;
  m.llh = Vec3(0.5, 2.0, 100.0);
  m.pos_sigma_enu_m = Vec3::Constant(0.1);
  m.vel_sigma_enu_mps = Vec3::Constant(0.05);
  EXPECT_TRUE(fsw::pvt_usable(m).pos);
  EXPECT_FALSE(fsw::pvt_usable(m).vel);  // no velocity
  m.has_velocity = true;
  EXPECT_TRUE(fsw::pvt_usable(m).vel);
  fsw::GnssPvtMeasurement pole = m;
  pole.llh.x() = 1.6;
  EXPECT_FALSE(fsw::pvt_usable(pole).pos);
  EXPECT_TRUE(fsw::pvt_usable(pole).vel);
  fsw::GnssPvtMeasurement zero_sigma = m;
  zero_sigma.pos_sigma_enu_m.y() = 0.0;
  zero_sigma.vel_sigma_enu_mps.z() = -1.0;
  EXPECT_FALSE(fsw::pvt_usable(zero_sigma).pos);
  EXPECT_FALSE(fsw::pvt_usable(zero_sigma).vel);
  fsw::GnssPvtMeasurement nan_vel = m;
  nan_vel.vel_enu_mps.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(fsw::pvt_usable(nan_vel).pos);
  EXPECT_FALSE(fsw::pvt_usable(nan_vel).vel);
}

// The core's fuse step as both aids use it, on a single satellite and on one solution: the
// record's innovation is predicted minus measured, its variance H P H^T + R; a scalar outside the
// gate is counted rejected and leaves the state alone; the NIS sum and its degrees of freedom
// hold exactly the accepted scalars.
TEST(EkfAids, FuseGatesCountsAndSumsTheNis) {
  fsw::EkfConfig cfg;
  cfg.use_pseudorange_rate = false;
  fsw::Ekf<fsw::Layout15> ekf;
  ASSERT_EQ(ekf.init(cfg), fsw::Status::kOk);
  fsw::NavState nav = level_nav();
  nav.t_s = 0.0;
  fsw::GnssEpoch ep;
  ep.n_obs = 1;
  ep.obs[0] = satellite(nav, 1.0, 0.9);
  const fsw::GnssRawAntenna a = fsw::gnss_raw_antenna(0.0, nav, Vec3::Zero(), Vec3::Zero(), 0.0, Vec3::Zero(), false);
  const fsw::GnssRawPrediction p = fsw::gnss_raw_predict(ep.obs[0], a, 0.0, false, 0.0, 0.0);
  ep.obs[0].pseudorange_m = p.geo.range_m + 50.0;  // the clock: 50 m
  fsw::EkfUpdateReport rep;
  ASSERT_EQ(ekf.update(ep, nav, Vec3::Zero(), rep), fsw::Status::kOk);
  ASSERT_TRUE(rep.clock_initialised);
  EXPECT_EQ(rep.nis_dof, 0);
  EXPECT_NEAR(ekf.clock_bias_m(), 50.0, 1e-6);
  // 3 m short of the prediction: inside the gate (sigma 8 m, position 10 m, clock 30 m).
  ep.obs[0].pseudorange_m = p.geo.range_m + 47.0;
  const double S = ekf.P()(0, 0) * 1.0 + ekf.P()(15, 15) + cfg.pseudorange_sigma_m * cfg.pseudorange_sigma_m;
  ASSERT_EQ(ekf.update(ep, nav, Vec3::Zero(), rep), fsw::Status::kOk);
  EXPECT_EQ(rep.obs[0].prn, 7);
  EXPECT_EQ(rep.obs[0].pr_outcome, fsw::InnovationOutcome::kUsed);
  EXPECT_EQ(rep.obs[0].prr_outcome, fsw::InnovationOutcome::kNotProcessed);
  EXPECT_NEAR(rep.obs[0].pr_innovation_m, 3.0, 1e-6);
  EXPECT_NEAR(rep.obs[0].pr_variance_m2, S, 1e-9 * S);
  EXPECT_EQ(rep.pr_used, 1);
  EXPECT_EQ(rep.pr_rejected, 0);
  EXPECT_EQ(rep.nis_dof, 1);
  EXPECT_NEAR(rep.nis_sum, 9.0 / S, 1e-12);
  // 500 m off: outside the gate, counted rejected; the state stays where it was.
  fsw::Ekf<fsw::Layout15>::Vec x;
  ASSERT_EQ(ekf.take_correction(x), fsw::Status::kOk);
  const Eigen::Matrix<double, fsw::Layout15::kSize, fsw::Layout15::kSize> P_before = ekf.P();
  ep.obs[0].pseudorange_m = p.geo.range_m + 550.0;
  ASSERT_EQ(ekf.update(ep, nav, Vec3::Zero(), rep), fsw::Status::kOk);
  EXPECT_EQ(rep.obs[0].pr_outcome, fsw::InnovationOutcome::kGated);
  EXPECT_LT(rep.obs[0].pr_innovation_m, -400.0);
  EXPECT_GT(rep.obs[0].pr_innovation_m * rep.obs[0].pr_innovation_m, cfg.gate_chi2 * rep.obs[0].pr_variance_m2);
  EXPECT_EQ(rep.pr_used, 0);
  EXPECT_EQ(rep.pr_rejected, 1);
  EXPECT_EQ(rep.nis_dof, 0);
  EXPECT_EQ(rep.nis_sum, 0.0);
  EXPECT_EQ(ekf.x().norm(), 0.0);
  EXPECT_EQ((ekf.P() - P_before).norm(), 0.0);

  // The position/velocity aid: a solution 2 m East of the INS (no lever arm) is used; its North
  // axis, 300 m off, is gated; the velocity part is absent (not processed).
  fsw::GnssPvtMeasurement m;
  m.t_s = nav.t_s;
  m.llh = nav.llh + fsw::llh_delta_from_enu(nav.llh, Vec3(2.0, 300.0, 0.0));
  m.pos_sigma_enu_m = Vec3::Constant(1.0);
  m.quality = 1;
  const double p_e = ekf.P()(0, 0);
  ASSERT_EQ(ekf.update_pvt(m, nav, Vec3::Zero(), rep), fsw::Status::kOk);
  EXPECT_TRUE(rep.pvt);
  EXPECT_EQ(rep.pvt_obs[0].outcome, fsw::InnovationOutcome::kUsed);
  EXPECT_NEAR(rep.pvt_obs[0].innovation, -2.0, 1e-6);
  EXPECT_NEAR(rep.pvt_obs[0].variance, p_e + 1.0, 1e-9 * p_e);
  EXPECT_EQ(rep.pvt_obs[1].outcome, fsw::InnovationOutcome::kGated);
  EXPECT_EQ(rep.pvt_obs[2].outcome, fsw::InnovationOutcome::kUsed);
  for (int i = 3; i < 6; ++i) EXPECT_EQ(rep.pvt_obs[static_cast<std::size_t>(i)].outcome, fsw::InnovationOutcome::kNotProcessed);
  EXPECT_EQ(rep.pos_used, 2);
  EXPECT_EQ(rep.pos_rejected, 1);
  EXPECT_EQ(rep.vel_used + rep.vel_rejected, 0);
  EXPECT_EQ(rep.nis_dof, 2);
  const double nis = rep.pvt_obs[0].innovation * rep.pvt_obs[0].innovation / rep.pvt_obs[0].variance +
                     rep.pvt_obs[2].innovation * rep.pvt_obs[2].innovation / rep.pvt_obs[2].variance;
  EXPECT_NEAR(rep.nis_sum, nis, 1e-12 * (1.0 + nis));
}
