// The rate-group executive of the flight software: two rate groups with a fixed hand-off, and the
// scheduler that divides each minor frame among them (as F Prime's rate-group driver divides one
// tick among its rate groups).
//
//   200 Hz group, NavGroup:      IMU compensation -> coning/sculling frame builder -> strapdown
//                                step -> accumulation of the filter's transition matrix
//                                (EkfTransition); at a release it hands over the closed interval,
//                                at a landing it applies the correction
//   1 Hz group, EkfGroup:        Ekf::propagate over the released interval -> measurement update
//                                with the GNSS epoch (or solution) -> the correction
//   scheduler, Executive::tick(): the tick's health, the pending GNSS epoch / solution, then per
//                                IMU sample the 200 Hz group and, after each navigation frame,
//                                the 1 Hz group's landing and release; Executive::run_ekf_group()
//                                runs the released 1 Hz group (inline or on the caller's thread)
//
// RELEASE. The 1 Hz group falls due every frames_per_ekf navigation frames and is released as
// soon as a GNSS epoch whose time tag lies within max_gnss_age_s of the INS time is available; if
// none arrives within gnss_wait_frames frames after it fell due, it is released without a
// measurement (propagation only, counted). At the release frame R the 200 Hz group fills the
// request (EkfRequest: the closed transition interval, the measurement, the INS solution aligned
// to the measurement's time tag: extrapolated from the frame end with the frame's velocity and
// acceleration, and the frame's body rate) and switches to its second transition accumulator, so
// it integrates the next interval while the 1 Hz group works on this one. Nothing the 1 Hz group
// reads is written by the 200 Hz group until the correction has landed, and vice versa.
//
// CORRECTION. The 1 Hz group returns the estimate x at frame R (EkfResult) and resets its own.
// The 200 Hz group applies it at frame R + ekf_latency_frames (L): the navigation part propagated
// over the L frames by the transition accumulated since R (dx_nav(R+L) = Phi_nav(R -> R+L) x,
// which carries the sensor-error states' effect on those frames), the sensor part added to the
// IMU compensation. So the correction lands at a frame fixed by the release, not by when the 1 Hz
// group happened to finish: with the same inputs every harness gets bit-identical outputs,
// whether the 1 Hz group runs inside tick() (ekf_group_inline: lockstep on one thread: Monte
// Carlo, diagnosis, tests, the Cortex-M replay) or on its own lower-priority thread or interrupt
// that the 200 Hz group waits for at frame R + L in lockstep (hal::FswNode). In real time, a
// correction not ready at R + L is counted (ekf_late) and lands at the first frame after it is
// ready, propagated over the longer span (still consistent, no longer bit-identical); a release
// that falls due while the previous correction has not landed is deferred (ekf_slips) and its
// interval keeps growing until the release can happen.
//
// FrameOutput reports the 1 Hz group in the frame its correction landed (ekf_ran, ekf_updated,
// report; ekf_t_s is the epoch's release time); ekf_output() is what telemetry reads of it.
//
// A GNSS position/velocity solution (FrameInput::pvt, the loosely coupled update) has its own
// pending slot, handled like the raw epoch's (aligned to the INS time, stale/replaced/invalid
// counted): a due release happens as soon as either is ready. When both are ready the raw epoch
// is used and the solution is dropped (pvt_unused); a solution that is ready while the raw epoch
// is not (yet) is used. With frames_per_ekf = nav rate / solution rate (50 for 4 Hz) the EKF
// follows the solutions, one update per solution.
//
// Everything arrives through FrameInput and leaves through FrameOutput, ekf_output() and Health:
// no clocks, no I/O, no allocation, no locks (the hand-off is one atomic state word, single
// producer / single consumer). Execution times are measured by the caller (HAL), which passes
// them in (prev_tick_exec_s, note_ekf_group_exec_s).
#pragma once

#include <atomic>
#include <cstdint>

#include "fsw/ekf.hpp"
#include "fsw/gnss.hpp"
#include "fsw/imu_compensation.hpp"
#include "fsw/status.hpp"
#include "fsw/strapdown.hpp"

