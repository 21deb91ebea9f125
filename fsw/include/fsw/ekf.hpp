// Error-state extended Kalman filter, tightly coupled to GPS pseudorange and pseudorange rate or
// loosely coupled to GNSS position/velocity solutions (1 Hz task): the core (init, propagate, the
// scalar update, feedback) and its aid units. One implementation for every model: Ekf<Layout15>, Ekf<Layout24>, and the
// extended layouts of the diagnosis (error_state.hpp defines the states and their signs).
//
// PROPAGATION (linearised SDINS error model, ENU, frames.hpp conventions)
//   d(dp)/dt  = dv
//   d(dv)/dt  = f_n x phi + C_b_n df_b - (2 w_ie + w_en) x dv + v x (2 dw_ie + dw_en) + dg
//   d(phi)/dt = -w_in x phi + dw_in - C_b_n dw_ib_b
//   df_b = db_a + (dSF_a + dM_a) f_b,    dw_ib_b = db_g + (dSF_g + dM_g) w_ib_b + dG .* f_b
// dw_ie, dw_en: the rate errors caused by the position (latitude) and velocity errors; dg the
// normal-gravity error of the height error (+2 g / R dh Up). The misalignment and scale-factor
// columns are driven by the measured angular rate and specific force, as in the paper's
// equations (6), (7), (10) and (11): the gyro misalignment gamma_ij enters phi through
// -C_b_n(:, i) * w_j. The filter integrates these columns from every 200 Hz frame (the
// accumulate() call) and forms the transition matrix of the navigation block in sub-steps
// (propagation_substep_frames frames each, second order), so the 1 Hz transition matrix sees the
// turn's rates and attitudes as they were, not their 1 s average. Every non-navigation block is a
// random constant or random walk; the clock is a two-state (bias, drift) random process.
// Q: Qd = 0.5 (Phi Qc Phi^T + Qc) T per interval; the clock's Qd is exact.
//
// MEASUREMENTS: one aid unit per measurement type, each in the same shape (observation, variance,
// innovation, gate, then fuse / reset) and each returning its innovation records in
// EkfUpdateReport: the raw GNSS aid, pseudorange and pseudorange rate (update(),
// fsw/ekf/aid_gnss_raw.hpp: the measurement model, the clock, the diagnosis' extension blocks and
// the time-correlated channel errors), and the position/velocity aid, a GNSS solution (update_pvt(),
// fsw/ekf/aid_gnss_pvt.hpp). What they share is the core's (fsw/src/ekf.cpp): the gated sequential
// scalar update in Joseph form (fuse()), the covariance check and the consistency bookkeeping (the
// NIS window and the gating runaway).
//
// FEEDBACK (closed loop): after each epoch the estimate is removed from the navigation solution
// (Strapdown::correct) and added to the IMU compensation, and the error state is reset to zero.
#pragma once

#include <Eigen/Core>
#include <array>
#include <span>
#include <cmath>
#include <limits>
#include <cstdint>

#include "fsw/ekf/aid_gnss_pvt.hpp"
#include "fsw/ekf/aid_gnss_raw.hpp"
#include "fsw/error_state.hpp"
#include "fsw/frames.hpp"
#include "fsw/gnss.hpp"
#include "fsw/imu_compensation.hpp"
#include "fsw/status.hpp"
#include "fsw/strapdown.hpp"

namespace fsw {

/// The longest NIS window (EkfConfig::nis_window) [epochs].
inline constexpr int kMaxNisWindow = 64;

struct EkfConfig {
  // Initial 1-sigma uncertainty of each block (used when the layout has it).
  double pos_sigma_m = 10.0;
  double vel_sigma_mps = 0.5;
  Vec3 att_sigma_rad = Vec3::Constant(100.0 * kArcsecToRad);  ///< phi_E, phi_N, phi_U
  double accel_bias_sigma_mps2 = 100.0 * kMicroG_mps2;
  double gyro_bias_sigma_radps = 0.01 * kDegPerHourToRadps;
  double accel_misalign_sigma_rad = 5.0 * kArcsecToRad;
  double gyro_misalign_sigma_rad = 5.0 * kArcsecToRad;
  double accel_scale_sigma = 100e-6;
  double gyro_scale_sigma = 100e-6;
  // Extension blocks (LayoutDiag); zero switches a block off.
  double gyro_g_sens_sigma_radps_per_mps2 = 0.0;
  double time_offset_sigma_s = 0.0;
  double time_drift_sigma_sps = 0.0;  ///< s/s
  double lever_arm_sigma_m = 0.0;
  double tropo_scale_sigma = 0.0;
  double iono_scale_sigma = 0.0;
  /// Bit i set: state i (i < 64) starts with zero variance whatever its block's sigma, so it stays
  /// exactly zero (the diagnosis switches single components off this way).
  std::uint64_t frozen_states = 0;
  double clock_bias_sigma_m = 30.0;
  double clock_drift_sigma_mps = 1.0;

