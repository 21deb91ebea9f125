// Stationary coarse self-alignment: levelling from the mean specific force and gyrocompassing
// from the mean angular rate (analytic TRIAD on the up and east directions).
//
// With accelerometer bias dA and gyro bias eps (both resolved in n), the resulting attitude
// error (frames.hpp definition) is, to first order:
//   phi_E = -dA_N / g,   phi_N = dA_E / g,
//   phi_U = -eps_E / (Omega cos L) + phi_N tan L
// The paper's section II quotes phi_U = eps_E / (Omega cos L): same magnitude; the sign here is
// the one that follows from the attitude-error definition that also gives the paper's levelling
// signs above (see the analysis report for the derivation).
#pragma once

#include "fsw/frames.hpp"
#include "fsw/status.hpp"
#include "fsw/strapdown.hpp"

namespace fsw {

class CoarseAlignment {
 public:
  void reset();
  /// Accumulates one stationary IMU sample. kBadInput for non-finite data (sample ignored).
  Status add(const ImuSample& s);
  /// Computes C_b_n from the accumulated samples at geodetic latitude lat_rad. kNotConverged when
  /// the data cannot define the directions (no samples, free fall, or rate parallel to gravity).
  Status solve(double lat_rad, Mat3& C_b_n) const;
  /// Adds another accumulator's samples (the flight application commits a stationary interval
  /// to its alignment window this way once the GNSS epoch at the interval's end showed rest).
  void merge(const CoarseAlignment& other);
  double duration_s() const { return dt_sum_; }
  /// Mean specific force and angular rate over the accumulated samples (body frame).
  Vec3 mean_f_b_mps2() const { return dt_sum_ > 0.0 ? Vec3(dv_sum_ / dt_sum_) : Vec3::Zero(); }
  Vec3 mean_omega_b_radps() const { return dt_sum_ > 0.0 ? Vec3(dtheta_sum_ / dt_sum_) : Vec3::Zero(); }