namespace fsw {

/// The rate groups' nominal rates: the one place that says 200 Hz and 1 Hz.
inline constexpr double kNavRate_hz = 200.0;  ///< 200 Hz group (navigation frames)
inline constexpr double kEkfRate_hz = 1.0;    ///< 1 Hz group (EKF) with a 1 Hz receiver

struct ExecutiveConfig {
  int imu_samples_per_frame = 5;    ///< IMU rate / navigation rate (1000 / 200)
  double nav_rate_hz = kNavRate_hz;
  int frames_per_ekf = static_cast<int>(kNavRate_hz / kEkfRate_hz);  ///< 200 Hz / 1 Hz
  int gnss_wait_frames = 40;        ///< how long a due EKF step waits for its epoch (0.2 s)
  double max_gnss_age_s = 0.25;     ///< epochs older than this at use are stale
  double frame_budget_s = 0.005;    ///< a tick that took longer is an overrun
  /// Frames after its release at which the 1 Hz group's correction lands (1 <= L < frames_per_ekf;
  /// 10 frames = 50 ms: the 1 Hz group's deadline; see the file header).
  int ekf_latency_frames = 10;
  /// true: tick() runs the 1 Hz group itself right after releasing it (one thread, lockstep);
  /// false: the caller runs run_ekf_group() (its own thread or interrupt) after out.ekf_released.
  bool ekf_group_inline = true;
  EkfConfig ekf{};
};

/// The executive's health counters, declared once: X(type, name, description). The struct below,
/// the FILTER_HEALTH message conversion and CSV export (hal), the JSON summaries and the Monte
/// Carlo's sums (tools) are generated from these lists, in the message's order (hal/lcm/
/// filter_health_t.lcm, which carries FSW_GNSS_CONVERSION_COUNTERS between the two lists); a
/// counter added here and not to the message fails to compile, and tests/unit/
/// test_health_counters.cpp checks the message definition against the lists both ways.
#define FSW_EXECUTIVE_HEALTH_COUNTERS(X)                                                            \
  X(std::uint32_t, ticks, "minor frames ticked")                                                    \
  X(std::uint32_t, nav_frames, "navigation frames completed")                                       \
  X(std::uint32_t, ekf_runs, "runs of the 1 Hz group")                                              \
  X(std::uint32_t, ekf_updates, "EKF runs with a measurement update")                               \
  X(std::uint32_t, ekf_without_gnss, "EKF runs that had to propagate only")                         \
  X(std::uint32_t, imu_samples, "IMU samples received")                                             \
  X(std::uint32_t, imu_rejected, "non-finite or non-positive dt samples, not used")                 \
  X(std::uint32_t, imu_short_ticks, "ticks with fewer samples than imu_samples_per_frame")          \
  X(std::uint32_t, imu_time_gaps, "consecutive samples further apart than 1.5 dt")                  \
  X(std::uint32_t, frame_rate_mismatch, "1 s windows of frames whose IMU time is off by > 10%")       \
  X(std::uint32_t, gnss_epochs, "raw-converted GNSS epochs received")                               \
  X(std::uint32_t, gnss_stale, "epochs too old when the EKF could use them")                        \
  X(std::uint32_t, gnss_replaced, "epochs overwritten by a newer one before use")                   \
  X(std::uint32_t, gnss_invalid, "malformed epochs (n_obs out of range, non-finite time)")          \
  X(std::uint32_t, pr_used, "pseudorange scalars used")                                             \
  X(std::uint32_t, prr_used, "pseudorange-rate scalars used")                                       \
  X(std::uint32_t, pr_rejected, "pseudorange scalars gated")                                        \
  X(std::uint32_t, prr_rejected, "pseudorange-rate scalars gated")                                  \
  X(std::uint32_t, obs_invalid, "observations with invalid values")                                 \
  X(std::uint32_t, overruns, "ticks that took longer than frame_budget_s")                          \
  X(double, worst_tick_s, "longest measured tick [s]")                                              \
  X(std::uint32_t, fsw_errors, "fsw calls that returned an unexpected status")                     \
  X(std::uint32_t, ekf_slips, "1 Hz releases deferred: the previous correction had not landed")     \
  X(std::uint32_t, ekf_late, "corrections not ready at their frame (landed later)")                 \
  X(std::uint32_t, ekf_overruns, "1 Hz runs longer than their deadline (ekf_latency_frames)")       \
  X(double, worst_ekf_s, "longest measured 1 Hz run [s]")
/// GNSS position/velocity solutions (loosely coupled update).
#define FSW_EXECUTIVE_PVT_COUNTERS(X)                                                               \
  X(std::uint32_t, pvt_received, "solutions received")                                              \
  X(std::uint32_t, pvt_stale, "too old when the EKF could use them")                                \
  X(std::uint32_t, pvt_replaced, "overwritten by a newer solution before use")                      \
  X(std::uint32_t, pvt_invalid, "non-finite time")                                                  \
  X(std::uint32_t, pvt_unused, "ready together with a raw epoch, which was used instead")           \
  X(std::uint32_t, pos_used, "position scalars used")                                               \
  X(std::uint32_t, vel_used, "velocity scalars used")                                               \
  X(std::uint32_t, pos_rejected, "position scalars gated")                                          \
  X(std::uint32_t, vel_rejected, "velocity scalars gated")

/// Health counters, F Prime style telemetry rather than asserts (the lists above).
struct ExecutiveHealth {
#define FSW_DECLARE_HEALTH_FIELD(type, name, doc) type name = 0;
  FSW_EXECUTIVE_HEALTH_COUNTERS(FSW_DECLARE_HEALTH_FIELD)
  FSW_EXECUTIVE_PVT_COUNTERS(FSW_DECLARE_HEALTH_FIELD)
#undef FSW_DECLARE_HEALTH_FIELD
  EkfHealth ekf{};  ///< the filter's numerical/statistical health after the last EKF run
};

inline std::uint32_t merge_health_field(std::uint32_t a, std::uint32_t b) { return a + b; }
inline double merge_health_field(double a, double b) { return a > b ? a : b; }

/// Sum of two runs' counters (worst_tick_s: the larger); the EKF's health is not summed.
inline void add_health_counters(ExecutiveHealth& sum, const ExecutiveHealth& h) {
#define FSW_ADD_HEALTH_FIELD(type, name, doc) sum.name = merge_health_field(sum.name, h.name);
  FSW_EXECUTIVE_HEALTH_COUNTERS(FSW_ADD_HEALTH_FIELD)
  FSW_EXECUTIVE_PVT_COUNTERS(FSW_ADD_HEALTH_FIELD)
#undef FSW_ADD_HEALTH_FIELD
}

struct FrameInput {
  const ImuSample* imu = nullptr;  ///< the raw IMU samples that arrived during this minor frame
  int n_imu = 0;
  const GnssEpoch* gnss = nullptr;  ///< an epoch that arrived during this frame, or nullptr
  const GnssPvtMeasurement* pvt = nullptr;  ///< a position/velocity solution that arrived during this frame
  double prev_tick_exec_s = -1.0;   ///< measured execution time of the previous tick (< 0: unknown)
};

struct FrameOutput {
  /// The IMU sample closed a minor frame (FlightApp::on_imu): after initialisation the executive
  /// ticked (the frame builder's frame was complete); before it, every imu_samples_per_frame-th
  /// sample (levelling, alignment). What a harness that times or counts minor frames reads.
  bool frame_closed = false;
  bool nav_valid = false;     ///< a navigation frame completed in this tick
  NavState nav{};             ///< solution at the end of the last completed frame (after any correction)
  bool ekf_released = false;  ///< this tick released the 1 Hz group (not inline: run run_ekf_group())
  bool ekf_ran = false;       ///< a 1 Hz group's result landed in this tick ...
  bool ekf_updated = false;   ///< ... with a measurement update
  double ekf_t_s = 0.0;       ///< ... of the epoch released at this INS time
  EkfUpdateReport report{};   ///< ... and what its update did
};

/// The 200 Hz -> 1 Hz hand-off: what one filter epoch needs, written by the 200 Hz group before it
/// releases the 1 Hz group (statically allocated in the executive).
template <class Layout>
struct EkfRequest {
  enum class Aid : std::uint8_t { kNone, kRaw, kPvt };
  Aid aid = Aid::kNone;
  int transition = 0;      ///< the closed interval: the executive's accumulator of this index
  GnssEpoch epoch{};
  GnssPvtMeasurement pvt{};
  NavState nav_at_aid{};   ///< the INS solution aligned to the aid's time tag
  Vec3 omega_ib_b_radps = Vec3::Zero();
  double t_s = 0.0;        ///< INS time of the release frame
};

/// The 1 Hz -> 200 Hz hand-off: the correction and what the epoch did.
template <class Layout>
struct EkfResult {
  bool updated = false;
  bool correction_valid = false;  ///< x holds a finite estimate to apply
  Eigen::Matrix<double, Layout::kSize, 1> x = Eigen::Matrix<double, Layout::kSize, 1>::Zero();  ///< estimate at the release frame
  EkfUpdateReport report{};
  EkfOutput<Layout> output{};
  EkfHealth ekf_health{};
  std::uint32_t fsw_errors = 0;
};

/// The hand-off's state word: atomic, and copyable (a copy takes the current value), so an
/// executive can be saved and restored (benchmarks, tests) like any other plain state.
struct HandOffState {
  std::atomic<std::uint8_t> v{0};
  HandOffState() = default;
  HandOffState(const HandOffState& o) : v(o.v.load(std::memory_order_acquire)) {}
  HandOffState& operator=(const HandOffState& o) {
    v.store(o.v.load(std::memory_order_acquire), std::memory_order_release);
    return *this;
  }
  std::uint8_t load(std::memory_order m) const { return v.load(m); }
  void store(std::uint8_t x, std::memory_order m) { v.store(x, m); }
};

/// The 200 Hz group (navigation): IMU compensation -> coning/sculling frame builder -> the frame
/// rate check -> strapdown step -> accumulation of the filter's transition matrix, plus what the
/// scheduler asks of it at a release (the solution aligned to an aid's time tag, the closed
/// interval) and at a landing (the correction). Owns the navigation state; runs on the 200 Hz
/// thread only.
template <class Layout>
class NavGroup {
 public:
  using Vec = Eigen::Matrix<double, Layout::kSize, 1>;
  /// Frame builder and strapdown from cfg and initial; kOk or their status.
  Status configure(const ExecutiveConfig& cfg, const NavState& initial);
  /// Empties the compensation, both transition intervals and the rate window (after configure()).
  void reset(const ExecutiveConfig& cfg);
  /// One raw IMU sample (counted in health): true when it completed a navigation frame (the
  /// strapdown stepped and the frame joined the accumulating interval).
  bool add_sample(const ImuSample& raw, ExecutiveHealth& health);
  /// Release: hands the accumulating interval to the 1 Hz group (returns its index) and starts the
  /// other one empty.
  int hand_over_interval();
  EkfTransition<Layout>& transition(int i) { return transition_[i]; }
  /// Landing: the estimate x of the release frame, its navigation part carried to this frame by
  /// the interval accumulated since (the sensor part into the compensation). kOk or the status of
  /// the solution's correction (nothing applied).
  Status apply_correction(const Vec& x);
  /// The solution at time t_s, extrapolated back (or forward) from the frame end.
  NavState aligned(double t_s) const;
  const Strapdown& ins() const { return ins_; }
  const ImuCompensation& compensation() const { return comp_; }
  int samples_to_frame_end() const { return builder_.samples_to_frame_end(); }