  // Process noise (continuous-time spectral densities, square roots).
  double vrw_mps_per_rts = 1e-4;           ///< velocity random walk
  double arw_rad_per_rts = 1e-7;           ///< angle random walk
  double accel_bias_rw_mps2_per_rts = 0.0; ///< bias random walk (0: random constant)
  double gyro_bias_rw_radps_per_rts = 0.0;
  double clock_bias_psd_m2ps = 0.0;        ///< S_b  (h0/2 c^2)
  double clock_drift_psd_m2ps3 = 0.0;      ///< S_d  (2 pi^2 h_-2 c^2)

  // Measurements. With the channel error blocks (Layout15Full/24Full) these are the white part only.
  double pseudorange_sigma_m = 8.0;
  double pseudorange_rate_sigma_mps = 0.2;
  // Time-correlated (first-order Gauss-Markov) channel errors, for layouts with kRangeError /
  // kRangeRateError: 1-sigma and correlation time.
  double range_gm_sigma_m = 8.0;
  double range_gm_tau_s = 60.0;
  double range_rate_gm_sigma_mps = 0.2;
  double range_rate_gm_tau_s = 10.0;
  bool use_pseudorange_rate = true;
  double gate_chi2 = 10.83;  ///< 1 degree of freedom, P(reject | good) = 0.001
  // Loosely coupled update (update_pvt): R = (pvt_sigma_scale * max(sigma, floor))^2 per ENU axis,
  // sigma the solver's own 1-sigma of the solution.
  double pvt_pos_sigma_floor_m = 0.02;
  double pvt_vel_sigma_floor_mps = 0.01;
  double pvt_sigma_scale = 1.0;
  Vec3 lever_arm_b_m = Vec3::Zero();  ///< IMU reference point -> GNSS antenna, body axes

  int propagation_substep_frames = 10;  ///< navigation frames per transition-matrix sub-step

