// The one table of configuration rules (fsw/config_check.hpp).
#include "fsw/config_check.hpp"

#include <cmath>

#include "fsw/flight_app_config.hpp"

namespace fsw {

const char* to_string(ConfigField f) {
  switch (f) {
#define FSW_CONFIG_FIELD_CASE(name, path) \
  case ConfigField::name: return path;
    FSW_CONFIG_FIELDS(FSW_CONFIG_FIELD_CASE)
#undef FSW_CONFIG_FIELD_CASE
    case ConfigField::kCount: break;
  }
  return "";
}

const char* to_string(ConfigRule r) {
  switch (r) {
    case ConfigRule::kNone: return "none";
    case ConfigRule::kFinite: return "finite";
    case ConfigRule::kPositive: return "positive";
    case ConfigRule::kNonNegative: return "non_negative";
    case ConfigRule::kAtLeast: return "at_least";
    case ConfigRule::kAtMost: return "at_most";
    case ConfigRule::kBelow: return "below";
    case ConfigRule::kAbove: return "above";
    case ConfigRule::kKnown: return "known";
  }
  return "";
}

namespace {

using F = ConfigField;

/// Applies the rules in order and keeps the first that fails (the later calls do nothing).
class Rules {
 public:
  const ConfigCheck& result() const { return r_; }

  void finite(F f, double v) { require(std::isfinite(v), f, ConfigRule::kFinite, v, 0.0); }
  void positive(F f, double v) { require(v > 0.0, f, ConfigRule::kPositive, v, 0.0); }
  void non_negative(F f, double v) { require(v >= 0.0, f, ConfigRule::kNonNegative, v, 0.0); }
  void at_least(F f, double v, double lo) { require(v >= lo, f, ConfigRule::kAtLeast, v, lo); }
  void at_most(F f, double v, double hi) { require(v <= hi, f, ConfigRule::kAtMost, v, hi); }
  void below(F f, double v, double hi) { require(v < hi, f, ConfigRule::kBelow, v, hi); }
  void above(F f, double v, double lo) { require(v > lo, f, ConfigRule::kAbove, v, lo); }
  void known(F f, bool ok, double v) { require(ok, f, ConfigRule::kKnown, v, 0.0); }
  void in(F f, int v, int lo, int hi) {
    at_least(f, v, lo);
    at_most(f, v, hi);
  }
  /// A standard deviation (or a scale of one): finite and >= 0.
  void sigma(F f, double v) {
    finite(f, v);
    non_negative(f, v);
  }

