// The flight application's initialisation (fsw::Initialiser): what happens to the inputs before
// navigation starts. FlightApp (fsw/flight_app.hpp) hands it every IMU sample, raw epoch and
// solution until it reports an initial state, then starts the executive with that state; the
// initialisation itself never touches the executive. The attitude solutions it uses are in
// fsw/alignment.hpp (CoarseAlignment, VelocityMatchAlignment).
//
// In-motion initialisation (no host, no ground alignment): at the first epoch with at least
// min_satellites_for_init satellites, PDOP <= max_init_pdop and a speed >= min_init_speed_mps,
// position and velocity come from the single-point solution, roll and pitch from the mean
// specific force of the last levelling_samples IMU samples (unaccelerated flight), heading from
// the GNSS velocity (zero sideslip). The EKF starts with the configured uncertainty of that
// initialisation and removes the rest once the turns make heading observable.
//
// From a position/velocity solution (on_gnss_pvt, e.g. a car with an RTK receiver): with
// has_velocity, a ground speed >= min_init_speed_mps (a car can use 3 m/s) and the levelling
// samples, position = the antenna's moved back by the lever arm (exec.ekf.lever_arm_b_m, rotated
// with the initial attitude), velocity = the solution's, heading = the GNSS track plus
// init_heading_offset_rad, roll and pitch from levelling. Heading from the track assumes the
// vehicle moves along body x (no sideslip: true for cars and aircraft; a sensor mounted at a yaw
// angle to the direction of travel states that angle in init_heading_offset_rad); levelling
// assumes no acceleration over the levelling window. After initialisation the solutions go to
// the executive; raw epochs and solutions may both arrive, the executive uses what it gets.
//
// INITIALISATION MODES (FlightAppConfig::init_mode). The text above is InitMode::kTrack, the
// default. Two more take their attitude from the IMU itself; both accept a raw epoch (its
// single-point fix, with the satellite count and PDOP checks above) or a solution with velocity.
//
// InitMode::kStatic, stationary coarse alignment (a vehicle at rest with a gyro good enough to
// sense the Earth rate, < about 1 deg/h: the heading error is eps_E / (Omega cos L), see
// fsw/alignment.hpp). The IMU samples between two GNSS epochs form an interval. An epoch is "at
// rest" when its ground speed <= static_max_speed_mps. An interval enters the alignment window
// (fsw::CoarseAlignment) only when the epochs at both of its ends are at rest and its mean
// specific force and mean angular rate differ from the window's by at most
// static_max_accel_dev_mps2 and static_max_rate_dev_radps (the IMU detects what the GNSS speed
// cannot: a turn in place, a tilt change, or motion that starts and stops between epochs; a
// quasi-static vehicle's sway averages out and must not trip it). An epoch that shows motion by
// either test restarts the window (init_moving). Once the window holds alignment_s of samples, the
// next epoch at rest initialises: position and velocity from the fix, attitude from
// CoarseAlignment::solve at the fix's latitude (levelling + gyrocompassing). Moving before that
// never initialises with a partial window: the window restarts and init_aligning counts the
// epochs that waited. Velocity from the fix (not zero): a raw fix's Doppler velocity, or the
// solution's, are what the filter compares with next.
//
// InitMode::kVelocityMatching, in-motion coarse alignment by velocity matching (the
// optimisation-based alignment of Wu & Pan 2013; fsw::VelocityMatchAlignment): no mounting yaw,
// no zero-sideslip assumption, any attitude. Before initialisation every IMU sample advances
// C_b^b0 (rotation-vector update) and alpha = integral C_b^b0 f_b dt (with the half-sample rotation
// correction) from a reference frame b0, kept in a short history (kVmHistory samples) to read
// alpha at a GNSS epoch's time by linear interpolation (or extrapolation by at most
// kVmMaxExtrapolation_s with the last sample's specific force, when the epoch arrives before the
// IMU reaches its time). A window opens at a GNSS epoch t_0; every later epoch adds the pair
// (alpha(t_k) - alpha(t_0), beta_k = v(t_k) - v(t_0) - g_n (t_k - t_0)), g_n from the fix's
// position (frames.hpp's Earth model), with weight 1 / sigma_k^2, dt = t_k - t_0,
//     sigma_k^2 = s_v(t_k)^2 + vrw^2 dt + (g arw dt^1.5 / sqrt 3)^2,
// s_v the fix's velocity sigma (a solution's largest axis; a raw fix: pseudorange_rate_sigma x
// PDOP), vrw and arw the IMU's white noise (exec.ekf; the angle random walk tilts b0 and leaks
// gravity into alpha), and the sensitivities of alpha to a gyro bias (G) and an accelerometer
// bias (Theta = integral C_b^b0 dt), integrated with alpha: the solver carries both biases as
// nuisance parameters with the configured sigmas exec.ekf.gyro_bias_sigma / accel_bias_sigma
// (the gyro's after a rest estimate, below: what remains of it, sqrt(arw^2 / T_rest + Omega^2)).
// Without turns an accelerometer bias is indistinguishable from a tilt (b / g, the levelling
// error); with turns the window separates them in part. t_0 is the pair (0, 0) with weight
// 1 / s_v(t_0)^2, and the solver fits the common offset that the error of v(t_0) puts into every
// pair (fsw::VelocityMatchAlignment). The window is "good enough" when it is at least vm_min_s
// long and the 1-sigma heading uncertainty from its geometry (the horizontal velocity change since
// t_0 must be large against those sigmas and biases) is <= vm_max_heading_sigma_rad; then C_b0^n,
// corrected by the window's bias estimates, is propagated to the last IMU sample
// (C_b^n = C_b0^n C_b^b0), the fitted velocity to that sample through alpha, the position by the
// fix's velocity, and the EKF starts with the geometry's attitude sigmas. The window restarts at
// the current epoch when it is older than vm_max_s without a determined heading
// (init_align_restarts; a straight constant-velocity segment never determines it), and at every
// epoch at rest (ground speed <= static_max_speed_mps) that does not complete it (after the pair
// is added: a short stop at the end of a good window still initialises): rest adds no heading
// information, only gyro error, so the window starts at the last rest before motion. The rest
// before motion also serves as a gyro bias estimate: with vm_rest_gyro_bias, the mean angular
// rate of the stationary window (built as in kStatic, at least vm_rest_min_s long) is subtracted
// from the gyro increments of the following velocity-matching window (it contains the Earth rate:
// the remainder is the rate relative to the Earth-fixed frame, which is what the neglected
// Earth-rate model wants). The EKF is not told this estimate nor the window's bias estimates
// (FlightAppHealth reports them); it starts from zero bias as before. Each restart re-bases the
// integration on the newest sample (alpha and the history are rotated into the re-based b0), so
// the numbers stay small.
//
// InitMode::kGiven: the harness that knows the truth gives the initial state (the Monte Carlo, the
// paper and the timing audit: the scenario's truth at t = 0 with the run's drawn errors) through
// start_given(); the EKF starts with init_pos_sigma_m, init_vel_sigma_mps and init_att_sigma_rad.
// GNSS inputs before it count in gnss_before_init / pvt_before_init and never initialise; after
// it every input goes the same way as after any other initialisation.
#pragma once

