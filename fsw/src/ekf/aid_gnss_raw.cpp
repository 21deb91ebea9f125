// The EKF's raw-GNSS aid: pseudorange and pseudorange rate (fsw/ekf/aid_gnss_raw.hpp).
#include "fsw/ekf/aid_gnss_raw.hpp"

#include <algorithm>
#include <cmath>

#include "fsw/ekf.hpp"
#include "fsw/gnss_delays.hpp"

namespace fsw {

GnssRawAntenna gnss_raw_antenna(double t_s, const NavState& nav, const Vec3& omega_ib_b_radps,
                                const Vec3& lever_arm_b_m, double time_offset_s, const Vec3& f_enu_mps2,
                                bool offset_moves_velocity) {
  GnssRawAntenna a;
  a.lat_rad = nav.llh.x();
  a.lon_rad = nav.llh.y();
  a.C_n_e = C_n_e(a.lat_rad, a.lon_rad);
  a.C_b_n = nav.C_b_n();
  a.lever_enu_m = a.C_b_n * lever_arm_b_m;
  const Vec3 w_ie_b = a.C_b_n.transpose() * omega_ie_n(a.lat_rad);
  a.omega_rel_b_radps = omega_ib_b_radps - w_ie_b;
  a.ins_vel_enu_mps = nav.vel_enu_mps;
  a.accel_enu_mps2 = f_enu_mps2 - Vec3(0.0, 0.0, normal_gravity_mps2(a.lat_rad, nav.llh.z()));
  // INS time tag of the epoch: its GNSS time plus the estimated IMU-GNSS offset at that time.
  const double dt_ins = t_s + time_offset_s - nav.t_s;
  Vec3 v_ant_n = nav.vel_enu_mps + a.C_b_n * a.omega_rel_b_radps.cross(lever_arm_b_m);
  a.r_ecef_m = ecef_from_llh(nav.llh) + a.C_n_e * (a.lever_enu_m + v_ant_n * dt_ins);
  if (offset_moves_velocity) v_ant_n += a.accel_enu_mps2 * time_offset_s;
  a.v_ecef_mps = a.C_n_e * v_ant_n;
  a.h_m = nav.llh.z() + a.lever_enu_m.z();
  return a;
}

bool gnss_observation_usable(const GnssObservation& o) {
  const double rs = o.sat_pos_ecef_m.norm();
  return o.sat_pos_ecef_m.allFinite() && o.sat_vel_ecef_mps.allFinite() && std::isfinite(o.pseudorange_m) &&
         std::isfinite(o.pseudorange_rate_mps) && !(rs < 1.0e7) && !(rs > 1.0e8);
}

GnssRawPrediction gnss_raw_predict(const GnssObservation& o, const GnssRawAntenna& a, double gps_tow_s,
                                   bool with_delays, double tropo_scale, double iono_scale) {
  GnssRawPrediction p;
  p.geo = gnss_geometry(o.sat_pos_ecef_m, o.sat_vel_ecef_mps, a.r_ecef_m, a.v_ecef_mps);
  if (with_delays) {  // modelled delays (diagnosis extensions): added to the predicted range
    const Vec3 los_n = gnss_los_enu(p, a);
    const double el = std::asin(std::clamp(los_n.z(), -1.0, 1.0));
    p.tropo_delay_m = saastamoinen_delay_m(a.lat_rad, a.h_m, el);
    const double az = std::atan2(los_n.x(), los_n.y());
    p.iono_delay_m = klobuchar_delay_m(kKlobucharDefault, gps_tow_s, a.lat_rad, a.lon_rad, az, el);
    p.geo.range_m += tropo_scale * p.tropo_delay_m + iono_scale * p.iono_delay_m;
  }
  return p;
}

template <class Layout>
Status Ekf<Layout>::update(const GnssEpoch& epoch, const NavState& nav, const Vec3& omega_ib_b_radps,
                           EkfUpdateReport& report) {
  report = EkfUpdateReport{};
  if (!initialised_) return Status::kNotInitialised;
  if (epoch.n_obs < 0 || epoch.n_obs > kMaxGnssChannels || !std::isfinite(epoch.t_s) || !omega_ib_b_radps.allFinite() ||
      !nav.llh.allFinite() || !nav.vel_enu_mps.allFinite() || !nav.q_b_n.coeffs().allFinite()) {
    ++health_.nonfinite_rejected;
    return Status::kBadInput;
  }
  // Observation: the antenna at the epoch's time tag, then each satellite's prediction.
  if (!std::isfinite(drift_t_ref_s_)) drift_t_ref_s_ = epoch.t_s;
  const double drift_lever_s = epoch.t_s - drift_t_ref_s_;  // d offset / d drift
  constexpr bool kTimeBlocks = Layout::has(Block::kTimeOffset) || Layout::has(Block::kTimeDrift);
  const GnssRawAntenna ant = gnss_raw_antenna(epoch.t_s, nav, omega_ib_b_radps, lever_arm_hat_b_m_,
                                              time_offset_at(epoch.t_s), last_f_enu_mps2_, kTimeBlocks);
  GnssRawPrediction pred[kMaxGnssChannels];
  bool valid[kMaxGnssChannels] = {};
  const int n_valid = predict_epoch(epoch, ant, pred, valid, report);
  if (!clock_initialised_) {  // reset: this epoch's measurements set the clock; they are not used twice
    if (n_valid == 0) return Status::kOk;
    init_clock(epoch, pred, valid, n_valid);
    report.clock_initialised = true;
    return Status::kOk;
  }
  const double clock_bias_m = clock_bias_m_ + clock_drift_mps_ * (epoch.t_s - nav.t_s);  // clock on GNSS time
  release_channels(epoch, valid);
  for (int k = 0; k < epoch.n_obs; ++k) {
    if (!valid[k]) continue;
    report.obs[static_cast<std::size_t>(k)] =
        fuse_observation(epoch.obs[k], pred[k], ant, clock_bias_m, drift_lever_s, report);
  }
  check_covariance();
  track_consistency(report);
  return Status::kOk;
}

template <class Layout>
int Ekf<Layout>::predict_epoch(const GnssEpoch& epoch, const GnssRawAntenna& ant, GnssRawPrediction* pred, bool* valid,
                               EkfUpdateReport& report) const {
  constexpr bool kDelays = Layout::has(Block::kTropoScale) || Layout::has(Block::kIonoScale);
  int n_valid = 0;
  report.n_obs = epoch.n_obs;
  for (int k = 0; k < epoch.n_obs; ++k) {
    const GnssObservation& o = epoch.obs[k];
    ObservationInnovation& inn = report.obs[static_cast<std::size_t>(k)];
    inn.prn = o.prn;
    if (!gnss_observation_usable(o)) {
      ++report.obs_invalid;
      inn.pr_outcome = InnovationOutcome::kInvalid;
      inn.prr_outcome = InnovationOutcome::kInvalid;
      continue;
    }
    pred[k] = gnss_raw_predict(o, ant, epoch.gps_tow_s, kDelays, tropo_scale_hat_, iono_scale_hat_);
    valid[k] = true;
    ++n_valid;
  }
  return n_valid;
}

template <class Layout>
void Ekf<Layout>::init_clock(const GnssEpoch& epoch, const GnssRawPrediction* pred, const bool* valid, int n_valid) {
  double sum_b = 0.0, sum_d = 0.0;
  for (int k = 0; k < epoch.n_obs; ++k) {
    if (!valid[k]) continue;
    sum_b += epoch.obs[k].pseudorange_m - pred[k].geo.range_m;
    sum_d += epoch.obs[k].pseudorange_rate_mps - pred[k].geo.range_rate_mps;
  }
  clock_bias_m_ = sum_b / n_valid;
  clock_drift_mps_ = sum_d / n_valid;
  clock_initialised_ = true;
}

template <class Layout>
void Ekf<Layout>::release_channels(const GnssEpoch& epoch, const bool* valid) {
  if constexpr (Layout::has(Block::kRangeError) || Layout::has(Block::kRangeRateError)) {
    for (int s = 0; s < kGnssErrorChannels; ++s) {
      bool tracked = false;
      for (int k = 0; k < epoch.n_obs; ++k) tracked = tracked || (valid[k] && epoch.obs[k].prn == slot_prn_[s]);
      if (!tracked) slot_prn_[s] = 0;
    }
  } else {
    (void)epoch;
    (void)valid;
  }
}

template <class Layout>
ObservationInnovation Ekf<Layout>::fuse_observation(const GnssObservation& o, const GnssRawPrediction& p,
                                                    const GnssRawAntenna& ant, double clock_bias_m,
                                                    double drift_lever_s, EkfUpdateReport& report) {
  constexpr int oc = Layout::offset(Block::kClock);
  constexpr bool kChannels = Layout::has(Block::kRangeError) || Layout::has(Block::kRangeRateError);
  ObservationInnovation inn;
  inn.prn = o.prn;
  // Variance: the white noise, plus the correlated error when no channel carries it.
  const int slot = kChannels ? bind_channel(o.prn) : -1;
  double r_pr = cfg_.pseudorange_sigma_m * cfg_.pseudorange_sigma_m;
  double r_prr = cfg_.pseudorange_rate_sigma_mps * cfg_.pseudorange_rate_sigma_mps;
  double range_err = 0.0, rate_err = 0.0;
  RowVec h = RowVec::Zero();
  if constexpr (kChannels) {
    if (slot < 0) {  // no channel left: fold the correlated error into the white noise
      ++report.obs_no_channel;
      r_pr += cfg_.range_gm_sigma_m * cfg_.range_gm_sigma_m;
      r_prr += cfg_.range_rate_gm_sigma_mps * cfg_.range_rate_gm_sigma_mps;
    }
  }
  // Pseudorange: its row, innovation (predicted minus measured), gate and fuse.
  const Vec3 e_n = gnss_los_enu(p, ant);
  h.template segment<3>(0) = -e_n.transpose();
  h.template segment<3>(6) = -e_n.transpose() * skew(ant.lever_enu_m);
  h(oc) = 1.0;
  if constexpr (Layout::has(Block::kTimeOffset)) h(Layout::offset(Block::kTimeOffset)) = -e_n.dot(ant.ins_vel_enu_mps);
  if constexpr (Layout::has(Block::kTimeDrift))
    h(Layout::offset(Block::kTimeDrift)) = -e_n.dot(ant.ins_vel_enu_mps) * drift_lever_s;
  if constexpr (Layout::has(Block::kLeverArm))
    h.template segment<3>(Layout::offset(Block::kLeverArm)) = -e_n.transpose() * ant.C_b_n;
  if constexpr (Layout::has(Block::kTropoScale)) h(Layout::offset(Block::kTropoScale)) = p.tropo_delay_m;
  if constexpr (Layout::has(Block::kIonoScale)) h(Layout::offset(Block::kIonoScale)) = p.iono_delay_m;
  if constexpr (Layout::has(Block::kRangeError)) {
    if (slot >= 0) {
      h(Layout::offset(Block::kRangeError) + slot) = 1.0;
      range_err = range_err_hat_(slot);
    }
  }
  inn.pr_outcome =
      fuse(h, p.geo.range_m + clock_bias_m + range_err - o.pseudorange_m, r_pr, inn.pr_innovation_m, inn.pr_variance_m2,
           report);
  ++(inn.pr_outcome == InnovationOutcome::kUsed ? report.pr_used : report.pr_rejected);
  if (!cfg_.use_pseudorange_rate) return inn;
  // Pseudorange rate: the same steps.
  h.setZero();
  h.template segment<3>(3) = -e_n.transpose();
  h(oc + 1) = 1.0;
  const Vec3& a_n = ant.accel_enu_mps2;
  if constexpr (Layout::has(Block::kTimeOffset)) h(Layout::offset(Block::kTimeOffset)) = -e_n.dot(a_n);
  if constexpr (Layout::has(Block::kTimeDrift)) h(Layout::offset(Block::kTimeDrift)) = -e_n.dot(a_n) * drift_lever_s;
  if constexpr (Layout::has(Block::kLeverArm))
    h.template segment<3>(Layout::offset(Block::kLeverArm)) = -e_n.transpose() * ant.C_b_n * skew(ant.omega_rel_b_radps);
  if constexpr (Layout::has(Block::kRangeRateError)) {
    if (slot >= 0) {
      h(Layout::offset(Block::kRangeRateError) + slot) = 1.0;
      rate_err = rate_err_hat_(slot);
    }
  }
  inn.prr_outcome = fuse(h, p.geo.range_rate_mps + clock_drift_mps_ + rate_err - o.pseudorange_rate_mps, r_prr,
                         inn.prr_innovation_mps, inn.prr_variance_m2ps2, report);
  ++(inn.prr_outcome == InnovationOutcome::kUsed ? report.prr_used : report.prr_rejected);
  return inn;
}

template <class Layout>
void Ekf<Layout>::reset_channel_state(int state, double sigma) {
  x_(state) = 0.0;
  P_.row(state).setZero();
  P_.col(state).setZero();
  P_(state, state) = sigma * sigma;
  if (sigma != 0.0 && dead_[static_cast<std::size_t>(state)]) {  // no longer +0: back into the covariance loops
    dead_[static_cast<std::size_t>(state)] = false;
    index_live_states();
  }
}

template <class Layout>
int Ekf<Layout>::bind_channel(std::uint8_t prn) {
  if constexpr (!Layout::has(Block::kRangeError) && !Layout::has(Block::kRangeRateError)) {
    (void)prn;
    return -1;
  } else {
    for (int s = 0; s < kGnssErrorChannels; ++s)
      if (slot_prn_[s] == prn) return s;
    for (int s = 0; s < kGnssErrorChannels; ++s) {
      if (slot_prn_[s] != 0) continue;
      slot_prn_[s] = prn;
      if constexpr (Layout::has(Block::kRangeError)) {
        reset_channel_state(Layout::offset(Block::kRangeError) + s, cfg_.range_gm_sigma_m);
        range_err_hat_(s) = 0.0;
      }
      if constexpr (Layout::has(Block::kRangeRateError)) {
        reset_channel_state(Layout::offset(Block::kRangeRateError) + s, cfg_.range_rate_gm_sigma_mps);
        rate_err_hat_(s) = 0.0;
      }
      return s;
    }
    return -1;
  }
}

// The members defined here, for every layout (the list: FSW_FOR_EACH_LAYOUT, fsw/error_state.hpp).
#define FSW_EKF_RAW_AID_INSTANTIATE(L)                                                                              \
  template Status Ekf<L>::update(const GnssEpoch&, const NavState&, const Vec3&, EkfUpdateReport&);                \
  template int Ekf<L>::predict_epoch(const GnssEpoch&, const GnssRawAntenna&, GnssRawPrediction*, bool*,           \
                                     EkfUpdateReport&) const;                                                      \
  template void Ekf<L>::init_clock(const GnssEpoch&, const GnssRawPrediction*, const bool*, int);                  \
  template void Ekf<L>::release_channels(const GnssEpoch&, const bool*);                                           \
  template ObservationInnovation Ekf<L>::fuse_observation(const GnssObservation&, const GnssRawPrediction&,        \
                                                          const GnssRawAntenna&, double, double, EkfUpdateReport&); \
  template void Ekf<L>::reset_channel_state(int, double);                                                          \
  template int Ekf<L>::bind_channel(std::uint8_t);
FSW_FOR_EACH_LAYOUT(FSW_EKF_RAW_AID_INSTANTIATE)
#undef FSW_EKF_RAW_AID_INSTANTIATE

}  // namespace fsw
