// The flight application on GNSS position/velocity solutions (loosely coupled update): a land
// vehicle initialises in motion at a few m/s from a solution, navigates at the solution's noise
// level at 1 Hz and at 4 Hz, gets its heading in a turn, coasts through a 15 s outage, and the
// diagnosis layout estimates an antenna lever arm from the turns.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <deque>
#include <vector>

#include "fsw/flight_app.hpp"
#include "sim/imu_model.hpp"
#include "sim/rng.hpp"
#include "sim/trajectory.hpp"
#include "land_motion_test_util.hpp"
#include "tools/free_inertial.hpp"

namespace {

using fsw::kDegToRad;
using fsw::kRadToDeg;
using fsw::Vec3;

/// A car: tests/unit/land_motion_test_util.hpp with the IMU mounted at a yaw angle only.
using CarMotion = land_motion::LandMotion;

/// The drive: 4 m/s at 30 deg, straight for 12 s, a -90 deg turn (12..22 s) at 4 m/s, speeding up
/// to 10 m/s (25..30 s), turns of +120 and -60 deg, slowing to 6 m/s, a +90 deg turn inside the
/// outage window 105..120 s.
CarMotion drive(double mount_yaw_rad) {
  return CarMotion(Vec3(35.0 * kDegToRad, 127.0 * kDegToRad, 80.0), 4.0, 30.0 * kDegToRad, Vec3(0.0, 0.0, mount_yaw_rad),
                   {{25.0, 5.0, 6.0}, {70.0, 6.0, -4.0}},
                   {{12.0, 10.0, -90.0 * kDegToRad},
                    {50.0, 10.0, 120.0 * kDegToRad},
                    {80.0, 8.0, -60.0 * kDegToRad},
                    {108.0, 8.0, 90.0 * kDegToRad}});
}

/// A tactical-grade MEMS IMU.
sim::ImuErrors imu_errors() {
  sim::ImuErrors e;
  e.accel_bias_mps2 = Vec3(300.0, -200.0, 250.0) * fsw::kMicroG_mps2;
  e.gyro_bias_radps = Vec3(3.0, -4.0, 5.0) * fsw::kDegPerHourToRadps;
  e.gyro_arw_rad_per_rts = 0.05 * kDegToRad / 60.0;  // 0.05 deg/sqrt(h)
  e.accel_vrw_mps_per_rts = 0.03 / 60.0;             // 0.03 m/s/sqrt(h)
  return e;
}

fsw::FlightAppConfig app_config(int frames_per_ekf, double heading_offset_rad) {
  fsw::FlightAppConfig cfg;
  cfg.min_init_speed_mps = 3.0;  // a car
  cfg.init_pos_sigma_m = 1.0;
  cfg.init_vel_sigma_mps = 0.2;
  cfg.init_heading_offset_rad = heading_offset_rad;
  cfg.exec.frames_per_ekf = frames_per_ekf;
  fsw::EkfConfig& e = cfg.exec.ekf;
  e.accel_bias_sigma_mps2 = 500.0 * fsw::kMicroG_mps2;
  e.gyro_bias_sigma_radps = 10.0 * fsw::kDegPerHourToRadps;
  e.accel_misalign_sigma_rad = e.gyro_misalign_sigma_rad = 1e-8;  // the simulated IMU has none
  e.accel_scale_sigma = e.gyro_scale_sigma = 1e-9;
  e.vrw_mps_per_rts = 0.03 / 60.0;
  e.arw_rad_per_rts = 0.05 * kDegToRad / 60.0;
  return cfg;
}

struct DriveResult {
  fsw::FlightAppHealth app;
  fsw::ExecutiveHealth exec;
  double init_heading_err_deg = 0.0;
  double heading_err_before_turn_deg = 0.0;    ///< at 11 s (straight at constant speed so far)
  double heading_err_after_turn_deg = 0.0;     ///< at 24 s (after the first turn, before the speed-up)
  double worst_heading_after_turns_deg = 0.0;  ///< from 65 s on, outside the outage
  double pos_rms_m = 0.0, vel_rms_mps = 0.0;   ///< from 20 s on, outside the outage (+10 s)
  double pos_max_m = 0.0, vel_max_mps = 0.0;
  double outage_max_horiz_m = 0.0;              ///< coasting 105..120 s
  Vec3 lever_arm_m = Vec3::Zero();
  Vec3 lever_arm_sigma_m = Vec3::Zero();
};

/// Flies the drive through FlightApp<Layout>: IMU at 1 kHz, solutions of the antenna (truth +
/// noise) at pvt_rate_hz, each delivered 30 ms after its time, none in (outage_t0, outage_t1].
template <class Layout>
DriveResult fly_drive(double pvt_rate_hz, const fsw::FlightAppConfig& cfg, double mount_yaw_rad, const Vec3& lever_b,
                      double duration_s, double outage_t0 = 1e9, double outage_t1 = 1e9) {
  static fsw::FlightApp<Layout> app;
  EXPECT_EQ(app.init(cfg), fsw::Status::kOk);
  const CarMotion motion = drive(mount_yaw_rad);
  sim::TruthGenerator gen(motion, 1000.0);
  sim::ImuModel imu(imu_errors(), 11);
  sim::Rng rng(7, 3);
  const Vec3 pos_sigma(0.02, 0.02, 0.04), vel_sigma(0.02, 0.02, 0.03);
  std::deque<fsw::GnssPvtMeasurement> in_flight;
  const double T = 1.0 / pvt_rate_hz;
  long next_k = 1;
  DriveResult r;
  double sum_p2 = 0.0, sum_v2 = 0.0;
  long n_err = 0;
  bool have_init = false;
  fsw::FrameOutput out;
  while (gen.current().t_s < duration_s - 1e-9) {
    const sim::TruthSample& t = gen.next();
    if (std::abs(t.t_s - next_k * T) < 1e-7) {
      ++next_k;
      if (!(t.t_s > outage_t0 && t.t_s <= outage_t1)) {
        fsw::GnssPvtMeasurement m;
        m.t_s = t.t_s;
        sim::antenna_truth(t, lever_b, m.llh, m.vel_enu_mps);
        Vec3 dp, dv;
        for (int i = 0; i < 3; ++i) dp(i) = rng.normal() * pos_sigma(i);
        for (int i = 0; i < 3; ++i) dv(i) = rng.normal() * vel_sigma(i);
        m.llh += fsw::llh_delta_from_enu(m.llh, dp);
        m.vel_enu_mps += dv;
        m.pos_sigma_enu_m = pos_sigma;
        m.vel_sigma_enu_mps = vel_sigma;
        m.has_velocity = true;
        m.quality = 1;
        m.n_sat = 12;
        in_flight.push_back(m);
      }
    }
    while (!in_flight.empty() && t.t_s >= in_flight.front().t_s + 0.03 - 1e-9) {
      EXPECT_EQ(app.on_gnss_pvt(in_flight.front()), fsw::Status::kOk);
      in_flight.pop_front();
    }
    EXPECT_NE(app.on_imu(imu.measure(t), out), fsw::Status::kBadInput);
    if (!out.nav_valid) continue;
    const tools::NavErrors e = tools::nav_errors(out.nav, t);
    const double head_deg = std::abs(e.att_phi_enu_rad.z()) * kRadToDeg;
    if (!have_init) {
      r.init_heading_err_deg = head_deg;
      have_init = true;
    }
    // (Frames end 4 ms after whole milliseconds of 5: the initialising solution arrived 30 ms late.)
    if (t.t_s >= 11.0 && t.t_s < 11.005) r.heading_err_before_turn_deg = head_deg;
    if (t.t_s >= 24.0 && t.t_s < 24.005) r.heading_err_after_turn_deg = head_deg;
    const bool in_outage = t.t_s > outage_t0 && t.t_s <= outage_t1 + 10.0;
    if (t.t_s > outage_t0 && t.t_s <= outage_t1)
      r.outage_max_horiz_m = std::max(r.outage_max_horiz_m, e.pos_enu_m.head<2>().norm());
    if (t.t_s >= 65.0 && !in_outage) r.worst_heading_after_turns_deg = std::max(r.worst_heading_after_turns_deg, head_deg);
    if (t.t_s >= 20.0 && !in_outage) {
      sum_p2 += e.pos_enu_m.squaredNorm();
      sum_v2 += e.vel_enu_mps.squaredNorm();
      ++n_err;
      r.pos_max_m = std::max(r.pos_max_m, e.pos_enu_m.norm());
      r.vel_max_mps = std::max(r.vel_max_mps, e.vel_enu_mps.norm());
    }
  }
  r.pos_rms_m = std::sqrt(sum_p2 / static_cast<double>(std::max(n_err, 1L)));
  r.vel_rms_mps = std::sqrt(sum_v2 / static_cast<double>(std::max(n_err, 1L)));
  r.app = app.health();
  r.exec = app.executive().health();
  r.lever_arm_m = app.executive().ekf().lever_arm_b_m();
  if constexpr (Layout::has(fsw::Block::kLeverArm))
    r.lever_arm_sigma_m =
        app.executive().ekf().P().diagonal().template segment<3>(Layout::offset(fsw::Block::kLeverArm)).cwiseSqrt();
  return r;
}

void print(const char* what, const DriveResult& r) {
  std::printf("%s: init at %.2f s, heading error %.3f deg at init, %.3f deg at 11 s, %.4f deg at 24 s, worst %.4f deg "
              "from 65 s\n"
              "  pos RMS %.4f m (max %.4f), vel RMS %.4f m/s (max %.4f); outage max horizontal %.3f m\n"
              "  EKF updates %u, without GNSS %u, pos used/rejected %u/%u, vel used/rejected %u/%u, pvt replaced %u stale %u\n",
              what, r.app.init_t_s, r.init_heading_err_deg, r.heading_err_before_turn_deg, r.heading_err_after_turn_deg,
              r.worst_heading_after_turns_deg,
              r.pos_rms_m, r.pos_max_m, r.vel_rms_mps, r.vel_max_mps, r.outage_max_horiz_m, r.exec.ekf_updates,
              r.exec.ekf_without_gnss, r.exec.pos_used, r.exec.pos_rejected, r.exec.vel_used, r.exec.vel_rejected,
              r.exec.pvt_replaced, r.exec.pvt_stale);
}

void expect_clean(const DriveResult& r) {
  EXPECT_TRUE(r.app.initialised);
  EXPECT_EQ(r.app.pvt_rejected, 0u);
  EXPECT_EQ(r.exec.fsw_errors, 0u);
  EXPECT_EQ(r.exec.ekf.cov_repairs, 0u);
  EXPECT_EQ(r.exec.ekf.resets, 0u);
  EXPECT_EQ(r.exec.pvt_invalid + r.exec.pvt_unused, 0u);
}

}  // namespace

