#include "fsw/ekf.hpp"

#include <algorithm>
#include <cmath>

#include "fsw/chi_square.hpp"
#include "fsw/config_check.hpp"
#include "fsw/effect_catalogue.hpp"

namespace fsw {
namespace {

using Mat9 = Eigen::Matrix<double, 9, 9>;

/// Navigation-block dynamics matrix (9 x 9) at the given solution and mean specific force.
Mat9 navigation_dynamics(const NavState& nav, const Vec3& f_enu_mps2) {
  const LatitudeTerms lat(nav.llh.x());  // one sine and cosine for every term below
  const double h = nav.llh.z();
  const double rm = meridian_radius_m(lat) + h;
  const double rn = normal_radius_m(lat) + h;
  const double tl = std::tan(lat.lat_rad), cl = lat.cos_lat, sl = lat.sin_lat;
  const Vec3& v = nav.vel_enu_mps;
  const double we = wgs84::omega_ie_radps;
  const Vec3 w_ie = omega_ie_n(lat);
  const Vec3 w_en = omega_en_n(lat, h, v);

  // Rate errors: d(w_in) = Mv dv + (Mp_ie + Mp_en) dp; only the latitude (North) error matters.
  Mat3 Mv = Mat3::Zero();
  Mv(0, 1) = -1.0 / rm;
  Mv(1, 0) = 1.0 / rn;
  Mv(2, 0) = tl / rn;
  Mat3 Mp_ie = Mat3::Zero();
  Mp_ie(1, 1) = -we * sl / rm;
  Mp_ie(2, 1) = we * cl / rm;
  Mat3 Mp_en = Mat3::Zero();
  Mp_en(2, 1) = v.x() / (rn * cl * cl * rm);
  Mp_en(0, 2) = v.y() / (rm * rm);
  Mp_en(1, 2) = -v.x() / (rn * rn);
  Mp_en(2, 2) = -v.x() * tl / (rn * rn);

  const double g = normal_gravity_mps2(lat, h);
  Mat9 F = Mat9::Zero();
  F.block<3, 3>(0, 3) = Mat3::Identity();
  F.block<3, 3>(3, 0) = skew(v) * (2.0 * Mp_ie + Mp_en);
  F(5, 2) += 2.0 * g / (rm > rn ? rm : rn);
  F.block<3, 3>(3, 3) = skew(v) * Mv - skew(2.0 * w_ie + w_en);
  F.block<3, 3>(3, 6) = skew(f_enu_mps2);
  F.block<3, 3>(6, 0) = Mp_ie + Mp_en;
  F.block<3, 3>(6, 3) = Mv;
  F.block<3, 3>(6, 6) = -skew(w_ie + w_en);
  return F;
}

/// Standard-normal quantile of the NIS test: P(Z > 3.090) = 0.001.
constexpr double kNisTestZ = 3.090232;

}  // namespace

template <class Layout>
Status Ekf<Layout>::init(const EkfConfig& cfg) {
  if (!check_config(cfg).ok()) return Status::kBadConfig;  // fsw/config_check.hpp
  cfg_ = cfg;
  x_.setZero();
  Vec sig = Vec::Zero();
  sig.template segment<3>(0).setConstant(cfg.pos_sigma_m);
  sig.template segment<3>(3).setConstant(cfg.vel_sigma_mps);
  sig.template segment<3>(6) = cfg.att_sigma_rad;
  auto fill = [&sig](Block b, double s) {
    const int o = Layout::offset(b);
    if (o >= 0)
      for (int k = 0; k < block_size(b); ++k) sig(o + k) = s;
  };
  fill(Block::kAccelBias, cfg.accel_bias_sigma_mps2);
  fill(Block::kGyroBias, cfg.gyro_bias_sigma_radps);
  fill(Block::kAccelMisalign, cfg.accel_misalign_sigma_rad);
  fill(Block::kGyroMisalign, cfg.gyro_misalign_sigma_rad);
  fill(Block::kAccelScale, cfg.accel_scale_sigma);
  fill(Block::kGyroScale, cfg.gyro_scale_sigma);
  fill(Block::kGyroGSens, cfg.gyro_g_sens_sigma_radps_per_mps2);
  fill(Block::kTimeOffset, cfg.time_offset_sigma_s);
  fill(Block::kTimeDrift, cfg.time_drift_sigma_sps);
  fill(Block::kLeverArm, cfg.lever_arm_sigma_m);
  fill(Block::kTropoScale, cfg.tropo_scale_sigma);
  fill(Block::kIonoScale, cfg.iono_scale_sigma);
  fill(Block::kRangeError, cfg.range_gm_sigma_m);
  fill(Block::kRangeRateError, cfg.range_rate_gm_sigma_mps);
  const int oc = Layout::offset(Block::kClock);
  sig(oc) = cfg.clock_bias_sigma_m;
  sig(oc + 1) = cfg.clock_drift_sigma_mps;
  for (int i = 0; i < N && i < 64; ++i)
    if ((cfg.frozen_states >> i) & 1u) sig(i) = 0.0;
  init_var_ = sig.array().square().matrix();
  P_ = init_var_.asDiagonal();
  find_dead_states();
  health_ = EkfHealth{};
  nis_head_ = 0;
  nis_count_ = 0;
  runaway_count_ = 0;
  reacquire_pvt_ = false;
  ungated_ = false;
  pvt_gated_run_.fill(0);
  Phi_.setIdentity();
  trans_.reset(cfg.propagation_substep_frames);
  last_f_enu_mps2_.setZero();
  clock_bias_m_ = 0.0;
  clock_drift_mps_ = 0.0;
  clock_initialised_ = false;
  time_offset_hat_s_ = 0.0;
  time_drift_hat_ = 0.0;
  drift_t_ref_s_ = std::numeric_limits<double>::quiet_NaN();
  lever_arm_hat_b_m_ = cfg.lever_arm_b_m;
  tropo_scale_hat_ = 0.0;
  iono_scale_hat_ = 0.0;
  slot_prn_.fill(0);
  range_err_hat_.setZero();
  rate_err_hat_.setZero();
  initialised_ = true;
  return Status::kOk;
}

template <class Layout>
void EkfTransition<Layout>::reset(int substep_frames) {
  substep_frames_ = substep_frames < 1 ? 1 : substep_frames;
  frames_ = 0;
  phi_nav_.setIdentity();
  interval_s_ = 0.0;
  clear_substep();
}

template <class Layout>
void EkfTransition<Layout>::clear_substep() {
  sub_frames_ = 0;
  sub_T_ = 0.0;
  sum_C_dt_.setZero();
  sum_dv_n_.setZero();
  sum_C_dv_.setZero();
  sum_C_dth_.setZero();
}

template <class Layout>
Status EkfTransition<Layout>::accumulate(const FrameIncrement& inc, const NavState& nav) {
  if (!(inc.dt_s > 0.0) || !inc.dv_sum_mps.allFinite() || !inc.dtheta_sum_rad.allFinite() || !nav.llh.allFinite() ||
      !nav.vel_enu_mps.allFinite() || !nav.q_b_n.coeffs().allFinite())
    return Status::kBadInput;
  const Mat3 C = nav.C_b_n();
  sum_C_dt_ += C * inc.dt_s;
  sum_dv_n_ += C * inc.dv_sum_mps;
  last_f_enu_mps2_ = C * inc.dv_sum_mps / inc.dt_s;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      sum_C_dv_.col(3 * i + j) += C.col(i) * inc.dv_sum_mps(j);
      sum_C_dth_.col(3 * i + j) += C.col(i) * inc.dtheta_sum_rad(j);
    }
  sub_T_ += inc.dt_s;
  last_nav_ = nav;
  ++frames_;
  if (++sub_frames_ >= substep_frames_) flush();
  return Status::kOk;
}

