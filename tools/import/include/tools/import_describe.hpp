// A recording described by one TOML file (`sdins import describe`, docs/own-recording.md): which
// files hold the IMU, the GNSS solution, the raw GNSS measurements and a reference trajectory, how
// their tables are laid out (CSV or whitespace, header names or column numbers), the unit of each
// column, the IMU's axes, and the time base of each stream. One import engine turns a description
// into the project's LCM log; the dedicated `sdins import rtklib|psins` formats are presets that
// build a description from a recording's directory (import_presets.cpp).
//
// The parser (parse_recording_description_text) never throws: a description is either parsed or
// refused with "<file>:<line>:<col>: <message naming the dotted key>" (the scenario and filter
// configuration rules, sim/src/toml_schema.hpp). The engine (import_described) throws
// std::runtime_error for input files it cannot use at all and counts every rejected row with its
// reason and line (LineStats).
#pragma once

#include <array>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tools/importers.hpp"

namespace tools {

/// A column of a table: by header name, or by its 1-based number (index 0-based here).
struct ColumnRef {
  std::string name;
  int index = -1;
  bool set() const { return !name.empty() || index >= 0; }
  std::string text() const { return name.empty() ? "column " + std::to_string(index + 1) : "'" + name + "'"; }
};

/// How the rows of a text table are read.
struct TableLayout {
  std::vector<std::string> files;  ///< read in order as one table (relative: to the description's directory)
  bool whitespace = false;         ///< fields separated by blanks instead of `delimiter`
  char delimiter = ',';
  bool header = false;             ///< the first line (after skip_lines) names the columns
  int skip_lines = 0;              ///< lines before the header or the data (not counted as data lines)
  std::string comment;             ///< lines starting with this are comments (empty: none)
  int fields = 0;                  ///< exact field count of a data row (0: the header's, else at least the columns used)
};

/// A stream's time: one column, its scale, and the base it counts on.
enum class TimeBase {
  kGpsTow,       ///< GPS seconds of week (week fixed, from a week column, or from the ephemerides)
  kGpsSeconds,   ///< GPS seconds since 1980-01-06 (continuous, no week)
  kUnix,         ///< UNIX/UTC seconds since 1970 (leap seconds applied and reported)
  kLocal,        ///< a local clock (boot time), placed on GPS time by the clock pair fit
  kRtklibTag,    ///< ticks of an IMU log with an RTKLIB time-tag file (the GNSS_IMU recordings)
};
const char* to_string(TimeBase b);

struct TimeSpec {
  ColumnRef column;
  std::string unit = "s";
  double scale_s = 1.0;        ///< seconds per unit of the column
  TimeBase base = TimeBase::kGpsTow;
  int week = -1;               ///< kGpsTow: the GPS week (-1: week_column or the ephemerides)
  ColumnRef week_column;
  bool week_from_ephemeris = false;
  std::string tag_file;        ///< kRtklibTag
  double clock_ratio = 0.0;    ///< kRtklibTag: GPS s per clock s (0: from the tag's start and last record)
};

/// Three columns of a vector quantity and their unit.
struct Vec3Columns {
  std::array<ColumnRef, 3> cols;
  std::string unit;
  double scale = 1.0;  ///< SI per unit
  bool set() const { return cols[0].set(); }
};

struct ImuStreamSpec {
  bool present = false;
  TableLayout table;
  TimeSpec time;
  bool increments = false;            ///< false: rates (rad/s, m/s^2); true: increments (rad, m/s)
  Vec3Columns gyro, accel;
  std::string axes = "x,y,z";         ///< body x, y, z in sensor axes (AxisMap)
  bool has_rotation = false;
  std::array<double, 3> rotation_rpy_deg{0, 0, 0};  ///< fixed rotation after the permutation (body = R * perm)
  double max_accel_mps2 = 16.0 * 9.80665;
  double max_gyro_radps = 2000.0 * 0.017453292519943295;
  std::string origin;                 ///< for the summary: what built this stream ("description", "preset rtklib")
};

enum class HeightDatum { kEllipsoid, kMslEgm96 };
enum class VelocityForm { kNone, kEnu, kNed, kEcef, kSpeedCourse };

/// Position, velocity and their sigmas as columns (GNSS solution and reference tables).
struct PositionColumns {
  ColumnRef lat, lon, height;
  std::string angle_unit = "deg";
  double angle_scale = 0.017453292519943295;  ///< rad per unit
  std::string height_unit = "m";
  double height_scale = 1.0;
  HeightDatum datum = HeightDatum::kEllipsoid;
  VelocityForm velocity = VelocityForm::kNone;
  Vec3Columns vel;                 ///< enu/ned/ecef components, or speed, course, vertical speed
  std::string course_unit = "deg";
  double course_scale = 0.017453292519943295;
  double vertical_sign = 1.0;      ///< speed_course: +1 vertical speed positive up, -1 positive down
};

struct GnssStreamSpec {
  bool present = false;
  std::string format = "table";  ///< "table" or "rtklib_pos"
  TableLayout table;
  TimeSpec time;
  ColumnRef local_clock;         ///< the clock pair: a local clock column on the same rows
  std::string local_unit = "s";
  double local_scale_s = 1.0;
  double latency_s = 0.0;        ///< the local clock stamps a fix this long after its validity time
  PositionColumns pos;
  Vec3Columns pos_sigma;         ///< east, north, up [m]
  ColumnRef hdop, vdop;          ///< the sigma model: sigma_h = uere * hdop / sqrt(2) per axis, sigma_u = uere * vdop
  double uere_m = 0.0;           ///< user equivalent range error of the model (0: no model)
  double vel_sigma_mps = -1.0;   ///< per axis, constant (negative: none)
  Vec3Columns vel_sigma;
  ColumnRef quality;
  std::map<long, int> quality_map;  ///< column value -> solution kind (sdins::gnss_pvt_t::QUALITY_*)
  int quality_default = 5;       ///< without a column: the kind of every row
  std::map<int, double> uere_by_kind;  ///< the model's UERE per solution kind (overrides uere_m)
  ColumnRef n_sat;
};

enum class RawFormat { kRinex3, kUbx, kTable };

struct RawStreamSpec {
  bool present = false;
  RawFormat format = RawFormat::kRinex3;
  std::string obs_file, nav_file, ubx_file;
  std::string convbin = "convbin";
  bool keep_temp = false;
  // kTable: one row per measurement; rows of equal time form an epoch.
  TableLayout table;
  TimeSpec time;
  ColumnRef prn, pseudorange, range_rate, cn0;
  double range_rate_scale = 1.0;  ///< m/s per unit (-1 for a Doppler column that is minus the range rate in m/s)
  std::string range_rate_unit = "m/s";
  std::string ephemeris_file;     ///< kTable: broadcast ephemeris, "rinex3" or "csv" (columns by name)
  std::string ephemeris_format = "csv";
};

struct ReferenceStreamSpec {
  bool present = false;
  std::string kind = "unknown";   ///< "rtk", "autopilot_estimate", "post_processed_ins", "simulation", ...
  bool from_gnss = false;         ///< the GNSS solution's epochs with 1 <= quality <= max_quality
  int max_quality = 1;
  TableLayout table;
  TimeSpec time;
  PositionColumns pos;
  Vec3Columns attitude;           ///< roll, pitch, yaw (yaw: heading clockwise from north), body FRD
  std::string attitude_unit = "deg";
};

struct RecordingDescription {
  std::string source;             ///< the description file (for messages)
  std::string base_dir;           ///< relative file names are resolved against this
  std::string name, description;
  std::string format = "describe";  ///< the summary's "format" (a preset's name)
  ImuStreamSpec imu;
  GnssStreamSpec gnss;
  RawStreamSpec raw;
  ReferenceStreamSpec reference;
  bool clip_gnss_to_imu = false;
  double max_fit_error_m = 0.1;
  std::string filter_config_out;  ///< empty: <log>.filter.toml
};

struct DescriptionParseResult {
  bool ok = false;
  std::string error;
};

/// Parses a description (TOML text); relative file names are resolved against base_dir.
DescriptionParseResult parse_recording_description_text(const std::string& text, const std::string& source,
                                                         const std::string& base_dir, RecordingDescription& out);
/// The same for a file; relative names resolve against data_dir, or the file's own directory when empty.
DescriptionParseResult parse_recording_description_file(const std::string& path, const std::string& data_dir,
                                                        RecordingDescription& out);

/// Every input file a description names (tables, time tags, RINEX, u-blox, ephemeris), for the
/// check that no output overwrites one.
std::vector<std::string> description_inputs(const RecordingDescription& d);

struct DescribeOptions {
  std::string log_path;
  std::string input;              ///< for the summary ("input")
  bool write_filter_config = true;
  bool write_sidecar = true;      ///< the summary beside the log: <log>.json
};

/// Runs the import of a description: reads the streams, writes the log, the summary sidecar and the
/// starting filter configuration; returns the summary (the JSON of `--json`).
nlohmann::json import_described(const RecordingDescription& d, const DescribeOptions& opt);

/// The summary lines of the description import (streams, time fit, leap seconds, warnings, the
/// written files), appended by import_summary_text.
std::string describe_summary_text(const nlohmann::json& summary);

/// The sidecar's schema ("version"): 2 since every stream of the summary ("imu", "gnss_pvt",
/// "gnss_raw", "truth") keeps its statistics under "samples" in the one shape of
/// tools/stream_summary.hpp (1: "samples"/"epochs"/"span" with count and mean rate only).
inline constexpr int kImportSummaryVersion = 2;

/// The sidecar of an imported log: "<log>.json" ("format": "sdins-import-summary"); its
/// "reference" names what TRUTH holds: {"kind", "source", "has_attitude"}.
std::string import_sidecar_path(const std::string& log_path);

/// The files every import writes beside its log, for any importer (the description engine, the
/// presets, a ULog reader): the starting filter configuration at filter_path (empty: none; checked
/// to parse) and the sidecar import_sidecar_path(log_path) holding `sum` with "format":
/// "sdins-import-summary", "importer", "version"; adds "filter_config" and "sidecar" to sum. A
/// summary for it needs "input", "reference" (null or {kind, source, has_attitude}) and the keys
/// starting_filter_config reads.
void finish_import_outputs(nlohmann::json& sum, const std::string& log_path, const std::string& filter_path,
                           const std::string& name, const std::string& importer, bool write_sidecar = true);

/// A starting filter configuration (TOML text, commented with where each value came from) from an
/// import summary's streams: navigation rate from the IMU, EKF rate from the GNSS, a valid
/// ekf_latency_frames, the GNSS source and its floors, the initialisation speed. Used by the
/// description import and by any importer that produces the same summary keys: "input";
/// "imu": {"samples": a StreamSummary} or null; "gnss_pvt": {"samples": a StreamSummary,
/// "by_quality": {"Q": n}} or null; "gnss_raw": {"samples": a StreamSummary} or null; "almanac":
/// {"written": [PRNs]} or null; "speed": {"p90_mps", "source"} or null (missing keys mean "not in
/// this recording"). The IMU's rate is its mean rate unless gaps move it more than 2 % from the
/// nominal (median-interval) rate; the GNSS rate is the nominal rate (lost epochs do not slow the EKF).
std::string starting_filter_config(const nlohmann::json& summary, const std::string& name);

/// The presets (`sdins import rtklib|psins`): a description built from a recording's directory.
RecordingDescription rtklib_preset(const ImportOptions& opt);
RecordingDescription psins_preset(const ImportOptions& opt);
DescribeOptions describe_options(const ImportOptions& opt);

/// GPS - UTC [s] at a UTC instant given as UNIX seconds (the leap second table since 1980; 18 s
/// from 2017-01-01). Throws for times before 1980-01-06.
int gps_minus_utc_s(double unix_s);

/// Ellipsoidal height [m] from a height above mean sea level (EGM96, PROJ with the geoid grid of
/// Debian's proj-data) at lat/lon [rad]; throws when PROJ or the grid is not available.
double egm96_msl_to_ellipsoid_m(double lat_rad, double lon_rad, double msl_m);

}  // namespace tools
