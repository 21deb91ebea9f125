// Scenario TOML writer: the one schema (sim::Scenario, sim/scenarios/README.md) written back as a
// complete file that parse_scenario_text() reads into an equal Scenario. Used for the scenario a
// diagnosis suggests flying next (tools/diagnosis_separation.hpp).
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>

#include "sim/scenario.hpp"

namespace sim {
namespace {

/// The shortest text that reads back as exactly v, always a TOML float ("60.0", "2e-19").
std::string num(double v) {
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  std::string s(buf, res.ptr);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";  // "60" would be an integer
  return s;
}

/// A TOML basic string: quotes, backslashes and control characters escaped.
std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (const char ch : s) {
    const unsigned char c = static_cast<unsigned char>(ch);
    switch (ch) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      case '\r': out += "\\r"; break;
      default:
        if (c < 0x20 || c == 0x7f) {
          char esc[8];
          std::snprintf(esc, sizeof esc, "\\u%04x", c);
          out += esc;
        } else {
          out += ch;
        }
    }
  }
  return out + "\"";
}

const char* direction(TurnDirection d) { return d == TurnDirection::kLeft ? "left" : "right"; }

const char* error_set(ImuErrorSet e) {
  switch (e) {
    case ImuErrorSet::kPaper: return "paper";
    case ImuErrorSet::kBaseline: return "baseline";
    case ImuErrorSet::kNone: return "none";
  }
  return "paper";
}

/// Every number of the scenario finite (the reader rejects nan and inf).
bool all_finite(const Scenario& sc) {
  bool ok = std::isfinite(sc.duration_s);
  const StartState& st = sc.start;
  for (double v : {st.lat_deg, st.lon_deg, st.alt_m, st.speed_mps, st.heading_deg, st.pitch_deg}) ok = ok && std::isfinite(v);
  for (const Segment& s : sc.segments)
    for (double v : {s.duration_s, s.bank_deg, s.heading_change_deg, s.roll_time_s, s.delta_speed_mps, s.flight_path_deg,
                     s.transition_s, s.crab_deg})
      ok = ok && std::isfinite(v);
  for (const auto& e : sc.effects.value)
    for (double v : e) ok = ok && std::isfinite(v);
  return ok;
}

/// The segment with only the fields its type uses (the others at their defaults): what the reader
/// gives back for it.
Segment used_fields(const Segment& s) {
  Segment d;
  d.type = s.type;
  switch (s.type) {
    case SegmentType::kStraight: d.duration_s = s.duration_s; break;
    case SegmentType::kTurn:
      d.direction = s.direction;
      d.bank_deg = s.bank_deg;
      d.heading_change_deg = s.heading_change_deg;
      d.roll_time_s = s.roll_time_s;
      break;
    case SegmentType::kSpeedChange:
      d.duration_s = s.duration_s;
      d.delta_speed_mps = s.delta_speed_mps;
      break;
    case SegmentType::kClimb:
      d.duration_s = s.duration_s;
      d.flight_path_deg = s.flight_path_deg;
      d.transition_s = s.transition_s;
      break;
    case SegmentType::kRoll:
      d.duration_s = s.duration_s;
      d.direction = s.direction;
      d.bank_deg = s.bank_deg;
      d.roll_time_s = s.roll_time_s;
      break;
    case SegmentType::kCrab:
      d.duration_s = s.duration_s;
      d.direction = s.direction;
      d.crab_deg = s.crab_deg;
      d.transition_s = s.transition_s;
      break;
  }
  return d;
}

}  // namespace

