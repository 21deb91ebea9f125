// Receiver side of the sdins CAN protocol: frames in arrival order in, complete fsw inputs out
// (IMU samples, raw GPS epochs, almanac entries), with a health counter for every reason a frame
// or a value was not passed on. Fixed-capacity queues, no allocation, no exceptions, no clock
// (the caller passes frame receive times and the current time for the epoch timeout).
//
// Rules (docs/can.md has the table):
//  - Every frame is checked for identifier, length and CRC; failures are counted and dropped.
//  - IMU: the sample counter must advance by one. A jump forward is a dropout: the frame is
//    delivered and the missing samples are counted. A counter already delivered (the last 64 are
//    remembered) is a duplicate; an older one that was never delivered arrived out of order and
//    cannot be delivered any more (the consumer has moved past it in time): both are counted and
//    dropped. A jump of more than kImuResyncSamples either way is a restart of the sender: counted,
//    and the counter is taken as the new reference. Samples the IMU flags unusable (gyro/accel
//    fail, invalid) and samples with absurd values (dt outside (0, 0.1] s, rate above 100 rad/s,
//    specific force above 5000 m/s^2) are counted and not delivered; saturated ones are delivered
//    and counted. A time tag that disagrees with the counter (by more than half a dt) is counted.
//  - GPS: an epoch is delivered when its header and all announced measurement frames have arrived
//    (measurement frames may arrive before their header), or, incomplete and counted, when a newer
//    epoch starts or its first frame is older than the epoch timeout. Epochs with zero or one
//    measurement are delivered and counted. Duplicate and late (older-epoch) frames are counted.
//    Headers and measurements with absurd values are counted; an absurd measurement is left out
//    of its epoch (which can still complete), an absurd header discards its epoch.
//  - Almanac frames are delivered when fsw::almanac_valid() accepts them, counted otherwise.
//  - A full output queue (the consumer did not drain it) counts the lost item.
#pragma once

#include <array>
#include <cstdint>

#include "fsw/gps_orbit.hpp"
#include "fsw/strapdown.hpp"
#include "hal/can_frame.hpp"
#include "hal/can_protocol.hpp"

namespace hal {

/// Counters of everything the assembler saw and every reason it did not pass something on.
struct CanRxHealth {
  // every frame
  std::uint32_t frames = 0;             ///< frames pushed
  std::uint32_t unknown_id = 0;         ///< not one of our identifiers (incl. extended IDs)
  std::uint32_t bad_length = 0;         ///< wrong DLC / payload length for the identifier
  std::uint32_t bad_crc = 0;            ///< CRC mismatch: corrupted payload
  std::uint32_t unsupported_frame = 0;  ///< remote / error frames, classic frames with an FD length
  std::uint32_t control_frames = 0;     ///< valid SIM_CONTROL / FSW_ACK (lockstep flow control): no sensor data
  // IMU
  std::uint32_t imu_frames = 0;         ///< valid IMU_SAMPLE frames
  std::uint32_t imu_delivered = 0;
  std::uint32_t imu_gaps = 0;           ///< counter jumps forward (dropout events)
  std::uint32_t imu_missing = 0;        ///< samples missing in those jumps
  std::uint32_t imu_duplicate = 0;
  std::uint32_t imu_out_of_order = 0;   ///< older than the last delivered sample, never delivered
  std::uint32_t imu_resync = 0;         ///< counter restarts (jump beyond kImuResyncSamples)
  std::uint32_t imu_flagged = 0;        ///< IMU status gyro/accel fail or invalid: not delivered
  std::uint32_t imu_saturated = 0;      ///< delivered with a saturation flag
  std::uint32_t imu_implausible = 0;    ///< absurd dt, rate or specific force: not delivered
  std::uint32_t imu_time_mismatch = 0;  ///< time tag inconsistent with counter and dt (delivered)
  // GPS
  std::uint32_t gps_epoch_frames = 0;
  std::uint32_t gps_meas_frames = 0;
  std::uint32_t gps_epochs_delivered = 0;
  std::uint32_t gps_epochs_incomplete = 0;  ///< delivered without all announced measurements
  std::uint32_t gps_meas_missing = 0;       ///< announced measurements that never arrived
  std::uint32_t gps_epochs_timeout = 0;     ///< incomplete epochs flushed by the timeout
  std::uint32_t gps_epochs_empty = 0;       ///< delivered with zero measurements
  std::uint32_t gps_epochs_single = 0;      ///< delivered with one measurement
  std::uint32_t gps_duplicate = 0;
  std::uint32_t gps_out_of_order = 0;       ///< frames of an epoch already delivered or abandoned
  std::uint32_t gps_seq_resync = 0;         ///< epoch sequence restarts
  std::uint32_t gps_epoch_implausible = 0;  ///< header: n_meas > 16, tow >= 1 week, time not valid
  std::uint32_t gps_meas_implausible = 0;   ///< PRN outside 1..32, index >= 16 or >= n_meas, absurd
                                            ///< pseudorange / rate / C/N0
  std::uint32_t gps_headerless = 0;         ///< epochs abandoned because their header never came
  std::uint32_t gps_meas_orphaned = 0;      ///< measurement frames lost with those epochs
  // almanac
  std::uint32_t almanac_frames = 0;
  std::uint32_t almanac_delivered = 0;
  std::uint32_t almanac_invalid = 0;        ///< fsw::almanac_valid() rejected the elements
  // consumer
  std::uint32_t queue_overflow = 0;         ///< outputs lost because a queue was full

