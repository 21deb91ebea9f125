// The one scenario schema: what a scenario TOML file holds, with the built-in defaults.
// The TOML layout (keys, units, validity ranges) is documented in sim/scenarios/README.md and
// parsed by parse_scenario_file()/parse_scenario_text() in scenario.cpp.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sim/effects.hpp"

namespace sim {

enum class SegmentType { kStraight, kTurn, kSpeedChange, kClimb, kRoll, kCrab };
const char* to_string(SegmentType t);
enum class TurnDirection { kLeft, kRight };

/// One piece of the flight. Every transition has the smooth_step shape (zero rate and
/// acceleration at both ends).
///  - straight: duration_s at the current speed, wings level.
///  - turn: a coordinated level bank-to-turn: roll-in over roll_time_s to bank_deg, constant bank
///    (heading rate g tan(phi) / V, no sideslip), roll-out over roll_time_s; heading_change_deg
///    counts the heading turned during the whole segment including the transitions.
///  - speed_change: wings level, the speed changes by delta_speed_mps over duration_s (a
///    longitudinal acceleration: what separates an accelerometer x scale factor from a bias).
///  - climb: pull-up over transition_s to the flight-path angle flight_path_deg (negative: a
///    push-over into a descent), held for duration_s (0: a pull-up followed at once by a push-over),
///    back to level over transition_s (body pitch rate and load factor, apart from a turn).
///  - roll: roll to bank_deg (direction) over roll_time_s, held for duration_s, back over
///    roll_time_s, with the heading held (not coordinated: the sideslip a pilot flies with rudder):
///    a roll without turning, which separates roll-rate effects from turn-rate ones.
///  - crab: wings level and straight, the nose yawed crab_deg to direction off the track over
///    transition_s, held for duration_s, back over transition_s; the velocity (track, speed, climb)
///    does not change: the heading offset an aircraft flies in a crosswind. The only segment with the
///    body x axis off the velocity (what separates a lever arm along x from a time offset).
struct Segment {
  SegmentType type = SegmentType::kStraight;
  double duration_s = 60.0;           ///< straight, speed_change, climb (hold), roll (hold), crab (hold) [s]
  TurnDirection direction = TurnDirection::kRight;  ///< turn, roll, crab (right: nose right of the track)
  double bank_deg = 60.0;             ///< turn, roll: magnitude (0, 80] [deg]
  double heading_change_deg = 180.0;  ///< turn only, magnitude (0, 3600] [deg]
  double roll_time_s = 5.0;           ///< turn, roll: each of roll-in and roll-out (0, 60] [s]
  double delta_speed_mps = 50.0;      ///< speed_change: [-400, 400], not 0 [m/s]
  double flight_path_deg = 10.0;      ///< climb: [-45, 45], not 0 [deg]
  double transition_s = 10.0;         ///< climb, crab: each of the two transitions (0, 120] [s]
  double crab_deg = 10.0;             ///< crab: heading minus track, magnitude (0, 45] [deg]
  bool operator==(const Segment&) const = default;
};

struct StartState {
  double lat_deg = 35.0;
  double lon_deg = 127.0;
  double alt_m = 5000.0;      ///< ellipsoidal height
  double speed_mps = 250.0;   ///< ground speed at t = 0 (speed_change segments change it)
  double heading_deg = 0.0;   ///< true heading
  double pitch_deg = 0.0;     ///< constant body pitch above the (level) flight path
  bool operator==(const StartState&) const = default;
};

/// 1-sigma values of the IMU errors drawn per run from the seed (the paper's Table 1 by default).
struct ImuErrorSigmas {
  double accel_bias_ug = 100.0;
  double accel_scale_factor_ppm = 100.0;
  double accel_misalignment_arcsec = 5.0;
  double gyro_bias_degph = 0.01;
  double gyro_scale_factor_ppm = 100.0;
  double gyro_misalignment_arcsec = 5.0;
  double gyro_arw_deg_per_rthr = 0.0;       ///< angle random walk [deg/sqrt(h)]
  double accel_vrw_ug_per_rthz = 0.0;       ///< velocity random walk [ug/sqrt(Hz)]
  double gyro_bias_instability_degph = 0.0; ///< 1-sigma of a first-order Gauss-Markov bias drift
  double accel_bias_instability_ug = 0.0;   ///< 1-sigma of a first-order Gauss-Markov bias drift
  double bias_instability_tau_s = 3600.0;   ///< correlation time of both drifts
  double gyro_bias_rw_degph_per_rthr = 0.0; ///< gyro bias random walk (rate random walk) [deg/h/sqrt(h)]
  double accel_bias_rw_ug_per_rthr = 0.0;   ///< accelerometer bias random walk [ug/sqrt(h)]
  bool operator==(const ImuErrorSigmas&) const = default;
};

/// Which error set the IMU model draws: the paper's Table 1, only biases and noise (what the
/// 15-state model estimates), or none at all (perfect IMU).
enum class ImuErrorSet { kPaper, kBaseline, kNone };

struct ImuConfig {
  int rate_hz = 1000;  ///< IMU sample rate; a multiple of the 200 Hz navigation rate
  ImuErrorSet errors = ImuErrorSet::kPaper;
  ImuErrorSigmas sigmas{};
  /// The IMU's mounting on the vehicle: roll, pitch, yaw [deg] of the sensor axes against the
  /// vehicle's body axes (z-y-x: yaw about the body z, then pitch, then roll; a vector v in the
  /// body frame reads C_s_b^T v in the sensor frame, C_s_b = Rz(yaw) Ry(pitch) Rx(roll)). The truth
  /// (TRUTH, the trajectory, the antenna) stays the vehicle's; only the IMU's outputs turn. All 0:
  /// no rotation at all (the seeded runs without it are unchanged).
  std::array<double, 3> mounting_rpy_deg{};
  bool operator==(const ImuConfig&) const = default;
};

/// The simulated GPS receiver (sim/gps_model.hpp): constellation, time, measurement errors.
/// Clock: two-state random process (bias b [m], drift d [m/s]) driven by white noise of PSD
/// S_bias = h0/2 c^2 [m^2/s] and S_drift = 2 pi^2 h_-2 c^2 [m^2/s^3] (Allan-variance coefficients).
struct GpsConfig {
  /// YUMA almanac path; empty: default_almanac_path(). parse_scenario_file() makes a relative path
  /// absolute against the scenario file's directory; use almanac_path() to get the file to read.
  std::string almanac;
  int start_week = 1455;             ///< full GPS week at scenario t = 0 (week 431 mod 1024 of the default almanac)
  double start_tow_s = 589824.0;     ///< GPS seconds of week at scenario t = 0 (the default almanac's toa)
  double rate_hz = 1.0;              ///< measurement epochs at t = k / rate_hz, (0, 20]
  double elevation_mask_deg = 10.0;  ///< satellites below are not tracked, [0, 90)
  double pseudorange_gm_sigma_m = 8.0;          ///< first-order Gauss-Markov error per satellite, 1-sigma
  double pseudorange_gm_tau_s = 60.0;           ///< its correlation time, > 0
  double pseudorange_rate_gm_sigma_mps = 0.2;   ///< first-order Gauss-Markov error per satellite, 1-sigma
  double pseudorange_rate_gm_tau_s = 10.0;      ///< its correlation time, > 0
  double pseudorange_white_sigma_m = 0.0;       ///< white noise per epoch, 1-sigma
  double pseudorange_rate_white_sigma_mps = 0.0;
  double clock_bias_sigma_m = 30.0;             ///< initial receiver clock bias (c * dt), 1-sigma
  double clock_drift_sigma_mps = 1.0;           ///< initial receiver clock drift (c * ddt), 1-sigma
  double clock_h0_s = 2e-19;                    ///< white-frequency coefficient h0 [s] (TCXO)
  double clock_h_minus2_per_s = 2e-20;          ///< random-walk-frequency coefficient h_-2 [1/s] (TCXO)
  int max_channels = 12;  ///< [1, fsw::kMaxGnssChannels]; the highest satellites are kept when more are visible
  bool operator==(const GpsConfig&) const = default;
};

/// The almanac shipped with the product: "<data directory>/almanac/yuma-week431.alm" (cfg/data_dir.hpp).
std::string default_almanac_path();
/// The almanac file a GpsConfig names: cfg.almanac, or default_almanac_path() when it is empty.
std::string almanac_path(const GpsConfig& cfg);

struct Scenario {
  std::string name = "bank-to-turn";
  double duration_s = 1800.0;
  std::uint64_t seed = 1;
  StartState start{};
  std::vector<Segment> segments = default_segments();
  /// After the last segment, continue with segment index repeat_from (0-based); nullopt: fly
  /// straight after the last segment until duration_s.
  std::optional<std::size_t> repeat_from = std::size_t{1};
  ImuConfig imu{};
  /// Truth-side effects switched on at fixed values on top of the drawn errors.
  EffectSet effects{};
  GpsConfig gps{};

