// IMU error model applied to the ideal increments of the truth generator.
//
//   dtheta_meas = (I + diag(sf_g) + M_g) dtheta + G_g dv + (b_g + d_g(t) + w_g(t)) dt + n_g
//   dv_meas     = (I + diag(sf_a) + M_a) dv + (b_a + d_a(t) + w_a(t)) dt + n_a
//
// M holds the misalignments (M(i, j) = gamma_ij, see fsw/effect_catalogue.hpp), G_g the diagonal
// gyro g-sensitivity, b the constant biases, d(t) first-order Gauss-Markov bias drifts, w(t) bias
// random walks (rate random walk, the filter's bias model; docs/noise.md) and n white noise
// (angle / velocity random walk). With a mounting (ImuConfig::mounting_rpy_deg) dtheta and dv are
// the body increments turned into the sensor axes first (C_s_b^T), so every error above is the
// sensor's own. Time tags are shifted by the IMU-to-GNSS time
// offset effect. Everything is drawn from the seed with the project's own portable generator so
// that the same scenario and seed give bit-identical output everywhere.
#pragma once

#include <cstdint>

#include "fsw/strapdown.hpp"
#include "sim/rng.hpp"
#include "sim/scenario.hpp"
#include "sim/trajectory.hpp"

namespace sim {

/// The truth values of one run's IMU errors, SI units.
struct ImuErrors {
  Vec3 accel_bias_mps2 = Vec3::Zero();
  Vec3 accel_scale_factor = Vec3::Zero();
  Mat3 accel_misalignment_rad = Mat3::Zero();  ///< only (1,0), (2,0), (2,1) used
  Vec3 gyro_bias_radps = Vec3::Zero();
  Vec3 gyro_scale_factor = Vec3::Zero();
  Mat3 gyro_misalignment_rad = Mat3::Zero();   ///< off-diagonal gamma_ij
  Vec3 gyro_g_sensitivity_radps_per_mps2 = Vec3::Zero();  ///< diagonal: gyro i senses g_i * f_i
  double gyro_arw_rad_per_rts = 0.0;           ///< angle random walk [rad/sqrt(s)]
  double accel_vrw_mps_per_rts = 0.0;          ///< velocity random walk [m/s/sqrt(s)]
  double gyro_bias_instability_radps = 0.0;    ///< 1-sigma of the Gauss-Markov drift
  double accel_bias_instability_mps2 = 0.0;
  double bias_instability_tau_s = 3600.0;
  double gyro_bias_rw_radps_per_rts = 0.0;     ///< bias random walk (rate random walk) [rad/s/sqrt(s)]
  double accel_bias_rw_mps2_per_rts = 0.0;     ///< [m/s^2/sqrt(s)]
  double time_offset_s = 0.0;                  ///< IMU time tag minus GNSS (true) time
  double clock_drift = 0.0;                    ///< IMU clock rate error: tags at t (1 + drift) + offset
  bool mounted = false;                        ///< the sensor axes turned against the body (ImuConfig::mounting_rpy_deg)
  Mat3 C_s_b = Mat3::Identity();               ///< sensor to body: body increments read C_s_b^T x in the sensor
};

/// C_s_b of a mounting [roll, pitch, yaw] in degrees (ImuConfig::mounting_rpy_deg).
Mat3 mounting_C_s_b(const std::array<double, 3>& rpy_deg);

/// Draws the per-run errors for a scenario: the error set's 1-sigma values from the seed, then
/// the scenario's fixed effects added on top.
ImuErrors draw_imu_errors(const ImuConfig& cfg, const EffectSet& effects, std::uint64_t seed);

/// Only the fixed effects (no random draw): used by analyses that inject one error at a time.
ImuErrors imu_errors_from_effects(const EffectSet& effects);

class ImuModel {
 public:
  ImuModel(const ImuErrors& errors, std::uint64_t noise_seed);
  /// The measured IMU sample for one truth sample (its increments over the last interval).
  fsw::ImuSample measure(const TruthSample& truth);
  const ImuErrors& errors() const { return e_; }

 private:
  ImuErrors e_;
  Rng rng_;
  Mat3 Kg_, Ka_;  ///< I + scale factors + misalignments: the errors' fixed parts, formed once
  Vec3 drift_g_ = Vec3::Zero();
  Vec3 drift_a_ = Vec3::Zero();
  Vec3 walk_g_ = Vec3::Zero();
  Vec3 walk_a_ = Vec3::Zero();
};

/// GNSS antenna position and velocity from the truth and the body-frame lever arm.
void antenna_truth(const TruthSample& truth, const Vec3& lever_arm_b_m, Vec3& llh_ant, Vec3& vel_ant_enu_mps);

}  // namespace sim