  // Divergence guard. NIS window for the consistency test, and the gating runaway: when more than
  // half of an epoch's pseudoranges (or of its rates; at least 4 of them) fail the gate, or one
  // axis of the PVT updates' positions or velocities is gated, for runaway_epochs updates in a row
  // (after a PVT runaway the position and velocity re-initialise from the next solution, ungated), the filter
  // no longer accepts the data that would correct it; the navigation and clock covariance is then
  // re-inflated to its initial values (counted in EkfHealth::resets). 0 disables the reset.
  int nis_window = 10;
  int runaway_epochs = 5;
};

/// What happened to one scalar measurement (pseudorange or pseudorange rate) of an epoch.
enum class InnovationOutcome : std::uint8_t {
  kNotProcessed = 0,  ///< not reached (epoch used to initialise the clock, rates disabled, update not run)
  kUsed,              ///< passed the gate and updated the state
  kGated,             ///< failed the innovation gate (or a non-positive innovation variance)
  kInvalid,           ///< the observation's data were non-finite or implausible
};

/// Innovations of one observation of the epoch. Innovation = predicted minus measured, after the
/// earlier scalar updates of the same epoch; variance = H P H^T + R of that scalar update (the
/// NIS is innovation^2 / variance).
struct ObservationInnovation {
  std::uint8_t prn = 0;
  InnovationOutcome pr_outcome = InnovationOutcome::kNotProcessed;
  InnovationOutcome prr_outcome = InnovationOutcome::kNotProcessed;
  double pr_innovation_m = 0.0;
  double pr_variance_m2 = 0.0;
  double prr_innovation_mps = 0.0;
  double prr_variance_m2ps2 = 0.0;
};

/// One scalar of a loosely coupled (position/velocity) update. innovation = predicted minus
/// measured [m or m/s], after the earlier scalars of the same update; variance = H P H^T + R.
struct PvtInnovation {
  InnovationOutcome outcome = InnovationOutcome::kNotProcessed;
  double innovation = 0.0;
  double variance = 0.0;
};

/// What one measurement update did (a raw epoch, update(); or a position/velocity solution,
/// update_pvt(), then pvt is set and the pseudorange fields stay zero).
struct EkfUpdateReport {
  int pr_used = 0;
  int prr_used = 0;
  int pr_rejected = 0;   ///< failed the innovation gate
  int prr_rejected = 0;
  int obs_invalid = 0;   ///< non-finite or implausible observation data, not used
  int obs_no_channel = 0;  ///< more satellites than error-state channels: used with the white model
  bool clock_initialised = false;  ///< this epoch set the clock estimate from the measurements
  int n_obs = 0;                   ///< entries of obs: the epoch's observations, in epoch order
  std::array<ObservationInnovation, kMaxGnssChannels> obs{};
  double nis_sum = 0.0;            ///< sum of the NIS of the accepted scalar measurements ...
  int nis_dof = 0;                 ///< ... and their number (pseudoranges, rates or PVT scalars)
  // Loosely coupled update (update_pvt). obs_invalid counts an invalid position or velocity part.
  bool pvt = false;                       ///< this report is a PVT update
  std::array<PvtInnovation, 6> pvt_obs{}; ///< pos E, N, U, vel E, N, U
  int pos_used = 0;
  int vel_used = 0;
  int pos_rejected = 0;  ///< failed the innovation gate
  int vel_rejected = 0;
};

/// Numerical and statistical health of the filter (F Prime style counters, never asserts).
struct EkfHealth {
  std::uint32_t cov_checks = 0;       ///< covariance SPD checks (one per epoch)
  std::uint32_t cov_repairs = 0;      ///< checks that found P not symmetric positive definite and repaired it
  std::uint32_t nonfinite_rejected = 0;  ///< inputs with NaN/Inf stopped before the state
  /// NIS test over a sliding window of nis_window epochs: the windowed NIS sum against the upper
  /// 99.9% chi-square quantile of its degrees of freedom (false-alarm rate 1e-3 per window).
  double nis_window_sum = 0.0;
  int nis_window_dof = 0;
  double nis_window_bound = 0.0;      ///< the chi-square quantile the sum is compared with
  bool diverging = false;             ///< the last window failed the NIS test
  std::uint32_t divergence_windows = 0;  ///< windows that failed it
  std::uint32_t gating_runaway_epochs = 0;  ///< consecutive epochs with most measurements gated
  std::uint32_t resets = 0;           ///< navigation covariance re-inflated after a gating runaway
};

/// The 200 Hz half of the filter's propagation: the transition matrix of one interval, integrated
/// frame by frame (accumulate(): the navigation rows' sensor-error columns, in sub-steps of
/// substep_frames frames, second order) and handed whole to Ekf::propagate(). Only the navigation
/// rows are dense; the rest of Phi is set by propagate(). The executive keeps two, so the 200 Hz
/// group integrates the next interval while the 1 Hz group propagates with the last one
/// (fsw/executive.hpp); Ekf keeps one of its own for accumulate()/propagate() on one thread.
/// The columns of the navigation rows of Phi that can be non-zero: the navigation blocks and the
/// inertial-sensor blocks that drive them (EkfTransition::flush() fills exactly these). Every other
/// block (clock, channel errors, time offset, lever arm, delay scales) enters the measurements
/// only, so its columns of the navigation rows stay exactly zero and the transition products
/// stop at this column (bit-identical: the skipped terms are products with zero).
template <class Layout>
constexpr int nav_driven_columns() {
  constexpr Block kDriven[] = {Block::kPosition,      Block::kVelocity,      Block::kAttitude,   Block::kAccelBias,
                               Block::kGyroBias,      Block::kAccelMisalign, Block::kGyroMisalign,
                               Block::kAccelScale,    Block::kGyroScale,     Block::kGyroGSens};
  int end = 0;
  for (Block b : kDriven)
    if (Layout::has(b) && Layout::offset(b) + block_size(b) > end) end = Layout::offset(b) + block_size(b);
  return end;
}

template <class Layout>
class EkfTransition {
 public:
  static constexpr int N = Layout::kSize;
  /// Columns 0..kNavCols-1 of the navigation rows can be non-zero (nav_driven_columns()).
  static constexpr int kNavCols = nav_driven_columns<Layout>();
  using NavRows = Eigen::Matrix<double, 9, N>;

