#include "tools/hil.hpp"

#include "tools/timing_stats.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "fsw/driver.hpp"
#include "hal/can_fsw_input.hpp"
#include "hal/rt_clock.hpp"
#include "tools/number_text.hpp"
#include "tools/step_producer.hpp"

namespace tools {
namespace {

using hal::CanBusStatus;
using hal::CanFrame;
namespace can = hal::can;

std::uint32_t draw_run_id() {
  std::random_device rd;
  std::uint32_t id = 0;
  while (id == 0) id = rd() ^ static_cast<std::uint32_t>(hal::mono_now_s() * 1e6);
  return id;
}


}  // namespace

// ---- bus simulator ------------------------------------------------------------------------------

namespace {

/// One run of the bus simulator: SIM_CONTROL start, the stream's steps as CAN frames (lockstep
/// window or real-time pacing), SIM_CONTROL end; the FSW_ACKs read in between. Each step returns
/// false when the run failed (the result says why).
class BusSimRun {
 public:
  BusSimRun(hal::CanBus& bus, sim::SensorStream& stream, const BusSimConfig& cfg, const std::atomic<bool>* stop)
      : bus_(bus), stream_(stream), cfg_(cfg), stop_(stop), t_begin_(hal::mono_now_s()),
        mode_(cfg.lockstep ? can::SimMode::kLockstep : can::SimMode::kRealtime), window_(std::max(1, cfg.window_imu)),
        last_progress_(hal::mono_now_s()) {
    r_.run_id = cfg.run_id != 0 ? cfg.run_id : draw_run_id();
  }

  BusSimResult run() {
    if (!start() || !send_stream() || !end()) return r_;
    r_.wall_s = hal::mono_now_s() - t_begin_;
    if (cfg_.lockstep && (r_.last_ack.imu_frames != r_.imu_sent || r_.last_ack.frames != r_.frames_sent))
      return fail("lockstep: the flight software took " + std::to_string(r_.last_ack.frames) + " of " +
                  std::to_string(r_.frames_sent) + " frames (" + std::to_string(r_.last_ack.imu_frames) + " of " +
                  std::to_string(r_.imu_sent) + " IMU frames)");
    r_.ok = true;
    return r_;
  }

 private:
  bool stopped() const { return stop_ != nullptr && stop_->load(); }

  BusSimResult fail(const std::string& why) {
    r_.ok = false;
    r_.error = why;
    r_.wall_s = hal::mono_now_s() - t_begin_;
    return r_;
  }
  bool failed(const std::string& why) {
    fail(why);
    return false;
  }

  /// Takes what the bus holds (waiting up to wait_s for the first frame): our run's FSW_ACKs.
  void pump(double wait_s) {
    CanFrame f;
    double w = wait_s;
    while (bus_.receive(f, w) == CanBusStatus::kOk) {
      w = 0.0;
      can::FswAckFrame a;
      if (can::decode_fsw_ack(f, a) != can::CodecStatus::kOk || a.run_id != r_.run_id) {
        ++r_.foreign_frames;
        continue;
      }
      ++r_.acks_received;
      r_.last_ack = a;
      if (!started_) {
        started_ = true;
        last_progress_ = hal::mono_now_s();
      }
      if (static_cast<long long>(a.imu_frames) > acked_imu_) {
        acked_imu_ = a.imu_frames;
        last_progress_ = hal::mono_now_s();
      }
    }
  }

  /// Sends one frame; a full transmit queue is retried (never dropped) while acks keep coming.
  bool send(const CanFrame& f) {
    const double t0 = hal::mono_now_s();
    for (;;) {
      const CanBusStatus st = bus_.send(f);
      if (st == CanBusStatus::kOk) return true;
      if (st != CanBusStatus::kTxBusy || hal::mono_now_s() - t0 > cfg_.ack_timeout_s) {
        r_.error = std::string("send on ") + bus_.name() + ": " + hal::to_string(st) + ": " + bus_.last_error();
        return false;
      }
      ++r_.tx_busy_retries;
      pump(0.001);
    }
  }