 private:
  /// The frame-rate check of one navigation frame (frame_rate_mismatch).
  void check_frame_rate(double frame_dt_s, ExecutiveHealth& health);

  int substep_frames_ = 10;
  FrameBuilder builder_{};
  Strapdown ins_{};
  ImuCompensation comp_{};
  EkfTransition<Layout> transition_[2]{};
  int acc_ = 0;  ///< transition_[acc_] accumulates; the other is the 1 Hz group's while released
  bool have_last_sample_ = false;
  double last_sample_t_s_ = 0.0;
  // The rate check (frame_rate_mismatch): a window of nav_rate_hz frames, 1 s of IMU time when the
  // configuration matches the IMU (both set at reset), and the current window's frames and IMU time.
  int rate_window_frames_ = 1;
  double rate_window_s_ = 1.0;
  int window_frames_ = 0;
  double window_imu_s_ = 0.0;
  Vec3 last_accel_enu_mps2_ = Vec3::Zero();
};

/// The 1 Hz group (EKF): Ekf::propagate over the released interval -> the measurement update with
/// the request's aid (raw epoch or solution) -> the correction, into the result. Owns the filter;
/// runs on the 1 Hz thread (or inline) only, while the hand-off says released.
template <class Layout>
class EkfGroup {
 public:
  Status init(const EkfConfig& cfg) { return ekf_.init(cfg); }
  /// One epoch of the request rq over the closed interval t.
  void run(const EkfRequest<Layout>& rq, EkfTransition<Layout>& t, EkfResult<Layout>& r);
  const Ekf<Layout>& ekf() const { return ekf_; }

