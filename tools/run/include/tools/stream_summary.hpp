// What an imported recording's streams look like (rate, span, gaps): the figures a starting
// filter configuration is derived from (navigation and EKF rates, latency frames) and that the
// import summaries print. One struct per stream, computed from its time tags alone.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace tools {

struct StreamSummary {
  std::string name;            ///< "imu", "gnss", "reference"
  std::string source;          ///< where it came from (a topic, a file)
  std::uint64_t samples = 0;
  double t_first_s = 0.0, t_last_s = 0.0, span_s = 0.0;
  double rate_hz = 0.0;        ///< 1 / median interval: the nominal rate
  double mean_rate_hz = 0.0;   ///< (samples - 1) / span
  double dt_min_s = 0.0, dt_median_s = 0.0, dt_max_s = 0.0;
  /// Intervals longer than 1.5 median intervals, and the longest of them.
  std::uint64_t gaps = 0;
  double longest_gap_s = 0.0;
  std::uint64_t duplicates = 0;  ///< samples dropped because they repeated a time tag (set by the caller)
  nlohmann::json to_json() const;
};

/// The summary of a stream from its time tags (navigation time scale, increasing).
StreamSummary summarize_stream(const std::string& name, const std::string& source, const std::vector<double>& t_s);

/// The streams of one recording: what a starting-configuration generator needs.
struct RecordingStreams {
  StreamSummary imu, gnss, reference;
  /// Time over which IMU and GNSS both have data [s] (0: they do not overlap).
  double imu_gnss_overlap_s = 0.0;
  nlohmann::json to_json() const;
};

}  // namespace tools
