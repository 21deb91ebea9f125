#include "fsw/alignment.hpp"

#include <algorithm>
#include <cmath>

namespace fsw {

void CoarseAlignment::reset() {
  dtheta_sum_.setZero();
  dv_sum_.setZero();
  dt_sum_ = 0.0;
}

Status CoarseAlignment::add(const ImuSample& s) {
  if (!s.dtheta_rad.allFinite() || !s.dv_mps.allFinite() || !std::isfinite(s.dt_s) || !(s.dt_s > 0.0)) {
    return Status::kBadInput;
  }
  dtheta_sum_ += s.dtheta_rad;
  dv_sum_ += s.dv_mps;
  dt_sum_ += s.dt_s;
  return Status::kOk;
}

void CoarseAlignment::merge(const CoarseAlignment& other) {
  dtheta_sum_ += other.dtheta_sum_;
  dv_sum_ += other.dv_sum_;
  dt_sum_ += other.dt_sum_;
}

Status CoarseAlignment::solve(double lat_rad, Mat3& C_b_n) const {
  if (!(dt_sum_ > 0.0) || !std::isfinite(lat_rad) || std::abs(lat_rad) > 0.5 * kPi - 1e-3) {
    return Status::kNotConverged;
  }
  const Vec3 f_b = dv_sum_ / dt_sum_;
  const Vec3 w_b = dtheta_sum_ / dt_sum_;
  const double fn = f_b.norm();
  const Vec3 east_raw = w_b.cross(f_b);
  // Earth rate times g times cos(lat) is ~7e-4 m/s^3 at mid latitudes; far below that the
  // directions are undefined.
  if (fn < 1.0 || east_raw.norm() < 1e-3 * wgs84::omega_ie_radps * fn * std::cos(lat_rad)) {
    return Status::kNotConverged;
  }
  const Vec3 up_b = f_b / fn;
  const Vec3 east_b = east_raw.normalized();
  const Vec3 north_b = up_b.cross(east_b);
  // Rows of C_b_n are the n axes expressed in b.
  C_b_n.row(0) = east_b.transpose();
  C_b_n.row(1) = north_b.transpose();
  C_b_n.row(2) = up_b.transpose();
  return Status::kOk;
}

Status davenport_q(const Mat3& B, Mat3& C_b_n, double& lambda_max) {
  if (!B.allFinite()) return Status::kNotConverged;
  using Mat4 = Eigen::Matrix<double, 4, 4>;
  // K = [[S - sigma I, Z], [Z^T, sigma]] (Shuster's convention: its eigenvector (q1, q2, q3, q4)
  // gives the attitude matrix A = (q4^2 - |q|^2) I + 2 q q^T - 2 q4 [q x], which is Eigen's
  // Hamilton quaternion (w = q4, v = -q) as a rotation matrix).
  const Mat3 S = B + B.transpose();
  const double sigma = B.trace();
  const Vec3 Z(B(1, 2) - B(2, 1), B(2, 0) - B(0, 2), B(0, 1) - B(1, 0));
  Mat4 A;
  A.topLeftCorner<3, 3>() = S - sigma * Mat3::Identity();
  A.topRightCorner<3, 1>() = Z;
  A.bottomLeftCorner<1, 3>() = Z.transpose();
  A(3, 3) = sigma;
  Mat4 V = Mat4::Identity();
  const double scale = A.squaredNorm();
  if (!(scale > 0.0)) return Status::kNotConverged;
  bool converged = false;
  for (int sweep = 0; sweep < VelocityMatchAlignment::kMaxSweeps; ++sweep) {
    double off = 0.0;
    for (int p = 0; p < 4; ++p)
      for (int q = p + 1; q < 4; ++q) off += A(p, q) * A(p, q);
    if (off <= 1e-30 * scale) {
      converged = true;
      break;
    }
    for (int p = 0; p < 4; ++p) {
      for (int q = p + 1; q < 4; ++q) {
        const double apq = A(p, q);
        if (apq == 0.0) continue;
        // Rotation in the (p, q) plane that zeroes A(p, q) (Numerical Recipes' jacobi).
        const double theta = (A(q, q) - A(p, p)) / (2.0 * apq);
        const double t = (theta >= 0.0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1.0));
        const double c = 1.0 / std::sqrt(t * t + 1.0);
        const double s = t * c;
        for (int k = 0; k < 4; ++k) {
          const double akp = A(k, p), akq = A(k, q);
          A(k, p) = c * akp - s * akq;
          A(k, q) = s * akp + c * akq;
        }
        for (int k = 0; k < 4; ++k) {
          const double apk = A(p, k), aqk = A(q, k);
          A(p, k) = c * apk - s * aqk;
          A(q, k) = s * apk + c * aqk;
        }
        for (int k = 0; k < 4; ++k) {
          const double vkp = V(k, p), vkq = V(k, q);
          V(k, p) = c * vkp - s * vkq;
          V(k, q) = s * vkp + c * vkq;
        }
      }
    }
  }
  if (!converged) return Status::kNotConverged;
  int best = 0;
  for (int k = 1; k < 4; ++k)
    if (A(k, k) > A(best, best)) best = k;
  lambda_max = A(best, best);
  Quat q(V(3, best), -V(0, best), -V(1, best), -V(2, best));
  q.normalize();
  C_b_n = q.toRotationMatrix();
  return Status::kOk;
}

