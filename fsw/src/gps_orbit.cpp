// GPS almanac orbits and the raw-measurement -> GnssEpoch conversion (see fsw/gps_orbit.hpp).
#include "fsw/gps_orbit.hpp"

#include <cmath>

namespace fsw {
namespace {

/// Semi-major axes of GPS orbits are about 26 560 km; anything far outside is a corrupt element.
constexpr double kMinSqrtA_sqrtm = 4000.0;   // a = 16 000 km
constexpr double kMaxSqrtA_sqrtm = 6000.0;   // a = 36 000 km
constexpr double kMaxAngle_rad = 8.0;        // |angle| <= 2.5 pi: YUMA angles are within [-pi, pi]
constexpr double kMaxClock_s = 1e-2;
constexpr double kMaxClockDrift_sps = 1e-6;
constexpr double kMaxPseudorange_m = 1.0e8;  // GPS pseudoranges are 2e7..2.6e7 m (+ clock)
constexpr double kMinPseudorange_m = -1.0e8;
constexpr double kMaxRangeRate_mps = 1.0e5;
constexpr int kKeplerIterations = 50;

bool finite_and_within(double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; }

}  // namespace

const char* almanac_invalid_field(const GpsAlmanac& sat) {
  if (!(sat.prn >= 1 && sat.prn <= kMaxGpsPrn)) return "PRN";
  if (!finite_and_within(sat.eccentricity, 0.0, 0.999)) return "eccentricity";
  if (!finite_and_within(sat.toa_s, 0.0, kSecondsPerWeek)) return "time of applicability";
  if (!finite_and_within(sat.inclination_rad, -kMaxAngle_rad, kMaxAngle_rad)) return "inclination";
  if (!finite_and_within(sat.omega_dot_radps, -1e-6, 1e-6)) return "rate of right ascension";
  if (!finite_and_within(sat.sqrt_a_sqrtm, kMinSqrtA_sqrtm, kMaxSqrtA_sqrtm)) return "sqrt(A)";
  if (!finite_and_within(sat.omega0_rad, -kMaxAngle_rad, kMaxAngle_rad)) return "right ascension at week";
  if (!finite_and_within(sat.arg_perigee_rad, -kMaxAngle_rad, kMaxAngle_rad)) return "argument of perigee";
  if (!finite_and_within(sat.mean_anomaly_rad, -kMaxAngle_rad, kMaxAngle_rad)) return "mean anomaly";
  if (!finite_and_within(sat.af0_s, -kMaxClock_s, kMaxClock_s)) return "af0 (clock bias)";
  if (!finite_and_within(sat.af1_sps, -kMaxClockDrift_sps, kMaxClockDrift_sps)) return "af1 (clock drift)";
  if (!(sat.week_mod_1024 >= 0 && sat.week_mod_1024 < 1024 * 64)) return "week";
  return nullptr;
}

bool almanac_valid(const GpsAlmanac& sat) { return almanac_invalid_field(sat) == nullptr; }

GpsTime gps_time(int week, double tow_s) {
  const double weeks = std::floor(tow_s / kSecondsPerWeek);
  GpsTime t{week + static_cast<int>(weeks), tow_s - weeks * kSecondsPerWeek};
  // The arithmetic rounds at the boundary: a negative time so small that the quotient underflows
  // to -0 stays below 0, and a time just before a week's start plus one week rounds to
  // kSecondsPerWeek (-1e-12 s + 604800 s is 604800.0), which is the next week's start.
  if (t.tow_s < 0.0) {
    t.tow_s += kSecondsPerWeek;
    --t.week;
  }
  if (t.tow_s >= kSecondsPerWeek) {
    t.tow_s -= kSecondsPerWeek;
    ++t.week;
  }
  return t;
}

int full_week(int week_mod_1024, int reference_full_week) {
  const int w = ((week_mod_1024 % 1024) + 1024) % 1024;
  const long k = std::lround(static_cast<double>(reference_full_week - w) / 1024.0);
  return w + 1024 * static_cast<int>(k);
}

double time_from_applicability_s(const GpsAlmanac& sat, int full_gps_week, double tow_s) {
  const int alm_week = full_week(sat.week_mod_1024, full_gps_week);
  return static_cast<double>(full_gps_week - alm_week) * kSecondsPerWeek + (tow_s - sat.toa_s);
}

double eccentric_anomaly_rad(double mean_anomaly_rad, double eccentricity) {
  // Kepler's equation M = E - e sin E by Newton iteration (bounded).
  double ecc_anom = mean_anomaly_rad;
  for (int it = 0; it < kKeplerIterations; ++it) {
    const double d = (ecc_anom - eccentricity * std::sin(ecc_anom) - mean_anomaly_rad) /
                     (1.0 - eccentricity * std::cos(ecc_anom));
    ecc_anom -= d;
    if (std::abs(d) < 1e-13) break;
  }
  return ecc_anom;
}

void satellite_pv_ecef(const GpsAlmanac& sat, int full_gps_week, double tow_s, Vec3& r_ecef_m, Vec3& v_ecef_mps) {
  const double tk = time_from_applicability_s(sat, full_gps_week, tow_s);
  const double a = sat.sqrt_a_sqrtm * sat.sqrt_a_sqrtm;
  const double e = sat.eccentricity;
  const double n = std::sqrt(kGpsGM_m3ps2 / (a * a * a));
  const double m = sat.mean_anomaly_rad + n * tk;

  const double ecc_anom = eccentric_anomaly_rad(m, e);
  const double sin_e = std::sin(ecc_anom), cos_e = std::cos(ecc_anom);
  const double one_m_ecos = 1.0 - e * cos_e;
  const double root = std::sqrt(1.0 - e * e);
  const double nu = std::atan2(root * sin_e, cos_e - e);
  const double u = nu + sat.arg_perigee_rad;  // argument of latitude (no corrections)
  const double r = a * one_m_ecos;
  const double inc = sat.inclination_rad;
  const double omega_rate = sat.omega_dot_radps - kGpsOmegaE_radps;
  const double node = sat.omega0_rad + omega_rate * tk - kGpsOmegaE_radps * sat.toa_s;

  const double cu = std::cos(u), su = std::sin(u);
  const double ci = std::cos(inc), si = std::sin(inc);
  const double cn = std::cos(node), sn = std::sin(node);
  const double xp = r * cu, yp = r * su;  // in the orbital plane
  r_ecef_m = Vec3(xp * cn - yp * ci * sn, xp * sn + yp * ci * cn, yp * si);

  // Time derivatives of the same equations.
  const double e_dot = n / one_m_ecos;
  const double u_dot = e_dot * root / one_m_ecos;  // d(nu)/dt
  const double r_dot = a * e * sin_e * e_dot;
  const double xp_dot = r_dot * cu - yp * u_dot;
  const double yp_dot = r_dot * su + xp * u_dot;
  v_ecef_mps = Vec3(xp_dot * cn - yp_dot * ci * sn - r_ecef_m.y() * omega_rate,
                    xp_dot * sn + yp_dot * ci * cn + r_ecef_m.x() * omega_rate, yp_dot * si);
}

double satellite_clock_bias_s(const GpsAlmanac& sat, int full_gps_week, double tow_s) {
  return sat.af0_s + sat.af1_sps * time_from_applicability_s(sat, full_gps_week, tow_s);
}

Status GpsAlmanacTable::set(const GpsAlmanac& sat) {
  if (!almanac_valid(sat)) return Status::kBadInput;
  const auto slot = static_cast<std::size_t>(sat.prn - 1);
  if (!have_[slot]) ++count_;
  have_[slot] = true;
  sats_[slot] = sat;
  return Status::kOk;
}

const GpsAlmanac* GpsAlmanacTable::find(int prn) const {
  if (prn < 1 || prn > kMaxGpsPrn) return nullptr;
  const auto slot = static_cast<std::size_t>(prn - 1);
  return have_[slot] ? &sats_[slot] : nullptr;
}

void GpsAlmanacTable::clear() {
  have_.fill(false);
  count_ = 0;
}

Status gnss_epoch_from_raw(const GnssRawEpoch& raw, const GpsAlmanacTable& almanac, const Vec3* rx_llh_hint,
                           GnssEpoch& out, GnssConversionStats& stats) {
  out = GnssEpoch{};
  if (!std::isfinite(raw.t_s) || !std::isfinite(raw.gps_tow_s) || raw.gps_tow_s < 0.0 ||
      raw.gps_tow_s >= kSecondsPerWeek || raw.gps_week < 0 || raw.n_meas < 0 || raw.n_meas > kMaxGnssChannels) {
    return Status::kBadInput;
  }
  out.t_s = raw.t_s;
  out.gps_week = raw.gps_week;
  out.gps_tow_s = raw.gps_tow_s;

  Vec3 r_rx = Vec3::Zero();
  Mat3 C_e_n = Mat3::Identity();
  const bool have_hint = rx_llh_hint != nullptr && rx_llh_hint->allFinite();
  if (have_hint) {
    r_rx = ecef_from_llh(*rx_llh_hint);
    C_e_n = C_n_e(rx_llh_hint->x(), rx_llh_hint->y()).transpose();
  }

  std::array<bool, kMaxGpsPrn> seen{};
  int n = 0;
  for (int i = 0; i < raw.n_meas; ++i) {
    const GnssRawMeasurement& m = raw.meas[static_cast<std::size_t>(i)];
    if (m.prn < 1 || m.prn > kMaxGpsPrn || !finite_and_within(m.pseudorange_m, kMinPseudorange_m, kMaxPseudorange_m) ||
        !finite_and_within(m.pseudorange_rate_mps, -kMaxRangeRate_mps, kMaxRangeRate_mps) ||
        !std::isfinite(m.cn0_dbhz)) {
      ++stats.invalid;
      continue;
    }
    const auto slot = static_cast<std::size_t>(m.prn - 1);
    if (seen[slot]) {
      ++stats.duplicate_prn;
      continue;
    }
    seen[slot] = true;
    const GpsAlmanac* sat = almanac.find(m.prn);
    if (sat == nullptr) {
      ++stats.no_almanac;
      continue;
    }
    if (sat->health != 0) {
      ++stats.unhealthy;
      continue;
    }
    // Transmit time on the GPS time scale: the pseudorange includes the receiver clock bias, which
    // the receiver's own time tag shares, so tow - rho / c is the transmit time to the extent the
    // time tag is on the receiver clock (and within c * clock error / 3.9 km/s otherwise: < 1 mm).
    const GpsTime tx = gps_time(raw.gps_week, raw.gps_tow_s - m.pseudorange_m / kSpeedOfLight_mps);
    const int week_tx = tx.week;
    double tow_tx = tx.tow_s;
    const double dt_sat_s = satellite_clock_bias_s(*sat, week_tx, tow_tx);
    tow_tx -= dt_sat_s;
    GnssObservation& o = out.obs[static_cast<std::size_t>(n)];
    o.prn = m.prn;
    satellite_pv_ecef(*sat, week_tx, tow_tx, o.sat_pos_ecef_m, o.sat_vel_ecef_mps);
    o.pseudorange_m = m.pseudorange_m + kSpeedOfLight_mps * dt_sat_s;
    o.pseudorange_rate_mps = m.pseudorange_rate_mps + kSpeedOfLight_mps * sat->af1_sps;
    if (have_hint) {
      const Vec3 los_enu = C_e_n * (o.sat_pos_ecef_m - r_rx);
      o.elevation_rad = std::atan2(los_enu.z(), std::hypot(los_enu.x(), los_enu.y()));
    }
    ++n;
  }
  out.n_obs = n;
  return Status::kOk;
}

}  // namespace fsw