  bool send_control(can::SimCommand cmd, std::uint32_t steps, std::uint32_t imu, std::uint32_t frames) {
    can::SimControlFrame c;
    c.command = cmd;
    c.mode = mode_;
    c.window_imu = static_cast<std::uint16_t>(std::min<long long>(window_, 65535));
    c.run_id = r_.run_id;
    c.seed = cfg_.seed;
    c.steps = steps;
    c.imu_samples = imu;
    c.frames = frames;
    CanFrame f;
    can::encode_sim_control(c, f);
    if (!send(f)) return false;
    ++r_.control_sent;
    return true;
  }

  /// Start: repeated until the flight software answers (so it may start before or after us).
  bool start() {
    const int spe = std::max(1, stream_.samples_per_epoch());
    const long long planned_imu = stream_.total_samples();
    const long long planned_steps = (planned_imu + spe - 1) / spe;
    const double t0 = hal::mono_now_s();
    double next_try = t0;
    while (!started_) {
      if (stopped()) return failed("stopped");
      if (hal::mono_now_s() >= next_try) {
        if (!send_control(can::SimCommand::kStart, static_cast<std::uint32_t>(planned_steps),
                          static_cast<std::uint32_t>(planned_imu), 0))
          return failed(r_.error);
        next_try = hal::mono_now_s() + cfg_.start_retry_s;
      }
      pump(0.02);
      if (!started_ && hal::mono_now_s() - t0 > cfg_.ack_timeout_s)
        return failed("no flight software answered the SIM_CONTROL start on " + bus_.name() + " within " +
                      fmt("%g", cfg_.ack_timeout_s) + " s (is `sdins fsw --can " + bus_.name() + "` running?)");
    }
    return true;
  }

  /// Lockstep: waits while `window` IMU samples are not yet acknowledged.
  bool wait_for_window() {
    bool waited = false;
    double w0 = 0.0;
    while (r_.imu_sent - acked_imu_ >= window_) {
      if (!waited) {
        waited = true;
        w0 = hal::mono_now_s();
        ++r_.window_waits;
      }
      if (stopped()) return failed("stopped");
      pump(0.05);
      if (hal::mono_now_s() - last_progress_ > cfg_.ack_timeout_s)
        return failed("no FSW_ACK progress for " + fmt("%g", cfg_.ack_timeout_s) + " s (acknowledged " +
                      std::to_string(acked_imu_) + " of " + std::to_string(r_.imu_sent) +
                      " IMU samples sent): has the flight software stopped?");
    }
    if (waited) r_.window_wait_s += hal::mono_now_s() - w0;
    return true;
  }

  /// Real time: every pace_every-th IMU sample waits for its time on CLOCK_MONOTONIC.
  void pace(const CanFrame& f) {
    can::ImuFrame d;
    if (can::decode_imu(f, d) != can::CodecStatus::kOk) return;
    if (!have_t0_) {
      have_t0_ = true;
      mono0_ = hal::mono_now_s();
      t0_s_ = d.sample.t_s;
    }
    if (r_.imu_sent % std::max(1, cfg_.pace_every) == 0) {
      const double late = hal::sleep_until_mono_s(mono0_ + (d.sample.t_s - t0_s_) / cfg_.speed);
      ++r_.paced;
      late_sum_ += late;
      r_.late_max_s = std::max(r_.late_max_s, late);
    }
  }

  bool send_frame(const CanFrame& f) {
    const bool is_imu = f.id == can::kIdImuSample;
    if (is_imu && cfg_.lockstep && !wait_for_window()) return false;
    if (is_imu && !cfg_.lockstep) pace(f);
    if (!send(f)) return failed(r_.error);
    ++r_.frames_sent;
    if (is_imu) {
      ++r_.imu_sent;
      r_.max_ahead_imu = std::max(r_.max_ahead_imu, r_.imu_sent - acked_imu_);
    } else if (f.id == can::kIdGpsEpoch) {
      ++r_.gps_epochs;
    } else if (f.id == can::kIdGpsAlmanac) {
      ++r_.almanac_sent;
    }
    pump(0.0);
    return true;
  }