#include <array>
#include <cstdint>

#include "fsw/alignment.hpp"
#include "fsw/flight_app_config.hpp"
#include "fsw/gnss.hpp"
#include "fsw/gnss_pvt.hpp"
#include "fsw/status.hpp"
#include "fsw/strapdown.hpp"

namespace fsw {

/// What an initialisation found: the state navigation starts from and what the health reports.
struct InitialState {
  NavState nav{};                          ///< the initial solution (t_s, llh, vel_enu_mps, q_b_n)
  Vec3 att_sigma_rad = Vec3::Zero();       ///< phi_E, phi_N, phi_U sigma the EKF starts with
  double align_s = 0.0;                    ///< length of the alignment window [s] (0: none)
  GnssPvt fix{};                           ///< the initialising fix (FlightAppHealth::init_fix)
  bool vm_biases = false;                  ///< kVelocityMatching: the two bias estimates below are set
  Vec3 vm_gyro_bias_radps = Vec3::Zero();  ///< rest estimate + the window's
  Vec3 vm_accel_bias_mps2 = Vec3::Zero();  ///< the window's accelerometer bias estimate
};

/// The initialisation before navigation starts (the file header). Every call takes the flight
/// application's configuration and counts what happened in its health (the init_* counters);
/// on_gnss / on_pvt set ready when the input completed an initialisation, out then holding the
/// initial state. Statically allocated, no I/O; one class for every layout.
class Initialiser {
 public:
  /// Empties the levelling buffer, the alignment windows and the velocity-matching history.
  void reset(const FlightAppConfig& cfg);
  /// One IMU sample before initialisation (levelling; kStatic / kVelocityMatching: alignment).
  /// kBadInput (counted in imu_rejected) for non-finite data or a non-positive dt; a sample not
  /// after the previous one in kVelocityMatching is counted there and skipped (kOk).
  Status on_imu(const ImuSample& s, const FlightAppConfig& cfg, FlightAppHealth& health);
  /// One raw epoch (satellite positions already computed) before initialisation.
  Status on_gnss(const GnssEpoch& epoch, const FlightAppConfig& cfg, FlightAppHealth& health, InitialState& out,
                 bool& ready);
  /// One validated position/velocity solution before initialisation.
  Status on_pvt(const GnssPvtMeasurement& m, const FlightAppConfig& cfg, FlightAppHealth& health, InitialState& out,
                bool& ready);

