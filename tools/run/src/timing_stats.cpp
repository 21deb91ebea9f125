#include "tools/timing_stats.hpp"

#include <algorithm>
#include <cmath>

namespace tools {

TimingStats timing_stats(std::vector<double> v) {
  TimingStats s;
  s.n = static_cast<long>(v.size());
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  auto rank = [&v](double q) {  // nearest rank: the smallest value with at least q of the samples at or below it
    const std::size_t r = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
    return v[std::min(v.size() - 1, r == 0 ? 0 : r - 1)] * 1e6;
  };
  for (double x : v) s.total_s += x;
  s.min_us = v.front() * 1e6;
  s.max_us = v.back() * 1e6;
  s.median_us = rank(0.5);
  s.p99_us = rank(0.99);
  s.p999_us = rank(0.999);
  s.mean_us = s.total_s / static_cast<double>(v.size()) * 1e6;
  return s;
}

}  // namespace tools
