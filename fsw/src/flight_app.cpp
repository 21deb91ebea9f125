// The flight application (see fsw/flight_app.hpp).
#include "fsw/flight_app.hpp"

#include <algorithm>
#include <cmath>

namespace fsw {

template <class Layout>
Status FlightApp<Layout>::init(const FlightAppConfig& cfg) {
  // The one rule table (fsw/config_check.hpp); the host checked the same at load.
  if (!check_config(cfg).ok()) return Status::kBadConfig;
  cfg_ = cfg;
  cfg_.exec.ekf.pos_sigma_m = cfg.init_pos_sigma_m;
  cfg_.exec.ekf.vel_sigma_mps = cfg.init_vel_sigma_mps;
  cfg_.exec.ekf.att_sigma_rad = cfg.init_att_sigma_rad;
  almanac_.clear();
  health_ = FlightAppHealth{};
  n_batch_ = 0;
  have_epoch_ = false;
  have_pvt_ = false;
  initialiser_.reset(cfg_);
  configured_ = true;
  return Status::kOk;
}

template <class Layout>
Status FlightApp<Layout>::on_almanac(const GpsAlmanac& sat) {
  if (!configured_) return Status::kNotInitialised;
  ++health_.almanac_received;
  const Status st = almanac_.set(sat);
  if (st != Status::kOk) ++health_.almanac_rejected;
  return st;
}

template <class Layout>
Status FlightApp<Layout>::on_gnss(const GnssRawEpoch& raw) {
  if (!configured_) return Status::kNotInitialised;
  ++health_.gnss_received;
  const Vec3 hint = exec_.ins().state().llh;
  const Status st = gnss_epoch_from_raw(raw, almanac_, health_.initialised ? &hint : nullptr, epoch_,
                                        health_.conversion);
  if (st != Status::kOk) {
    ++health_.gnss_rejected;
    return st;
  }
  if (!health_.initialised) {
    InitialState initial;
    bool ready = false;
    const Status init_st = initialiser_.on_gnss(epoch_, cfg_, health_, initial, ready);
    return ready ? start(initial) : init_st;
  }
  have_epoch_ = true;  // handed to the executive with the next minor frame
  return Status::kOk;
}

template <class Layout>
Status FlightApp<Layout>::start_given(const NavState& nav) {
  if (!configured_ || cfg_.init_mode != InitMode::kGiven) return Status::kBadConfig;
  if (health_.initialised || !std::isfinite(nav.t_s) || !nav.llh.allFinite() || !nav.vel_enu_mps.allFinite() ||
      !nav.q_b_n.coeffs().allFinite())
    return Status::kBadInput;
  InitialState initial;
  initial.nav = nav;
  initial.att_sigma_rad = cfg_.init_att_sigma_rad;
  return start(initial);
}

template <class Layout>
Status FlightApp<Layout>::start(const InitialState& initial) {
  cfg_.exec.ekf.att_sigma_rad = initial.att_sigma_rad;
  const Status st = exec_.init(cfg_.exec, initial.nav);
  if (st != Status::kOk) return st;
  health_.initialised = true;
  health_.init_t_s = initial.nav.t_s;
  health_.init_mode = cfg_.init_mode;
  health_.init_align_s = initial.align_s;
  health_.init_att_sigma_rad = initial.att_sigma_rad;
  health_.init_euler_rad = euler_from_C_b_n(initial.nav.C_b_n());
  health_.init_fix = initial.fix;
  if (initial.vm_biases) {
    health_.vm_gyro_bias_radps = initial.vm_gyro_bias_radps;
    health_.vm_accel_bias_mps2 = initial.vm_accel_bias_mps2;
  }
  n_batch_ = 0;
  have_epoch_ = false;  // this fix initialised the solution; the EKF starts with the next one
  have_pvt_ = false;
  return Status::kOk;
}

template <class Layout>
Status FlightApp<Layout>::on_gnss_pvt(const GnssPvtMeasurement& m) {
  if (!configured_) return Status::kNotInitialised;
  ++health_.pvt_received;
  const bool ok = std::isfinite(m.t_s) && m.llh.allFinite() && std::abs(m.llh.x()) <= 0.5 * kPi &&
                  m.pos_sigma_enu_m.allFinite() && (m.pos_sigma_enu_m.array() > 0.0).all() && m.quality >= 1 &&
                  m.quality <= cfg_.pvt_max_quality &&
                  (!m.has_velocity || (m.vel_enu_mps.allFinite() && m.vel_sigma_enu_mps.allFinite() &&
                                       (m.vel_sigma_enu_mps.array() > 0.0).all()));
  if (!ok) {
    ++health_.pvt_rejected;
    return Status::kBadInput;
  }
  if (!health_.initialised) {
    InitialState initial;
    bool ready = false;
    const Status init_st = initialiser_.on_pvt(m, cfg_, health_, initial, ready);
    return ready ? start(initial) : init_st;
  }
  pvt_ = m;
  have_pvt_ = true;  // handed to the executive with the next minor frame
  return Status::kOk;
}

template <class Layout>
Status FlightApp<Layout>::on_imu(const ImuSample& s, FrameOutput& out) {
  out.frame_closed = false;
  out.nav_valid = false;
  out.ekf_ran = false;
  out.ekf_updated = false;
  out.ekf_released = false;
  if (!configured_) return Status::kNotInitialised;
  ++health_.imu_received;
  if (!health_.initialised) {
    ++health_.imu_before_init;
    out.frame_closed = health_.imu_before_init % static_cast<std::uint32_t>(cfg_.exec.imu_samples_per_frame) == 0u;
    return initialiser_.on_imu(s, cfg_, health_);
  }
  if (!(s.t_s > exec_.ins().state().t_s) && n_batch_ == 0) {
    ++health_.imu_rejected;  // at or before the initialisation epoch: already represented
    return Status::kOk;
  }
  // The minor frame ends where the executive's frame builder completes one (a rejected sample
  // leaves it a sample short, and the batch follows it: one grouping, not two).
  batch_[static_cast<std::size_t>(n_batch_++)] = s;
  if (n_batch_ < exec_.samples_to_frame_end()) return Status::kOk;
  FrameInput in;
  in.imu = batch_.data();
  in.n_imu = n_batch_;
  in.gnss = have_epoch_ ? &epoch_ : nullptr;
  in.pvt = have_pvt_ ? &pvt_ : nullptr;
  in.prev_tick_exec_s = prev_tick_exec_s_;
  have_epoch_ = false;
  have_pvt_ = false;
  n_batch_ = 0;
  const Status st = exec_.tick(in, out);
  out.frame_closed = true;
  return st;
}

template <class Layout>
Status FlightApp<Layout>::on_event(const InputEvent& ev, FrameOutput& out) {
  switch (ev.kind) {
    case InputEvent::Kind::kImu: return on_imu(ev.imu, out);
    case InputEvent::Kind::kGnssRaw: return on_gnss(ev.gnss);
    case InputEvent::Kind::kGnssPvt: return on_gnss_pvt(ev.pvt);
    case InputEvent::Kind::kAlmanac: return on_almanac(ev.almanac);
  }
  return Status::kBadInput;
}

#define FSW_FLIGHT_APP_INSTANTIATE(L) template class FlightApp<L>;
FSW_FOR_EACH_LAYOUT(FSW_FLIGHT_APP_INSTANTIATE)
#undef FSW_FLIGHT_APP_INSTANTIATE

}  // namespace fsw
