// Importing recorded data into the project's LCM log format (`sdins import`, docs/import.md).
//
// The readers take streams (or bytes) so that the tests can feed them hand-made lines; each counts
// every line it could not use under a reason (LineStats) and never throws for bad data lines. A
// file whose format is not the expected one (no header, unsupported time system, ...) is an error
// (std::runtime_error).
//
// Conventions of the imported logs:
// - time: t_s = GPS time in seconds since the start of the GPS week of the recording's earliest
//   sample (ImportTimeScale): within that week t_s is the GPS time of week, so it can be compared
//   directly with gps_tow_s and with the source files; it keeps counting past fsw::kSecondsPerWeek across a
//   week rollover. IMU, GNSS_RAW, GNSS_PVT, TRUTH and GPS_ALMANAC share it.
// - IMU: body axes x forward, y right, z down (fsw/frames.hpp) through a signed axis permutation
//   per data set (AxisMap); increments in rad and m/s over (t_s - dt_s, t_s].
#pragma once

#include <array>
#include <cstdint>
#include <istream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "fsw/gps_orbit.hpp"
#include "hal/lcm_convert.hpp"
#include "tools/gps_ephemeris.hpp"

namespace tools {

// ---------------------------------------------------------------------------------------------
// Time

/// RTKLIB's gtime_t seconds (GPS time counted from 1970-01-01 like a Unix time, no leap seconds)
/// of the GPS epoch 1980-01-06 00:00:00.
inline constexpr std::int64_t kGpsEpochGtime_s = 315964800;

/// Full GPS week and seconds of the week: the flight software's type (one GPS time, one week wrap:
/// fsw::gps_time).
using GpsTime = fsw::GpsTime;

/// GPS time of `count` units of 1 / per_second s since the GPS epoch (whole seconds: 1,
/// microseconds: 1000000), plus fraction_s. The whole weeks are split off in integers before
/// anything is a double, so the seconds of the week keep the count's resolution (a double of the
/// ~1.4e9 s since 1980 resolves only 0.24 us, and would lose a fraction kept apart), then
/// fsw::gps_time wraps. The importers' one integer week split.
GpsTime gps_time_from_count(std::int64_t count, std::int64_t per_second, double fraction_s = 0.0);

/// GPS time from RTKLIB gtime_t seconds (integer part and fraction, kept apart for precision).
GpsTime gps_time_from_gtime(std::int64_t seconds, double fraction_s);
/// GPS time from a calendar date and time on the GPS time scale; false for an invalid date.
bool gps_time_from_calendar(int year, int month, int day, int hour, int minute, double second, GpsTime& out);

/// The navigation time scale of an imported log: seconds since the start of GPS week week0.
struct ImportTimeScale {
  int week0 = 0;
  double t_s(const GpsTime& t) const {
    return static_cast<double>(t.week - week0) * fsw::kSecondsPerWeek + t.tow_s;
  }
};

// ---------------------------------------------------------------------------------------------
// Line accounting

/// Lines a time jump must hold for to be taken as a new time base (hal::TimeTagGate).
inline constexpr int kTimeBaseConfirmLines = 5;

/// Lines of one input file: how many were read, used and rejected, by reason, with the first few
/// rejected line numbers (1-based) as examples.
struct LineStats {
  std::uint64_t lines = 0;     ///< data lines seen (headers and comments excluded)
  std::uint64_t accepted = 0;
  std::uint64_t rejected = 0;
  std::map<std::string, std::uint64_t> by_reason;
  std::vector<std::pair<std::uint64_t, std::string>> examples;  ///< at most kMaxExamples
  /// Lines that are fine but not used (other GNSS systems, absent satellites, ...), by reason.
  std::map<std::string, std::uint64_t> skipped;
  /// Time tags (hal::TimeTagGate, docs/faults.md): sustained jumps taken as a new time base, the
  /// last one's size (in the file's time unit) and line. Single outliers are rejected lines.
  std::uint64_t time_base_changes = 0;
  double last_time_jump = 0.0;
  std::uint64_t last_time_jump_line = 0;
  static constexpr std::size_t kMaxExamples = 10;