template <class Layout>
Status Ekf<Layout>::accumulate(const FrameIncrement& inc, const NavState& nav) {
  if (!initialised_) return Status::kNotInitialised;
  const Status st = trans_.accumulate(inc, nav);
  if (st != Status::kOk) {
    ++health_.nonfinite_rejected;
    return st;
  }
  last_f_enu_mps2_ = trans_.last_f_enu_mps2();
  return Status::kOk;
}

template <class Layout>
void EkfTransition<Layout>::set_dead_states(const std::array<bool, N>& dead) {
  every_column_ = true;
  for (int c = 0; c < kNavCols; ++c) {
    dead_col_[static_cast<std::size_t>(c)] = dead[static_cast<std::size_t>(c)];
    if (dead[static_cast<std::size_t>(c)]) every_column_ = false;
  }
}

template <class Layout>
void EkfTransition<Layout>::flush() {
  if (sub_frames_ == 0) return;
  const double T = sub_T_;
  const Mat9 FT = navigation_dynamics(last_nav_, sum_dv_n_ / T) * T;
  Mat9 A = Mat9::Identity() + FT;
  A.noalias() += 0.5 * FT.lazyProduct(FT);  // coefficient-based: no GEMM blocking (alloca/malloc)

  // Phi_nav <- A Phi_nav + (I + FT / 2) B, B the integrated sensor-error columns of the
  // navigation rows (sparse: added block by block, never formed). top_ is member scratch. A dead
  // state's column (set_dead_states) is neither formed nor copied: it keeps the zero of reset().
  // Each element of a formed column is the same sum, in the same order, as in the whole block's
  // product. One function with branches, not two instantiations: a separate every-column path
  // cost the Cortex-M7 image's sub-step frame 680 instructions (docs/baremetal-qemu.md).
  const Mat9 half = Mat9::Identity() + 0.5 * FT;
  constexpr int K = EkfTransition<Layout>::kNavCols;  // columns K.. of phi_nav_ and top_ stay zero
  if (every_column_) {
    top_.template leftCols<K>().noalias() = A.lazyProduct(phi_nav_.template leftCols<K>());
  } else {
    for (int c = 0; c < K; ++c)
      if (live_column(c))
        top_.col(c).noalias() = A.lazyProduct(phi_nav_.col(c));
      else
        top_.col(c).setZero();  // the sums below add to it, and it is not copied
  }
  if constexpr (Layout::has(Block::kAccelBias)) {
    top_.template middleCols<3>(Layout::offset(Block::kAccelBias)).noalias() +=
        half.template middleCols<3>(3).lazyProduct(sum_C_dt_);
  }
  if constexpr (Layout::has(Block::kGyroBias)) {
    top_.template middleCols<3>(Layout::offset(Block::kGyroBias)).noalias() -=
        half.template middleCols<3>(6).lazyProduct(sum_C_dt_);
  }
  if constexpr (Layout::has(Block::kAccelMisalign)) {
    constexpr int o = Layout::offset(Block::kAccelMisalign);
    for (int k = 0; k < 3; ++k) {
      const AxisPair ax = kAccelMisalignmentAxes[k];
      top_.col(o + k).noalias() += half.template middleCols<3>(3).lazyProduct(sum_C_dv_.col(3 * ax.i + ax.j));
    }
  }
  if constexpr (Layout::has(Block::kGyroMisalign)) {
    constexpr int o = Layout::offset(Block::kGyroMisalign);
    for (int k = 0; k < 6; ++k) {
      const AxisPair ax = kGyroMisalignmentAxes[k];
      top_.col(o + k).noalias() -= half.template middleCols<3>(6).lazyProduct(sum_C_dth_.col(3 * ax.i + ax.j));
    }
  }
  if constexpr (Layout::has(Block::kAccelScale)) {
    constexpr int o = Layout::offset(Block::kAccelScale);
    for (int i = 0; i < 3; ++i) top_.col(o + i).noalias() += half.template middleCols<3>(3).lazyProduct(sum_C_dv_.col(4 * i));
  }
  if constexpr (Layout::has(Block::kGyroScale)) {
    constexpr int o = Layout::offset(Block::kGyroScale);
    for (int i = 0; i < 3; ++i) top_.col(o + i).noalias() -= half.template middleCols<3>(6).lazyProduct(sum_C_dth_.col(4 * i));
  }
  if constexpr (Layout::has(Block::kGyroGSens)) {  // gyro i senses G_i f_i: driven by C(:, i) dv_i
    constexpr int o = Layout::offset(Block::kGyroGSens);
    for (int i = 0; i < 3; ++i) top_.col(o + i).noalias() -= half.template middleCols<3>(6).lazyProduct(sum_C_dv_.col(4 * i));
  }
  if (every_column_) {
    phi_nav_.template leftCols<K>() = top_.template leftCols<K>();
  } else {
    for (int c = 0; c < K; ++c)
      if (live_column(c)) phi_nav_.col(c) = top_.col(c);
  }

  interval_s_ += T;
  clear_substep();
}

