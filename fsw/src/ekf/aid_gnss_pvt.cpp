// The EKF's position/velocity aid: a GNSS solution of the antenna (fsw/ekf/aid_gnss_pvt.hpp).
#include "fsw/ekf/aid_gnss_pvt.hpp"

#include <algorithm>
#include <cmath>

#include "fsw/ekf.hpp"

namespace fsw {

PvtModel pvt_measurement_model(const GnssPvtMeasurement& m, const NavState& nav, const Vec3& omega_ib_b_radps,
                               const Vec3& lever_arm_b_m, double time_offset_s, const Vec3& accel_enu_mps2) {
  PvtModel o;
  const Mat3 C = nav.C_b_n();
  const Vec3 l_n = C * lever_arm_b_m;
  const Vec3 w_ie = omega_ie_n(nav.llh.x());
  const Vec3 w_rel_b = omega_ib_b_radps - C.transpose() * w_ie;
  const Vec3 lw_n = C * w_rel_b.cross(lever_arm_b_m);
  // As the raw aid: the INS at the solution's GNSS time plus the estimated IMU-GNSS offset.
  const double dt_ins = m.t_s + time_offset_s - nav.t_s;
  const Vec3 v_ant = nav.vel_enu_mps + lw_n;
  const Vec3 d_ant = l_n + v_ant * dt_ins;  // antenna relative to the INS solution, ENU
  o.llh_ant = nav.llh + llh_delta_from_enu(nav.llh, d_ant);
  o.vel_ant_enu_mps = v_ant + accel_enu_mps2 * time_offset_s;
  // The measured antenna relative to the INS solution in ENU metres at the solution's point (the
  // exact inverse of llh_delta_from_enu there), so no rounded llh sum enters the innovation.
  o.pos_innovation_m = d_ant - enu_difference_m(m.llh, nav.llh);
  o.vel_innovation_mps = o.vel_ant_enu_mps - m.vel_enu_mps;
  // v_a = v + C (w_ib x l) - w_ie x (C l): with C_hat = (I - [phi x]) C both terms move.
  const Mat3 vel_att = skew(lw_n) + skew(w_ie.cross(l_n)) - skew(w_ie) * skew(l_n);
  const Mat3 vel_lever = C * skew(w_rel_b);
  o.H.block<3, 3>(0, 0).setIdentity();
  o.H.block<3, 3>(0, 3) = Mat3::Identity() * dt_ins;
  o.H.block<3, 3>(0, 6) = skew(l_n) + dt_ins * vel_att;
  o.H.block<3, 3>(0, 9) = C + dt_ins * vel_lever;
  o.H.block<3, 1>(0, 12) = v_ant;
  o.H.block<3, 3>(3, 3).setIdentity();
  o.H.block<3, 3>(3, 6) = vel_att;
  o.H.block<3, 3>(3, 9) = vel_lever;
  o.H.block<3, 1>(3, 12) = accel_enu_mps2;
  return o;
}

PvtUsable pvt_usable(const GnssPvtMeasurement& m) {
  PvtUsable u;
  u.pos = m.llh.allFinite() && std::abs(m.llh.x()) <= 0.5 * kPi && m.pos_sigma_enu_m.allFinite() &&
          (m.pos_sigma_enu_m.array() > 0.0).all();
  u.vel = m.has_velocity && m.vel_enu_mps.allFinite() && m.vel_sigma_enu_mps.allFinite() &&
          (m.vel_sigma_enu_mps.array() > 0.0).all();
  return u;
}

template <class Layout>
Status Ekf<Layout>::update_pvt(const GnssPvtMeasurement& m, const NavState& nav, const Vec3& omega_ib_b_radps,
                               EkfUpdateReport& report) {
  report = EkfUpdateReport{};
  report.pvt = true;
  if (!initialised_) return Status::kNotInitialised;
  if (!std::isfinite(m.t_s) || !omega_ib_b_radps.allFinite() || !nav.llh.allFinite() || !nav.vel_enu_mps.allFinite() ||
      !nav.q_b_n.coeffs().allFinite()) {
    ++health_.nonfinite_rejected;
    return Status::kBadInput;
  }
  // Observation: the usable parts of the solution.
  const PvtUsable use = pvt_usable(m);
  if (!use.pos) {
    ++report.obs_invalid;
    for (int i = 0; i < 3; ++i) report.pvt_obs[static_cast<std::size_t>(i)].outcome = InnovationOutcome::kInvalid;
  }
  if (m.has_velocity && !use.vel) {
    ++report.obs_invalid;
    for (int i = 3; i < 6; ++i) report.pvt_obs[static_cast<std::size_t>(i)].outcome = InnovationOutcome::kInvalid;
  }
  if (use.pos || use.vel) {
    const double lat = nav.llh.x();
    // The frame's kinematic acceleration, exactly as the raw aid forms it for the time-offset terms.
    const Vec3 a_n = last_f_enu_mps2_ - Vec3(0.0, 0.0, normal_gravity_mps2(lat, nav.llh.z()));
    if (!std::isfinite(drift_t_ref_s_)) drift_t_ref_s_ = m.t_s;
    const double drift_lever_s = m.t_s - drift_t_ref_s_;  // d offset / d drift
    const PvtModel mdl =
        pvt_measurement_model(m, nav, omega_ib_b_radps, lever_arm_hat_b_m_, time_offset_at(m.t_s), a_n);
    // Re-acquisition after a PVT runaway reset: this update is not gated (the reset opened the
    // position and velocity variances, so the solution is taken nearly as it is).
    ungated_ = reacquire_pvt_;
    reacquire_pvt_ = false;
    for (int i = 0; i < 6; ++i) {
      if (i < 3 ? !use.pos : !use.vel) continue;
      report.pvt_obs[static_cast<std::size_t>(i)] = fuse_pvt_axis(i, m, mdl, drift_lever_s, report);
    }
    ungated_ = false;
  }
  check_covariance();
  track_consistency(report);
  return Status::kOk;
}

template <class Layout>
PvtInnovation Ekf<Layout>::fuse_pvt_axis(int i, const GnssPvtMeasurement& m, const PvtModel& mdl, double drift_lever_s,
                                         EkfUpdateReport& report) {
  const bool is_pos = i < 3;
  const int a = is_pos ? i : i - 3;
  // Variance: the solver's own sigma, floored and scaled.
  const double sig = is_pos ? std::max(m.pos_sigma_enu_m(a), cfg_.pvt_pos_sigma_floor_m)
                            : std::max(m.vel_sigma_enu_mps(a), cfg_.pvt_vel_sigma_floor_mps);
  const double scale2 = cfg_.pvt_sigma_scale * cfg_.pvt_sigma_scale;
  // The row of the model in this layout's states, the innovation, then gate and fuse.
  RowVec h = RowVec::Zero();
  h.template head<9>() = mdl.H.template block<1, 9>(i, 0);
  if constexpr (Layout::has(Block::kLeverArm))
    h.template segment<3>(Layout::offset(Block::kLeverArm)) = mdl.H.template block<1, 3>(i, 9);
  if constexpr (Layout::has(Block::kTimeOffset)) h(Layout::offset(Block::kTimeOffset)) = mdl.H(i, 12);
  if constexpr (Layout::has(Block::kTimeDrift)) h(Layout::offset(Block::kTimeDrift)) = mdl.H(i, 12) * drift_lever_s;
  const double y = is_pos ? mdl.pos_innovation_m(a) : mdl.vel_innovation_mps(a);
  PvtInnovation inn;
  inn.outcome = fuse(h, y, scale2 * sig * sig, inn.innovation, inn.variance, report);
  if (inn.outcome == InnovationOutcome::kUsed)
    ++(is_pos ? report.pos_used : report.vel_used);
  else
    ++(is_pos ? report.pos_rejected : report.vel_rejected);
  return inn;
}

// The members defined here, for every layout (the list: FSW_FOR_EACH_LAYOUT, fsw/error_state.hpp).
#define FSW_EKF_PVT_AID_INSTANTIATE(L)                                                                             \
  template Status Ekf<L>::update_pvt(const GnssPvtMeasurement&, const NavState&, const Vec3&, EkfUpdateReport&);  \
  template PvtInnovation Ekf<L>::fuse_pvt_axis(int, const GnssPvtMeasurement&, const PvtModel&, double,           \
                                               EkfUpdateReport&);
FSW_FOR_EACH_LAYOUT(FSW_EKF_PVT_AID_INSTANTIATE)
#undef FSW_EKF_PVT_AID_INSTANTIATE

}  // namespace fsw