  /// The stream's steps, each encoded into its frames.
  bool send_stream() {
    StepProducer producer(stream_, stop_);
    EncodedStep step;
    while (producer.next(step)) {
      if (stopped()) return failed("stopped");
      ++r_.steps;
      r_.imu_rejected += step.r.imu_rejected;
      r_.imu_flagged += step.r.imu_flagged;
      r_.gps_skipped += step.r.gps_skipped;
      r_.gps_rejected += step.r.gps_rejected;
      r_.almanac_rejected += step.r.almanac_rejected;
      for (const CanFrame& f : step.frames)
        if (!send_frame(f)) return false;
    }
    if (!producer.error().empty()) return failed("simulator: " + producer.error());
    if (r_.paced > 0) r_.late_mean_s = late_sum_ / static_cast<double>(r_.paced);
    return true;
  }

  /// End: repeated until the flight software confirms it with the final counts.
  bool end() {
    const double t0 = hal::mono_now_s();
    double next_try = t0;
    for (;;) {
      if (stopped()) return failed("stopped");
      if (hal::mono_now_s() >= next_try) {
        if (!send_control(can::SimCommand::kEnd, static_cast<std::uint32_t>(r_.steps),
                          static_cast<std::uint32_t>(r_.imu_sent), static_cast<std::uint32_t>(r_.frames_sent)))
          return failed(r_.error);
        next_try = hal::mono_now_s() + cfg_.start_retry_s;
      }
      pump(0.02);
      if ((r_.last_ack.flags & can::kAckEndReceived) != 0) {
        r_.final_ack = true;
        return true;
      }
      if (hal::mono_now_s() - t0 > cfg_.ack_timeout_s)
        return failed("the flight software did not acknowledge the SIM_CONTROL end within " +
                      fmt("%g", cfg_.ack_timeout_s) + " s (last ack: " + std::to_string(r_.last_ack.imu_frames) +
                      " of " + std::to_string(r_.imu_sent) + " IMU frames)");
    }
  }

  hal::CanBus& bus_;
  sim::SensorStream& stream_;
  const BusSimConfig& cfg_;
  const std::atomic<bool>* stop_;
  BusSimResult r_;
  const double t_begin_;
  const can::SimMode mode_;
  const long long window_;
  long long acked_imu_ = 0;
  bool started_ = false;
  double last_progress_;
  // Real-time pacing: the monotonic time and stream time of the first IMU sample.
  bool have_t0_ = false;
  double mono0_ = 0.0, t0_s_ = 0.0, late_sum_ = 0.0;
};

}  // namespace

BusSimResult run_bus_sim(hal::CanBus& bus, sim::SensorStream& stream, const BusSimConfig& cfg,
                         const std::atomic<bool>* stop) {
  return BusSimRun(bus, stream, cfg, stop).run();
}

nlohmann::json to_json(const BusSimResult& r) {
  nlohmann::json j;
  j["ok"] = r.ok;
  j["error"] = r.error;
  j["run_id"] = r.run_id;
  j["steps"] = r.steps;
  j["imu_sent"] = r.imu_sent;
  j["frames_sent"] = r.frames_sent;
  j["control_sent"] = r.control_sent;
  j["gps_epochs"] = r.gps_epochs;
  j["almanac_sent"] = r.almanac_sent;
  j["encoder"] = {{"imu_rejected", r.imu_rejected},
                  {"imu_flagged", r.imu_flagged},
                  {"gps_skipped", r.gps_skipped},
                  {"gps_rejected", r.gps_rejected},
                  {"almanac_rejected", r.almanac_rejected}};
  j["acks_received"] = r.acks_received;
  j["foreign_frames"] = r.foreign_frames;
  j["tx_busy_retries"] = r.tx_busy_retries;
  j["window_waits"] = r.window_waits;
  j["window_wait_s"] = r.window_wait_s;
  j["max_ahead_imu"] = r.max_ahead_imu;
  j["final_ack"] = r.final_ack;
  j["last_ack"] = {{"imu_frames", r.last_ack.imu_frames},
                   {"frames", r.last_ack.frames},
                   {"imu_delivered", r.last_ack.imu_delivered},
                   {"nav_frames", r.last_ack.nav_frames},
                   {"flags", r.last_ack.flags}};
  j["wall_s"] = r.wall_s;
  j["paced"] = r.paced;
  j["late_mean_s"] = r.late_mean_s;
  j["late_max_s"] = r.late_max_s;
  return j;
}

// ---- flight software --------------------------------------------------------------------------

const char* to_string(FswExit e) {
  switch (e) {
    case FswExit::kEndOfRun: return "end_of_run";
    case FswExit::kIdleTimeout: return "idle_timeout";
    case FswExit::kStopped: return "stopped";
    case FswExit::kError: return "error";
  }
  return "unknown";
}

namespace {

/// Real time: each IMU frame's lateness against the first one's arrival, and each minor frame's
/// execution (the handling of every frame since the previous minor frame completed).
class RealtimeMeter {
 public:
  RealtimeMeter(const FswRunConfig& cfg, double budget_s, FswRunResult& r) : cfg_(cfg), budget_s_(budget_s), r_(r) {}

