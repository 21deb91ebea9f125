// The import engine of a recording description (tools/import_describe.hpp): text tables through
// the bounded readers and the time-tag gate into IMU increments, GNSS solutions, raw epochs and a
// reference on one GPS time scale; then the log, its summary sidecar and a starting filter
// configuration. `sdins import rtklib|psins` are presets of this path (import_presets.cpp).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "fsw/frames.hpp"
#include "import_common.hpp"
#include "import_util.hpp"
#include "cfg/flight_config.hpp"
#include "tools/import_describe.hpp"
#include "tools/output_file.hpp"

namespace tools {

using namespace import_util;
using namespace import_detail;

namespace {

// ---------------------------------------------------------------------------------------------
// Tables

/// One accepted row: its line (counted on through the files in order) and the requested columns.
struct Row {
  std::uint64_t line = 0;
  std::vector<double> v;
};

struct TableRead {
  std::vector<Row> rows;       ///< in file order, before the time gate
  std::vector<std::string> header;
  std::string files;
};

int column_index(const ColumnRef& c, const std::vector<std::string>& header, const std::string& file,
                 const std::string& stream) {
  if (c.index >= 0) return c.index;
  for (std::size_t i = 0; i < header.size(); ++i)
    if (header[i] == c.name) return static_cast<int>(i);
  std::string names;
  for (const std::string& h : header) names += (names.empty() ? "" : ", ") + h;
  throw std::runtime_error(file + ": " + stream + " column '" + c.name + "' is not in the header (" +
                           (header.empty() ? std::string("no header: set header = true or use column numbers") : names) +
                           ")");
}

std::vector<std::string_view> fields_of(std::string_view s, const TableLayout& l) {
  return l.whitespace ? split_ws(s) : split(s, l.delimiter);
}

/// Reads the table's rows with the requested columns parsed as numbers. Rejected (counted with
/// line and reason): empty lines, a last line without its newline, a wrong field count, an
/// unparsable or non-finite number. Throws for a missing file or a header without a column.
TableRead read_table(const TableLayout& l, const std::vector<ColumnRef>& cols, LineStats& stats, const std::string& stream) {
  TableRead out;
  std::vector<int> idx;
  int needed = 0;
  std::uint64_t line_no = 0;
  for (const std::string& file : l.files) {
    out.files += (out.files.empty() ? "" : ", ") + file;
    std::ifstream in;
    try {
      in = open_in(file);
    } catch (const std::runtime_error& e) {
      throw std::runtime_error("the " + stream + " stream's file: " + e.what());
    }
    std::string line;
    bool terminated = true;
    int skipped = 0;
    bool have_header = !l.header || !out.header.empty();
    bool file_header_done = !l.header;
    while (getline_counted(in, line, terminated)) {
      ++line_no;
      if (skipped < l.skip_lines) {
        ++skipped;
        continue;
      }
      const std::string_view s = trim(line);
      if (!l.comment.empty() && s.substr(0, l.comment.size()) == l.comment) continue;
      if (!file_header_done) {
        file_header_done = true;
        if (!have_header || out.header.empty()) {
          for (std::string_view f : fields_of(s, l)) out.header.emplace_back(trim(f));
          have_header = true;
        }
        continue;
      }
      if (idx.empty()) {
        for (const ColumnRef& c : cols) {
          idx.push_back(c.set() ? column_index(c, out.header, file, stream) : -1);
          needed = std::max(needed, idx.back() + 1);
        }
      }
      if (!take_data_line(stats, line_no, s, terminated)) continue;
      const auto f = fields_of(s, l);
      const std::size_t expect = l.fields > 0 ? static_cast<std::size_t>(l.fields) : l.header ? out.header.size() : 0;
      if ((expect > 0 && f.size() != expect) || f.size() < static_cast<std::size_t>(needed)) {
        stats.reject(line_no, "wrong field count (" + std::to_string(f.size()) + ", expected " +
                                  std::to_string(expect > 0 ? expect : static_cast<std::size_t>(needed)) + ")");
        continue;
      }
      Row r;
      r.line = line_no;
      r.v.assign(idx.size(), std::nan(""));
      bool ok = true, finite = true;
      for (std::size_t k = 0; k < idx.size() && ok; ++k) {
        if (idx[k] < 0) continue;
        ok = parse_double(f[static_cast<std::size_t>(idx[k])], r.v[k]);
        finite = finite && std::isfinite(r.v[k]);
      }
      if (!ok) {
        stats.reject(line_no, "unparsable number");
        continue;
      }
      if (!finite) {
        stats.reject(line_no, "non-finite value");
        continue;
      }
      out.rows.push_back(std::move(r));
    }
    if (l.header && out.header.empty()) throw std::runtime_error(file + ": no header line (header = true)");
  }
  return out;
}

/// Rows through the time-tag gate on their raw time (column k_time), thresholds in seconds.
/// Duplicates (the same time as the previous accepted row) are dropped and counted first.
std::vector<Row> gate_rows(std::vector<Row> rows, std::size_t k_time, double scale_s, double fwd_s, double back_s,
                           bool strict, LineStats& stats, std::uint64_t& duplicates) {
  std::vector<Row> out;
  LineTimeGate<Row> gate(stats, out, gate_config(fwd_s / scale_s, back_s / scale_s, strict));
  double last = std::nan("");
  for (Row& r : rows) {
    if (strict && r.v[k_time] == last) {
      ++duplicates;
      stats.reject(r.line, "duplicate time (dropped)");
      continue;
    }
    last = r.v[k_time];
    const double t = r.v[k_time];  // read before the row is moved into the gate
    gate.push(t, std::move(r));
  }
  gate.finish();
  return out;
}

// ---------------------------------------------------------------------------------------------
// Time

double gps_seconds(const GpsTime& t) { return static_cast<double>(t.week) * fsw::kSecondsPerWeek + t.tow_s; }

/// The clock pair: GPS = offset + (1 + drift) * local, least squares over the GNSS rows.
struct ClockFit {
  bool valid = false;
  double local0_s = 0.0, gps0_s = 0.0;  ///< the first pair (the fit is about it, for precision)
  double offset_s = 0.0;                ///< GPS - local at local0
  double slope = 1.0;
  double rms_s = 0.0, max_s = 0.0;
  std::size_t pairs = 0;
  double gps_s(double local_s) const { return gps0_s + offset_s + slope * (local_s - local0_s); }
  nlohmann::json to_json(double latency_s) const {
    return {{"pairs", pairs},
            {"model", "GPS seconds = gps0 + offset + slope * (local - local0), fitted to (local clock, GPS time + latency) "
                       "of the GNSS rows: the local clock stamps a fix on arrival, latency after its validity"},
            {"local0_s", local0_s},
            {"gps0_s", gps0_s},
            {"offset_s", offset_s},
            {"gps_minus_local_at_local0_s", gps0_s + offset_s - local0_s},
            {"drift_ppm", (slope - 1.0) * 1e6},
            {"residual_rms_s", rms_s},
            {"residual_max_s", max_s},
            {"latency_s", latency_s}};
  }
};

ClockFit fit_clock(const std::vector<std::pair<double, double>>& pairs) {
  ClockFit f;
  f.pairs = pairs.size();
  if (pairs.size() < 2) return f;
  f.local0_s = pairs.front().first;
  f.gps0_s = pairs.front().second;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = static_cast<double>(pairs.size());
  for (const auto& [l, g] : pairs) {
    const double x = l - f.local0_s, y = g - f.gps0_s;
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  const double den = n * sxx - sx * sx;
  if (!(den > 0.0)) return f;
  f.slope = (n * sxy - sx * sy) / den;
  f.offset_s = (sy - f.slope * sx) / n;
  double ss = 0.0;
  for (const auto& [l, g] : pairs) {
    const double r = (g - f.gps0_s) - (f.offset_s + f.slope * (l - f.local0_s));
    ss += r * r;
    f.max_s = std::max(f.max_s, std::abs(r));
  }
  f.rms_s = std::sqrt(ss / n);
  f.valid = true;
  return f;
}

/// The week of a gps_tow stream's row (fixed, a column, or the ephemerides' week).
struct TimeContext {
  int ephemeris_week = -1;
  ClockFit fit;
  double latency_s = 0.0;
  std::set<int> leap_seconds;
  std::uint64_t leap_rows = 0;
};

/// GPS seconds since the GPS epoch -> week and seconds of week; false for a time before the epoch
/// or past week 9999.
bool placed(double gps_s, GpsTime& out, std::string& why) {
  if (!(gps_s >= 0.0 && gps_s < 1e4 * fsw::kSecondsPerWeek)) {
    why = "GPS time out of range (before 1980-01-06 or past week 9999)";
    return false;
  }
  out = fsw::gps_time(0, gps_s);
  return true;
}

/// A row's raw time (and week column) -> GPS time; false (with a reason) when it cannot be placed.
bool row_gps_time(const TimeSpec& ts, double raw, double week_raw, TimeContext& ctx, GpsTime& out, std::string& why) {
  const double v = raw * ts.scale_s;
  switch (ts.base) {
    case TimeBase::kGpsTow: {
      int week = ts.week;
      if (ts.week_column.set()) {
        if (!(week_raw >= 0.0 && week_raw < 10000.0) || week_raw != std::floor(week_raw)) {
          why = "GPS week out of range";
          return false;
        }
        week = static_cast<int>(week_raw);
      }
      if (week < 0 && ts.week_from_ephemeris) week = ctx.ephemeris_week;
      if (week < 0) {
        why = "no GPS week";
        return false;
      }
      if (v < 0.0 || v >= fsw::kSecondsPerWeek) {
        why = "time of week out of range";
        return false;
      }
      out = GpsTime{week, v};
      return true;
    }
    case TimeBase::kGpsSeconds:
      return placed(v, out, why);
    case TimeBase::kUnix: {
      if (v < static_cast<double>(kGpsEpochGtime_s)) {
        why = "UNIX time before the GPS epoch";
        return false;
      }
      const int leap = gps_minus_utc_s(v);
      ctx.leap_seconds.insert(leap);
      ++ctx.leap_rows;
      return placed(v - static_cast<double>(kGpsEpochGtime_s) + leap, out, why);
    }
    case TimeBase::kLocal:
      if (!ctx.fit.valid) {
        why = "no clock fit";
        return false;
      }
      return placed(ctx.fit.gps_s(v), out, why);
    case TimeBase::kRtklibTag:
      break;  // placed by the caller (the tag maps the whole stream)
  }
  why = "time base";
  return false;
}

}  // namespace

int gps_minus_utc_s(double unix_s) {
  // UTC dates (UNIX seconds) from which GPS - UTC is the value (IERS Bulletin C; none since 2017).
  static const std::pair<double, int> kSteps[] = {
      {315964800.0, 0},  {362793600.0, 1},  {394329600.0, 2},  {425865600.0, 3},  {489024000.0, 4},
      {567993600.0, 5},  {631152000.0, 6},  {662688000.0, 7},  {709948800.0, 8},  {741484800.0, 9},
      {773020800.0, 10}, {820454400.0, 11}, {867715200.0, 12}, {915148800.0, 13}, {1136073600.0, 14},
      {1230768000.0, 15}, {1341100800.0, 16}, {1435708800.0, 17}, {1483228800.0, 18}};
  if (!(unix_s >= kSteps[0].first)) throw std::runtime_error("UTC time before the GPS epoch (1980-01-06)");
  int leap = 0;
  for (const auto& [t, v] : kSteps)
    if (unix_s >= t) leap = v;
  return leap;
}

namespace {

// ---------------------------------------------------------------------------------------------
// Streams

/// What one stream's reading produced, for the summary and the checks.
struct StreamInfo {
  std::string name;
  LineStats lines;
  std::uint64_t duplicates = 0;
  std::string files;
  std::string time_base;
};

/// Where a stream came from; its statistics are its "samples" (the one stream shape).
nlohmann::json stream_origin(const StreamInfo& s) { return {{"files", s.files}, {"time_base", s.time_base}}; }

/// Vector columns of a row (k0, k0+1, k0+2) times the unit's scale.
fsw::Vec3 vec_at(const Row& r, std::size_t k0, double scale) {
  return fsw::Vec3(r.v[k0] * scale, r.v[k0 + 1] * scale, r.v[k0 + 2] * scale);
}

fsw::Mat3 fixed_rotation(const ImuStreamSpec& s) {
  // body = C * sensor: roll about x, pitch about y, yaw about z (z-y-x, FRD), in degrees.
  const double r = s.rotation_rpy_deg[0] * fsw::kDegToRad, p = s.rotation_rpy_deg[1] * fsw::kDegToRad,
               y = s.rotation_rpy_deg[2] * fsw::kDegToRad;
  const Eigen::AngleAxisd rx(r, fsw::Vec3::UnitX()), ry(p, fsw::Vec3::UnitY()), rz(y, fsw::Vec3::UnitZ());
  return (rz * ry * rx).toRotationMatrix().transpose();
}

struct ImuResult {
  std::vector<hal::ImuRecord> records;
  StreamInfo info;
  nlohmann::json extra = nlohmann::json::object();
  AxisMap axes;
  std::vector<std::string> warnings;
  bool have = false;
  // raw rows (after the gate) and the tag, kept for placing on the time scale
  std::vector<Row> rows;
  TimeTag tag;
  double raw0 = 0.0, spt = 0.0;  ///< rtklib_tag: first raw tick and seconds per raw unit
};

/// The IMU's magnitude checks: a description that contradicts its data gets a warning naming it.
void imu_unit_checks(const ImuStreamSpec& s, const std::vector<fsw::Vec3>& f, const std::vector<fsw::Vec3>& w,
                     std::vector<std::string>& warnings) {
  if (f.empty()) return;
  std::vector<double> fn, wn;
  for (const auto& x : f) fn.push_back(x.norm());
  for (const auto& x : w) wn.push_back(x.norm());
  const double fmed = median(fn);
  std::sort(wn.begin(), wn.end());
  const double w95 = wn[static_cast<std::size_t>(0.95 * static_cast<double>(wn.size() - 1))];
  char b[400];
  if (fmed < 3.0 || fmed > 30.0) {
    std::snprintf(b, sizeof(b),
                  "imu.accel: the median specific force is %.3g m/s^2 with unit \"%s\" (about 9.8 expected at rest "
                  "and in most motion): %s",
                  fmed, s.accel.unit.c_str(),
                  fmed < 3.0 && fmed > 0.5 ? "the column looks like g declared as m/s^2"
                  : fmed > 30.0 && fmed < 150.0 ? "the column looks like m/s^2 declared as g"
                                                : "check the unit and the kind (rates or increments)");
    warnings.push_back(b);
  }
  if (s.gyro.unit == "rad/s" && w95 > 3.0) {
    std::snprintf(b, sizeof(b),
                  "imu.gyro: 5%% of the rates exceed %.3g rad/s (%.0f deg/s) with unit \"rad/s\": the column looks like "
                  "deg/s",
                  w95, w95 * fsw::kRadToDeg);
    warnings.push_back(b);
  }
  if (s.gyro.unit == "deg/s" && w95 > 0.0 && w95 < 2e-3) {
    std::snprintf(b, sizeof(b),
                  "imu.gyro: 95%% of the rates are below %.3g deg/s with unit \"deg/s\" (a MEMS gyro's noise alone is "
                  "larger): the column looks like rad/s",
                  w95 * fsw::kRadToDeg);
    warnings.push_back(b);
  }
}

ImuResult read_imu(const ImuStreamSpec& s) {
  ImuResult r;
  r.have = true;
  r.info.name = "imu";
  r.info.time_base = to_string(s.time.base);
  r.axes = parse_axis_map(s.axes);
  std::vector<ColumnRef> cols = {s.time.column, s.gyro.cols[0], s.gyro.cols[1], s.gyro.cols[2],
                                 s.accel.cols[0], s.accel.cols[1], s.accel.cols[2], s.time.week_column};
  TableRead t = read_table(s.table, cols, r.info.lines, "imu");
  r.info.files = t.files;
  // Sensor range (rates) or the implied rate (increments, checked once the interval is known).
  std::vector<Row> ok;
  for (Row& row : t.rows) {
    if (!s.increments) {
      bool in_range = true;
      for (int i = 0; i < 3; ++i)
        in_range = in_range && std::abs(row.v[1 + i] * s.gyro.scale) <= s.max_gyro_radps &&
                   std::abs(row.v[4 + i] * s.accel.scale) <= s.max_accel_mps2;
      if (!in_range) {
        r.info.lines.reject(row.line, "value beyond the sensor range");
        continue;
      }
    }
    ok.push_back(std::move(row));
  }
  r.rows = gate_rows(std::move(ok), 0, s.time.scale_s, 1.0, 1.0, true, r.info.lines, r.info.duplicates);
  if (s.time.base == TimeBase::kRtklibTag) {
    if (r.info.lines.time_base_changes > 0 && r.info.lines.last_time_jump < 0.0)
      throw std::runtime_error(t.files + ": the IMU time goes back by " + std::to_string(-r.info.lines.last_time_jump) +
                               " " + s.time.unit + " near line " + std::to_string(r.info.lines.last_time_jump_line) +
                               " and stays there (the IMU restarted): one .tag cannot place both parts on GPS time");
  }
  return r;
}

/// Places the rtklib-tag IMU on GPS time: the first accepted sample at the tag's start, the last
/// at the start plus the tag's last tick, linear in between (or at a given clock ratio).
void place_tagged_imu(const ImuStreamSpec& s, ImuResult& r, nlohmann::json& warnings_json) {
  const std::string& tag_path = s.time.tag_file;
  r.tag = read_time_tag(tag_path);
  if (r.rows.size() < 2) throw std::runtime_error(tag_path + ": fewer than two usable IMU samples");
  if (r.tag.records.empty()) throw std::runtime_error(tag_path + ": time-tag file without records");
  if (r.tag.non_monotonic > 0)
    throw std::runtime_error(tag_path + ": " + std::to_string(r.tag.non_monotonic) +
                             " records go backwards in tick or offset: a damaged time-tag file");
  r.raw0 = r.rows.front().v[0];
  const double raw_span = r.rows.back().v[0] - r.raw0;
  r.spt = r.tag.last_tick_s() / raw_span;
  const double ratio = r.spt / s.time.scale_s;
  const double imu_span_s = raw_span * s.time.scale_s;
  const std::string why = tag_path + ": the last tag record is " + std::to_string(r.tag.last_tick_s()) +
                          " s after the start but the IMU's own ticks span " + std::to_string(imu_span_s) +
                          " s (ratio " + std::to_string(ratio) + ", beyond the " + std::to_string(kMaxTagClockDeviation) +
                          " a clock drift can explain): a cut .tag or a truncated IMU CSV";
  if (s.time.clock_ratio > 0.0) {
    if (!(std::abs(ratio - 1.0) <= kMaxTagClockDeviation)) {
      std::fprintf(stderr, "sdins import: warning: %s; using --imu-clock-ratio %g (the IMU's own clock)\n", why.c_str(),
                   s.time.clock_ratio);
      warnings_json.push_back(why + "; the IMU's own clock used (--imu-clock-ratio)");
    }
    r.spt = s.time.clock_ratio * s.time.scale_s;
  } else if (!(std::abs(ratio - 1.0) <= kMaxTagClockDeviation)) {
    throw std::runtime_error(why + "; to place the IMU by its own clock from the tag's start time instead, pass "
                             "--imu-clock-ratio 1 (description: imu.time.clock_ratio = 1)");
  }
}

/// The IMU rows on the time scale -> increments (rates: trapezoid; increments: as recorded).
void imu_records(const ImuStreamSpec& s, ImuResult& r, const ImportTimeScale& scale, TimeContext& ctx) {
  const bool rotate = s.has_rotation;
  const fsw::Mat3 R = rotate ? fixed_rotation(s) : fsw::Mat3::Identity();
  const auto to_body = [&](const fsw::Vec3& v) { return rotate ? fsw::Vec3(R * r.axes.apply(v)) : r.axes.apply(v); };
  std::vector<double> t;
  std::vector<Row> rows;
  t.reserve(r.rows.size());
  const double t_start = s.time.base == TimeBase::kRtklibTag ? scale.t_s(r.tag.start()) : 0.0;
  for (Row& row : r.rows) {
    if (s.time.base == TimeBase::kRtklibTag) {
      t.push_back(t_start + r.spt * (row.v[0] - r.raw0));
    } else {
      GpsTime g;
      std::string why;
      if (!row_gps_time(s.time, row.v[0], row.v[7], ctx, g, why)) {
        r.info.lines.reject(row.line, why);
        --r.info.lines.accepted;
        continue;
      }
      t.push_back(scale.t_s(g));
    }
    rows.push_back(std::move(row));
  }
  std::vector<fsw::Vec3> fs_body, ws_body;
  if (!s.increments) {
    std::vector<RateSample> rs;
    rs.reserve(rows.size());
    for (std::size_t k = 0; k < rows.size(); ++k) {
      RateSample x;
      x.t_s = t[k];
      x.f_mps2 = to_body(vec_at(rows[k], 4, s.accel.scale));
      x.omega_radps = to_body(vec_at(rows[k], 1, s.gyro.scale));
      x.counter = static_cast<std::int32_t>(rows[k].line - 1);  // zero-based line: rejected lines show as counter gaps
      fs_body.push_back(x.f_mps2);
      ws_body.push_back(x.omega_radps);
      rs.push_back(x);
    }
    r.records = increments_from_rates(rs);
  } else {
    std::vector<double> d;
    for (std::size_t k = 1; k < rows.size(); ++k) d.push_back(t[k] - t[k - 1]);
    const double nominal = d.empty() ? 0.005 : median(d);
    std::uint64_t odd = 0;
    for (std::size_t k = 0; k < rows.size(); ++k) {
      hal::ImuRecord rec;
      rec.sample.t_s = t[k];
      rec.sample.dt_s = k == 0 ? nominal : t[k] - t[k - 1];
      rec.sample.dtheta_rad = to_body(vec_at(rows[k], 1, s.gyro.scale));
      rec.sample.dv_mps = to_body(vec_at(rows[k], 4, s.accel.scale));
      rec.counter = static_cast<std::int32_t>(rows[k].line - 1);
      if (std::abs(rec.sample.dt_s - nominal) > 0.5 * nominal) ++odd;
      if (rec.sample.dt_s > 0.0) {
        fs_body.push_back(rec.sample.dv_mps / rec.sample.dt_s);
        ws_body.push_back(rec.sample.dtheta_rad / rec.sample.dt_s);
      }
      r.records.push_back(rec);
    }
    r.extra["increment_intervals"] = {{"nominal_s", nominal}, {"off_by_more_than_half", odd}};
    if (odd > 0)
      r.warnings.push_back("imu: " + std::to_string(odd) + " increments cover an interval more than 50 % off the median " +
                           std::to_string(nominal) + " s (the increments are written with their own interval)");
  }
  imu_unit_checks(s, fs_body, ws_body, r.warnings);
  r.rows = std::move(rows);  // the placed rows (the summary reads the first and last tick)
}

// ---------------------------------------------------------------------------------------------
// GNSS solutions and the reference

fsw::Vec3 velocity_enu(const PositionColumns& pc, const Row& r, std::size_t k0, const fsw::Vec3& llh) {
  const fsw::Vec3 v = vec_at(r, k0, pc.vel.scale);
  switch (pc.velocity) {
    case VelocityForm::kEnu: return v;
    case VelocityForm::kNed: return fsw::Vec3(v.y(), v.x(), -v.z());
    case VelocityForm::kEcef: return fsw::C_n_e(llh.x(), llh.y()).transpose() * v;
    case VelocityForm::kSpeedCourse: {
      const double speed = r.v[k0] * pc.vel.scale, course = r.v[k0 + 1] * pc.course_scale;
      return fsw::Vec3(speed * std::sin(course), speed * std::cos(course), pc.vertical_sign * r.v[k0 + 2] * pc.vel.scale);
    }
    case VelocityForm::kNone: break;
  }
  return fsw::Vec3::Constant(std::nan(""));
}

/// Columns of a position table: time, week, lat, lon, height, vel x3 (from index 5).
std::vector<ColumnRef> position_columns(const TimeSpec& t, const PositionColumns& pc) {
  return {t.column, t.week_column, pc.lat, pc.lon, pc.height, pc.vel.cols[0], pc.vel.cols[1], pc.vel.cols[2]};
}

bool position_llh(const PositionColumns& pc, const Row& r, fsw::Vec3& llh, std::uint64_t& geoid_rows) {
  llh = fsw::Vec3(r.v[2] * pc.angle_scale, r.v[3] * pc.angle_scale, r.v[4] * pc.height_scale);
  if (std::abs(llh.x()) > 0.5 * fsw::kPi || std::abs(llh.y()) > 2.0 * fsw::kPi) return false;
  if (pc.datum == HeightDatum::kMslEgm96) {
    llh.z() = egm96_msl_to_ellipsoid_m(llh.x(), llh.y(), llh.z());
    ++geoid_rows;
  }
  return true;
}

struct GnssResult {
  std::vector<hal::GnssPvtSample> pvt;
  StreamInfo info;
  std::vector<Row> rows;  ///< after the gate (table format)
  std::vector<std::pair<double, double>> clock_pairs;
  std::uint64_t geoid_rows = 0;
  bool has_velocity = false;
  nlohmann::json sigma_source;
};

std::vector<ColumnRef> gnss_columns(const GnssStreamSpec& s) {
  std::vector<ColumnRef> c = position_columns(s.time, s.pos);
  for (const ColumnRef& x : s.pos_sigma.cols) c.push_back(x);  // 8..10
  c.push_back(s.hdop);                                           // 11
  c.push_back(s.vdop);                                           // 12
  for (const ColumnRef& x : s.vel_sigma.cols) c.push_back(x);  // 13..15
  c.push_back(s.quality);                                        // 16
  c.push_back(s.n_sat);                                          // 17
  c.push_back(s.local_clock);                                    // 18
  return c;
}

GnssResult read_gnss_rows(const GnssStreamSpec& s) {
  GnssResult g;
  g.info.name = "gnss";
  g.info.time_base = s.format == "rtklib_pos" ? "gps (RTKLIB .pos GPST)" : to_string(s.time.base);
  if (s.format == "rtklib_pos") {
    std::ifstream f = open_in(s.table.files.front());
    PosFile pf = read_rtklib_pos(f);
    g.info.files = s.table.files.front();
    g.info.lines = pf.lines;
    g.pvt = pf.samples;
    g.has_velocity = pf.has_velocity;
    g.sigma_source = "the solver's sigmas (.pos sdn/sde/sdu, sdvn/sdve/sdvu)";
    return g;
  }
  TableRead t = read_table(s.table, gnss_columns(s), g.info.lines, "gnss");
  g.info.files = t.files;
  g.rows = gate_rows(std::move(t.rows), 0, s.time.scale_s, 600.0, 0.0, true, g.info.lines, g.info.duplicates);
  if (s.local_clock.set())
    for (const Row& r : g.rows) {
      GpsTime gt;
      std::string why;
      TimeContext none;
      if (row_gps_time(s.time, r.v[0], r.v[1], none, gt, why))
        g.clock_pairs.emplace_back(r.v[18] * s.local_scale_s, gps_seconds(gt) + s.latency_s);  // arrival on both clocks
    }
  return g;
}

int solution_kind(const GnssStreamSpec& s, const Row& r, bool& ok) {
  ok = true;
  if (!s.quality.set()) return s.quality_default;
  const double q = r.v[16];
  if (!(std::abs(q) < 1e6)) {
    ok = false;
    return 0;
  }
  if (!s.quality_map.empty()) {
    const auto it = s.quality_map.find(std::lround(q));
    if (it == s.quality_map.end() || q != std::round(q)) {
      ok = false;
      return 0;
    }
    return it->second;
  }
  if (q != std::round(q) || q < 0 || q > 7) ok = false;
  return static_cast<int>(q);
}

void gnss_solutions(const GnssStreamSpec& s, GnssResult& g, const ImportTimeScale& scale, TimeContext& ctx) {
  if (s.format == "rtklib_pos") {
    for (hal::GnssPvtSample& p : g.pvt) p.t_s = scale.t_s(GpsTime{p.gps_week, p.gps_tow_s});
    return;
  }
  g.has_velocity = s.pos.velocity != VelocityForm::kNone;
  for (const Row& r : g.rows) {
    GpsTime gt;
    std::string why;
    if (!row_gps_time(s.time, r.v[0], r.v[1], ctx, gt, why)) {
      g.info.lines.reject(r.line, why);
      --g.info.lines.accepted;
      continue;
    }
    hal::GnssPvtSample p;
    p.gps_week = gt.week;
    p.gps_tow_s = gt.tow_s;
    p.t_s = scale.t_s(gt);
    bool ok = position_llh(s.pos, r, p.llh, g.geoid_rows);
    bool kind_ok = true;
    p.quality = solution_kind(s, r, kind_ok);
    const bool nsat_ok = !s.n_sat.set() || (r.v[17] >= 0.0 && r.v[17] <= 255.0);
    p.n_sat = s.n_sat.set() && nsat_ok ? static_cast<int>(r.v[17]) : 0;
    if (s.pos_sigma.set()) {
      p.pos_sigma_enu_m = vec_at(r, 8, s.pos_sigma.scale);
    } else {
      const auto it = s.uere_by_kind.find(p.quality);
      const double uere = it != s.uere_by_kind.end() ? it->second : s.uere_m;
      const double sh = uere * r.v[11] / std::sqrt(2.0);
      const double su = s.vdop.set() ? uere * r.v[12] : 1.5 * uere * r.v[11];
      p.pos_sigma_enu_m = fsw::Vec3(sh, sh, su);
    }
    if (g.has_velocity) {
      p.vel_enu_mps = velocity_enu(s.pos, r, 5, p.llh);
      p.vel_sigma_enu_mps = s.vel_sigma.set() ? vec_at(r, 13, s.vel_sigma.scale)
                                              : fsw::Vec3::Constant(s.vel_sigma_mps > 0.0 ? s.vel_sigma_mps : 0.2);
    } else {
      p.vel_sigma_enu_mps = fsw::Vec3::Constant(hal::kGnssPvtNoVelocity);
    }
    if (!ok || !kind_ok || !nsat_ok) {
      g.info.lines.reject(r.line, !ok        ? "position out of range (check the angle unit)"
                                  : !kind_ok ? "fix quality not in the map (or not a solution kind)"
                                             : "satellite count outside 0..255");
      --g.info.lines.accepted;
      continue;
    }
    sdins::gnss_pvt_t m{};
    hal::to_msg(p, m);
    hal::GnssPvtSample back;
    const hal::LcmInputStatus st = hal::from_msg(m, back);
    if (st != hal::LcmInputStatus::kOk) {
      g.info.lines.reject(r.line, std::string("GNSS_PVT validation: ") + hal::to_string(st));
      --g.info.lines.accepted;
      continue;
    }
    g.pvt.push_back(p);
  }
  g.sigma_source = s.pos_sigma.set()
                       ? nlohmann::json("columns")
                       : nlohmann::json("model: sigma_e = sigma_n = UERE * HDOP / sqrt(2), sigma_u = " +
                                        std::string(s.vdop.set() ? "UERE * VDOP" : "1.5 * UERE * HDOP") +
                                        ", UERE per solution kind or uere_m");
}

struct ReferenceResult {
  std::vector<ReferenceEpoch> epochs;
  StreamInfo info;
  std::uint64_t left_out = 0, geoid_rows = 0;
  bool has_attitude = false, has_velocity = false;
  std::string source;
};

ReferenceResult read_reference(const ReferenceStreamSpec& s, const GnssResult* gnss, const ImportTimeScale& scale,
                               TimeContext& ctx) {
  ReferenceResult out;
  out.info.name = "reference";
  if (s.from_gnss) {
    out.source = gnss->info.files + " (GNSS solutions with 1 <= quality <= " + std::to_string(s.max_quality) + ")";
    out.info.files = gnss->info.files;
    out.info.time_base = gnss->info.time_base;
    for (const hal::GnssPvtSample& p : gnss->pvt) {
      if (p.quality >= 1 && p.quality <= s.max_quality) {
        ReferenceEpoch e;
        e.t_s = p.t_s;
        e.llh = p.llh;
        e.vel_enu_mps = p.has_velocity() ? p.vel_enu_mps : fsw::Vec3::Constant(std::nan(""));
        out.has_velocity = out.has_velocity || p.has_velocity();
        out.epochs.push_back(e);
      } else {
        ++out.left_out;
      }
    }
    return out;
  }
  std::vector<ColumnRef> cols = position_columns(s.time, s.pos);
  for (const ColumnRef& c : s.attitude.cols) cols.push_back(c);  // 8..10
  TableRead t = read_table(s.table, cols, out.info.lines, "reference");
  out.info.files = t.files;
  out.source = t.files;
  out.info.time_base = to_string(s.time.base);
  const std::vector<Row> rows = gate_rows(std::move(t.rows), 0, s.time.scale_s, 600.0, 0.0, true, out.info.lines,
                                          out.info.duplicates);
  out.has_attitude = s.attitude.set();
  out.has_velocity = s.pos.velocity != VelocityForm::kNone;
  for (const Row& r : rows) {
    GpsTime gt;
    std::string why;
    ReferenceEpoch e;
    if (!row_gps_time(s.time, r.v[0], r.v[1], ctx, gt, why) || !position_llh(s.pos, r, e.llh, out.geoid_rows)) {
      out.info.lines.reject(r.line, why.empty() ? "position out of range (check the angle unit)" : why);
      --out.info.lines.accepted;
      continue;
    }
    e.t_s = scale.t_s(gt);
    if (out.has_velocity) e.vel_enu_mps = velocity_enu(s.pos, r, 5, e.llh);
    if (out.has_attitude) {
      const fsw::Vec3 a = vec_at(r, 8, s.attitude.scale);
      e.has_attitude = true;
      e.C_b_n = fsw::C_b_n_from_euler(a.x(), a.y(), a.z());
    }
    out.epochs.push_back(e);
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Raw GNSS

struct RawResult {
  std::vector<RinexObsEpoch> obs;  ///< rinex3 / ubx
  std::vector<GpsEphemeris> ephs;
  RinexObsStats obs_stats;
  LineStats nav_lines, table_lines;
  nlohmann::json convbin = nullptr;
  std::vector<Row> rows;  ///< table: after the gate
  std::uint64_t duplicates = 0;
  std::string files;
  TempDir tmp;
};

void read_rinex_pair(const std::string& obs_path, const std::string& nav_path, RawResult& r) {
  std::ifstream of = open_in(obs_path);
  r.obs = read_rinex3_obs(of, r.obs_stats);
  if (fs::exists(nav_path)) {
    std::ifstream nf = open_in(nav_path);
    r.ephs = read_rinex3_nav(nf, r.nav_lines);
  }
}

void read_raw(const RawStreamSpec& s, RawResult& r) {
  if (s.format == RawFormat::kRinex3) {
    r.files = s.obs_file + ", " + s.nav_file;
    if (!fs::exists(s.nav_file)) throw std::runtime_error("missing " + s.nav_file);
    read_rinex_pair(s.obs_file, s.nav_file, r);
    return;
  }
  if (s.format == RawFormat::kUbx) {
    r.files = s.ubx_file;
    r.tmp.path = make_temp_dir();
    r.tmp.keep = s.keep_temp;
    const std::string obs_path = (r.tmp.path / "raw.obs").string(), nav_path = (r.tmp.path / "raw.nav").string();
    // RINEX 3.04 with Doppler and SNR; only GPS (the flight software is GPS L1 C/A).
    const std::vector<std::string> cmd = {s.convbin, "-r", "ubx", "-v", "3.04", "-od", "-os", "-y", "R", "-y", "E",
                                          "-y", "J", "-y", "S", "-y", "C", "-y", "I", "-o", obs_path, "-n", nav_path,
                                          s.ubx_file};
    const int rc = run_program(cmd, (r.tmp.path / "convbin.log").string());
    if (rc != 0 || !fs::exists(obs_path) || fs::file_size(obs_path) == 0)
      throw std::runtime_error("convbin failed (exit " + std::to_string(rc) + ", is RTKLIB installed? Debian: rtklib): " +
                               join(cmd));
    read_rinex_pair(obs_path, nav_path, r);
    std::set<int> eph_prns;
    for (const GpsEphemeris& e : r.ephs) eph_prns.insert(e.prn);
    r.convbin = {{"command", join(cmd)},
                 {"exit_status", rc},
                 {"temp_dir", s.keep_temp ? r.tmp.path.string() : std::string("(removed)")},
                 {"rinex_version", r.obs_stats.version},
                 {"obs_bytes", fs::file_size(obs_path)},
                 {"obs_epochs", r.obs.size()},
                 {"obs_lines", r.obs_stats.lines.to_json()},
                 {"event_epochs", r.obs_stats.event_epochs},
                 {"nav_bytes", fs::exists(nav_path) ? fs::file_size(nav_path) : 0},
                 {"nav_gps_ephemerides", r.ephs.size()},
                 {"nav_gps_prns", std::vector<int>(eph_prns.begin(), eph_prns.end())},
                 {"nav_records", r.nav_lines.to_json()}};
    return;
  }
  // A table of measurements and a broadcast ephemeris file.
  std::ifstream ef = open_in(s.ephemeris_file);
  r.ephs = s.ephemeris_format == "rinex3" ? read_rinex3_nav(ef, r.nav_lines) : read_psins_eph(ef, r.nav_lines);
  const std::vector<ColumnRef> cols = {s.time.column, s.time.week_column, s.prn, s.pseudorange, s.range_rate, s.cn0};
  TableRead t = read_table(s.table, cols, r.table_lines, "gnss_raw");
  r.files = t.files + ", " + s.ephemeris_file;
  std::vector<Row> ok;
  for (Row& row : t.rows) {
    if (row.v[2] < 1 || row.v[2] > 32 || row.v[2] != std::round(row.v[2])) {
      r.table_lines.reject(row.line, "PRN outside 1..32");
      continue;
    }
    if (row.v[3] < 1e7 || row.v[3] > 5e7) {
      r.table_lines.reject(row.line, "pseudorange outside 1e7..5e7 m");
      continue;
    }
    ok.push_back(std::move(row));
  }
  std::uint64_t unused = 0;
  r.rows = gate_rows(std::move(ok), 0, s.time.scale_s, 600.0, 0.0, false, r.table_lines, unused);
}

int ephemeris_week(const std::vector<GpsEphemeris>& ephs) {
  std::map<int, int> weeks;
  for (const GpsEphemeris& e : ephs) ++weeks[e.week];
  if (weeks.empty()) return -1;
  return std::max_element(weeks.begin(), weeks.end(), [](auto& a, auto& b) { return a.second < b.second; })->first;
}

void raw_epochs(const RawStreamSpec& s, RawResult& r, const ImportTimeScale& scale, TimeContext& ctx, RawCounts& rc,
                std::vector<fsw::GnssRawEpoch>& out) {
  if (s.format != RawFormat::kTable) {
    for (const RinexObsEpoch& ep : r.obs) {
      ++rc.epochs_in;
      std::vector<RawMeas> m;
      for (const RinexObsSat& sat : ep.sats) {
        if (sat.sys != 'G') {
          ++rc.non_gps;
          continue;
        }
        if (!sat.has_c1c) {
          ++rc.no_pseudorange;
          continue;
        }
        if (!sat.has_d1c) {
          ++rc.no_doppler;
          continue;
        }
        if (sat.c1c_m < 1e7 || sat.c1c_m > 5e7) {
          ++rc.bad_pseudorange;
          continue;
        }
        m.push_back({sat.prn, sat.c1c_m, -sat.d1c_hz * kGpsL1Wavelength_m, sat.has_s1c ? sat.s1c_dbhz : 0.0});
      }
      fsw::GnssRawEpoch e;
      if (make_epoch(scale.t_s(ep.time), ep.time, m, rc, e)) out.push_back(e);
    }
    return;
  }
  for (std::size_t i = 0; i < r.rows.size();) {
    std::size_t j = i;
    std::vector<RawMeas> m;
    while (j < r.rows.size() && r.rows[j].v[0] == r.rows[i].v[0]) {
      const Row& x = r.rows[j];
      m.push_back({static_cast<int>(x.v[2]), x.v[3], x.v[4] * s.range_rate_scale, s.cn0.set() ? x.v[5] : 0.0});
      ++j;
    }
    ++rc.epochs_in;
    GpsTime t;
    std::string why;
    if (row_gps_time(s.time, r.rows[i].v[0], r.rows[i].v[1], ctx, t, why)) {
      fsw::GnssRawEpoch e;
      if (make_epoch(scale.t_s(t), t, m, rc, e)) out.push_back(e);
    } else {
      for (std::size_t k = i; k < j; ++k) {
        r.table_lines.reject(r.rows[k].line, why);
        --r.table_lines.accepted;
      }
    }
    i = j;
  }
}

// ---------------------------------------------------------------------------------------------
// Checks and summary

std::string number_text(double v) {
  char b[40];
  std::snprintf(b, sizeof(b), "%.10g", v);
  return b;
}

std::pair<double, double> span_of(const nlohmann::json& samples) {
  if (!samples.is_object() || samples.value("count", std::uint64_t{0}) == 0) return {NAN, NAN};
  return {samples["t_first_s"].get<double>(), samples["t_last_s"].get<double>()};
}

void overlap_checks(const nlohmann::json& sum, std::vector<std::string>& warnings) {
  const auto imu = sum["imu"].is_object() ? span_of(sum["imu"]["samples"]) : std::pair<double, double>{NAN, NAN};
  const auto check = [&](const char* key, const char* what, const nlohmann::json& s) {
    const auto o = span_of(s);
    if (std::isnan(imu.first) || std::isnan(o.first)) return;
    const double a = std::max(imu.first, o.first), b = std::min(imu.second, o.second);
    char buf[300];
    if (b <= a) {
      std::snprintf(buf, sizeof(buf),
                    "%s: the %s span t_s %.3f .. %.3f does not overlap the IMU's %.3f .. %.3f (a time base or week "
                    "wrong?)",
                    key, what, o.first, o.second, imu.first, imu.second);
      warnings.push_back(buf);
    } else if (b - a < 0.5 * (imu.second - imu.first)) {
      std::snprintf(buf, sizeof(buf), "%s: the %s overlaps the IMU over %.1f s only (IMU %.1f s)", key, what, b - a,
                    imu.second - imu.first);
      warnings.push_back(buf);
    }
  };
  if (sum["gnss_pvt"].is_object()) check("gnss", "GNSS solutions'", sum["gnss_pvt"]["samples"]);
  if (sum["gnss_raw"].is_object()) check("gnss_raw", "raw epochs'", sum["gnss_raw"]["samples"]);
  if (sum["reference"].is_object() && sum["truth"].is_object()) check("reference", "reference's", sum["truth"]["samples"]);
}

/// Speed statistics of the solutions (or the reference) for the initialisation speed.
nlohmann::json speed_json(const std::vector<hal::GnssPvtSample>& pvt, const std::vector<ReferenceEpoch>& ref) {
  if (nlohmann::json j = pvt_speed_json(pvt); !j.is_null()) return j;
  std::vector<double> v;
  for (const auto& r : ref)
    if (std::isfinite(r.vel_enu_mps.x())) v.push_back(r.vel_enu_mps.head<2>().norm());
  return speed_stats_json(v, "reference");
}

std::uint64_t total_rejected(const nlohmann::json& j) {
  std::uint64_t n = 0;
  for (const char* k : {"imu", "gnss_pvt", "gnss_raw", "ephemeris", "reference_lines"})
    if (j.contains(k) && j[k].is_object() && j[k].contains("lines") && j[k]["lines"].is_object())
      n += j[k]["lines"]["rejected"].get<std::uint64_t>();
  return n;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// The engine

std::string import_sidecar_path(const std::string& log_path) { return log_path + ".json"; }

std::string describe_summary_text(const nlohmann::json& j) {
  std::ostringstream o;
  char b[400];
  // The solutions' stream: its nominal rate and intervals in the stream's own time base.
  if (j.contains("gnss_pvt") && j["gnss_pvt"].is_object() && j["gnss_pvt"].contains("stream") &&
      j["gnss_pvt"]["samples"].value("count", std::uint64_t{0}) >= 2) {
    const nlohmann::json& s = j["gnss_pvt"]["samples"];
    std::snprintf(b, sizeof(b), "GNSS stream:  %s: %.3f Hz (median interval %.4f s, longest %.3f s), %llu gaps, %llu duplicates dropped\n",
                  j["gnss_pvt"]["stream"]["time_base"].get<std::string>().c_str(), s["rate_hz"].get<double>(),
                  s["dt_s"]["median"].get<double>(), s["dt_s"]["max"].get<double>(),
                  static_cast<unsigned long long>(s["gaps"].get<std::uint64_t>()),
                  static_cast<unsigned long long>(s["duplicates"].get<std::uint64_t>()));
    o << b;
  }
  if (j.contains("time_fit") && j["time_fit"].is_object()) {
    const auto& f = j["time_fit"];
    std::snprintf(b, sizeof(b),
                  "clock fit:    GPS - local = %.6f s at local %.3f s, drift %.3f ppm, residual %.3g s RMS (max %.3g s) "
                  "over %llu pairs; GNSS latency %.3f s\n",
                  f["gps_minus_local_at_local0_s"].get<double>(), f["local0_s"].get<double>(), f["drift_ppm"].get<double>(),
                  f["residual_rms_s"].get<double>(), f["residual_max_s"].get<double>(),
                  static_cast<unsigned long long>(f["pairs"].get<std::uint64_t>()), f["latency_s"].get<double>());
    o << b;
  }
  if (j.contains("leap_seconds") && j["leap_seconds"].is_object()) {
    o << "UTC -> GPS:   GPS - UTC =";
    for (const auto& v : j["leap_seconds"]["gps_minus_utc_s"]) o << " " << v.get<int>();
    o << " s applied (" << j["leap_seconds"]["rows"].get<std::uint64_t>() << " rows)\n";
  }
  if (j.contains("reference") && j["reference"].is_object())
    o << "reference:    " << j["reference"]["kind"].get<std::string>() << " from " << j["reference"]["source"].get<std::string>()
      << (j["reference"]["has_attitude"].get<bool>() ? " (with attitude)" : " (no attitude)") << "\n";
  if (j.contains("warnings"))
    for (const auto& w : j["warnings"]) o << "WARNING:      " << w.get<std::string>() << "\n";
  if (j.contains("filter_config")) o << "filter configuration: " << j["filter_config"].get<std::string>() << "\n";
  if (j.contains("sidecar")) o << "summary:      " << j["sidecar"].get<std::string>() << "\n";
  return o.str();
}

namespace {

struct Streams {
  ImuResult imu;
  GnssResult gnss;
  RawResult raw;
  ReferenceResult ref;
  TimeContext ctx;
  nlohmann::json warnings = nlohmann::json::array();
};

/// Reads every stream's rows, fits the clock pair, finds the time scale's week.
int read_streams(const RecordingDescription& d, Streams& st) {
  if (d.raw.present) read_raw(d.raw, st.raw);
  st.ctx.ephemeris_week = ephemeris_week(st.raw.ephs);
  if (d.imu.present) {
    st.imu = read_imu(d.imu);
    if (d.imu.time.base == TimeBase::kRtklibTag) place_tagged_imu(d.imu, st.imu, st.warnings);
  }
  if (d.gnss.present) {
    st.gnss = read_gnss_rows(d.gnss);
    st.ctx.latency_s = d.gnss.latency_s;
    if (d.gnss.local_clock.set()) {
      st.ctx.fit = fit_clock(st.gnss.clock_pairs);
      if (!st.ctx.fit.valid)
        throw std::runtime_error(d.source + ": the clock pair (gnss.local_clock) needs at least two GNSS rows with both "
                                 "times; " + std::to_string(st.gnss.clock_pairs.size()) + " found");
    }
  }
  // The week of the earliest sample of any stream.
  int week0 = 1 << 30;
  const auto consider = [&](const GpsTime& g) { week0 = std::min(week0, g.week); };
  if (st.imu.have) {
    if (d.imu.time.base == TimeBase::kRtklibTag) {
      consider(st.imu.tag.start());
    } else {
      for (const Row& r : st.imu.rows) {
        GpsTime g;
        std::string why;
        if (row_gps_time(d.imu.time, r.v[0], r.v[7], st.ctx, g, why)) {
          consider(g);
          break;
        }
      }
    }
  }
  if (d.gnss.present) {
    if (d.gnss.format == "rtklib_pos" && !st.gnss.pvt.empty()) consider(GpsTime{st.gnss.pvt.front().gps_week, 0.0});
    for (const Row& r : st.gnss.rows) {
      GpsTime g;
      std::string why;
      if (row_gps_time(d.gnss.time, r.v[0], r.v[1], st.ctx, g, why)) {
        consider(g);
        break;
      }
    }
  }
  if (!st.raw.obs.empty()) consider(st.raw.obs.front().time);
  if (d.raw.present && d.raw.format == RawFormat::kTable)
    for (const Row& r : st.raw.rows) {
      GpsTime g;
      std::string why;
      if (row_gps_time(d.raw.time, r.v[0], r.v[1], st.ctx, g, why)) {
        consider(g);
        break;
      }
    }
  if (week0 == (1 << 30)) throw std::runtime_error("nothing to import in " + d.source);
  return week0;
}

nlohmann::json imu_summary(const RecordingDescription& d, ImuResult& imu, Collected& c) {
  nlohmann::json ij = finish_imu(c.imu, imu.info.lines, imu.axes, imu.info.files, imu.info.duplicates);
  if (d.imu.time.base == TimeBase::kRtklibTag) {
    const GpsTime start = imu.tag.start();
    ij["tag"] = {{"label", imu.tag.label},
                 {"start_week", start.week},
                 {"start_tow_s", start.tow_s},
                 {"records", imu.tag.records.size()},
                 {"last_tick_s", imu.tag.last_tick_s()},
                 {"non_monotonic_records", imu.tag.non_monotonic},
                 {"trailing_bytes", imu.tag.trailing_bytes}};
    ij["tick_ms_first"] = static_cast<std::int64_t>(imu.rows.front().v[0]);
    ij["tick_ms_last"] = static_cast<std::int64_t>(imu.rows.back().v[0]);
    ij["seconds_per_imu_second"] = d.imu.time.clock_ratio > 0.0 ? d.imu.time.clock_ratio : imu.spt / d.imu.time.scale_s;
    ij["timing"] = d.imu.time.clock_ratio > 0.0
                       ? "first accepted sample at the tag's start time, linear in the IMU tick at --imu-clock-ratio"
                       : "first accepted sample at the tag's start time, last at start + last tag tick, linear in the IMU tick";
  }
  ij["increments"] = d.imu.increments
                         ? "as recorded, dt_s = the time since the previous row (the first row: the median interval), "
                           "t_s = the row's time (end of the interval)"
                         : "trapezoid of consecutive samples over (t[k-1], t[k]]: n accepted lines give n - 1 samples";
  ij["units"] = {{"gyro", d.imu.gyro.unit}, {"accel", d.imu.accel.unit}, {"time", d.imu.time.unit}};
  if (d.imu.has_rotation)
    ij["fixed_rotation_rpy_deg"] = {d.imu.rotation_rpy_deg[0], d.imu.rotation_rpy_deg[1], d.imu.rotation_rpy_deg[2]};
  for (auto& [k, v] : imu.extra.items()) ij[k] = v;
  ij["stream"] = stream_origin(imu.info);
  return ij;
}

}  // namespace

namespace {

/// The summary of the streams read (the keys of import_recording's summary, plus streams and checks).
nlohmann::json streams_summary(const RecordingDescription& d, const DescribeOptions& opt, Streams& st, Collected& c,
                               const RawCounts& rc, int week0, std::uint64_t clipped_raw, std::uint64_t clipped_pvt,
                               const nlohmann::json& alm_json) {
  nlohmann::json sum;
  sum["format"] = d.format;
  sum["input"] = opt.input.empty() ? d.source : opt.input;
  if (!d.name.empty()) sum["name"] = d.name;
  sum["time_scale"] = {{"gps_week0", week0},
                       {"definition", "t_s = GPS time in seconds since the start of GPS week " + std::to_string(week0) +
                                          " (= GPS time of week within that week)"}};
  sum["files"] = nlohmann::json::object();
  if (st.imu.have) sum["files"]["imu"] = st.imu.info.files;
  if (d.imu.present && d.imu.time.base == TimeBase::kRtklibTag) sum["files"]["imu_tag"] = d.imu.time.tag_file;
  if (d.gnss.present) sum["files"]["gnss"] = st.gnss.info.files;
  if (d.raw.present) sum["files"]["gnss_raw"] = st.raw.files;
  sum["imu"] = st.imu.have ? imu_summary(d, st.imu, c) : nlohmann::json(nullptr);
  if (d.gnss.present) {
    nlohmann::json gj = pvt_json(c.pvt, st.gnss.info.lines, st.gnss.info.files, st.gnss.info.duplicates);
    gj["clipped_to_imu"] = clipped_pvt;
    gj["has_velocity"] = st.gnss.has_velocity;
    gj["stream"] = stream_origin(st.gnss.info);
    gj["sigmas"] = st.gnss.sigma_source;
    gj["latency_s"] = d.gnss.latency_s;
    if (st.gnss.geoid_rows > 0)
      gj["height"] = {{"datum", "MSL (EGM96) converted to ellipsoidal through PROJ"}, {"rows", st.gnss.geoid_rows}};
    sum["gnss_pvt"] = gj;
  } else {
    sum["gnss_pvt"] = nullptr;
  }
  if (d.raw.present) {
    nlohmann::json rj = rc.to_json();
    if (d.raw.format == RawFormat::kTable) rj["lines"] = st.raw.table_lines.to_json();
    rj["samples"] = raw_stream(c.raw, st.raw.files);
    rj["clipped_to_imu"] = clipped_raw;
    rj["files"] = st.raw.files;
    rj["pseudorange_rate"] = d.raw.format == RawFormat::kTable
                                 ? "the range-rate column x " + number_text(d.raw.range_rate_scale) + " (unit \"" +
                                       d.raw.range_rate_unit + "\")" + (d.raw.cn0.set() ? "" : "; C/N0 unknown: 0")
                                 : std::string("-D1C * c / 1575.42 MHz (L1 C/A Doppler)");
    sum["gnss_raw"] = rj;
    if (d.raw.format == RawFormat::kTable)
      sum["ephemeris"] = {{"lines", st.raw.nav_lines.to_json()}, {"gps_week", st.ctx.ephemeris_week}};
  } else {
    sum["gnss_raw"] = nullptr;
  }
  sum["convbin"] = st.raw.convbin;
  sum["almanac"] = alm_json;
  if (d.reference.present) {
    nlohmann::json tj = {{"kind", d.reference.kind}, {"source", st.ref.source}};
    if (d.reference.from_gnss) {
      tj["max_quality"] = d.reference.max_quality;
      tj["left_out"] = st.ref.left_out;
    } else {
      sum["reference_lines"] = {{"lines", st.ref.info.lines.to_json()}};
    }
    tj["samples"] = stream_of("reference", st.ref.source, c.truth, [](const ReferenceEpoch& r) { return r.t_s; },
                              d.reference.from_gnss ? 0 : st.ref.info.duplicates)
                        .to_json();
    tj["note"] = "the reference (" + d.reference.kind + "), not truth: position" +
                 std::string(st.ref.has_velocity ? ", velocity" : "") +
                 (st.ref.has_attitude ? ", attitude" : "; attitude NaN");
    sum["truth"] = tj;
    sum["files"]["reference"] = st.ref.info.files;
    sum["reference"] = {{"kind", d.reference.kind}, {"source", st.ref.source}, {"has_attitude", st.ref.has_attitude}};
  } else {
    sum["truth"] = nullptr;
    sum["reference"] = nullptr;
  }
  if (st.ctx.fit.pairs > 0) {
    sum["time_fit"] = st.ctx.fit.to_json(d.gnss.latency_s);
  }
  if (st.ctx.leap_rows > 0)
    sum["leap_seconds"] = {{"gps_minus_utc_s", std::vector<int>(st.ctx.leap_seconds.begin(), st.ctx.leap_seconds.end())},
                           {"rows", st.ctx.leap_rows}};
  sum["speed"] = speed_json(c.pvt, c.truth);
  std::vector<std::string> warnings = st.imu.warnings;
  overlap_checks(sum, warnings);
  if (d.gnss.present && d.gnss.format != "rtklib_pos" && d.gnss.pos.velocity != VelocityForm::kNone &&
      !d.gnss.vel_sigma.set() && !(d.gnss.vel_sigma_mps > 0.0))
    warnings.push_back("gnss: no velocity sigma given (vel_sigma or vel_sigma_mps): 0.2 m/s per axis assumed");
  for (const std::string& w : warnings) st.warnings.push_back(w);
  sum["warnings"] = st.warnings;
  return sum;
}

}  // namespace

void finish_import_outputs(nlohmann::json& sum, const std::string& log_path, const std::string& filter_path,
                           const std::string& name, const std::string& importer, bool write_sidecar) {
  if (!filter_path.empty()) {
    const std::string text = starting_filter_config(sum, name);
    cfg::FlightConfig check;
    const cfg::FlightConfigResult pr = cfg::parse_flight_config_text(text, filter_path, check);
    if (!pr.ok) throw std::runtime_error("the starting filter configuration does not parse (a bug): " + pr.error);
    write_text_file(filter_path, text);
    sum["filter_config"] = filter_path;
  }
  if (write_sidecar) {
    sum["sidecar"] = import_sidecar_path(log_path);
    nlohmann::json side = sum;
    side["format"] = "sdins-import-summary";
    side["importer"] = importer;
    side["version"] = kImportSummaryVersion;
    write_json_file(import_sidecar_path(log_path), side);
  }
}

nlohmann::json import_described(const RecordingDescription& d, const DescribeOptions& opt) {
  if (opt.log_path.empty()) throw std::runtime_error("no output log (--log)");
  Streams st;
  const int week0 = read_streams(d, st);
  const ImportTimeScale ts{week0};
  Collected c;
  if (st.imu.have) {
    imu_records(d.imu, st.imu, ts, st.ctx);
    c.imu = st.imu.records;
  }
  if (d.gnss.present) {
    gnss_solutions(d.gnss, st.gnss, ts, st.ctx);
    c.pvt = st.gnss.pvt;
  }
  RawCounts rc;
  if (d.raw.present) raw_epochs(d.raw, st.raw, ts, st.ctx, rc, c.raw);

  std::uint64_t clipped_raw = 0, clipped_pvt = 0;
  if (d.clip_gnss_to_imu && !c.imu.empty()) {
    const double a = c.imu.front().sample.t_s - 1.0, b = c.imu.back().sample.t_s + 1.0;
    const auto out_raw = [&](const fsw::GnssRawEpoch& e) { return e.t_s < a || e.t_s > b; };
    const auto out_pvt = [&](const hal::GnssPvtSample& p) { return p.t_s < a || p.t_s > b; };
    clipped_raw = static_cast<std::uint64_t>(std::count_if(c.raw.begin(), c.raw.end(), out_raw));
    clipped_pvt = static_cast<std::uint64_t>(std::count_if(c.pvt.begin(), c.pvt.end(), out_pvt));
    c.raw.erase(std::remove_if(c.raw.begin(), c.raw.end(), out_raw), c.raw.end());
    c.pvt.erase(std::remove_if(c.pvt.begin(), c.pvt.end(), out_pvt), c.pvt.end());
    st.gnss.pvt = c.pvt;
  }
  if (d.reference.present) {
    st.ref = read_reference(d.reference, &st.gnss, ts, st.ctx);
    c.truth = st.ref.epochs;
  }
  nlohmann::json alm_json = nullptr;
  if (!c.raw.empty()) {
    const GpsTime first{c.raw.front().gps_week, c.raw.front().gps_tow_s};
    alm_json = almanacs_from_ephemeris(st.raw.ephs, rc.prns, first, c.raw.front().t_s,
                                       c.raw.back().t_s - c.raw.front().t_s, d.max_fit_error_m, c.almanacs);
  }

  nlohmann::json sum = streams_summary(d, opt, st, c, rc, week0, clipped_raw, clipped_pvt, alm_json);
  sum["log"] = write_log(opt.log_path, c);
  sum["rejected_lines_total"] = total_rejected(sum);

  const std::string filter_path =
      !opt.write_filter_config ? std::string()
      : d.filter_config_out.empty() ? fs::path(opt.log_path).replace_extension(".filter.toml").string()
                                    : d.filter_config_out;
  finish_import_outputs(sum, opt.log_path, filter_path, d.name.empty() ? fs::path(opt.log_path).stem().string() : d.name,
                        d.format, opt.write_sidecar);
  return sum;
}

}  // namespace tools
