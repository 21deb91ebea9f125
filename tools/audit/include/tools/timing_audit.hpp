// Timing audit of the flight-software rate groups (`sdins audit timing`, docs/audits.md): the
// flight application flies a whole scenario on the wiring of the Monte Carlo (truth simulator ->
// IMU and GPS error models -> raw receiver epochs and IMU samples -> fsw::FlightApp<Layout>),
// initialised in flight from the GNSS as HIL is (TimingAuditConfig::init_mode), and every call
// into it is timed with the steady clock. The two rate groups are timed apart (the 1 Hz group runs
// with exec.ekf_group_inline = false, after the frame that released it).
//
// Tasks (the `groups` of the JSON), per layout:
//   mech_200hz/<L>  the 200 Hz group: every minor frame of the whole flight, initialisation
//                   included: its on_gnss call when an epoch arrived in it (satellite positions;
//                   before initialisation the initialisation attempt) and its on_imu calls (before
//                   initialisation levelling, grouped by a frame's samples; after it
//                   Executive::tick: compensation, coning/sculling, strapdown, transition
//                   accumulation, release of the 1 Hz group, landing of its correction).
//   ekf_1hz/<L>     the 1 Hz group: each run_ekf_group() (propagate, update, correction).
// and any per-frame stage registered in TimingAuditConfig::frame_stages (the extension point for
// the HAL's bus decode, see there). The worst unpreempted 200 Hz frame of each layout is reported
// with the work it did (LayoutTiming::worst_frame_*), and the initialisation frame apart.
//
// Slips. 200 Hz: frames not finished before the next frame's release in the single-core schedule
// below. 1 Hz: runs that, given only the time the 200 Hz group leaves in each frame after their
// release, do not finish before the frame at which their correction lands (ekf_latency_frames).
//
// Each layout flies in its own pass over identical inputs (same seed), so no executive evicts
// another's state from the cache between ticks. The timer's own cost (median of back-to-back
// clock reads) is subtracted from every sample.
//
// Preemption: on a time-shared host a tick during which the scheduler ran another thread measures
// the host, not the task (the scheduler tick is 4 ms). The thread's context-switch counters
// (getrusage RUSAGE_THREAD) are read around every timed call, outside the timed interval; samples
// with a switch are counted (`preempted`) and left out of the statistics, and their wall time
// is kept in max_including_preempted_us.
//
// Release jitter: in the SIL every tick is released at its exact virtual time (the IMU time tags on
// the 5 ms grid), so virtual-time release jitter is zero by construction. What is reported instead
// is the start delay each tick would see on one core at real time, with the measured execution
// times, if ticks ran back to back on their 5 ms grid: start_k = max(k * 5 ms, finish_(k-1)),
// jitter = start_k - k * 5 ms (non-zero only when the previous tick overran its frame); a preempted
// sample enters the schedule with its task's largest unpreempted time. Interrupts,
// cache effects of other software and the HAL are not modelled. For the 1 Hz group the interval
// between its runs in navigation frames (200 nominal; more when it had to wait for a late epoch) is
// reported too.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "fsw/executive.hpp"
#include "fsw/flight_app.hpp"
#include "sim/scenario.hpp"
#include "tools/timing_stats.hpp"

namespace tools {

/// A per-frame stage timed as its own task: run once per minor frame, before the executive's tick.
/// EXTENSION POINT (bus decode, HAL issue): the HAL's decoder plugs in here with `prepare` encoding
/// the frame's IMU samples and GNSS epoch into bus frames the way the simulated bus would carry
/// them (untimed: that is the sensor side) and `run` decoding them into the flight software's
/// input (timed: that is flight code), named "bus_decode".
struct FrameStage {
  std::string name;
  std::function<void(const fsw::FrameInput&)> prepare;  ///< untimed; may be empty
  std::function<void()> run;                            ///< timed
};

struct TimingAuditConfig {
  /// Layouts to fly: any of Layout15, Layout24, Layout15Full, Layout24Full. The plain layouts run
  /// with white measurement noise, the Full ones with the GPS error states (as sdins montecarlo).
  std::vector<std::string> layouts{"Layout15", "Layout24", "Layout15Full", "Layout24Full"};
  std::vector<FrameStage> frame_stages;
  int run = 0;  ///< Monte Carlo run index whose seed draws the errors (seed = scenario seed + run)
  /// kTrack: in-motion initialisation from the GNSS as HIL flies (the frames before and at it are
  /// timed too); kGiven: the Monte Carlo's start from the run's given state.
  fsw::InitMode init_mode = fsw::InitMode::kTrack;
};

struct TaskTiming {
  std::string name;         ///< "mech_200hz/Layout24", "ekf_1hz/Layout24", or a stage's name
  std::string layout;       ///< empty for frame stages
  std::string description;
  double nominal_rate_hz = 0;
  TimingStats stats;                ///< samples without a context switch
  long preempted = 0;               ///< samples left out: the thread was switched out during the call
  double max_including_preempted_us = 0;
  double cpu_share = 0;             ///< total execution time / flight duration: fraction of one core at real time
  double release_jitter_max_us = 0; ///< single-core schedule at real time (see the file comment)
  double release_jitter_p99_us = 0;
  long deadline_misses = 0;         ///< releases whose run finished after its deadline (= slips)
  long slips = 0;                   ///< 200 Hz: frames not finished at the next frame's release; 1 Hz: runs
                                    ///< not finished before the frame at which their correction lands
  double response_max_us = 0;       ///< ekf_1hz: longest release-to-finish time in the single-core schedule
  int interval_frames_min = 0;      ///< ekf_1hz only: navigation frames between runs
  int interval_frames_max = 0;
};

struct LayoutTiming {
  std::string layout;
  double fsw_cpu_share = 0;  ///< all of this layout's tasks (and the frame stages)
  long ekf_updates = 0;
  long fsw_errors = 0;
  int sats_min = 0, sats_median = 0, sats_max = 0;  ///< satellites in the epochs the EKF used
  double wall_s = 0;
  double worst_frame_us = 0;       ///< the longest minor frame without a context switch
  long worst_frame_index = -1;     ///< its index (0: the first frame)
  double worst_frame_t_s = 0;      ///< its navigation time at the frame end
  std::string worst_frame_work;    ///< what it did (raw-epoch conversion, 200 Hz group, release, landing)
  long init_frame = -1;            ///< the frame in which the flight application initialised (-1: given start)
  double init_frame_us = 0;        ///< its execution time
  bool init_frame_preempted = false;
  long ekf_slips_counted = 0;      ///< the executive's ekf_slips / ekf_late (lockstep: 0)
  long ekf_late_counted = 0;
};

struct TimingAuditResult {
  std::string scenario;
  double flight_s = 0;
  long frames = 0;       ///< minor frames (ticks) per layout
  double timer_overhead_ns = 0;
  std::vector<TaskTiming> tasks;
  std::vector<LayoutTiming> layouts;
};

/// Flies the scenario once per layout. Throws std::runtime_error for an unknown layout, a
/// scenario the SIL cannot fly or an executive that fails to initialise.
TimingAuditResult run_timing_audit(const sim::Scenario& sc, const TimingAuditConfig& cfg);

}  // namespace tools
