// sdins: the one user-facing command line of the project.
#include <CLI/CLI.hpp>
#include <fcntl.h>
#include <poll.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <iostream>

#include "commands.hpp"
#include "cfg/data_dir.hpp"
#include "tools/interrupt.hpp"
#include "numeric_options.hpp"

namespace {

/// docs/faults.md, "standard streams": a descriptor 0, 1 or 2 that is closed at start is opened on
/// /dev/null, so the next file the command opens cannot become its stdout (printed tables would land
/// inside a CSV) or its stderr.
void open_missing_std_streams() {
  for (int fd = 0; fd <= 2; ++fd) {
    if (::fcntl(fd, F_GETFD) != -1 || errno != EBADF) continue;
    const int n = ::open("/dev/null", fd == 0 ? O_RDONLY : O_WRONLY);
    if (n < 0) ::_exit(125);  // nowhere to say it; without /dev/null nothing is safe to open
    if (n != fd) {  // cannot happen (the lowest free descriptor is fd), but do not leave it astray
      ::dup2(n, fd);
      ::close(n);
    }
  }
}

/// stdout on a file or a device (not a terminal, not a pipe: their readers expect the usual
/// buffering) gets a 1 MiB buffer, so that a write error on it usually happens in finish_stdout()'s
/// flush, where its errno is known ("No space left on device"), rather than in an earlier flush.
void buffer_stdout_for_files() {
  struct stat st {};
  if (::isatty(1) || ::fstat(1, &st) != 0 || !(S_ISREG(st.st_mode) || S_ISCHR(st.st_mode))) return;
  (void)std::setvbuf(stdout, nullptr, _IOFBF, 1 << 20);
}

/// Flushes stdout and reports a write error on it (a full disk behind a redirect, a closed pipe
/// when SIGPIPE is ignored): the command's exit code becomes 1 when it was 0.
int finish_stdout(int rc) {
  errno = 0;
  const bool flush_failed = std::fflush(stdout) != 0;  // first: std::cout's flush is this fflush too
  int e = flush_failed ? errno : 0;
  std::cout.flush();
  if (e == 0) {  // the error came from an earlier flush; a closed pipe still says so
    pollfd p{1, POLLOUT, 0};
    if (::poll(&p, 1, 0) == 1 && (p.revents & POLLERR) != 0) e = EPIPE;
  }
  if (!flush_failed && !std::cout.bad() && std::ferror(stdout) == 0) return rc;
  std::fprintf(stderr, "sdins: error: writing standard output failed: %s\n",
               e != 0 ? std::strerror(e) : "an earlier write failed (output incomplete)");
  return rc == 0 ? 1 : rc;
}

int run(int argc, char** argv) {
  CLI::App app{
      "sdins: SDINS/GPS integrated navigation for bank-to-turn aircraft.\n"
      "Flight-software core (200 Hz strapdown mechanization), truth simulator and analysis tools."};
  app.require_subcommand(1);
  app.fallthrough();  // --data-dir may follow the subcommand
  app.set_version_flag("--version", "sdins " SDINS_VERSION);
  // Set while parsing (before --help prints the footer that names the data directory).
  app.add_option_function<std::string>(
      "--data-dir", [](const std::string& dir) { cfg::set_data_dir_override(dir); },
                 "the product's data directory (almanac, scenarios, filter configurations, DBC, LCM definitions, "
                 "plot scripts; default: $SDINS_DATA_DIR, else ../share/sdins beside the executable)");
  app.footer([] {
    const cfg::DataDirLookup d = cfg::find_data_dir();
    return d.ok() ? "Data directory: " + d.path + " (" + cfg::to_string(d.source) + ")"
                  : "Data directory: " + d.error;
  });
  sdins::register_analyze(app);
  sdins::register_scenario(app);
  sdins::register_fly(app);
  sdins::register_montecarlo(app);
  sdins::register_paper(app);
  sdins::register_sil(app);
  sdins::register_replay(app);
  sdins::register_log(app);
  sdins::register_can(app);
  sdins::register_audit(app);
  sdins::register_bus_sim(app);
  sdins::register_fsw(app);
  sdins::register_diagnose(app);
  sdins::register_sim(app);
  sdins::register_import(app);
  sdins::register_noise(app);
  tools::require_valid_values(app);  // docs/faults.md: NaN, infinities, integers beyond 64 bits, non-UTF-8 refused
  tools::install_interrupt_handlers();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    return sdins::run_selected(app);
  } catch (const tools::Interrupted& e) {
    std::fprintf(stderr, "sdins: interrupted: %s\n", e.what());
    return tools::interrupt_exit_code();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sdins: error: %s\n", e.what());
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) {
  open_missing_std_streams();
  buffer_stdout_for_files();
  return finish_stdout(run(argc, argv));
}
