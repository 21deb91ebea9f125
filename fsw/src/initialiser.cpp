// The flight application's initialisation (see fsw/initialiser.hpp).
#include "fsw/initialiser.hpp"

#include <algorithm>
#include <cmath>

namespace fsw {

void Initialiser::reset(const FlightAppConfig& cfg) {
  level_head_ = 0;
  level_count_ = 0;
  window_.reset();
  interval_.reset();
  prev_epoch_at_rest_ = false;
  vm_q_b_b0_ = Quat::Identity();
  vm_alpha_.setZero();
  vm_last_f_b_.setZero();
  vm_bias_radps_.setZero();
  vm_gyro_sigma_radps_ = cfg.exec.ekf.gyro_bias_sigma_radps;
  vm_hist_head_ = 0;
  vm_hist_count_ = 0;
  vm_window_open_ = false;
  vm_.reset();
}

Status Initialiser::on_imu(const ImuSample& s, const FlightAppConfig& cfg, FlightAppHealth& health) {
  const bool aligning = cfg.init_mode != InitMode::kTrack;
  if (!(s.dt_s > 0.0) || !s.dv_mps.allFinite() || !std::isfinite(s.dt_s) ||
      (aligning && (!s.dtheta_rad.allFinite() || !std::isfinite(s.t_s)))) {
    ++health.imu_rejected;
    return Status::kBadInput;
  }
  if (cfg.init_mode == InitMode::kVelocityMatching && vm_hist_count_ > 0 && !(s.t_s > vm_newest_t_s())) {
    ++health.imu_rejected;  // not after the previous sample: the history must be in time order
    return Status::kOk;
  }
  const int n = cfg.levelling_samples;
  level_dv_[static_cast<std::size_t>(level_head_)] = s.dv_mps;
  level_dt_[static_cast<std::size_t>(level_head_)] = s.dt_s;
  level_head_ = (level_head_ + 1) % n;
  if (level_count_ < n) ++level_count_;
  if (aligning) {
    (void)interval_.add(s);  // validated above
    if (cfg.init_mode == InitMode::kVelocityMatching) vm_imu(s);
  }
  return Status::kOk;
}

Status Initialiser::on_gnss(const GnssEpoch& epoch, const FlightAppConfig& cfg, FlightAppHealth& health,
                            InitialState& out, bool& ready) {
  ready = false;
  ++health.gnss_before_init;
  if (cfg.init_mode == InitMode::kGiven) return Status::kOk;  // waits for FlightApp::start_given()
  if (cfg.init_mode == InitMode::kTrack && level_count_ < cfg.levelling_samples) {
    ++health.init_not_level;
    return Status::kOk;
  }
  GnssPvt fix;
  if (epoch.n_obs < cfg.min_satellites_for_init || gnss_pvt(epoch, fix) != Status::kOk ||
      fix.n_used < cfg.min_satellites_for_init) {
    ++health.init_no_fix;
    return Status::kOk;
  }
  if (!(fix.pdop <= cfg.max_init_pdop)) {
    ++health.init_bad_geometry;
    return Status::kOk;
  }
  InitFix f;
  f.t_s = epoch.t_s;
  f.llh = llh_from_ecef(fix.r_ecef_m);
  f.vel_enu_mps = C_n_e(f.llh.x(), f.llh.y()).transpose() * fix.v_ecef_mps;
  f.vel_sigma_mps = cfg.exec.ekf.pseudorange_rate_sigma_mps * fix.pdop;
  f.antenna = false;
  ready = init_from_fix(f, cfg, health, out);
  if (ready) out.fix = fix;
  return Status::kOk;
}

Status Initialiser::on_pvt(const GnssPvtMeasurement& m, const FlightAppConfig& cfg, FlightAppHealth& health,
                           InitialState& out, bool& ready) {
  ready = false;
  ++health.pvt_before_init;
  if (cfg.init_mode == InitMode::kGiven) return Status::kOk;  // waits for FlightApp::start_given()
  if (cfg.init_mode == InitMode::kTrack && level_count_ < cfg.levelling_samples) {
    ++health.init_not_level;
    return Status::kOk;
  }
  if (!m.has_velocity) {
    ++health.init_no_fix;  // no velocity, no heading (kStatic: no rest test)
    return Status::kOk;
  }
  InitFix f;
  f.t_s = m.t_s;
  f.llh = m.llh;
  f.vel_enu_mps = m.vel_enu_mps;
  f.vel_sigma_mps = m.vel_sigma_enu_mps.maxCoeff();
  f.antenna = true;
  ready = init_from_fix(f, cfg, health, out);
  if (ready) {
    out.fix = GnssPvt{};
    out.fix.r_ecef_m = ecef_from_llh(m.llh);
    out.fix.v_ecef_mps = C_n_e(m.llh.x(), m.llh.y()) * m.vel_enu_mps;
    out.fix.n_used = m.n_sat;
  }
  return Status::kOk;
}

bool Initialiser::init_from_fix(const InitFix& f, const FlightAppConfig& cfg, FlightAppHealth& health,
                                InitialState& out) {
  switch (cfg.init_mode) {
    case InitMode::kTrack: return init_track(f, cfg, health, out);
    case InitMode::kStatic: return init_static(f, cfg, health, out);
    case InitMode::kVelocityMatching: return init_velocity_matching(f, cfg, health, out);
    case InitMode::kGiven: break;
  }
  return false;
}

bool Initialiser::init_track(const InitFix& f, const FlightAppConfig& cfg, FlightAppHealth& health,
                             InitialState& out) const {
  const double ground_speed = std::hypot(f.vel_enu_mps.x(), f.vel_enu_mps.y());
  if (!(ground_speed >= cfg.min_init_speed_mps)) {
    ++health.init_too_slow;
    return false;
  }
  double roll = 0.0, pitch = 0.0;
  levelled_roll_pitch(roll, pitch);
  const double heading = std::atan2(f.vel_enu_mps.x(), f.vel_enu_mps.y()) + cfg.init_heading_offset_rad;
  const Mat3 C = C_b_n_from_euler(roll, pitch, heading);
  out.nav.t_s = f.t_s;
  // A solution's antenna: the IMU reference point is the antenna moved back by the lever arm (the
  // lever arm's rotation velocity is left in the velocity's uncertainty).
  out.nav.llh = f.antenna ? Vec3(f.llh + llh_delta_from_enu(f.llh, -(C * cfg.exec.ekf.lever_arm_b_m))) : f.llh;
  out.nav.vel_enu_mps = f.vel_enu_mps;
  out.nav.q_b_n = Quat(C);
  out.att_sigma_rad = cfg.init_att_sigma_rad;
  out.align_s = 0.0;
  return true;
}

bool Initialiser::rest_epoch(double ground_speed_mps, const FlightAppConfig& cfg) {
  const bool gnss_rest = ground_speed_mps <= cfg.static_max_speed_mps;
  bool imu_rest = true;
  if (gnss_rest && prev_epoch_at_rest_ && interval_.duration_s() > 0.0 && window_.duration_s() > 0.0) {
    const double df = (interval_.mean_f_b_mps2() - window_.mean_f_b_mps2()).norm();
    const double dw = (interval_.mean_omega_b_radps() - window_.mean_omega_b_radps()).norm();
    imu_rest = df <= cfg.static_max_accel_dev_mps2 && dw <= cfg.static_max_rate_dev_radps;
  }
  if (!gnss_rest || !imu_rest) {
    window_.reset();
    interval_.reset();
    prev_epoch_at_rest_ = false;
    return false;
  }
  // Only an interval bracketed by two epochs at rest joins the window; the first one after motion
  // (or the very first one) is dropped.
  if (prev_epoch_at_rest_) window_.merge(interval_);
  interval_.reset();
  prev_epoch_at_rest_ = true;
  return true;
}

bool Initialiser::init_static(const InitFix& f, const FlightAppConfig& cfg, FlightAppHealth& health,
                              InitialState& out) {
  if (!rest_epoch(std::hypot(f.vel_enu_mps.x(), f.vel_enu_mps.y()), cfg)) {
    ++health.init_moving;
    return false;
  }
  if (window_.duration_s() < cfg.alignment_s) {
    ++health.init_aligning;
    return false;
  }
  Mat3 C;
  if (window_.solve(f.llh.x(), C) != Status::kOk) {
    ++health.init_align_failed;
    window_.reset();
    return false;
  }
  out.nav.t_s = f.t_s;
  out.nav.llh = f.antenna ? Vec3(f.llh + llh_delta_from_enu(f.llh, -(C * cfg.exec.ekf.lever_arm_b_m))) : f.llh;
  out.nav.vel_enu_mps = f.vel_enu_mps;
  out.nav.q_b_n = Quat(C);
  out.nav.q_b_n.normalize();
  out.att_sigma_rad = cfg.init_att_sigma_rad;
  out.align_s = window_.duration_s();
  return true;
}

void Initialiser::vm_imu(const ImuSample& s) {
  // C_b^b0 and alpha = integral C_b^b0 f_b dt, one rotation-vector step per sample; the
  // specific-force increment is rotated to the sample's mid-attitude (dv + dtheta x dv / 2).
  const Vec3 dth = s.dtheta_rad - vm_bias_radps_ * s.dt_s;
  const Mat3 C = vm_q_b_b0_.toRotationMatrix();
  const Vec3 dv_b0 = C * (s.dv_mps + 0.5 * dth.cross(s.dv_mps));
  // Gyro-bias sensitivities (fsw::VelocityMatchAlignment): Theta = integral C_b^b0 dt and
  // G = -integral [f_b0 x] Theta dt, Theta taken at the sample's middle.
  const Mat3 theta_mid = vm_theta_ + 0.5 * s.dt_s * C;
  vm_G_.noalias() -= skew(dv_b0).lazyProduct(theta_mid);
  vm_theta_ += s.dt_s * C;
  vm_alpha_ += dv_b0;
  vm_q_b_b0_ = vm_q_b_b0_ * quat_from_rotvec(dth);
  vm_q_b_b0_.normalize();
  vm_last_f_b_ = s.dv_mps / s.dt_s;
  vm_hist_t_[static_cast<std::size_t>(vm_hist_head_)] = s.t_s;
  vm_hist_alpha_[static_cast<std::size_t>(vm_hist_head_)] = vm_alpha_;
  vm_hist_head_ = (vm_hist_head_ + 1) % kVmHistory;
  if (vm_hist_count_ < kVmHistory) ++vm_hist_count_;
}

bool Initialiser::vm_alpha_at(double t_s, Vec3& alpha) const {
  if (vm_hist_count_ < 2) return false;
  const auto slot = [this](int back) {  // back = 0: the newest sample
    return static_cast<std::size_t>((vm_hist_head_ - 1 - back + 2 * kVmHistory) % kVmHistory);
  };
  const double t_new = vm_hist_t_[slot(0)];
  if (t_s >= t_new) {
    if (t_s - t_new > kVmMaxExtrapolation_s) return false;
    alpha = vm_alpha_ + vm_q_b_b0_ * (vm_last_f_b_ * (t_s - t_new));
    return true;
  }
  for (int back = 1; back < vm_hist_count_; ++back) {
    const double t_a = vm_hist_t_[slot(back)];
    if (t_a <= t_s) {
      const double t_b = vm_hist_t_[slot(back - 1)];
      const double u = t_b > t_a ? (t_s - t_a) / (t_b - t_a) : 1.0;
      alpha = vm_hist_alpha_[slot(back)] + u * (vm_hist_alpha_[slot(back - 1)] - vm_hist_alpha_[slot(back)]);
      return true;
    }
  }
  return false;  // older than the history
}

double Initialiser::vm_newest_t_s() const {
  return vm_hist_t_[static_cast<std::size_t>((vm_hist_head_ - 1 + kVmHistory) % kVmHistory)];
}

void Initialiser::vm_open_window(const InitFix& f, const FlightAppConfig& cfg) {
  // Re-base: b0 becomes the newest sample's body frame; alpha and its history rotate with it.
  const Quat q_b0_new = vm_q_b_b0_.conjugate();
  for (int k = 0; k < vm_hist_count_; ++k) {
    Vec3& a = vm_hist_alpha_[static_cast<std::size_t>(k)];
    a = q_b0_new * (a - vm_alpha_);
  }
  vm_alpha_.setZero();
  vm_q_b_b0_ = Quat::Identity();
  vm_theta_.setZero();
  vm_G_.setZero();
  vm_.reset();
  vm_window_open_ = false;
  if (cfg.vm_rest_gyro_bias && prev_epoch_at_rest_ && window_.duration_s() >= cfg.vm_rest_min_s) {
    // What remains of the bias: the noise of the rest mean and the Earth rate, whose body
    // components change when the body turns.
    vm_bias_radps_ = window_.mean_omega_b_radps();
    const double arw = cfg.exec.ekf.arw_rad_per_rts;
    vm_gyro_sigma_radps_ = std::min(cfg.exec.ekf.gyro_bias_sigma_radps,
                                    std::sqrt(arw * arw / window_.duration_s() +
                                              wgs84::omega_ie_radps * wgs84::omega_ie_radps));
  }
  Vec3 alpha0;
  if (!vm_alpha_at(f.t_s, alpha0)) return;
  vm_window_open_ = true;
  vm_t0_s_ = f.t_s;
  vm_v0_ = f.vel_enu_mps;
  vm_alpha0_ = alpha0;
  vm_g_n_ = gravity_enu_mps2(f.llh.x(), f.llh.z());
  // t_0 is a pair too (alpha = beta = 0) with its own velocity error: the solver fits the
  // common offset that error puts into every later pair.
  (void)vm_.add(Vec3::Zero(), Vec3::Zero(), 1.0 / std::max(f.vel_sigma_mps * f.vel_sigma_mps, 1e-12));
}

bool Initialiser::init_velocity_matching(const InitFix& f, const FlightAppConfig& cfg, FlightAppHealth& health,
                                         InitialState& out) {
  const double ground_speed = std::hypot(f.vel_enu_mps.x(), f.vel_enu_mps.y());
  (void)rest_epoch(ground_speed, cfg);  // the rest window (gyro bias estimate) and its bookkeeping
  Vec3 alpha_k;
  if (!vm_alpha_at(f.t_s, alpha_k)) {
    ++health.init_not_level;  // no IMU history at this time (yet)
    return false;
  }
  const bool at_rest = ground_speed <= cfg.static_max_speed_mps;
  const double dt = f.t_s - vm_t0_s_;
  if (!vm_window_open_ || (at_rest && dt < cfg.vm_min_s)) {
    vm_open_window(f, cfg);  // the first window, or rest: start (again) here
    ++health.init_aligning;
    return false;
  }
  if (dt > cfg.vm_max_s || !(dt > 0.0)) {
    vm_open_window(f, cfg);
    ++health.init_align_restarts;
    return false;
  }
  const Vec3 beta = f.vel_enu_mps - vm_v0_ - vm_g_n_ * dt;
  // White error budget of the pair (file header): the fix's velocity noise and the IMU's white
  // noise (velocity random walk; the angle random walk tilts b0 and leaks gravity into alpha). The
  // gyro and accelerometer biases enter the solver as nuisance parameters through G and Theta.
  const double g = vm_g_n_.norm();
  const double arw = cfg.exec.ekf.arw_rad_per_rts;
  const double s_tilt = g * arw * dt * std::sqrt(dt / 3.0);
  const double vrw = cfg.exec.ekf.vrw_mps_per_rts;
  const double var = f.vel_sigma_mps * f.vel_sigma_mps + vrw * vrw * dt + s_tilt * s_tilt;
  if (!(var > 0.0) || vm_.add(alpha_k - vm_alpha0_, beta, 1.0 / var, vm_G_, vm_theta_) != Status::kOk) {
    ++health.init_align_failed;
    return false;
  }
  if (dt < cfg.vm_min_s) {
    ++health.init_aligning;
    return false;
  }
  Mat3 C_b0_n;
  Vec3 sigma;
  if (vm_.solve(C_b0_n, sigma, vm_gyro_sigma_radps_, cfg.exec.ekf.accel_bias_sigma_mps2) != Status::kOk ||
      !(sigma.z() <= cfg.vm_max_heading_sigma_rad)) {
    // Not determined yet. At rest the window starts again here: rest adds no heading information,
    // only gyro error.
    if (at_rest) vm_open_window(f, cfg);
    ++health.init_aligning;
    return false;
  }
  // Propagate to the newest IMU sample.
  const double t_new = vm_newest_t_s();
  // The window's bias estimates correct the integration up to the newest sample: its attitude
  // drifted by Theta eps (C_true = (I - [Theta eps x]) C_hat), its alpha by G eps + Theta b_a.
  const Vec3& eps = vm_.gyro_bias_radps();
  const Vec3& b_a = vm_.accel_bias_mps2();
  const Mat3 C = C_b0_n * quat_from_rotvec(-(vm_theta_ * eps)).toRotationMatrix() * vm_q_b_b0_.toRotationMatrix();
  NavState& nav = out.nav;
  nav.t_s = t_new;
  // The fitted velocity (every epoch of the window through the fitted offset), at the newest sample.
  const Vec3 alpha_new = vm_alpha_ - vm_alpha0_ - vm_G_ * eps - vm_theta_ * b_a;
  nav.vel_enu_mps = vm_v0_ - vm_.offset_mps() + C_b0_n * alpha_new + vm_g_n_ * (t_new - vm_t0_s_);
  Vec3 d_enu = f.vel_enu_mps * (t_new - f.t_s);
  if (f.antenna) d_enu -= C * cfg.exec.ekf.lever_arm_b_m;
  nav.llh = f.llh + llh_delta_from_enu(f.llh, d_enu);
  nav.q_b_n = Quat(C);
  nav.q_b_n.normalize();
  out.att_sigma_rad = sigma;
  out.align_s = dt;
  out.vm_biases = true;
  out.vm_gyro_bias_radps = vm_bias_radps_ + eps;
  out.vm_accel_bias_mps2 = b_a;
  return true;
}

void Initialiser::levelled_roll_pitch(double& roll, double& pitch) const {
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

}  // namespace fsw
