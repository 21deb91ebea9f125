// Standard tropospheric and ionospheric delay models (see fsw/gnss_delays.hpp).
#include "fsw/gnss_delays.hpp"

#include <algorithm>
#include <cmath>

#include "fsw/frames.hpp"
#include "fsw/gnss.hpp"

namespace fsw {
namespace {

constexpr double kHalfPi = 0.5 * kPi;

bool valid_latitude(double lat_rad) { return std::isfinite(lat_rad) && std::abs(lat_rad) <= kHalfPi; }

}  // namespace

ZenithTropoDelay saastamoinen_zenith_delay(double lat_rad, double h_m, double rel_humidity) {
  if (!valid_latitude(lat_rad) || !std::isfinite(h_m) || !std::isfinite(rel_humidity)) return ZenithTropoDelay{};
  const double h = std::clamp(h_m, 0.0, kSaastamoinenMaxHeight_m);
  const double rh = std::clamp(rel_humidity, 0.0, 1.0);
  const double pressure_hpa = 1013.25 * std::pow(1.0 - 2.2557e-5 * h, 5.2568);
  const double temp_k = 15.0 - 6.5e-3 * h + 273.16;
  const double e_hpa = 6.108 * rh * std::exp((17.15 * temp_k - 4684.0) / (temp_k - 38.45));
  ZenithTropoDelay z;
  z.hydrostatic_m = 0.0022768 * pressure_hpa / (1.0 - 0.00266 * std::cos(2.0 * lat_rad) - 0.00028 * h / 1e3);
  z.wet_m = 0.002277 * (1255.0 / temp_k + 0.05) * e_hpa;
  return z;
}

double tropo_mapping(double elevation_rad, TropoMapping mapping) {
  if (!std::isfinite(elevation_rad) || elevation_rad <= 0.0) return 0.0;
  const double s = std::sin(std::min(elevation_rad, kHalfPi));
  switch (mapping) {
    case TropoMapping::kCosZenith: return 1.0 / s;
    case TropoMapping::kDo229: break;
  }
  return 1.001 / std::sqrt(0.002001 + s * s);
}

double saastamoinen_delay_m(double lat_rad, double h_m, double elevation_rad, double rel_humidity,
                            TropoMapping mapping) {
  const double m = tropo_mapping(elevation_rad, mapping);
  if (m == 0.0) return 0.0;
  return m * saastamoinen_zenith_delay(lat_rad, h_m, rel_humidity).total_m();
}

double klobuchar_delay_m(const KlobucharCoefficients& c, double gps_tow_s, double lat_rad, double lon_rad,
                         double azimuth_rad, double elevation_rad) {
  if (!std::isfinite(elevation_rad) || elevation_rad <= 0.0 || !valid_latitude(lat_rad) || !std::isfinite(lon_rad) ||
      !std::isfinite(azimuth_rad) || !std::isfinite(gps_tow_s)) {
    return 0.0;
  }
  for (int n = 0; n < 4; ++n) {
    if (!std::isfinite(c.alpha[static_cast<std::size_t>(n)]) || !std::isfinite(c.beta[static_cast<std::size_t>(n)]))
      return 0.0;
  }
  const double el_sc = std::min(elevation_rad, kHalfPi) / kPi;  // semicircles
  const double psi = 0.0137 / (el_sc + 0.11) - 0.022;
  const double phi_i = std::clamp(lat_rad / kPi + psi * std::cos(azimuth_rad), -0.416, 0.416);
  const double lambda_i = lon_rad / kPi + psi * std::sin(azimuth_rad) / std::cos(phi_i * kPi);
  const double phi_m = phi_i + 0.064 * std::cos((lambda_i - 1.617) * kPi);
  double t = 4.32e4 * lambda_i + gps_tow_s;
  t -= std::floor(t / 86400.0) * 86400.0;
  if (!(t >= 0.0 && t < 86400.0)) t = 0.0;  // rounding of a huge tow: any time of day is defined
  const double f = 1.0 + 16.0 * std::pow(0.53 - el_sc, 3.0);
  const double amp = std::max(c.alpha[0] + phi_m * (c.alpha[1] + phi_m * (c.alpha[2] + phi_m * c.alpha[3])), 0.0);
  const double per = std::max(c.beta[0] + phi_m * (c.beta[1] + phi_m * (c.beta[2] + phi_m * c.beta[3])), 72000.0);
  const double x = 2.0 * kPi * (t - 50400.0) / per;
  const double x2 = x * x;
  const double t_iono_s = f * (std::abs(x) < 1.57 ? 5e-9 + amp * (1.0 - x2 / 2.0 + x2 * x2 / 24.0) : 5e-9);
  const double delay_m = kSpeedOfLight_mps * t_iono_s;
  return std::isfinite(delay_m) ? delay_m : 0.0;  // absurd (finite) coefficients overflow
}

}  // namespace fsw
