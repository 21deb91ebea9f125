// Receiver-side assembly of the sdins CAN protocol (see hal/can_rx_assembler.hpp).
// Flight-side code: no allocation, no exceptions, no I/O.
#include "hal/can_rx_assembler.hpp"

#include <cmath>

namespace hal {
namespace {

// Physical plausibility limits: beyond any aircraft IMU / GPS receiver (and beyond the IMU fields'
// range at 1 kHz, so saturated samples pass), so only corrupted or wrongly scaled data trips them.
constexpr double kMaxImuDt_s = 0.1;
constexpr double kMaxRate_radps = 100.0;
constexpr double kMaxSpecificForce_mps2 = 5000.0;
constexpr double kMinPseudorange_m = 1.0e7;
constexpr double kMaxPseudorange_m = 5.0e7;
constexpr double kMaxRangeRate_mps = 2.0e4;
constexpr double kMaxCn0_dbhz = 100.0;
constexpr std::uint64_t kTowLimit_ns = 604800ull * 1000000000ull;

int popcount32(std::uint32_t v) {
  int n = 0;
  for (; v != 0; v &= v - 1) ++n;
  return n;
}
std::uint32_t index_mask(int n) { return n >= 32 ? 0xFFFFFFFFu : ((1u << n) - 1u); }

}  // namespace

std::uint32_t CanRxHealth::rejections() const {
  return unknown_id + bad_length + bad_crc + unsupported_frame + imu_missing + imu_duplicate + imu_out_of_order +
         imu_flagged + imu_implausible + gps_meas_missing + gps_duplicate + gps_out_of_order + gps_epoch_implausible +
         gps_meas_implausible + gps_meas_orphaned + almanac_invalid + queue_overflow;
}

can::CodecStatus CanRxAssembler::push(const CanFrame& f, double rx_time_s) {
  ++h_.frames;
  poll(rx_time_s);
  if (!can_frame_valid(f)) {
    ++h_.unsupported_frame;
    return can::CodecStatus::kBadLength;
  }
  can::MessageKind kind;
  const can::CodecStatus st = can::check_frame(f, kind);
  switch (st) {
    case can::CodecStatus::kOk: break;
    case can::CodecStatus::kUnknownId: ++h_.unknown_id; return st;
    case can::CodecStatus::kBadLength: ++h_.bad_length; return st;
    case can::CodecStatus::kBadCrc: ++h_.bad_crc; return st;
    default: ++h_.unsupported_frame; return st;
  }
  switch (kind) {
    case can::MessageKind::kImuSample: {
      can::ImuFrame d;
      can::decode_imu(f, d);
      on_imu(d);
      break;
    }
    case can::MessageKind::kGpsEpoch: {
      can::GpsEpochFrame d;
      can::decode_gps_epoch(f, d);
      on_gps_epoch(d, rx_time_s);
      break;
    }
    case can::MessageKind::kGpsMeas: {
      can::GpsMeasFrame d;
      can::decode_gps_meas(f, d);
      on_gps_meas(d, rx_time_s);
      break;
    }
    case can::MessageKind::kGpsAlmanac: {
      fsw::GpsAlmanac a;
      can::decode_gps_almanac(f, a);
      on_almanac(a);
      break;
    }
    case can::MessageKind::kSimControl:
    case can::MessageKind::kFswAck: ++h_.control_frames; break;  // flow control, no sensor data
    case can::MessageKind::kUnknown: ++h_.unknown_id; return can::CodecStatus::kUnknownId;
  }
  return can::CodecStatus::kOk;
}

// ---- IMU ------------------------------------------------------------------------------------------

void CanRxAssembler::deliver_imu(const fsw::ImuSample& s) {
  if (imu_q_.push(s))
    ++h_.imu_delivered;
  else
    ++h_.queue_overflow;
}

void CanRxAssembler::on_imu(const can::ImuFrame& f) {
  ++h_.imu_frames;
  bool restart = !imu_started_;
  std::int64_t advance = 1;  // counter steps since the last delivered sample
  if (imu_started_) {
    const std::int32_t d = static_cast<std::int32_t>(f.counter - (imu_last_counter_ + 1u));
    if (d >= 0) {
      if (d > kImuResyncSamples) {
        ++h_.imu_resync;
        restart = true;
      } else if (d > 0) {
        ++h_.imu_gaps;
        h_.imu_missing += static_cast<std::uint32_t>(d);
      }
      advance = static_cast<std::int64_t>(d) + 1;
    } else {
      const std::uint32_t back = imu_last_counter_ - f.counter;  // 0 = the last delivered one
      if (back > static_cast<std::uint32_t>(kImuResyncSamples)) {
        ++h_.imu_resync;
        restart = true;
      } else if (back < 64 && ((imu_seen_ >> back) & 1u)) {
        ++h_.imu_duplicate;
        return;
      } else {
        ++h_.imu_out_of_order;
        return;
      }
    }
  }
  // The counter slot is taken whether or not the sample is usable.
  if (!restart && f.dt_ns > 0) {
    const double expected = static_cast<double>(imu_last_time_ns_) + static_cast<double>(advance) * f.dt_ns;
    if (std::abs(static_cast<double>(f.time_ns) - expected) > 0.5 * f.dt_ns) ++h_.imu_time_mismatch;
  }
  if (restart)
    imu_seen_ = 1;
  else
    imu_seen_ = advance >= 64 ? 1u : ((imu_seen_ << advance) | 1u);
  imu_started_ = true;
  imu_last_counter_ = f.counter;
  imu_last_time_ns_ = f.time_ns;

  if (f.status & can::kImuUnusableMask) {
    ++h_.imu_flagged;
    return;
  }
  const fsw::ImuSample& s = f.sample;
  if (!(s.dt_s > 0.0 && s.dt_s <= kMaxImuDt_s) || s.dtheta_rad.norm() > kMaxRate_radps * s.dt_s ||
      s.dv_mps.norm() > kMaxSpecificForce_mps2 * s.dt_s) {
    ++h_.imu_implausible;
    return;
  }
  if (f.status & (can::kImuDthetaSaturated | can::kImuDvSaturated)) ++h_.imu_saturated;
  deliver_imu(s);
}

// ---- GPS ------------------------------------------------------------------------------------------

void CanRxAssembler::start_epoch(std::uint16_t seq, double rx_time_s) {
  ep_.active = true;
  ep_.have_header = false;
  ep_.seq = seq;
  ep_.got = 0;
  ep_.valid = 0;
  ep_.first_rx_s = rx_time_s;
}

bool CanRxAssembler::accept_seq(std::uint16_t seq, double rx_time_s) {
  if (ep_.active) {
    const int d = static_cast<std::int16_t>(static_cast<std::uint16_t>(seq - ep_.seq));
    if (d == 0) return true;
    if (d < 0 && d >= -kGpsSeqWindow) return false;  // older than the pending epoch
    if (d < 0) ++h_.gps_seq_resync;
    finish_epoch(false);
    start_epoch(seq, rx_time_s);
    return true;
  }
  if (gps_have_last_) {
    const int d = static_cast<std::int16_t>(static_cast<std::uint16_t>(seq - gps_last_seq_));
    if (d <= 0 && d >= -kGpsSeqWindow) return false;  // the last finished epoch or an older one
    if (d < 0) ++h_.gps_seq_resync;
  }
  start_epoch(seq, rx_time_s);
  return true;
}

void CanRxAssembler::on_gps_epoch(const can::GpsEpochFrame& f, double rx_time_s) {
  ++h_.gps_epoch_frames;
  if (f.n_meas > fsw::kMaxGnssChannels || f.tow_ns >= kTowLimit_ns || !(f.status & can::kGpsTimeValid)) {
    ++h_.gps_epoch_implausible;
    return;
  }
  if (!accept_seq(f.seq, rx_time_s)) {
    if (gps_have_last_ && f.seq == gps_last_seq_ && gps_last_had_header_)
      ++h_.gps_duplicate;
    else
      ++h_.gps_out_of_order;
    return;
  }
  if (ep_.have_header) {
    ++h_.gps_duplicate;
    return;
  }
  ep_.header = f;
  ep_.have_header = true;
  // Measurements that came before the header with an index beyond what it announces.
  const std::uint32_t beyond = ep_.valid & ~index_mask(f.n_meas);
  if (beyond != 0) {
    h_.gps_meas_implausible += static_cast<std::uint32_t>(popcount32(beyond));
    ep_.valid &= ~beyond;
  }
  try_complete();
}

void CanRxAssembler::on_gps_meas(const can::GpsMeasFrame& f, double rx_time_s) {
  ++h_.gps_meas_frames;
  if (f.index >= fsw::kMaxGnssChannels) {
    ++h_.gps_meas_implausible;
    return;
  }
  const std::uint32_t bit = 1u << f.index;
  if (!accept_seq(f.seq, rx_time_s)) {
    if (gps_have_last_ && f.seq == gps_last_seq_ && (gps_last_got_ & bit))
      ++h_.gps_duplicate;
    else
      ++h_.gps_out_of_order;
    return;
  }
  if (ep_.got & bit) {
    ++h_.gps_duplicate;
    return;
  }
  ep_.got |= bit;
  const fsw::GnssRawMeasurement& m = f.meas;
  const bool plausible = m.prn >= 1 && m.prn <= fsw::kMaxGpsPrn && m.pseudorange_m >= kMinPseudorange_m &&
                         m.pseudorange_m <= kMaxPseudorange_m && std::abs(m.pseudorange_rate_mps) <= kMaxRangeRate_mps &&
                         m.cn0_dbhz <= kMaxCn0_dbhz && (!ep_.have_header || f.index < ep_.header.n_meas);
  if (!plausible) {
    ++h_.gps_meas_implausible;
  } else {
    ep_.valid |= bit;
    ep_.meas[f.index] = m;
  }
  try_complete();
}

void CanRxAssembler::try_complete() {
  if (!ep_.active || !ep_.have_header) return;
  const std::uint32_t want = index_mask(ep_.header.n_meas);
  if ((ep_.got & want) == want) finish_epoch(false);
}

void CanRxAssembler::finish_epoch(bool timeout) {
  if (!ep_.active) return;
  if (timeout) ++h_.gps_epochs_timeout;
  if (ep_.have_header) {
    const int n = ep_.header.n_meas;
    const std::uint32_t want = index_mask(n);
    const int got = popcount32(ep_.got & want);
    if (got < n) {
      ++h_.gps_epochs_incomplete;
      h_.gps_meas_missing += static_cast<std::uint32_t>(n - got);
    }
    fsw::GnssRawEpoch e;
    e.t_s = ep_.header.t_s;
    e.gps_week = ep_.header.gps_week;
    e.gps_tow_s = ep_.header.gps_tow_s;
    e.n_meas = 0;
    for (int i = 0; i < n; ++i)
      if (ep_.valid & (1u << i)) e.meas[static_cast<std::size_t>(e.n_meas++)] = ep_.meas[static_cast<std::size_t>(i)];
    if (e.n_meas == 0) ++h_.gps_epochs_empty;
    if (e.n_meas == 1) ++h_.gps_epochs_single;
    if (gps_q_.push(e))
      ++h_.gps_epochs_delivered;
    else
      ++h_.queue_overflow;
  } else {
    ++h_.gps_headerless;
    h_.gps_meas_orphaned += static_cast<std::uint32_t>(popcount32(ep_.got));
  }
  gps_have_last_ = true;
  gps_last_seq_ = ep_.seq;
  gps_last_got_ = ep_.got;
  gps_last_had_header_ = ep_.have_header;
  ep_.active = false;
}

void CanRxAssembler::poll(double now_s) {
  if (ep_.active && now_s - ep_.first_rx_s > cfg_.gps_epoch_timeout_s) finish_epoch(true);
}

void CanRxAssembler::flush() { finish_epoch(false); }

// ---- almanac --------------------------------------------------------------------------------------

void CanRxAssembler::on_almanac(const fsw::GpsAlmanac& a) {
  ++h_.almanac_frames;
  if (!fsw::almanac_valid(a)) {
    ++h_.almanac_invalid;
    return;
  }
  if (alm_q_.push(a))
    ++h_.almanac_delivered;
  else
    ++h_.queue_overflow;
}

bool CanRxAssembler::pop_imu(fsw::ImuSample& s) { return imu_q_.pop(s); }
bool CanRxAssembler::pop_gps(fsw::GnssRawEpoch& e) { return gps_q_.pop(e); }
bool CanRxAssembler::pop_almanac(fsw::GpsAlmanac& a) { return alm_q_.pop(a); }

}  // namespace hal
