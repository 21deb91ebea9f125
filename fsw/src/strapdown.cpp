#include "fsw/strapdown.hpp"

namespace fsw {

Status FrameBuilder::configure(int samples_per_frame) {
  if (samples_per_frame < 1 || samples_per_frame > kMaxSamplesPerFrame) return Status::kBadConfig;
  n_per_frame_ = samples_per_frame;
  reset();
  return Status::kOk;
}

void FrameBuilder::reset() {
  n_in_frame_ = 0;
  have_prev_sample_ = false;
  prev_dtheta_.setZero();
  prev_dv_.setZero();
  alpha_.setZero();
  nu_.setZero();
  beta_.setZero();
  scul_.setZero();
  dt_acc_ = 0.0;
}

Status FrameBuilder::add(const ImuSample& s) {
  if (!s.dtheta_rad.allFinite() || !s.dv_mps.allFinite() || !std::isfinite(s.dt_s) || !(s.dt_s > 0.0) ||
      !std::isfinite(s.t_s)) {
    return Status::kBadInput;
  }
  // Savage, Strapdown Analytics (2nd ed.), eqs. 7.1.1.1-11 and 7.2.2.2.2-15: high-rate coning
  // (beta) and sculling terms using the running sums and the previous sample (which may lie in the
  // previous frame; that is what makes the algorithm exact for linearly varying rates).
  const Vec3 dth_prev = have_prev_sample_ ? prev_dtheta_ : s.dtheta_rad;
  const Vec3 dv_prev = have_prev_sample_ ? prev_dv_ : s.dv_mps;
  const Vec3 a_term = alpha_ + dth_prev / 6.0;
  const Vec3 v_term = nu_ + dv_prev / 6.0;
  beta_ += 0.5 * a_term.cross(s.dtheta_rad);
  scul_ += 0.5 * (a_term.cross(s.dv_mps) + v_term.cross(s.dtheta_rad));
  alpha_ += s.dtheta_rad;
  nu_ += s.dv_mps;
  dt_acc_ += s.dt_s;
  prev_dtheta_ = s.dtheta_rad;
  prev_dv_ = s.dv_mps;
  have_prev_sample_ = true;
  if (++n_in_frame_ < n_per_frame_) return Status::kFrameIncomplete;

  frame_.t_s = s.t_s;
  frame_.dt_s = dt_acc_;
  frame_.dtheta_sum_rad = alpha_;
  frame_.dv_sum_mps = nu_;
  frame_.rotvec_rad = alpha_ + beta_;
  frame_.dv_sf_b_mps = nu_ + 0.5 * alpha_.cross(nu_) + scul_;
  n_in_frame_ = 0;
  alpha_.setZero();
  nu_.setZero();
  beta_.setZero();
  scul_.setZero();
  dt_acc_ = 0.0;
  return Status::kOk;
}

Status Strapdown::init(const NavState& s) {
  if (!s.llh.allFinite() || !s.vel_enu_mps.allFinite() || !std::isfinite(s.q_b_n.w()) || !s.q_b_n.vec().allFinite() ||
      std::abs(s.llh.x()) > 0.5 * kPi) {
    return Status::kBadInput;
  }
  cur_ = s;
  cur_.q_b_n.normalize();
  prev_ = cur_;
  have_prev_ = false;
  initialised_ = true;
  return Status::kOk;
}

Status Strapdown::step(const FrameIncrement& inc) {
  if (!initialised_) return Status::kNotInitialised;
  if (!inc.rotvec_rad.allFinite() || !inc.dv_sf_b_mps.allFinite() || !(inc.dt_s > 0.0) || !std::isfinite(inc.dt_s)) {
    return Status::kBadInput;
  }
  const double T = inc.dt_s;
  const NavState k1 = cur_;  // state at t(k-1)

  // Midpoint (t(k-1) + T/2) position and velocity, extrapolated from the last two frames.
  Vec3 llh_mid = k1.llh;
  Vec3 vel_mid = k1.vel_enu_mps;
  if (have_prev_) {
    llh_mid = 1.5 * k1.llh - 0.5 * prev_.llh;
    vel_mid = 1.5 * k1.vel_enu_mps - 0.5 * prev_.vel_enu_mps;
  }
  const LatitudeTerms lat_k_mid(llh_mid.x());  // one sine and cosine for the radii, rates and gravity there
  const Vec3 w_ie = omega_ie_n(lat_k_mid);
  const Vec3 w_en = omega_en_n(lat_k_mid, llh_mid.z(), vel_mid);
  const Vec3 zeta = (w_ie + w_en) * T;

  // Velocity update.
  const Mat3 C_b_n_k1 = k1.C_b_n();
  const Vec3 dv_sf_enu_mps = (Mat3::Identity() - 0.5 * skew(zeta)) * (C_b_n_k1 * inc.dv_sf_b_mps);
  const Vec3 g_enu_mps2 = gravity_enu_mps2(lat_k_mid, llh_mid.z());
  const Vec3 dv_cor_g = (g_enu_mps2 - (2.0 * w_ie + w_en).cross(vel_mid)) * T;
  NavState k = k1;
  k.t_s = inc.t_s;
  k.vel_enu_mps = k1.vel_enu_mps + dv_sf_enu_mps + dv_cor_g;

  // Position update (trapezoidal velocity, midpoint radii).
  const Vec3 v_avg = 0.5 * (k1.vel_enu_mps + k.vel_enu_mps);
  const double h_new = k1.llh.z() + v_avg.z() * T;
  const double h_mid = 0.5 * (k1.llh.z() + h_new);
  const double lat_mid = k1.llh.x() + 0.5 * v_avg.y() / (meridian_radius_m(k1.llh.x()) + h_mid) * T;
  const double lat_new = k1.llh.x() + v_avg.y() / (meridian_radius_m(lat_mid) + h_mid) * T;
  const LatitudeTerms lat_mid2(0.5 * (k1.llh.x() + lat_new));
  const double lon_new = k1.llh.y() + v_avg.x() / ((normal_radius_m(lat_mid2) + h_mid) * lat_mid2.cos_lat) * T;
  k.llh = Vec3(lat_new, lon_new, h_new);

  // Attitude update: body rotation, then navigation-frame rotation over the frame (midpoint rate
  // recomputed with the updated position and velocity).
  const Vec3 w_in_mid = omega_ie_n(lat_mid2) + omega_en_n(lat_mid2, h_mid, v_avg);
  const Quat q_bb = quat_from_rotvec(inc.rotvec_rad);
  const Quat q_nn = quat_from_rotvec(-w_in_mid * T);
  k.q_b_n = q_nn * k1.q_b_n * q_bb;
  k.q_b_n.normalize();

  f_enu_mps2_ = dv_sf_enu_mps / T;
  omega_ib_b_radps_ = inc.dtheta_sum_rad / T;
  prev_ = k1;
  have_prev_ = true;
  cur_ = k;
  return Status::kOk;
}

Status Strapdown::correct(const Vec3& dpos_enu_m, const Vec3& dvel_enu_mps, const Vec3& phi_enu_rad) {
  if (!initialised_) return Status::kNotInitialised;
  if (!dpos_enu_m.allFinite() || !dvel_enu_mps.allFinite() || !phi_enu_rad.allFinite()) return Status::kBadInput;
  const Vec3 dllh = llh_delta_from_enu(cur_.llh, dpos_enu_m);
  cur_.llh -= dllh;
  cur_.vel_enu_mps -= dvel_enu_mps;
  // C_true = (I - [phi x])^-1 C_hat ~ (I + [phi x]) C_hat: rotate by +phi in n.
  cur_.q_b_n = quat_from_rotvec(phi_enu_rad) * cur_.q_b_n;
  cur_.q_b_n.normalize();
  // Shift the previous frame by the same correction so the midpoint extrapolation stays smooth.
  prev_.llh -= dllh;
  prev_.vel_enu_mps -= dvel_enu_mps;
  return Status::kOk;
}

}  // namespace fsw