template <class Layout>
typename Ekf<Layout>::Vec Ekf<Layout>::white_noise_psd() const {
  Vec qc = Vec::Zero();
  qc.template segment<3>(3).setConstant(cfg_.vrw_mps_per_rts * cfg_.vrw_mps_per_rts);
  qc.template segment<3>(6).setConstant(cfg_.arw_rad_per_rts * cfg_.arw_rad_per_rts);
  if constexpr (Layout::has(Block::kAccelBias))
    qc.template segment<3>(Layout::offset(Block::kAccelBias))
        .setConstant(cfg_.accel_bias_rw_mps2_per_rts * cfg_.accel_bias_rw_mps2_per_rts);
  if constexpr (Layout::has(Block::kGyroBias))
    qc.template segment<3>(Layout::offset(Block::kGyroBias))
        .setConstant(cfg_.gyro_bias_rw_radps_per_rts * cfg_.gyro_bias_rw_radps_per_rts);
  return qc;
}

template <class Layout>
void Ekf<Layout>::find_dead_states() {
  // Dead: a sensor or extension state (a diagonal row of Phi, decay > 0) started with zero
  // variance and driven by no noise. Its row and column of P start +0; Phi P Phi^T keeps them +0
  // (each element a sum of exact zeros with at least one +0 term, the diagonal of Phi being
  // positive), no Qd term reaches them, and an update adds K(i) u(j) + u(i) K(j) with K and u +0
  // there (s = P h^T starts +0). So they stay +0 for good, and the loops that skip them add
  // nothing that would have changed a bit. The navigation rows (dense in Phi) and the clock
  // (bias-drift coupled, always driven) are never dead.
  const Vec qc = white_noise_psd();
  constexpr int oc = Layout::offset(Block::kClock);
  for (int i = 0; i < N; ++i) {
    bool driven = qc(i) != 0.0 || i < 9 || i == oc || i == oc + 1;
    if constexpr (Layout::has(Block::kRangeError)) {
      constexpr int o = Layout::offset(Block::kRangeError);
      if (i >= o && i < o + kGnssErrorChannels) driven = driven || cfg_.range_gm_sigma_m != 0.0;
    }
    if constexpr (Layout::has(Block::kRangeRateError)) {
      constexpr int o = Layout::offset(Block::kRangeRateError);
      if (i >= o && i < o + kGnssErrorChannels) driven = driven || cfg_.range_rate_gm_sigma_mps != 0.0;
    }
    dead_[static_cast<std::size_t>(i)] = !driven && init_var_(i) == 0.0;
  }
  index_live_states();
}

template <class Layout>
void Ekf<Layout>::index_live_states() {
  n_live_ = 0;
  n_runs_ = 0;
  n_nav_live_ = 0;
  for (int i = 0; i < N; ++i) {
    if (skipped(i)) continue;
    if (i < EkfTransition<Layout>::kNavCols) nav_live_[static_cast<std::size_t>(n_nav_live_++)] = i;
    ++n_live_;
    if (n_runs_ > 0 && runs_[static_cast<std::size_t>(n_runs_ - 1)].end == i)
      ++runs_[static_cast<std::size_t>(n_runs_ - 1)].end;
    else
      runs_[static_cast<std::size_t>(n_runs_++)] = LiveRun{i, i + 1};
  }
  trans_.set_dead_states(skipped_states());
}

