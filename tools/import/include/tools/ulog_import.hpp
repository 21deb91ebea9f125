// `sdins import ulog FILE.ulg --log OUT.lcmlog` (docs/ulog.md): a PX4 ULog into the project's log.
//
// - IMU from `sensor_combined` (mean rates over the integration interval: gyro_rad [rad/s],
//   accelerometer_m_s2 [m/s^2], each times the interval since the previous sample) or
//   `vehicle_imu` (delta_angle [rad], delta_velocity [m/s] over delta_angle_dt). Body axes: PX4's
//   FRD body frame is the project's (x forward, y right, z down), so no axis change.
// - GNSS solutions (GNSS_PVT) from `vehicle_gps_position` or `sensor_gps`: 3D fixes only; lat/lon,
//   ellipsoidal height (alt_ellipsoid), NED velocity -> ENU, eph / epv / s_variance_m_s as the
//   1-sigma of each horizontal axis, the vertical and each velocity axis (as PX4's EKF2 uses them),
//   fix_type -> quality, time from time_utc_usec (the receiver's UTC, leap seconds applied).
// - The reference (TRUTH): PX4's own estimate, `vehicle_global_position` (lat, lon, alt_ellipsoid),
//   velocity from `vehicle_local_position` (vx, vy, vz NED, where v_xy_valid and v_z_valid) and
//   attitude from `vehicle_attitude` (q: FRD body -> NED; C_b_n = T_ned_enu * C(q)), sampled at the
//   attitude's times (at most 50 Hz); a part missing in the log is NaN. An autopilot's estimate,
//   not an independent truth: labelled so in the summary ("reference").
// - Time: PX4 stamps everything with its boot clock [us]. The GNSS messages pair a boot time
//   (timestamp + timestamp_time_relative, minus a declared receiver latency) with the receiver's
//   UTC; a straight line through the pairs (offset and drift, one outlier pass) maps boot time to
//   GPS time (UTC + GPS-UTC, tools/gps_utc.hpp), then to the navigation time scale
//   (tools/importers.hpp: seconds since the start of the GPS week of the earliest sample).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "tools/stream_summary.hpp"
#include "tools/ulog.hpp"

namespace tools {

struct UlogImportOptions {
  std::string path;      ///< the .ulg file
  std::string log_path;  ///< the LCM log to write
  std::string imu_topic = "auto";   ///< auto, sensor_combined, vehicle_imu
  std::string gnss_topic = "auto";  ///< auto, vehicle_gps_position, sensor_gps
  int imu_instance = 0;             ///< multi_id of the IMU topic
  int gnss_instance = 0;            ///< multi_id of the GNSS topic
  /// Receiver latency [s]: a fix's UTC is taken as valid at its boot time stamp minus this (PX4's
  /// own assumption is the EKF2_GPS_DELAY parameter, printed in the summary).
  double gnss_latency_s = 0.0;
  bool reference = true;            ///< write PX4's estimate on TRUTH
};

/// Boot clock -> GPS time: gps(t_boot) = gps0 + offset + (1 + drift) (t_boot - boot0), fitted to
/// (boot time, receiver UTC) pairs.
struct UlogClockFit {
  std::size_t pairs = 0;      ///< pairs used
  std::size_t outliers = 0;   ///< pairs left out (residual beyond 5 robust sigmas and 1 ms)
  std::int64_t boot0_us = 0;  ///< boot time of the first pair
  std::int64_t gps0_us = 0;   ///< its GPS time [us since the GPS epoch]
  double offset_s = 0.0;      ///< fitted GPS time at boot0 minus gps0
  double drift = 0.0;         ///< applied boot clock rate error [s/s] (GPS s per boot s minus 1)
  double fitted_drift = 0.0;  ///< the least-squares drift, and its standard error [s/s]
  double drift_sigma = 0.0;
  /// |fitted_drift| > 3 drift_sigma: the drift is applied; otherwise the fit is an offset only
  /// (over a short log the time stamps' jitter would pose as a drift).
  bool drift_significant = false;
  double residual_rms_s = 0.0, residual_max_s = 0.0;
  int gps_minus_utc_first_s = 0, gps_minus_utc_last_s = 0;
  /// GPS seconds since the GPS epoch of a boot time (about 0.2 us resolution at today's dates).
  double gps_s(std::int64_t boot_us) const { return nav_s(boot_us, 0); }
  /// GPS seconds since origin_us [us since the GPS epoch] of a boot time, without the loss of
  /// precision of the large number (the navigation time scale: origin = the start of week0).
  double nav_s(std::int64_t boot_us, std::int64_t origin_us) const;
};

/// Fits the clock to (boot time [us], UTC [us since 1970]) pairs; throws std::runtime_error
/// without pairs.
UlogClockFit fit_boot_to_gps(const std::vector<std::pair<std::int64_t, std::int64_t>>& boot_utc_us);

/// The streams of one imported log, in the one shape of tools/stream_summary.hpp.
struct UlogStreams {
  StreamSummary imu, gnss, reference;
  /// Time over which IMU and GNSS both have data [s] (0: they do not overlap).
  double imu_gnss_overlap_s = 0.0;
};

struct UlogImportResult {
  nlohmann::json summary;  ///< what `sdins import ulog --json` writes (and LOG.json beside the log)
  /// The summary's imu.samples, gnss_pvt.samples, truth.samples and imu_gnss_overlap_s as structs.
  UlogStreams streams;
};

/// The import of a parsed file (the tests feed handcrafted ULog bytes): writes opt.log_path and
/// returns the summary; throws std::runtime_error when the file lacks an IMU topic or GNSS time.
UlogImportResult import_ulog_file(const ulog::File& file, const UlogImportOptions& opt);
/// Reads opt.path and imports it.
UlogImportResult import_ulog(const UlogImportOptions& opt);
/// The human-readable summary `sdins import ulog` prints.
std::string ulog_import_summary_text(const nlohmann::json& summary);

}  // namespace tools
