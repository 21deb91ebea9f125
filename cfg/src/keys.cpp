// The TOML keys of the flight software's fields and the one unit conversion (keys.hpp).
#include "keys.hpp"

#include "fsw/frames.hpp"
#include "fsw/gnss.hpp"

namespace cfg::keys {
namespace {

using F = fsw::ConfigField;

constexpr double kRth = 60.0;  // sqrt(3600 s / h)
double deg_to_rad(double v) { return v * fsw::kDegToRad; }
double rad_to_deg(double v) { return v / fsw::kDegToRad; }

// Every field of fsw/config_check.hpp that a file sets; the others (the diagnosis' extension
// blocks, the EKF's initial sigmas that FlightApp replaces by init.*) have no key.
const Key kKeys[] = {
    {F::kMinSatellitesForInit, "init.min_satellites"},
    {F::kMaxInitPdop, "init.max_pdop"},
    {F::kMinInitSpeed, "init.min_speed_mps"},
    {F::kLevellingSamples, "init.levelling_samples"},
    {F::kInitPosSigma, "init.pos_sigma_m"},
    {F::kInitVelSigma, "init.vel_sigma_mps"},
    {F::kInitRollSigma, "init.roll_pitch_sigma_deg", deg_to_rad, rad_to_deg},
    {F::kInitPitchSigma, "init.roll_pitch_sigma_deg", deg_to_rad, rad_to_deg},
    {F::kInitHeadingSigma, "init.heading_sigma_deg", deg_to_rad, rad_to_deg},
    {F::kInitHeadingOffset, "init.heading_offset_deg", deg_to_rad, rad_to_deg},
    {F::kPvtMaxQuality, "gnss.pvt_max_quality"},
    {F::kInitMode, "init.mode"},
    {F::kAlignment, "init.alignment_s"},
    {F::kStaticMaxSpeed, "init.static_max_speed_mps"},
    {F::kStaticMaxRateDev, "init.static_max_rate_dev_dps", deg_to_rad, rad_to_deg},
    {F::kStaticMaxAccelDev, "init.static_max_accel_dev_mps2"},
    {F::kVmMin, "init.vm_min_s"},
    {F::kVmMax, "init.vm_max_s"},
    {F::kVmMaxHeadingSigma, "init.vm_max_heading_sigma_deg", deg_to_rad, rad_to_deg},
    {F::kVmRestMin, "init.vm_rest_min_s"},
    {F::kImuSamplesPerFrame, "executive.imu_samples_per_frame"},
    {F::kNavRate, "executive.nav_rate_hz"},
    {F::kMaxGnssAge, "executive.max_gnss_age_s"},
    {F::kFrameBudget, "executive.frame_budget_s"},
    {F::kEkfLatencyFrames, "executive.ekf_latency_frames"},
    {F::kPropagationSubstepFrames, "executive.propagation_substep_frames"},
    {F::kAccelBiasSigma, "imu.accel_bias_sigma_mg", [](double v) { return v * 1e3 * fsw::kMicroG_mps2; },
     [](double v) { return v / (1e3 * fsw::kMicroG_mps2); }},
    {F::kGyroBiasSigma, "imu.gyro_bias_sigma_degph", [](double v) { return v * fsw::kDegPerHourToRadps; },
     [](double v) { return v / fsw::kDegPerHourToRadps; }},
    // Divided, not multiplied by 1e-6: 100 ppm is exactly the double 1e-4.
    {F::kAccelScaleSigma, "imu.accel_scale_factor_sigma_ppm", [](double v) { return v / 1e6; },
     [](double v) { return v * 1e6; }},
    {F::kGyroScaleSigma, "imu.gyro_scale_factor_sigma_ppm", [](double v) { return v / 1e6; },
     [](double v) { return v * 1e6; }},
    {F::kAccelMisalignSigma, "imu.accel_misalignment_sigma_arcsec", [](double v) { return v * fsw::kArcsecToRad; },
     [](double v) { return v / fsw::kArcsecToRad; }},
    {F::kGyroMisalignSigma, "imu.gyro_misalignment_sigma_arcsec", [](double v) { return v * fsw::kArcsecToRad; },
     [](double v) { return v / fsw::kArcsecToRad; }},
    {F::kVrw, "imu.vrw_mps_per_rts", nullptr, nullptr, "imu.vrw_mps_per_rthr", [](double v) { return v / kRth; },
     [](double v) { return v * kRth; }},
    {F::kArw, "imu.arw_rad_per_rts", nullptr, nullptr, "imu.arw_deg_per_rthr",
     [](double v) { return v * fsw::kDegToRad / kRth; }, [](double v) { return v * kRth / fsw::kDegToRad; }},
    {F::kAccelBiasRw, "imu.accel_bias_rw_mps2_per_rts"},
    {F::kGyroBiasRw, "imu.gyro_bias_rw_radps_per_rts"},
    // The clock's Allan-variance coefficients become the filter's process noise through the one
    // formula the simulated receiver draws with (fsw/gnss.hpp).
    {F::kClockBiasPsd, "gnss.clock_h0_s", fsw::clock_bias_psd_m2ps, [](double v) { return v / fsw::clock_bias_psd_m2ps(1.0); }},
    {F::kClockDriftPsd, "gnss.clock_h_minus2_per_s", fsw::clock_drift_psd_m2ps3,
     [](double v) { return v / fsw::clock_drift_psd_m2ps3(1.0); }},
    {F::kClockBiasSigma, "gnss.clock_bias_sigma_m"},
    {F::kClockDriftSigma, "gnss.clock_drift_sigma_mps"},
    {F::kPseudorangeSigma, "gnss.pseudorange_sigma_m"},
    {F::kPseudorangeRateSigma, "gnss.pseudorange_rate_sigma_mps"},
    {F::kRangeGmSigma, "gnss.range_error_sigma_m"},
    {F::kRangeGmTau, "gnss.range_error_tau_s"},
    {F::kRangeRateGmSigma, "gnss.range_rate_error_sigma_mps"},
    {F::kRangeRateGmTau, "gnss.range_rate_error_tau_s"},
    {F::kGateChi2, "gnss.gate_chi2"},
    {F::kPvtPosSigmaFloor, "gnss.pvt_pos_sigma_floor_m"},
    {F::kPvtVelSigmaFloor, "gnss.pvt_vel_sigma_floor_mps"},
    {F::kPvtSigmaScale, "gnss.pvt_sigma_scale"},
    {F::kLeverArmX, "mounting.lever_arm_b_m"},
    {F::kLeverArmY, "mounting.lever_arm_b_m"},
    {F::kLeverArmZ, "mounting.lever_arm_b_m"},
    {F::kNisWindow, "health.nis_window_epochs"},
    {F::kRunawayEpochs, "health.runaway_epochs"},
};

}  // namespace

const Key* find_key(F field) {
  for (const Key& k : kKeys) {
    if (k.field == field) return &k;
  }
  return nullptr;
}

double to_si(F field, double v) {
  const Key* k = find_key(field);
  return k && k->to_si ? k->to_si(v) : v;
}
double alt_to_si(F field, double v) { return find_key(field)->alt_to_si(v); }

}  // namespace cfg::keys