void VelocityMatchAlignment::reset() {
  sum_w_ = 0.0;
  sum_w_alpha_.setZero();
  sum_w_beta_.setZero();
  sum_w_beta_alpha_.setZero();
  sum_w_alpha2_ = 0.0;
  info_.setZero();
  h_alpha_.setZero();
  h_beta_.setZero();
  sum_w_alpha_beta_.setZero();
  sum_w_beta2_ = 0.0;
  n_ = 0;
  chi2_ = 0.0;
  offset_.setZero();
  gyro_bias_.setZero();
  accel_bias_.setZero();
}

Status VelocityMatchAlignment::add(const Vec3& alpha_b0_mps, const Vec3& beta_enu_mps, double weight, const Mat3& G,
                                   const Mat3& Theta) {
  if (!alpha_b0_mps.allFinite() || !beta_enu_mps.allFinite() || !G.allFinite() || !Theta.allFinite() ||
      !std::isfinite(weight) || !(weight > 0.0))
    return Status::kBadInput;
  Eigen::Matrix<double, 3, 12> H;
  H.leftCols<3>() = skew(alpha_b0_mps);
  H.middleCols<3>(3) = G;
  H.middleCols<3>(6) = Theta;
  H.rightCols<3>() = Mat3::Identity();
  const Eigen::Matrix<double, 12, 3> Ht = H.transpose();
  info_.noalias() += weight * Ht.lazyProduct(H);  // coefficient-wise: no GEMM temporaries
  h_alpha_.noalias() += weight * Ht.lazyProduct(alpha_b0_mps);
  for (int j = 0; j < 3; ++j)
    for (int m = 0; m < 3; ++m) h_beta_.col(3 * j + m) += (weight * beta_enu_mps(m)) * Ht.col(j);
  sum_w_alpha_beta_.noalias() += weight * alpha_b0_mps.lazyProduct(beta_enu_mps.transpose());
  sum_w_beta2_ += weight * beta_enu_mps.squaredNorm();
  sum_w_ += weight;
  sum_w_alpha_ += weight * alpha_b0_mps;
  sum_w_beta_ += weight * beta_enu_mps;
  sum_w_beta_alpha_ += weight * beta_enu_mps * alpha_b0_mps.transpose();
  sum_w_alpha2_ += weight * alpha_b0_mps.squaredNorm();
  ++n_;
  return Status::kOk;
}

namespace {

/// Cholesky solve of the SPD system A X = R (X holds R on entry). false when A is not positive
/// definite or (relatively) singular.
template <int N, int R>
bool cholesky_solve(Eigen::Matrix<double, N, N> A, Eigen::Matrix<double, N, R>& X) {
  for (int j = 0; j < N; ++j) {
    const double diag = A(j, j);
    double d = diag;
    for (int k = 0; k < j; ++k) d -= A(j, k) * A(j, k);
    // A pivot that lost all but 1e-12 of its diagonal: a direction without information.
    if (!(diag > 0.0) || !(d > 1e-12 * diag)) return false;
    A(j, j) = std::sqrt(d);
    for (int i = j + 1; i < N; ++i) {
      double v = A(i, j);
      for (int k = 0; k < j; ++k) v -= A(i, k) * A(j, k);
      A(i, j) = v / A(j, j);
    }
  }
  for (int c = 0; c < R; ++c) {
    for (int i = 0; i < N; ++i) {  // L y = r
      double v = X(i, c);
      for (int k = 0; k < i; ++k) v -= A(i, k) * X(k, c);
      X(i, c) = v / A(i, i);
    }
    for (int i = N - 1; i >= 0; --i) {  // L^T x = y
      double v = X(i, c);
      for (int k = i + 1; k < N; ++k) v -= A(k, i) * X(k, c);
      X(i, c) = v / A(i, i);
    }
  }
  return true;
}

}  // namespace

