// GPS broadcast ephemeris (IS-GPS-200 20.3.3.4.3, Table 20-IV, with the harmonic corrections,
// delta-n and IDOT) and its fit to the flight software's almanac orbit model.
//
// The flight software computes satellite positions from almanac elements (fsw/gps_orbit.hpp:
// Keplerian orbit, no harmonic corrections, a linear clock af0 + af1 tk). Recorded data come with
// broadcast ephemeris instead. Over a recording of minutes to an hour, an almanac whose elements
// are fitted by least squares to the ephemeris positions (and whose af0/af1 are fitted to the
// ephemeris clock including the relativistic term and the L1 group delay TGD) reproduces the
// ephemeris to centimetres, far below the pseudorange noise. fit_almanac() does that fit and
// reports its worst position, clock and velocity error over the window, so an importer can decide
// whether the fitted almanac is exact enough to give the flight software. Host code (tools/).
#pragma once

#include <string>

#include "fsw/frames.hpp"
#include "fsw/gps_orbit.hpp"

namespace tools {

/// One broadcast ephemeris (subframes 1-3) of a GPS satellite, IS-GPS-200 units (angles in rad).
struct GpsEphemeris {
  int prn = 0;
  int week = 0;          ///< full GPS week of toe
  double toe_s = 0.0;    ///< ephemeris reference time, seconds of `week`
  double toc_s = 0.0;    ///< clock reference time, seconds of `week` (may lie outside [0, fsw::kSecondsPerWeek) at a week boundary)
  double af0_s = 0.0, af1_sps = 0.0, af2_sps2 = 0.0;
  double crs_m = 0.0, crc_m = 0.0;
  double cus_rad = 0.0, cuc_rad = 0.0, cis_rad = 0.0, cic_rad = 0.0;
  double delta_n_radps = 0.0;
  double m0_rad = 0.0;
  double eccentricity = 0.0;
  double sqrt_a_sqrtm = 0.0;
  double omega0_rad = 0.0;
  double i0_rad = 0.0;
  double arg_perigee_rad = 0.0;
  double omega_dot_radps = 0.0;
  double idot_radps = 0.0;
  double tgd_s = 0.0;    ///< L1-L2 group delay; the L1 C/A user subtracts it from the clock
  int health = 0;        ///< 0: healthy
  int iode = 0;
};

/// Plausibility of decoded ephemeris values (PRN, sqrt(A), eccentricity, finite values).
bool ephemeris_valid(const GpsEphemeris& eph);

/// Seconds from the ephemeris' toe to (week, tow_s).
double ephemeris_tk_s(const GpsEphemeris& eph, int week, double tow_s);

/// Satellite ECEF position at GPS time (week, tow_s) and the satellite clock offset for an L1 C/A
/// user [s]: af0 + af1 dt + af2 dt^2 + relativistic term F e sqrt(A) sin E - TGD.
void ephemeris_position_clock(const GpsEphemeris& eph, int week, double tow_s, fsw::Vec3& r_ecef_m, double& clock_s);

/// Result of fitting almanac elements to an ephemeris over a time window.
struct AlmanacFit {
  fsw::GpsAlmanac almanac{};    ///< toa = window centre (whole second), week of the toa
  bool converged = false;
  int iterations = 0;
  int samples = 0;              ///< epochs compared (over the window, every few seconds)
  double max_pos_err_m = 0.0;   ///< worst |r_almanac - r_ephemeris| over the window
  double rms_pos_err_m = 0.0;
  double max_clock_err_m = 0.0; ///< worst c |clock_almanac - clock_ephemeris|
  double max_vel_err_mps = 0.0; ///< worst |v_almanac - v_ephemeris| (ephemeris velocity by central differences)
  /// Worst pseudorange error the fitted almanac can cause: max_pos_err_m + max_clock_err_m.
  double max_range_err_m() const { return max_pos_err_m + max_clock_err_m; }
};

/// Fits almanac elements (e, i0, Omega-dot, sqrt(A), Omega0, omega, M0 by Gauss-Newton on the ECEF
/// positions; af0, af1 by linear least squares on the clock) to the ephemeris over
/// [start, start + span_s] of GPS time, evaluated with fsw::satellite_pv_ecef /
/// fsw::satellite_clock_bias_s, i.e. exactly as the flight software will use them.
AlmanacFit fit_almanac(const GpsEphemeris& eph, int start_week, double start_tow_s, double span_s);

}  // namespace tools
