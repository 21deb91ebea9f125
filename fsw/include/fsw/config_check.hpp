// The rules a flight configuration must meet: one table, checked by FlightApp::init (and, for
// their parts, by Executive::init and Ekf::init), and by every host command when it loads a
// configuration (cfg::validate, cfg/flight_config.hpp), so that a rejected configuration is
// refused at load with the file, the key, the value and the rule instead of as a bare kBadConfig.
//
// The result names the field (ConfigField, its C++ path in to_string), the rule, the value and
// the limit; no strings are built here (fsw: no heap, no I/O). The host translates the field to
// its TOML key and unit (cfg/src/flight_config.cpp).
#pragma once

#include <cstdint>

#include "fsw/status.hpp"

namespace fsw {

struct EkfConfig;
struct ExecutiveConfig;
struct FlightAppConfig;

/// The fields the rules name: X(enumerator, C++ path from FlightAppConfig). Components of a vector
/// are their own fields (init_att_sigma_rad x/y: roll and pitch; z: heading).
#define FSW_CONFIG_FIELDS(X)                                                         \
  X(kNone, "")                                                                       \
  X(kMinSatellitesForInit, "min_satellites_for_init")                                \
  X(kMaxInitPdop, "max_init_pdop")                                                   \
  X(kMinInitSpeed, "min_init_speed_mps")                                             \
  X(kLevellingSamples, "levelling_samples")                                          \
  X(kInitPosSigma, "init_pos_sigma_m")                                               \
  X(kInitVelSigma, "init_vel_sigma_mps")                                             \
  X(kInitRollSigma, "init_att_sigma_rad.x")                                          \
  X(kInitPitchSigma, "init_att_sigma_rad.y")                                         \
  X(kInitHeadingSigma, "init_att_sigma_rad.z")                                       \
  X(kInitHeadingOffset, "init_heading_offset_rad")                                   \
  X(kPvtMaxQuality, "pvt_max_quality")                                               \
  X(kInitMode, "init_mode")                                                          \
  X(kAlignment, "alignment_s")                                                       \
  X(kStaticMaxSpeed, "static_max_speed_mps")                                         \
  X(kStaticMaxRateDev, "static_max_rate_dev_radps")                                  \
  X(kStaticMaxAccelDev, "static_max_accel_dev_mps2")                                 \
  X(kVmMin, "vm_min_s")                                                              \
  X(kVmMax, "vm_max_s")                                                              \
  X(kVmMaxHeadingSigma, "vm_max_heading_sigma_rad")                                  \
  X(kVmRestMin, "vm_rest_min_s")                                                     \
  X(kImuSamplesPerFrame, "exec.imu_samples_per_frame")                               \
  X(kNavRate, "exec.nav_rate_hz")                                                    \
  X(kFramesPerEkf, "exec.frames_per_ekf")                                            \
  X(kGnssWaitFrames, "exec.gnss_wait_frames")                                        \
  X(kMaxGnssAge, "exec.max_gnss_age_s")                                              \
  X(kFrameBudget, "exec.frame_budget_s")                                             \
  X(kEkfLatencyFrames, "exec.ekf_latency_frames")                                    \
  X(kPosSigma, "exec.ekf.pos_sigma_m")                                               \
  X(kVelSigma, "exec.ekf.vel_sigma_mps")                                             \
  X(kAttSigmaE, "exec.ekf.att_sigma_rad.x")                                          \
  X(kAttSigmaN, "exec.ekf.att_sigma_rad.y")                                          \
  X(kAttSigmaU, "exec.ekf.att_sigma_rad.z")                                          \
  X(kAccelBiasSigma, "exec.ekf.accel_bias_sigma_mps2")                               \
  X(kGyroBiasSigma, "exec.ekf.gyro_bias_sigma_radps")                                \
  X(kAccelMisalignSigma, "exec.ekf.accel_misalign_sigma_rad")                        \
  X(kGyroMisalignSigma, "exec.ekf.gyro_misalign_sigma_rad")                          \
  X(kAccelScaleSigma, "exec.ekf.accel_scale_sigma")                                  \
  X(kGyroScaleSigma, "exec.ekf.gyro_scale_sigma")                                    \
  X(kGyroGSensSigma, "exec.ekf.gyro_g_sens_sigma_radps_per_mps2")                    \
  X(kTimeOffsetSigma, "exec.ekf.time_offset_sigma_s")                                \
  X(kTimeDriftSigma, "exec.ekf.time_drift_sigma_sps")                                \
  X(kLeverArmSigma, "exec.ekf.lever_arm_sigma_m")                                    \
  X(kTropoScaleSigma, "exec.ekf.tropo_scale_sigma")                                  \
  X(kIonoScaleSigma, "exec.ekf.iono_scale_sigma")                                    \
  X(kClockBiasSigma, "exec.ekf.clock_bias_sigma_m")                                  \
  X(kClockDriftSigma, "exec.ekf.clock_drift_sigma_mps")                              \
  X(kVrw, "exec.ekf.vrw_mps_per_rts")                                                \
  X(kArw, "exec.ekf.arw_rad_per_rts")                                                \
  X(kAccelBiasRw, "exec.ekf.accel_bias_rw_mps2_per_rts")                             \
  X(kGyroBiasRw, "exec.ekf.gyro_bias_rw_radps_per_rts")                              \
  X(kClockBiasPsd, "exec.ekf.clock_bias_psd_m2ps")                                   \
  X(kClockDriftPsd, "exec.ekf.clock_drift_psd_m2ps3")                                \
  X(kPseudorangeSigma, "exec.ekf.pseudorange_sigma_m")                               \
  X(kPseudorangeRateSigma, "exec.ekf.pseudorange_rate_sigma_mps")                    \
  X(kRangeGmSigma, "exec.ekf.range_gm_sigma_m")                                      \
  X(kRangeGmTau, "exec.ekf.range_gm_tau_s")                                          \
  X(kRangeRateGmSigma, "exec.ekf.range_rate_gm_sigma_mps")                           \
  X(kRangeRateGmTau, "exec.ekf.range_rate_gm_tau_s")                                 \
  X(kGateChi2, "exec.ekf.gate_chi2")                                                 \
  X(kPvtPosSigmaFloor, "exec.ekf.pvt_pos_sigma_floor_m")                             \
  X(kPvtVelSigmaFloor, "exec.ekf.pvt_vel_sigma_floor_mps")                           \
  X(kPvtSigmaScale, "exec.ekf.pvt_sigma_scale")                                      \
  X(kLeverArmX, "exec.ekf.lever_arm_b_m.x")                                          \
  X(kLeverArmY, "exec.ekf.lever_arm_b_m.y")                                          \
  X(kLeverArmZ, "exec.ekf.lever_arm_b_m.z")                                          \
  X(kPropagationSubstepFrames, "exec.ekf.propagation_substep_frames")                \
  X(kNisWindow, "exec.ekf.nis_window")                                               \
  X(kRunawayEpochs, "exec.ekf.runaway_epochs")

enum class ConfigField : std::uint8_t {
#define FSW_CONFIG_FIELD_ENUM(name, path) name,
  FSW_CONFIG_FIELDS(FSW_CONFIG_FIELD_ENUM)
#undef FSW_CONFIG_FIELD_ENUM
      kCount
};

/// The field's C++ path from FlightAppConfig ("exec.ekf_latency_frames"; "" for kNone).
const char* to_string(ConfigField f);

/// What the value failed. The limit (ConfigCheck::limit) is the bound the rule compares with.
enum class ConfigRule : std::uint8_t {
  kNone,
  kFinite,       ///< must be a finite number
  kPositive,     ///< must be > 0
  kNonNegative,  ///< must be >= 0
  kAtLeast,      ///< must be >= limit
  kAtMost,       ///< must be <= limit
  kBelow,        ///< must be < limit
  kAbove,        ///< must be > limit
  kKnown,        ///< must be one of the enumerators
};
const char* to_string(ConfigRule r);

/// The outcome of a check: kOk, or kBadConfig with the first rule that failed.
struct ConfigCheck {
  Status status = Status::kOk;
  ConfigField field = ConfigField::kNone;
  ConfigRule rule = ConfigRule::kNone;
  double value = 0.0;
  double limit = 0.0;
  bool ok() const { return status == Status::kOk; }
};

/// The whole flight configuration (what FlightApp::init accepts). exec.ekf's initial pos/vel/att
/// sigmas are not checked: FlightApp replaces them by the init_* sigmas, which are.
ConfigCheck check_config(const FlightAppConfig& cfg);
/// The executive's part with its EKF (what Executive::init accepts).
ConfigCheck check_config(const ExecutiveConfig& cfg);
/// The EKF's part (what Ekf::init accepts).
ConfigCheck check_config(const EkfConfig& cfg);

}  // namespace fsw
