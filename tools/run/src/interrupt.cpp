#include "tools/interrupt.hpp"

#include <unistd.h>

#include <csignal>
#include <cstring>

#include "hal/output_file.hpp"

namespace tools {
namespace {

std::atomic<bool> g_flag{false};
std::atomic<int> g_signal{0};
std::atomic<int> g_polling{0};

void write_err(const char* s) {
  const ssize_t n = ::write(STDERR_FILENO, s, std::strlen(s));
  (void)n;
}

extern "C" void on_signal(int sig) {
  int expected = 0;
  if (g_polling.load() > 0 && g_signal.compare_exchange_strong(expected, sig)) {
    g_flag.store(true);
    write_err(sig == SIGTERM ? "sdins: SIGTERM: stopping at the next check\n" : "sdins: SIGINT: stopping at the next check\n");
    return;
  }
  // Not polled, or a second signal: no partial output is left behind (targets keep their old contents).
  hal::remove_pending_outputs();
  write_err(sig == SIGTERM ? "sdins: SIGTERM: stopped, no output written\n" : "sdins: SIGINT: stopped, no output written\n");
  ::_exit(128 + sig);
}

}  // namespace

void install_interrupt_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

const std::atomic<bool>& interrupt_flag() { return g_flag; }
int interrupt_signal() { return g_signal.load(); }
int interrupt_exit_code() { return 128 + (g_signal.load() != 0 ? g_signal.load() : SIGINT); }
std::string interrupt_signal_name() { return g_signal.load() == SIGTERM ? "SIGTERM" : "SIGINT"; }

InterruptPolling::InterruptPolling() { g_polling.fetch_add(1); }
InterruptPolling::~InterruptPolling() { g_polling.fetch_sub(1); }

void throw_if_interrupted(const std::string& what) {
  if (interrupted()) throw Interrupted(interrupt_signal_name() + ": " + what);
}

}  // namespace tools
