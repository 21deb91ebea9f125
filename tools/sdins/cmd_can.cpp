// sdins can {encode, dump, record, play}: the CAN bus tools (protocol in hal/can/sdins.dbc).
//   encode  flies a scenario's sensors (IMU + GPS receiver models) into a candump log of protocol
//           frames, optionally with a CSV of the expected physical values for independent decoders
//   dump    decodes frames from a bus or a log and prints the physical values and health counters
//   record  copies frames from a bus into a candump log
//   play    sends a candump log's frames onto a bus (as fast as possible or at log time)
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <fstream>
#include <stdexcept>
#include <thread>

#include "commands.hpp"
#include "numeric_options.hpp"
#include "tools/interrupt.hpp"
#include "tools/output_file.hpp"
#include "hal/can_bus.hpp"
#include "hal/can_log.hpp"
#include "hal/can_protocol.hpp"
#include "hal/can_rx_assembler.hpp"
#include "sim/sensor_stream.hpp"

namespace sdins {
namespace {

struct CanOptions {
  // encode
  ScenarioOptions scenario;
  std::string out;
  std::string expected;
  std::string iface = "can0";
  // dump / record / play
  std::string bus;
  std::string log;
  long long count = 0;
  double timeout_s = 2.0;
  bool quiet = false;
  bool realtime = false;
  double speed = 1.0;
  double gap_s = 0.0;
} can_opt;

CLI::App* g_encode = nullptr;
CLI::App* g_dump = nullptr;
CLI::App* g_record = nullptr;
CLI::App* g_play = nullptr;

double lsb_dtheta() { return 1.0 / hal::can::kDthetaPerRad; }
double lsb_dv() { return 1.0 / hal::can::kDvPerMps; }

/// Long-format CSV of the values the frames must decode to: line, message, signal, value,
/// tolerance. Values are the encoder's inputs (not decoded frames), so an independent decoder
/// checks the whole chain: scaling, layout, and the residual-carry quantization bound.
class ExpectedCsv {
 public:
  void open(const std::string& path) {
    f_.emplace(path);  // docs/faults.md: a temporary file renamed into place by commit()
    f_->os() << "line,message,signal,value,tolerance\n";
    f_->os().precision(17);
  }
  void row(long line, const char* msg, const char* sig, double value, double tol) {
    if (f_) f_->os() << line << ',' << msg << ',' << sig << ',' << value << ',' << tol << '\n';
  }
  /// An IMU_SAMPLE frame's values. Residual carry: each transmitted increment is within one LSB of
  /// the true one.
  void imu_rows(long line, const fsw::ImuSample& s) {
    const char* m = "IMU_SAMPLE";
    row(line, m, "ImuTimeTag", s.t_s, 0.5e-9 + 1e-12 * std::abs(s.t_s));
    row(line, m, "ImuDt", s.dt_s, 0.5e-9);
    const char* th[3] = {"DeltaThetaX", "DeltaThetaY", "DeltaThetaZ"};
    const char* dv[3] = {"DeltaVX", "DeltaVY", "DeltaVZ"};
    for (int i = 0; i < 3; ++i) {
      row(line, m, th[i], s.dtheta_rad(i), 1.0001 * lsb_dtheta());
      row(line, m, dv[i], s.dv_mps(i), 1.0001 * lsb_dv());
    }
  }
  /// A GPS_ALMANAC frame's values, each within half its LSB.
  void almanac_rows(long line, const fsw::GpsAlmanac& x) {
    const char* m = "GPS_ALMANAC";
    const double pi = hal::can::kSemicircle_rad;
    const double angle_tol = 0.5001 * hal::can::kAlmAngleLsb_sc * pi + 1e-15;
    row(line, m, "AlmPrn", x.prn, 0.0);
    row(line, m, "AlmHealth", x.health, 0.0);
    row(line, m, "AlmWeek", x.week_mod_1024, 0.0);
    row(line, m, "AlmToa", x.toa_s, 0.5 * hal::can::kAlmToaLsb_s);
    row(line, m, "AlmEccentricity", x.eccentricity, 0.5001 * hal::can::kAlmEccLsb);
    row(line, m, "AlmInclination", x.inclination_rad, angle_tol);
    row(line, m, "AlmOmegaDot", x.omega_dot_radps, 0.5001 * hal::can::kAlmOmegaDotLsb_scps * pi);
    row(line, m, "AlmSqrtA", x.sqrt_a_sqrtm, 0.5001 * hal::can::kAlmSqrtALsb);
    row(line, m, "AlmOmega0", x.omega0_rad, angle_tol);
    row(line, m, "AlmArgPerigee", x.arg_perigee_rad, angle_tol);
    row(line, m, "AlmMeanAnomaly", x.mean_anomaly_rad, angle_tol);
    row(line, m, "AlmAf0", x.af0_s, 0.5001 * hal::can::kAlmAf0Lsb_s);
    row(line, m, "AlmAf1", x.af1_sps, 0.5001 * hal::can::kAlmAf1Lsb_sps);
  }
  bool is_open() const { return f_.has_value(); }
  void commit() {
    if (f_) f_->commit();
  }

