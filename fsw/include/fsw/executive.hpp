// The rate-group executive of the flight software: one minor frame per call of tick().
//
//   200 Hz rate group: IMU compensation -> coning/sculling frame builder -> strapdown step ->
//                      EKF accumulation (the transition-matrix integrals)
//   1 Hz rate group:   EKF propagate -> measurement update with the GNSS epoch -> feedback
//
// The 1 Hz group runs inside the minor frame in which it falls due, after the 200 Hz group (the
// order of a rate-monotonic schedule on one core): it is due every frames_per_ekf navigation frames
// and runs as soon as a GNSS epoch whose time tag lies within max_gnss_age_s of the INS time is
// available; if none arrives within gnss_wait_frames frames after it fell due, it propagates
// without a measurement (counted). The measurement is aligned to the INS time tag: the solution
// is extrapolated from the frame end to the epoch's time with the frame's velocity and
// acceleration.
//
// A GNSS position/velocity solution (FrameInput::pvt, the loosely coupled update) has its own
// pending slot, handled like the raw epoch's (aligned to the INS time, stale/replaced/invalid
// counted): a due EKF step runs as soon as either is ready. When both are ready the raw epoch is
// used and the solution is dropped (pvt_unused); a solution that is ready while the raw epoch is
// not (yet) is used. With frames_per_ekf = nav rate / solution rate (50 for 4 Hz) the EKF follows
// the solutions, one update per solution.
//
// Everything arrives through FrameInput and leaves through FrameOutput and Health: no clocks, no
// I/O, no allocation; the same inputs give bit-identical outputs. Frame overruns are measured by
// the caller (HAL), which passes the previous tick's execution time in.
#pragma once

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
  X(std::uint32_t, fsw_errors, "fsw calls that returned an unexpected status")
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
  bool nav_valid = false;     ///< a navigation frame completed in this tick
  NavState nav{};             ///< solution at the end of the last completed frame (after feedback)
  bool ekf_ran = false;
  bool ekf_updated = false;
  EkfUpdateReport report{};
};

template <class Layout>
class Executive {
 public:
  Status init(const ExecutiveConfig& cfg, const NavState& initial);
  Status tick(const FrameInput& in, FrameOutput& out);

  const ExecutiveHealth& health() const { return health_; }
  const Ekf<Layout>& ekf() const { return ekf_; }
  const Strapdown& ins() const { return ins_; }
  const ImuCompensation& compensation() const { return comp_; }
  const ExecutiveConfig& config() const { return cfg_; }

 private:
  void run_ekf(FrameOutput& out);
  /// The solution at time t_s, extrapolated back (or forward) from the frame end.
  NavState aligned(double t_s) const;

  ExecutiveConfig cfg_{};
  bool initialised_ = false;
  FrameBuilder builder_{};
  Strapdown ins_{};
  ImuCompensation comp_{};
  Ekf<Layout> ekf_{};
  ExecutiveHealth health_{};
  GnssEpoch pending_{};
  bool have_pending_ = false;
  GnssPvtMeasurement pending_pvt_{};
  bool have_pending_pvt_ = false;
  int frames_since_ekf_ = 0;
  bool have_last_sample_ = false;
  double last_sample_t_s_ = 0.0;
  Vec3 last_accel_enu_mps2_ = Vec3::Zero();
};

extern template class Executive<Layout15>;
extern template class Executive<Layout24>;
extern template class Executive<Layout15Full>;
extern template class Executive<Layout24Full>;
extern template class Executive<Layout15Conv>;
extern template class Executive<LayoutDiag>;

}  // namespace fsw
