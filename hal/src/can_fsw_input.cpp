#include "hal/can_fsw_input.hpp"

namespace hal {

can::CodecStatus CanFswInput::push(const CanFrame& f, double rx_time_s) {
  control_changed_ = false;
  if (!f.extended && f.id == can::kIdSimControl) {
    on_control(f);
    rx_.poll(rx_time_s);
    return can::CodecStatus::kOk;
  }
  if (!f.extended && f.id == can::kIdFswAck) {  // another node's acknowledgement: not for us
    ++foreign_acks_;
    return can::CodecStatus::kOk;
  }
  const can::CodecStatus st = rx_.push(f, rx_time_s);
  // Counted for the acknowledgement only when the identifier, length and CRC are right: another
  // node's frames and damaged ones are the assembler's counted rejections, not the simulator's.
  if (st == can::CodecStatus::kOk) {
    ++data_frames_;
    if (!f.extended && f.id == can::kIdImuSample) ++imu_frames_;
  }
  return st;
}

void CanFswInput::on_control(const CanFrame& f) {
  can::SimControlFrame c;
  if (can::decode_sim_control(f, c) != can::CodecStatus::kOk) {
    ++control_rejected_;
    return;
  }
  if (c.command == can::SimCommand::kStart) {
    ++control_frames_;
    if (run_started_ && c.run_id == run_.run_id) return;  // a repeated start of the current run
    run_started_ = true;
    end_received_ = false;
    run_ = c;
    base_data_ = data_frames_;
    base_imu_frames_ = imu_frames_;
    base_imu_delivered_ = imu_delivered_;
    base_nav_ = progress_.nav_frames;
    control_changed_ = true;
    return;
  }
  // End: only the current run's (a stale end of an earlier run is counted, not obeyed).
  if (!run_started_ || c.run_id != run_.run_id) {
    ++control_rejected_;
    return;
  }
  ++control_frames_;
  if (!end_received_) control_changed_ = true;
  end_received_ = true;
  end_ = c;
}

can::FswAckFrame CanFswInput::ack() const {
  can::FswAckFrame a;
  if (!run_started_) return a;
  a.run_id = run_.run_id;
  a.imu_frames = static_cast<std::uint32_t>(imu_frames_ - base_imu_frames_);
  a.frames = static_cast<std::uint32_t>(data_frames_ - base_data_);
  a.imu_delivered = static_cast<std::uint32_t>(imu_delivered_ - base_imu_delivered_);
  a.nav_frames = static_cast<std::uint32_t>(progress_.nav_frames - base_nav_);
  if (progress_.initialised) a.flags |= can::kAckInitialised;
  if (end_received_) a.flags |= can::kAckEndReceived;
  return a;
}

void CanFswInput::poll(double now_s) {
  rx_.poll(now_s);
}

void CanFswInput::finish() {
  rx_.flush();
}

const fsw::InputEvent* CanFswInput::next() {
  // The almanac elements first, then the epochs, then the samples, of what the last frames
  // completed (the order the flight software has always been fed them in).
  fsw::GpsAlmanac a;
  if (rx_.pop_almanac(a)) {
    event_ = fsw::InputEvent::of_almanac(a, last_imu_t_s_);
    return &event_;
  }
  if (rx_.pop_gps(event_.gnss)) {
    event_.kind = fsw::InputEvent::Kind::kGnssRaw;
    event_.t_s = event_.gnss.t_s;
    return &event_;
  }
  if (rx_.pop_imu(event_.imu)) {
    event_.kind = fsw::InputEvent::Kind::kImu;
    event_.t_s = event_.imu.t_s;
    event_.imu_counter = -1;
    event_.imu_status = 0;
    last_imu_t_s_ = event_.imu.t_s;
    ++imu_delivered_;
    return &event_;
  }
  return nullptr;
}

}  // namespace hal
