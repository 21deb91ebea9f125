// What a recording's streams look like (count, span, rate, gaps): one shape for every stream of
// every import summary (IMU, GNSS solutions, raw epochs, reference; docs/import.md, "The summary's
// streams"), computed from the stream's time tags alone. A starting filter configuration is derived
// from it (navigation and EKF rates, latency frames) and the import summaries print it.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace tools {

struct StreamSummary {
  std::string name;            ///< "imu", "gnss_pvt", "gnss_raw", "reference"
  std::string source;          ///< where it came from (a topic, a file)
  std::uint64_t count = 0;     ///< samples (epochs) in the stream
  double t_first_s = 0.0, t_last_s = 0.0, span_s = 0.0;
  double rate_hz = 0.0;        ///< 1 / median interval: the nominal rate (0: fewer than 2 samples)
  double mean_rate_hz = 0.0;   ///< (count - 1) / span: counts the gaps
  double dt_min_s = 0.0, dt_median_s = 0.0, dt_max_s = 0.0;
  /// Intervals longer than 1.5 median intervals, and the longest of them.
  std::uint64_t gaps = 0;
  double longest_gap_s = 0.0;
  std::uint64_t duplicates = 0;  ///< samples dropped because they repeated a time tag (set by the caller)
  /// {"name", "source", "count", "t_first_s", "t_last_s", "span_s", "rate_hz", "mean_rate_hz",
  /// "dt_s": {"min", "median", "max"}, "gaps", "longest_gap_s", "duplicates"}.
  nlohmann::json to_json() const;
};

/// The summary of a stream from its time tags (navigation time scale, increasing).
StreamSummary summarize_stream(const std::string& name, const std::string& source, const std::vector<double>& t_s);

/// One line for a StreamSummary's JSON: "N, t_s a .. b (span s, R Hz nominal, M Hz mean, G gaps,
/// longest L s)", or "none" without samples.
std::string stream_summary_text(const nlohmann::json& s);

}  // namespace tools