template <class Layout>
void Ekf<Layout>::set_dense_covariance_loops(bool dense) {
  dense_loops_ = dense;
  index_live_states();
}

template <class Layout>
Status Ekf<Layout>::propagate() {
  if (!initialised_) return Status::kNotInitialised;
  const Status st = propagate(trans_);
  trans_.reset(cfg_.propagation_substep_frames);
  return st;
}

template <class Layout>
Status Ekf<Layout>::propagate(EkfTransition<Layout>& t) {
  if (!initialised_) return Status::kNotInitialised;
  t.set_dead_states(skipped_states());  // the next interval of an executive's accumulator, this one's last sub-step
  t.flush();
  const double T = t.interval_s();
  if (t.frames() > 0) last_f_enu_mps2_ = t.last_f_enu_mps2();
  if (!(T > 0.0)) return Status::kOk;
  Phi_.setIdentity();
  Phi_.template topRows<9>() = t.phi_nav();
  constexpr int oc = Layout::offset(Block::kClock);
  Phi_(oc, oc + 1) = T;  // the nav rows never touch the clock, whose block is still identity
  double a_range = 1.0, a_rate = 1.0;
  if constexpr (Layout::has(Block::kRangeError)) {
    a_range = std::exp(-T / cfg_.range_gm_tau_s);
    for (int k = 0; k < kGnssErrorChannels; ++k) Phi_(Layout::offset(Block::kRangeError) + k, Layout::offset(Block::kRangeError) + k) = a_range;
  }
  if constexpr (Layout::has(Block::kRangeRateError)) {
    a_rate = std::exp(-T / cfg_.range_rate_gm_tau_s);
    for (int k = 0; k < kGnssErrorChannels; ++k)
      Phi_(Layout::offset(Block::kRangeRateError) + k, Layout::offset(Block::kRangeRateError) + k) = a_rate;
  }

  const Vec qc = white_noise_psd();
  // Phi's structure: dense navigation rows (0..8); below them a diagonal (random constants,
  // Gauss-Markov decays) plus the clock's bias-drift coupling. P uses it (O(9 N^2), not N^3), and
  // every N x N intermediate lives in member scratch, not on the task's stack.
  Mat& PhiP = work_;
  constexpr int K = EkfTransition<Layout>::kNavCols;
  if constexpr (N - K >= 16) {
    // The layouts with channel states: the navigation rows are zero beyond column K
    // (nav_driven_columns()), so both products stop there. Written out column by column, each
    // element summed over k = 0, 1, ... in order: what Eigen's product does at these sizes, so the
    // results are the same bits, whatever inner size Eigen would see (it sums a short fixed-size
    // row as a tree). With dead states, k runs over the live columns only (nav_live_).
    if (n_nav_live_ == K)
      nav_products(PhiP, [](int c) { return c; }, K);
    else
      nav_products(PhiP, [this](int c) { return nav_live_[static_cast<std::size_t>(c)]; }, n_nav_live_);
  } else {
    PhiP.template topRows<9>().noalias() = Phi_.template topRows<9>().lazyProduct(P_);
    for (int i = 9; i < N; ++i) PhiP.row(i) = Phi_(i, i) * P_.row(i);
    PhiP.row(oc) += Phi_(oc, oc + 1) * P_.row(oc + 1);
    P_.template leftCols<9>().noalias() = PhiP.lazyProduct(Phi_.template topRows<9>().transpose());
  }
  for (int j = 9; j < N; ++j) P_.col(j) = Phi_(j, j) * PhiP.col(j);
  P_.col(oc) += Phi_(oc, oc + 1) * PhiP.col(oc + 1);

  // + Qd = 0.5 (Phi Qc Phi^T + Qc) T, Qc diagonal, added in place with the same structure.
  const double halfT = 0.5 * T;
  for (int j = 0; j < N; ++j) {
    if (qc(j) == 0.0) continue;
    const double q = qc(j) * halfT;
    const Eigen::Matrix<double, 9, 1> v = Phi_.template block<9, 1>(0, j);
    P_.template topLeftCorner<9, 9>().noalias() += (q * v) * v.transpose();
    if (j >= 9) {
      const double vj = Phi_(j, j);
      P_.template block<9, 1>(0, j) += (q * vj) * v;
      P_.template block<1, 9>(j, 0) += (q * vj) * v.transpose();
      P_(j, j) += q * vj * vj;
    }
    P_(j, j) += q;
  }
  const double Sb = cfg_.clock_bias_psd_m2ps, Sd = cfg_.clock_drift_psd_m2ps3;
  P_(oc, oc) += Sb * T + Sd * T * T * T / 3.0;
  P_(oc, oc + 1) += Sd * T * T / 2.0;
  P_(oc + 1, oc) += Sd * T * T / 2.0;
  P_(oc + 1, oc + 1) += Sd * T;
  if constexpr (Layout::has(Block::kRangeError)) {
    const double q = cfg_.range_gm_sigma_m * cfg_.range_gm_sigma_m * (1.0 - a_range * a_range);
    for (int k = 0; k < kGnssErrorChannels; ++k) P_(Layout::offset(Block::kRangeError) + k, Layout::offset(Block::kRangeError) + k) += q;
    range_err_hat_ *= a_range;
  }
  if constexpr (Layout::has(Block::kRangeRateError)) {
    const double q = cfg_.range_rate_gm_sigma_mps * cfg_.range_rate_gm_sigma_mps * (1.0 - a_rate * a_rate);
    for (int k = 0; k < kGnssErrorChannels; ++k)
      P_(Layout::offset(Block::kRangeRateError) + k, Layout::offset(Block::kRangeRateError) + k) += q;
    rate_err_hat_ *= a_rate;
  }
  symmetrise();
  // x <- Phi x with the same structure (x is normally zero after feedback).
  const Eigen::Matrix<double, 9, 1> x_nav = Phi_.template topRows<9>() * x_;
  const double x_clock = Phi_(oc, oc) * x_(oc) + Phi_(oc, oc + 1) * x_(oc + 1);
  for (int i = 9; i < N; ++i) x_(i) *= Phi_(i, i);
  x_(oc) = x_clock;
  x_.template head<9>() = x_nav;
  clock_bias_m_ += clock_drift_mps_ * T;
  last_Phi_ = Phi_;
  return Status::kOk;
}

