// The GPS constellation from a YUMA almanac: the file reader and the satellites a receiver sees
// above an elevation mask. The orbit computation from the Keplerian elements is flight code and
// lives in fsw/gps_orbit.hpp.
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
#include "fsw/gps_orbit.hpp"

namespace sim {

/// The orbit computation is flight code (fsw/gps_orbit.hpp); sim uses the same functions.
using AlmanacEntry = fsw::GpsAlmanac;
using fsw::kGpsGM_m3ps2;
using fsw::kGpsOmegaE_radps;
using fsw::kSecondsPerWeek;
using fsw::full_week;
using fsw::time_from_applicability_s;
using fsw::satellite_pv_ecef;
using fsw::satellite_clock_bias_s;

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
