// GPS time from UTC: the leap seconds between the two scales (GPS time = UTC + GPS-UTC, GPS-UTC
// = TAI-UTC - 19 s). The table holds every leap second since the GPS epoch (1980-01-06) as
// announced by the IERS (Bulletin C); a test compares it with the system's tzdata list
// (/usr/share/zoneinfo/leap-seconds.list) when that is installed.
#pragma once

#include <cstdint>

namespace tools {

/// UNIX time [s] of the GPS epoch, 1980-01-06 00:00:00 UTC.
inline constexpr std::int64_t kGpsEpochUnix_s = 315964800;

/// The table is known complete up to this UNIX time (2026-06-28 00:00:00 UTC, the expiry of the
/// IERS list it was checked against): later times get GPS-UTC = 18 s with a warning.
inline constexpr std::int64_t kLeapTableValidUntilUnix_s = 1782604800;

/// GPS-UTC [s] at the UTC instant unix_s (seconds since 1970 on the UTC scale, as UNIX clocks
/// count them); 0 before the first leap second after the GPS epoch (1981-07-01).
int gps_minus_utc_s(std::int64_t unix_s);

/// GPS time in microseconds since the GPS epoch of a UTC time in microseconds since 1970.
inline std::int64_t gps_us_from_utc_us(std::int64_t utc_us) {
  const std::int64_t s = utc_us >= 0 ? utc_us / 1000000 : -((-utc_us + 999999) / 1000000);
  return utc_us - kGpsEpochUnix_s * 1000000 + static_cast<std::int64_t>(gps_minus_utc_s(s)) * 1000000;
}

}  // namespace tools