// 1 Hz solutions; the IMU is mounted 20 deg right of the direction of travel and the configured
// offset is 20.5 deg, so the initial heading is 0.5 deg off (plus the track's noise).
TEST(FlightAppPvt, CarInitialisesAtLowSpeedAndNavigatesAtTheSolutionNoise) {
  const DriveResult r = fly_drive<fsw::Layout15Full>(1.0, app_config(200, 20.5 * kDegToRad), 20.0 * kDegToRad,
                                                     Vec3::Zero(), 130.0, 105.0, 120.0);
  print("car, 1 Hz solutions", r);
  expect_clean(r);
  EXPECT_NEAR(r.app.init_t_s, 1.0, 1e-9);  // the first solution: 4 m/s >= 3 m/s, levelling done
  EXPECT_EQ(r.app.pvt_before_init, 1u);
  EXPECT_EQ(r.app.pvt_received, 114u);     // 1..130 s without 106..120, the last one still in flight
  EXPECT_NEAR(r.init_heading_err_deg, 0.5, 0.3);
  EXPECT_GT(r.heading_err_before_turn_deg, 0.3);  // straight at constant speed: unobservable ...
  EXPECT_LT(r.heading_err_after_turn_deg, 0.1);   // ... the first turn removes it
  EXPECT_LT(r.worst_heading_after_turns_deg, 0.1);
  // After the outage the 1 Hz EKF (which propagated every 1.2 s without GNSS) re-locks to the
  // solutions' phase; the two solutions that arrived just after its runs were stale by then.
  EXPECT_EQ(r.exec.pvt_stale, 2u);
  EXPECT_EQ(r.exec.ekf_without_gnss, 14u);
  EXPECT_LT(r.pos_rms_m, 0.05);
  EXPECT_LT(r.vel_rms_mps, 0.03);
  EXPECT_LT(r.outage_max_horiz_m, 1.0);
  EXPECT_EQ(r.exec.pos_rejected + r.exec.vel_rejected, 0u);
}

