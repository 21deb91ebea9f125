#include "hal/rt_clock.hpp"

#include <cerrno>
#include <cstring>
#include <ctime>
#include <sched.h>

namespace hal {
namespace {
double now_s(clockid_t c) {
  timespec ts{};
  clock_gettime(c, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}
}  // namespace

double mono_now_s() { return now_s(CLOCK_MONOTONIC); }
double wall_now_s() { return now_s(CLOCK_REALTIME); }
double thread_cpu_now_s() { return now_s(CLOCK_THREAD_CPUTIME_ID); }

double sleep_until_mono_s(double t_s) {
  if (t_s > mono_now_s()) {
    timespec ts{};
    ts.tv_sec = static_cast<time_t>(t_s);
    ts.tv_nsec = static_cast<long>((t_s - static_cast<double>(ts.tv_sec)) * 1e9);
    if (ts.tv_nsec >= 1000000000L) {
      ts.tv_sec += 1;
      ts.tv_nsec -= 1000000000L;
    }
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
  }
  const double late = mono_now_s() - t_s;
  return late > 0.0 ? late : 0.0;
}

RtSchedStatus try_sched_fifo(int priority, std::string& why) {
  const int lo = sched_get_priority_min(SCHED_FIFO), hi = sched_get_priority_max(SCHED_FIFO);
  if (priority < lo) priority = lo;
  if (priority > hi) priority = hi;
  sched_param p{};
  p.sched_priority = priority;
  // pid 0: the calling thread (Linux schedules threads individually).
  const int rc = sched_setscheduler(0, SCHED_FIFO, &p) == 0 ? 0 : errno;
  if (rc == 0) {
    why = "SCHED_FIFO priority " + std::to_string(priority);
    return RtSchedStatus::kOk;
  }
  why = std::string("SCHED_FIFO priority ") + std::to_string(priority) + " refused: " + std::strerror(rc);
  return rc == EPERM ? RtSchedStatus::kNotPermitted : RtSchedStatus::kError;
}

}  // namespace hal
