#include "hal/can_fsw_input.hpp"

namespace hal {

can::CodecStatus CanFswInput::push(const CanFrame& f, double rx_time_s) {
  const can::CodecStatus st = rx_.push(f, rx_time_s);
  drain();
  return st;
}

void CanFswInput::poll(double now_s) {
  rx_.poll(now_s);
  drain();
}

void CanFswInput::finish() {
  rx_.flush();
  drain();
}

void CanFswInput::drain() {
  fsw::GpsAlmanac a;
  while (rx_.pop_almanac(a)) node_.on_almanac(a, last_imu_t_s_);
  fsw::GnssRawEpoch e;
  while (rx_.pop_gps(e)) node_.on_gnss(e);
  fsw::ImuSample s;
  while (rx_.pop_imu(s)) {
    node_.on_imu(s);
    last_imu_t_s_ = s.t_s;
    ++imu_delivered_;
  }
}

}  // namespace hal
