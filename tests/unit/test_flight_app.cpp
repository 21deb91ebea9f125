// The flight application (fsw/flight_app.hpp) on the simulated sensor stream: in-motion
// initialisation from the single-point GNSS solution and levelling, then the 24-state filter
// through a turn; and the single-point solution itself (fsw/gnss_pvt.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "fsw/flight_app.hpp"
#include "fsw/gnss_pvt.hpp"
#include "sim/almanac.hpp"
#include "sim/gps_model.hpp"
#include "tools/free_inertial.hpp"
#include "tools/montecarlo.hpp"
#include "sim/sensor_stream.hpp"

namespace {

using fsw::kDegToRad;
using fsw::kRadToDeg;
using fsw::Vec3;

sim::TruthSample at(double t_s, const Vec3& llh, const Vec3& vel_enu) {
  sim::TruthSample s;
  s.t_s = t_s;
  s.llh = llh;
  s.vel_enu_mps = vel_enu;
  s.C_b_n = fsw::Mat3::Identity();
  return s;
}

TEST(GnssPvt, ErrorFreeEpochGivesTheReceiverStateAndClock) {
  const sim::AlmanacParseResult alm = sim::parse_yuma_file(sim::default_almanac_path());
  ASSERT_TRUE(alm.ok()) << alm.error;
  sim::GpsConfig c;
  c.pseudorange_gm_sigma_m = c.pseudorange_rate_gm_sigma_mps = 0.0;
  c.pseudorange_white_sigma_m = c.pseudorange_rate_white_sigma_mps = 0.0;
  c.clock_h0_s = c.clock_h_minus2_per_s = 0.0;  // clock bias/drift drawn once (30 m, 1 m/s sigma), constant
  sim::GpsModel gps(c, *alm.almanac, sim::EffectSet{}, 5);
  const Vec3 llh(35.0 * kDegToRad, 127.0 * kDegToRad, 5000.0), v(180.0, 170.0, -3.0);
  fsw::GnssEpoch e;
  gps.measure(at(100.0, llh, v), e);
  ASSERT_GE(e.n_obs, 6);
  fsw::GnssPvt p;
  ASSERT_EQ(fsw::gnss_pvt(e, p), fsw::Status::kOk);
  EXPECT_LT((p.r_ecef_m - fsw::ecef_from_llh(llh)).norm(), 1e-3);
  EXPECT_LT((p.v_ecef_mps - fsw::C_n_e(llh.x(), llh.y()) * v).norm(), 1e-5);
  EXPECT_NEAR(p.clock_bias_m, gps.clock().bias_m, 1e-3);
  EXPECT_NEAR(p.clock_drift_mps, gps.clock().drift_mps, 1e-5);
  EXPECT_GT(p.pdop, 0.5);
  EXPECT_LT(p.pdop, 6.0);
  EXPECT_LT(p.pr_rms_residual_m, 1e-3);

  fsw::GnssEpoch three = e;
  three.n_obs = 3;
  EXPECT_EQ(fsw::gnss_pvt(three, p), fsw::Status::kBadInput);
  fsw::GnssEpoch bad = e;
  for (int k = 0; k < bad.n_obs - 3; ++k) bad.obs[k].pseudorange_m = std::nan("");
  EXPECT_EQ(fsw::gnss_pvt(bad, p), fsw::Status::kBadInput);
}

TEST(FlightApp, InitialisesInMotionAndNavigatesThroughATurn) {
  sim::Scenario sc;
  sc.duration_s = 200.0;  // 60 s straight, the first turn, straight again
  sim::SensorStream stream(sc, 3);
  fsw::FlightAppConfig cfg;
  cfg.exec = tools::executive_config(sc, tools::MonteCarloConfig{});
  static fsw::FlightApp<fsw::Layout24Full> app;
  ASSERT_EQ(app.init(cfg), fsw::Status::kOk);
  fsw::InputEvent ev;
  sim::TruthSample truth;
  fsw::FrameOutput out;
  tools::NavErrors at_init{}, last{};
  bool have_init_err = false;
  double worst_heading_after_turn_deg = 0.0;
  while (stream.next(ev, &truth)) {
    // The one dispatch (FlightApp::on_event) every harness uses.
    const fsw::Status st = app.on_event(ev, out);
    switch (ev.kind) {
      case fsw::InputEvent::Kind::kAlmanac:
      case fsw::InputEvent::Kind::kGnssRaw:
      case fsw::InputEvent::Kind::kGnssPvt: break;
      case fsw::InputEvent::Kind::kImu:
        ASSERT_NE(st, fsw::Status::kBadInput);
        if (out.nav_valid) {
          last = tools::nav_errors(out.nav, truth);
          if (!have_init_err) {
            at_init = last;
            have_init_err = true;
          }
          if (truth.t_s > 130.0)
            worst_heading_after_turn_deg = std::max(worst_heading_after_turn_deg, std::abs(last.att_phi_enu_rad.z()) * kRadToDeg);
        }
        break;
    }
  }
  const fsw::FlightAppHealth& h = app.health();
  ASSERT_TRUE(h.initialised);
  EXPECT_NEAR(h.init_t_s, 1.0, 1e-9);  // the first epoch after 200 levelling samples
  EXPECT_EQ(h.almanac_received, 31u);
  EXPECT_EQ(h.almanac_rejected, 0u);
  EXPECT_EQ(h.conversion.invalid + h.conversion.no_almanac + h.conversion.duplicate_prn, 0u);
  std::printf("init at %.1f s: %d satellites, PDOP %.2f; errors at init: pos %.1f m, vel %.2f m/s, att %.3f %.3f %.3f deg\n",
              h.init_t_s, h.init_fix.n_used, h.init_fix.pdop, at_init.pos_enu_m.norm(), at_init.vel_enu_mps.norm(),
              at_init.att_phi_enu_rad.x() * kRadToDeg, at_init.att_phi_enu_rad.y() * kRadToDeg,
              at_init.att_phi_enu_rad.z() * kRadToDeg);
  std::printf("at %.0f s: pos %.2f m, vel %.3f m/s, att %.4f %.4f %.4f deg; worst heading after the turn %.4f deg\n",
              sc.duration_s, last.pos_enu_m.norm(), last.vel_enu_mps.norm(), last.att_phi_enu_rad.x() * kRadToDeg,
              last.att_phi_enu_rad.y() * kRadToDeg, last.att_phi_enu_rad.z() * kRadToDeg, worst_heading_after_turn_deg);
  // The initialisation is as good as its sigmas say (30 m, 1 m/s, 0.2/0.2/1 deg) ...
  EXPECT_LT(at_init.pos_enu_m.norm(), 60.0);
  EXPECT_LT(at_init.vel_enu_mps.norm(), 2.0);
  EXPECT_LT(std::abs(at_init.att_phi_enu_rad.x()) * kRadToDeg, 0.4);
  EXPECT_LT(std::abs(at_init.att_phi_enu_rad.y()) * kRadToDeg, 0.4);
  EXPECT_LT(std::abs(at_init.att_phi_enu_rad.z()) * kRadToDeg, 2.0);
  // ... and the filter takes it from there: the turn makes heading observable.
  EXPECT_LT(last.pos_enu_m.norm(), 15.0);
  EXPECT_LT(last.vel_enu_mps.norm(), 0.2);
  EXPECT_LT(std::abs(last.att_phi_enu_rad.x()) * kRadToDeg, 0.02);
  EXPECT_LT(std::abs(last.att_phi_enu_rad.y()) * kRadToDeg, 0.02);
  EXPECT_LT(worst_heading_after_turn_deg, 0.05);
  const fsw::ExecutiveHealth& eh = app.executive().health();
  EXPECT_EQ(eh.fsw_errors, 0u);
  EXPECT_GE(eh.ekf_updates, 195u);
  EXPECT_EQ(eh.ekf.cov_repairs, 0u);
  EXPECT_EQ(eh.ekf.resets, 0u);
}

}  // namespace