  /// Default flight: 60 s straight, then alternating 180-degree right and left 60-degree bank
  /// turns with 30 s straights between them, repeated for the whole 1800 s.
  static std::vector<Segment> default_segments();
  /// Field by field (the scenario writer's round trip: parse(write(s)) == s).
  bool operator==(const Scenario&) const = default;
};

/// Result of parsing: either a scenario or a message naming the offending key and its line.
struct ScenarioParseResult {
  std::optional<Scenario> scenario;
  std::string error;  ///< e.g. "scenario.toml:12:1: unknown key 'trajectory.segment[2].bnak_deg'"
  bool ok() const { return scenario.has_value(); }
};

/// gps.almanac is kept as written (a relative path is then relative to the working directory).
ScenarioParseResult parse_scenario_text(const std::string& toml_text, const std::string& source_name);
/// As parse_scenario_text; a relative gps.almanac is resolved against the file's directory.
ScenarioParseResult parse_scenario_file(const std::string& path);

/// Result of writing: the TOML text, or a message saying why the scenario cannot be written.
struct ScenarioWriteResult {
  std::string text;
  std::string error;
  bool ok() const { return error.empty(); }
};
/// The scenario as a complete scenario file (sim/src/scenario_writer.cpp): every key of the schema
/// in the reader's layout, numbers in their shortest exact form, so parse_scenario_text(text) gives
/// back a Scenario equal to sc (a segment's fields that its type does not use are not written: they
/// read back at their defaults). The text is parsed back before it is returned: a scenario the reader
/// would reject (a value out of range, a seed above 2^63 - 1, a non-finite number) is an error, not
/// a file. header: comment lines put at the top ("# " added to each line).
ScenarioWriteResult write_scenario_toml(const Scenario& sc, const std::string& header = "");
/// Segments as [[trajectory.segment]] entries (the keys their type allows), for quoting a few
/// segments in a report; the same text write_scenario_toml writes for each.
std::string segments_toml(const std::vector<Segment>& segments);

}  // namespace sim
