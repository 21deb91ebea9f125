#include "fsw/alignment.hpp"

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

Vec3 predicted_alignment_error(const Vec3& accel_bias_n_mps2, const Vec3& gyro_bias_n_radps, double lat_rad,
                               double g_mps2) {
  const double phi_e = -accel_bias_n_mps2.y() / g_mps2;
  const double phi_n = accel_bias_n_mps2.x() / g_mps2;
  const double phi_u =
      -gyro_bias_n_radps.x() / (wgs84::omega_ie_radps * std::cos(lat_rad)) + phi_n * std::tan(lat_rad);
  return Vec3(phi_e, phi_n, phi_u);
}

}  // namespace fsw
