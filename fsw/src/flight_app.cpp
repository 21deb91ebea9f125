// The flight application (see fsw/flight_app.hpp).
#include "fsw/flight_app.hpp"

#include <cmath>

namespace fsw {

template <class Layout>
Status FlightApp<Layout>::init(const FlightAppConfig& cfg) {
  if (cfg.min_satellites_for_init < 4 || cfg.min_satellites_for_init > kMaxGnssChannels ||
      !(cfg.max_init_pdop > 0.0) || !(cfg.min_init_speed_mps >= 0.0) || cfg.levelling_samples < 1 ||
      cfg.levelling_samples > kMaxLevelling || !(cfg.init_pos_sigma_m > 0.0) || !(cfg.init_vel_sigma_mps > 0.0) ||
      !cfg.init_att_sigma_rad.allFinite() || !(cfg.init_att_sigma_rad.array() > 0.0).all() ||
      cfg.exec.imu_samples_per_frame < 1 || cfg.exec.imu_samples_per_frame > FrameBuilder::kMaxSamplesPerFrame ||
      !std::isfinite(cfg.init_heading_offset_rad) || cfg.pvt_max_quality < 1)
    return Status::kBadConfig;
  cfg_ = cfg;
  cfg_.exec.ekf.pos_sigma_m = cfg.init_pos_sigma_m;
  cfg_.exec.ekf.vel_sigma_mps = cfg.init_vel_sigma_mps;
  cfg_.exec.ekf.att_sigma_rad = cfg.init_att_sigma_rad;
  almanac_.clear();
  health_ = FlightAppHealth{};
  level_head_ = 0;
  level_count_ = 0;
  n_batch_ = 0;
  have_epoch_ = false;
  have_pvt_ = false;
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
  if (!health_.initialised) return try_initialise(epoch_);
  have_epoch_ = true;  // handed to the executive with the next minor frame
  return Status::kOk;
}

template <class Layout>
Status FlightApp<Layout>::try_initialise(const GnssEpoch& epoch) {
  ++health_.gnss_before_init;
  if (level_count_ < cfg_.levelling_samples) {
    ++health_.init_not_level;
    return Status::kOk;
  }
  GnssPvt fix;
  if (epoch.n_obs < cfg_.min_satellites_for_init || gnss_pvt(epoch, fix) != Status::kOk ||
      fix.n_used < cfg_.min_satellites_for_init) {
    ++health_.init_no_fix;
    return Status::kOk;
  }
  if (!(fix.pdop <= cfg_.max_init_pdop)) {
    ++health_.init_bad_geometry;
    return Status::kOk;
  }
  NavState nav;
  nav.t_s = epoch.t_s;
  nav.llh = llh_from_ecef(fix.r_ecef_m);
  nav.vel_enu_mps = C_n_e(nav.llh.x(), nav.llh.y()).transpose() * fix.v_ecef_mps;
  const double ground_speed = std::hypot(nav.vel_enu_mps.x(), nav.vel_enu_mps.y());
  if (!(ground_speed >= cfg_.min_init_speed_mps)) {
    ++health_.init_too_slow;
    return Status::kOk;
  }
  double roll = 0.0, pitch = 0.0;
  levelled_roll_pitch(roll, pitch);
  const double heading = std::atan2(nav.vel_enu_mps.x(), nav.vel_enu_mps.y()) + cfg_.init_heading_offset_rad;
  nav.q_b_n = Quat(C_b_n_from_euler(roll, pitch, heading));
  const Status st = exec_.init(cfg_.exec, nav);
  if (st != Status::kOk) return st;
  health_.initialised = true;
  health_.init_t_s = epoch.t_s;
  health_.init_fix = fix;
  n_batch_ = 0;
  have_epoch_ = false;  // this epoch initialised the solution; the EKF starts with the next one
  have_pvt_ = false;
  return Status::kOk;
}

template <class Layout>
void FlightApp<Layout>::levelled_roll_pitch(double& roll, double& pitch) const {
  // Levelling: mean specific force in body axes, f_b = (g sin(pitch), -g sin(roll) cos(pitch),
  // -g cos(roll) cos(pitch)) in unaccelerated motion (body x forward, y right, z down).
  Vec3 dv = Vec3::Zero();
  double dt = 0.0;
  for (int k = 0; k < level_count_; ++k) {
    dv += level_dv_[static_cast<std::size_t>(k)];
    dt += level_dt_[static_cast<std::size_t>(k)];
  }
  const Vec3 f = dv / dt;
  roll = std::atan2(-f.y(), -f.z());
  pitch = std::atan2(f.x(), std::hypot(f.y(), f.z()));
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
  if (!health_.initialised) return try_initialise_pvt(m);
  pvt_ = m;
  have_pvt_ = true;  // handed to the executive with the next minor frame
  return Status::kOk;
}

template <class Layout>
Status FlightApp<Layout>::try_initialise_pvt(const GnssPvtMeasurement& m) {
  ++health_.pvt_before_init;
  if (level_count_ < cfg_.levelling_samples) {
    ++health_.init_not_level;
    return Status::kOk;
  }
  if (!m.has_velocity) {
    ++health_.init_no_fix;  // no velocity, no heading
    return Status::kOk;
  }
  const double ground_speed = std::hypot(m.vel_enu_mps.x(), m.vel_enu_mps.y());
  if (!(ground_speed >= cfg_.min_init_speed_mps)) {
    ++health_.init_too_slow;
    return Status::kOk;
  }
  double roll = 0.0, pitch = 0.0;
  levelled_roll_pitch(roll, pitch);
  const double heading = std::atan2(m.vel_enu_mps.x(), m.vel_enu_mps.y()) + cfg_.init_heading_offset_rad;
  const Mat3 C = C_b_n_from_euler(roll, pitch, heading);
  NavState nav;
  nav.t_s = m.t_s;
  // The IMU reference point: the antenna moved back by the lever arm (the lever arm's rotation
  // velocity is left in the velocity's uncertainty).
  nav.llh = m.llh + llh_delta_from_enu(m.llh, -(C * cfg_.exec.ekf.lever_arm_b_m));
  nav.vel_enu_mps = m.vel_enu_mps;
  nav.q_b_n = Quat(C);
  const Status st = exec_.init(cfg_.exec, nav);
  if (st != Status::kOk) return st;
  health_.initialised = true;
  health_.init_t_s = m.t_s;
  health_.init_fix = GnssPvt{};
  health_.init_fix.r_ecef_m = ecef_from_llh(m.llh);
  health_.init_fix.v_ecef_mps = C_n_e(m.llh.x(), m.llh.y()) * m.vel_enu_mps;
  health_.init_fix.n_used = m.n_sat;
  n_batch_ = 0;
  have_epoch_ = false;  // this solution initialised the solution; the EKF starts with the next one
  have_pvt_ = false;
  return Status::kOk;
}

template <class Layout>
Status FlightApp<Layout>::on_imu(const ImuSample& s, FrameOutput& out) {
  out.nav_valid = false;
  out.ekf_ran = false;
  out.ekf_updated = false;
  if (!configured_) return Status::kNotInitialised;
  ++health_.imu_received;
  if (!health_.initialised) {
    ++health_.imu_before_init;
    if (!(s.dt_s > 0.0) || !s.dv_mps.allFinite() || !std::isfinite(s.dt_s)) {
      ++health_.imu_rejected;
      return Status::kBadInput;
    }
    const int n = cfg_.levelling_samples;
    level_dv_[static_cast<std::size_t>(level_head_)] = s.dv_mps;
    level_dt_[static_cast<std::size_t>(level_head_)] = s.dt_s;
    level_head_ = (level_head_ + 1) % n;
    if (level_count_ < n) ++level_count_;
    return Status::kOk;
  }
  if (!(s.t_s > exec_.ins().state().t_s) && n_batch_ == 0) {
    ++health_.imu_rejected;  // at or before the initialisation epoch: already represented
    return Status::kOk;
  }
  batch_[static_cast<std::size_t>(n_batch_++)] = s;
  if (n_batch_ < cfg_.exec.imu_samples_per_frame) return Status::kOk;
  FrameInput in;
  in.imu = batch_.data();
  in.n_imu = n_batch_;
  in.gnss = have_epoch_ ? &epoch_ : nullptr;
  in.pvt = have_pvt_ ? &pvt_ : nullptr;
  in.prev_tick_exec_s = prev_tick_exec_s_;
  have_epoch_ = false;
  have_pvt_ = false;
  n_batch_ = 0;
  return exec_.tick(in, out);
}

template class FlightApp<Layout15Full>;
template class FlightApp<Layout24Full>;
template class FlightApp<LayoutDiag>;

}  // namespace fsw
