// The flight application: everything between the decoded sensor inputs and the navigation
// output, the same in SIL (simulator in-process), HIL (CAN bus) and replay (LCM log).
//
//   on_almanac(GpsAlmanac)   -> the almanac table (flight code validates every element)
//   on_gnss(GnssRawEpoch)    -> satellite positions from the almanac (gnss_epoch_from_raw); before
//                               initialisation: a single-point solution that may initialise
//   on_gnss_pvt(GnssPvtMeasurement) -> a position/velocity solution (loosely coupled update);
//                               before initialisation: may initialise (land vehicles)
//   on_imu(ImuSample)        -> before initialisation: levelling; after: batched into the
//                               executive's minor frames (the 200 Hz group; it releases the 1 Hz
//                               group, which runs inside on_imu or, with exec.ekf_group_inline
//                               false, in run_ekf_group() on the caller's other thread)
//   on_event(InputEvent)     -> the one dispatch every harness uses: the entry of the event's kind
//                               (fsw/input_event.hpp)
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
#include "fsw/config_check.hpp"
#include "fsw/executive.hpp"
#include "fsw/gnss_pvt.hpp"
#include "fsw/gps_orbit.hpp"
#include "fsw/input_event.hpp"

namespace fsw {

/// How the flight application gets its initial attitude (see the file header).
enum class InitMode : std::uint8_t {
  kTrack,             ///< in motion: heading = GNSS track + init_heading_offset_rad, levelling
  kStatic,            ///< at rest: levelling + gyrocompassing over alignment_s
  kVelocityMatching,  ///< in motion: IMU-integrated velocity matched to GNSS velocities (Wahba)
  kGiven,             ///< the harness gives the initial state: start_given() (see the file header)
};
const char* to_string(InitMode m);

/// The most IMU samples the levelling averages (FlightAppConfig::levelling_samples).
inline constexpr int kMaxLevellingSamples = 1024;

struct FlightAppConfig {
  ExecutiveConfig exec{};  ///< exec.ekf's pos/vel/att sigmas are replaced by the init_* below
  int min_satellites_for_init = 5;
  double max_init_pdop = 6.0;
  double min_init_speed_mps = 20.0;
  int levelling_samples = 200;                      ///< IMU samples averaged for roll and pitch
  double init_pos_sigma_m = 30.0;
  double init_vel_sigma_mps = 1.0;
  Vec3 init_att_sigma_rad = Vec3(0.2, 0.2, 1.0) * kDegToRad;  ///< roll/pitch (levelling), heading (velocity)
  /// Heading of body x minus the GNSS track at initialisation (a sensor mounted at a yaw angle to
  /// the direction of travel) [rad]; used by both initialisations.
  double init_heading_offset_rad = 0.0;
  /// Solutions with quality (RTKLIB Q) outside 1..pvt_max_quality are rejected.
  int pvt_max_quality = 6;

  InitMode init_mode = InitMode::kTrack;
  // kStatic (and the rest detection of kVelocityMatching).
  double alignment_s = 60.0;                ///< stationary samples needed (kStatic) [s]
  double static_max_speed_mps = 0.2;        ///< an epoch at or below this ground speed is at rest
  double static_max_rate_dev_radps = 0.1 * kDegToRad;  ///< interval mean rate vs window mean
  double static_max_accel_dev_mps2 = 0.1;   ///< interval mean specific force vs window mean
  // kVelocityMatching.
  double vm_min_s = 2.0;                    ///< shortest window [s]
  double vm_max_s = 20.0;                   ///< a window without a determined heading restarts [s]
  double vm_max_heading_sigma_rad = 3.0 * kDegToRad;  ///< heading sigma that ends the window
  bool vm_rest_gyro_bias = true;            ///< subtract the rest window's mean rate
  double vm_rest_min_s = 1.0;               ///< rest needed for that estimate [s]
};

struct FlightAppHealth {
  std::uint32_t imu_received = 0;
  std::uint32_t imu_before_init = 0;     ///< used for levelling only
  std::uint32_t imu_rejected = 0;        ///< non-finite samples (levelling) or time not after the INS
  std::uint32_t gnss_received = 0;
  std::uint32_t gnss_rejected = 0;       ///< malformed raw epochs
  std::uint32_t gnss_before_init = 0;    ///< epochs that did not (yet) initialise
  std::uint32_t init_no_fix = 0;         ///< ... of which: no single-point solution / too few satellites
  std::uint32_t init_bad_geometry = 0;   ///< ... PDOP too large
  std::uint32_t init_too_slow = 0;       ///< ... speed too low for a velocity heading
  std::uint32_t init_not_level = 0;      ///< ... not enough IMU samples for levelling yet (kVelocityMatching:
                                         ///< no IMU history at the epoch's time)
  std::uint32_t init_moving = 0;         ///< ... kStatic: motion (GNSS speed or IMU) restarted the window
  std::uint32_t init_aligning = 0;       ///< ... alignment not complete yet (kStatic: window shorter than
                                         ///< alignment_s; kVelocityMatching: heading not determined yet)
  std::uint32_t init_align_restarts = 0; ///< ... kVelocityMatching: window older than vm_max_s restarted
  std::uint32_t init_align_failed = 0;   ///< ... the alignment could not be solved (degenerate data)
  std::uint32_t pvt_received = 0;
  std::uint32_t pvt_rejected = 0;        ///< quality out of range, non-finite fields, sigma <= 0
  std::uint32_t pvt_before_init = 0;     ///< solutions that did not (yet) initialise (init_* say why)
  std::uint32_t almanac_received = 0;
  std::uint32_t almanac_rejected = 0;
  GnssConversionStats conversion{};
  bool initialised = false;
  double init_t_s = 0.0;
  GnssPvt init_fix{};  ///< the initialising fix (from a PVT: position, velocity, n_used = n_sat, pdop 0)
  InitMode init_mode = InitMode::kTrack;
  double init_align_s = 0.0;             ///< length of the alignment window that initialised [s]
  Vec3 init_att_sigma_rad = Vec3::Zero();  ///< phi_E, phi_N, phi_U sigma the EKF started with
  Vec3 init_euler_rad = Vec3::Zero();      ///< initial roll, pitch, heading (euler_from_C_b_n)
  Vec3 vm_gyro_bias_radps = Vec3::Zero();  ///< kVelocityMatching: gyro bias (rest estimate + window's)
  Vec3 vm_accel_bias_mps2 = Vec3::Zero();  ///< kVelocityMatching: the window's accelerometer bias estimate
};

template <class Layout>
class FlightApp {
 public:
  Status init(const FlightAppConfig& cfg);
  Status on_almanac(const GpsAlmanac& sat);
  Status on_gnss(const GnssRawEpoch& raw);
  /// One GNSS position/velocity solution. kBadInput (counted in pvt_rejected) when invalid.
  Status on_gnss_pvt(const GnssPvtMeasurement& m);
  /// One IMU sample. out.nav_valid is set when the sample completed a minor frame.
  Status on_imu(const ImuSample& s, FrameOutput& out);
  /// One input event (fsw/input_event.hpp), the way every harness feeds the application: calls
  /// the entry of ev.kind. out is written by an IMU event only (the other kinds leave it as it
  /// is): out.nav_valid when the sample completed a minor frame.
  Status on_event(const InputEvent& ev, FrameOutput& out);
  /// InitMode::kGiven: starts navigation from nav (t_s, llh, vel_enu_mps, q_b_n). kBadConfig in any
  /// other mode or before init(), kBadInput for a non-finite state or when already initialised.
  Status start_given(const NavState& nav);
  /// Measured execution time of the previous tick, passed to the executive (real-time mode).
  void set_prev_tick_exec_s(double s) { prev_tick_exec_s_ = s; }
  /// The 1 Hz group (Executive::run_ekf_group): with exec.ekf_group_inline = false the caller runs
  /// it after an out.ekf_released, on its own thread or between two on_imu calls.
  Status run_ekf_group() { return exec_.run_ekf_group(); }
  /// A lockstep caller running the 1 Hz group elsewhere waits for it while this is true.
  bool ekf_result_due_next_frame() const { return health_.initialised && exec_.ekf_result_due_next_frame(); }
  /// Measured execution time of a 1 Hz run (real-time mode).
  void note_ekf_group_exec_s(double s) { exec_.note_ekf_group_exec_s(s); }