std::string segments_toml(const std::vector<Segment>& segments) {
  std::ostringstream o;
  for (std::size_t i = 0; i < segments.size(); ++i) {
    const Segment& s = segments[i];
    if (i > 0) o << "\n";
    o << "[[trajectory.segment]]\n";
    o << "type = \"" << to_string(s.type) << "\"\n";
    switch (s.type) {
      case SegmentType::kStraight: o << "duration_s = " << num(s.duration_s) << "\n"; break;
      case SegmentType::kTurn:
        o << "direction = \"" << direction(s.direction) << "\"\n"
          << "bank_deg = " << num(s.bank_deg) << "\n"
          << "heading_change_deg = " << num(s.heading_change_deg) << "\n"
          << "roll_time_s = " << num(s.roll_time_s) << "\n";
        break;
      case SegmentType::kSpeedChange:
        o << "duration_s = " << num(s.duration_s) << "\n"
          << "delta_speed_mps = " << num(s.delta_speed_mps) << "\n";
        break;
      case SegmentType::kClimb:
        o << "duration_s = " << num(s.duration_s) << "\n"
          << "flight_path_deg = " << num(s.flight_path_deg) << "\n"
          << "transition_s = " << num(s.transition_s) << "\n";
        break;
      case SegmentType::kRoll:
        o << "duration_s = " << num(s.duration_s) << "\n"
          << "direction = \"" << direction(s.direction) << "\"\n"
          << "bank_deg = " << num(s.bank_deg) << "\n"
          << "roll_time_s = " << num(s.roll_time_s) << "\n";
        break;
      case SegmentType::kCrab:
        o << "duration_s = " << num(s.duration_s) << "\n"
          << "direction = \"" << direction(s.direction) << "\"\n"
          << "crab_deg = " << num(s.crab_deg) << "\n"
          << "transition_s = " << num(s.transition_s) << "\n";
        break;
    }
  }
  return o.str();
}