template <class Layout>
template <class Column>
void Ekf<Layout>::nav_products(Mat& PhiP, Column column, int n) {
  // Why a dead column k may be left out with the same bits: P's row and column k are +0, so its
  // terms are zeros, and each sum has met its own diagonal's term (k = i < 9, before every dead k)
  // by then: +0 or non-zero, after which adding a zero changes no bit. The second product's dead
  // columns of PhiP are +0 (sums of such zeros) and meet P's diagonal term (k = j < 9) first too.
  constexpr int oc = Layout::offset(Block::kClock);
  for (int j = 0; j < N; ++j) {
    Eigen::Matrix<double, 9, 1> acc = Phi_.template block<9, 1>(0, 0) * P_(0, j);
    for (int c = 1; c < n; ++c) {
      const int k = column(c);
      acc += Phi_.template block<9, 1>(0, k) * P_(k, j);
    }
    PhiP.template block<9, 1>(0, j) = acc;
  }
  for (int i = 9; i < N; ++i) PhiP.row(i) = Phi_(i, i) * P_.row(i);
  PhiP.row(oc) += Phi_(oc, oc + 1) * P_.row(oc + 1);
  for (int j = 0; j < 9; ++j) {
    P_.col(j) = PhiP.col(0) * Phi_(j, 0);
    for (int c = 1; c < n; ++c) {
      const int k = column(c);
      P_.col(j) += PhiP.col(k) * Phi_(j, k);
    }
  }
}

template <class Layout>
bool Ekf<Layout>::scalar_update(const RowVec& h, double y, double r, double& nu, double& S) {
  Vec s = Vec::Zero();  // P h^T over the few non-zeros of h
  for (int j = 0; j < N; ++j)
    if (h(j) != 0.0 && !skipped(j)) s.noalias() += h(j) * P_.col(j);
  S = h.dot(s) + r;
  nu = y - h.dot(x_);
  if (!(S > 0.0) || (!ungated_ && !(nu * nu <= cfg_.gate_chi2 * S))) return false;
  Vec K = s / S;
  // Consider states get no gain; the Joseph form below stays exact for this suboptimal gain.
  for (int b = 0; b < Layout::kNumBlocks; ++b) {
    const Block blk = Layout::kBlocks[b];
    if (Layout::is_consider(blk)) K.segment(Layout::offset(blk), block_size(blk)).setZero();
  }
  x_ += K * nu;
  // Joseph form (I - K h) P (I - K h)^T + K r K^T, expanded for a scalar measurement.
  const Vec u = 0.5 * S * K - s;  // P - K s^T - s K^T + S K K^T = P + K u^T + u K^T
  // P <- (P + K u^T) + u K^T in one pass over P (the same two additions per element, in the same
  // order, as the two rank-one updates one after the other), over the live states' runs: a dead
  // state's row and column would stay +0 (find_dead_states). With every state live, the loop of
  // compile-time size (the Cortex-M7 image's filters: the compiler unrolls it).
  if (n_live_ == N) {
    for (int j = 0; j < N; ++j) {
      const double uj = u(j), kj = K(j);
      for (int i = 0; i < N; ++i) P_(i, j) = (P_(i, j) + K(i) * uj) + u(i) * kj;
    }
    return true;
  }
  for (const LiveRun& cols : live_runs())
    for (int j = cols.begin; j < cols.end; ++j) {
      const double uj = u(j), kj = K(j);
      for (const LiveRun& rows : live_runs())
        for (int i = rows.begin; i < rows.end; ++i) P_(i, j) = (P_(i, j) + K(i) * uj) + u(i) * kj;
    }
  return true;
}

template <class Layout>
InnovationOutcome Ekf<Layout>::fuse(const RowVec& h, double y, double r, double& nu, double& S,
                                    EkfUpdateReport& report) {
  if (!scalar_update(h, y, r, nu, S)) return InnovationOutcome::kGated;
  report.nis_sum += nu * nu / S;
  ++report.nis_dof;
  return InnovationOutcome::kUsed;
}

