// libFuzzer target: the scenario parser, sim::parse_scenario_text (sim/include/sim/scenario.hpp).
//
// Contract checked on every input: the result is either a scenario or an error message, never both
// and never neither; an error names the source ("fuzz.toml:<line>:<col>: ..."); a parsed scenario
// holds only finite values inside the ranges of sim/scenarios/README.md. The parser documents no
// exception (TOML syntax errors come back as messages), so only std::bad_alloc (memory exhaustion)
// is caught: anything else escaping is a finding, which libFuzzer reports as a crash.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <string>

#include "fsw/gnss.hpp"
#include "sim/scenario.hpp"

namespace {

void check(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "fuzz_scenario: contract violated: %s\n", what);
  std::abort();
}

bool in(double v, double lo, double hi, bool lo_open = false, bool hi_open = false) {
  if (!std::isfinite(v)) return false;
  return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
}

void check_ranges(const sim::Scenario& s) {
  check(in(s.duration_s, 0.0, 86400.0, true), "duration_s");
  check(in(s.start.lat_deg, -85.0, 85.0) && in(s.start.lon_deg, -180.0, 360.0, false, true), "start lat/lon");
  check(in(s.start.alt_m, -400.0, 30000.0) && in(s.start.speed_mps, 0.0, 1000.0, true), "start alt/speed");
  check(in(s.start.heading_deg, -360.0, 360.0) && in(s.start.pitch_deg, -30.0, 30.0), "start heading/pitch");
  for (const sim::Segment& g : s.segments) {
    if (g.type == sim::SegmentType::kStraight) {
      check(in(g.duration_s, 0.0, 86400.0, true), "straight duration_s");
    } else {
      check(in(g.bank_deg, 0.0, 80.0, true) && in(g.heading_change_deg, 0.0, 3600.0, true) &&
                in(g.roll_time_s, 0.0, 60.0, true),
            "turn bank/heading_change/roll_time");
    }
  }
  check(!s.repeat_from || *s.repeat_from < s.segments.size(), "repeat_from inside the segment list");
  check(s.imu.rate_hz >= 200 && s.imu.rate_hz <= 6400 && s.imu.rate_hz % 200 == 0, "imu.rate_hz");
  const sim::ImuErrorSigmas& e = s.imu.sigmas;
  for (double v : {e.accel_bias_ug, e.accel_scale_factor_ppm, e.accel_misalignment_arcsec, e.gyro_bias_degph,
                   e.gyro_scale_factor_ppm, e.gyro_misalignment_arcsec, e.gyro_arw_deg_per_rthr, e.accel_vrw_ug_per_rthz,
                   e.gyro_bias_instability_degph, e.accel_bias_instability_ug})
    check(in(v, 0.0, HUGE_VAL, false, true), "imu sigma finite and >= 0");
  check(in(e.bias_instability_tau_s, 0.0, HUGE_VAL, true, true), "bias_instability_tau_s > 0");
  const sim::GpsConfig& g = s.gps;
  check(g.start_week >= 0 && g.start_week <= 9999 && in(g.start_tow_s, 0.0, 604800.0, false, true), "gps time");
  check(in(g.rate_hz, 0.0, 20.0, true) && in(g.elevation_mask_deg, 0.0, 90.0, false, true), "gps rate/mask");
  check(g.max_channels >= 1 && g.max_channels <= fsw::kMaxGnssChannels, "gps.max_channels");
  check(in(g.pseudorange_gm_tau_s, 0.0, HUGE_VAL, true, true) && in(g.pseudorange_rate_gm_tau_s, 0.0, HUGE_VAL, true, true),
        "gps correlation times > 0");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  sim::ScenarioParseResult r;
  try {
    r = sim::parse_scenario_text(text, "fuzz.toml");
  } catch (const std::bad_alloc&) {
    return 0;
  }
  check(r.ok() == r.error.empty(), "exactly one of scenario and error");
  if (!r.ok()) {
    check(r.error.rfind("fuzz.toml:", 0) == 0, "the error names the source");
    return 0;
  }
  check_ranges(*r.scenario);
  return 0;
}
