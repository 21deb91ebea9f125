#include "tools/hil.hpp"

#include "tools/timing_stats.hpp"

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <mutex>
#include <random>
#include <thread>
#include <vector>

#include "fsw/driver.hpp"
#include "hal/can_fsw_input.hpp"
#include "hal/rt_clock.hpp"

namespace tools {
namespace {

using hal::CanBusStatus;
using hal::CanFrame;
namespace can = hal::can;

/// One GPS interval encoded into frames (IMU samples, epoch, almanac with the first step).
struct EncodedStep {
  std::vector<CanFrame> frames;
  can::CanStepEncoder::Result r{};
  bool has_epoch = false;
  int n_alm = 0;
};

/// Flies the stream on its own thread, a few steps ahead of the sender, so that simulating the
/// next GPS interval never stalls the bus (it matters in real time: a step takes tens of ms).
class StepProducer {
 public:
  StepProducer(sim::SensorStream& stream, const std::atomic<bool>* stop) : stream_(stream), stop_(stop) {
    th_ = std::thread([this] { produce(); });
  }
  ~StepProducer() {
    {
      std::lock_guard<std::mutex> lk(mu_);
      quit_ = true;
    }
    cv_.notify_all();
    th_.join();
  }
  /// The next step; false at the end (error() says whether the stream failed).
  bool next(EncodedStep& out) {
    std::unique_lock<std::mutex> lk(mu_);
    cv_.wait(lk, [this] { return !q_.empty() || done_; });
    if (q_.empty()) return false;
    out = std::move(q_.front());
    q_.pop_front();
    cv_.notify_all();
    return true;
  }
  std::string error() {
    std::lock_guard<std::mutex> lk(mu_);
    return error_;
  }

 private:
  void produce() {
    try {
      can::CanStepEncoder enc;
      sim::SensorStep step;
      bool first = true;
      while (stream_.next(step)) {
        EncodedStep e;
        e.n_alm = first ? static_cast<int>(stream_.almanac().size()) : 0;
        e.has_epoch = step.has_epoch;
        e.frames.resize(static_cast<std::size_t>(
            can::CanStepEncoder::max_frames(static_cast<int>(step.imu.size()), e.n_alm)));
        e.r = enc.encode(step.imu.data(), static_cast<int>(step.imu.size()), step.has_epoch ? &step.epoch : nullptr,
                         stream_.almanac().data(), e.n_alm, e.frames.data());
        e.frames.resize(static_cast<std::size_t>(e.r.n_frames));
        first = false;
        std::unique_lock<std::mutex> lk(mu_);
        cv_.wait(lk, [this] { return q_.size() < kAhead || quit_; });
        if (quit_ || (stop_ && stop_->load())) break;
        q_.push_back(std::move(e));
        cv_.notify_all();
      }
    } catch (const std::exception& ex) {
      std::lock_guard<std::mutex> lk(mu_);
      error_ = ex.what();
    }
    std::lock_guard<std::mutex> lk(mu_);
    done_ = true;
    cv_.notify_all();
  }

