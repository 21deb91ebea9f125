// Readers of recorded data (RTKLIB .pos/.tag, GNSS_IMU CSV, PSINS CSV, RINEX 3) and the
// conversions into the project's inputs; the import drivers are in import_recording.cpp.
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "hal/input_file.hpp"
#include "hal/time_tag_gate.hpp"
#include "import_util.hpp"
#include "tools/importers.hpp"

namespace tools {

// ---------------------------------------------------------------------------------------------
// Parsing helpers (import_util.hpp)

namespace import_util {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> split(std::string_view s, char sep) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  for (;;) {
    const std::size_t p = s.find(sep, start);
    if (p == std::string_view::npos) {
      out.push_back(s.substr(start));
      return out;
    }
    out.push_back(s.substr(start, p - start));
    start = p + 1;
  }
}

std::vector<std::string_view> split_ws(std::string_view s) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t' || s[i] == '\r')) ++i;
    const std::size_t b = i;
    while (i < s.size() && s[i] != ' ' && s[i] != '\t' && s[i] != '\r') ++i;
    if (i > b) out.push_back(s.substr(b, i - b));
  }
  return out;
}

bool parse_double(std::string_view s, double& v) {
  s = trim(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty()) return false;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

bool parse_int(std::string_view s, std::int64_t& v) {
  s = trim(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty()) return false;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

bool to_int(double v, int& out) {
  if (!std::isfinite(v) || v != std::floor(v) || std::abs(v) > 1e9) return false;
  out = static_cast<int>(v);
  return true;
}

bool parse_fortran_double(std::string_view s, double& v) {
  std::string t(trim(s));
  for (char& c : t)
    if (c == 'D' || c == 'd') c = 'E';
  return parse_double(t, v);
}

bool getline_counted(std::istream& in, std::string& line, bool& terminated) {
  // std::getline with a bound (docs/faults.md): a line longer than hal::kMaxInputLineBytes keeps
  // its first kMaxInputLineBytes bytes (the rest is read and dropped), so it fails to parse and
  // is counted as a bad line instead of growing memory without limit.
  line.clear();
  if (!in.good()) return false;
  std::streambuf* sb = in.rdbuf();
  bool any = false;
  for (;;) {
    const int c = sb->sbumpc();
    if (c == std::char_traits<char>::eof()) {
      in.setstate(std::ios::eofbit);
      terminated = false;
      return any;
    }
    any = true;
    if (c == '\n') {
      terminated = true;
      return true;
    }
    if (line.size() < hal::kMaxInputLineBytes) line.push_back(static_cast<char>(c));
  }
}

std::vector<std::uint8_t> read_file_bytes(const std::string& path) {
  const std::string bad = hal::check_input_file(path, hal::kMaxTextInputBytes);
  if (!bad.empty()) throw std::runtime_error(bad);
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error("cannot read " + path);
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

}  // namespace import_util

using namespace import_util;

// ---------------------------------------------------------------------------------------------
// Time

namespace {

/// Days from 1970-01-01 to a proleptic Gregorian date (H. Hinnant's days_from_civil).
std::int64_t days_from_civil(std::int64_t y, unsigned m, unsigned d) {
  y -= m <= 2 ? 1 : 0;
  const std::int64_t era = (y >= 0 ? y : y - 399) / 400;
  const unsigned yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + static_cast<std::int64_t>(doe) - 719468;
}

}  // namespace

GpsTime gps_time_from_count(std::int64_t count, std::int64_t per_second, double fraction_s) {
  const std::int64_t per_week = static_cast<std::int64_t>(fsw::kSecondsPerWeek) * per_second;
  std::int64_t week = count / per_week;
  std::int64_t rem = count - week * per_week;
  if (rem < 0) {
    rem += per_week;
    --week;
  }
  // 1.0 / per_second is the double nearest 1/per_second (1e-6 for microseconds), exact for seconds.
  return fsw::gps_time(static_cast<int>(week), static_cast<double>(rem) * (1.0 / static_cast<double>(per_second)) + fraction_s);
}

GpsTime gps_time_from_gtime(std::int64_t seconds, double fraction_s) {
  return gps_time_from_count(seconds - kGpsEpochGtime_s, 1, fraction_s);
}

bool gps_time_from_calendar(int year, int month, int day, int hour, int minute, double second, GpsTime& out) {
  static const int kDays[] = {31, 29, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  if (month < 1 || month > 12 || day < 1 || day > kDays[month - 1] || hour < 0 || hour > 23 || minute < 0 ||
      minute > 59 || !(second >= 0.0) || !(second < 61.0) || year < 1980 || year > 2200)
    return false;
  const bool leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
  if (month == 2 && day == 29 && !leap) return false;
  const std::int64_t days = days_from_civil(year, static_cast<unsigned>(month), static_cast<unsigned>(day));
  const std::int64_t gps_day0 = days_from_civil(1980, 1, 6);
  const double whole = std::floor(second);
  const std::int64_t secs = (days - gps_day0) * 86400 + hour * 3600 + minute * 60 + static_cast<std::int64_t>(whole);
  if (secs < 0) return false;
  out = gps_time_from_count(secs, 1, second - whole);
  return true;
}

// ---------------------------------------------------------------------------------------------
// LineStats

void LineStats::reject(std::uint64_t line, const std::string& reason) {
  ++rejected;
  ++by_reason[reason];
  if (examples.size() < kMaxExamples) examples.emplace_back(line, reason);
}

void LineStats::skip(const std::string& reason) { ++skipped[reason]; }

nlohmann::json LineStats::to_json() const {
  nlohmann::json ex = nlohmann::json::array();
  for (const auto& [line, reason] : examples) ex.push_back({{"line", line}, {"reason", reason}});
  nlohmann::json j = {{"lines", lines},         {"accepted", accepted}, {"rejected", rejected},
                      {"rejected_by_reason", by_reason}, {"rejected_examples", ex}, {"skipped", skipped}};
  if (time_base_changes > 0)
    j["time_base_changes"] = {{"count", time_base_changes}, {"last_jump", last_time_jump}, {"last_line", last_time_jump_line}};
  return j;
}


// ---------------------------------------------------------------------------------------------
// Time tags

namespace {
std::uint32_t le32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}
}  // namespace

TimeTag parse_time_tag(const std::vector<std::uint8_t>& b) {
  if (b.size() < TimeTag::kHeaderBytes)
    throw std::runtime_error("time-tag file too short (" + std::to_string(b.size()) + " bytes, header is 76)");
  TimeTag t;
  std::string label(reinterpret_cast<const char*>(b.data()), TimeTag::kHeaderTextBytes);
  label = label.substr(0, label.find('\0'));
  while (!label.empty() && label.back() == ' ') label.pop_back();
  if (label.rfind("TIMETAG", 0) != 0) throw std::runtime_error("not an RTKLIB time-tag file (no TIMETAG header)");
  t.label = label;
  t.tick_f = le32(b.data() + 60);
  t.start_gtime_s = le32(b.data() + 64);
  std::uint64_t bits = 0;
  for (int i = 7; i >= 0; --i) bits = (bits << 8) | b[68 + static_cast<std::size_t>(i)];
  std::memcpy(&t.start_fraction_s, &bits, sizeof(double));
  if (!(t.start_fraction_s >= 0.0 && t.start_fraction_s < 1.0))
    throw std::runtime_error("time-tag start fraction out of [0, 1): " + std::to_string(t.start_fraction_s));
  const std::size_t n = (b.size() - TimeTag::kHeaderBytes) / TimeTag::kRecordBytes;
  t.trailing_bytes = (b.size() - TimeTag::kHeaderBytes) % TimeTag::kRecordBytes;
  t.records.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* p = b.data() + TimeTag::kHeaderBytes + i * TimeTag::kRecordBytes;
    TimeTagRecord r{le32(p), le32(p + 4)};
    if (!t.records.empty() && (r.tick_ms < t.records.back().tick_ms || r.offset < t.records.back().offset))
      ++t.non_monotonic;
    t.records.push_back(r);
  }
  return t;
}

TimeTag read_time_tag(const std::string& path) {
  try {
    return parse_time_tag(read_file_bytes(path));
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
}

// ---------------------------------------------------------------------------------------------
// RTKLIB .pos

namespace {

bool parse_pos_time(std::string_view a, std::string_view b, GpsTime& t) {
  if (a.find('/') != std::string_view::npos) {
    const auto d = split(a, '/');
    const auto c = split(b, ':');
    std::int64_t y = 0, mo = 0, dd = 0, hh = 0, mi = 0;
    double ss = 0.0;
    if (d.size() != 3 || c.size() != 3 || !parse_int(d[0], y) || !parse_int(d[1], mo) || !parse_int(d[2], dd) ||
        !parse_int(c[0], hh) || !parse_int(c[1], mi) || !parse_double(c[2], ss))
      return false;
    return gps_time_from_calendar(static_cast<int>(y), static_cast<int>(mo), static_cast<int>(dd), static_cast<int>(hh),
                                  static_cast<int>(mi), ss, t);
  }
  std::int64_t w = 0;
  double tow = 0.0;
  if (!parse_int(a, w) || !parse_double(b, tow) || w < 0 || !(tow >= 0.0) || tow >= fsw::kSecondsPerWeek) return false;
  t.week = static_cast<int>(w);
  t.tow_s = tow;
  return true;
}

/// Data-token indices of the .pos columns (the time takes data tokens 0 and 1), from the column
/// header; -1 for a column it does not have.
struct PosColumns {
  int lat = -1, lon = -1, h = -1, q = -1, ns = -1, sdn = -1, sde = -1, sdu = -1;
  int vn = -1, ve = -1, vu = -1, sdvn = -1, sdve = -1, sdvu = -1;
  std::size_t n_tokens = 0;  ///< data tokens of a line
  bool has_velocity() const { return vn >= 0 && ve >= 0 && vu >= 0 && sdvn >= 0 && sdve >= 0 && sdvu >= 0; }
};

/// Reads a '%' comment line (without the '%') as the column header: false when it is another
/// comment. A header is read whole into cols: no column index of an earlier header may survive
/// into a layout with fewer columns (found by fuzz_importers: an out-of-range read). Throws for
/// a layout other than GPST latitude/longitude/height or one without the columns needed.
bool read_pos_header(std::string_view comment, PosColumns& cols) {
  const auto tok = split_ws(comment);
  if (tok.size() < 4 || !(tok[1].find("latitude") == 0 || tok[1].find("x-ecef") == 0 || tok[1].find("e-baseline") == 0))
    return false;
  if (tok[1] != "latitude(deg)")
    throw std::runtime_error("RTKLIB .pos with positions as '" + std::string(tok[1]) +
                             "': only latitude(deg)/longitude(deg)/height(m) is supported (rnx2rtkp -a off, "
                             "out-solformat llh, degrees)");
  if (tok[0] != "GPST")
    throw std::runtime_error("RTKLIB .pos time system '" + std::string(tok[0]) + "': only GPST is supported (out-timesys gpst)");
  // The header's name of each column read; any other column is passed over.
  static constexpr std::pair<std::string_view, int PosColumns::*> kNames[] = {
      {"latitude(deg)", &PosColumns::lat}, {"longitude(deg)", &PosColumns::lon}, {"height(m)", &PosColumns::h},
      {"Q", &PosColumns::q},               {"ns", &PosColumns::ns},              {"sdn(m)", &PosColumns::sdn},
      {"sde(m)", &PosColumns::sde},        {"sdu(m)", &PosColumns::sdu},         {"vn(m/s)", &PosColumns::vn},
      {"ve(m/s)", &PosColumns::ve},        {"vu(m/s)", &PosColumns::vu},         {"sdvn", &PosColumns::sdvn},
      {"sdve", &PosColumns::sdve},         {"sdvu", &PosColumns::sdvu}};
  PosColumns c;
  // Header token k (k >= 1) is data token k + 1: the time is two data tokens.
  for (std::size_t k = 1; k < tok.size(); ++k)
    for (const auto& [name, column] : kNames)
      if (tok[k] == name) c.*column = static_cast<int>(k) + 1;
  c.n_tokens = tok.size() + 1;
  if (c.lat < 0 || c.lon < 0 || c.h < 0 || c.q < 0 || c.ns < 0 || c.sdn < 0 || c.sde < 0 || c.sdu < 0)
    throw std::runtime_error("RTKLIB .pos column header lacks one of latitude, longitude, height, Q, ns, sdn, sde, sdu");
  cols = c;
  return true;
}

/// One data line (its tokens) as a solution at time t: "" when it is one, else why the line is
/// rejected. The solution passes the GNSS_PVT reader's own validation (t_s is set later).
std::string pos_solution(const std::vector<std::string_view>& tok, const PosColumns& c, GpsTime& t,
                         hal::GnssPvtSample& p) {
  if (tok.size() != c.n_tokens) return "wrong field count";
  if (!parse_pos_time(tok[0], tok[1], t)) return "bad time";
  std::vector<double> v(tok.size(), 0.0);
  bool ok = true;
  for (std::size_t k = 2; k < tok.size() && ok; ++k) ok = parse_double(tok[k], v[k]);
  if (!ok) return "unparsable number";
  bool finite = true;
  for (std::size_t k = 2; k < tok.size(); ++k) finite = finite && std::isfinite(v[k]);
  if (!finite) return "non-finite value";
  const auto at = [&v](int i) { return v[static_cast<std::size_t>(i)]; };
  p.gps_week = t.week;
  p.gps_tow_s = t.tow_s;
  p.llh = fsw::Vec3(at(c.lat) * fsw::kDegToRad, at(c.lon) * fsw::kDegToRad, at(c.h));
  p.pos_sigma_enu_m = fsw::Vec3(at(c.sde), at(c.sdn), at(c.sdu));
  if (c.has_velocity()) {
    p.vel_enu_mps = fsw::Vec3(at(c.ve), at(c.vn), at(c.vu));
    p.vel_sigma_enu_mps = fsw::Vec3(at(c.sdve), at(c.sdvn), at(c.sdvu));
  } else {
    p.vel_sigma_enu_mps = fsw::Vec3::Constant(hal::kGnssPvtNoVelocity);
  }
  const double q = at(c.q), ns = at(c.ns);
  if (q != std::floor(q) || ns != std::floor(ns) || std::abs(q) > 1e6 || std::abs(ns) > 1e6) return "Q or ns not an integer";
  p.quality = static_cast<int>(q);
  p.n_sat = static_cast<int>(ns);
  sdins::gnss_pvt_t m{};
  hal::to_msg(p, m);
  hal::GnssPvtSample check;
  const hal::LcmInputStatus st = hal::from_msg(m, check);
  if (st != hal::LcmInputStatus::kOk) return std::string("implausible solution (GNSS_PVT validation: ") + hal::to_string(st) + ")";
  return "";
}

}  // namespace

PosFile read_rtklib_pos(std::istream& in) {
  PosFile out;
  std::string line;
  bool terminated = true;
  std::uint64_t line_no = 0;
  PosColumns cols;
  bool have_header = false;
  bool have_prev = false;
  GpsTime prev;  // the first line's time: the gate's origin
  struct PosRow {
    std::uint64_t line;
    hal::GnssPvtSample sample;
  };
  std::vector<PosRow> rows;
  // Solutions at a few Hz; a step of more than 600 s (or any step back) is a jump.
  LineTimeGate<PosRow> gate(out.lines, rows, gate_config(600.0, 0.0, true));
  while (getline_counted(in, line, terminated)) {
    ++line_no;
    const std::string_view s = trim(line);
    if (s.empty()) continue;
    if (s.front() == '%') {
      if (read_pos_header(s.substr(1), cols)) {
        out.time_system = "GPST";
        out.has_velocity = cols.has_velocity();
        have_header = true;
      }
      continue;
    }
    if (!have_header)
      throw std::runtime_error("RTKLIB .pos: data before the column header ('%  GPST latitude(deg) ...') at line " +
                               std::to_string(line_no));
    ++out.lines.lines;
    if (!terminated) {
      out.lines.reject(line_no, "partial last line (no newline)");
      continue;
    }
    GpsTime t;
    hal::GnssPvtSample p;
    const std::string why = pos_solution(split_ws(s), cols, t, p);
    if (!why.empty()) {
      out.lines.reject(line_no, why);
      continue;
    }
    // Time order through the time-tag gate (docs/faults.md): seconds since the first line's week.
    if (!have_prev) prev = t;
    have_prev = true;
    gate.push(static_cast<double>(t.week - prev.week) * fsw::kSecondsPerWeek + t.tow_s, PosRow{line_no, p});
  }
  gate.finish();
  for (PosRow& r : rows) out.samples.push_back(r.sample);
  if (!have_header) throw std::runtime_error("not an RTKLIB .pos file: no column header ('%  GPST latitude(deg) ...')");
  return out;
}

// ---------------------------------------------------------------------------------------------
// GNSS_IMU CSV

std::vector<ImuCsvSample> read_gnss_imu_csv(std::istream& in, LineStats& stats, const ImuCsvLimits& limits) {
  std::vector<ImuCsvSample> out;
  // Ticks in ms, strictly increasing; a step of more than 1 s either way is a jump.
  LineTimeGate<ImuCsvSample> gate(stats, out, gate_config(1000.0, 1000.0, true));
  std::string line;
  bool terminated = true;
  std::uint64_t line_no = 0;
  while (getline_counted(in, line, terminated)) {
    ++line_no;
    const std::string_view s = trim(line);
    if (!take_data_line(stats, line_no, s, terminated)) continue;
    const auto f = split(s, ',');
    if (f.size() != 7) {
      stats.reject(line_no, "wrong field count (" + std::to_string(f.size()) + ", expected 7)");
      continue;
    }
    ImuCsvSample smp;
    smp.line = line_no;
    bool ok = true;
    for (int i = 0; i < 3 && ok; ++i) ok = parse_double(f[static_cast<std::size_t>(i)], smp.accel_g[i]);
    for (int i = 0; i < 3 && ok; ++i) ok = parse_double(f[static_cast<std::size_t>(3 + i)], smp.gyro_dps[i]);
    if (ok) ok = parse_int(f[6], smp.tick_ms);
    if (!ok) {
      stats.reject(line_no, "unparsable number");
      continue;
    }
    bool finite = true, in_range = true;
    for (int i = 0; i < 3; ++i) {
      finite = finite && std::isfinite(smp.accel_g[i]) && std::isfinite(smp.gyro_dps[i]);
      in_range = in_range && std::abs(smp.accel_g[i]) <= limits.max_accel_g && std::abs(smp.gyro_dps[i]) <= limits.max_gyro_dps;
    }
    if (!finite) {
      stats.reject(line_no, "non-finite value");
      continue;
    }
    if (!in_range) {
      stats.reject(line_no, "value beyond the sensor range");
      continue;
    }
    gate.push(static_cast<double>(smp.tick_ms), smp);
  }
  gate.finish();
  return out;
}

TickToGps tick_to_gps(const TimeTag& tag, const std::vector<ImuCsvSample>& samples) {
  if (samples.size() < 2) throw std::runtime_error("fewer than two usable IMU samples");
  if (tag.records.empty()) throw std::runtime_error("time-tag file without records");
  TickToGps m;
  m.start = tag.start();
  m.tick0_ms = samples.front().tick_ms;
  m.seconds_per_tick = tag.last_tick_s() / static_cast<double>(samples.back().tick_ms - samples.front().tick_ms);
  return m;
}

// ---------------------------------------------------------------------------------------------
// Axes

std::string AxisMap::text() const {
  std::string s;
  for (int i = 0; i < 3; ++i) {
    if (i > 0) s += ',';
    if (sign[static_cast<std::size_t>(i)] < 0.0) s += '-';
    s += static_cast<char>('x' + src[static_cast<std::size_t>(i)]);
  }
  return s;
}

fsw::Mat3 AxisMap::matrix() const {
  fsw::Mat3 c = fsw::Mat3::Zero();
  for (int i = 0; i < 3; ++i) c(i, src[static_cast<std::size_t>(i)]) = sign[static_cast<std::size_t>(i)];
  return c;
}

AxisMap parse_axis_map(const std::string& text) {
  const auto terms = split(text, ',');
  if (terms.size() != 3)
    throw std::runtime_error("axis map '" + text + "': three comma-separated terms expected (body x, y, z), e.g. -x,y,-z");
  AxisMap m;
  bool used[3] = {false, false, false};
  for (std::size_t i = 0; i < 3; ++i) {
    std::string_view t = trim(terms[i]);
    double sg = 1.0;
    if (!t.empty() && (t.front() == '-' || t.front() == '+')) {
      sg = t.front() == '-' ? -1.0 : 1.0;
      t.remove_prefix(1);
    }
    if (t.size() != 1 || t[0] < 'x' || t[0] > 'z')
      throw std::runtime_error("axis map '" + text + "': term '" + std::string(terms[i]) + "' is not [+-]x, y or z");
    const int a = t[0] - 'x';
    if (used[a]) throw std::runtime_error("axis map '" + text + "': sensor axis " + std::string(1, t[0]) + " used twice");
    used[a] = true;
    m.src[i] = a;
    m.sign[i] = sg;
  }
  if (m.matrix().determinant() < 0.0)
    throw std::runtime_error("axis map '" + text +
                             "' is a reflection (determinant -1): it would turn the right-handed sensor frame into a "
                             "left-handed body frame; flip the sign of one term");
  return m;
}

std::vector<hal::ImuRecord> increments_from_rates(const std::vector<RateSample>& s) {
  std::vector<hal::ImuRecord> out;
  if (s.size() < 2) return out;
  out.reserve(s.size() - 1);
  for (std::size_t k = 1; k < s.size(); ++k) {
    const double dt = s[k].t_s - s[k - 1].t_s;
    hal::ImuRecord r;
    r.sample.t_s = s[k].t_s;
    r.sample.dt_s = dt;
    r.sample.dtheta_rad = 0.5 * (s[k - 1].omega_radps + s[k].omega_radps) * dt;
    r.sample.dv_mps = 0.5 * (s[k - 1].f_mps2 + s[k].f_mps2) * dt;
    r.counter = s[k].counter;
    out.push_back(r);
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// PSINS

namespace {

/// Reads a CSV with one header line; calls row(line_no, fields) for each data line.
template <class F>
void read_csv_rows(std::istream& in, LineStats& stats, std::string& header, F&& row) {
  std::string line;
  bool terminated = true;
  std::uint64_t line_no = 0;
  bool have_header = false;
  while (getline_counted(in, line, terminated)) {
    ++line_no;
    const std::string_view s = trim(line);
    if (!have_header) {
      header = std::string(s);
      have_header = true;
      continue;
    }
    if (!take_data_line(stats, line_no, s, terminated)) continue;
    row(line_no, split(s, ','));
  }
}

/// The PSINS CSVs start with a header of column names: a first line that starts with a number is data.
void require_header(const std::string& header, const char* what) {
  if (header.empty() || !std::isalpha(static_cast<unsigned char>(header[0])))
    throw std::runtime_error(std::string(what) + ": the first line must be the header of column names");
}

/// A CSV row of exactly n numbers into v; false (and the row rejected with the reason) otherwise.
bool parse_number_row(const std::vector<std::string_view>& f, std::size_t n, double* v, LineStats& stats,
                      std::uint64_t ln) {
  if (f.size() != n) {
    stats.reject(ln, "wrong field count (" + std::to_string(f.size()) + ", expected " + std::to_string(n) + ")");
    return false;
  }
  for (std::size_t i = 0; i < n; ++i)
    if (!parse_double(f[i], v[i])) {
      stats.reject(ln, "unparsable number");
      return false;
    }
  return true;
}

}  // namespace

std::vector<PsinsImuRow> read_psins_imu(std::istream& in, LineStats& stats) {
  std::vector<PsinsImuRow> out;
  LineTimeGate<PsinsImuRow> gate(stats, out, gate_config(1.0, 1.0, true));  // tow [s], 200 Hz
  std::string header;
  read_csv_rows(in, stats, header, [&](std::uint64_t ln, const std::vector<std::string_view>& f) {
    double v[7];
    if (!parse_number_row(f, 7, v, stats, ln)) return;
    for (double x : v)
      if (!std::isfinite(x)) {
        stats.reject(ln, "non-finite value");
        return;
      }
    if (v[0] < 0.0 || v[0] >= fsw::kSecondsPerWeek) {
      stats.reject(ln, "time of week out of range");
      return;
    }
    PsinsImuRow r;
    r.tow_s = v[0];
    r.dtheta_rad = fsw::Vec3(v[1], v[2], v[3]);
    r.dv_mps = fsw::Vec3(v[4], v[5], v[6]);
    r.line = ln;
    gate.push(r.tow_s, r);
  });
  gate.finish();
  require_header(header, "PSINS IMU CSV");
  return out;
}

std::vector<PsinsObsRow> read_psins_obs(std::istream& in, LineStats& stats) {
  std::vector<PsinsObsRow> out;
  // Several rows per epoch (equal times); a step of more than 600 s or any step back is a jump.
  LineTimeGate<PsinsObsRow> gate(stats, out, gate_config(600.0, 0.0, false));
  std::string header;
  read_csv_rows(in, stats, header, [&](std::uint64_t ln, const std::vector<std::string_view>& f) {
    double v[6];
    if (!parse_number_row(f, 6, v, stats, ln)) return;
    // Column 5 (undocumented) is not used: NaN there does not matter.
    if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]) || !std::isfinite(v[3]) ||
        !std::isfinite(v[5])) {
      stats.reject(ln, "non-finite value");
      return;
    }
    if (v[1] != std::floor(v[1]) || v[1] < 1 || v[1] > fsw::kMaxGpsPrn) {
      stats.reject(ln, "PRN outside 1..32");
      return;
    }
    if (v[2] < 1e7 || v[2] > 5e7) {
      stats.reject(ln, "pseudorange outside 1e7..5e7 m");
      return;
    }
    if (v[0] < 0.0 || v[0] >= fsw::kSecondsPerWeek) {
      stats.reject(ln, "time of week out of range");
      return;
    }
    PsinsObsRow r;
    r.tow_s = v[0];
    r.prn = static_cast<int>(v[1]);
    r.pseudorange_m = v[2];
    r.carrier_m = v[3];
    r.doppler_mps = v[5];
    r.line = ln;
    gate.push(r.tow_s, r);
  });
  gate.finish();
  require_header(header, "PSINS GPS observation CSV");
  return out;
}

std::vector<GpsEphemeris> read_psins_eph(std::istream& in, LineStats& stats) {
  std::vector<GpsEphemeris> out;
  std::string header;
  std::vector<std::string> names;
  const auto col = [&](const char* n) -> int {
    for (std::size_t i = 0; i < names.size(); ++i)
      if (names[i] == n) return static_cast<int>(i);
    return -1;
  };
  const char* kRequired[] = {"PRN", "Toc", "af0",   "af1", "af2",   "IODE",     "Crs",  "Deltan", "M0",
                             "Cuc", "e",   "Cus",   "sqrtA", "Toe", "Cic",      "OMEGA0", "Cis", "i0",
                             "Crc", "omega", "OMEGADot", "iDot", "WN", "SatHl", "TGD"};
  read_csv_rows(in, stats, header, [&](std::uint64_t ln, const std::vector<std::string_view>& f) {
    if (names.empty()) {
      for (auto h : split(header, ',')) names.emplace_back(trim(h));
      for (const char* r : kRequired)
        if (col(r) < 0) throw std::runtime_error(std::string("PSINS ephemeris CSV: no column '") + r + "' in the header");
    }
    if (f.size() != names.size()) {
      stats.reject(ln, "wrong field count (" + std::to_string(f.size()) + ", expected " + std::to_string(names.size()) + ")");
      return;
    }
    const auto get = [&](const char* n, double& v) { return parse_double(f[static_cast<std::size_t>(col(n))], v); };
    double v[25];
    for (int i = 0; i < 25; ++i)
      if (!get(kRequired[i], v[i])) {
        stats.reject(ln, std::string("unparsable ") + kRequired[i]);
        return;
      }
    GpsEphemeris e;
    if (!to_int(v[0], e.prn) || !to_int(v[5], e.iode) || !to_int(v[22], e.week) || !to_int(v[23], e.health)) {
      stats.reject(ln, "PRN, IODE, WN or SatHl not an integer");
      return;
    }
    e.toc_s = v[1];
    e.af0_s = v[2];
    e.af1_sps = v[3];
    e.af2_sps2 = v[4];
    e.crs_m = v[6];
    e.delta_n_radps = v[7];
    e.m0_rad = v[8];
    e.cuc_rad = v[9];
    e.eccentricity = v[10];
    e.cus_rad = v[11];
    e.sqrt_a_sqrtm = v[12];
    e.toe_s = v[13];
    e.cic_rad = v[14];
    e.omega0_rad = v[15];
    e.cis_rad = v[16];
    e.i0_rad = v[17];
    e.crc_m = v[18];
    e.arg_perigee_rad = v[19];
    e.omega_dot_radps = v[20];
    e.idot_radps = v[21];
    e.tgd_s = std::isfinite(v[24]) ? v[24] : 0.0;
    if (e.health == 255 && e.sqrt_a_sqrtm == 0.0) {
      stats.skip("absent satellite (health 255, no elements)");
      return;
    }
    if (!ephemeris_valid(e)) {
      stats.reject(ln, "implausible ephemeris");
      return;
    }
    ++stats.accepted;
    out.push_back(e);
  });
  require_header(header, "PSINS ephemeris CSV");
  return out;
}

// ---------------------------------------------------------------------------------------------
// RINEX 3

namespace {

std::string_view label_of(std::string_view line) { return line.size() > 60 ? trim(line.substr(60)) : std::string_view(); }

std::string_view field(std::string_view line, std::size_t pos, std::size_t len) {
  if (pos >= line.size()) return {};
  return line.substr(pos, std::min(len, line.size() - pos));
}

/// The observation types of each system in the order of their columns (SYS / # / OBS TYPES).
struct RinexObsTypes {
  std::map<char, std::vector<std::string>> by_sys;
  /// The column of observation type t of system sys, -1 when the file has none.
  int index(char sys, const char* t) const {
    const auto it = by_sys.find(sys);
    if (it == by_sys.end()) return -1;
    for (std::size_t i = 0; i < it->second.size(); ++i)
      if (it->second[i] == t) return static_cast<int>(i);
    return -1;
  }
};

/// Reads the header through END OF HEADER (ln counts the lines read): the version into st, the
/// observation types returned. Throws for a file that is not RINEX 3 observations.
RinexObsTypes read_rinex3_obs_header(std::istream& in, std::uint64_t& ln, RinexObsStats& st) {
  RinexObsTypes types;
  std::string line;
  bool terminated = true;
  char cont_sys = 0;
  int cont_left = 0;
  bool header_done = false;
  while (!header_done && getline_counted(in, line, terminated)) {
    ++ln;
    const std::string_view lab = label_of(line);
    if (lab == "RINEX VERSION / TYPE") {
      st.version = std::string(trim(field(line, 0, 9)));
      if (st.version.empty() || st.version[0] != '3' || field(line, 20, 1) != "O")
        throw std::runtime_error("not a RINEX 3 observation file (version '" + st.version + "', type '" +
                                 std::string(field(line, 20, 1)) + "')");
    } else if (lab == "SYS / # / OBS TYPES") {
      std::size_t start = 7;
      if (line[0] != ' ') {
        cont_sys = line[0];
        std::int64_t n = 0;
        if (!parse_int(field(line, 3, 3), n)) throw std::runtime_error("RINEX obs: bad SYS / # / OBS TYPES line " + std::to_string(ln));
        cont_left = static_cast<int>(n);
      }
      for (int k = 0; k < 13 && cont_left > 0; ++k, --cont_left)
        types.by_sys[cont_sys].emplace_back(trim(field(line, start + 4 * static_cast<std::size_t>(k), 3)));
    } else if (lab == "END OF HEADER") {
      header_done = true;
    }
  }
  if (!header_done) throw std::runtime_error("RINEX obs: no END OF HEADER");
  if (st.version.empty()) throw std::runtime_error("RINEX obs: no RINEX VERSION / TYPE line");
  if (types.index('G', "C1C") < 0) throw std::runtime_error("RINEX obs: no GPS C1C observations in the header");
  return types;
}

/// One satellite line of an epoch (complete, with its newline) as s: nullptr when it is one, else
/// why the line is rejected. An observation the file has no column for, or left blank, is absent.
const char* rinex_obs_satellite(const std::string& line, const RinexObsTypes& types, RinexObsSat& s) {
  if (line.size() < 3) return "short satellite line";
  s.sys = line[0];
  std::int64_t prn = 0;
  if (!parse_int(field(line, 1, 2), prn)) return "bad satellite id";
  s.prn = static_cast<int>(prn);
  const auto get = [&](const char* t, double& v, bool& has) {
    const int i = types.index(s.sys, t);
    has = false;
    if (i < 0) return true;
    const std::string_view f = trim(field(line, 3 + 16 * static_cast<std::size_t>(i), 14));
    if (f.empty()) return true;
    has = parse_double(f, v) && std::isfinite(v);
    return has;
  };
  const bool ok = get("C1C", s.c1c_m, s.has_c1c) & get("D1C", s.d1c_hz, s.has_d1c) & get("S1C", s.s1c_dbhz, s.has_s1c);
  return ok ? nullptr : "unparsable observation";
}

}  // namespace

std::vector<RinexObsEpoch> read_rinex3_obs(std::istream& in, RinexObsStats& st) {
  std::vector<RinexObsEpoch> out;
  // Epoch times through the time-tag gate (docs/faults.md): more than 600 s ahead or any step
  // back is a jump; a lone one costs its epoch only.
  struct ObsRow {
    std::uint64_t line;
    RinexObsEpoch ep;
  };
  std::vector<ObsRow> rows;
  LineTimeGate<ObsRow> gate(st.lines, rows, gate_config(600.0, 0.0, true));
  bool have_week0 = false;
  int week0 = 0;
  std::uint64_t ln = 0;
  const RinexObsTypes types = read_rinex3_obs_header(in, ln, st);
  std::string line;
  bool terminated = true;
  while (getline_counted(in, line, terminated)) {
    ++ln;
    if (line.empty() || line[0] != '>') {
      if (!trim(line).empty()) {
        ++st.lines.lines;
        st.lines.reject(ln, "line outside an epoch");
      }
      continue;
    }
    ++st.lines.lines;
    const std::uint64_t epoch_line = ln;
    int y = 0, mo = 0, d = 0, h = 0, mi = 0, flag = 0, nsat = 0;
    double sec = 0.0;
    if (std::sscanf(line.c_str(), "> %d %d %d %d %d %lf %d %d", &y, &mo, &d, &h, &mi, &sec, &flag, &nsat) != 8 ||
        nsat < 0 || nsat > 999) {
      st.lines.reject(ln, "bad epoch line");
      continue;
    }
    RinexObsEpoch ep;
    const bool time_ok = gps_time_from_calendar(y, mo, d, h, mi, sec, ep.time);
    const bool event = flag > 1;
    bool epoch_ok = time_ok && terminated;
    if (!time_ok) st.lines.reject(ln, "bad epoch time");
    for (int k = 0; k < nsat; ++k) {
      if (!getline_counted(in, line, terminated)) break;
      ++ln;
      if (event) continue;
      ++st.lines.lines;
      if (!terminated) {
        st.lines.reject(ln, "partial last line (no newline)");
        epoch_ok = false;
        continue;
      }
      RinexObsSat s;
      if (const char* why = rinex_obs_satellite(line, types, s)) {
        st.lines.reject(ln, why);
        continue;
      }
      ++st.lines.accepted;
      ep.sats.push_back(s);
    }
    if (event) {
      ++st.event_epochs;
      st.lines.skip("event epoch (flag > 1)");
      continue;
    }
    if (!epoch_ok) continue;
    if (!have_week0) week0 = ep.time.week;
    have_week0 = true;
    const double t = static_cast<double>(ep.time.week - week0) * fsw::kSecondsPerWeek + ep.time.tow_s;
    gate.push(t, ObsRow{epoch_line, std::move(ep)});
  }
  gate.finish();
  out.reserve(rows.size());
  for (ObsRow& r : rows) out.push_back(std::move(r.ep));
  return out;
}

std::vector<GpsEphemeris> read_rinex3_nav(std::istream& in, LineStats& stats) {
  std::vector<GpsEphemeris> out;
  std::string line;
  bool terminated = true;
  std::uint64_t ln = 0;
  bool header_done = false;
  std::string version;
  while (!header_done && getline_counted(in, line, terminated)) {
    ++ln;
    const std::string_view lab = label_of(line);
    if (lab == "RINEX VERSION / TYPE") {
      version = std::string(trim(field(line, 0, 9)));
      if (version.empty() || version[0] != '3' || field(line, 20, 1) != "N")
        throw std::runtime_error("not a RINEX 3 navigation file (version '" + version + "', type '" +
                                 std::string(field(line, 20, 1)) + "')");
    } else if (lab == "END OF HEADER") {
      header_done = true;
    }
  }
  if (!header_done || version.empty()) throw std::runtime_error("RINEX nav: no header");

  // A record: a line starting with the system letter, then continuation lines starting with spaces.
  std::vector<std::string> rec;
  std::uint64_t rec_line = 0;
  bool rec_complete = true;
  const auto flush = [&]() {
    if (rec.empty()) return;
    ++stats.lines;
    const char sys = rec[0][0];
    if (sys != 'G') {
      stats.skip(std::string("other system (") + sys + ")");
      rec.clear();
      return;
    }
    if (!rec_complete || rec.size() < 8) {
      stats.reject(rec_line, "incomplete GPS record");
      rec.clear();
      return;
    }
    double v[32] = {};
    bool ok = true;
    int y = 0, mo = 0, d = 0, h = 0, mi = 0;
    double s = 0.0;
    std::int64_t prn = 0;
    ok = parse_int(field(rec[0], 1, 2), prn) &&
         std::sscanf(std::string(field(rec[0], 3, 20)).c_str(), "%d %d %d %d %d %lf", &y, &mo, &d, &h, &mi, &s) == 6;
    for (int k = 0; k < 3 && ok; ++k) ok = parse_fortran_double(field(rec[0], 23 + 19 * static_cast<std::size_t>(k), 19), v[k]);
    for (int l = 1; l <= 7 && ok; ++l)
      for (int k = 0; k < 4; ++k) {
        const std::string_view f = trim(field(rec[static_cast<std::size_t>(l)], 4 + 19 * static_cast<std::size_t>(k), 19));
        if (f.empty()) continue;  // e.g. the fit interval's unused spare fields
        ok = ok && parse_fortran_double(f, v[3 + 4 * (l - 1) + k]);
      }
    GpsTime toc;
    if (!ok || !gps_time_from_calendar(y, mo, d, h, mi, s, toc)) {
      stats.reject(rec_line, "unparsable GPS record");
      rec.clear();
      return;
    }
    GpsEphemeris e;
    e.prn = static_cast<int>(prn);
    if (!to_int(v[3], e.iode) || !to_int(v[21], e.week) || !to_int(v[24], e.health)) {
      stats.reject(rec_line, "IODE, week or health not an integer");
      rec.clear();
      return;
    }
    e.af0_s = v[0];
    e.af1_sps = v[1];
    e.af2_sps2 = v[2];
    e.crs_m = v[4];
    e.delta_n_radps = v[5];
    e.m0_rad = v[6];
    e.cuc_rad = v[7];
    e.eccentricity = v[8];
    e.cus_rad = v[9];
    e.sqrt_a_sqrtm = v[10];
    e.toe_s = v[11];
    e.cic_rad = v[12];
    e.omega0_rad = v[13];
    e.cis_rad = v[14];
    e.i0_rad = v[15];
    e.crc_m = v[16];
    e.arg_perigee_rad = v[17];
    e.omega_dot_radps = v[18];
    e.idot_radps = v[19];
    e.tgd_s = v[25];
    e.toc_s = static_cast<double>(toc.week - e.week) * fsw::kSecondsPerWeek + toc.tow_s;
    if (!ephemeris_valid(e)) {
      stats.reject(rec_line, "implausible ephemeris");
    } else {
      ++stats.accepted;
      out.push_back(e);
    }
    rec.clear();
  };
  while (getline_counted(in, line, terminated)) {
    ++ln;
    if (trim(line).empty()) continue;
    if (line[0] != ' ') {
      flush();
      rec_line = ln;
      rec_complete = true;
    } else if (rec.empty()) {
      ++stats.lines;
      stats.reject(ln, "continuation line without a record");
      continue;
    }
    if (!terminated) rec_complete = false;
    rec.push_back(line);
  }
  flush();
  return out;
}

}  // namespace tools
