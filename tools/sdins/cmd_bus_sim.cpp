// sdins bus-sim: plays a scenario's simulated IMU and GPS receiver onto a CAN bus (the bus side of
// a HIL run), in lockstep with `sdins fsw` (flow control by FSW_ACK) or paced in real time.
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include "commands.hpp"
#include "tools/interrupt.hpp"
#include "tools/output_file.hpp"
#include "hal/can_bus.hpp"
#include "tools/hil.hpp"

namespace sdins {
namespace {

struct BusSimOptions {
  ScenarioOptions scenario;
  std::string bus;
  bool lockstep = false;
  bool realtime = false;
  int window = 200;
  double speed = 1.0;
  int pace_every = 1;
  double ack_timeout_s = 10.0;
  std::string json;
} bus_sim_opt;

}  // namespace

void register_bus_sim(CLI::App& app) {
  CLI::App* sub = app.add_subcommand(
      "bus-sim", "Play a scenario's simulated IMU and GPS receiver onto a CAN bus for `sdins fsw`: in lockstep "
                 "(as fast as the flight software acknowledges, no frame dropped) or in real time.");
  sub->add_option("--can", bus_sim_opt.bus, "bus: socketcan:IFACE, udp:PORT, udp:GROUP:PORT (this host only; append ?scope=lan to reach the network)")->required();
  add_scenario_options(sub, bus_sim_opt.scenario);
  auto* mode = sub->add_option_group("mode");
  CLI::Option* lockstep = mode->add_flag("--lockstep", bus_sim_opt.lockstep, "wait for FSW_ACK: never more than --window IMU samples ahead");
  CLI::Option* realtime = mode->add_flag("--realtime", bus_sim_opt.realtime, "pace the IMU samples on CLOCK_MONOTONIC (clock_nanosleep)");
  mode->require_option(1);
  sub->add_option("--window", bus_sim_opt.window, "lockstep: IMU samples allowed beyond the last acknowledged [samples]")
      ->capture_default_str()
      ->check(CLI::Range(1, 65535))
      ->needs(lockstep);  // docs/faults.md: an option that would do nothing is refused
  sub->add_option("--speed", bus_sim_opt.speed, "realtime: time factor (2 = twice as fast)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber)
      ->needs(realtime);
  sub->add_option("--pace-every", bus_sim_opt.pace_every, "realtime: sleep before every N-th IMU sample [samples]")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000))
      ->needs(realtime);
  sub->add_option("--ack-timeout", bus_sim_opt.ack_timeout_s,
                  "give up when no flight software answers / acknowledges for this long [s]")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  sub->add_option("--json", bus_sim_opt.json, "write the run's counters as JSON");
}

int run_bus_sim() {
  tools::require_distinct({bus_sim_opt.json}, {bus_sim_opt.scenario.file});
  const sim::Scenario sc = bus_sim_opt.scenario.load();
  sim::SensorStream stream(sc);
  hal::CanBus bus;
  if (bus.open(bus_sim_opt.bus) != hal::CanBusStatus::kOk) throw std::runtime_error(bus.last_error());
  tools::BusSimConfig cfg;
  cfg.lockstep = bus_sim_opt.lockstep;
  cfg.window_imu = bus_sim_opt.window;
  cfg.speed = bus_sim_opt.speed;
  cfg.pace_every = bus_sim_opt.pace_every;
  cfg.ack_timeout_s = bus_sim_opt.ack_timeout_s;
  cfg.seed = sc.seed;
  std::fprintf(stderr, "sdins bus-sim: %s, %s on %s, %.3f s, seed %llu\n", sc.name.c_str(),
               bus_sim_opt.lockstep ? "lockstep" : "realtime", bus_sim_opt.bus.c_str(), sc.duration_s,
               static_cast<unsigned long long>(sc.seed));
  const tools::InterruptPolling polling;  // docs/faults.md: SIGINT/SIGTERM stop the run, counters printed
  const tools::BusSimResult r = tools::run_bus_sim(bus, stream, cfg, &tools::interrupt_flag());
  std::printf("run %08x: %lld steps, %lld frames (%lld IMU, %lld GPS epochs, %lld almanac), %lld control frames, "
              "%.3f s wall\n",
              r.run_id, r.steps, r.frames_sent, r.imu_sent, r.gps_epochs, r.almanac_sent, r.control_sent, r.wall_s);
  std::printf("acks: %lld received, final %s (fsw took %u frames, %u IMU, %u nav frames); foreign frames %lld\n",
              r.acks_received, r.final_ack ? "yes" : "no", r.last_ack.frames, r.last_ack.imu_frames,
              r.last_ack.nav_frames, r.foreign_frames);
  if (bus_sim_opt.lockstep)
    std::printf("lockstep: window %d, max ahead %lld IMU samples, window full %lld times (%.3f s waited)\n", bus_sim_opt.window,
                r.max_ahead_imu, r.window_waits, r.window_wait_s);
  else
    std::printf("realtime: %lld paced sleeps, lateness mean %.6f s max %.6f s\n", r.paced, r.late_mean_s,
                r.late_max_s);
  std::printf("encoder: %lld IMU rejected, %lld flagged, %lld measurements skipped, %lld epochs rejected, %lld "
              "almanac rejected; tx busy retries %lld\n",
              r.imu_rejected, r.imu_flagged, r.gps_skipped, r.gps_rejected, r.almanac_rejected, r.tx_busy_retries);
  if (!bus_sim_opt.json.empty()) tools::write_json_file(bus_sim_opt.json, tools::to_json(r));
  if (tools::interrupted()) {
    std::fprintf(stderr, "sdins bus-sim: stopped by %s\n", tools::interrupt_signal_name().c_str());
    return tools::interrupt_exit_code();
  }
  if (!r.ok) {
    std::fprintf(stderr, "sdins bus-sim: error: %s\n", r.error.c_str());
    return 3;
  }
  return 0;
}

}  // namespace sdins
