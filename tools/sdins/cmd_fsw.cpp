// sdins fsw: the flight software as its own process, fed by a CAN bus (the flight side of a HIL
// run). Answers `sdins bus-sim` with FSW_ACK; ends on the run's SIM_CONTROL end (exit 0) or after
// --idle-timeout seconds without frames (exit 2, a silent bus).
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include "commands.hpp"
#include "cfg/flight_config.hpp"
#include "hal/can_bus.hpp"
#include "tools/hil.hpp"
#include "tools/fsw_report.hpp"
#include "tools/interrupt.hpp"
#include "tools/output_file.hpp"

namespace sdins {
namespace {

struct FswOptions {
  std::string bus;
  FswRunOptions run;  ///< --model, --log, --lcm-url, --nav-decimation, --json, --filter-config
  bool realtime = false;
  double idle_timeout_s = 5.0;
  int fifo_priority = 50;
} fsw_opt;

void warn(const std::string& m) { std::fprintf(stderr, "sdins fsw: %s\n", m.c_str()); }

}  // namespace

void register_fsw(CLI::App& app) {
  CLI::App* sub = app.add_subcommand(
      "fsw", "Run the flight software fed by a CAN bus (IMU and GPS frames of hal/can/sdins.dbc), with LCM "
             "telemetry and log; answers `sdins bus-sim` with FSW_ACK. Exit 0: end of run; 2: silent bus; 130/143: "
             "stopped by SIGINT/SIGTERM (summary, log and --json complete).");
  sub->add_option("--can", fsw_opt.bus, "bus: socketcan:IFACE, udp:PORT, udp:GROUP:PORT (this host only; append ?scope=lan to reach the network)")->required();
  add_fsw_run_options(sub, fsw_opt.run, "");
  CLI::Option* realtime = sub->add_flag("--realtime", fsw_opt.realtime,
                "real-time mode: SCHED_FIFO when permitted, minor-frame execution times (overruns), IMU lateness");
  sub->add_option("--fifo-priority", fsw_opt.fifo_priority, "realtime: SCHED_FIFO priority")
      ->capture_default_str()
      ->check(CLI::Range(1, 99))
      ->needs(realtime);  // docs/faults.md: an option that would do nothing is refused
  sub->add_option("--idle-timeout", fsw_opt.idle_timeout_s, "stop after this long without frames [s]")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
}

int run_fsw() {
  tools::require_distinct({fsw_opt.run.log, fsw_opt.run.json}, {fsw_opt.run.flight_config});
  tools::FswRunConfig cfg;
  const cfg::FlightConfig flight = fsw_opt.run.flight();  // the shipped config/default.toml, --flight-config on top
  cfg::require_raw_gnss(flight, "--flight-config", "the CAN bus carries raw GNSS epochs (hal/can/sdins.dbc)");
  cfg.node = fsw_opt.run.node_config(flight);
  cfg.realtime = fsw_opt.realtime;
  cfg.fifo_priority = fsw_opt.fifo_priority;
  cfg.idle_timeout_s = fsw_opt.idle_timeout_s;
  hal::CanBus bus;
  if (bus.open(fsw_opt.bus) != hal::CanBusStatus::kOk) throw std::runtime_error(bus.last_error());
  std::fprintf(stderr, "sdins fsw: %s-state model listening on %s\n", fsw_opt.run.model.c_str(), fsw_opt.bus.c_str());
  // SIGINT/SIGTERM (docs/faults.md): the loop stops, the log is closed complete, the summary and
  // --json are written, exit 128 + signal.
  const tools::InterruptPolling polling;
  const tools::FswRunResult r = tools::run_fsw(bus, cfg, &tools::interrupt_flag(), &warn);
  if (r.exit == tools::FswExit::kError) throw std::runtime_error(r.error);

  if (r.exit == tools::FswExit::kStopped)
    std::printf("stopped by %s%s\n", tools::interrupt_signal_name().c_str(),
                r.run_started ? " during the run (no SIM_CONTROL end)" : " (no run started)");
  else if (r.exit == tools::FswExit::kIdleTimeout)
    std::printf("silent bus: no frame for %.3f s, stopping%s\n", r.idle_timeout_s,
                r.end_received ? "" : (r.run_started ? " (run started, no SIM_CONTROL end)" : " (no run started)"));
  else
    std::printf("end of run %08x received\n", r.run.run_id);
  const fsw::NavState& n = r.summary.last_nav;
  const double deg = fsw::kRadToDeg;
  std::printf("initialised: %s", r.summary.initialised ? "yes" : "no");
  if (r.summary.initialised) std::printf(" at t=%.3f s", r.summary.init_t_s);
  std::printf("\nnav frames: %llu  digest: %s\n", static_cast<unsigned long long>(r.summary.nav_frames),
              tools::digest_hex(r.summary.digest).c_str());
  std::printf("last position: t=%.3f s lat=%.9f deg lon=%.9f deg h=%.3f m vel_enu=%.4f,%.4f,%.4f m/s\n", n.t_s,
              n.llh(0) * deg, n.llh(1) * deg, n.llh(2), n.vel_enu_mps(0), n.vel_enu_mps(1), n.vel_enu_mps(2));
  const fsw::ExecutiveHealth& e = r.exec;
  std::printf("executive: ticks=%u nav_frames=%u ekf_runs=%u ekf_updates=%u ekf_without_gnss=%u imu_rejected=%u "
              "imu_time_gaps=%u gnss_stale=%u pr_used=%u pr_rejected=%u overruns=%u worst_tick_s=%.6f fsw_errors=%u\n",
              e.ticks, e.nav_frames, e.ekf_runs, e.ekf_updates, e.ekf_without_gnss, e.imu_rejected, e.imu_time_gaps,
              e.gnss_stale, e.pr_used, e.pr_rejected, e.overruns, e.worst_tick_s, e.fsw_errors);
  tools::print_configuration_warnings(e);
  std::printf("frames: received=%llu data=%llu imu=%llu imu_delivered=%llu control=%llu control_rejected=%llu "
              "foreign_acks=%llu acks_sent=%llu\n",
              static_cast<unsigned long long>(r.frames_received), static_cast<unsigned long long>(r.data_frames),
              static_cast<unsigned long long>(r.imu_frames), static_cast<unsigned long long>(r.imu_delivered),
              static_cast<unsigned long long>(r.control_frames), static_cast<unsigned long long>(r.control_rejected),
              static_cast<unsigned long long>(r.foreign_acks), static_cast<unsigned long long>(r.acks_sent));
  std::printf("assembler: rejections=%u", r.rx.rejections());
  r.rx.for_each([](const char* name, std::uint32_t v) {
    if (v != 0) std::printf(" %s=%u", name, v);
  });
  std::printf("\ntelemetry: lcm %s published=%llu send_failures=%llu; log %s events=%llu failures=%llu\n",
              r.lcm_network ? "on" : "off", static_cast<unsigned long long>(r.lcm_published),
              static_cast<unsigned long long>(r.lcm_send_failures), r.log_path.empty() ? "(none)" : r.log_path.c_str(),
              static_cast<unsigned long long>(r.lcm_logged), static_cast<unsigned long long>(r.lcm_log_failures));
  if (r.realtime)
    std::printf("realtime: %s; minor frames timed=%llu exec mean=%.6f s max=%.6f s (CPU max %.6f s) overruns=%u "
                "(execution %llu, stalled %llu); IMU lateness mean=%.6f s max=%.6f s late(>%.3f s)=%llu missing=%u\n",
                r.sched_note.c_str(), static_cast<unsigned long long>(r.minor_frames_timed), r.exec_mean_s,
                r.exec_max_s, r.exec_cpu_max_s, e.overruns, static_cast<unsigned long long>(r.overruns_execution),
                static_cast<unsigned long long>(r.overruns_stalled), r.imu_lateness_mean_s, r.imu_lateness_max_s,
                r.late_threshold_s,
                static_cast<unsigned long long>(r.imu_late), r.rx.imu_missing);
  if (r.realtime && r.minor_frames_timed > 0)
    std::printf("realtime: longest minor frame %.6f s at INS time %.3f s (%s)\n", r.exec_max_s, r.exec_max_t_s,
                r.exec_max_work.c_str());
  std::printf("bus %s: %s\n", fsw_opt.bus.c_str(), hal::to_string(r.bus).c_str());
  if (r.bus.foreign_dropped > 0)
    std::printf("WARNING: %llu datagrams from other hosts dropped (the bus is local to this host; docs/can.md: "
                "?scope=lan to take frames from the network)\n",
                static_cast<unsigned long long>(r.bus.foreign_dropped));
  std::printf("wall time: %.3f s\n", r.wall_s);
  if (!fsw_opt.run.json.empty()) tools::write_json_file(fsw_opt.run.json, tools::to_json(r));
  if (r.exit == tools::FswExit::kStopped) return tools::interrupt_exit_code();
  return r.exit == tools::FswExit::kEndOfRun ? 0 : 2;
}

}  // namespace sdins