// 4 Hz solutions with frames_per_ekf = 50: a 4 Hz EKF, one update per solution.
TEST(FlightAppPvt, FourHertzSolutionsRunAFourHertzEkf) {
  const DriveResult r =
      fly_drive<fsw::Layout15Full>(4.0, app_config(50, 0.0), 0.0, Vec3::Zero(), 70.0);
  print("car, 4 Hz solutions", r);
  expect_clean(r);
  EXPECT_NEAR(r.app.init_t_s, 0.25, 1e-9);
  EXPECT_GE(r.exec.ekf_updates, 4u * 69u);
  EXPECT_EQ(r.exec.ekf_without_gnss, 0u);
  EXPECT_EQ(r.exec.pvt_replaced + r.exec.pvt_stale, 0u);
  EXPECT_EQ(r.exec.pos_used + r.exec.pos_rejected, 3u * r.exec.ekf_updates);
  EXPECT_LE(r.exec.pos_rejected + r.exec.vel_rejected, 4u);  // the gate's 0.1% of 1668 scalars
  EXPECT_LT(r.pos_rms_m, 0.05);
  EXPECT_LT(r.vel_rms_mps, 0.03);
  EXPECT_LT(r.worst_heading_after_turns_deg, 0.1);
}

// The diagnosis layout with the lever-arm block on: the antenna 0.5 m ahead, 0.3 m right and
// 0.8 m above the IMU, configured as zero; the turns make the horizontal components observable.
TEST(FlightAppPvt, DiagLayoutEstimatesTheLeverArmInTurns) {
  fsw::FlightAppConfig cfg = app_config(200, 0.0);
  cfg.exec.ekf.lever_arm_sigma_m = 1.0;
  const Vec3 lever(0.5, 0.3, -0.8);
  const DriveResult r = fly_drive<fsw::LayoutDiag>(1.0, cfg, 0.0, lever, 130.0);
  print("car, lever arm", r);
  std::printf("  lever arm estimate %.3f %.3f %.3f m (sigma %.3f %.3f %.3f), truth %.1f %.1f %.1f\n", r.lever_arm_m.x(),
              r.lever_arm_m.y(), r.lever_arm_m.z(), r.lever_arm_sigma_m.x(), r.lever_arm_sigma_m.y(),
              r.lever_arm_sigma_m.z(), lever.x(), lever.y(), lever.z());
  expect_clean(r);
  EXPECT_EQ(r.exec.pvt_stale, 0u);
  // The vertical component is not observable on a flat road without roll or pitch (it is the
  // height error), so the position error there stays at the lever arm's; horizontally it is fine.
  EXPECT_NEAR(r.lever_arm_m.x(), lever.x(), 0.05);
  EXPECT_NEAR(r.lever_arm_m.y(), lever.y(), 0.05);
  EXPECT_LT(r.lever_arm_sigma_m.head<2>().maxCoeff(), 0.05);
}