  void reject(std::uint64_t line, const std::string& reason);
  void skip(const std::string& reason);
  nlohmann::json to_json() const;
};

// ---------------------------------------------------------------------------------------------
// RTKLIB time-tag files (.tag)

struct TimeTagRecord {
  std::uint32_t tick_ms = 0;  ///< ms since the log was opened
  std::uint32_t offset = 0;   ///< byte offset in the tagged file
};

/// An RTKLIB time-tag file: 60 bytes of header text ("TIMETAG RTKLIB ..."), uint32 (RTKLIB's
/// tick_f: the PC's ms tick when the file was opened; the data set README calls it the tick
/// frequency; not used for timing), uint32 GPST seconds since 1970 (gtime_t.time), float64
/// fraction of a second: the start time; then records of uint32 tick [ms since the start] and
/// uint32 byte offset. Little-endian.
struct TimeTag {
  static constexpr std::size_t kHeaderTextBytes = 60;
  static constexpr std::size_t kHeaderBytes = 76;
  static constexpr std::size_t kRecordBytes = 8;
  std::string label;                 ///< header text without the padding, e.g. "TIMETAG RTKLIB demo5"
  std::uint32_t tick_f = 0;
  std::int64_t start_gtime_s = 0;    ///< integer seconds
  double start_fraction_s = 0.0;
  std::vector<TimeTagRecord> records;
  std::uint64_t trailing_bytes = 0;  ///< bytes after the last whole record (a cut record: ignored)
  std::uint64_t non_monotonic = 0;   ///< records whose tick or offset goes backwards
  GpsTime start() const { return gps_time_from_gtime(start_gtime_s, start_fraction_s); }
  /// Tick of the last record [s] (0 without records).
  double last_tick_s() const { return records.empty() ? 0.0 : 1e-3 * records.back().tick_ms; }
};

/// Parses the bytes of a .tag file; throws std::runtime_error when the header is not an RTKLIB
/// time tag (too short, no "TIMETAG" label, fraction outside [0, 1)).
TimeTag parse_time_tag(const std::vector<std::uint8_t>& bytes);
TimeTag read_time_tag(const std::string& path);

// ---------------------------------------------------------------------------------------------
// RTKLIB solution files (.pos)

struct PosFile {
  std::vector<hal::GnssPvtSample> samples;  ///< t_s not set (0): the importer sets it
  LineStats lines;
  std::string time_system;                  ///< "GPST"
  bool has_velocity = false;
};

/// Reads an RTKLIB .pos solution: '%' header lines, the column header
/// "%  GPST latitude(deg) longitude(deg) height(m) Q ns sdn(m) sde(m) sdu(m) ... [vn(m/s) ve(m/s)
/// vu(m/s) sdvn sdve sdvu ...]", data lines with the time as "yyyy/mm/dd hh:mm:ss.sss" or
/// "week tow". Positions to radians, N/E/U velocities and sigmas to E/N/U order. Rejected lines:
/// wrong field count, unparsable or non-finite number, invalid date, time not increasing, values
/// the GNSS_PVT validation (hal::from_msg) rejects. Throws for a file without the column header,
/// with a time system other than GPST or positions not in latitude/longitude degrees.
PosFile read_rtklib_pos(std::istream& in);

// ---------------------------------------------------------------------------------------------
// GNSS_IMU IMU logs (CSV: accel x,y,z [g], gyro x,y,z [deg/s], tick [ms])

struct ImuCsvSample {
  double accel_g[3] = {0, 0, 0};
  double gyro_dps[3] = {0, 0, 0};
  std::int64_t tick_ms = 0;
  std::uint64_t line = 0;  ///< 1-based line number
};

/// Plausibility of a GNSS_IMU line (MEMS ranges).
struct ImuCsvLimits {
  double max_accel_g = 16.0;
  double max_gyro_dps = 2000.0;
};

/// Reads the 7-column CSV. Rejected lines: wrong field count (the partial first line), unparsable
/// or non-finite number, a value beyond ImuCsvLimits, a tick not after the previous accepted one,
/// and a last line without its newline (cut off while logging).
std::vector<ImuCsvSample> read_gnss_imu_csv(std::istream& in, LineStats& stats, const ImuCsvLimits& limits = {});

/// The GNSS_IMU project's mapping of IMU ticks to GPS time: the first accepted sample is at the
/// tag's start time, the last at the start time plus the last tag record's tick, linear in between.
struct TickToGps {
  GpsTime start;
  std::int64_t tick0_ms = 0;
  double seconds_per_tick = 1e-3;  ///< (last tag tick) / (last tick - first tick) in s per IMU tick
  /// Seconds after start of a tick.
  double offset_s(std::int64_t tick_ms) const { return seconds_per_tick * static_cast<double>(tick_ms - tick0_ms); }
};
/// How far (relative) the tag's span may differ from the IMU's own tick span (1 ms per tick)
/// before the importer refuses the mapping (docs/faults.md): a crystal drifts by 1e-4, not 1e-2.
inline constexpr double kMaxTagClockDeviation = 0.01;
/// Throws std::runtime_error with fewer than two samples or no tag records.
TickToGps tick_to_gps(const TimeTag& tag, const std::vector<ImuCsvSample>& samples);

// ---------------------------------------------------------------------------------------------
// IMU axes

/// A signed axis permutation sensor -> body: body[i] = sign[i] * sensor[src[i]]. Written as three
/// comma-separated terms giving body x, y, z in sensor axes, e.g. "-x,y,-z" (body x = -sensor x,
/// ...). Only proper rotations (determinant +1) are accepted.
struct AxisMap {
  std::array<int, 3> src{0, 1, 2};
  std::array<double, 3> sign{1.0, 1.0, 1.0};
  std::string text() const;
  fsw::Vec3 apply(const fsw::Vec3& sensor) const {
    return fsw::Vec3(sign[0] * sensor[src[0]], sign[1] * sensor[src[1]], sign[2] * sensor[src[2]]);
  }
  /// The rotation matrix C (body = C * sensor).
  fsw::Mat3 matrix() const;
};
/// Throws std::runtime_error for a malformed map, a repeated axis or a reflection.
AxisMap parse_axis_map(const std::string& text);

/// The default axis maps: the GNSS_IMU board (x backward, y right, z up relative to the car in
/// the drive data set) and PSINS' Right-Front-Up IMU frame.
inline constexpr const char* kAxesGnssImu = "-x,y,-z";
inline constexpr const char* kAxesPsins = "y,x,-z";

/// Rate samples (body axes, rad/s and m/s^2) at times t_s -> increments over each interval
/// (t[k-1], t[k]] by the trapezoid rule (the integral of the linear interpolation of the samples).
/// The first sample only opens the first interval, so n samples give n - 1 increments; record k
/// gets counter[k].
struct RateSample {
  double t_s = 0.0;
  fsw::Vec3 omega_radps = fsw::Vec3::Zero();
  fsw::Vec3 f_mps2 = fsw::Vec3::Zero();
  std::int32_t counter = 0;
};
std::vector<hal::ImuRecord> increments_from_rates(const std::vector<RateSample>& samples);

// ---------------------------------------------------------------------------------------------
// PSINS (insgpseo_tc converted to CSV)

struct PsinsImuRow {
  double tow_s = 0.0;
  fsw::Vec3 dtheta_rad = fsw::Vec3::Zero();  ///< sensor axes (Right-Front-Up)
  fsw::Vec3 dv_mps = fsw::Vec3::Zero();
  std::uint64_t line = 0;
};
/// imu_200hz.csv: header, then GPS tow [s], delta-theta x,y,z [rad], delta-v x,y,z [m/s].
/// Rejected: field count, unparsable/non-finite, time of week out of range, time not increasing
/// (implausible increments are rejected later by the importer with the IMU input validation).
std::vector<PsinsImuRow> read_psins_imu(std::istream& in, LineStats& stats);

struct PsinsObsRow {
  double tow_s = 0.0;
  int prn = 0;
  double pseudorange_m = 0.0;
  double carrier_m = 0.0;
  double doppler_mps = 0.0;  ///< as in the file: minus the range rate
  std::uint64_t line = 0;
};
/// gps_obs.csv: header, then GPS tow [s], PRN, C/A pseudorange [m], L1 carrier [m], an
/// undocumented column, Doppler [m/s] (= -range rate). Rejected: field count, unparsable or
/// non-finite number, PRN outside 1..32, pseudorange outside 1e7..5e7 m, a time going backwards or
/// jumping alone (hal::TimeTagGate).
std::vector<PsinsObsRow> read_psins_obs(std::istream& in, LineStats& stats);

/// gps_eph.csv: a header naming the columns (PRN,Toc,af0,...), one row per PRN; rows with health
/// 255 and zero elements (absent satellites) are skipped and counted as "absent satellite".
std::vector<GpsEphemeris> read_psins_eph(std::istream& in, LineStats& stats);

// ---------------------------------------------------------------------------------------------
// RINEX 3 (as written by RTKLIB's convbin)

struct RinexObsSat {
  char sys = 'G';
  int prn = 0;
  double c1c_m = 0.0, d1c_hz = 0.0, s1c_dbhz = 0.0;
  bool has_c1c = false, has_d1c = false, has_s1c = false;
};
struct RinexObsEpoch {
  GpsTime time;  ///< receiver time (GPST)
  std::vector<RinexObsSat> sats;
};
struct RinexObsStats {
  LineStats lines;                  ///< epoch and satellite lines
  std::string version;
  std::uint64_t event_epochs = 0;   ///< epochs with flag > 1 (events, header records): skipped
};
/// Reads a RINEX 3.0x observation file (GPS C1C, D1C, S1C; other systems are kept with their
/// system letter). Throws for a file that is not RINEX 3 observation data or has no GPS C1C.
std::vector<RinexObsEpoch> read_rinex3_obs(std::istream& in, RinexObsStats& stats);

/// Reads the GPS records of a RINEX 3.0x navigation file; other systems are skipped and counted
/// under "other system". Throws for a file that is not RINEX 3 navigation data.
std::vector<GpsEphemeris> read_rinex3_nav(std::istream& in, LineStats& stats);

/// L1 carrier wavelength [m] (c / 1575.42 MHz): pseudorange rate = -Doppler [Hz] * this.
inline constexpr double kGpsL1Wavelength_m = 299792458.0 / 1575.42e6;

// ---------------------------------------------------------------------------------------------
// The importers (`sdins import`)

struct ImportOptions {
  std::string format;     ///< "rtklib" or "psins"
  std::string path;       ///< directory (or, for rtklib, a .pos file)
  std::string log_path;   ///< the LCM log to write
  std::string axes;       ///< sensor -> body axis map; empty: the format's default
  int truth_max_quality = 1;       ///< .pos epochs with Q <= this (and >= 1) also go to TRUTH
  double max_fit_error_m = 0.1;    ///< almanac fits must be within this (position + clock); see import_recording.cpp
  bool clip_gnss_to_imu = false;   ///< keep GNSS epochs / solutions only within the IMU span (+-1 s)
  std::string convbin = "convbin"; ///< RTKLIB's convbin (for a .ubx next to the solution)
  bool keep_temp = false;          ///< keep convbin's RINEX files (their directory is in the summary)
  /// GNSS_IMU logs: GPS seconds per IMU-clock second. 0: from the tag file (its start time and
  /// last record, as the data sets' source does); otherwise the first sample stays at the tag's
  /// start time and the ticks are scaled by this (an IMU clock rate measured elsewhere, e.g. by
  /// the diagnosis' drifting time offset).
  double imu_clock_ratio = 0.0;
};

/// Runs one import: reads the recording, writes the log, returns the summary (the JSON of
/// `sdins import --json`). Throws std::runtime_error for missing or unusable input files.
nlohmann::json import_recording(const ImportOptions& opt);

/// The human-readable summary `sdins import` prints.
std::string import_summary_text(const nlohmann::json& summary);

}  // namespace tools