  static constexpr std::size_t kAhead = 3;
  sim::SensorStream& stream_;
  const std::atomic<bool>* stop_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<EncodedStep> q_;
  bool done_ = false, quit_ = false;
  std::string error_;
  std::thread th_;
};

std::uint32_t draw_run_id() {
  std::random_device rd;
  std::uint32_t id = 0;
  while (id == 0) id = rd() ^ static_cast<std::uint32_t>(hal::mono_now_s() * 1e6);
  return id;
}

std::string fmt(const char* f, double a) {
  char b[64];
  std::snprintf(b, sizeof b, f, a);
  return b;
}

}  // namespace

// ---- bus simulator ------------------------------------------------------------------------------

BusSimResult run_bus_sim(hal::CanBus& bus, sim::SensorStream& stream, const BusSimConfig& cfg,
                         const std::atomic<bool>* stop) {
  BusSimResult r;
  const double t_begin = hal::mono_now_s();
  r.run_id = cfg.run_id != 0 ? cfg.run_id : draw_run_id();
  const can::SimMode mode = cfg.lockstep ? can::SimMode::kLockstep : can::SimMode::kRealtime;
  const long long window = std::max(1, cfg.window_imu);
  long long acked_imu = 0;
  bool started = false;
  double last_progress = hal::mono_now_s();
  auto stopped = [&] { return stop != nullptr && stop->load(); };
  auto fail = [&](const std::string& why) {
    r.ok = false;
    r.error = why;
    r.wall_s = hal::mono_now_s() - t_begin;
    return r;
  };

  // Takes what the bus holds (waiting up to wait_s for the first frame): our run's FSW_ACKs.
  auto pump = [&](double wait_s) {
    CanFrame f;
    double w = wait_s;
    while (bus.receive(f, w) == CanBusStatus::kOk) {
      w = 0.0;
      can::FswAckFrame a;
      if (can::decode_fsw_ack(f, a) != can::CodecStatus::kOk || a.run_id != r.run_id) {
        ++r.foreign_frames;
        continue;
      }
      ++r.acks_received;
      r.last_ack = a;
      if (!started) {
        started = true;
        last_progress = hal::mono_now_s();
      }
      if (static_cast<long long>(a.imu_frames) > acked_imu) {
        acked_imu = a.imu_frames;
        last_progress = hal::mono_now_s();
      }
    }
  };
  // Sends one frame; a full transmit queue is retried (never dropped) while acks keep coming.
  auto send = [&](const CanFrame& f) -> bool {
    const double t0 = hal::mono_now_s();
    for (;;) {
      const CanBusStatus st = bus.send(f);
      if (st == CanBusStatus::kOk) return true;
      if (st != CanBusStatus::kTxBusy || hal::mono_now_s() - t0 > cfg.ack_timeout_s) {
        r.error = std::string("send on ") + bus.name() + ": " + hal::to_string(st) + ": " + bus.last_error();
        return false;
      }
      ++r.tx_busy_retries;
      pump(0.001);
    }
  };
  auto send_control = [&](can::SimCommand cmd, std::uint32_t steps, std::uint32_t imu, std::uint32_t frames) {
    can::SimControlFrame c;
    c.command = cmd;
    c.mode = mode;
    c.window_imu = static_cast<std::uint16_t>(std::min<long long>(window, 65535));
    c.run_id = r.run_id;
    c.seed = cfg.seed;
    c.steps = steps;
    c.imu_samples = imu;
    c.frames = frames;
    CanFrame f;
    can::encode_sim_control(c, f);
    if (!send(f)) return false;
    ++r.control_sent;
    return true;
  };

  // Start: repeated until the flight software answers (so it may start before or after us).
  const int spe = std::max(1, stream.samples_per_epoch());
  const long long planned_imu = stream.total_samples();
  const long long planned_steps = (planned_imu + spe - 1) / spe;
  {
    const double t0 = hal::mono_now_s();
    double next_try = t0;
    while (!started) {
      if (stopped()) return fail("stopped");
      if (hal::mono_now_s() >= next_try) {
        if (!send_control(can::SimCommand::kStart, static_cast<std::uint32_t>(planned_steps),
                          static_cast<std::uint32_t>(planned_imu), 0))
          return fail(r.error);
        next_try = hal::mono_now_s() + cfg.start_retry_s;
      }
      pump(0.02);
      if (!started && hal::mono_now_s() - t0 > cfg.ack_timeout_s)
        return fail("no flight software answered the SIM_CONTROL start on " + bus.name() + " within " +
                    fmt("%g", cfg.ack_timeout_s) + " s (is `sdins fsw --can " + bus.name() + "` running?)");
    }
  }

  StepProducer producer(stream, stop);
  EncodedStep step;
  bool have_t0 = false;
  double mono0 = 0.0, t0_s = 0.0, late_sum = 0.0;
  while (producer.next(step)) {
    if (stopped()) return fail("stopped");
    ++r.steps;
    r.imu_rejected += step.r.imu_rejected;
    r.imu_flagged += step.r.imu_flagged;
    r.gps_skipped += step.r.gps_skipped;
    r.gps_rejected += step.r.gps_rejected;
    r.almanac_rejected += step.r.almanac_rejected;
    for (const CanFrame& f : step.frames) {
      const bool is_imu = f.id == can::kIdImuSample;
      if (is_imu && cfg.lockstep) {
        bool waited = false;
        double w0 = 0.0;
        while (r.imu_sent - acked_imu >= window) {
          if (!waited) {
            waited = true;
            w0 = hal::mono_now_s();
            ++r.window_waits;
          }
          if (stopped()) return fail("stopped");
          pump(0.05);
          if (hal::mono_now_s() - last_progress > cfg.ack_timeout_s)
            return fail("no FSW_ACK progress for " + fmt("%g", cfg.ack_timeout_s) + " s (acknowledged " +
                        std::to_string(acked_imu) + " of " + std::to_string(r.imu_sent) +
                        " IMU samples sent): has the flight software stopped?");
        }
        if (waited) r.window_wait_s += hal::mono_now_s() - w0;
      }
      if (is_imu && !cfg.lockstep) {
        can::ImuFrame d;
        if (can::decode_imu(f, d) == can::CodecStatus::kOk) {
          if (!have_t0) {
            have_t0 = true;
            mono0 = hal::mono_now_s();
            t0_s = d.sample.t_s;
          }
          if (r.imu_sent % std::max(1, cfg.pace_every) == 0) {
            const double late = hal::sleep_until_mono_s(mono0 + (d.sample.t_s - t0_s) / cfg.speed);
            ++r.paced;
            late_sum += late;
            r.late_max_s = std::max(r.late_max_s, late);
          }
        }
      }
      if (!send(f)) return fail(r.error);
      ++r.frames_sent;
      if (is_imu) {
        ++r.imu_sent;
        r.max_ahead_imu = std::max(r.max_ahead_imu, r.imu_sent - acked_imu);
      } else if (f.id == can::kIdGpsEpoch) {
        ++r.gps_epochs;
      } else if (f.id == can::kIdGpsAlmanac) {
        ++r.almanac_sent;
      }
      pump(0.0);
    }
  }
  if (!producer.error().empty()) return fail("simulator: " + producer.error());
  if (r.paced > 0) r.late_mean_s = late_sum / static_cast<double>(r.paced);

  // End: repeated until the flight software confirms it with the final counts.
  {
    const double t0 = hal::mono_now_s();
    double next_try = t0;
    for (;;) {
      if (stopped()) return fail("stopped");
      if (hal::mono_now_s() >= next_try) {
        if (!send_control(can::SimCommand::kEnd, static_cast<std::uint32_t>(r.steps),
                          static_cast<std::uint32_t>(r.imu_sent), static_cast<std::uint32_t>(r.frames_sent)))
          return fail(r.error);
        next_try = hal::mono_now_s() + cfg.start_retry_s;
      }
      pump(0.02);
      if ((r.last_ack.flags & can::kAckEndReceived) != 0) {
        r.final_ack = true;
        break;
      }
      if (hal::mono_now_s() - t0 > cfg.ack_timeout_s)
        return fail("the flight software did not acknowledge the SIM_CONTROL end within " +
                    fmt("%g", cfg.ack_timeout_s) + " s (last ack: " + std::to_string(r.last_ack.imu_frames) + " of " +
                    std::to_string(r.imu_sent) + " IMU frames)");
    }
  }
  r.wall_s = hal::mono_now_s() - t_begin;
  if (cfg.lockstep && (r.last_ack.imu_frames != r.imu_sent || r.last_ack.frames != r.frames_sent))
    return fail("lockstep: the flight software took " + std::to_string(r.last_ack.frames) + " of " +
                std::to_string(r.frames_sent) + " frames (" + std::to_string(r.last_ack.imu_frames) + " of " +
                std::to_string(r.imu_sent) + " IMU frames)");
  r.ok = true;
  return r;
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

  double exec_acc = 0.0, exec_cpu_acc = 0.0, exec_sum = 0.0, late_sum = 0.0;
  const double budget_s = ncfg.app.exec.frame_budget_s;  // the executive's overrun threshold
  double imu_t_s = 0.0;  // the last IMU sample's time
  bool have_base = false;
  double base_mono = 0.0, base_t = 0.0;
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
    if (cfg.realtime && !f.extended && f.id == can::kIdImuSample) {
      can::ImuFrame d;
      if (can::decode_imu(f, d) == can::CodecStatus::kOk) {
        if (!have_base) {
          have_base = true;
          base_mono = arrival;
          base_t = d.sample.t_s;
        }
        imu_t_s = d.sample.t_s;
        const double late = arrival - (base_mono + (d.sample.t_s - base_t));
        r.imu_lateness_max_s = r.imu_lateness_n == 0 ? late : std::max(r.imu_lateness_max_s, late);
        ++r.imu_lateness_n;
        late_sum += late;
        if (late > cfg.late_threshold_s) ++r.imu_late;
      }
    }
    const std::uint64_t nav_before = node.summary().nav_frames, minor_before = node.summary().minor_frames;
    in.push(f, f.timestamp_s);
    fsw::drive(in, node);
    if (cfg.realtime) {
      // A minor frame's execution: the handling of every frame since the previous one completed,
      // as the flight application closes them (FrameOutput::frame_closed: before initialisation
      // a frame's worth of levelling samples and the initialisation attempts on the GNSS epochs).
      exec_acc += hal::mono_now_s() - arrival;
      exec_cpu_acc += hal::thread_cpu_now_s() - arrival_cpu;
      const bool nav_frame = node.summary().nav_frames != nav_before;
      if (node.summary().minor_frames != minor_before) {
        node.set_prev_tick_exec_s(exec_acc);
        ++r.minor_frames_timed;
        r.frame_exec_s.push_back(exec_acc);
        exec_sum += exec_acc;
        if (exec_acc > r.exec_max_s) {
          const fsw::FrameOutput& fo = node.last_frame();
          r.exec_max_s = exec_acc;
          r.exec_max_t_s = nav_frame ? fo.nav.t_s : imu_t_s;
          r.exec_max_work = !nav_frame                    ? "before initialisation (levelling, initialisation attempts)"
                            : fo.ekf_released             ? "released the 1 Hz group"
                            : fo.ekf_ran                  ? "landed a 1 Hz correction"
                                                          : "200 Hz group only";
        }
        r.exec_cpu_max_s = std::max(r.exec_cpu_max_s, exec_cpu_acc);
        if (exec_acc > budget_s) ++(exec_cpu_acc > budget_s ? r.overruns_execution : r.overruns_stalled);
        exec_acc = 0.0;
        exec_cpu_acc = 0.0;
      }
    }
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
  if (r.minor_frames_timed > 0) r.exec_mean_s = exec_sum / static_cast<double>(r.minor_frames_timed);
  if (r.imu_lateness_n > 0) r.imu_lateness_mean_s = late_sum / static_cast<double>(r.imu_lateness_n);

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
  r.lcm_network = t.network_active();
  r.lcm_published = t.published();
  r.lcm_send_failures = t.send_failures();
  r.lcm_logged = t.logged();
  r.lcm_log_failures = t.log_failures();
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
