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
  double duration_s() const { return dt_sum_; }
  /// Mean specific force and angular rate over the accumulated samples (body frame).
  Vec3 mean_f_b_mps2() const { return dt_sum_ > 0.0 ? Vec3(dv_sum_ / dt_sum_) : Vec3::Zero(); }
  Vec3 mean_omega_b_radps() const { return dt_sum_ > 0.0 ? Vec3(dtheta_sum_ / dt_sum_) : Vec3::Zero(); }

 private:
  Vec3 dtheta_sum_ = Vec3::Zero();
  Vec3 dv_sum_ = Vec3::Zero();
  double dt_sum_ = 0.0;
};

/// First-order prediction of the alignment attitude error for biases resolved in n.
Vec3 predicted_alignment_error(const Vec3& accel_bias_n_mps2, const Vec3& gyro_bias_n_radps, double lat_rad,
                               double g_mps2);

}  // namespace fsw