 private:
  Vec3 dtheta_sum_ = Vec3::Zero();
  Vec3 dv_sum_ = Vec3::Zero();
  double dt_sum_ = 0.0;
};

/// In-motion coarse alignment by velocity matching: the optimisation-based alignment (OBA) of
/// Wu & Pan (2013), solved as Wahba's problem.
///
/// The caller integrates the gyro increments from a reference body frame b0 (C_b(t)^b0) and the
/// specific force rotated into b0, alpha(t) = integral C_b(tau)^b0 f_b dtau, and takes GNSS
/// velocities v_n(t_k). With Earth and transport rate neglected (over a window of tens of seconds
/// they rotate n by < 0.1 deg and the Coriolis term 2 Omega v integrates to millimetres per second
/// at walking or driving speed, far below a MEMS IMU's errors), the velocity equation
/// dv_n/dt = C_b0^n C_b^b0 f_b + g_n integrates to
///     beta_k = v_n(t_k) - v_n(t_0) - g_n (t_k - t_0) = C_b0^n (alpha(t_k) - alpha(t_0)),
/// one vector pair per GNSS epoch. The error of v_n(t_0) is common to every pair: a 5 cm/s error
/// against 1 m/s of velocity change would turn the whole fit by 3 deg. So the offset is an unknown
/// too: C_b0^n and d minimise sum_k w_k |beta_k + d - C alpha_k|^2 (t_0 itself is the pair (0, 0)),
/// which is Wahba's problem on the pairs centred on their weighted means (the orthogonal
/// Procrustes problem with translation), solved by Davenport's q-method: the eigenvector of the
/// largest eigenvalue of the symmetric 4x4 K matrix, here by cyclic Jacobi rotations (fixed size,
/// at most kMaxSweeps sweeps, no allocation; Eigen's dense eigen solvers go through its general
/// products). Each pair then carries only its own epoch's error.
///
/// The IMU biases, estimated with the attitude. A gyro bias error eps (rad/s, body) turns the
/// integrated b frame by dtheta(t) = Theta(t) eps, Theta = integral C_b^b0 dt, and adds G(t) eps
/// to alpha, G = -integral [f_b0 x] Theta dt; an accelerometer bias error b_a (m/s^2, body) adds
/// Theta(t) b_a (the caller integrates Theta and G with alpha). With C = C_hat (I + [phi x]) (phi in
/// b0) the residual, rotated into b0, is linear in the unknowns x = (phi, eps, b_a, d_b0):
///     z_k = C_hat^T beta_k - alpha_k = -H_k x + e_k,   H_k = [[alpha_k x], G_k, Theta_k, I].
/// The q-method's C_hat (biases zero) starts a Gauss-Newton iteration (at most kMaxIterations) on
///     sum_k w_k |z_k + H_k x|^2 + x^T P0^-1 x,   P0^-1 = diag(0, 1 / sigma_eps^2, 1 / sigma_a^2, 0),
/// a 12x12 system whose matrix does not depend on C_hat (accumulated once per pair; the right-hand
/// side is a contraction of accumulated sums with C_hat), solved by Cholesky. The attitude
/// covariance is the phi block of its inverse, rotated into n: cov(phi_n) = C cov(phi) C^T, scaled
/// by the a-posteriori variance factor chi^2 / (3n - 12) of the fit when that exceeds 1. Gravity
/// (the vertical part of beta, growing with t_k - t_0) carries roll and pitch; only the horizontal
/// velocity change carries heading (without biases: J_UU = sum_k w_k |beta_k,horizontal - its
/// mean|^2). A window on a straight line at constant velocity has no horizontal velocity change and
/// an undetermined heading. Without rotation an accelerometer bias is exactly a tilt (b / g, the
/// levelling error: the prior decides) and a horizontal gyro bias mostly one (gravity leaks in as
/// g eps t^2 / 2); turns separate them, and the vertical gyro bias turns the velocity changes.
class VelocityMatchAlignment {
 public:
  static constexpr int kMaxSweeps = 16;
  static constexpr int kMaxIterations = 4;
  using Mat12 = Eigen::Matrix<double, 12, 12>;
  void reset();
  /// One pair: alpha_b0 (b0 frame) and beta_n (ENU) [m/s], weight w > 0 [1/(m/s)^2], and the
  /// sensitivities of alpha to a gyro bias error, G [m/s per rad/s], and to an accelerometer bias
  /// error, Theta [s] (zero: that error not modelled).
  Status add(const Vec3& alpha_b0_mps, const Vec3& beta_enu_mps, double weight, const Mat3& G = Mat3::Zero(),
             const Mat3& Theta = Mat3::Zero());
  /// C_b0^n and the 1-sigma attitude uncertainty phi_E, phi_N, phi_U [rad] for bias errors of
  /// gyro_bias_sigma_radps and accel_bias_sigma_mps2 per axis. kNotConverged with fewer than 3
  /// pairs or a singular information matrix (no horizontal velocity change).
  Status solve(Mat3& C_b0_n, Vec3& att_sigma_enu_rad, double gyro_bias_sigma_radps = 0.0,
               double accel_bias_sigma_mps2 = 0.0) const;
  /// The offset d of the last solve: the fitted correction of beta (of v_n(t_0)) [m/s].
  const Vec3& offset_mps() const { return offset_; }
  /// The bias errors of the last solve (body): what the caller's increments still contain.
  const Vec3& gyro_bias_radps() const { return gyro_bias_; }
  const Vec3& accel_bias_mps2() const { return accel_bias_; }
  int count() const { return n_; }
  /// Weighted sum of squared residuals of the last solve (chi^2) [-].
  double chi2() const { return chi2_; }

 private:
  // Weighted sums of the raw pairs; solve() centres them.
  double sum_w_ = 0.0;
  Vec3 sum_w_alpha_ = Vec3::Zero();
  Vec3 sum_w_beta_ = Vec3::Zero();
  Mat3 sum_w_beta_alpha_ = Mat3::Zero();  ///< sum w beta alpha^T
  double sum_w_alpha2_ = 0.0;
  Mat12 info_ = Mat12::Zero();                                  ///< sum w H^T H
  Eigen::Matrix<double, 12, 1> h_alpha_ = Eigen::Matrix<double, 12, 1>::Zero();  ///< sum w H^T alpha
  Eigen::Matrix<double, 12, 9> h_beta_ = Eigen::Matrix<double, 12, 9>::Zero();   ///< column 3j+m: sum w H^T e_j beta_m
  Mat3 sum_w_alpha_beta_ = Mat3::Zero();  ///< sum w alpha beta^T
  double sum_w_beta2_ = 0.0;
  int n_ = 0;
  mutable double chi2_ = 0.0;
  mutable Vec3 offset_ = Vec3::Zero();
  mutable Vec3 gyro_bias_ = Vec3::Zero();
  mutable Vec3 accel_bias_ = Vec3::Zero();
};

/// Davenport q-method: the rotation C (b -> n) that maximises tr(C B^T) for an attitude profile
/// matrix B = sum w beta_n alpha_b^T; lambda_max = that maximum. kNotConverged for non-finite B
/// or when the Jacobi sweeps do not converge.
Status davenport_q(const Mat3& B, Mat3& C_b_n, double& lambda_max);

/// First-order prediction of the alignment attitude error for biases resolved in n.
Vec3 predicted_alignment_error(const Vec3& accel_bias_enu_mps2, const Vec3& gyro_bias_enu_radps, double lat_rad,
                               double g_mps2);

}  // namespace fsw
