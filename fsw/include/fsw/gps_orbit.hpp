// GPS satellite orbits from almanac elements (IS-GPS-200 20.3.3.5.2.1, Table 20-IV with the
// almanac simplifications: no harmonic corrections, no inclination rate, i0 given in full), and
// the receiver-side conversion of raw measurements (PRN, pseudorange, pseudorange rate) into the
// GnssEpoch the EKF uses.
//
// This is flight code: the almanac arrives over the bus (or from a log), is kept in a fixed
// 32-slot table, and every raw epoch is turned into satellite positions/velocities at the
// signal's transmit time here, the same way in SIL, HIL and replay. The YUMA text reader lives in
// sim/almanac.hpp (host code).
#pragma once

#include <array>
#include <cstdint>

#include "fsw/frames.hpp"
#include "fsw/gnss.hpp"
#include "fsw/status.hpp"

namespace fsw {

/// IS-GPS-200 constants for the orbit computation (not the WGS-84 GM of frames.hpp).
inline constexpr double kGpsGM_m3ps2 = 3.986005e14;
inline constexpr double kGpsOmegaE_radps = kGpsEarthRate_radps;
inline constexpr double kSecondsPerWeek = 604800.0;
inline constexpr int kMaxGpsPrn = 32;

/// One satellite's almanac elements, units as in a YUMA file.
struct GpsAlmanac {
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

/// Plausibility of received elements (PRN 1..32, 0 <= e < 1, sqrt(A) in the GPS range, finite
/// angles and times, toa within a week).
bool almanac_valid(const GpsAlmanac& sat);
/// The first element almanac_valid() refuses ("sqrt(A)", "af0 (clock bias)", ...), nullptr when
/// valid. The one validation of almanac elements: the flight software's inputs (CAN, LCM) and the
/// simulator's almanac reader (sim::parse_yuma_text) both use it (docs/faults.md).
const char* almanac_invalid_field(const GpsAlmanac& sat);

/// A time on the GPS time scale: the full week and the seconds of that week.
struct GpsTime {
  int week = 0;
  double tow_s = 0.0;  ///< in [0, kSecondsPerWeek)
};

/// (week, tow_s) with the seconds of week brought into [0, kSecondsPerWeek) and the whole weeks
/// carried into the week: a time before the week's start (a transmit time tow - rho / c in the
/// first 0.09 s of a week, a receiver clock running behind) or any number of weeks past its end.
/// The one week wrap of the project: the flight software's transmit times and the simulator's
/// receive times, receiver time tags and transmit times all use it. tow_s must be finite.
GpsTime gps_time(int week, double tow_s);

/// Full GPS week for a week modulo 1024: the rollover candidate nearest reference_full_week.
int full_week(int week_mod_1024, int reference_full_week);

/// Time from the almanac's applicability [s] at (full_gps_week, tow_s); the almanac's full week
/// is resolved with full_week(sat.week_mod_1024, full_gps_week), so week crossovers are exact.
double time_from_applicability_s(const GpsAlmanac& sat, int full_gps_week, double tow_s);

/// Eccentric anomaly E [rad] from Kepler's equation M = E - e sin E (Newton, at most 50
/// iterations, |step| < 1e-13): the one solver for almanac and ephemeris orbits.
double eccentric_anomaly_rad(double mean_anomaly_rad, double eccentricity);

/// Satellite ECEF position and velocity (velocity analytic: derivative of the same equations,
/// including the Earth-rotation term of the node longitude).
void satellite_pv_ecef(const GpsAlmanac& sat, int full_gps_week, double tow_s, Vec3& r_ecef_m, Vec3& v_ecef_mps);

/// Satellite clock bias af0 + af1 * tk [s] and drift af1 [s/s].
double satellite_clock_bias_s(const GpsAlmanac& sat, int full_gps_week, double tow_s);

/// The almanac as the flight software holds it: one slot per PRN, filled as elements arrive.
class GpsAlmanacTable {
 public:
  /// Stores (or replaces) a satellite's elements. kBadInput if almanac_valid() fails.
  Status set(const GpsAlmanac& sat);
  /// nullptr when the PRN has no elements.
  const GpsAlmanac* find(int prn) const;
  int count() const { return count_; }
  void clear();

 private:
  std::array<GpsAlmanac, kMaxGpsPrn> sats_{};
  std::array<bool, kMaxGpsPrn> have_{};
  int count_ = 0;
};

/// One raw tracking-channel measurement as a receiver reports it: the pseudorange still contains
/// the satellite clock error (the receiver-side conversion removes it with af0/af1).
struct GnssRawMeasurement {
  std::uint8_t prn = 0;
  double pseudorange_m = 0.0;
  double pseudorange_rate_mps = 0.0;
  double cn0_dbhz = 0.0;
};

/// One raw receiver epoch.
struct GnssRawEpoch {
  double t_s = 0.0;        ///< receive time on the navigation (IMU) time scale [s]
  int gps_week = 0;        ///< receive time on the GPS time scale: full week ...
  double gps_tow_s = 0.0;  ///< ... and seconds of the week
  int n_meas = 0;          ///< valid entries in meas, [0, kMaxGnssChannels]
  std::array<GnssRawMeasurement, kMaxGnssChannels> meas{};
};

/// Why raw measurements did not make it into the epoch (counted, never silent).
/// Raw measurements left out by gnss_epoch_from_raw, X(type, name, description); the message
/// field is conv_<name> (see FSW_EXECUTIVE_HEALTH_COUNTERS in fsw/executive.hpp).
#define FSW_GNSS_CONVERSION_COUNTERS(X)                                                             \
  X(std::uint32_t, no_almanac, "PRN without elements in the table")                                 \
  X(std::uint32_t, unhealthy, "almanac health != 0")                                                \
  X(std::uint32_t, invalid, "non-finite or out-of-range values, PRN outside 1..32")                 \
  X(std::uint32_t, duplicate_prn, "second measurement of a PRN in the same epoch")

struct GnssConversionStats {
#define FSW_DECLARE_CONVERSION_FIELD(type, name, doc) type name = 0;
  FSW_GNSS_CONVERSION_COUNTERS(FSW_DECLARE_CONVERSION_FIELD)
#undef FSW_DECLARE_CONVERSION_FIELD
};

/// Raw epoch -> GnssEpoch: transmit time tow - rho / c, satellite position and velocity from the
/// almanac at that time, satellite clock (af0 + af1 tk) removed from the pseudorange and af1 from
/// the rate. Elevation is computed from rx_llh_hint when given (an approximate receiver
/// position), else left 0. Measurements that cannot be used are counted in stats and left out.
/// Returns kBadInput for an epoch with a non-finite time or n_meas out of range (out is then
/// an empty epoch), else kOk (possibly with zero observations).
Status gnss_epoch_from_raw(const GnssRawEpoch& raw, const GpsAlmanacTable& almanac, const Vec3* rx_llh_hint,
                           GnssEpoch& out, GnssConversionStats& stats);

}  // namespace fsw