 private:
  std::optional<tools::TextOutput> f_;
};

int run_encode() {
  tools::require_distinct({can_opt.out, can_opt.expected}, {can_opt.scenario.file});
  const sim::Scenario sc = can_opt.scenario.load();
  sim::SensorStream stream(sc, sim::TruthThread::kOwn);  // the writer leaves the second core idle
  hal::CandumpWriter w;
  if (!w.open(can_opt.out)) throw std::runtime_error(w.error());
  ExpectedCsv csv;
  if (!can_opt.expected.empty()) csv.open(can_opt.expected);

  // One encoder state per bus (IMU residual and counter, GPS epoch sequence), as
  // hal::can::CanStepEncoder keeps it; frames are written one by one to pair them with the CSV.
  hal::can::CanStepEncoder enc;
  const std::vector<fsw::GpsAlmanac>& alm = stream.almanac();
  sim::SensorStep step;
  long line = 0;
  std::size_t alm_next = 0;
  bool first = true;
  long n_imu = 0, n_epochs = 0, n_alm = 0;
  int imu_rejected = 0, imu_flagged = 0, gps_skipped = 0, gps_rejected = 0, alm_rejected = 0;
  auto put = [&](hal::CanFrame& f, double t) {
    f.timestamp_s = t;
    if (!w.write(f, can_opt.iface)) throw std::runtime_error(w.error());
    ++line;
  };
  while (stream.next(step)) {
    double t_end = 0.0;
    for (const fsw::ImuSample& s : step.imu) {
      hal::CanFrame f;
      const hal::can::CodecStatus st = enc.imu().encode(s, f);
      if (st != hal::can::CodecStatus::kOk && st != hal::can::CodecStatus::kFlagged) {
        ++imu_rejected;
        continue;
      }
      if (st == hal::can::CodecStatus::kFlagged) ++imu_flagged;
      put(f, s.t_s);
      t_end = s.t_s;
      ++n_imu;
      csv.imu_rows(line, s);
    }
    if (step.has_epoch) {
      const fsw::GnssRawEpoch& e = step.epoch;
      hal::CanFrame frames[hal::can::GpsEncoder::kMaxFrames];
      int n = 0, skipped = 0;
      if (enc.gps().encode(e, frames, n, skipped) != hal::can::CodecStatus::kOk) {
        ++gps_rejected;
      } else {
        gps_skipped += skipped;
        ++n_epochs;
        put(frames[0], t_end);
        csv.row(line, "GPS_EPOCH", "GpsWeek", e.gps_week, 0.0);
        csv.row(line, "GPS_EPOCH", "GpsTow", e.gps_tow_s, 0.5e-9 + 1e-15 * e.gps_tow_s);
        csv.row(line, "GPS_EPOCH", "GpsRxTimeTag", e.t_s, 0.5e-9 + 1e-12 * std::abs(e.t_s));
        csv.row(line, "GPS_EPOCH", "GpsNumMeas", n - 1, 0.0);
        int j = 0;
        for (int i = 0; i < e.n_meas; ++i) {
          const fsw::GnssRawMeasurement& mm = e.meas[static_cast<std::size_t>(i)];
          hal::CanFrame scratch;
          if (hal::can::encode_gps_meas(0, 0, mm, scratch) != hal::can::CodecStatus::kOk) continue;  // left out
          put(frames[1 + j], t_end);
          csv.row(line, "GPS_MEAS", "GpsMeasIndex", j, 0.0);
          csv.row(line, "GPS_MEAS", "GpsPrn", mm.prn, 0.0);
          csv.row(line, "GPS_MEAS", "GpsPseudorange", mm.pseudorange_m, 0.5e-4 + 1e-15 * mm.pseudorange_m);
          csv.row(line, "GPS_MEAS", "GpsPseudorangeRate", mm.pseudorange_rate_mps, 0.5e-4);
          csv.row(line, "GPS_MEAS", "GpsCn0", mm.cn0_dbhz, 0.5e-2);
          ++j;
        }
      }
    }
    // The whole almanac with the first step, then one PRN per epoch (round robin).
    std::vector<const fsw::GpsAlmanac*> send;
    if (first) {
      for (const fsw::GpsAlmanac& x : alm) send.push_back(&x);
    } else if (step.has_epoch && !alm.empty()) {
      send.push_back(&alm[alm_next]);
      alm_next = (alm_next + 1) % alm.size();
    }
    first = false;
    for (const fsw::GpsAlmanac* px : send) {
      const fsw::GpsAlmanac& x = *px;
      hal::CanFrame f;
      if (hal::can::encode_gps_almanac(x, f) != hal::can::CodecStatus::kOk) {
        ++alm_rejected;
        continue;
      }
      put(f, t_end);
      ++n_alm;
      csv.almanac_rows(line, x);
    }
  }
  if (!w.close()) throw std::runtime_error("cannot write " + w.error());
  csv.commit();
  std::printf("sdins can encode: %d frames (%ld IMU samples, %ld GPS epochs, %ld almanac) -> %s\n", w.frames(), n_imu,
              n_epochs, n_alm, can_opt.out.c_str());
  std::printf("  encoder: %d IMU samples rejected, %d flagged, %d measurements skipped, %d epochs rejected, %d almanac "
              "entries rejected\n",
              imu_rejected, imu_flagged, gps_skipped, gps_rejected, alm_rejected);
  return 0;
}

void print_health(const hal::CanRxHealth& h) {
  std::printf("health:");
  h.for_each([](const char* name, std::uint32_t v) { std::printf(" %s=%u", name, v); });
  std::printf("\n");
}

void print_bus_stats(const hal::CanBus& bus) {
  std::printf("bus %s: %s\n", bus.name().c_str(), hal::to_string(bus.stats()).c_str());
}

void drain(hal::CanRxAssembler& rx, long long& items) {
  fsw::ImuSample s;
  while (rx.pop_imu(s)) {
    ++items;
    if (!can_opt.quiet)
      std::printf("imu t=%.9f dt=%.9f dtheta_rad=%.11e,%.11e,%.11e dv_mps=%.9e,%.9e,%.9e\n", s.t_s, s.dt_s,
                  s.dtheta_rad(0), s.dtheta_rad(1), s.dtheta_rad(2), s.dv_mps(0), s.dv_mps(1), s.dv_mps(2));
  }
  fsw::GnssRawEpoch e;
  while (rx.pop_gps(e)) {
    ++items;
    if (can_opt.quiet) continue;
    std::printf("gps t=%.9f week=%d tow_s=%.9f n_meas=%d\n", e.t_s, e.gps_week, e.gps_tow_s, e.n_meas);
    for (int i = 0; i < e.n_meas; ++i) {
      const fsw::GnssRawMeasurement& m = e.meas[static_cast<std::size_t>(i)];
      std::printf("  prn=%d pseudorange_m=%.4f pseudorange_rate_mps=%.4f cn0_dbhz=%.2f\n", m.prn, m.pseudorange_m,
                  m.pseudorange_rate_mps, m.cn0_dbhz);
    }
  }
  fsw::GpsAlmanac a;
  while (rx.pop_almanac(a)) {
    ++items;
    if (!can_opt.quiet)
      std::printf("almanac prn=%d health=%d week=%d toa_s=%.4f e=%.10e i0_rad=%.12f omegadot_radps=%.6e sqrtA=%.8f "
                  "omega0_rad=%.12f w_rad=%.12f M0_rad=%.12f af0_s=%.6e af1_sps=%.6e\n",
                  a.prn, a.health, a.week_mod_1024, a.toa_s, a.eccentricity, a.inclination_rad, a.omega_dot_radps,
                  a.sqrt_a_sqrtm, a.omega0_rad, a.arg_perigee_rad, a.mean_anomaly_rad, a.af0_s, a.af1_sps);
  }
}

/// Receives frames from bus into on_frame(f), counted in n, until can_opt.count of them (0: no limit),
/// a signal ("SIGNAL: <stopped>" printed; the signal's exit code) or a silent bus for can_opt.timeout_s
/// (printed; exit code 2 when a count was asked for, else 0). Returns the exit code.
template <class OnFrame>
int receive_frames(hal::CanBus& bus, const char* stopped, long long& n, OnFrame on_frame) {
  while (can_opt.count <= 0 || n < can_opt.count) {
    hal::CanFrame f;
    // docs/faults.md: a signal ends the wait at once; the frames received so far are kept.
    const hal::CanBusStatus st = bus.receive(f, can_opt.timeout_s, tools::interrupt_flag());
    if (st == hal::CanBusStatus::kStopped) {
      std::printf("%s: %s\n", tools::interrupt_signal_name().c_str(), stopped);
      return tools::interrupt_exit_code();
    }
    if (st == hal::CanBusStatus::kTimeout) {
      std::printf("silent bus: no frame for %.3f s\n", can_opt.timeout_s);
      return can_opt.count > 0 ? 2 : 0;
    }
    if (st != hal::CanBusStatus::kOk) throw std::runtime_error(bus.last_error());
    on_frame(f);
    ++n;
  }
  return 0;
}

int run_dump() {
  hal::CanRxAssembler rx;
  long long items = 0;
  long long frames = 0;
  if (!can_opt.log.empty()) {
    hal::CandumpReader r;
    if (!r.open(can_opt.log)) throw std::runtime_error(r.error());
    hal::CanFrame f;
    std::string iface;
    while ((can_opt.count <= 0 || frames < can_opt.count) && r.next(f, iface)) {
      ++frames;
      rx.push(f, f.timestamp_s);
      drain(rx, items);
    }
    rx.flush();
    drain(rx, items);
    std::printf("log %s: %d lines, %d frames, %d malformed lines\n", can_opt.log.c_str(), r.lines(), r.frames(),
                r.bad_lines());
    for (const std::string& p : r.problems()) std::printf("  %s\n", p.c_str());
    print_health(rx.health());
    if (!r.error().empty()) throw std::runtime_error(r.error());
    // docs/faults.md: an input with nothing valid in it is an error, not an empty success.
    if (r.frames() == 0)
      throw std::runtime_error(can_opt.log + ": no valid candump frame in " + std::to_string(r.lines()) + " lines");
    return 0;
  }
  const tools::InterruptPolling polling;  // SIGINT/SIGTERM end the dump with the counters so far
  hal::CanBus bus;
  if (bus.open(can_opt.bus) != hal::CanBusStatus::kOk) throw std::runtime_error(bus.last_error());
  std::fprintf(stderr, "sdins can dump: listening on %s\n", can_opt.bus.c_str());
  const int rc = receive_frames(bus, "stopped", frames, [&](const hal::CanFrame& f) {
    rx.push(f, f.timestamp_s);
    drain(rx, items);
  });
  rx.flush();
  drain(rx, items);
  std::printf("frames=%lld decoded_items=%lld\n", frames, items);
  print_health(rx.health());
  print_bus_stats(bus);
  return rc;
}

int run_record() {
  const tools::InterruptPolling polling;  // SIGINT/SIGTERM end the recording: the log is kept complete
  hal::CanBus bus;
  if (bus.open(can_opt.bus) != hal::CanBusStatus::kOk) throw std::runtime_error(bus.last_error());
  hal::CandumpWriter w;
  if (!w.open(can_opt.out)) throw std::runtime_error(w.error());
  std::fprintf(stderr, "sdins can record: listening on %s\n", can_opt.bus.c_str());
  std::fflush(stderr);
  const std::string iface = can_opt.iface;
  long long n = 0;
  const int rc = receive_frames(bus, "recording stopped", n, [&](const hal::CanFrame& f) {
    if (!w.write(f, iface)) throw std::runtime_error("cannot write " + w.error());
  });
  if (!w.close()) throw std::runtime_error("cannot write " + w.error());
  std::printf("recorded %lld frames -> %s\n", n, can_opt.out.c_str());
  print_bus_stats(bus);
  return rc;
}

int run_play() {
  hal::CandumpReader r;
  if (!r.open(can_opt.log)) throw std::runtime_error(r.error());
  hal::CanBus bus;
  if (bus.open(can_opt.bus) != hal::CanBusStatus::kOk) throw std::runtime_error(bus.last_error());
  using Clock = std::chrono::steady_clock;
  const Clock::time_point t0 = Clock::now();
  long long n = 0;
  const auto send = [&](const hal::CanFrame& f, double play_s) {
    if (can_opt.realtime)
      std::this_thread::sleep_until(
          t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(play_s / can_opt.speed)));
    else if (can_opt.gap_s > 0.0 && n > 0)
      std::this_thread::sleep_for(std::chrono::duration<double>(can_opt.gap_s));
    const hal::CanBusStatus st = bus.send(f);
    if (st != hal::CanBusStatus::kOk)
      throw std::runtime_error("send frame " + std::to_string(n + 1) + ": " + hal::to_string(st) + ": " + bus.last_error());
    ++n;
  };
  // --realtime: the log's timestamps pass the replay reader's time-tag gate (hal::CandumpPacer): one
  // wild timestamp neither stops the play nor sleeps for days (docs/faults.md).
  hal::CandumpPacer pacer;
  hal::CanFrame f;
  std::string iface;
  double play_s = 0.0;
  bool log_left = true;
  while (can_opt.count <= 0 || n < can_opt.count) {
    if (!can_opt.realtime) {
      if (!r.next(f, iface)) break;
      send(f, 0.0);
    } else if (pacer.pop(f, play_s)) {
      send(f, play_s);
    } else if (!log_left) {
      break;
    } else if (r.next(f, iface)) {
      pacer.push(f);
    } else {
      pacer.finish();
      log_left = false;
    }
  }
  std::printf("played %lld frames from %s (%d lines, %d malformed)\n", n, can_opt.log.c_str(), r.lines(), r.bad_lines());
  for (const std::string& p : r.problems()) std::printf("  %s\n", p.c_str());
  if (can_opt.realtime) {
    const hal::TimeTagGateStats& g = pacer.stats();
    std::printf("time tags: %llu outliers (sent without pacing), %llu new time bases",
                static_cast<unsigned long long>(g.rejected()), static_cast<unsigned long long>(g.new_bases));
    if (g.new_bases > 0) std::printf(" (last: a jump of %.6g s at %.6f)", g.last_new_base_jump_s, g.last_new_base_at_s);
    std::printf("\n");
  }
  print_bus_stats(bus);
  return r.error().empty() ? 0 : 1;
}

}  // namespace