  void imu_arrived(const CanFrame& f, double arrival) {
    can::ImuFrame d;
    if (can::decode_imu(f, d) != can::CodecStatus::kOk) return;
    if (!have_base_) {
      have_base_ = true;
      base_mono_ = arrival;
      base_t_ = d.sample.t_s;
    }
    imu_t_s_ = d.sample.t_s;
    const double late = arrival - (base_mono_ + (d.sample.t_s - base_t_));
    r_.imu_lateness_max_s = r_.imu_lateness_n == 0 ? late : std::max(r_.imu_lateness_max_s, late);
    ++r_.imu_lateness_n;
    late_sum_ += late;
    if (late > cfg_.late_threshold_s) ++r_.imu_late;
  }

  /// A minor frame's execution: the handling of every frame since the previous one completed,
  /// as the flight application closes them (FrameOutput::frame_closed: before initialisation
  /// a frame's worth of levelling samples and the initialisation attempts on the GNSS epochs).
  void frame_handled(hal::FswNode& node, double arrival, double arrival_cpu, std::uint64_t nav_before,
                     std::uint64_t minor_before) {
    exec_acc_ += hal::mono_now_s() - arrival;
    exec_cpu_acc_ += hal::thread_cpu_now_s() - arrival_cpu;
    const bool nav_frame = node.summary().nav_frames != nav_before;
    if (node.summary().minor_frames == minor_before) return;
    node.set_prev_tick_exec_s(exec_acc_);
    ++r_.minor_frames_timed;
    r_.frame_exec_s.push_back(exec_acc_);
    exec_sum_ += exec_acc_;
    if (exec_acc_ > r_.exec_max_s) {
      const fsw::FrameOutput& fo = node.last_frame();
      r_.exec_max_s = exec_acc_;
      r_.exec_max_t_s = nav_frame ? fo.nav.t_s : imu_t_s_;
      r_.exec_max_work = !nav_frame                    ? "before initialisation (levelling, initialisation attempts)"
                         : fo.ekf_released             ? "released the 1 Hz group"
                         : fo.ekf_ran                  ? "landed a 1 Hz correction"
                                                       : "200 Hz group only";
    }
    r_.exec_cpu_max_s = std::max(r_.exec_cpu_max_s, exec_cpu_acc_);
    if (exec_acc_ > budget_s_) ++(exec_cpu_acc_ > budget_s_ ? r_.overruns_execution : r_.overruns_stalled);
    exec_acc_ = 0.0;
    exec_cpu_acc_ = 0.0;
  }