  bool initialised() const { return health_.initialised; }
  const Executive<Layout>& executive() const { return exec_; }
  const FlightAppHealth& health() const { return health_; }
  const GpsAlmanacTable& almanac() const { return almanac_; }

 private:
  Status try_initialise(const GnssEpoch& epoch);
  Status try_initialise_pvt(const GnssPvtMeasurement& m);
  /// A GNSS velocity fix before initialisation in kStatic / kVelocityMatching. llh is the IMU's
  /// position (raw fix) or the antenna's (antenna = true: moved back by the lever arm).
  struct InitFix {
    double t_s = 0.0;
    Vec3 llh = Vec3::Zero();
    Vec3 vel_enu_mps = Vec3::Zero();
    double vel_sigma_mps = 0.0;
    bool antenna = false;
  };
  Status init_static(const InitFix& f);
  Status init_velocity_matching(const InitFix& f);
  /// Common end of every initialisation: starts the executive, records the health.
  Status start(const NavState& nav, const Vec3& att_sigma_rad, double align_s);
  /// kStatic bookkeeping of one epoch: true when the interval ending here was at rest and joined
  /// the window; false (window restarted) when the epoch or the IMU showed motion.
  bool rest_epoch(double ground_speed_mps);
  void vm_imu(const ImuSample& s);
  /// alpha (current b0) at time t_s from the history; false when t_s is outside it.
  bool vm_alpha_at(double t_s, Vec3& alpha) const;
  /// Re-bases the integration on the newest sample and opens a window at the fix f.
  void vm_open_window(const InitFix& f);
  /// Roll and pitch [rad] from the mean specific force of the levelling samples.
  void levelled_roll_pitch(double& roll, double& pitch) const;

  static constexpr int kMaxLevelling = kMaxLevellingSamples;
  static constexpr int kVmHistory = 128;
  static constexpr double kVmMaxExtrapolation_s = 0.1;
  FlightAppConfig cfg_{};
  bool configured_ = false;
  Executive<Layout> exec_{};
  GpsAlmanacTable almanac_{};
  FlightAppHealth health_{};
  std::array<Vec3, kMaxLevelling> level_dv_{};
  std::array<double, kMaxLevelling> level_dt_{};
  int level_head_ = 0;
  int level_count_ = 0;
  std::array<ImuSample, FrameBuilder::kMaxSamplesPerFrame> batch_{};
  int n_batch_ = 0;
  GnssEpoch epoch_{};
  bool have_epoch_ = false;
  GnssPvtMeasurement pvt_{};
  bool have_pvt_ = false;
  double prev_tick_exec_s_ = -1.0;
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

#define FSW_FLIGHT_APP_EXTERN(L) extern template class FlightApp<L>;
FSW_FOR_EACH_LAYOUT(FSW_FLIGHT_APP_EXTERN)
#undef FSW_FLIGHT_APP_EXTERN

}  // namespace fsw