// Validation before the executive: quality, non-finite fields, sigmas; the initialisation's
// reasons (levelling, no velocity, too slow) reuse the raw path's counters.
TEST(FlightAppPvt, RejectsBadSolutionsAndCountsWhyItDoesNotInitialise) {
  static fsw::FlightApp<fsw::Layout15Full> app;
  fsw::FlightAppConfig cfg = app_config(200, 0.0);
  cfg.pvt_max_quality = 2;
  ASSERT_EQ(app.init(cfg), fsw::Status::kOk);
  fsw::GnssPvtMeasurement m;
  m.t_s = 1.0;
  m.llh = Vec3(0.6, 2.2, 50.0);
  m.vel_enu_mps = Vec3(1.0, 1.0, 0.0);
  m.pos_sigma_enu_m = Vec3::Constant(0.02);
  m.vel_sigma_enu_mps = Vec3::Constant(0.02);
  m.has_velocity = true;
  m.quality = 1;
  EXPECT_EQ(app.on_gnss_pvt(m), fsw::Status::kOk);  // no levelling samples yet
  EXPECT_EQ(app.health().init_not_level, 1u);
  fsw::FrameOutput out;
  for (int k = 0; k < 200; ++k) app.on_imu({1.0 + 1e-3 * (k + 1), 1e-3, Vec3::Zero(), Vec3(0.0, 0.0, -9.8e-3)}, out);
  EXPECT_EQ(app.on_gnss_pvt(m), fsw::Status::kOk);  // 1.4 m/s < 3 m/s
  EXPECT_EQ(app.health().init_too_slow, 1u);
  fsw::GnssPvtMeasurement no_vel = m;
  no_vel.has_velocity = false;
  no_vel.vel_enu_mps.x() = std::nan("");  // ignored without has_velocity
  EXPECT_EQ(app.on_gnss_pvt(no_vel), fsw::Status::kOk);
  EXPECT_EQ(app.health().init_no_fix, 1u);
  for (int bad = 0; bad < 6; ++bad) {
    fsw::GnssPvtMeasurement b = m;
    if (bad == 0) b.quality = 3;  // above pvt_max_quality
    if (bad == 1) b.quality = 0;
    if (bad == 2) b.llh.x() = std::nan("");
    if (bad == 3) b.pos_sigma_enu_m.z() = 0.0;
    if (bad == 4) b.vel_sigma_enu_mps.x() = -1.0;
    if (bad == 5) b.t_s = INFINITY;
    EXPECT_EQ(app.on_gnss_pvt(b), fsw::Status::kBadInput) << bad;
  }
  EXPECT_EQ(app.health().pvt_received, 9u);
  EXPECT_EQ(app.health().pvt_rejected, 6u);
  EXPECT_EQ(app.health().pvt_before_init, 3u);
  EXPECT_FALSE(app.initialised());
  m.vel_enu_mps = Vec3(3.0, -1.0, 0.0);
  EXPECT_EQ(app.on_gnss_pvt(m), fsw::Status::kOk);
  ASSERT_TRUE(app.initialised());
  // Heading = track (no offset configured); roll/pitch from the level specific force.
  const fsw::Vec3 eul = fsw::euler_from_C_b_n(app.executive().ins().state().C_b_n());
  EXPECT_NEAR(eul.z(), std::atan2(3.0, -1.0), 1e-12);
  EXPECT_NEAR(eul.x(), 0.0, 1e-12);
  EXPECT_NEAR(eul.y(), 0.0, 1e-12);
}
