// IMU error compensation fed back by the EKF (closed loop): applied to every raw IMU sample before
// the coning/sculling frame builder.
//
//   compensated = measured - b_hat * dt - E_hat * measured,   E_hat = diag(SF_hat) + M_hat
//   gyro additionally: - G_hat .* dv_measured (g-sensitivity: gyro i senses G_i f_i)
//
// which inverts measured = (I + E) true + b * dt (+ G .* dv) to first order in the
// (ppm/arcsec-level) errors.
#pragma once

#include "fsw/frames.hpp"
#include "fsw/strapdown.hpp"

namespace fsw {

struct ImuCompensation {
  Vec3 accel_bias_mps2 = Vec3::Zero();
  Vec3 gyro_bias_radps = Vec3::Zero();
  Mat3 accel_error = Mat3::Zero();  ///< diag: scale factors; (i, j): misalignment gamma_ij
  Mat3 gyro_error = Mat3::Zero();
  Vec3 gyro_g_sens_radps_per_mps2 = Vec3::Zero();  ///< diagonal g-sensitivity (only the diagnosis model estimates it)

  ImuSample apply(const ImuSample& raw) const {
    ImuSample s = raw;
    s.dtheta_rad = raw.dtheta_rad - gyro_bias_radps * raw.dt_s - gyro_error * raw.dtheta_rad -
                   gyro_g_sens_radps_per_mps2.cwiseProduct(raw.dv_mps);
    s.dv_mps = raw.dv_mps - accel_bias_mps2 * raw.dt_s - accel_error * raw.dv_mps;
    return s;
  }
};

}  // namespace fsw
