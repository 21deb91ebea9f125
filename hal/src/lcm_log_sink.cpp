#include "hal/lcm_log_sink.hpp"

#include <algorithm>
#include <utility>

namespace hal {

LcmLogStatus LcmLogSink::write_imu(const fsw::ImuSample& sample, std::int16_t status) {
  ImuRecord r;
  r.sample = sample;
  r.counter = imu_counter_;
  r.status = status;
  return write_imu(r);
}

LcmLogStatus LcmLogSink::write_imu(const ImuRecord& record) {
  sdins::imu_sample_t m{};
  to_msg(record, m);
  // The running counter continues from the last sample written (wraps like an int32 sensor counter).
  imu_counter_ = static_cast<std::int32_t>(static_cast<std::uint32_t>(record.counter) + 1u);
  return publish(kLcmChannelImu, m);
}

LcmLogStatus LcmLogSink::write_gnss(const fsw::GnssRawEpoch& epoch) {
  sdins::gnss_raw_epoch_t m{};
  to_msg(epoch, m);
  return publish(kLcmChannelGnssRaw, m);
}

LcmLogStatus LcmLogSink::write_almanac(const fsw::GpsAlmanac& almanac, double t_s) {
  sdins::gps_almanac_t m{};
  to_msg(almanac, t_s, m);
  return publish(kLcmChannelGpsAlmanac, m);
}

LcmLogStatus LcmLogSink::write_nav(const fsw::NavState& nav, bool valid, bool ekf_updated) {
  sdins::nav_solution_t m{};
  to_msg(nav, valid, ekf_updated, m);
  return publish(kLcmChannelNavSolution, m);
}

LcmLogStatus LcmLogSink::write_truth(double t_s, const fsw::Vec3& llh, const fsw::Vec3& vel_enu_mps,
                                     const fsw::Mat3& C_b_n) {
  sdins::truth_t m{};
  truth_to_msg(t_s, llh, vel_enu_mps, C_b_n, m);
  return publish(kLcmChannelTruth, m);
}

LcmLogStatus LcmLogSink::write_reference(double t_s, const fsw::Vec3& llh, const fsw::Vec3& vel_enu_mps) {
  sdins::truth_t m{};
  reference_to_msg(t_s, llh, vel_enu_mps, m);
  return publish(kLcmChannelTruth, m);
}

LcmLogStatus LcmLogSink::write_pvt(const GnssPvtSample& pvt) {
  sdins::gnss_pvt_t m{};
  to_msg(pvt, m);
  return publish(kLcmChannelGnssPvt, m);
}

LcmLogStatus LcmLogSink::write_health(double t_s, const fsw::ExecutiveHealth& health,
                                      const fsw::GnssConversionStats& conversion, const fsw::FrameOutput& frame,
                                      double gate_chi2) {
  to_msg(t_s, health, conversion, frame, gate_chi2, health_msg_);
  return publish(kLcmChannelFilterHealth, health_msg_);
}

// ---------------------------------------------------------------------------------------------
std::uint64_t max_imu_samples(std::uint64_t log_bytes, const std::string& imu_channel) {
  const std::uint64_t event_bytes = kLcmLogHeaderBytes + imu_channel.size() +
                                    static_cast<std::uint64_t>(sdins::imu_sample_t{}.getEncodedSize());
  return log_bytes / event_bytes;
}

bool LcmReplayReader::later_pending(const Pending& a, const Pending& b) {
  return std::pair<double, std::uint64_t>(a.t_s, a.seq) > std::pair<double, std::uint64_t>(b.t_s, b.seq);
}

LcmLogStatus LcmReplayReader::open(const std::string& path, const LcmReplayConfig& cfg) {
  cfg_ = cfg;
  if (!(cfg_.reorder_window_s >= 0.0)) cfg_.reorder_window_s = 0.0;  // NaN or negative: no reordering
  if (!(cfg_.max_time_jump_s > 0.0)) cfg_.max_time_jump_s = LcmReplayConfig{}.max_time_jump_s;
  stats_ = LcmReplayStats{};
  pending_.clear();
  slots_.clear();
  free_slots_.clear();
  seq_ = 0;
  eof_ = false;
  have_newest_ = false;
  have_delivered_ = false;
  have_counter_ = false;
  TimeTagGateConfig g;
  g.max_forward_s = cfg_.max_time_jump_s;
  g.max_backward_s = cfg_.reorder_window_s;
  g.confirm_samples = cfg_.time_base_confirm_inputs;
  gate_ = TimeTagFilter<fsw::InputEvent>(g);
  return log_.open(path, cfg.max_event_bytes);
}

void LcmReplayReader::push(fsw::InputEvent&& in) {
  gate_.push(
      in.t_s, std::move(in), [this](fsw::InputEvent&& a) { enqueue(std::move(a)); },
      [this](fsw::InputEvent&&, TimeTagRejection) { ++stats_.time_tag_rejected; });
  const TimeTagGateStats& g = gate_.stats();
  stats_.time_base_changes = g.new_bases;
  stats_.last_time_base_jump_s = g.last_new_base_jump_s;
  stats_.last_time_base_at_s = g.last_new_base_at_s;
}

void LcmReplayReader::enqueue(fsw::InputEvent&& in) {
  // Inputs are delivered in time order: one older than an input already returned is too late.
  if (have_delivered_ && in.t_s < last_delivered_t_s_) {
    ++stats_.out_of_order;
    return;
  }
  if (!have_newest_ || in.t_s > newest_t_s_) newest_t_s_ = in.t_s;
  have_newest_ = true;
  std::uint32_t slot;
  if (free_slots_.empty()) {
    slot = static_cast<std::uint32_t>(slots_.size());
    slots_.push_back(std::move(in));
  } else {
    slot = free_slots_.back();
    free_slots_.pop_back();
    slots_[slot] = std::move(in);
  }
  pending_.push_back(Pending{slots_[slot].t_s, seq_++, slot});
  std::push_heap(pending_.begin(), pending_.end(), later_pending);
}

namespace {

/// Decodes ev as a Msg into m, validates it into out (from_msg with args) and counts the status in
/// stats; true when the input is accepted.
template <class Msg, class Out, class... Args>
bool decode_input(const LcmLogEvent& ev, LcmInputStats& stats, Msg& m, Out& out, const Args&... args) {
  LcmInputStatus st = decode_exact(ev.data, ev.data_len, m);
  if (st == LcmInputStatus::kOk) st = from_msg(m, out, args...);
  stats.record(st);
  return st == LcmInputStatus::kOk;
}

}  // namespace

void LcmReplayReader::take(const LcmLogEvent& ev) {
  fsw::InputEvent in;
  if (ev.channel == cfg_.imu_channel) {
    sdins::imu_sample_t m{};
    ImuRecord rec;
    if (!decode_input(ev, stats_.imu, m, rec, cfg_.imu_limits)) return;
    in.imu = rec.sample;
    in.imu_counter = rec.counter;
    in.imu_status = rec.status;
    if (have_counter_) {
      const std::uint32_t step = static_cast<std::uint32_t>(in.imu_counter) - static_cast<std::uint32_t>(last_counter_);
      if (step != 1u) {
        ++stats_.imu_counter_gaps;
        if (step > 1u && step < (1u << 30)) stats_.imu_counter_missing += step - 1u;
      }
    }
    have_counter_ = true;
    last_counter_ = in.imu_counter;
    in.kind = fsw::InputEvent::Kind::kImu;
    in.t_s = in.imu.t_s;
  } else if (ev.channel == cfg_.gnss_channel) {
    sdins::gnss_raw_epoch_t m{};
    LcmInputStatus st = decode_exact(ev.data, ev.data_len, m);
    int dropped = 0;
    if (st == LcmInputStatus::kOk) st = from_msg(m, in.gnss, dropped);
    stats_.gnss.record(st);
    stats_.gnss.measurements_dropped += static_cast<std::uint64_t>(dropped);
    if (st != LcmInputStatus::kOk && st != LcmInputStatus::kMeasurementsDropped) return;
    in.kind = fsw::InputEvent::Kind::kGnssRaw;
    in.t_s = in.gnss.t_s;
  } else if (ev.channel == cfg_.almanac_channel) {
    sdins::gps_almanac_t m{};
    if (!decode_input(ev, stats_.almanac, m, in.almanac)) return;
    in.kind = fsw::InputEvent::Kind::kAlmanac;
    in.t_s = m.t_s;
  } else if (!cfg_.gnss_pvt_channel.empty() && ev.channel == cfg_.gnss_pvt_channel) {
    sdins::gnss_pvt_t m{};
    GnssPvtSample pvt;
    if (!decode_input(ev, stats_.gnss_pvt, m, pvt, cfg_.pvt_limits)) return;
    in.pvt = to_fsw(pvt);
    in.kind = fsw::InputEvent::Kind::kGnssPvt;
    in.t_s = in.pvt.t_s;
  } else {
    ++stats_.other_events;
    return;
  }
  push(std::move(in));
}

LcmLogStatus LcmReplayReader::next(fsw::InputEvent& in) {
  for (;;) {
    if (!pending_.empty() && (eof_ || pending_.front().t_s <= newest_t_s_ - cfg_.reorder_window_s)) {
      std::pop_heap(pending_.begin(), pending_.end(), later_pending);
      const std::uint32_t slot = pending_.back().slot;
      in = std::move(slots_[slot]);
      free_slots_.push_back(slot);
      pending_.pop_back();
      have_delivered_ = true;
      last_delivered_t_s_ = in.t_s;
      ++stats_.delivered;
      return LcmLogStatus::kOk;
    }
    if (eof_) return LcmLogStatus::kEndOfLog;
    LcmLogEvent ev;
    const LcmLogStatus st = log_.next(ev);
    if (st == LcmLogStatus::kOk) {
      take(ev);
    } else if (st == LcmLogStatus::kEndOfLog) {
      gate_.finish([this](fsw::InputEvent&& a) { enqueue(std::move(a)); },
                   [this](fsw::InputEvent&&, TimeTagRejection) { ++stats_.time_tag_rejected; });
      eof_ = true;
    } else {
      return st;
    }
  }
}

}  // namespace hal
