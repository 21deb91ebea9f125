// Synthetic sensor input of the bare-metal image (fsw/baremetal/main.cpp) and of its host test
// (tests/unit/test_baremetal_input.cpp): a receiver at rest at a fixed position, level, body axes
// along ENU, with a 24-satellite Walker constellation (6 planes x 4, 55 deg, circular, semi-major
// axis 26 560 km) as almanac elements and raw receiver epochs whose pseudoranges and rates the
// flight code's own models give for that position (satellite at tow - rho / c from the almanac,
// Sagnac included, no clocks): what the flight application takes from the HAL on a target, so the
// image flies the same entries (FlightApp::on_almanac / on_gnss / on_imu) as HIL. The IMU measures
// gravity and the Earth rate without error. fsw rules: no heap, no I/O, bounded loops.
#pragma once

#include <cmath>
#include <cstdint>

#include "default_flight_config.hpp"
#include "fsw/flight_app.hpp"
#include "fsw/frames.hpp"
#include "fsw/gnss.hpp"
#include "fsw/gps_orbit.hpp"
#include "fsw/strapdown.hpp"

namespace sdins_baremetal {

inline constexpr int kSatellites = 24;
inline constexpr int kGpsWeek = 2300;
inline constexpr double kTow0_s = 345600.0;   ///< GPS time of navigation time 0
inline constexpr double kImuDt_s = 0.001;     ///< 1 kHz IMU
inline constexpr double kMinElevation_rad = 10.0 * fsw::kDegToRad;

/// The receiver's position (35 N, 127 E, 100 m).
inline fsw::Vec3 receiver_llh() { return fsw::Vec3(35.0 * fsw::kDegToRad, 127.0 * fsw::kDegToRad, 100.0); }

/// Almanac element k (0 <= k < kSatellites), PRN k + 1.
inline fsw::GpsAlmanac almanac(int k) {
  const int plane = k / 4, slot = k % 4;
  fsw::GpsAlmanac a;
  a.prn = k + 1;
  a.health = 0;
  a.eccentricity = 0.0;
  a.toa_s = kTow0_s;
  a.week_mod_1024 = kGpsWeek % 1024;
  a.inclination_rad = 55.0 * fsw::kDegToRad;
  a.omega_dot_radps = 0.0;
  a.sqrt_a_sqrtm = 5153.7;
  a.omega0_rad = (60.0 * plane - 180.0) * fsw::kDegToRad;
  a.arg_perigee_rad = 0.0;
  a.mean_anomaly_rad = (90.0 * slot + 15.0 * plane - 180.0) * fsw::kDegToRad;
  return a;
}

/// IMU sample n (n >= 0) at t = (n + 1) dt: gravity up and the Earth rate in ENU body axes.
inline fsw::ImuSample imu_sample(std::uint32_t n) {
  const fsw::Vec3 llh = receiver_llh();
  fsw::ImuSample s;
  s.t_s = (static_cast<double>(n) + 1.0) * kImuDt_s;
  s.dt_s = kImuDt_s;
  s.dtheta_rad = fsw::omega_ie_n(llh.x()) * kImuDt_s;
  s.dv_mps = fsw::Vec3(0.0, 0.0, fsw::normal_gravity_mps2(llh.x(), llh.z())) * kImuDt_s;
  return s;
}

/// The raw epoch at navigation time t_s: every satellite above kMinElevation_rad (at most
/// kMaxGnssChannels), PRN order.
inline void raw_epoch(double t_s, fsw::GnssRawEpoch& e) {
  const fsw::Vec3 llh = receiver_llh();
  const fsw::Vec3 r_rx = fsw::ecef_from_llh(llh);
  const fsw::Mat3 C_e_n = fsw::C_n_e(llh.x(), llh.y()).transpose();
  e = fsw::GnssRawEpoch{};
  e.t_s = t_s;
  e.gps_week = kGpsWeek;
  e.gps_tow_s = kTow0_s + t_s;
  for (int k = 0; k < kSatellites && e.n_meas < fsw::kMaxGnssChannels; ++k) {
    const fsw::GpsAlmanac a = almanac(k);
    double pr_m = 2.0e7;
    fsw::GnssGeometry g;
    for (int it = 0; it < 4; ++it) {  // transmit time tow - rho / c and the range it gives
      fsw::Vec3 r_sat, v_sat;
      fsw::satellite_pv_ecef(a, kGpsWeek, e.gps_tow_s - pr_m / fsw::kSpeedOfLight_mps, r_sat, v_sat);
      g = fsw::gnss_geometry(r_sat, v_sat, r_rx, fsw::Vec3::Zero());
      pr_m = g.range_m;
    }
    const fsw::Vec3 los_enu = C_e_n * g.los_ecef;
    if (!(std::asin(los_enu.z()) >= kMinElevation_rad)) continue;
    fsw::GnssRawMeasurement& m = e.meas[static_cast<std::size_t>(e.n_meas++)];
    m.prn = static_cast<std::uint8_t>(a.prn);
    m.pseudorange_m = pr_m;
    m.pseudorange_rate_mps = g.range_rate_mps;
    m.cn0_dbhz = 45.0;
  }
}

/// The flight configuration of the image: config/default.toml's values (generated into
/// default_flight_config.hpp at build time by the host build, checked by BaremetalConfig.*), with
/// one departure for this input: stationary alignment (levelling + gyrocompassing) from the raw
/// fixes, since the synthetic receiver is at rest (the file's "track" needs motion).
inline fsw::FlightAppConfig flight_config() {
  fsw::FlightAppConfig c = default_flight_config();
  c.init_mode = fsw::InitMode::kStatic;
  return c;
}

}  // namespace sdins_baremetal