 private:
  Ekf<Layout> ekf_{};
};

/// The executive: the scheduler (the rate-group driver) of the two groups above. tick() divides one
/// minor frame among them: the tick's health, the pending GNSS epoch / solution, then per IMU
/// sample the 200 Hz group and, after each navigation frame, the 1 Hz group's landing and release
/// (the hand-off, the file header).
template <class Layout>
class Executive {
 public:
  Status init(const ExecutiveConfig& cfg, const NavState& initial);
  /// One minor frame: the scheduler.
  Status tick(const FrameInput& in, FrameOutput& out);
  /// The 1 Hz group: runs the released epoch (kOk and nothing done when none is released). With
  /// ekf_group_inline tick() calls it; otherwise the caller does, once per out.ekf_released, on
  /// any one thread other than tick()'s or between two ticks. noinline: it is the 1 Hz group's
  /// task entry, which the stack audit cuts from the 200 Hz task (tick's inline call); inlined
  /// into tick, the cut would miss it.
  [[gnu::noinline]] Status run_ekf_group();
  /// The 1 Hz group has been released and not finished.
  bool ekf_group_busy() const { return group_state_.load(std::memory_order_acquire) == kReleased; }
  /// The next navigation frame is the one at which a released epoch's correction must land
  /// (a lockstep caller waits for run_ekf_group() to finish before the tick that completes it).
  bool ekf_result_due_next_frame() const {
    return group_state_.load(std::memory_order_acquire) != kIdle && health_.nav_frames + 1 >= apply_frame_;
  }
  /// Measured execution time of a 1 Hz run (caller's clock): worst_ekf_s, ekf_overruns.
  void note_ekf_group_exec_s(double s);

