// YUMA almanac reader and visibility (the orbit computation is fsw/gps_orbit.cpp).
#include "sim/almanac.hpp"
#include "fsw/gps_orbit.hpp"
#include "cfg/text_file.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace sim {
namespace {

using fsw::Vec3;

enum Field : int {
  kId,
  kHealth,
  kEccentricity,
  kToa,
  kInclination,
  kOmegaDot,
  kSqrtA,
  kOmega0,
  kArgPerigee,
  kMeanAnomaly,
  kAf0,
  kAf1,
  kWeek,
  kFieldCount
};

/// Canonical labels: lower case, whitespace runs collapsed to one space.
constexpr std::array<const char*, kFieldCount> kLabels = {
    "id",                        "health",                   "eccentricity",
    "time of applicability(s)",  "orbital inclination(rad)", "rate of right ascen(r/s)",
    "sqrt(a) (m 1/2)",           "right ascen at week(rad)", "argument of perigee(rad)",
    "mean anom(rad)",            "af0(s)",                   "af1(s/s)",
    "week"};

std::string normalize_label(const std::string& s) {
  std::string out;
  bool space = false;
  for (char c : s) {
    if (std::isspace(static_cast<unsigned char>(c))) {
      space = true;
      continue;
    }
    if (space && !out.empty()) out.push_back(' ');
    space = false;
    out.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  }
  return out;
}

std::string trim(const std::string& s) {
  std::size_t b = 0, e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return s.substr(b, e - b);
}

bool parse_double(const std::string& s, double& out) {
  if (s.empty()) return false;
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size() || errno == ERANGE || !std::isfinite(v)) return false;
  out = v;
  return true;
}

bool parse_int(const std::string& s, int& out) {
  if (s.empty()) return false;
  errno = 0;
  char* end = nullptr;
  const long v = std::strtol(s.c_str(), &end, 10);
  if (end != s.c_str() + s.size() || errno == ERANGE || v < -1000000000L || v > 1000000000L) return false;
  out = static_cast<int>(v);
  return true;
}

struct PendingRecord {
  int header_line = 0;
  std::array<int, kFieldCount> line{};  ///< 0: not seen
  std::array<std::string, kFieldCount> value{};
};

class YumaParser {
 public:
  explicit YumaParser(std::string source) : source_(std::move(source)) {}

  AlmanacParseResult run(const std::string& text) {
    std::istringstream in(text);
    std::string raw;
    int line_no = 0;
    bool open = false;
    PendingRecord rec;
    while (std::getline(in, raw)) {
      ++line_no;
      const std::string line = trim(raw);
      if (line.empty()) continue;
      if (line.front() == '*') {
        if (open && !finish(rec)) return fail();
        rec = PendingRecord{};
        rec.header_line = line_no;
        open = true;
        continue;
      }
      const std::size_t colon = line.find(':');
      if (colon == std::string::npos) return fail(line_no, "expected 'field: value', got '" + line + "'");
      const std::string label = normalize_label(line.substr(0, colon));
      const auto it = std::find_if(kLabels.begin(), kLabels.end(), [&](const char* l) { return label == l; });
      if (it == kLabels.end()) return fail(line_no, "unknown field '" + trim(line.substr(0, colon)) + "'");
      if (!open) return fail(line_no, "field '" + trim(line.substr(0, colon)) + "' before the first record header");
      const auto f = static_cast<std::size_t>(it - kLabels.begin());
      if (rec.line[f] != 0) {
        return fail(line_no, "duplicate field '" + trim(line.substr(0, colon)) + "' (first on line " +
                                 std::to_string(rec.line[f]) + ")");
      }
      rec.line[f] = line_no;
      rec.value[f] = trim(line.substr(colon + 1));
    }
    if (open && !finish(rec)) return fail();
    if (sats_.empty()) return fail(std::max(line_no, 1), "no almanac records");
    std::sort(sats_.begin(), sats_.end(), [](const AlmanacEntry& a, const AlmanacEntry& b) { return a.prn < b.prn; });
    return {std::move(sats_), ""};
  }

 private:
  bool error(int line_no, const std::string& reason) {
    error_ = source_ + ":" + std::to_string(line_no) + ": " + reason;
    return false;
  }
  AlmanacParseResult fail() { return {std::nullopt, error_}; }
  AlmanacParseResult fail(int line_no, const std::string& reason) {
    error(line_no, reason);
    return fail();
  }

  bool get_double(const PendingRecord& r, Field f, double& out) {
    if (!parse_double(r.value[f], out)) {
      return error(r.line[f], std::string("field '") + kLabels[f] + "': not a finite number: '" + r.value[f] + "'");
    }
    return true;
  }
  bool get_int(const PendingRecord& r, Field f, int& out) {
    if (!parse_int(r.value[f], out)) {
      return error(r.line[f], std::string("field '") + kLabels[f] + "': not an integer: '" + r.value[f] + "'");
    }
    return true;
  }

