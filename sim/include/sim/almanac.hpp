// The GPS constellation from a YUMA almanac: reader, satellite position/velocity/clock from the
// almanac's Keplerian elements (IS-GPS-200 20.3.3.5.2.1 with the almanac simplifications), and
// the satellites a receiver sees above an elevation mask.
//
// YUMA record (one per satellite, header line "******** Week 431 almanac for PRN-01 ********"):
//   ID, Health, Eccentricity, Time of Applicability(s), Orbital Inclination(rad) (the full
//   inclination, not an offset from 0.3 pi), Rate of Right Ascen(r/s), SQRT(A)  (m 1/2),
//   Right Ascen at Week(rad), Argument of Perigee(rad), Mean Anom(rad), Af0(s), Af1(s/s), week
//   (GPS week modulo 1024).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "fsw/frames.hpp"

namespace sim {

/// IS-GPS-200 constants for the orbit computation (not the WGS-84 GM of frames.hpp).
inline constexpr double kGpsGM_m3ps2 = 3.986005e14;
inline constexpr double kGpsOmegaE_radps = 7.2921151467e-5;
inline constexpr double kSecondsPerWeek = 604800.0;

/// One satellite's almanac elements, units as in the YUMA file.
struct AlmanacEntry {
  int prn = 0;
  int health = 0;                    ///< 0: healthy
  double eccentricity = 0.0;
  double toa_s = 0.0;                ///< time of applicability, seconds of the almanac week
  double inclination_rad = 0.0;      ///< full inclination i0
  double omega_dot_radps = 0.0;      ///< rate of right ascension
  double sqrt_a_sqrtm = 0.0;         ///< square root of the semi-major axis [m^(1/2)]
  double omega0_rad = 0.0;           ///< longitude of the ascending node at the week's start
  double arg_perigee_rad = 0.0;      ///< argument of perigee omega
  double mean_anomaly_rad = 0.0;     ///< M0 at toa
  double af0_s = 0.0;                ///< clock bias
  double af1_sps = 0.0;              ///< clock drift
  int week_mod_1024 = 0;             ///< almanac reference week, modulo 1024
};

/// Result of parsing: either the satellites (sorted by PRN) or "<source>:<line>: <reason>".
struct AlmanacParseResult {
  std::optional<std::vector<AlmanacEntry>> almanac;
  std::string error;
  bool ok() const { return almanac.has_value(); }
};

/// Never throw; reject unknown/missing/duplicate fields, non-numeric or non-finite values,
/// eccentricity outside [0, 1), sqrt(A) <= 0, PRN outside 1..32, duplicate PRN, no records.
AlmanacParseResult parse_yuma_text(const std::string& text, const std::string& source);
AlmanacParseResult parse_yuma_file(const std::string& path);

/// Full GPS week for a week modulo 1024: the rollover candidate nearest reference_full_week.
int full_week(int week_mod_1024, int reference_full_week);

/// Time from the almanac's applicability [s] at (full_gps_week, tow_s); the almanac's full week
/// is resolved with full_week(entry.week_mod_1024, full_gps_week), so week crossovers are exact.
double time_from_applicability_s(const AlmanacEntry& sat, int full_gps_week, double tow_s);

/// Satellite ECEF position and velocity (velocity analytic: derivative of the same equations,
/// including the Earth-rotation term of the node longitude).
void satellite_pv_ecef(const AlmanacEntry& sat, int full_gps_week, double tow_s, fsw::Vec3& r_ecef_m,
                       fsw::Vec3& v_ecef_mps);

/// Satellite clock bias af0 + af1 * tk [s].
double satellite_clock_bias_s(const AlmanacEntry& sat, int full_gps_week, double tow_s);

struct LookAngles {
  double elevation_rad = 0.0;  ///< above the local (ellipsoid-normal) horizon
  double azimuth_rad = 0.0;    ///< from North towards East, [0, 2 pi)
};

/// Elevation/azimuth of an ECEF point seen from a receiver at (lat, lon, h) (ENU line of sight).
LookAngles look_angles(const fsw::Vec3& receiver_llh, const fsw::Vec3& r_target_ecef_m);

struct Visible {
  int prn = 0;
  fsw::Vec3 r_ecef_m = fsw::Vec3::Zero();
  fsw::Vec3 v_ecef_mps = fsw::Vec3::Zero();
  double elevation_rad = 0.0;
  double azimuth_rad = 0.0;
};

/// Healthy satellites (health == 0) with elevation >= mask_rad, in almanac (PRN) order.
/// out is cleared first.
void visible_satellites(const std::vector<AlmanacEntry>& almanac, int full_gps_week, double tow_s,
                        const fsw::Vec3& receiver_llh, double mask_rad, std::vector<Visible>& out);

}  // namespace sim
