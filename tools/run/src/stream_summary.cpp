// Stream summaries (tools/stream_summary.hpp).
#include "tools/stream_summary.hpp"

#include <algorithm>
#include <cstdio>

namespace tools {

StreamSummary summarize_stream(const std::string& name, const std::string& source, const std::vector<double>& t_s) {
  StreamSummary s;
  s.name = name;
  s.source = source;
  s.count = t_s.size();
  if (t_s.empty()) return s;
  s.t_first_s = t_s.front();
  s.t_last_s = t_s.back();
  s.span_s = s.t_last_s - s.t_first_s;
  if (t_s.size() < 2) return s;
  std::vector<double> dt(t_s.size() - 1);
  for (std::size_t k = 1; k < t_s.size(); ++k) dt[k - 1] = t_s[k] - t_s[k - 1];
  std::vector<double> sorted = dt;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
  s.dt_median_s = sorted[sorted.size() / 2];
  s.dt_min_s = *std::min_element(dt.begin(), dt.end());
  s.dt_max_s = *std::max_element(dt.begin(), dt.end());
  s.rate_hz = s.dt_median_s > 0.0 ? 1.0 / s.dt_median_s : 0.0;
  s.mean_rate_hz = s.span_s > 0.0 ? static_cast<double>(t_s.size() - 1) / s.span_s : 0.0;
  for (double d : dt)
    if (d > 1.5 * s.dt_median_s) {
      ++s.gaps;
      s.longest_gap_s = std::max(s.longest_gap_s, d);
    }
  return s;
}

nlohmann::json StreamSummary::to_json() const {
  return {{"name", name},
          {"source", source},
          {"count", count},
          {"t_first_s", t_first_s},
          {"t_last_s", t_last_s},
          {"span_s", span_s},
          {"rate_hz", rate_hz},
          {"mean_rate_hz", mean_rate_hz},
          {"dt_s", {{"min", dt_min_s}, {"median", dt_median_s}, {"max", dt_max_s}}},
          {"gaps", gaps},
          {"longest_gap_s", longest_gap_s},
          {"duplicates", duplicates}};
}

std::string stream_summary_text(const nlohmann::json& s) {
  if (!s.is_object() || s.value("count", std::uint64_t{0}) == 0) return "none";
  char b[300];
  std::snprintf(b, sizeof(b), "%llu, t_s %.3f .. %.3f (%.3f s, %.3f Hz nominal, %.3f Hz mean, %llu gaps, longest %.3f s)",
                static_cast<unsigned long long>(s["count"].get<std::uint64_t>()), s["t_first_s"].get<double>(),
                s["t_last_s"].get<double>(), s["span_s"].get<double>(), s["rate_hz"].get<double>(),
                s["mean_rate_hz"].get<double>(), static_cast<unsigned long long>(s["gaps"].get<std::uint64_t>()),
                s["longest_gap_s"].get<double>());
  return b;
}

}  // namespace tools
