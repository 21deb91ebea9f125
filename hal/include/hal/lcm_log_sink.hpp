// Writing a run to LCM (telemetry and/or log) and reading a log back as flight-software inputs.
//
// LcmLogSink: typed writers for every channel. Each message is encoded into the sink's own
// fixed buffer and handed to LcmTelemetry as bytes (no allocation per message); the log event's
// timestamp is the message's utime, i.e. the navigation time in microseconds, so lcm-logplayer
// replays a simulated run at its own pace.
//
// LcmReplayReader: reads a log's IMU, GNSS_RAW and GPS_ALMANAC channels (names configurable), and
// GNSS_PVT solutions when LcmReplayConfig::gnss_pvt_channel names it (off by default: a replay reads
// them when its filter configuration takes solutions, gnss.source = "pvt"), and returns them as
// flight-software input events (fsw::InputEvent: an IMU sample keeps the sensor's counter and status,
// a solution becomes fsw::GnssPvtMeasurement) in time order (t_s, then log order for equal times). Inputs may be
// logged slightly out of order (e.g. an epoch written after the IMU samples that followed it); a
// reorder window (reorder_window_s of input time) puts them back in order. Every input's time tag
// passes hal::TimeTagGate (time_tag_gate.hpp) in log order: an input more than the window behind
// the newest accepted input, or more than max_time_jump_s ahead of it, is a jump; a jump alone is
// dropped and counted (time_tag_rejected) and the log goes on, a jump sustained over
// time_base_confirm_inputs consecutive inputs is a new time base (time_base_changes, nothing
// dropped). An input older than one already returned is dropped and counted (out_of_order). The
// rules depend only on the log, not on how far the caller has read, so a single wild time tag can
// neither jump ahead of the data nor make the rest of the log look late. Every event is
// accounted for: log-level rejections (LcmLogReader), per-channel decode/validation statuses
// (LcmInputStats), events on other channels (other_events), IMU counter gaps.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fsw/ekf.hpp"
#include "fsw/executive.hpp"
#include "fsw/gps_orbit.hpp"
#include "fsw/input_event.hpp"
#include "fsw/strapdown.hpp"
#include "hal/lcm_channels.hpp"
#include "hal/lcm_convert.hpp"
#include "hal/lcm_log.hpp"
#include "hal/lcm_telemetry.hpp"
#include "hal/time_tag_gate.hpp"

namespace hal {

/// Size of the sink's encode buffer; every project message type fits (tested).
inline constexpr std::size_t kLcmMaxEncodedBytes = 4096;

class LcmLogSink {
 public:
  /// Opens the telemetry: network per cfg.lcm_url (use "none" for a log-only sink) and the log file.
  LcmLogStatus open(const LcmTelemetryConfig& cfg) { return telemetry_.open(cfg); }
  LcmLogStatus close() { return telemetry_.close(); }

  /// IMU sample with the sink's running counter (0, 1, 2, ...) and the given status bits.
  LcmLogStatus write_imu(const fsw::ImuSample& sample, std::int16_t status = 0);
  /// IMU sample with the sensor's own counter and status.
  LcmLogStatus write_imu(const ImuRecord& record);
  LcmLogStatus write_gnss(const fsw::GnssRawEpoch& epoch);
  /// t_s: when the elements were received (navigation time scale).
  LcmLogStatus write_almanac(const fsw::GpsAlmanac& almanac, double t_s);
  LcmLogStatus write_nav(const fsw::NavState& nav, bool valid, bool ekf_updated);
  LcmLogStatus write_nav(const fsw::FrameOutput& frame) { return write_nav(frame.nav, frame.nav_valid, frame.ekf_updated); }
  LcmLogStatus write_truth(double t_s, const fsw::Vec3& llh, const fsw::Vec3& vel_enu_mps, const fsw::Mat3& C_b_n);
  /// A reference without attitude on TRUTH (e.g. the RTK solution of a recording; attitude NaN).
  LcmLogStatus write_reference(double t_s, const fsw::Vec3& llh, const fsw::Vec3& vel_enu_mps);
  /// A GNSS position/velocity solution on GNSS_PVT.
  LcmLogStatus write_pvt(const GnssPvtSample& pvt);

  /// The EKF state after a run of the 1 Hz group (call when frame.ekf_ran).
  template <class Layout>
  LcmLogStatus write_ekf(const fsw::Executive<Layout>& exec) {
    to_msg(exec.ekf_output(), exec.compensation(), ekf_msg_);
    return publish(kLcmChannelEkfState, ekf_msg_);
  }
  template <class Layout>
  LcmLogStatus write_ekf(const fsw::Ekf<Layout>& ekf, const fsw::ImuCompensation& comp, double t_s) {
    to_msg(ekf, comp, t_s, ekf_msg_);
    return publish(kLcmChannelEkfState, ekf_msg_);
  }
  /// Health after a run of the 1 Hz group: executive counters, conversion counters and the
  /// frame's EKF report.
  template <class Layout>
  LcmLogStatus write_health(const fsw::Executive<Layout>& exec, const fsw::FrameOutput& frame,
                            const fsw::GnssConversionStats& conversion) {
    return write_health(frame.ekf_t_s, exec.health(), conversion, frame, exec.config().ekf.gate_chi2);
  }
  LcmLogStatus write_health(double t_s, const fsw::ExecutiveHealth& health, const fsw::GnssConversionStats& conversion,
                            const fsw::FrameOutput& frame, double gate_chi2);

  LcmTelemetry& telemetry() { return telemetry_; }
  const LcmTelemetry& telemetry() const { return telemetry_; }
  std::uint64_t encode_failures() const { return encode_failures_; }