  /// Calls f(name, value) for every counter, in declaration order.
  template <class F>
  void for_each(F&& f) const;
  /// Sum of the counters that mean "something was rejected or lost".
  std::uint32_t rejections() const;
};

struct CanRxConfig {
  double gps_epoch_timeout_s = 0.5;  ///< incomplete epochs are flushed this long after their first frame
};

class CanRxAssembler {
 public:
  static constexpr int kImuQueue = 256;
  static constexpr int kGpsQueue = 4;
  static constexpr int kAlmanacQueue = fsw::kMaxGpsPrn;
  static constexpr std::int32_t kImuResyncSamples = 100000;  ///< 100 s at 1 kHz
  static constexpr int kGpsSeqWindow = 64;                     ///< epochs

  explicit CanRxAssembler(const CanRxConfig& cfg = {}) : cfg_(cfg) {}

  /// One received frame (rx_time_s: its receive time, any monotonic or wall time scale, used only
  /// for the GPS epoch timeout). Returns the frame's decode status (kOk for any of our frames that
  /// passed identifier, length and CRC checks).
  can::CodecStatus push(const CanFrame& f, double rx_time_s);
  /// Time passes without frames: flushes an incomplete epoch older than the timeout.
  void poll(double now_s);
  /// Flushes an incomplete epoch now (end of a log or of a run).
  void flush();

  bool pop_imu(fsw::ImuSample& s);
  bool pop_gps(fsw::GnssRawEpoch& e);
  bool pop_almanac(fsw::GpsAlmanac& a);
  int imu_pending() const { return imu_q_.size(); }
  int gps_pending() const { return gps_q_.size(); }
  int almanac_pending() const { return alm_q_.size(); }

  const CanRxHealth& health() const { return h_; }
  /// IMU sample counter of the last delivered sample (valid once one was delivered).
  std::uint32_t last_imu_counter() const { return imu_last_counter_; }

 private:
  template <class T, int N>
  struct Ring {
    std::array<T, N> buf{};
    int head = 0, count = 0;
    bool push(const T& v) {
      if (count == N) return false;
      buf[static_cast<std::size_t>((head + count) % N)] = v;
      ++count;
      return true;
    }
    bool pop(T& v) {
      if (count == 0) return false;
      v = buf[static_cast<std::size_t>(head)];
      head = (head + 1) % N;
      --count;
      return true;
    }
    int size() const { return count; }
  };

  struct PendingEpoch {
    bool active = false;
    bool have_header = false;
    std::uint16_t seq = 0;
    can::GpsEpochFrame header{};
    std::uint32_t got = 0;       ///< bit i: measurement index i arrived (valid or not)
    std::uint32_t valid = 0;     ///< bit i: measurement index i is plausible
    double first_rx_s = 0.0;
    std::array<fsw::GnssRawMeasurement, fsw::kMaxGnssChannels> meas{};
  };