template <class Layout>
Status Ekf<Layout>::set_covariance(const Mat& P) {
  if (!initialised_) return Status::kNotInitialised;
  if (!P.allFinite()) {
    ++health_.nonfinite_rejected;
    return Status::kBadInput;
  }
  P_ = P;
  // A dead state stays dead only if P keeps its row and column +0 (find_dead_states' invariant).
  bool revived = false;
  for (int i = 0; i < N; ++i) {
    if (!dead_[static_cast<std::size_t>(i)]) continue;
    bool plus_zero = true;
    for (int k = 0; k < N; ++k) {
      const double a = P_(i, k), b = P_(k, i);
      if (a != 0.0 || b != 0.0 || std::signbit(a) || std::signbit(b)) plus_zero = false;
    }
    if (!plus_zero) {
      dead_[static_cast<std::size_t>(i)] = false;
      revived = true;
    }
  }
  if (revived) index_live_states();
  check_covariance();
  return Status::kOk;
}

template <class Layout>
void Ekf<Layout>::symmetrise() {
  // Over the live states' runs (a dead state's row and column are +0 on both sides already);
  // with every state live, one run: the plain triangle.
  const std::span<const LiveRun> runs = live_runs();
  for (auto cols = runs.begin(); cols != runs.end(); ++cols)
    for (int j = cols->begin; j < cols->end; ++j)
      for (auto rows = cols; rows != runs.end(); ++rows)
        for (int i = std::max(rows->begin, j + 1); i < rows->end; ++i) {
          const double v = 0.5 * (P_(i, j) + P_(j, i));
          P_(i, j) = v;
          P_(j, i) = v;
        }
}

template <class Layout>
void Ekf<Layout>::gather_live_correlations(const Vec& d) {
  // work_(a, b), a >= b: the correlation of the a-th and b-th live states (d = 1 / sigma), by runs
  // (with every state live, one run: the plain lower triangle); a live state of zero variance
  // gets a unit diagonal.
  int b = 0;
  const std::span<const LiveRun> runs = live_runs();
  for (auto cols = runs.begin(); cols != runs.end(); ++cols)
    for (int j = cols->begin; j < cols->end; ++j, ++b) {
      int a = b;
      for (auto rows = cols; rows != runs.end(); ++rows)
        for (int i = std::max(rows->begin, j); i < rows->end; ++i, ++a) work_(a, b) = d(i) * P_(i, j) * d(j);
      if (d(j) == 0.0) work_(b, b) = 1.0;
    }
}

template <class Layout>
void Ekf<Layout>::check_column_update(int j, int n) {
  // work_(i, j) -= sum over k < j of work_(j, k) work_(i, k), i = j..n-1, each element's terms
  // subtracted one at a time in increasing k: the bits of the per-k column operations. Blocks of
  // eight rows keep their sums in registers (the compiler vectorises them across the rows); the
  // pass per k reloaded and stored the column each time, and for n of 40-60 the loop overheads of
  // ~1,500 short column operations were most of the check's time.
  double* const wj = work_.col(j).data();
  const double* const wjk = work_.row(j).data();  // w(j, k): stride N (column-major)
  int i = j;
  for (; i + 8 <= n; i += 8) {
    double acc[8];
    for (int r = 0; r < 8; ++r) acc[r] = wj[i + r];
    for (int k = 0; k < j; ++k) {
      const double b = wjk[static_cast<std::ptrdiff_t>(k) * N];
      const double* const wk = work_.col(k).data() + i;
      for (int r = 0; r < 8; ++r) acc[r] -= b * wk[r];
    }
    for (int r = 0; r < 8; ++r) wj[i + r] = acc[r];
  }
  for (; i < n; ++i) {
    double acc = wj[i];
    for (int k = 0; k < j; ++k) acc -= wjk[static_cast<std::ptrdiff_t>(k) * N] * work_(i, k);
    wj[i] = acc;
  }
}

