// The two processes of a hardware-in-the-loop run, as library functions so that the commands
// (`sdins bus-sim`, `sdins fsw`) stay thin and the tests can run both on two threads over a
// `loop:` bus:
//
//   run_bus_sim: sim::SensorStream -> hal::can::CanStepEncoder -> bus, with SIM_CONTROL
//                start/end; lockstep (never more than `window_imu` IMU samples beyond the last
//                FSW_ACK) or real time (paced on CLOCK_MONOTONIC per IMU sample).
//   run_fsw:     bus -> hal::CanFswInput -> hal::FswNode, answering with FSW_ACK; exits on the
//                run's SIM_CONTROL end or after idle_timeout_s without frames.
//
// The frames of a lockstep run are exactly those `sdins sil` feeds in-process through
// CanFswInput (same encoder, same order), so the navigation digest is identical.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "tools/fsw_report.hpp"  // digest_hex

#include "hal/can_bus.hpp"
#include "hal/can_protocol.hpp"
#include "hal/can_rx_assembler.hpp"
#include "hal/fsw_node.hpp"
#include "sim/sensor_stream.hpp"

namespace tools {

// ---- bus simulator ------------------------------------------------------------------------------

struct BusSimConfig {
  bool lockstep = true;
  int window_imu = 200;          ///< lockstep: IMU samples allowed beyond the last acknowledged one
  double ack_timeout_s = 10.0;   ///< no progress of the acknowledgements for this long: error
  double speed = 1.0;            ///< real time: time factor (2 = twice as fast)
  int pace_every = 1;            ///< real time: sleep before every n-th IMU sample
  std::uint32_t run_id = 0;      ///< 0: drawn at random (non-zero)
  std::uint64_t seed = 0;        ///< reported in SIM_CONTROL (the stream was made with it)
  double start_retry_s = 0.25;   ///< SIM_CONTROL start / end repeated this often until acknowledged
};

struct BusSimResult {
  bool ok = false;
  std::string error;               ///< why not ok
  std::uint32_t run_id = 0;
  long long steps = 0, imu_sent = 0, frames_sent = 0, control_sent = 0;
  long long gps_epochs = 0, almanac_sent = 0;
  long long imu_rejected = 0, imu_flagged = 0, gps_skipped = 0, gps_rejected = 0, almanac_rejected = 0;
  long long acks_received = 0, foreign_frames = 0, tx_busy_retries = 0;
  long long window_waits = 0;      ///< lockstep: times the window was full
  double window_wait_s = 0.0;      ///< ... total time waited
  long long max_ahead_imu = 0;     ///< largest (IMU sent - IMU acknowledged) when a sample was sent
  bool final_ack = false;          ///< the consumer acknowledged the end with every IMU frame
  hal::can::FswAckFrame last_ack{};
  double wall_s = 0.0;
  // real time
  long long paced = 0;             ///< pacing sleeps
  double late_mean_s = 0.0, late_max_s = 0.0;  ///< how late the sleeps woke
};

/// Plays the stream onto bus (opened by the caller). stop (optional) aborts the run.
BusSimResult run_bus_sim(hal::CanBus& bus, sim::SensorStream& stream, const BusSimConfig& cfg,
                         const std::atomic<bool>* stop = nullptr);
nlohmann::json to_json(const BusSimResult& r);

// ---- flight software --------------------------------------------------------------------------

struct FswRunConfig {
  hal::FswNodeConfig node{};
  bool realtime = false;            ///< SCHED_FIFO attempt, execution times, IMU lateness
  int fifo_priority = 50;
  double idle_timeout_s = 5.0;      ///< no frame for this long ends the run (silent bus)
  int ack_every_imu = 5;            ///< FSW_ACK after this many IMU frames (one minor frame)
  double idle_ack_s = 0.05;         ///< while the bus is quiet, repeat the ack this often
  double late_threshold_s = 0.005;  ///< real time: an IMU frame later than this counts as late
};

enum class FswExit { kEndOfRun, kIdleTimeout, kStopped, kError };
const char* to_string(FswExit e);

struct FswRunResult {
  FswExit exit = FswExit::kError;
  std::string error;                 ///< kError: why
  hal::FswNodeSummary summary{};
  fsw::ExecutiveHealth exec{};
  fsw::FlightAppHealth app{};
  hal::CanRxHealth rx{};
  hal::CanBusStats bus{};
  // run control
  bool run_started = false, end_received = false;
  hal::can::SimControlFrame run{}, end{};
  hal::can::FswAckFrame last_ack{};
  std::uint64_t frames_received = 0, data_frames = 0, imu_frames = 0, imu_delivered = 0;
  std::uint64_t control_frames = 0, control_rejected = 0, foreign_acks = 0, acks_sent = 0, ack_send_failures = 0;
  bool counts_match_end = false;     ///< the end's IMU / data frame counts equal what arrived
  // telemetry
  std::string lcm_url, log_path;
  bool lcm_network = false;
  std::uint64_t lcm_published = 0, lcm_send_failures = 0, lcm_logged = 0, lcm_log_failures = 0;
  // timing
  /// The rate groups' rates the flight configuration sets (exec.nav_rate_hz; / exec.frames_per_ekf)
  double nav_rate_hz = 0.0, ekf_rate_hz = 0.0;
  double wall_s = 0.0, idle_timeout_s = 0.0;
  bool realtime = false, sched_fifo = false;
  std::string sched_note;
  std::uint64_t minor_frames_timed = 0;
  double exec_mean_s = 0.0, exec_max_s = 0.0;
  std::vector<double> frame_exec_s;  ///< real time: each minor frame's execution [s] (the 200 Hz group)
  /// The same frames' CPU time on the receiving thread [s]: an overrun whose CPU time is within the
  /// budget was a stall (preemption, the hypervisor), not execution.
  double exec_cpu_max_s = 0.0;
  double exec_max_t_s = 0.0;        ///< INS time at the end of the longest frame (wall time)
  std::string exec_max_work;        ///< what that frame did ("released the 1 Hz group", ...)
  std::uint64_t overruns_execution = 0;  ///< frames over the budget in CPU time
  std::uint64_t overruns_stalled = 0;    ///< frames over the budget in wall time only
  hal::EkfGroupTimes ekf_group{};    ///< the 1 Hz thread's runs
  std::uint64_t imu_lateness_n = 0, imu_late = 0;
  double imu_lateness_mean_s = 0.0, imu_lateness_max_s = 0.0, late_threshold_s = 0.0;
};

/// Runs the flight software on bus (opened by the caller) until the end of the run, a silent bus
/// or stop. Warnings (SCHED_FIFO refused, telemetry fallback) go to warn when given.
FswRunResult run_fsw(hal::CanBus& bus, const FswRunConfig& cfg, const std::atomic<bool>* stop = nullptr,
                     void (*warn)(const std::string&) = nullptr);
nlohmann::json to_json(const FswRunResult& r);

}  // namespace tools
