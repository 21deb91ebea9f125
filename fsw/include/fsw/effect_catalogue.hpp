// The effect catalogue: the named sensor and signal effects that the simulator can inject on the
// truth side and that the diagnosis can name and estimate. One table, shared by sim/, fsw/ and
// tools/, so that a name and its unit mean the same thing everywhere.
//
// Misalignment convention (gyro and accelerometer): sensor i is tilted toward body axis j, so it
// also senses gamma_ij times the rate (specific force) about (along) j:
//   measured_i = (1 + sf_i) * true_i + sum_{j != i} gamma_ij * true_j + bias_i + ...
// The body frame is defined by the accelerometer triad (x along the x accelerometer, y in the
// plane of the x and y accelerometers), so the accelerometer keeps only yx, zx, zy; the gyro
// triad keeps all six.
#pragma once

#include <cstddef>
#include <cstdint>

#include "fsw/frames.hpp"

namespace fsw {

enum class Effect : std::uint8_t {
  kGyroMisalignment = 0,
  kAccelMisalignment,
  kGyroScaleFactor,
  kAccelScaleFactor,
  kGyroGSensitivity,
  kImuGnssTimeOffset,
  kAntennaLeverArm,
  kTroposphericDelay,
  kIonosphericDelay,
  kImuClockDrift,
  kCount
};

inline constexpr std::size_t kEffectCount = static_cast<std::size_t>(Effect::kCount);
inline constexpr std::size_t kMaxEffectComponents = 6;

struct EffectInfo {
  Effect effect;
  const char* name;                               ///< catalogue name, e.g. "gyro_misalignment"
  const char* unit;                               ///< catalogue unit, e.g. "arcsec"
  std::size_t n_components;                       ///< 1 for scalar effects (component name "")
  const char* components[kMaxEffectComponents];   ///< component names
  double unit_to_si;                              ///< multiply a catalogue value to get SI
};

inline constexpr EffectInfo kEffectCatalogue[kEffectCount] = {
    {Effect::kGyroMisalignment, "gyro_misalignment", "arcsec", 6, {"xy", "xz", "yx", "yz", "zx", "zy"}, kArcsecToRad},
    {Effect::kAccelMisalignment, "accel_misalignment", "arcsec", 3, {"yx", "zx", "zy", "", "", ""}, kArcsecToRad},
    {Effect::kGyroScaleFactor, "gyro_scale_factor", "ppm", 3, {"x", "y", "z", "", "", ""}, 1e-6},
    {Effect::kAccelScaleFactor, "accel_scale_factor", "ppm", 3, {"x", "y", "z", "", "", ""}, 1e-6},
    {Effect::kGyroGSensitivity, "gyro_g_sensitivity", "deg/h/g", 3, {"x", "y", "z", "", "", ""},
     kDegPerHourToRadps / kStandardGravity_mps2},
    {Effect::kImuGnssTimeOffset, "imu_gnss_time_offset", "s", 1, {"", "", "", "", "", ""}, 1.0},
    {Effect::kAntennaLeverArm, "antenna_lever_arm", "m", 3, {"x", "y", "z", "", "", ""}, 1.0},
    {Effect::kTroposphericDelay, "tropospheric_delay", "scale", 1, {"", "", "", "", "", ""}, 1.0},
    {Effect::kIonosphericDelay, "ionospheric_delay", "scale", 1, {"", "", "", "", "", ""}, 1.0},
    // The IMU clock's rate error against GNSS time: the IMU-GNSS time offset grows by this much
    // per second (IMU time tags and intervals stretched by 1 + drift).
    {Effect::kImuClockDrift, "imu_clock_drift", "ppm", 1, {"", "", "", "", "", ""}, 1e-6},
};

inline constexpr const EffectInfo& effect_info(Effect e) { return kEffectCatalogue[static_cast<std::size_t>(e)]; }

/// Row/column (i, j) of misalignment component k of a 6-component (gyro) or 3-component
/// (accelerometer) misalignment effect; e.g. gyro "xy" -> (0, 1).
struct AxisPair {
  int i;
  int j;
};
inline constexpr AxisPair kGyroMisalignmentAxes[6] = {{0, 1}, {0, 2}, {1, 0}, {1, 2}, {2, 0}, {2, 1}};
inline constexpr AxisPair kAccelMisalignmentAxes[3] = {{1, 0}, {2, 0}, {2, 1}};

}  // namespace fsw