 private:
  /// A GNSS velocity fix before initialisation in kStatic / kVelocityMatching. llh is the IMU's
  /// position (raw fix) or the antenna's (antenna = true: moved back by the lever arm).
  struct InitFix {
    double t_s = 0.0;
    Vec3 llh = Vec3::Zero();
    Vec3 vel_enu_mps = Vec3::Zero();
    double vel_sigma_mps = 0.0;
    bool antenna = false;
  };
  /// kStatic: levelling and gyrocompassing over the rest window.
  bool init_static(const InitFix& f, const FlightAppConfig& cfg, FlightAppHealth& health, InitialState& out);
  /// kVelocityMatching: the velocity-matching window.
  bool init_velocity_matching(const InitFix& f, const FlightAppConfig& cfg, FlightAppHealth& health,
                              InitialState& out);
  /// The three ways from a fix to an initial state (true: out holds it; false: counted in health).
  /// kTrack: heading from the GNSS track (ground speed >= min_init_speed_mps), roll and pitch from
  /// levelling.
  bool init_track(const InitFix& f, const FlightAppConfig& cfg, FlightAppHealth& health, InitialState& out) const;
  /// kStatic bookkeeping of one epoch: true when the interval ending here was at rest and joined
  /// the window; false (window restarted) when the epoch or the IMU showed motion.
  bool rest_epoch(double ground_speed_mps, const FlightAppConfig& cfg);
  /// Dispatch of a fix by cfg.init_mode (kTrack, kStatic, kVelocityMatching).
  bool init_from_fix(const InitFix& f, const FlightAppConfig& cfg, FlightAppHealth& health, InitialState& out);
  /// kVelocityMatching: one IMU sample into C_b^b0, alpha, its sensitivities and the history.
  void vm_imu(const ImuSample& s);
  /// alpha (current b0) at time t_s from the history; false when t_s is outside it.
  bool vm_alpha_at(double t_s, Vec3& alpha) const;
  /// Re-bases the integration on the newest sample and opens a window at the fix f.
  void vm_open_window(const InitFix& f, const FlightAppConfig& cfg);
  /// The time of the newest sample in the velocity-matching history.
  double vm_newest_t_s() const;
  /// Roll and pitch [rad] from the mean specific force of the levelling samples.
  void levelled_roll_pitch(double& roll, double& pitch) const;

  static constexpr int kMaxLevelling = kMaxLevellingSamples;
  static constexpr int kVmHistory = 128;
  static constexpr double kVmMaxExtrapolation_s = 0.1;
  std::array<Vec3, kMaxLevelling> level_dv_{};
  std::array<double, kMaxLevelling> level_dt_{};
  int level_head_ = 0;
  int level_count_ = 0;
  // kStatic / rest detection: the window and the interval since the last epoch.
  CoarseAlignment window_{};
  CoarseAlignment interval_{};
  bool prev_epoch_at_rest_ = false;
  // kVelocityMatching: integration from b0 and its history.
  Quat vm_q_b_b0_ = Quat::Identity();
  Vec3 vm_alpha_ = Vec3::Zero();
  Mat3 vm_theta_ = Mat3::Zero();  ///< integral C_b^b0 dt [s]
  Mat3 vm_G_ = Mat3::Zero();      ///< d alpha / d gyro bias [m/s per rad/s]
  Vec3 vm_last_f_b_ = Vec3::Zero();  ///< specific force of the newest sample [m/s^2]
  Vec3 vm_bias_radps_ = Vec3::Zero();
  double vm_gyro_sigma_radps_ = 0.0;  ///< gyro bias sigma the weights assume (after the rest estimate)
  std::array<double, kVmHistory> vm_hist_t_{};
  std::array<Vec3, kVmHistory> vm_hist_alpha_{};
  int vm_hist_head_ = 0;   ///< next slot
  int vm_hist_count_ = 0;
  bool vm_window_open_ = false;
  double vm_t0_s_ = 0.0;
  Vec3 vm_v0_ = Vec3::Zero();
  Vec3 vm_alpha0_ = Vec3::Zero();
  Vec3 vm_g_n_ = Vec3::Zero();
  VelocityMatchAlignment vm_{};
};

}  // namespace fsw
