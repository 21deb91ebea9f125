// Execution-time statistics of a task's samples: what the timing audit, the HIL report and the
// flight software's own timing report (fsw_report.hpp) state for each task.
#pragma once

#include <vector>

namespace tools {

struct TimingStats {
  long n = 0;
  double min_us = 0, median_us = 0, p99_us = 0, p999_us = 0, max_us = 0, mean_us = 0;
  double total_s = 0;  ///< sum of all samples
};

/// Order statistics (nearest rank) of execution times in seconds.
TimingStats timing_stats(std::vector<double> samples_s);

}  // namespace tools