  /// Starts an empty interval (Phi = I).
  void reset(int substep_frames);
  /// One navigation frame: inc the compensated increments, nav the solution at its end. kBadInput
  /// (nothing accumulated) for a non-positive dt or non-finite values.
  Status accumulate(const FrameIncrement& inc, const NavState& nav);
  /// Closes the sub-step in progress, so phi_nav() and interval_s() cover every accumulated frame.
  void flush();
  /// The filter's dead states (Ekf::live_states): their columns of the navigation rows are not
  /// formed from the next sub-step on and stay zero, for the filter multiplies them with rows of P
  /// that are +0 (the same bits: Ekf::propagate). Ekf::propagate() sets them on the interval it is
  /// given; the default, and an all-false dead, forms every column. Kept by reset(). A state that
  /// comes back to life enters at the next sub-step: its column misses the sub-steps before.
  void set_dead_states(const std::array<bool, N>& dead);

  const NavRows& phi_nav() const { return phi_nav_; }  ///< rows 0..8 of Phi (flushed frames)
  double interval_s() const { return interval_s_; }    ///< time covered by phi_nav()
  const Vec3& last_f_enu_mps2() const { return last_f_enu_mps2_; }  ///< specific force of the last frame
  int frames() const { return frames_; }  ///< frames accumulated since reset()

 private:
  void clear_substep();  ///< empties the sub-step sums
  bool live_column(int c) const { return !dead_col_[static_cast<std::size_t>(c)]; }
  int substep_frames_ = 10;
  int frames_ = 0;
  NavRows phi_nav_ = NavRows::Identity();
  NavRows top_ = NavRows::Zero();  ///< scratch of flush(): a member, so it is not on the task's stack
  double interval_s_ = 0.0;
  int sub_frames_ = 0;
  double sub_T_ = 0.0;
  Mat3 sum_C_dt_ = Mat3::Zero();  ///< sum C_b_n dt
  Vec3 sum_dv_n_ = Vec3::Zero();  ///< sum C_b_n dv (f_n dt)
  Vec3 last_f_enu_mps2_ = Vec3::Zero();
  Eigen::Matrix<double, 3, 9> sum_C_dv_ = Eigen::Matrix<double, 3, 9>::Zero();   ///< col 3i+j: sum C(:,i) dv_j
  Eigen::Matrix<double, 3, 9> sum_C_dth_ = Eigen::Matrix<double, 3, 9>::Zero();  ///< col 3i+j: sum C(:,i) dtheta_j
  NavState last_nav_{};  ///< the solution at the end of the last frame (linearisation point of a sub-step)
  std::array<bool, kNavCols> dead_col_{};  ///< set_dead_states(), the navigation-driven columns
  bool every_column_ = true;               ///< no dead column: the products over the whole block
};

/// What telemetry reads of the filter after one epoch of the 1 Hz group (hal's EKF_STATE message),
/// published by the executive so no reader reaches into the filter while the 1 Hz group runs.
template <class Layout>
struct EkfOutput {
  double t_s = 0.0;  ///< INS time of the epoch (the end of the frame that released it)
  Eigen::Matrix<double, Layout::kSize, 1> sigma = Eigen::Matrix<double, Layout::kSize, 1>::Zero();  ///< sqrt(diag P)
  double clock_bias_m = 0.0;
  double clock_drift_mps = 0.0;
  bool clock_initialised = false;
  std::array<std::uint8_t, kGnssErrorChannels> channel_prn{};
};

/// Adds the sensor-error part of a correction x (the error-state estimate, error_state.hpp signs)
/// to the IMU compensation: biases, misalignments, scale factors, g-sensitivity.
template <class Layout>
void add_sensor_correction(const Eigen::Matrix<double, Layout::kSize, 1>& x, ImuCompensation& comp);

template <class Layout>
class Ekf {
  static_assert(kNavigationBlocksLead<Layout>, "position, velocity, attitude must be the first blocks");
  static_assert(Layout::has(Block::kClock), "tight coupling needs the receiver clock states");

