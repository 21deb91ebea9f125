// The flight-software node: the thin glue (PX4 style) that binds fsw::FlightApp to the outside
// world, the host's driver of the one driver loop (fsw/driver.hpp: fsw::drive(source, node)).
// Inputs arrive already decoded from an event source (the CAN receive assembler, an LCM log);
// the node owns the flight application of the layout the configuration names (an
// fsw::FlightDriver) and its own observers around it: the input log (so every run can be
// replayed), the 1 Hz group's thread, the LCM telemetry (NAV_SOLUTION at nav_decimation of the
// 200 Hz frames; EKF_STATE and FILTER_HEALTH after every 1 Hz EKF run) and a digest of every
// navigation frame's solution, so two runs can be compared bit for bit (SIL vs HIL, replay). A
// harness adds its own observer to step() (fsw::drive(source, node, observer)).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "fsw/filter_model.hpp"
#include "fsw/flight_app.hpp"
#include "hal/lcm_log_sink.hpp"

namespace hal {

struct FswNodeConfig {
  /// 15 or 24 (fsw/filter_model.hpp), flown as Layout15Full / Layout24Full; open() refuses others.
  fsw::FilterModel model = fsw::FilterModel::k24;
  /// The flight configuration: what cfg::load_flight_config reads (config/default.toml and a data
  /// set's file on top); the initialiser is only the schema's field defaults.
  fsw::FlightAppConfig app{};
  LcmTelemetryConfig telemetry{};  ///< network URL ("none": off) and the log path ("": no log)
  int nav_decimation = 10;         ///< NAV_SOLUTION every n-th 200 Hz frame (10: 20 Hz)
  bool log_inputs = true;          ///< write IMU, GNSS_RAW, GPS_ALMANAC (makes the log replayable)
  /// Where the 1 Hz group runs (fsw/executive.hpp): on its own thread at a lower priority than the
  /// caller's (the 200 Hz group), or inline in the 200 Hz tick.
  enum class EkfGroup : std::uint8_t { kThread, kInline };
  EkfGroup ekf_group = EkfGroup::kThread;
  /// false (lockstep, virtual time): before the frame at which a 1 Hz correction lands, the 200 Hz
  /// group waits for the 1 Hz thread, so the outputs are bit-identical to kInline and to every other
  /// lockstep harness. true (real time): it never waits; a late correction is counted (ekf_late)
  /// and lands when ready.
  bool realtime = false;
};

/// Execution times of the 1 Hz group's runs on its thread (steady clock) [s].
struct EkfGroupTimes {
  std::vector<double> exec_s;
  std::uint64_t waits = 0;       ///< lockstep: frames at which the 200 Hz group waited for it
  double wait_max_s = 0.0;       ///< ... the longest wait
};

struct FswNodeSummary {
  bool initialised = false;
  double init_t_s = 0.0;
  std::uint64_t nav_frames = 0;
  /// Minor frames the flight application closed (FrameOutput::frame_closed: before initialisation
  /// too, a frame's worth of levelling samples each).
  std::uint64_t minor_frames = 0;
  std::uint64_t digest = 0;   ///< FNV-1a over every frame's (t, llh, vel, quaternion) bytes
  fsw::NavState last_nav{};
};

class FswNode {
 public:
  FswNode();
  ~FswNode();
  FswNode(const FswNode&) = delete;
  FswNode& operator=(const FswNode&) = delete;

  /// kBadConfig for an invalid flight configuration; the log status when the log cannot be opened.
  /// error receives a one-line reason.
  bool open(const FswNodeConfig& cfg, std::string& error);
  /// One input event, the node's only way in (fsw::drive calls it): logged (with log_inputs: IMU
  /// with the sensor's counter and status, imu_counter -1 lets the sink count; GNSS_RAW; GNSS_PVT;
  /// GPS_ALMANAC at ev.t_s), then handed to the flight application. An IMU event may complete a
  /// minor frame (frame_completed(), last_frame()), whose outputs the node publishes. Before
  /// open(): ignored (kNotInitialised).
  fsw::Status step(const fsw::InputEvent& ev);
  /// The same with a harness' observer around it (fsw/driver.hpp).
  template <class Observer>
  fsw::Status step(const fsw::InputEvent& ev, Observer& obs) {
    obs.before(ev);
    const fsw::Status st = step(ev);
    obs.after(ev, st, last_frame());
    return st;
  }
  /// Truth (simulator runs only) on the TRUTH channel.
  void on_truth(double t_s, const fsw::Vec3& llh, const fsw::Vec3& vel_enu_mps, const fsw::Mat3& C_b_n);
  /// Measured execution time of the previous minor frame (real-time mode).
  void set_prev_tick_exec_s(double s);
  /// Flushes and closes the log (hal::OutputFile: renamed into place only when complete).
  bool close(std::string& error);
  /// Ends the run without its log: the log's temporary file is removed, the target left as it was
  /// (an interrupted replay, docs/faults.md).
  void abort();

  const FswNodeSummary& summary() const { return summary_; }
  const fsw::FlightAppHealth& app_health() const;
  const fsw::ExecutiveHealth& exec_health() const;
  const LcmLogSink& sink() const { return sink_; }
  /// Whether the last IMU event completed a minor frame, and its output.
  const fsw::FrameOutput& last_frame() const;
  bool frame_completed() const { return frame_done_; }
  /// The navigation part of the EKF's published 1-sigma after its last run (as on EKF_STATE):
  /// position E, N, U [m], velocity E, N, U [m/s]; NaN before the first run.
  const std::array<double, 6>& last_ekf_nav_sigma() const { return nav_sigma_; }
  /// The 1 Hz thread's execution times (empty with EkfGroup::kInline).
  const EkfGroupTimes& ekf_group_times() const { return group_times_; }

  struct App;  ///< the flight driver of the chosen layout (defined in the .cpp)
  struct GroupThread;  ///< the 1 Hz group's thread (defined in the .cpp)
  struct Observers;    ///< the node's own observers of its driver (defined in the .cpp)

 private:
  void before_event(const fsw::InputEvent& ev);
  void after_event(const fsw::InputEvent& ev, const fsw::FrameOutput& out);
  void after_frame(const fsw::FrameOutput& out);
  /// Stops the 1 Hz thread after its current run (close, abort, destructor).
  void stop_group_thread();
  std::unique_ptr<App> app_;
  std::unique_ptr<GroupThread> group_;
  EkfGroupTimes group_times_{};
  FswNodeConfig cfg_{};
  LcmLogSink sink_;
  std::array<double, 6> nav_sigma_{NAN, NAN, NAN, NAN, NAN, NAN};
  bool frame_done_ = false;
  bool closed_ = false;
  FswNodeSummary summary_{};
};

}  // namespace hal
