// Clocks and real-time scheduling for the HIL processes (`sdins bus-sim`, `sdins fsw`): the only
// place outside the transports where the project reads a clock or sleeps. Nothing throws; calls
// that can fail return a status and a reason in words.
#pragma once

#include <string>

namespace hal {

/// CLOCK_MONOTONIC now [s] (pacing, execution times, lateness).
double mono_now_s();
/// CLOCK_THREAD_CPUTIME_ID now [s]: CPU time the calling thread has run. Set against the monotonic
/// clock it tells execution from time the thread spent switched out or stalled.
double thread_cpu_now_s();
/// CLOCK_REALTIME now [s] (the time scale of CAN frame receive timestamps).
double wall_now_s();
/// Sleeps until CLOCK_MONOTONIC reaches t_s (clock_nanosleep with TIMER_ABSTIME, restarted after
/// signals). Returns how late it woke [s] (>= 0; 0 when t_s had already passed, measured after the
/// call either way).
double sleep_until_mono_s(double t_s);

enum class RtSchedStatus { kOk, kNotPermitted, kError };
/// Switches the calling thread to SCHED_FIFO at priority (1..99, clamped to the system range).
/// kNotPermitted (EPERM: no CAP_SYS_NICE / RLIMIT_RTPRIO) or kError, with the reason in why.
RtSchedStatus try_sched_fifo(int priority, std::string& why);

}  // namespace hal