Status VelocityMatchAlignment::solve(Mat3& C_b0_n, Vec3& att_sigma_enu_rad, double gyro_bias_sigma_radps,
                                     double accel_bias_sigma_mps2) const {
  if (n_ < 3 || !(sum_w_ > 0.0)) return Status::kNotConverged;
  // Start: Wahba's problem on the pairs centred on their weighted means (biases zero), i.e.
  // sum w (beta - beta_m)(alpha - alpha_m)^T = sum w beta alpha^T - W beta_m alpha_m^T.
  const Vec3 alpha_m = sum_w_alpha_ / sum_w_;
  const Vec3 beta_m = sum_w_beta_ / sum_w_;
  const Mat3 B = sum_w_beta_alpha_ - sum_w_ * beta_m * alpha_m.transpose();
  double lambda = 0.0;
  Mat3 C;
  if (davenport_q(B, C, lambda) != Status::kOk) return Status::kNotConverged;
  // Gauss-Newton with the biases and the offset (header). A zero bias sigma: the bias is known (a
  // prior of 1e-9 in its unit).
  Mat12 A = info_;
  const double s_eps = std::max(gyro_bias_sigma_radps, 1e-9);
  const double s_acc = std::max(accel_bias_sigma_mps2, 1e-9);
  for (int i = 0; i < 3; ++i) {
    A(3 + i, 3 + i) += 1.0 / (s_eps * s_eps);
    A(6 + i, 6 + i) += 1.0 / (s_acc * s_acc);
  }
  using Vec12 = Eigen::Matrix<double, 12, 1>;
  Vec12 x = Vec12::Zero();
  Vec12 g = Vec12::Zero();
  for (int it = 0; it < kMaxIterations; ++it) {
    // g = sum w H^T z = sum w H^T C^T beta - sum w H^T alpha; (C^T beta)_j = sum_m C(m, j) beta_m.
    g = -h_alpha_;
    for (int jj = 0; jj < 3; ++jj)
      for (int m = 0; m < 3; ++m) g += C(m, jj) * h_beta_.col(3 * jj + m);
    x = -g;
    if (!cholesky_solve<12, 1>(A, x)) return Status::kNotConverged;
    const Vec3 phi = x.head<3>();
    if (!phi.allFinite()) return Status::kNotConverged;
    C = C * quat_from_rotvec(phi).toRotationMatrix();
    if (phi.norm() < 1e-10) break;
  }
  // At the final C (phi ~ 0): biases, offset, and the fit's chi^2:
  // sum w |z + H x|^2 = sum w |z|^2 + 2 x^T g + x^T N x, sum w |z|^2 = sum w (|beta|^2 + |alpha|^2)
  // - 2 tr(C sum w alpha beta^T).
  g = -h_alpha_;
  for (int jj = 0; jj < 3; ++jj)
    for (int m = 0; m < 3; ++m) g += C(m, jj) * h_beta_.col(3 * jj + m);
  x = -g;
  if (!cholesky_solve<12, 1>(A, x)) return Status::kNotConverged;
  const double z2 = sum_w_beta2_ + sum_w_alpha2_ - 2.0 * (C * sum_w_alpha_beta_).trace();
  chi2_ = std::max(0.0, z2 + 2.0 * x.dot(g) + x.dot(info_.lazyProduct(x)));
  gyro_bias_ = x.segment<3>(3);
  accel_bias_ = x.segment<3>(6);
  offset_ = C * x.tail<3>();
  // Covariance of phi: the phi block of A^-1 (three right-hand sides).
  Eigen::Matrix<double, 12, 3> E = Eigen::Matrix<double, 12, 3>::Zero();
  E.topRows<3>() = Mat3::Identity();
  if (!cholesky_solve<12, 3>(A, E)) return Status::kNotConverged;
  Mat3 cov_b = E.topRows<3>();
  cov_b = 0.5 * (cov_b + cov_b.transpose());
  const double tr = cov_b.trace();
  if (!(tr > 0.0) || !std::isfinite(tr)) return Status::kNotConverged;
  const Mat3 cov_enu_rad2 = C * cov_b * C.transpose();
  const double dof = 3.0 * n_ - 12.0;
  const double factor = dof > 0.0 ? std::max(1.0, chi2_ / dof) : 1.0;
  att_sigma_enu_rad = (cov_enu_rad2.diagonal() * factor).cwiseMax(0.0).cwiseSqrt();
  C_b0_n = C;
  return Status::kOk;
}

Vec3 predicted_alignment_error(const Vec3& accel_bias_enu_mps2, const Vec3& gyro_bias_enu_radps, double lat_rad,
                               double g_mps2) {
  const double phi_e = -accel_bias_enu_mps2.y() / g_mps2;
  const double phi_n = accel_bias_enu_mps2.x() / g_mps2;
  const double phi_u =
      -gyro_bias_enu_radps.x() / (wgs84::omega_ie_radps * std::cos(lat_rad)) + phi_n * std::tan(lat_rad);
  return Vec3(phi_e, phi_n, phi_u);
}

}  // namespace fsw
