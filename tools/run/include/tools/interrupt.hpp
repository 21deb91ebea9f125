// SIGINT / SIGTERM for the sdins commands (docs/faults.md, "Signals").
//
// install_interrupt_handlers() (called once by main) installs one async-signal-safe handler:
//  - while a long run polls for it (an InterruptPolling scope is alive: fsw, bus-sim, montecarlo,
//    paper, diagnose, replay), the first signal only sets a flag (interrupted()); the run stops at
//    its next poll, prints what it has so far, leaves its outputs complete (a live run's log and
//    summary) or absent (a batch run's results), and main exits with interrupt_exit_code();
//  - otherwise, or on a second signal, the handler removes every temporary output file
//    (hal::remove_pending_outputs(): the targets keep their old contents) and _exit()s at once.
// Exit code: 128 + the signal number (130 SIGINT, 143 SIGTERM), the shell's convention.
#pragma once

#include <atomic>
#include <stdexcept>
#include <string>

#include "fsw/driver.hpp"

namespace tools {

void install_interrupt_handlers();
/// The flag the handler sets (for loops that take a const std::atomic<bool>* stop).
const std::atomic<bool>& interrupt_flag();
inline bool interrupted() { return interrupt_flag().load(std::memory_order_relaxed); }
/// The signal received (0: none).
int interrupt_signal();
/// 128 + the signal (130 when none was recorded).
int interrupt_exit_code();
/// "SIGINT" / "SIGTERM".
std::string interrupt_signal_name();

/// While alive, the first SIGINT/SIGTERM sets the flag instead of ending the process.
class InterruptPolling {
 public:
  InterruptPolling();
  ~InterruptPolling();
  InterruptPolling(const InterruptPolling&) = delete;
  InterruptPolling& operator=(const InterruptPolling&) = delete;
};

/// Thrown by a batch run that stopped on the flag; main prints it and returns interrupt_exit_code().
class Interrupted : public std::runtime_error {
 public:
  explicit Interrupted(const std::string& what) : std::runtime_error(what) {}
};
/// Throws Interrupted(what) when the flag is set.
void throw_if_interrupted(const std::string& what);

/// An event source (fsw/driver.hpp) that ends at the first event after SIGINT/SIGTERM.
template <fsw::EventSource Source>
struct UntilInterrupted {
  Source& src;
  const fsw::InputEvent* next() { return interrupted() ? nullptr : src.next(); }
};

}  // namespace tools