  void on_imu(const can::ImuFrame& f);
  void on_gps_epoch(const can::GpsEpochFrame& f, double rx_time_s);
  void on_gps_meas(const can::GpsMeasFrame& f, double rx_time_s);
  void on_almanac(const fsw::GpsAlmanac& a);
  /// Whether frames of epoch seq may still be accepted (a newer seq finishes the pending epoch
  /// and starts one); false for the last finished epoch or an older one (the caller counts it).
  bool accept_seq(std::uint16_t seq, double rx_time_s);
  void start_epoch(std::uint16_t seq, double rx_time_s);
  void finish_epoch(bool timeout);
  void try_complete();
  void deliver_imu(const fsw::ImuSample& s);

  CanRxConfig cfg_;
  CanRxHealth h_{};
  Ring<fsw::ImuSample, kImuQueue> imu_q_;
  Ring<fsw::GnssRawEpoch, kGpsQueue> gps_q_;
  Ring<fsw::GpsAlmanac, kAlmanacQueue> alm_q_;

  bool imu_started_ = false;
  std::uint32_t imu_last_counter_ = 0;
  std::uint64_t imu_seen_ = 0;  ///< bit k: counter (last - k) was delivered
  std::int64_t imu_last_time_ns_ = 0;

  PendingEpoch ep_{};
  bool gps_have_last_ = false;
  std::uint16_t gps_last_seq_ = 0;      ///< last finished (delivered or abandoned) epoch
  std::uint32_t gps_last_got_ = 0;      ///< its received measurement indices
  bool gps_last_had_header_ = false;
};

template <class F>
void CanRxHealth::for_each(F&& f) const {
#define SDINS_CAN_RX_COUNTER(name) f(#name, name)
  SDINS_CAN_RX_COUNTER(frames);
  SDINS_CAN_RX_COUNTER(unknown_id);
  SDINS_CAN_RX_COUNTER(bad_length);
  SDINS_CAN_RX_COUNTER(bad_crc);
  SDINS_CAN_RX_COUNTER(unsupported_frame);
  SDINS_CAN_RX_COUNTER(control_frames);
  SDINS_CAN_RX_COUNTER(imu_frames);
  SDINS_CAN_RX_COUNTER(imu_delivered);
  SDINS_CAN_RX_COUNTER(imu_gaps);
  SDINS_CAN_RX_COUNTER(imu_missing);
  SDINS_CAN_RX_COUNTER(imu_duplicate);
  SDINS_CAN_RX_COUNTER(imu_out_of_order);
  SDINS_CAN_RX_COUNTER(imu_resync);
  SDINS_CAN_RX_COUNTER(imu_flagged);
  SDINS_CAN_RX_COUNTER(imu_saturated);
  SDINS_CAN_RX_COUNTER(imu_implausible);
  SDINS_CAN_RX_COUNTER(imu_time_mismatch);
  SDINS_CAN_RX_COUNTER(gps_epoch_frames);
  SDINS_CAN_RX_COUNTER(gps_meas_frames);
  SDINS_CAN_RX_COUNTER(gps_epochs_delivered);
  SDINS_CAN_RX_COUNTER(gps_epochs_incomplete);
  SDINS_CAN_RX_COUNTER(gps_meas_missing);
  SDINS_CAN_RX_COUNTER(gps_epochs_timeout);
  SDINS_CAN_RX_COUNTER(gps_epochs_empty);
  SDINS_CAN_RX_COUNTER(gps_epochs_single);
  SDINS_CAN_RX_COUNTER(gps_duplicate);
  SDINS_CAN_RX_COUNTER(gps_out_of_order);
  SDINS_CAN_RX_COUNTER(gps_seq_resync);
  SDINS_CAN_RX_COUNTER(gps_epoch_implausible);
  SDINS_CAN_RX_COUNTER(gps_meas_implausible);
  SDINS_CAN_RX_COUNTER(gps_headerless);
  SDINS_CAN_RX_COUNTER(gps_meas_orphaned);
  SDINS_CAN_RX_COUNTER(almanac_frames);
  SDINS_CAN_RX_COUNTER(almanac_delivered);
  SDINS_CAN_RX_COUNTER(almanac_invalid);
  SDINS_CAN_RX_COUNTER(queue_overflow);
#undef SDINS_CAN_RX_COUNTER
}

}  // namespace hal
