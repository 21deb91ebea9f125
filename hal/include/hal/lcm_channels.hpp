// The LCM channel names of the project, in one place. Every process that publishes or logs uses
// these names; the message type of each channel is in hal/lcm/*.lcm (docs/lcm.md).
#pragma once

namespace hal {

inline constexpr const char* kLcmChannelImu = "IMU";                    ///< sdins.imu_sample_t
inline constexpr const char* kLcmChannelGnssRaw = "GNSS_RAW";           ///< sdins.gnss_raw_epoch_t
inline constexpr const char* kLcmChannelGpsAlmanac = "GPS_ALMANAC";     ///< sdins.gps_almanac_t
inline constexpr const char* kLcmChannelNavSolution = "NAV_SOLUTION";   ///< sdins.nav_solution_t
inline constexpr const char* kLcmChannelEkfState = "EKF_STATE";         ///< sdins.ekf_state_t
inline constexpr const char* kLcmChannelFilterHealth = "FILTER_HEALTH"; ///< sdins.filter_health_t
inline constexpr const char* kLcmChannelTruth = "TRUTH";                ///< sdins.truth_t (simulator truth, or a recording's reference)
inline constexpr const char* kLcmChannelGnssPvt = "GNSS_PVT";           ///< sdins.gnss_pvt_t

/// A channel and the full name of the message type it carries.
struct LcmChannelInfo {
  const char* channel;
  const char* type_name;
};

/// Every project channel with its type: `sdins log info` flags a message whose fingerprint is
/// not its channel's type.
inline constexpr LcmChannelInfo kLcmChannels[] = {
    {kLcmChannelImu, "sdins.imu_sample_t"},
    {kLcmChannelGnssRaw, "sdins.gnss_raw_epoch_t"},
    {kLcmChannelGpsAlmanac, "sdins.gps_almanac_t"},
    {kLcmChannelNavSolution, "sdins.nav_solution_t"},
    {kLcmChannelEkfState, "sdins.ekf_state_t"},
    {kLcmChannelFilterHealth, "sdins.filter_health_t"},
    {kLcmChannelTruth, "sdins.truth_t"},
    {kLcmChannelGnssPvt, "sdins.gnss_pvt_t"},
};

/// The UDP multicast URL telemetry uses when neither --lcm-url nor LCM_DEFAULT_URL says
/// otherwise: LCM's own default group and port, ttl=0 so that nothing leaves the host.
inline constexpr const char* kLcmDefaultUrl = "udpm://239.255.76.67:7667?ttl=0";

}  // namespace hal