void register_can(CLI::App& app) {
  CLI::App* can = app.add_subcommand("can", "CAN bus tools for the sdins IMU/GPS protocol (hal/can/sdins.dbc). Buses: "
                                            "socketcan:IFACE, udp:PORT, udp:GROUP:PORT (this host only; ?scope=lan: the network), loop:NAME.");
  can->require_subcommand(1);

  g_encode = can->add_subcommand("encode", "Fly a scenario's IMU and GPS receiver models and write the protocol frames "
                                           "to a candump log (frame timestamps = simulation time).");
  add_scenario_options(g_encode, can_opt.scenario);
  g_encode->add_option("--out", can_opt.out, "candump log to write")->required();
  g_encode->add_option("--expected", can_opt.expected,
                       "also write a CSV of the physical value every signal must decode to (line,message,signal,"
                       "value,tolerance), from the encoder's inputs");
  g_encode->add_option("--iface", can_opt.iface, "interface name in the log")->capture_default_str();

  g_dump = can->add_subcommand("dump", "Decode frames from a bus (--can) or a candump log (--log) and print the "
                                       "physical values, then the receive health counters.");
  auto* src = g_dump->add_option_group("source");
  src->add_option("--can", can_opt.bus, "bus to listen on");
  src->add_option("--log", can_opt.log, "candump log to decode");
  src->require_option(1);
  g_dump->add_option("--count", can_opt.count, "stop after N frames (0: until the bus is silent / the log ends)")->capture_default_str()->check(CLI::NonNegativeNumber);
  g_dump->add_option("--timeout", can_opt.timeout_s, "a bus silent this long ends the dump [s]")->capture_default_str()->check(tools::positive());
  g_dump->add_flag("--quiet", can_opt.quiet, "print only the counters");

  g_record = can->add_subcommand("record", "Record frames from a bus into a candump log.");
  g_record->add_option("--can", can_opt.bus, "bus to listen on")->required();
  g_record->add_option("--out", can_opt.out, "candump log to write")->required();
  g_record->add_option("--count", can_opt.count, "stop after N frames (0: until the bus is silent)")->capture_default_str()->check(CLI::NonNegativeNumber);
  g_record->add_option("--timeout", can_opt.timeout_s, "a bus silent this long ends the recording [s]")->capture_default_str()->check(tools::positive());
  g_record->add_option("--iface", can_opt.iface, "interface name in the log")->capture_default_str();

  g_play = can->add_subcommand("play", "Send the frames of a candump log onto a bus.");
  g_play->add_option("log", can_opt.log, "candump log")->required();
  g_play->add_option("--can", can_opt.bus, "bus to send on")->required();
  g_play->add_option("--count", can_opt.count, "send only the first N frames (0: all)")->capture_default_str()->check(CLI::NonNegativeNumber);
  CLI::Option* realtime = g_play->add_flag("--realtime", can_opt.realtime, "pace the frames by the log's timestamps");
  g_play->add_option("--speed", can_opt.speed, "with --realtime: time factor (2 = twice as fast)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber)
      ->needs(realtime);  // docs/faults.md: an option that would do nothing is refused
  g_play->add_option("--gap", can_opt.gap_s, "without --realtime: pause between frames [s]")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber)
      ->excludes(realtime);
}

int run_can() {
  if (g_encode->parsed()) return run_encode();
  if (g_dump->parsed()) return run_dump();
  if (g_record->parsed()) return run_record();
  if (g_play->parsed()) return run_play();
  return 1;
}

}  // namespace sdins