  void finish() {
    if (r_.minor_frames_timed > 0) r_.exec_mean_s = exec_sum_ / static_cast<double>(r_.minor_frames_timed);
    if (r_.imu_lateness_n > 0) r_.imu_lateness_mean_s = late_sum_ / static_cast<double>(r_.imu_lateness_n);
  }

 private:
  const FswRunConfig& cfg_;
  const double budget_s_;  ///< the executive's overrun threshold
  FswRunResult& r_;
  double exec_acc_ = 0.0, exec_cpu_acc_ = 0.0, exec_sum_ = 0.0, late_sum_ = 0.0;
  double imu_t_s_ = 0.0;  ///< the last IMU sample's time
  bool have_base_ = false;
  double base_mono_ = 0.0, base_t_ = 0.0;
};

/// The run's final counts: the node's, the receive side's, the bus's and the telemetry's.
void read_final_counts(FswRunResult& r, const hal::FswNode& node, const hal::CanFswInput& in, const hal::CanBus& bus) {
  r.summary = node.summary();
  r.exec = node.exec_health();
  r.app = node.app_health();
  r.rx = in.health();
  r.bus = bus.stats();
  r.run_started = in.run_started();
  r.end_received = in.end_received();
  r.run = in.run();
  r.end = in.end();
  r.data_frames = in.data_frames();
  r.imu_frames = in.imu_frames();
  r.imu_delivered = in.imu_delivered();
  r.control_frames = in.control_frames();
  r.control_rejected = in.control_rejected();
  r.foreign_acks = in.foreign_acks();
  if (r.end_received)
    r.counts_match_end = r.last_ack.imu_frames == r.end.imu_samples && r.last_ack.frames == r.end.frames;
  const hal::LcmTelemetry& t = node.sink().telemetry();
  r.lcm_network = t.network_used();
  r.lcm_published = t.published();
  r.lcm_send_failures = t.send_failures();
  r.lcm_logged = t.logged();
  r.lcm_log_failures = t.log_failures();
}

}  // namespace

FswRunResult run_fsw(hal::CanBus& bus, const FswRunConfig& cfg, const std::atomic<bool>* stop,
                     void (*warn)(const std::string&)) {
  FswRunResult r;
  r.realtime = cfg.realtime;
  r.idle_timeout_s = cfg.idle_timeout_s;
  r.late_threshold_s = cfg.late_threshold_s;
  r.lcm_url = cfg.node.telemetry.lcm_url;
  r.log_path = cfg.node.telemetry.log_path;
  if (cfg.realtime) {  // before the node starts its 1 Hz thread, which takes a priority below this one
    r.sched_fifo = hal::try_sched_fifo(cfg.fifo_priority, r.sched_note) == hal::RtSchedStatus::kOk;
    if (!r.sched_fifo && warn) warn("warning: " + r.sched_note + "; running at normal priority");
  }
  hal::FswNode node;
  std::string err;
  hal::FswNodeConfig ncfg = cfg.node;
  ncfg.realtime = cfg.realtime;  // real time: the 200 Hz group never waits for the 1 Hz thread
  if (!node.open(ncfg, err)) {
    r.error = err;
    return r;
  }
  hal::CanFswInput in(node.summary());
  r.nav_rate_hz = ncfg.app.exec.nav_rate_hz;
  r.ekf_rate_hz = ncfg.app.exec.nav_rate_hz / ncfg.app.exec.frames_per_ekf;

  const double t_begin = hal::mono_now_s();
  double last_frame = t_begin, last_ack_sent = -1e300;
  std::uint32_t last_ack_imu = 0;
  auto send_ack = [&] {
    const can::FswAckFrame a = in.ack();
    CanFrame f;
    can::encode_fsw_ack(a, f);
    if (bus.send(f) == CanBusStatus::kOk)
      ++r.acks_sent;
    else
      ++r.ack_send_failures;
    r.last_ack = a;
    last_ack_sent = hal::mono_now_s();
    last_ack_imu = a.imu_frames;
  };

  RealtimeMeter meter(cfg, ncfg.app.exec.frame_budget_s, r);
  for (;;) {
    if (stop != nullptr && stop->load()) {
      r.exit = FswExit::kStopped;
      break;
    }
    const double idle_left = cfg.idle_timeout_s - (hal::mono_now_s() - last_frame);
    if (idle_left <= 0.0) {
      r.exit = FswExit::kIdleTimeout;
      break;
    }
    CanFrame f;
    const CanBusStatus st = bus.receive(f, std::min(idle_left, cfg.idle_ack_s));
    if (st == CanBusStatus::kTimeout) {
      in.poll(hal::wall_now_s());
      fsw::drive(in, node);
      // A quiet bus: repeat the ack, in case the simulator missed the last one.
      if (in.run_started() && hal::mono_now_s() - last_ack_sent >= cfg.idle_ack_s) send_ack();
      continue;
    }
    if (st != CanBusStatus::kOk) {
      r.exit = FswExit::kError;
      r.error = std::string("receive on ") + bus.name() + ": " + hal::to_string(st) + ": " + bus.last_error();
      break;
    }
    const double arrival = hal::mono_now_s();
    const double arrival_cpu = cfg.realtime ? hal::thread_cpu_now_s() : 0.0;
    last_frame = arrival;
    ++r.frames_received;
    if (cfg.realtime && !f.extended && f.id == can::kIdImuSample) meter.imu_arrived(f, arrival);
    const std::uint64_t nav_before = node.summary().nav_frames, minor_before = node.summary().minor_frames;
    in.push(f, f.timestamp_s);
    fsw::drive(in, node);
    if (cfg.realtime) meter.frame_handled(node, arrival, arrival_cpu, nav_before, minor_before);
    if (in.control_changed()) {
      if (in.end_received()) {
        in.finish();
        fsw::drive(in, node);
        send_ack();
        r.exit = FswExit::kEndOfRun;
        break;
      }
      send_ack();  // a new run: tell the simulator we are here
      continue;
    }
    if (in.run_started() && in.ack().imu_frames - last_ack_imu >= static_cast<std::uint32_t>(cfg.ack_every_imu))
      send_ack();
  }
  if (r.exit != FswExit::kEndOfRun) {
    in.finish();
    fsw::drive(in, node);
    if (in.run_started()) send_ack();
  }
  r.wall_s = hal::mono_now_s() - t_begin;
  meter.finish();
  read_final_counts(r, node, in, bus);
  if (!node.close(err) && r.exit != FswExit::kError) {
    r.exit = FswExit::kError;
    r.error = err;
  }
  r.ekf_group = node.ekf_group_times();  // complete once close() stopped the 1 Hz thread
  return r;
}

static nlohmann::json groups_json(const FswRunResult& r) {
  nlohmann::json g = nlohmann::json::array();
  const auto entry = [](const char* name, double rate_hz, const std::vector<double>& s, long slips) {
    const TimingStats t = timing_stats(s);
    return nlohmann::json{{"name", name},         {"rate_hz", rate_hz},     {"n", t.n},
                          {"median_us", t.median_us}, {"p99_us", t.p99_us}, {"p999_us", t.p999_us},
                          {"max_us", t.max_us},   {"slips", slips}};
  };
  // 200 Hz: measured per minor frame in real time only (bus handling included); slips = overruns.
  nlohmann::json nav = entry("nav_200hz", r.nav_rate_hz, r.frame_exec_s, static_cast<long>(r.exec.overruns));
  nav["measured"] = r.realtime ? "each minor frame's handling (bus decode + the 200 Hz group), steady clock"
                               : "not measured (lockstep: virtual time; sdins fsw --realtime measures it)";
  g.push_back(nav);
  nlohmann::json ekf = entry("ekf_1hz", r.ekf_rate_hz, r.ekf_group.exec_s,
                             static_cast<long>(r.exec.ekf_slips + r.exec.ekf_late));
  ekf["overruns"] = r.exec.ekf_overruns;
  ekf["ekf_slips"] = r.exec.ekf_slips;
  ekf["ekf_late"] = r.exec.ekf_late;
  ekf["lockstep_waits"] = r.ekf_group.waits;
  ekf["lockstep_wait_max_s"] = r.ekf_group.wait_max_s;
  ekf["measured"] = r.ekf_group.exec_s.empty() ? "not run on its own thread" : "each run on the 1 Hz thread, steady clock";
  g.push_back(ekf);
  return g;
}

nlohmann::json to_json(const FswRunResult& r) {
  nlohmann::json j;
  j["exit"] = to_string(r.exit);
  j["error"] = r.error;
  const fsw::NavState& n = r.summary.last_nav;
  j["initialised"] = r.summary.initialised;
  j["init_t_s"] = r.summary.init_t_s;
  j["nav_frames"] = r.summary.nav_frames;
  j["digest"] = digest_hex(r.summary.digest);
  j["last_nav"] = last_nav_json(n);
  j["run"] = {{"started", r.run_started},
              {"run_id", r.run.run_id},
              {"mode", r.run.mode == can::SimMode::kLockstep ? "lockstep" : "realtime"},
              {"seed", r.run.seed},
              {"window_imu", r.run.window_imu},
              {"planned_steps", r.run.steps},
              {"planned_imu", r.run.imu_samples},
              {"end_received", r.end_received},
              {"sent_steps", r.end.steps},
              {"sent_imu", r.end.imu_samples},
              {"sent_frames", r.end.frames},
              {"counts_match_end", r.counts_match_end}};
  j["frames"] = {{"received", r.frames_received},
                 {"data", r.data_frames},
                 {"imu", r.imu_frames},
                 {"imu_delivered", r.imu_delivered},
                 {"control", r.control_frames},
                 {"control_rejected", r.control_rejected},
                 {"foreign_acks", r.foreign_acks},
                 {"acks_sent", r.acks_sent},
                 {"ack_send_failures", r.ack_send_failures}};
  j["assembler"] = can_rx_json(r.rx);
  j["executive"] = executive_json(r.exec);
  j["app"] = app_json(r.app);
  j["telemetry"] = {{"lcm_url", r.lcm_url},
                    {"network_active", r.lcm_network},
                    {"published", r.lcm_published},
                    {"send_failures", r.lcm_send_failures},
                    {"log_path", r.log_path},
                    {"logged", r.lcm_logged},
                    {"log_failures", r.lcm_log_failures}};
  j["bus"] = {{"sent", r.bus.sent},
              {"received", r.bus.received},
              {"own_dropped", r.bus.own_dropped},
              {"foreign_dropped", r.bus.foreign_dropped},
              {"malformed", r.bus.malformed},
              {"unsupported", r.bus.unsupported},
              {"queue_dropped", r.bus.queue_dropped}};
  j["wall_s"] = r.wall_s;
  j["idle_timeout_s"] = r.idle_timeout_s;
  j["realtime"] = r.realtime;
  j["groups"] = groups_json(r);
  if (r.realtime)
    j["realtime_stats"] = {{"sched_fifo", r.sched_fifo},
                           {"sched_note", r.sched_note},
                           {"minor_frames_timed", r.minor_frames_timed},
                           {"exec_mean_s", r.exec_mean_s},
                           {"exec_max_s", r.exec_max_s},
                           {"exec_cpu_max_s", r.exec_cpu_max_s},
                           {"exec_max_t_s", r.exec_max_t_s},
                           {"exec_max_work", r.exec_max_work},
                           {"overruns", r.exec.overruns},
                           {"overruns_execution", r.overruns_execution},
                           {"overruns_stalled", r.overruns_stalled},
                           {"imu_frames_timed", r.imu_lateness_n},
                           {"imu_lateness_mean_s", r.imu_lateness_mean_s},
                           {"imu_lateness_max_s", r.imu_lateness_max_s},
                           {"imu_late", r.imu_late},
                           {"late_threshold_s", r.late_threshold_s},
                           {"imu_missing", r.rx.imu_missing},
                           {"imu_gaps", r.rx.imu_gaps}};
  return j;
}

}  // namespace tools