 public:
  static constexpr int N = Layout::kSize;
  static constexpr int kNs = N - 9;
  using Vec = Eigen::Matrix<double, N, 1>;
  using Mat = Eigen::Matrix<double, N, N>;
  using RowVec = Eigen::Matrix<double, 1, N>;

  Status init(const EkfConfig& cfg);

  /// 200 Hz: one navigation frame after the mechanization step. inc holds the compensated
  /// increments of the frame, nav the solution at its end.
  Status accumulate(const FrameIncrement& inc, const NavState& nav);

  /// 1 Hz: P = Phi P Phi^T + Q over the frames accumulated since the last call.
  Status propagate();
  /// 1 Hz: the same over the interval t (closed here by t.flush()), which the caller accumulated
  /// (the executive's 200 Hz group); the filter's own accumulator is not touched.
  Status propagate(EkfTransition<Layout>& t);

  /// Measurement update with one epoch. nav: the INS solution at the frame closest to the epoch;
  /// omega_ib_b: body rate of that frame (for the lever-arm velocity).
  Status update(const GnssEpoch& epoch, const NavState& nav, const Vec3& omega_ib_b_radps, EkfUpdateReport& report);

  /// Loosely coupled update with one GNSS position/velocity solution of the antenna; nav and
  /// omega_ib_b as for update() (the frame acceleration of the time-offset term is the filter's
  /// own, from accumulate(), as in update()). Non-finite nav/rate/time: kBadInput, counted in
  /// nonfinite_rejected. An invalid position or velocity part (non-finite, sigma <= 0, latitude
  /// beyond +-90 deg) is not used and counted in report.obs_invalid; the rest is.
  Status update_pvt(const GnssPvtMeasurement& m, const NavState& nav, const Vec3& omega_ib_b_radps,
                    EkfUpdateReport& report);

  /// Applies the estimate to the solution and the IMU compensation and resets it to zero
  /// (take_correction(), then the navigation and sensor parts applied at once).
  Status feedback(Strapdown& ins, ImuCompensation& comp);
  /// The filter's half of the feedback: returns the estimate in x, applies the parts the filter
  /// keeps itself (clock, time offset, lever arm, delay scales, channel errors) and resets the
  /// estimate to zero. The navigation (x(0..8)) and sensor parts (add_sensor_correction) are the
  /// caller's to apply; the executive applies them ekf_latency_frames later. kBadInput (estimate
  /// dropped, x zero) when it is not finite.
  Status take_correction(Vec& x);
  /// The published output of the filter at INS time t_s.
  void output(double t_s, EkfOutput<Layout>& out) const;

  /// Replaces the covariance (restoring a saved filter, tests); symmetrised and checked like every
  /// epoch's (a non-positive-definite P is repaired and counted). kBadInput for NaN/Inf. A dead
  /// state it revives enters the transition at the next sub-step (EkfTransition::set_dead_states):
  /// exact right after a propagate(), before the next frame.
  Status set_covariance(const Mat& P);

  /// Dead states: sensor or extension states started with zero variance and driven by no noise
  /// (EkfConfig::frozen_states, a diagnosis block switched off). Their rows and columns of P stay
  /// exactly +0, so the update, the symmetrisation and the definiteness check leave them out: the
  /// same bits, fewer operations (docs/filters.md, "Frozen states"). The number of live states:
  int live_states() const { return n_live_; }
  /// Tests and benchmarks: true runs those loops over every state, the reference the skip is
  /// checked against (bit for bit); false (the default) skips the dead states.
  void set_dense_covariance_loops(bool dense);

  const Vec& x() const { return x_; }
  const Mat& P() const { return P_; }
  /// Transition matrix of the interval closed by the last propagate().
  const Mat& last_transition() const { return last_Phi_; }
  double clock_bias_m() const { return clock_bias_m_; }
  double clock_drift_mps() const { return clock_drift_mps_; }
  /// Extension estimates (LayoutDiag): IMU-GNSS time offset, lever arm (starts at the configured
  /// one), tropospheric and ionospheric delay scales.
  double time_offset_s() const { return time_offset_hat_s_; }
  /// The estimated IMU-GNSS time offset's rate (s/s; 0 without kTimeDrift) and the offset it gives
  /// at GNSS time t_s (the one the measurement models use).
  double time_drift() const { return time_drift_hat_; }
  double time_offset_at(double t_s) const {
    return std::isfinite(drift_t_ref_s_) ? time_offset_hat_s_ + time_drift_hat_ * (t_s - drift_t_ref_s_)
                                         : time_offset_hat_s_;
  }
  const Vec3& lever_arm_b_m() const { return lever_arm_hat_b_m_; }
  double tropo_scale() const { return tropo_scale_hat_; }
  double iono_scale() const { return iono_scale_hat_; }
  bool clock_initialised() const { return clock_initialised_; }
  /// PRN bound to each measurement-error channel (0: free); only for layouts with kRangeError.
  const std::array<std::uint8_t, kGnssErrorChannels>& channel_prn() const { return slot_prn_; }
  const EkfConfig& config() const { return cfg_; }
  const EkfHealth& health() const { return health_; }

