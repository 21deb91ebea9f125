// GNSS measurement input of the flight software and the one pseudorange / pseudorange-rate
// geometry shared by the simulator (truth measurements) and the EKF (predicted measurements).
//
// An epoch carries, per tracked satellite, the satellite's ECEF position and velocity at the
// signal's transmit time (expressed in the ECEF frame of the transmit time, as a receiver or the
// HAL computes them from the broadcast ephemeris) and the pseudorange / pseudorange rate already
// corrected for the satellite clock. The geometry accounts for the Earth's rotation during the
// signal's flight (Sagnac): the satellite vector is rotated into the ECEF frame of the receive
// time, which makes the computation equal to the inertial-frame one.
//
//   pseudorange      rho  = |R3(we*tau) r_sat - r_rx| + c*dt_rx + errors
//   pseudorange rate rhod = e . (v_sat_i - v_rx_i) / (1 + e . v_sat_i / c) + c*ddt_rx + errors
// with e the unit vector receiver -> satellite, tau = |...|/c the signal flight time and v_*_i the
// inertial velocities (v + we x r) in the receive-time ECEF frame.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

#include "fsw/frames.hpp"
#include "fsw/gnss_delays.hpp"

namespace fsw {

inline constexpr double kSpeedOfLight_mps = 299792458.0;
/// Earth rotation rate of the GPS interface specification (IS-GPS-200), used for Sagnac.
inline constexpr double kGpsEarthRate_radps = 7.2921151467e-5;
inline constexpr int kMaxGnssChannels = 16;

/// Receiver-clock process noise of the two-state clock model (bias, drift) from the oscillator's
/// Allan-variance coefficients: the one formula the simulated receiver draws with and the filter
/// configurations assume. Bias PSD h0 / 2 c^2 [m^2/s] (h0: white frequency [s]); drift PSD
/// 2 pi^2 h_-2 c^2 [m^2/s^3] (h_-2: random-walk frequency [1/s]).
inline double clock_bias_psd_m2ps(double h0_s) { return h0_s / 2.0 * (kSpeedOfLight_mps * kSpeedOfLight_mps); }
inline double clock_drift_psd_m2ps3(double h_minus2_per_s) {
  return 2.0 * kPi * kPi * h_minus2_per_s * (kSpeedOfLight_mps * kSpeedOfLight_mps);
}

struct GnssObservation {
  std::uint8_t prn = 0;
  Vec3 sat_pos_ecef_m = Vec3::Zero();   ///< at transmit time, transmit-time ECEF
  Vec3 sat_vel_ecef_mps = Vec3::Zero(); ///< at transmit time, relative to ECEF
  double pseudorange_m = 0.0;           ///< satellite clock removed
  double pseudorange_rate_mps = 0.0;    ///< satellite clock drift removed
  double elevation_rad = 0.0;           ///< as computed by the source (informational)
};

/// One measurement epoch: every tracked satellite at one receive time.
struct GnssEpoch {
  double t_s = 0.0;      ///< receive time on the navigation time scale of the IMU time tags [s]
  int gps_week = 0;      ///< receive time on the GPS time scale: full week number ...
  double gps_tow_s = 0.0;  ///< ... and seconds of the week
  int n_obs = 0;         ///< valid entries in obs, [0, kMaxGnssChannels]
  std::array<GnssObservation, kMaxGnssChannels> obs{};
};

/// One GNSS position/velocity solution (of the antenna), the input of the loosely coupled update
/// (Ekf::update_pvt). Recorded data sets give these instead of raw pseudoranges (RTKLIB .pos).
struct GnssPvtMeasurement {
  double t_s = 0.0;                    ///< time of the solution on the navigation time scale [s]
  int gps_week = 0;                    ///< GPS time of the solution (carried, not used in flight): week ...
  double gps_tow_s = 0.0;              ///< ... and seconds of the week
  Vec3 llh = Vec3::Zero();             ///< antenna: lat [rad], lon [rad], ellipsoidal h [m]
  Vec3 vel_enu_mps = Vec3::Zero();     ///< antenna velocity relative to the Earth, ENU
  Vec3 pos_sigma_enu_m = Vec3::Zero(); ///< the solver's 1-sigma, E N U [m] (> 0)
  Vec3 vel_sigma_enu_mps = Vec3::Zero();
  bool has_velocity = false;           ///< false: position only
  int quality = 0;                     ///< RTKLIB Q: 1 fix, 2 float, 3 SBAS, 4 DGPS, 5 single, 6 PPP
  int n_sat = 0;
};

// The atmospheric delay models (Saastamoinen troposphere, Klobuchar ionosphere) that the
// simulator's delay effects and the EKF's diagnosis blocks share are in fsw/gnss_delays.hpp.

/// Predicted range, range rate and line of sight of one satellite from a receiver.
struct GnssGeometry {
  double range_m = 0.0;          ///< geometric range, Sagnac included
  double range_rate_mps = 0.0;   ///< geometric range rate, Sagnac included
  Vec3 los_ecef = Vec3::Zero();  ///< unit vector receiver -> satellite, ECEF
};

/// Geometry of a satellite (position/velocity at transmit time) seen by a receiver at
/// r_rx_ecef_m with velocity v_rx_ecef_mps (relative to ECEF) at the receive time.
inline GnssGeometry gnss_geometry(const Vec3& sat_pos_ecef_m, const Vec3& sat_vel_ecef_mps, const Vec3& r_rx_ecef_m,
                                  const Vec3& v_rx_ecef_mps) {
  const Vec3 we(0.0, 0.0, kGpsEarthRate_radps);
  // Two fixed-point passes of the flight time are exact to far below a millimetre.
  double tau = (sat_pos_ecef_m - r_rx_ecef_m).norm() / kSpeedOfLight_mps;
  Vec3 r_s = sat_pos_ecef_m;
  Mat3 R = Mat3::Identity();
  for (int i = 0; i < 2; ++i) {
    const double a = kGpsEarthRate_radps * tau;
    const double ca = std::cos(a), sa = std::sin(a);
    R << ca, sa, 0.0, -sa, ca, 0.0, 0.0, 0.0, 1.0;  // R3(a): transmit-time ECEF -> receive-time ECEF
    r_s = R * sat_pos_ecef_m;
    tau = (r_s - r_rx_ecef_m).norm() / kSpeedOfLight_mps;
  }
  GnssGeometry g;
  const Vec3 d = r_s - r_rx_ecef_m;
  g.range_m = d.norm();
  g.los_ecef = d / g.range_m;
  const Vec3 v_s_i = R * (sat_vel_ecef_mps + we.cross(sat_pos_ecef_m));
  const Vec3 v_r_i = v_rx_ecef_mps + we.cross(r_rx_ecef_m);
  // Exact derivative of |r_s(t - tau(t)) - r_rx(t)|: the light-time factor 1 / (1 + e.v_s / c).
  g.range_rate_mps = g.los_ecef.dot(v_s_i - v_r_i) / (1.0 + g.los_ecef.dot(v_s_i) / kSpeedOfLight_mps);
  return g;
}

}  // namespace fsw
