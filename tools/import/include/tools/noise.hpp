// The sensor noise from the data (`sdins noise`, docs/noise.md): the segments of a log where the
// vehicle is at rest, the overlapping Allan deviation of every gyro and accelerometer axis over
// them (tools/allan.hpp), the IEEE Std 952 noise terms with their intervals, the filter
// configuration values that follow, and the same analysis of the simulator's IMU model
// (sim/imu_model.hpp) for comparison.
//
// Rest detector (stated, every threshold from the data):
//  - the IMU samples are cut into windows of window_s; per window the standard deviation of the
//    specific-force magnitude |dv/dt| and the root-sum-square of the per-axis standard deviations
//    of the angular rate dtheta/dt;
//  - the reference of each statistic is the median of the k quietest windows, k = min_rest_s /
//    window_s / 2 (half a minimum rest: a log that rests at all rests at least that long); a window
//    is quiet when both statistics are at most threshold_factor x their reference;
//  - with GNSS (GNSS_PVT velocity, or the single-point velocity of GNSS_RAW epochs with the
//    almanac) a window is at rest only when every solution within it (and the nearest within
//    speed_max_age_s when none) has a ground speed <= max_speed_mps;
//  - a run of quiet windows at rest of at least min_rest_s, less margin_s at both ends, with no IMU
//    interval above max_gap_factor x the median, is a rest segment.
// A smooth straight motion at constant speed without vibration passes the IMU test (nothing in
// specific force or rate tells it from rest): without GNSS the detector says so in its report.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "fsw/strapdown.hpp"
#include "sim/imu_model.hpp"
#include "tools/allan.hpp"

namespace tools {

struct SpeedFix {
  double t_s = 0.0;
  double ground_speed_mps = 0.0;
};

/// What `sdins noise` reads from a log.
struct NoiseInput {
  std::vector<fsw::ImuSample> imu;
  std::vector<SpeedFix> speed;   ///< GNSS ground speed, time order
  std::string speed_source;      ///< "GNSS_PVT", "GNSS_RAW" (single-point velocity) or "" (none)
  bool have_position = false;    ///< lat/h from the first GNSS solution (normal gravity, Earth rate)
  double lat_rad = 0.0, h_m = 0.0;
  std::uint64_t imu_rejected = 0, imu_counter_gaps = 0, raw_epochs_without_fix = 0, log_rejections = 0;
};
/// Reads the IMU channel and the GNSS solutions / raw epochs of an LCM log (hal::LcmReplayReader).
/// Throws std::runtime_error naming the file when it cannot be read.
NoiseInput read_noise_input(const std::string& log_path);

struct RestDetectorConfig {
  double window_s = 1.0;
  double threshold_factor = 5.0;
  double min_rest_s = 10.0;
  double margin_s = 1.0;
  double max_speed_mps = 0.2;
  double speed_max_age_s = 1.0;
  double max_gap_factor = 2.5;
  bool use_gnss = true;
};

struct RestSegment {
  std::size_t first = 0, last = 0;  ///< IMU sample indices, inclusive
  double t_begin_s = 0.0, t_end_s = 0.0;
  double duration_s() const { return t_end_s - t_begin_s; }
};

struct RestDetection {
  RestDetectorConfig cfg;
  double median_dt_s = 0.0;
  double ref_sf_std_mps2 = 0.0, ref_rate_std_radps = 0.0;  ///< the quiet windows' reference
  double thr_sf_std_mps2 = 0.0, thr_rate_std_radps = 0.0;
  std::size_t windows = 0, windows_quiet_imu = 0, windows_moving_gnss = 0, windows_no_gnss = 0;
  bool gnss_used = false;
  std::vector<RestSegment> segments;
  std::vector<double> window_t_s, window_sf_std, window_rate_std;  ///< per window (plots)
  std::vector<int> window_rest;  ///< 1: part of a rest run before trimming
};
RestDetection detect_rest(const NoiseInput& in, const RestDetectorConfig& cfg);

/// One sensor axis: its Allan curve and noise terms.
struct AxisNoise {
  std::string name;  ///< gyro_x .. accel_z (body FRD)
  bool gyro = true;
  double mean = 0.0;  ///< mean rate [rad/s] or specific force [m/s^2] over the rest
  AllanCurve curve;
  NoiseReading reading;
};

struct NoiseAnalysis {
  double tau0_s = 0.0;
  double rest_s = 0.0;
  std::vector<double> segment_s;
  std::vector<AxisNoise> axes;  ///< gyro x, y, z, accel x, y, z
};

/// The Allan analysis of the rest segments: the increments integrated and resampled (linear in the
/// integral) onto a uniform grid of the median interval, one phase series per segment.
NoiseAnalysis analyse_noise(const std::vector<fsw::ImuSample>& imu, const std::vector<RestSegment>& segments);

/// The simulator's IMU model at rest (level, north-aligned, at lat_rad) for the same segment
/// lengths and interval: the model's errors as drawn for the scenario, its noise from seed.
NoiseAnalysis analyse_simulated_rest(const sim::ImuErrors& errors, const std::vector<double>& segment_s,
                                     double tau0_s, double lat_rad, std::uint64_t seed);

/// The filter configuration ([imu] of config/README.md) the analysis gives, each value with where
/// it came from as comments; the same as JSON in filter_values_json.
std::string filter_config_toml(const NoiseAnalysis& a, const NoiseInput& in, const std::string& source);
nlohmann::json filter_values_json(const NoiseAnalysis& a, const NoiseInput& in);

/// The scenario [imu] noise keys (sim/scenarios/README.md) that reproduce the analysis' terms with
/// the simulator's model (white noise, Gauss-Markov bias drift, bias random walk).
sim::ImuErrors imu_errors_from_analysis(const NoiseAnalysis& a);
std::string scenario_imu_toml(const sim::ImuErrors& e);

nlohmann::json to_json(const NoiseAnalysis& a);
nlohmann::json to_json(const RestDetection& d);
/// The terminal summary.
std::string noise_summary_text(const RestDetection& d, const NoiseAnalysis& a);
/// Data against a model's analysis: per axis and term, both readings and their ratio.
nlohmann::json compare_json(const NoiseAnalysis& data, const NoiseAnalysis& model);
std::string compare_text(const NoiseAnalysis& data, const NoiseAnalysis& model, const std::string& model_name);
/// The white noise N of every axis per segment analysed alone, and the axes whose segments'
/// 95% intervals do not overlap (the noise was not the same in every rest: pooling mixes them).
/// Fills j with the same.
std::string segments_text(const std::vector<NoiseAnalysis>& each, nlohmann::json& j);
/// One line of an IMU error model's noise terms in display units.
std::string imu_errors_text(const sim::ImuErrors& e);

}  // namespace tools