template <class Layout>
void Ekf<Layout>::check_covariance() {
  symmetrise();
  ++health_.cov_checks;
  // Cholesky of the correlation matrix D^-1 P D^-1 (scale-free: the states span 1e-10..1e2), in
  // the member scratch work_. Unblocked and in place: no temporaries, no alloca.
  Vec d = Vec::Zero();  // 1 / sigma, 0 for a state with exactly zero variance
  bool ok = P_.allFinite();
  for (int i = 0; ok && i < N; ++i) {
    if (P_(i, i) < 0.0) ok = false;
    d(i) = P_(i, i) > 0.0 ? 1.0 / std::sqrt(P_(i, i)) : 0.0;
  }
  constexpr double kMinPivot = 1e-12;
  const int n = n_live_;
  for (int attempt = 0; ok; ++attempt) {
    // The lower triangle of the live states' correlations, gathered into the top-left n x n of
    // work_ (P is symmetric here): the factor overwrites it column by column. A dead state is an
    // identity row and column of the full correlation matrix, uncoupled: leaving it out changes
    // no pivot of the others (their updates from it are exact zeros).
    gather_live_correlations(d);
    // Left-looking by columns: column j less the columns before it, then the pivot test and the
    // scaling. Each element is w(i, j) - w(j, 0) w(i, 0) - w(j, 1) w(i, 1) - ... in that order
    // (the order of one column operation per k); the rows go eight at a time with the sum in
    // registers across k, instead of one pass over the column per k (check_column_update).
    bool pd = true;
    for (int j = 0; j < n && pd; ++j) {
      check_column_update(j, n);
      const double piv = work_(j, j);
      if (!(piv > kMinPivot)) {
        pd = false;
        break;
      }
      const double l = std::sqrt(piv);
      work_.col(j).segment(j + 1, n - j - 1) /= l;
      work_(j, j) = l;
    }
    if (pd) return;
    // Not positive definite: shrink the correlations, P <- (P + delta diag(P)) / (1 + delta) off
    // the diagonal, with growing delta; a diagonal P is always positive definite.
    if (attempt == 0) ++health_.cov_repairs;
    constexpr double kDeltas[] = {1e-9, 1e-6, 1e-3, 1e-1, 1.0};
    if (attempt >= 5) {
      ok = false;
      break;
    }
    const double shrink = 1.0 / (1.0 + kDeltas[attempt]);
    for (int j = 0; j < N; ++j)
      for (int i = 0; i < N; ++i)
        if (i != j) P_(i, j) *= shrink;
  }
  if (!ok) {
    // Non-finite or negative variances (or correlations that would not shrink into shape): keep
    // the finite positive variances, fall back to the initial ones elsewhere, drop correlations.
    ++health_.cov_repairs;
    for (int i = 0; i < N; ++i) {
      const double v = P_(i, i);
      work_(i, i) = (std::isfinite(v) && v > 0.0) ? v : init_var_(i);
    }
    P_.setZero();
    for (int i = 0; i < N; ++i) P_(i, i) = work_(i, i);
    if (!x_.allFinite()) x_.setZero();
  }
}

template <class Layout>
void Ekf<Layout>::track_consistency(const EkfUpdateReport& report) {
  // Windowed NIS test.
  const int w = cfg_.nis_window;
  nis_hist_[static_cast<std::size_t>(nis_head_)] = report.nis_sum;
  dof_hist_[static_cast<std::size_t>(nis_head_)] = report.nis_dof;
  nis_head_ = (nis_head_ + 1) % w;
  if (nis_count_ < w) ++nis_count_;
  double sum = 0.0;
  int dof = 0;
  for (int k = 0; k < nis_count_; ++k) {
    sum += nis_hist_[static_cast<std::size_t>(k)];
    dof += dof_hist_[static_cast<std::size_t>(k)];
  }
  health_.nis_window_sum = sum;
  health_.nis_window_dof = dof;
  health_.nis_window_bound = dof > 0 ? chi2_quantile_wilson_hilferty(dof, kNisTestZ) : 0.0;
  health_.diverging = nis_count_ == w && dof > 0 && sum > health_.nis_window_bound;
  if (health_.diverging) ++health_.divergence_windows;

  // Gating runaway: most of the epoch's measurements fail the gate, epoch after epoch.
  // (Per measurement type: a clock jump fails every pseudorange and no rate.)
  const int pr_seen = report.pr_used + report.pr_rejected;
  const int prr_seen = report.prr_used + report.prr_rejected;
  // A PVT update: per axis, since its scalars are not redundant like the satellites of an epoch
  // (an overconfident filter can reject one axis for ever, as on a car whose East error grew while
  // the filter trusted its cm-level position: the other axes kept it from a reset). An axis gated
  // in every update of the run counts.
  if (report.pvt) {
    int longest = 0;
    for (std::size_t i = 0; i < pvt_gated_run_.size(); ++i) {
      const InnovationOutcome o = report.pvt_obs[i].outcome;
      if (o == InnovationOutcome::kGated)
        ++pvt_gated_run_[i];
      else if (o == InnovationOutcome::kUsed)
        pvt_gated_run_[i] = 0;
      longest = pvt_gated_run_[i] > longest ? pvt_gated_run_[i] : longest;
    }
    if (longest > 0) ++health_.gating_runaway_epochs;
    runaway_count_ = longest;
  } else if ((pr_seen >= 4 && 2 * report.pr_rejected > pr_seen) ||
             (prr_seen >= 4 && 2 * report.prr_rejected > prr_seen)) {
    ++runaway_count_;
    ++health_.gating_runaway_epochs;
  } else {
    runaway_count_ = 0;
  }
  if (cfg_.runaway_epochs > 0 && runaway_count_ >= cfg_.runaway_epochs) {
    // Re-open the filter to the data: navigation and clock states back to their initial
    // uncertainty, uncorrelated with the rest; the clock is re-initialised from the next epoch.
    constexpr int oc = Layout::offset(Block::kClock);
    for (int i : {0, 1, 2, 3, 4, 5, 6, 7, 8, oc, oc + 1}) {
      P_.row(i).setZero();
      P_.col(i).setZero();
      P_(i, i) = init_var_(i);
      x_(i) = 0.0;
    }
    clock_initialised_ = false;
    if (report.pvt) {
      // A runaway on position/velocity solutions: the filter no longer believes the solutions
      // because its own position/velocity drifted while it was confident (an unmodelled error, a
      // coasting interval); re-initialise them from the next solution, ungated.
      for (int i = 0; i < 3; ++i) {
        P_(i, i) = kReacquirePosVar_m2;
        P_(3 + i, 3 + i) = kReacquireVelVar_m2ps2;
      }
      reacquire_pvt_ = true;
    }
    runaway_count_ = 0;
    pvt_gated_run_.fill(0);
    nis_count_ = 0;
    nis_head_ = 0;
    ++health_.resets;
  }
}

