// Standard atmospheric delay models of the GPS signal, shared by the simulator (truth: the
// tropospheric_delay / ionospheric_delay effects scale them) and the EKF's diagnosis blocks
// (kTropoScale / kIonoScale: H_pr is the model delay), so that truth and estimator use one
// definition. Scale 1 means the full model delay.
//
// TROPOSPHERE  Saastamoinen zenith delay with the standard atmosphere, as RTKLIB's tropmodel()
// (rtkcmn.c) computes it:
//   P = 1013.25 hPa (1 - 2.2557e-5 h)^5.2568,  T = 15 C - 6.5e-3 h  (+273.16 K),
//   e = 6.108 rh exp((17.15 T - 4684) / (T - 38.45)) hPa   (water-vapour pressure, rh in [0, 1]),
//   zenith hydrostatic  Zh = 0.0022768 P / (1 - 0.00266 cos(2 lat) - 0.00028 h[km]),
//   zenith wet          Zw = 0.002277 (1255 / T + 0.05) e,
//   slant delay         m(el) (Zh + Zw)      [m].
// Zenith at sea level, rh 0.7: 2.434 m at the equator, 2.427 m at 45 deg.
// Mapping m(el): RTKLIB uses 1 / cos(z) = 1 / sin(el) (TropoMapping::kCosZenith), which grows
// without bound towards the horizon (11.5 at 5 deg, 57 at 1 deg). The default is the RTCA
// DO-229 mapping (TropoMapping::kDo229) m = 1.001 / sqrt(0.002001 + sin^2(el)): equal to 1 / sin
// within 0.3 % at 30 deg and 3 % at 10 deg, 22.4 at 0 deg, and closer to the Niell hydrostatic
// mapping below 15 deg (5 deg: Niell about 10.2, DO-229 10.22, 1 / sin 11.47).
// Height: RTKLIB returns 0 outside [-100 m, 10 km]; here a negative height uses the sea-level
// atmosphere (as RTKLIB does on [-100, 0)), and above 10 km the same standard-atmosphere formula
// continues (0.60 m zenith at 10 km, 0.10 m at 20 km, 0.006 m at 30 km, no step at 10 km for a
// vehicle that climbs through it) up to kSaastamoinenMaxHeight_m, above which the 30 km value is
// used (the formula's temperature reaches the singularity of e at 38 km).
//
// IONOSPHERE  Klobuchar broadcast model, IS-GPS-200 20.3.3.5.2.5 (all angles in semicircles):
//   E elevation, A azimuth, phi_u / lambda_u user geodetic latitude / longitude,
//   psi     = 0.0137 / (E + 0.11) - 0.022                         Earth-centred angle
//   phi_i   = phi_u + psi cos(A), limited to [-0.416, 0.416]     ionospheric pierce point
//   lambda_i = lambda_u + psi sin(A) / cos(phi_i)
//   phi_m   = phi_i + 0.064 cos(lambda_i - 1.617)                 geomagnetic latitude
//   t       = 4.32e4 lambda_i + GPS time, reduced to [0, 86400) s local time
//   F       = 1 + 16 (0.53 - E)^3                                 obliquity factor
//   AMP     = sum alpha_n phi_m^n (0 if negative), PER = sum beta_n phi_m^n (at least 72000 s)
//   x       = 2 pi (t - 50400) / PER
//   T_iono  = F (5e-9 + AMP (1 - x^2/2 + x^4/24)) s if |x| < 1.57, else F 5e-9 s
// returned as the L1 delay c T_iono [m]: at least the night-time floor c 5 ns F = 1.499 m F.
// Coefficients: the receiver decodes them from subframe 4 page 18. The simulator and the EKF both
// use kKlobucharDefault (the flight software does not receive the broadcast values yet), so the
// EKF's iono scale estimates the ratio of the true delay to this model.
//
// Both functions are total: no heap, no exceptions, no I/O, and every input gives a defined
// finite value. Elevation <= 0, a non-finite input, a latitude outside [-pi/2, pi/2] or a
// non-finite coefficient give 0 (no delay); an elevation above pi/2 is taken as pi/2; a relative
// humidity outside [0, 1] is clamped. Longitude, azimuth and GPS time may have any finite value
// (periodic; the time of week need not be reduced).
#pragma once

#include <array>
#include <cstdint>

namespace fsw {

/// Mapping of the zenith tropospheric delay to elevation el.
enum class TropoMapping : std::uint8_t {
  kDo229 = 0,  ///< 1.001 / sqrt(0.002001 + sin^2 el) (RTCA DO-229), bounded at the horizon
  kCosZenith,  ///< 1 / cos(z) = 1 / sin(el), RTKLIB tropmodel()
};

inline constexpr double kSaastamoinenDefaultHumidity = 0.7;
inline constexpr double kSaastamoinenMaxHeight_m = 30000.0;

/// Zenith tropospheric delay split into its hydrostatic (dry) and wet parts [m].
struct ZenithTropoDelay {
  double hydrostatic_m = 0.0;
  double wet_m = 0.0;
  double total_m() const { return hydrostatic_m + wet_m; }
};

/// Saastamoinen zenith delay with the standard atmosphere at geodetic latitude lat_rad and
/// ellipsoidal height h_m; 0 for a non-finite input or |lat| > pi/2.
ZenithTropoDelay saastamoinen_zenith_delay(double lat_rad, double h_m,
                                           double rel_humidity = kSaastamoinenDefaultHumidity);

/// Tropospheric mapping factor at elevation el (0 for el <= 0 or non-finite, el > pi/2 as pi/2).
double tropo_mapping(double elevation_rad, TropoMapping mapping = TropoMapping::kDo229);

/// Slant tropospheric delay [m]: tropo_mapping(el) * saastamoinen_zenith_delay(lat, h).total_m().
/// With TropoMapping::kCosZenith and h in [0, 10 km] it is RTKLIB's tropmodel().
double saastamoinen_delay_m(double lat_rad, double h_m, double elevation_rad,
                            double rel_humidity = kSaastamoinenDefaultHumidity,
                            TropoMapping mapping = TropoMapping::kDo229);

/// Broadcast ionosphere parameters: alpha [s, s/semicircle, s/semicircle^2, s/semicircle^3],
/// beta [s, s/semicircle, s/semicircle^2, s/semicircle^3].
struct KlobucharCoefficients {
  std::array<double, 4> alpha{};
  std::array<double, 4> beta{};
};

/// Default coefficients: RTKLIB's ion_default (rtkcmn.c, ionmodel()), the GPS broadcast values of
/// 2004/1/1.
inline constexpr KlobucharCoefficients kKlobucharDefault{
    {0.1118e-07, -0.7451e-08, -0.5961e-07, 0.1192e-06},
    {0.1167e+06, -0.2294e+06, -0.1311e+06, 0.1049e+07},
};

/// Klobuchar L1 ionospheric delay [m] for a user at (lat_rad, lon_rad), a satellite at
/// azimuth_rad (from North towards East) / elevation_rad, at GPS time of week gps_tow_s.
double klobuchar_delay_m(const KlobucharCoefficients& coefficients, double gps_tow_s, double lat_rad,
                         double lon_rad, double azimuth_rad, double elevation_rad);

}  // namespace fsw