 private:
  /// One gated scalar update; nu and S receive the innovation and its variance.
  bool scalar_update(const RowVec& h, double y, double r, double& nu, double& S);
  /// The core's step of every aid: one scalar through the gate and, when it passes, into the state
  /// (scalar_update); nu and S receive the innovation and its variance, the NIS of an accepted
  /// scalar joins report's sum. kUsed or kGated (the aid counts it by type). At most six integer
  /// arguments: a seventh is pushed on the stack at each call, which the stack audit sees as a
  /// dynamic frame.
  InnovationOutcome fuse(const RowVec& h, double y, double r, double& nu, double& S, EkfUpdateReport& report);
  /// Symmetrises P in place and checks it is positive definite; repairs (counted) if not.
  void check_covariance();
  /// Applies the part of the estimate the filter keeps itself and zeroes the estimate.
  void keep_correction();
  void symmetrise();
  void track_consistency(const EkfUpdateReport& report);
  /// The white-noise spectral densities per state (velocity, attitude, bias random walks).
  Vec white_noise_psd() const;
  /// propagate()'s two products with the navigation rows (PhiP's and P's first nine columns), over
  /// the n navigation-driven columns column(0), column(1), ... (ascending, column(0) = 0).
  template <class Column>
  void nav_products(Mat& PhiP, Column column, int n);
  /// Marks the dead states after init() (live_states()) and indexes the others.
  void find_dead_states();
  /// The runs of consecutive live states from dead_ (and dense_loops_).
  void index_live_states();
  /// The Cholesky check's column j (rows j..n-1 of work_) less its columns before j.
  void check_column_update(int j, int n);
  /// The live states' correlations into the top-left n_live_ x n_live_ lower triangle of work_.
  void gather_live_correlations(const Vec& d);
  bool skipped(int i) const { return !dense_loops_ && dead_[static_cast<std::size_t>(i)]; }
  /// skipped(i) for every i: the dead states a transition is told (none with the dense loops).
  const std::array<bool, N>& skipped_states() const { return dense_loops_ ? kNoneDead : dead_; }
  static constexpr std::array<bool, N> kNoneDead{};

  // The raw GNSS aid (fsw/src/ekf/aid_gnss_raw.cpp).
  /// Observation: each satellite's prediction from the antenna (valid[k] false and the record
  /// kInvalid for unusable data); returns the number of usable observations.
  int predict_epoch(const GnssEpoch& epoch, const GnssRawAntenna& ant, GnssRawPrediction* pred, bool* valid,
                    EkfUpdateReport& report) const;
  /// Reset: the clock from the mean residuals of the usable observations (the first epoch).
  void init_clock(const GnssEpoch& epoch, const GnssRawPrediction* pred, const bool* valid, int n_valid);
  /// Releases the channels of satellites that are no longer tracked.
  void release_channels(const GnssEpoch& epoch, const bool* valid);
  /// Variance, innovation, gate and fuse of one observation's pseudorange and pseudorange rate;
  /// returns its innovation record (and counts it in report). At most six integer arguments with
  /// the record's return slot (the stack audit, fuse()).
  ObservationInnovation fuse_observation(const GnssObservation& o, const GnssRawPrediction& p, const GnssRawAntenna& ant,
                                         double clock_bias_m, double drift_lever_s, EkfUpdateReport& report);
  // noinline: a partially inlined clone (.part.0) folded by identical-code folding leaves the
  // stack audit without a frame size for it.
  [[gnu::noinline]] int bind_channel(std::uint8_t prn);
  void reset_channel_state(int state, double sigma);

