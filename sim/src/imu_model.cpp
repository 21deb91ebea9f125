#include "sim/imu_model.hpp"

#include <cmath>

#include "fsw/frames.hpp"

namespace sim {
namespace {

using fsw::Effect;

enum Stream : std::uint64_t { kStreamErrors = 1, kStreamNoise = 2 };

Vec3 normal3(Rng& r, double sigma) {
  const double x = r.normal(), y = r.normal(), z = r.normal();
  return Vec3(x, y, z) * sigma;
}

void add_effects(ImuErrors& e, const EffectSet& fx) {
  for (std::size_t k = 0; k < 6; ++k) {
    const auto ax = fsw::kGyroMisalignmentAxes[k];
    e.gyro_misalignment_rad(ax.i, ax.j) += fx.si(Effect::kGyroMisalignment, k);
  }
  for (std::size_t k = 0; k < 3; ++k) {
    const auto ax = fsw::kAccelMisalignmentAxes[k];
    e.accel_misalignment_rad(ax.i, ax.j) += fx.si(Effect::kAccelMisalignment, k);
    const int i = static_cast<int>(k);
    e.gyro_scale_factor(i) += fx.si(Effect::kGyroScaleFactor, k);
    e.accel_scale_factor(i) += fx.si(Effect::kAccelScaleFactor, k);
    e.gyro_g_sensitivity_radps_per_mps2(i) += fx.si(Effect::kGyroGSensitivity, k);
  }
  e.time_offset_s += fx.si(Effect::kImuGnssTimeOffset, 0);
  e.clock_drift += fx.si(Effect::kImuClockDrift, 0);
}

}  // namespace

Mat3 mounting_C_s_b(const std::array<double, 3>& rpy_deg) {
  // C_b_n_from_euler is the rotation to NED followed by the NED -> ENU permutation: undo the latter.
  return fsw::C_ned_enu() *
         fsw::C_b_n_from_euler(rpy_deg[0] * fsw::kDegToRad, rpy_deg[1] * fsw::kDegToRad, rpy_deg[2] * fsw::kDegToRad);
}

ImuErrors imu_errors_from_effects(const EffectSet& effects) {
  ImuErrors e;
  add_effects(e, effects);
  return e;
}

ImuErrors draw_imu_errors(const ImuConfig& cfg, const EffectSet& effects, std::uint64_t seed) {
  ImuErrors e;
  const ImuErrorSigmas& s = cfg.sigmas;
  if (cfg.errors != ImuErrorSet::kNone) {
    // Fixed draw order: changing it changes every seeded run.
    Rng r(seed, kStreamErrors);
    e.accel_bias_mps2 = normal3(r, s.accel_bias_ug * fsw::kMicroG_mps2);
    e.gyro_bias_radps = normal3(r, s.gyro_bias_degph * fsw::kDegPerHourToRadps);
    const Vec3 asf = normal3(r, s.accel_scale_factor_ppm * 1e-6);
    const Vec3 gsf = normal3(r, s.gyro_scale_factor_ppm * 1e-6);
    const Vec3 ama = normal3(r, s.accel_misalignment_arcsec * fsw::kArcsecToRad);
    const Vec3 gm1 = normal3(r, s.gyro_misalignment_arcsec * fsw::kArcsecToRad);
    const Vec3 gm2 = normal3(r, s.gyro_misalignment_arcsec * fsw::kArcsecToRad);
    if (cfg.errors == ImuErrorSet::kPaper) {
      e.accel_scale_factor = asf;
      e.gyro_scale_factor = gsf;
      for (int k = 0; k < 3; ++k) {
        const auto ax = fsw::kAccelMisalignmentAxes[k];
        e.accel_misalignment_rad(ax.i, ax.j) = ama(k);
      }
      for (int k = 0; k < 6; ++k) {
        const auto ax = fsw::kGyroMisalignmentAxes[k];
        e.gyro_misalignment_rad(ax.i, ax.j) = k < 3 ? gm1(k) : gm2(k - 3);
      }
    }
    e.gyro_arw_rad_per_rts = s.gyro_arw_deg_per_rthr * fsw::kDegToRad / 60.0;
    e.accel_vrw_mps_per_rts = s.accel_vrw_ug_per_rthz * fsw::kMicroG_mps2;
    e.gyro_bias_instability_radps = s.gyro_bias_instability_degph * fsw::kDegPerHourToRadps;
    e.accel_bias_instability_mps2 = s.accel_bias_instability_ug * fsw::kMicroG_mps2;
    e.bias_instability_tau_s = s.bias_instability_tau_s;
    // deg/h/sqrt(h) -> rad/s/sqrt(s); ug/sqrt(h) -> m/s^2/sqrt(s)
    e.gyro_bias_rw_radps_per_rts = s.gyro_bias_rw_degph_per_rthr * fsw::kDegPerHourToRadps / 60.0;
    e.accel_bias_rw_mps2_per_rts = s.accel_bias_rw_ug_per_rthr * fsw::kMicroG_mps2 / 60.0;
  }
  add_effects(e, effects);
  const std::array<double, 3>& m = cfg.mounting_rpy_deg;
  e.mounted = m[0] != 0.0 || m[1] != 0.0 || m[2] != 0.0;  // no draw: the seeded runs are unchanged
  if (e.mounted) e.C_s_b = mounting_C_s_b(m);
  return e;
}

ImuModel::ImuModel(const ImuErrors& errors, std::uint64_t noise_seed)
    : e_(errors),
      rng_(noise_seed, kStreamNoise),
      Kg_(Mat3::Identity() + Mat3(e_.gyro_scale_factor.asDiagonal()) + e_.gyro_misalignment_rad),
      Ka_(Mat3::Identity() + Mat3(e_.accel_scale_factor.asDiagonal()) + e_.accel_misalignment_rad) {}

fsw::ImuSample ImuModel::measure(const TruthSample& truth) {
  const double dt = truth.dt_s;
  // First-order Gauss-Markov drifts, exact discretisation.
  if (e_.gyro_bias_instability_radps > 0.0 || e_.accel_bias_instability_mps2 > 0.0) {
    const double a = std::exp(-dt / e_.bias_instability_tau_s);
    const double q = std::sqrt(1.0 - a * a);
    drift_g_ = a * drift_g_ + normal3(rng_, q * e_.gyro_bias_instability_radps);
    drift_a_ = a * drift_a_ + normal3(rng_, q * e_.accel_bias_instability_mps2);
  }
  // Bias random walks (drawn only when set: the seeded runs without them are unchanged).
  if (e_.gyro_bias_rw_radps_per_rts > 0.0 || e_.accel_bias_rw_mps2_per_rts > 0.0) {
    walk_g_ += normal3(rng_, e_.gyro_bias_rw_radps_per_rts * std::sqrt(dt));
    walk_a_ += normal3(rng_, e_.accel_bias_rw_mps2_per_rts * std::sqrt(dt));
  }
  // The increments in the sensor's axes (a fixed rotation turns the integrals exactly).
  const Vec3 dtheta = e_.mounted ? Vec3(e_.C_s_b.transpose() * truth.dtheta_rad) : truth.dtheta_rad;
  const Vec3 dv = e_.mounted ? Vec3(e_.C_s_b.transpose() * truth.dv_mps) : truth.dv_mps;
  fsw::ImuSample s;
  s.t_s = truth.t_s * (1.0 + e_.clock_drift) + e_.time_offset_s;
  s.dt_s = dt * (1.0 + e_.clock_drift);
  s.dtheta_rad = Kg_ * dtheta + e_.gyro_g_sensitivity_radps_per_mps2.cwiseProduct(dv) +
                 (e_.gyro_bias_radps + drift_g_ + walk_g_) * dt;
  s.dv_mps = Ka_ * dv + (e_.accel_bias_mps2 + drift_a_ + walk_a_) * dt;
  if (e_.gyro_arw_rad_per_rts > 0.0) s.dtheta_rad += normal3(rng_, e_.gyro_arw_rad_per_rts * std::sqrt(dt));
  if (e_.accel_vrw_mps_per_rts > 0.0) s.dv_mps += normal3(rng_, e_.accel_vrw_mps_per_rts * std::sqrt(dt));
  return s;
}

void antenna_truth(const TruthSample& truth, const Vec3& lever_arm_b_m, Vec3& llh_ant, Vec3& vel_ant_enu_mps) {
  const Vec3 d_enu = truth.C_b_n * lever_arm_b_m;
  const double lat = truth.llh.x();
  llh_ant = truth.llh + fsw::llh_delta_from_enu(truth.llh, d_enu);
  // Velocity of the antenna relative to the Earth: v + C_b_n (omega_eb_b x l).
  const Vec3 w_ie_b = truth.C_b_n.transpose() * fsw::omega_ie_n(lat);
  vel_ant_enu_mps = truth.vel_enu_mps + truth.C_b_n * (truth.omega_ib_b_radps - w_ie_b).cross(lever_arm_b_m);
}

}  // namespace sim