namespace {

// GPS absent for 30 s (epochs with zero satellites, then with one): the flight software keeps
// navigating on the INS, counts the empty epochs, and takes the GPS back when it returns.
TEST(FlightApp, CoastsThroughAGpsOutageAndRecovers) {
  sim::Scenario sc;
  sc.duration_s = 160.0;
  sim::SensorStream stream(sc, 5);
  fsw::FlightAppConfig cfg;
  cfg.exec = tools::executive_config(sc, tools::MonteCarloConfig{});
  static fsw::FlightApp<fsw::Layout15Full> app;
  ASSERT_EQ(app.init(cfg), fsw::Status::kOk);
  fsw::InputEvent ev;
  sim::TruthSample truth;
  fsw::FrameOutput out;
  double worst_pos_in_outage = 0.0, pos_before = 0.0;
  std::uint32_t updates_before = 0, updates_after_outage = 0;
  tools::NavErrors last{};
  while (stream.next(ev, &truth)) {
    if (ev.kind == fsw::InputEvent::Kind::kGnssRaw) {
      const double t = ev.gnss.t_s;
      if (t > 100.0 && t <= 120.0) ev.gnss.n_meas = 0;  // no satellite
      if (t > 120.0 && t <= 130.0) ev.gnss.n_meas = 1;  // one satellite
    }
    const fsw::Status st = app.on_event(ev, out);
    if (ev.kind != fsw::InputEvent::Kind::kImu) continue;
    ASSERT_NE(st, fsw::Status::kBadInput);
    if (!out.nav_valid) continue;
    last = tools::nav_errors(out.nav, truth);
    if (std::abs(truth.t_s - 100.5) < 1e-9) {  // after the last full epoch (t = 100) was used
      pos_before = last.pos_enu_m.norm();
      updates_before = app.executive().health().pr_used;
    }
    if (truth.t_s > 100.0 && truth.t_s <= 130.0) worst_pos_in_outage = std::max(worst_pos_in_outage, last.pos_enu_m.norm());
    if (std::abs(truth.t_s - 130.5) < 1e-9) updates_after_outage = app.executive().health().pr_used;
  }
  const fsw::ExecutiveHealth& h = app.executive().health();
  std::printf("GPS outage 100..130 s: position error %.2f m before, worst %.2f m during, %.2f m at the end\n", pos_before,
              worst_pos_in_outage, last.pos_enu_m.norm());
  ASSERT_TRUE(app.health().initialised);
  EXPECT_EQ(h.fsw_errors, 0u);
  // 20 empty epochs used nothing; the 10 single-satellite ones updated with that one satellite.
  EXPECT_LE(updates_after_outage - updates_before, 10u);
  EXPECT_GE(h.ekf_runs, 155u);  // the 1 Hz group kept running (propagation) through the outage
  EXPECT_LT(worst_pos_in_outage, 40.0);  // 30 s of INS coasting with the calibrated IMU
  EXPECT_LT(last.pos_enu_m.norm(), 15.0);  // and the GPS taken back afterwards
  EXPECT_GT(h.pr_used - updates_after_outage, 250u);
}

}  // namespace