 private:
  void require(bool ok, F f, ConfigRule rule, double v, double limit) {
    if (r_.ok() && !ok) r_ = ConfigCheck{Status::kBadConfig, f, rule, v, limit};
  }
  ConfigCheck r_{};
};

void ekf_rules(Rules& r, const EkfConfig& c, bool initial_sigmas) {
  if (initial_sigmas) {
    r.sigma(F::kPosSigma, c.pos_sigma_m);
    r.sigma(F::kVelSigma, c.vel_sigma_mps);
    r.sigma(F::kAttSigmaE, c.att_sigma_rad.x());
    r.sigma(F::kAttSigmaN, c.att_sigma_rad.y());
    r.sigma(F::kAttSigmaU, c.att_sigma_rad.z());
  }
  r.sigma(F::kAccelBiasSigma, c.accel_bias_sigma_mps2);
  r.sigma(F::kGyroBiasSigma, c.gyro_bias_sigma_radps);
  r.sigma(F::kAccelMisalignSigma, c.accel_misalign_sigma_rad);
  r.sigma(F::kGyroMisalignSigma, c.gyro_misalign_sigma_rad);
  r.sigma(F::kAccelScaleSigma, c.accel_scale_sigma);
  r.sigma(F::kGyroScaleSigma, c.gyro_scale_sigma);
  r.sigma(F::kGyroGSensSigma, c.gyro_g_sens_sigma_radps_per_mps2);
  r.sigma(F::kTimeOffsetSigma, c.time_offset_sigma_s);
  r.sigma(F::kTimeDriftSigma, c.time_drift_sigma_sps);
  r.sigma(F::kLeverArmSigma, c.lever_arm_sigma_m);
  r.sigma(F::kTropoScaleSigma, c.tropo_scale_sigma);
  r.sigma(F::kIonoScaleSigma, c.iono_scale_sigma);
  r.sigma(F::kClockBiasSigma, c.clock_bias_sigma_m);
  r.sigma(F::kClockDriftSigma, c.clock_drift_sigma_mps);
  r.sigma(F::kVrw, c.vrw_mps_per_rts);
  r.sigma(F::kArw, c.arw_rad_per_rts);
  r.sigma(F::kAccelBiasRw, c.accel_bias_rw_mps2_per_rts);
  r.sigma(F::kGyroBiasRw, c.gyro_bias_rw_radps_per_rts);
  r.sigma(F::kClockBiasPsd, c.clock_bias_psd_m2ps);
  r.sigma(F::kClockDriftPsd, c.clock_drift_psd_m2ps3);
  r.positive(F::kPseudorangeSigma, c.pseudorange_sigma_m);
  r.positive(F::kPseudorangeRateSigma, c.pseudorange_rate_sigma_mps);
  r.sigma(F::kRangeGmSigma, c.range_gm_sigma_m);
  r.positive(F::kRangeGmTau, c.range_gm_tau_s);
  r.sigma(F::kRangeRateGmSigma, c.range_rate_gm_sigma_mps);
  r.positive(F::kRangeRateGmTau, c.range_rate_gm_tau_s);
  r.positive(F::kGateChi2, c.gate_chi2);
  r.sigma(F::kPvtPosSigmaFloor, c.pvt_pos_sigma_floor_m);
  r.sigma(F::kPvtVelSigmaFloor, c.pvt_vel_sigma_floor_mps);
  r.finite(F::kPvtSigmaScale, c.pvt_sigma_scale);
  r.positive(F::kPvtSigmaScale, c.pvt_sigma_scale);
  r.finite(F::kLeverArmX, c.lever_arm_b_m.x());
  r.finite(F::kLeverArmY, c.lever_arm_b_m.y());
  r.finite(F::kLeverArmZ, c.lever_arm_b_m.z());
  r.at_least(F::kPropagationSubstepFrames, c.propagation_substep_frames, 1);
  r.in(F::kNisWindow, c.nis_window, 1, kMaxNisWindow);
  r.non_negative(F::kRunawayEpochs, c.runaway_epochs);
}

void executive_rules(Rules& r, const ExecutiveConfig& c, bool initial_sigmas) {
  r.in(F::kImuSamplesPerFrame, c.imu_samples_per_frame, 1, FrameBuilder::kMaxSamplesPerFrame);
  r.finite(F::kNavRate, c.nav_rate_hz);
  r.positive(F::kNavRate, c.nav_rate_hz);
  r.at_least(F::kFramesPerEkf, c.frames_per_ekf, 1);
  r.non_negative(F::kGnssWaitFrames, c.gnss_wait_frames);
  r.non_negative(F::kMaxGnssAge, c.max_gnss_age_s);
  r.positive(F::kFrameBudget, c.frame_budget_s);
  // The 1 Hz group's correction lands inside its own EKF step (fsw/executive.hpp).
  r.at_least(F::kEkfLatencyFrames, c.ekf_latency_frames, 1);
  r.below(F::kEkfLatencyFrames, c.ekf_latency_frames, c.frames_per_ekf);
  ekf_rules(r, c.ekf, initial_sigmas);
}

}  // namespace

ConfigCheck check_config(const EkfConfig& cfg) {
  Rules r;
  ekf_rules(r, cfg, true);
  return r.result();
}

ConfigCheck check_config(const ExecutiveConfig& cfg) {
  Rules r;
  executive_rules(r, cfg, true);
  return r.result();
}

ConfigCheck check_config(const FlightAppConfig& c) {
  Rules r;
  r.in(F::kMinSatellitesForInit, c.min_satellites_for_init, 4, kMaxGnssChannels);
  r.positive(F::kMaxInitPdop, c.max_init_pdop);
  r.non_negative(F::kMinInitSpeed, c.min_init_speed_mps);
  r.in(F::kLevellingSamples, c.levelling_samples, 1, kMaxLevellingSamples);
  r.positive(F::kInitPosSigma, c.init_pos_sigma_m);
  r.finite(F::kInitPosSigma, c.init_pos_sigma_m);
  r.positive(F::kInitVelSigma, c.init_vel_sigma_mps);
  r.finite(F::kInitVelSigma, c.init_vel_sigma_mps);
  r.finite(F::kInitRollSigma, c.init_att_sigma_rad.x());
  r.positive(F::kInitRollSigma, c.init_att_sigma_rad.x());
  r.finite(F::kInitPitchSigma, c.init_att_sigma_rad.y());
  r.positive(F::kInitPitchSigma, c.init_att_sigma_rad.y());
  r.finite(F::kInitHeadingSigma, c.init_att_sigma_rad.z());
  r.positive(F::kInitHeadingSigma, c.init_att_sigma_rad.z());
  r.finite(F::kInitHeadingOffset, c.init_heading_offset_rad);
  r.at_least(F::kPvtMaxQuality, c.pvt_max_quality, 1);
  const bool mode_ok = c.init_mode == InitMode::kTrack || c.init_mode == InitMode::kStatic ||
                       c.init_mode == InitMode::kVelocityMatching || c.init_mode == InitMode::kGiven;
  r.known(F::kInitMode, mode_ok, static_cast<int>(c.init_mode));
  r.positive(F::kAlignment, c.alignment_s);
  r.finite(F::kAlignment, c.alignment_s);
  r.non_negative(F::kStaticMaxSpeed, c.static_max_speed_mps);
  r.finite(F::kStaticMaxSpeed, c.static_max_speed_mps);
  r.positive(F::kStaticMaxRateDev, c.static_max_rate_dev_radps);
  r.positive(F::kStaticMaxAccelDev, c.static_max_accel_dev_mps2);
  r.non_negative(F::kVmMin, c.vm_min_s);
  r.above(F::kVmMax, c.vm_max_s, c.vm_min_s);
  r.finite(F::kVmMax, c.vm_max_s);
  r.positive(F::kVmMaxHeadingSigma, c.vm_max_heading_sigma_rad);
  r.at_most(F::kVmMaxHeadingSigma, c.vm_max_heading_sigma_rad, kPi);
  r.non_negative(F::kVmRestMin, c.vm_rest_min_s);
  r.finite(F::kVmRestMin, c.vm_rest_min_s);
  // exec.ekf's initial sigmas are FlightApp's init_* (checked above), set when it starts.
  executive_rules(r, c.exec, false);
  return r.result();
}

}  // namespace fsw
