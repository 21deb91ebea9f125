// CAN frames -> flight-software node, in arrival order: the one path by which bus frames reach
// the flight software, used by `sdins fsw` (frames from a bus) and `sdins sil` (frames from the
// in-process encoder), so both deliver the same inputs in the same order. Every frame is pushed
// into the receive assembler and everything it completes is handed on at once (almanac, GPS
// epoch, IMU sample). Lockstep control frames (hal/can/sdins.dbc: SIM_CONTROL) are taken out
// before the assembler sees them.
#pragma once

#include <cstdint>

#include "hal/can_frame.hpp"
#include "hal/can_rx_assembler.hpp"
#include "hal/fsw_node.hpp"

namespace hal {

class CanFswInput {
 public:
  explicit CanFswInput(FswNode& node, const CanRxConfig& cfg = {}) : node_(node), rx_(cfg) {}
  /// One received frame; returns the codec status of the frame.
  can::CodecStatus push(const CanFrame& f, double rx_time_s);
  /// Time passes without frames (GPS epoch timeout).
  void poll(double now_s);
  /// End of input: flushes an incomplete epoch to the node.
  void finish();
  const CanRxHealth& health() const { return rx_.health(); }
  std::uint64_t imu_delivered() const { return imu_delivered_; }

 private:
  void drain();
  FswNode& node_;
  CanRxAssembler rx_;
  std::uint64_t imu_delivered_ = 0;
  double last_imu_t_s_ = 0.0;
};

}  // namespace hal