  const ExecutiveHealth& health() const { return health_; }
  /// What telemetry reads of the filter: valid after an out.ekf_ran.
  const EkfOutput<Layout>& ekf_output() const { return ekf_output_; }
  /// The filter itself: read it only between run_ekf_group() calls (lockstep callers).
  const Ekf<Layout>& ekf() const { return ekf_group_.ekf(); }
  const Strapdown& ins() const { return nav_.ins(); }
  const ImuCompensation& compensation() const { return nav_.compensation(); }
  /// IMU samples the next tick needs to complete its minor frame (FrameBuilder: the one grouping).
  int samples_to_frame_end() const { return nav_.samples_to_frame_end(); }
  const ExecutiveConfig& config() const { return cfg_; }

 private:
  enum : std::uint8_t { kIdle = 0, kReleased = 1, kDone = 2 };
  /// The tick's execution-time health (overruns, worst_tick_s).
  void note_tick_exec_s(double s);
  /// The frame's GNSS epoch and solution, if any, become pending (or are counted invalid).
  void accept_aids(const FrameInput& in);
  /// After a navigation frame: lands a finished epoch's correction at its frame (counts a late
  /// one) and releases the 1 Hz group when it is due.
  void schedule_ekf(FrameOutput& out);
  /// Release decision of a due frame; fills the request and releases when ready.
  void maybe_release(FrameOutput& out);
  /// Lands the 1 Hz group's result in this frame.
  void land(FrameOutput& out);

  ExecutiveConfig cfg_{};
  bool initialised_ = false;
  NavGroup<Layout> nav_{};  ///< the 200 Hz group
  ExecutiveHealth health_{};
  GnssEpoch pending_{};
  bool have_pending_ = false;
  GnssPvtMeasurement pending_pvt_{};
  bool have_pending_pvt_ = false;
  int frames_since_ekf_ = 0;
  bool slip_counted_ = false;
  std::uint32_t apply_frame_ = 0;
  bool late_counted_ = false;
  EkfOutput<Layout> ekf_output_{};
  // The hand-off (one atomic state word; the request is the 200 Hz group's to write while idle,
  // the result the 1 Hz group's while released).
  HandOffState group_state_{};  ///< kIdle, kReleased, kDone
  EkfRequest<Layout> request_{};
  EkfResult<Layout> result_{};
  EkfGroup<Layout> ekf_group_{};  ///< the 1 Hz group
};

#define FSW_EXECUTIVE_EXTERN(L)          \
  extern template class NavGroup<L>;     \
  extern template class EkfGroup<L>;     \
  extern template class Executive<L>;
FSW_FOR_EACH_LAYOUT(FSW_EXECUTIVE_EXTERN)
#undef FSW_EXECUTIVE_EXTERN

}  // namespace fsw