 private:
  template <class Msg>
  LcmLogStatus publish(const char* channel, const Msg& msg) {
    const int n = msg.encode(buf_, 0, static_cast<int>(sizeof(buf_)));
    if (n < 0) {
      ++encode_failures_;
      return LcmLogStatus::kTooLarge;
    }
    return telemetry_.publish(channel, buf_, static_cast<std::size_t>(n), msg.utime);
  }

  LcmTelemetry telemetry_;
  std::int32_t imu_counter_ = 0;
  std::uint64_t encode_failures_ = 0;
  alignas(8) std::uint8_t buf_[kLcmMaxEncodedBytes] = {};
  // The two large messages live here rather than on the caller's stack.
  sdins::ekf_state_t ekf_msg_{};
  sdins::filter_health_t health_msg_{};
};

// ---------------------------------------------------------------------------------------------

struct LcmReplayConfig {
  std::string imu_channel = kLcmChannelImu;
  std::string gnss_channel = kLcmChannelGnssRaw;
  std::string almanac_channel = kLcmChannelGpsAlmanac;
  /// GNSS position/velocity solutions (sdins.gnss_pvt_t); empty: not read (counted as other events).
  std::string gnss_pvt_channel;
  GnssPvtLimits pvt_limits{};
  double reorder_window_s = 1.0;  ///< how far (input time) a logged input may lag behind later ones
  double max_time_jump_s = 2.0;   ///< a step ahead of the newest input larger than this is a time jump
  int time_base_confirm_inputs = 5;  ///< consecutive inputs that make a time jump a new time base
  ImuInputLimits imu_limits{};
  std::size_t max_event_bytes = 64u << 20;
};

struct LcmReplayStats {
  LcmInputStats imu, gnss, almanac;  ///< per input channel: accepted and each rejection reason
  LcmInputStats gnss_pvt;            ///< GNSS_PVT (all zero while the channel is not read)
  std::uint64_t other_events = 0;    ///< events on other channels (outputs, truth, foreign data)
  std::uint64_t imu_counter_gaps = 0;     ///< accepted samples whose counter is not previous + 1
  std::uint64_t imu_counter_missing = 0;  ///< samples missing according to forward counter jumps
  std::uint64_t out_of_order = 0;    ///< inputs older than one already returned: dropped
  std::uint64_t time_tag_rejected = 0;  ///< time-tag outliers (TimeTagGate): dropped, the log goes on
  std::uint64_t time_base_changes = 0;  ///< sustained time jumps taken as a new time base
  double last_time_base_jump_s = 0.0;   ///< size of the last one
  double last_time_base_at_s = 0.0;     ///< first input time of the last new base
  std::uint64_t delivered = 0;       ///< inputs returned by next()

  std::uint64_t rejected() const {
    return imu.rejected() + gnss.rejected() + almanac.rejected() + gnss_pvt.rejected() + out_of_order +
           time_tag_rejected;
  }
};

/// At most how many IMU samples a log of log_bytes can hold on imu_channel: one per smallest IMU
/// event (the event header, the channel name, an encoded sdins.imu_sample_t). A bound for
/// reserving arrays before reading, so they never regrow.
std::uint64_t max_imu_samples(std::uint64_t log_bytes, const std::string& imu_channel);

class LcmReplayReader {
 public:
  LcmLogStatus open(const std::string& path, const LcmReplayConfig& cfg = {});
  /// The next input in time order (kOk) or kEndOfLog.
  LcmLogStatus next(fsw::InputEvent& in);
  /// The same as an event source of the one driver (fsw/driver.hpp): the next input, held here
  /// until the following call, or nullptr at the end of the log or on a read error (status() says
  /// which: kEndOfLog at the end).
  const fsw::InputEvent* next() {
    status_ = next(event_);
    return status_ == LcmLogStatus::kOk ? &event_ : nullptr;
  }
  /// The status of the last next(): kOk while inputs come, then kEndOfLog or the read error.
  LcmLogStatus status() const { return status_; }

  const LcmReplayStats& stats() const { return stats_; }
  const LcmLogReadStats& log_stats() const { return log_.stats(); }
  const std::string& error() const { return log_.error(); }

 private:
  /// A heap entry: the input's order key and where it waits (slots_). The inputs themselves
  /// (864 bytes each) stay put while the heap moves its 24-byte keys.
  struct Pending {
    double t_s;
    std::uint64_t seq;
    std::uint32_t slot;
  };
  /// The heap's order: time, then arrival (seq is unique, so the order is total and the delivery
  /// order does not depend on how the heap arranges its entries).
  static bool later_pending(const Pending& a, const Pending& b);
  /// Decodes one event into pending_ (or counts why not).
  void take(const LcmLogEvent& ev);
  void push(fsw::InputEvent&& in);
  void enqueue(fsw::InputEvent&& in);

  LcmLogReader log_;
  LcmReplayConfig cfg_{};
  LcmReplayStats stats_{};
  std::vector<Pending> pending_;  ///< min-heap on (t_s, seq)
  std::vector<fsw::InputEvent> slots_;     ///< the pending inputs, by Pending::slot
  std::vector<std::uint32_t> free_slots_;  ///< slots_ not in use
  TimeTagFilter<fsw::InputEvent> gate_;
  std::uint64_t seq_ = 0;
  bool eof_ = false;
  bool have_newest_ = false;
  double newest_t_s_ = 0.0;
  bool have_delivered_ = false;
  double last_delivered_t_s_ = 0.0;
  bool have_counter_ = false;
  std::int32_t last_counter_ = 0;
  fsw::InputEvent event_{};  ///< what next() hands out
  LcmLogStatus status_ = LcmLogStatus::kOk;
};

}  // namespace hal
