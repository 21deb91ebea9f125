// CAN frames -> flight-software node, in arrival order: the one path by which bus frames reach
// the flight software, used by `sdins fsw` (frames from a bus) and `sdins sil` (frames from the
// in-process encoder), so both deliver the same inputs in the same order. Every frame is pushed
// into the receive assembler; what it completes (almanac elements, GPS epochs, IMU samples, in
// that order) is an event source of the one driver (fsw/driver.hpp): after each push() (and
// poll(), finish()) the caller drives the node with it, fsw::drive(input, node), until next()
// has nothing more. Lockstep control frames (hal/can/sdins.dbc: SIM_CONTROL) are taken out
// before the assembler sees them; FSW_ACK frames (sent by a flight software, possibly another
// one on the same bus) are ignored and counted. The counts an FSW_ACK reports are kept here.
#pragma once

#include <cstdint>

#include "hal/can_frame.hpp"
#include "hal/can_protocol.hpp"
#include "hal/can_rx_assembler.hpp"
#include "hal/fsw_node.hpp"

namespace hal {

class CanFswInput {
 public:
  /// progress: the summary of the node this input feeds (what FSW_ACK reports of it).
  explicit CanFswInput(const FswNodeSummary& progress, const CanRxConfig& cfg = {}) : progress_(progress), rx_(cfg) {}
  /// One received frame; returns the codec status of the frame.
  can::CodecStatus push(const CanFrame& f, double rx_time_s);
  /// Time passes without frames (GPS epoch timeout).
  void poll(double now_s);
  /// End of input: flushes an incomplete epoch.
  void finish();
  /// The next completed input (an event source, fsw/driver.hpp), or nullptr when none is pending.
  const fsw::InputEvent* next();
  const CanRxHealth& health() const { return rx_.health(); }
  std::uint64_t imu_delivered() const { return imu_delivered_; }

  // ---- lockstep flow control ----
  /// A SIM_CONTROL start has been received (run() holds it).
  bool run_started() const { return run_started_; }
  /// The SIM_CONTROL end of the current run has been received (end() holds it).
  bool end_received() const { return end_received_; }
  const can::SimControlFrame& run() const { return run_; }
  const can::SimControlFrame& end() const { return end_; }
  /// The last push() was a new SIM_CONTROL (a start of another run id, or the end): answer it.
  bool control_changed() const { return control_changed_; }
  /// The FSW_ACK content for the current run (counts since its start).
  can::FswAckFrame ack() const;
  std::uint64_t control_frames() const { return control_frames_; }      ///< SIM_CONTROL frames obeyed (starts, repeats included; this run's end)
  std::uint64_t control_rejected() const { return control_rejected_; }  ///< SIM_CONTROL with bad length/CRC/content, or an end of another run
  std::uint64_t foreign_acks() const { return foreign_acks_; }          ///< FSW_ACK frames seen (ignored)
  std::uint64_t data_frames() const { return data_frames_; }            ///< frames the assembler accepted (ID, length, CRC right)
  std::uint64_t imu_frames() const { return imu_frames_; }              ///< ... IMU_SAMPLE frames among them

 private:
  void on_control(const CanFrame& f);
  const FswNodeSummary& progress_;
  fsw::InputEvent event_{};  ///< what next() hands out
  CanRxAssembler rx_;
  std::uint64_t imu_delivered_ = 0;
  double last_imu_t_s_ = 0.0;
  bool run_started_ = false;
  bool end_received_ = false;
  bool control_changed_ = false;
  can::SimControlFrame run_{};
  can::SimControlFrame end_{};
  std::uint64_t control_frames_ = 0, control_rejected_ = 0, foreign_acks_ = 0;
  std::uint64_t data_frames_ = 0, imu_frames_ = 0;
  // counts at the run's start (FSW_ACK reports counts since then)
  std::uint64_t base_data_ = 0, base_imu_frames_ = 0, base_imu_delivered_ = 0, base_nav_ = 0;
};

}  // namespace hal