template <class Layout>
void add_sensor_correction(const Eigen::Matrix<double, Layout::kSize, 1>& x, ImuCompensation& comp) {
  if constexpr (Layout::has(Block::kAccelBias)) comp.accel_bias_mps2 += x.template segment<3>(Layout::offset(Block::kAccelBias));
  if constexpr (Layout::has(Block::kGyroBias)) comp.gyro_bias_radps += x.template segment<3>(Layout::offset(Block::kGyroBias));
  if constexpr (Layout::has(Block::kAccelMisalign)) {
    constexpr int o = Layout::offset(Block::kAccelMisalign);
    for (int k = 0; k < 3; ++k) comp.accel_error(kAccelMisalignmentAxes[k].i, kAccelMisalignmentAxes[k].j) += x(o + k);
  }
  if constexpr (Layout::has(Block::kGyroMisalign)) {
    constexpr int o = Layout::offset(Block::kGyroMisalign);
    for (int k = 0; k < 6; ++k) comp.gyro_error(kGyroMisalignmentAxes[k].i, kGyroMisalignmentAxes[k].j) += x(o + k);
  }
  if constexpr (Layout::has(Block::kAccelScale)) {
    constexpr int o = Layout::offset(Block::kAccelScale);
    for (int i = 0; i < 3; ++i) comp.accel_error(i, i) += x(o + i);
  }
  if constexpr (Layout::has(Block::kGyroScale)) {
    constexpr int o = Layout::offset(Block::kGyroScale);
    for (int i = 0; i < 3; ++i) comp.gyro_error(i, i) += x(o + i);
  }
  if constexpr (Layout::has(Block::kGyroGSens))
    comp.gyro_g_sens_radps_per_mps2 += x.template segment<3>(Layout::offset(Block::kGyroGSens));
}

template <class Layout>
Status Ekf<Layout>::take_correction(Vec& x) {
  if (!initialised_) return Status::kNotInitialised;
  if (!x_.allFinite()) {
    x_.setZero();
    x.setZero();
    return Status::kBadInput;
  }
  x = x_;
  keep_correction();
  return Status::kOk;
}

template <class Layout>
void Ekf<Layout>::keep_correction() {
  if constexpr (Layout::has(Block::kTimeOffset)) time_offset_hat_s_ -= x_(Layout::offset(Block::kTimeOffset));
  if constexpr (Layout::has(Block::kTimeDrift)) time_drift_hat_ -= x_(Layout::offset(Block::kTimeDrift));
  if constexpr (Layout::has(Block::kLeverArm)) lever_arm_hat_b_m_ -= x_.template segment<3>(Layout::offset(Block::kLeverArm));
  if constexpr (Layout::has(Block::kTropoScale)) tropo_scale_hat_ -= x_(Layout::offset(Block::kTropoScale));
  if constexpr (Layout::has(Block::kIonoScale)) iono_scale_hat_ -= x_(Layout::offset(Block::kIonoScale));
  constexpr int oc = Layout::offset(Block::kClock);
  clock_bias_m_ -= x_(oc);
  clock_drift_mps_ -= x_(oc + 1);
  if constexpr (Layout::has(Block::kRangeError))
    range_err_hat_ -= x_.template segment<kGnssErrorChannels>(Layout::offset(Block::kRangeError));
  if constexpr (Layout::has(Block::kRangeRateError))
    rate_err_hat_ -= x_.template segment<kGnssErrorChannels>(Layout::offset(Block::kRangeRateError));
  x_.setZero();
}

template <class Layout>
Status Ekf<Layout>::feedback(Strapdown& ins, ImuCompensation& comp) {
  if (!initialised_) return Status::kNotInitialised;
  if (!x_.allFinite()) {
    x_.setZero();
    return Status::kBadInput;
  }
  const Status st = ins.correct(x_.template segment<3>(0), x_.template segment<3>(3), x_.template segment<3>(6));
  if (st != Status::kOk) return st;
  add_sensor_correction<Layout>(x_, comp);
  keep_correction();
  return Status::kOk;
}

template <class Layout>
void Ekf<Layout>::output(double t_s, EkfOutput<Layout>& out) const {
  out.t_s = t_s;
  // A negative variance gives NaN: a broken covariance is shown, not hidden.
  for (int i = 0; i < N; ++i) out.sigma(i) = std::sqrt(P_(i, i));
  out.clock_bias_m = clock_bias_m_;
  out.clock_drift_mps = clock_drift_mps_;
  out.clock_initialised = clock_initialised_;
  out.channel_prn = slot_prn_;
}

// The core's members (the aid units instantiate theirs), for every layout (FSW_FOR_EACH_LAYOUT).
#define FSW_EKF_INSTANTIATE(L)                                                                          \
  template class EkfTransition<L>;                                                                      \
  template void add_sensor_correction<L>(const Eigen::Matrix<double, L::kSize, 1>&, ImuCompensation&); \
  template class Ekf<L>;
FSW_FOR_EACH_LAYOUT(FSW_EKF_INSTANTIATE)
#undef FSW_EKF_INSTANTIATE

}  // namespace fsw