  // The position/velocity aid (fsw/src/ekf/aid_gnss_pvt.cpp).
  /// Variance, innovation, gate and fuse of axis i (pos E N U, vel E N U) of a solution; returns
  /// its innovation record (and counts it in report).
  PvtInnovation fuse_pvt_axis(int i, const GnssPvtMeasurement& m, const PvtModel& mdl, double drift_lever_s,
                              EkfUpdateReport& report);

  EkfConfig cfg_{};
  bool initialised_ = false;
  Vec x_ = Vec::Zero();
  Mat P_ = Mat::Zero();
  Mat Phi_ = Mat::Identity();  ///< scratch of propagate(): the full transition of the interval
  Mat last_Phi_ = Mat::Identity();
  Mat work_ = Mat::Zero();     ///< scratch (Phi P, Cholesky): a member, so it is not on the task's stack
  EkfTransition<Layout> trans_{};  ///< accumulate() / propagate() on one thread
  EkfHealth health_{};
  static constexpr int kMaxNisWindow = fsw::kMaxNisWindow;
  std::array<double, kMaxNisWindow> nis_hist_{};
  std::array<int, kMaxNisWindow> dof_hist_{};
  int nis_head_ = 0;
  int nis_count_ = 0;
  int runaway_count_ = 0;
  std::array<int, 6> pvt_gated_run_{};  ///< consecutive PVT updates in which each axis was gated
  bool reacquire_pvt_ = false;  ///< the next update_pvt is ungated (after a PVT runaway reset)
  bool ungated_ = false;        ///< scalar_update skips the gate (during that update)
  /// Position and velocity variance after a PVT runaway reset: (1 km)^2 and (10 m/s)^2, so the
  /// next solution is taken nearly as it is.
  static constexpr double kReacquirePosVar_m2 = 1.0e6;
  static constexpr double kReacquireVelVar_m2ps2 = 100.0;
  Vec init_var_ = Vec::Zero();  ///< initial variances (covariance repair, resets)
  std::array<bool, N> dead_{};  ///< find_dead_states(); a reset with a variance revives one
  bool dense_loops_ = false;    ///< set_dense_covariance_loops()
  int n_live_ = 0;                  ///< the states the covariance loops visit
  /// Consecutive live states [begin, end), ascending.
  struct LiveRun {
    int begin = 0, end = 0;
  };
  std::array<LiveRun, N> runs_{};
  int n_runs_ = 0;
  /// The live navigation-driven columns (below EkfTransition::kNavCols, ascending): the inner index
  /// of propagate()'s products. With all of them live, propagate() passes the identity instead.
  std::array<int, EkfTransition<Layout>::kNavCols> nav_live_{};
  int n_nav_live_ = 0;
  std::span<const LiveRun> live_runs() const { return {runs_.data(), static_cast<std::size_t>(n_runs_)}; }
  Vec3 last_f_enu_mps2_ = Vec3::Zero();  ///< specific force of the last frame of the last interval, ENU
  double clock_bias_m_ = 0.0;
  double clock_drift_mps_ = 0.0;
  bool clock_initialised_ = false;
  double time_offset_hat_s_ = 0.0;
  double time_drift_hat_ = 0.0;
  double drift_t_ref_s_ = std::numeric_limits<double>::quiet_NaN();  ///< set by the first update
  Vec3 lever_arm_hat_b_m_ = Vec3::Zero();
  double tropo_scale_hat_ = 0.0;
  double iono_scale_hat_ = 0.0;
  std::array<std::uint8_t, kGnssErrorChannels> slot_prn_{};
  Eigen::Matrix<double, kGnssErrorChannels, 1> range_err_hat_ = Eigen::Matrix<double, kGnssErrorChannels, 1>::Zero();
  Eigen::Matrix<double, kGnssErrorChannels, 1> rate_err_hat_ = Eigen::Matrix<double, kGnssErrorChannels, 1>::Zero();
};

#define FSW_EKF_EXTERN(L)                                                                                   \
  extern template class EkfTransition<L>;                                                                   \
  extern template void add_sensor_correction<L>(const Eigen::Matrix<double, L::kSize, 1>&, ImuCompensation&); \
  extern template class Ekf<L>;
FSW_FOR_EACH_LAYOUT(FSW_EKF_EXTERN)
#undef FSW_EKF_EXTERN

}  // namespace fsw