  bool finish(const PendingRecord& r) {
    for (int f = 0; f < kFieldCount; ++f) {
      if (r.line[f] == 0) return error(r.header_line, std::string("record misses field '") + kLabels[f] + "'");
    }
    AlmanacEntry s;
    if (!get_int(r, kId, s.prn) || !get_int(r, kHealth, s.health) || !get_double(r, kEccentricity, s.eccentricity) ||
        !get_double(r, kToa, s.toa_s) || !get_double(r, kInclination, s.inclination_rad) ||
        !get_double(r, kOmegaDot, s.omega_dot_radps) || !get_double(r, kSqrtA, s.sqrt_a_sqrtm) ||
        !get_double(r, kOmega0, s.omega0_rad) || !get_double(r, kArgPerigee, s.arg_perigee_rad) ||
        !get_double(r, kMeanAnomaly, s.mean_anomaly_rad) || !get_double(r, kAf0, s.af0_s) ||
        !get_double(r, kAf1, s.af1_sps) || !get_int(r, kWeek, s.week_mod_1024)) {
      return false;
    }
    if (s.prn < 1 || s.prn > 32) return error(r.line[kId], "PRN " + std::to_string(s.prn) + " outside 1..32");
    for (const AlmanacEntry& other : sats_) {
      if (other.prn == s.prn) return error(r.line[kId], "duplicate PRN " + std::to_string(s.prn));
    }
    if (s.health < 0 || s.health > 255) return error(r.line[kHealth], "health outside 0..255");
    if (!(s.eccentricity >= 0.0 && s.eccentricity < 1.0)) return error(r.line[kEccentricity], "eccentricity outside [0, 1)");
    if (!(s.sqrt_a_sqrtm > 0.0)) return error(r.line[kSqrtA], "sqrt(A) not positive");
    if (!(s.toa_s >= 0.0 && s.toa_s < kSecondsPerWeek)) {
      return error(r.line[kToa], "time of applicability outside [0, 604800) s");
    }
    if (s.week_mod_1024 < 0 || s.week_mod_1024 > 1023) return error(r.line[kWeek], "week outside 0..1023");
    // The flight software's own plausibility (one validation, docs/faults.md): what a receiver
    // would reject must not be simulated either (e.g. sqrt(A) 1e30, a clock bias of 1e6 s).
    if (const char* bad = fsw::almanac_invalid_field(s))
      return error(r.header_line, std::string("PRN ") + std::to_string(s.prn) + ": " + bad +
                                      " outside the flight software's plausible range (fsw::almanac_valid)");
    sats_.push_back(s);
    return true;
  }

  std::string source_;
  std::string error_;
  std::vector<AlmanacEntry> sats_;
};

}  // namespace

AlmanacParseResult parse_yuma_text(const std::string& text, const std::string& source) {
  try {
    return YumaParser(source).run(text);
  } catch (const std::exception& e) {  // only std::bad_alloc is conceivable
    return {std::nullopt, source + ":0: " + e.what()};
  }
}

AlmanacParseResult parse_yuma_file(const std::string& path) {
  try {
    const std::optional<std::string> text = cfg::read_text_file(path);
    if (!text) return {std::nullopt, path + ":0: cannot open almanac file: " + cfg::text_file_problem(path)};
    return parse_yuma_text(*text, path);
  } catch (const std::exception& e) {
    return {std::nullopt, path + ":0: " + e.what()};
  }
}

LookAngles look_angles(const Vec3& receiver_llh, const Vec3& r_target_ecef_m) {
  const Vec3 los_e = r_target_ecef_m - fsw::ecef_from_llh(receiver_llh);
  const Vec3 los_enu = fsw::C_n_e(receiver_llh.x(), receiver_llh.y()).transpose() * los_e;  // ENU
  LookAngles out;
  out.elevation_rad = std::atan2(los_enu.z(), std::hypot(los_enu.x(), los_enu.y()));
  double az = std::atan2(los_enu.x(), los_enu.y());
  if (az < 0.0) az += 2.0 * fsw::kPi;
  out.azimuth_rad = az;
  return out;
}

void visible_satellites(const std::vector<AlmanacEntry>& almanac, int full_gps_week, double tow_s,
                        const Vec3& receiver_llh, double mask_rad, std::vector<Visible>& out) {
  out.clear();
  for (const AlmanacEntry& sat : almanac) {
    if (sat.health != 0) continue;
    Visible v;
    v.prn = sat.prn;
    satellite_pv_ecef(sat, full_gps_week, tow_s, v.r_ecef_m, v.v_ecef_mps);
    const LookAngles la = look_angles(receiver_llh, v.r_ecef_m);
    if (la.elevation_rad < mask_rad) continue;
    v.elevation_rad = la.elevation_rad;
    v.azimuth_rad = la.azimuth_rad;
    out.push_back(v);
  }
}

}  // namespace sim