ScenarioWriteResult write_scenario_toml(const Scenario& sc, const std::string& header) {
  ScenarioWriteResult r;
  if (!all_finite(sc)) {
    r.error = "the scenario has a non-finite number (a scenario file holds finite numbers only)";
    return r;
  }
  if (sc.seed > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) {
    r.error = "seed " + std::to_string(sc.seed) + " is above the largest TOML integer (2^63 - 1)";
    return r;
  }
  std::ostringstream o;
  std::istringstream h(header);
  for (std::string line; std::getline(h, line);) o << "# " << line << "\n";
  if (!header.empty()) o << "\n";
  o << "name = " << quoted(sc.name) << "\n"
    << "duration_s = " << num(sc.duration_s) << "\n"
    << "seed = " << sc.seed << "\n\n";
  const StartState& st = sc.start;
  o << "[start]\n"
    << "lat_deg = " << num(st.lat_deg) << "\n"
    << "lon_deg = " << num(st.lon_deg) << "\n"
    << "alt_m = " << num(st.alt_m) << "\n"
    << "speed_mps = " << num(st.speed_mps) << "\n"
    << "heading_deg = " << num(st.heading_deg) << "\n"
    << "pitch_deg = " << num(st.pitch_deg) << "\n\n";
  o << "[trajectory]\n"
    << "repeat_from = ";
  if (sc.repeat_from)
    o << *sc.repeat_from << "\n\n";
  else
    o << "\"none\"\n\n";
  o << segments_toml(sc.segments) << "\n";
  const ImuErrorSigmas& s = sc.imu.sigmas;
  o << "[imu]\n"
    << "rate_hz = " << sc.imu.rate_hz << "\n"
    << "errors = \"" << error_set(sc.imu.errors) << "\"\n"
    << "accel_bias_ug = " << num(s.accel_bias_ug) << "\n"
    << "accel_scale_factor_ppm = " << num(s.accel_scale_factor_ppm) << "\n"
    << "accel_misalignment_arcsec = " << num(s.accel_misalignment_arcsec) << "\n"
    << "gyro_bias_degph = " << num(s.gyro_bias_degph) << "\n"
    << "gyro_scale_factor_ppm = " << num(s.gyro_scale_factor_ppm) << "\n"
    << "gyro_misalignment_arcsec = " << num(s.gyro_misalignment_arcsec) << "\n"
    << "gyro_arw_deg_per_rthr = " << num(s.gyro_arw_deg_per_rthr) << "\n"
    << "accel_vrw_ug_per_rthz = " << num(s.accel_vrw_ug_per_rthz) << "\n"
    << "gyro_bias_instability_degph = " << num(s.gyro_bias_instability_degph) << "\n"
    << "accel_bias_instability_ug = " << num(s.accel_bias_instability_ug) << "\n"
    << "bias_instability_tau_s = " << num(s.bias_instability_tau_s) << "\n"
    << "gyro_bias_rw_degph_per_rthr = " << num(s.gyro_bias_rw_degph_per_rthr) << "\n"
    << "accel_bias_rw_ug_per_rthr = " << num(s.accel_bias_rw_ug_per_rthr) << "\n";
  // Written only when set: a scenario without a mounting is written as before.
  const std::array<double, 3>& m = sc.imu.mounting_rpy_deg;
  if (m[0] != 0.0 || m[1] != 0.0 || m[2] != 0.0)
    o << "mounting_rpy_deg = [" << num(m[0]) << ", " << num(m[1]) << ", " << num(m[2]) << "]\n";
  o << "\n";
  o << "[effects]\n";
  for (const fsw::EffectInfo& info : fsw::kEffectCatalogue) {
    if (!sc.effects.on(info.effect)) continue;
    if (info.n_components == 1) {
      o << info.name << " = " << num(sc.effects.get(info.effect, 0)) << "\n";
      continue;
    }
    o << info.name << " = {";
    bool first = true;
    for (std::size_t k = 0; k < info.n_components; ++k) {
      const double v = sc.effects.get(info.effect, k);
      if (v == 0.0) continue;
      o << (first ? " " : ", ") << info.components[k] << " = " << num(v);
      first = false;
    }
    o << " }\n";
  }
  const GpsConfig& g = sc.gps;
  o << "\n[gps]\n"
    << "almanac = " << quoted(g.almanac) << "\n"
    << "start_week = " << g.start_week << "\n"
    << "start_tow_s = " << num(g.start_tow_s) << "\n"
    << "rate_hz = " << num(g.rate_hz) << "\n"
    << "elevation_mask_deg = " << num(g.elevation_mask_deg) << "\n"
    << "max_channels = " << g.max_channels << "\n"
    << "pseudorange_gm_sigma_m = " << num(g.pseudorange_gm_sigma_m) << "\n"
    << "pseudorange_gm_tau_s = " << num(g.pseudorange_gm_tau_s) << "\n"
    << "pseudorange_rate_gm_sigma_mps = " << num(g.pseudorange_rate_gm_sigma_mps) << "\n"
    << "pseudorange_rate_gm_tau_s = " << num(g.pseudorange_rate_gm_tau_s) << "\n"
    << "pseudorange_white_sigma_m = " << num(g.pseudorange_white_sigma_m) << "\n"
    << "pseudorange_rate_white_sigma_mps = " << num(g.pseudorange_rate_white_sigma_mps) << "\n"
    << "clock_bias_sigma_m = " << num(g.clock_bias_sigma_m) << "\n"
    << "clock_drift_sigma_mps = " << num(g.clock_drift_sigma_mps) << "\n"
    << "clock_h0_s = " << num(g.clock_h0_s) << "\n"
    << "clock_h_minus2_per_s = " << num(g.clock_h_minus2_per_s) << "\n";
  // What is written must read back: the reader is the judge of every range.
  const ScenarioParseResult back = parse_scenario_text(o.str(), "written scenario");
  if (!back.ok()) {
    r.error = "the scenario cannot be written as a valid scenario file: " + back.error;
    return r;
  }
  Scenario expected = sc;  // a segment's fields that its type does not use are not part of the file
  for (Segment& seg : expected.segments) seg = used_fields(seg);
  if (!(*back.scenario == expected)) {
    r.error = "internal error: the written scenario does not read back equal";
    return r;
  }
  r.text = o.str();
  return r;
}

}  // namespace sim
