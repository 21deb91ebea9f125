#include "hal/fsw_node.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <thread>

#include "fsw/driver.hpp"
#include "fsw/nav_digest.hpp"

namespace hal {

/// The node's own observers of its flight driver: the input log and the lockstep wait before the
/// event, the 1 Hz release, the digest and the telemetry after it.
struct FswNode::Observers {
  FswNode& node;
  void before(const fsw::InputEvent& ev) { node.before_event(ev); }
  void after(const fsw::InputEvent& ev, fsw::Status, const fsw::FrameOutput& out) { node.after_event(ev, out); }
};

/// The flight driver of the layout the configuration names (one virtual call per event: the
/// host node's harnesses run in real or virtual time, not in the Monte Carlo's inner loop).
struct FswNode::App {
  virtual ~App() = default;
  virtual fsw::Status init(const fsw::FlightAppConfig& cfg) = 0;
  virtual fsw::Status step(const fsw::InputEvent& ev, Observers& obs) = 0;
  virtual const fsw::FrameOutput& frame() const = 0;
  virtual void set_prev_tick_exec_s(double s) = 0;
  virtual fsw::Status run_ekf_group() = 0;
  virtual bool ekf_result_due_next_frame() const = 0;
  virtual void note_ekf_group_exec_s(double s) = 0;
  virtual const fsw::FlightAppHealth& health() const = 0;
  virtual const fsw::ExecutiveHealth& exec_health() const = 0;
  virtual void write_ekf(LcmLogSink& sink) const = 0;
  virtual void nav_sigma(std::array<double, 6>& out) const = 0;
  virtual void write_health(LcmLogSink& sink, const fsw::FrameOutput& frame) const = 0;
};

namespace {

template <class Layout>
struct AppOf final : FswNode::App {
  fsw::FlightDriver<Layout> driver;
  fsw::FlightApp<Layout>& app = driver.app();
  fsw::Status init(const fsw::FlightAppConfig& cfg) override { return driver.init(cfg); }
  fsw::Status step(const fsw::InputEvent& ev, FswNode::Observers& obs) override { return driver.step(ev, obs); }
  const fsw::FrameOutput& frame() const override { return driver.frame(); }
  void set_prev_tick_exec_s(double s) override { app.set_prev_tick_exec_s(s); }
  fsw::Status run_ekf_group() override { return app.run_ekf_group(); }
  bool ekf_result_due_next_frame() const override { return app.ekf_result_due_next_frame(); }
  void note_ekf_group_exec_s(double s) override { app.note_ekf_group_exec_s(s); }
  const fsw::FlightAppHealth& health() const override { return app.health(); }
  const fsw::ExecutiveHealth& exec_health() const override { return app.executive().health(); }
  void write_ekf(LcmLogSink& sink) const override { sink.write_ekf(app.executive()); }
  void nav_sigma(std::array<double, 6>& out) const override {
    for (int i = 0; i < 6; ++i) out[static_cast<std::size_t>(i)] = app.executive().ekf_output().sigma(i);
  }
  void write_health(LcmLogSink& sink, const fsw::FrameOutput& frame) const override {
    sink.write_health(app.executive(), frame, app.health().conversion);
  }
};

}  // namespace

/// The 1 Hz group's thread: released by the 200 Hz group (release()), runs App::run_ekf_group once
/// per release and times it. One release at a time: the executive releases again only after the
/// previous result has landed, which the 200 Hz group sees after this thread finished.
struct FswNode::GroupThread {
  std::mutex m;
  std::condition_variable cv_run, cv_done;
  bool run = false, busy = false, stop = false;
  std::vector<double> exec_s;  ///< guarded by m; moved to the node's times by the 200 Hz side
  std::thread th;

  explicit GroupThread(FswNode::App& app) {
    // Priority below the creating (200 Hz) thread's: SCHED_FIFO/RR one level lower, else nice + 5.
    int policy = SCHED_OTHER;
    sched_param sp{};
    const bool have = pthread_getschedparam(pthread_self(), &policy, &sp) == 0;
    th = std::thread([this, &app, have, policy, sp] {
      if (have && (policy == SCHED_FIFO || policy == SCHED_RR)) {
        sched_param lower = sp;
        lower.sched_priority = sp.sched_priority > sched_get_priority_min(policy) ? sp.sched_priority - 1 : sp.sched_priority;
        (void)pthread_setschedparam(pthread_self(), policy, &lower);
      } else {
        errno = 0;
        const int nice_now = getpriority(PRIO_PROCESS, 0);
        if (errno == 0) (void)setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), nice_now + 5 > 19 ? 19 : nice_now + 5);
      }
      std::unique_lock<std::mutex> lk(m);
      for (;;) {
        cv_run.wait(lk, [this] { return run || stop; });
        if (stop && !run) return;
        run = false;
        lk.unlock();
        const auto t0 = std::chrono::steady_clock::now();
        (void)app.run_ekf_group();
        const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        lk.lock();
        exec_s.push_back(dt);
        busy = false;
        cv_done.notify_all();
      }
    });
  }
  void release() {
    {
      std::lock_guard<std::mutex> lk(m);
      run = true;
      busy = true;
    }
    cv_run.notify_one();
  }
  /// Waits until the current run finished; returns the time waited [s].
  double wait_idle() {
    std::unique_lock<std::mutex> lk(m);
    if (!busy) return 0.0;
    const auto t0 = std::chrono::steady_clock::now();
    cv_done.wait(lk, [this] { return !busy; });
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  /// Moves the finished runs' times out.
  void take_times(std::vector<double>& out) {
    std::lock_guard<std::mutex> lk(m);
    out.insert(out.end(), exec_s.begin(), exec_s.end());
    exec_s.clear();
  }
  ~GroupThread() {
    {
      std::lock_guard<std::mutex> lk(m);
      stop = true;
    }
    cv_run.notify_one();
    if (th.joinable()) th.join();
  }
};

FswNode::FswNode() = default;
FswNode::~FswNode() {
  abort();  // docs/faults.md: only close() puts the log in place; a node dropped unclosed leaves none
  stop_group_thread();
}

void FswNode::stop_group_thread() {
  if (!group_) return;
  (void)group_->wait_idle();
  group_->take_times(group_times_.exec_s);
  group_.reset();
}

bool FswNode::open(const FswNodeConfig& cfg, std::string& error) {
  stop_group_thread();
  group_times_ = EkfGroupTimes{};
  if (cfg.nav_decimation < 1) {
    error = "nav_decimation must be >= 1";
    return false;
  }
  cfg_ = cfg;
  if (cfg.model == fsw::FilterModel::k15)
    app_ = std::make_unique<AppOf<fsw::Layout15Full>>();
  else if (cfg.model == fsw::FilterModel::k24)
    app_ = std::make_unique<AppOf<fsw::Layout24Full>>();
  else {
    error = std::string("the flight-software node flies the models 15 and 24, not ") + fsw::to_string(cfg.model);
    return false;
  }
  fsw::FlightAppConfig app_cfg = cfg.app;
  app_cfg.exec.ekf_group_inline = cfg.ekf_group == FswNodeConfig::EkfGroup::kInline;
  const fsw::Status st = app_->init(app_cfg);
  if (st != fsw::Status::kOk) {
    // The commands refuse such a configuration at load with its file and TOML key (cfg::validate);
    // a program that built its own still learns which field broke which rule (fsw/config_check.hpp).
    const fsw::ConfigCheck check = fsw::check_config(app_cfg);
    char text[160];
    std::snprintf(text, sizeof text, "%s = %g breaks the rule '%s' (limit %g)", fsw::to_string(check.field),
                  check.value, fsw::to_string(check.rule), check.limit);
    error = std::string("flight application configuration rejected: ") + text;
    app_.reset();
    return false;
  }
  const LcmLogStatus ls = sink_.open(cfg.telemetry);
  if (ls != LcmLogStatus::kOk) {
    const std::string& why = sink_.telemetry().log().error();
    error = "cannot open the telemetry/log (" + cfg.telemetry.log_path + "): " + (why.empty() ? to_string(ls) : why);
    app_.reset();
    return false;
  }
  summary_ = FswNodeSummary{};
  summary_.digest = fsw::kNavDigestSeed;
  closed_ = false;
  if (cfg.ekf_group == FswNodeConfig::EkfGroup::kThread) group_ = std::make_unique<GroupThread>(*app_);
  return true;
}

fsw::Status FswNode::step(const fsw::InputEvent& ev) {
  if (ev.kind == fsw::InputEvent::Kind::kImu) frame_done_ = false;
  if (!app_) return fsw::Status::kNotInitialised;
  Observers obs{*this};
  return app_->step(ev, obs);
}

void FswNode::before_event(const fsw::InputEvent& ev) {
  if (cfg_.log_inputs) {
    switch (ev.kind) {
      case fsw::InputEvent::Kind::kAlmanac: sink_.write_almanac(ev.almanac, ev.t_s); break;
      case fsw::InputEvent::Kind::kGnssRaw: sink_.write_gnss(ev.gnss); break;
      case fsw::InputEvent::Kind::kGnssPvt: sink_.write_pvt(from_fsw(ev.pvt)); break;
      case fsw::InputEvent::Kind::kImu:
        if (ev.imu_counter >= 0)
          sink_.write_imu(ImuRecord{ev.imu, ev.imu_counter, ev.imu_status});
        else
          sink_.write_imu(ev.imu, ev.imu_status);
        break;
    }
  }
  if (ev.kind != fsw::InputEvent::Kind::kImu || !group_) return;
  // Lockstep: the correction lands at a fixed frame; wait for the 1 Hz thread before it.
  if (!cfg_.realtime && app_->ekf_result_due_next_frame()) {
    const double w = group_->wait_idle();
    ++group_times_.waits;
    if (w > group_times_.wait_max_s) group_times_.wait_max_s = w;
  }
  const std::size_t before = group_times_.exec_s.size();
  group_->take_times(group_times_.exec_s);
  for (std::size_t k = before; k < group_times_.exec_s.size(); ++k) app_->note_ekf_group_exec_s(group_times_.exec_s[k]);
}

void FswNode::after_event(const fsw::InputEvent& ev, const fsw::FrameOutput& out) {
  if (ev.kind != fsw::InputEvent::Kind::kImu) return;  // out is an IMU event's
  if (out.frame_closed) ++summary_.minor_frames;
  if (group_ && out.ekf_released) group_->release();
  if (out.nav_valid) after_frame(out);
}

void FswNode::after_frame(const fsw::FrameOutput& out) {
  frame_done_ = true;
  const fsw::NavState& n = out.nav;
  fsw::nav_digest_add(summary_.digest, n);
  if (summary_.nav_frames % static_cast<std::uint64_t>(cfg_.nav_decimation) == 0 || out.ekf_updated)
    sink_.write_nav(out);
  ++summary_.nav_frames;
  summary_.last_nav = n;
  summary_.initialised = true;
  summary_.init_t_s = app_->health().init_t_s;
  if (out.ekf_ran) {
    app_->nav_sigma(nav_sigma_);
    app_->write_ekf(sink_);
    app_->write_health(sink_, out);
  }
}

void FswNode::on_truth(double t_s, const fsw::Vec3& llh, const fsw::Vec3& vel_enu_mps, const fsw::Mat3& C_b_n) {
  if (app_) sink_.write_truth(t_s, llh, vel_enu_mps, C_b_n);
}

void FswNode::set_prev_tick_exec_s(double s) {
  if (app_) app_->set_prev_tick_exec_s(s);
}

bool FswNode::close(std::string& error) {
  if (!app_ || closed_) return true;
  closed_ = true;
  stop_group_thread();
  const std::uint64_t failures = sink_.telemetry().log().write_failures();
  const LcmLogStatus ls = sink_.close();
  if (ls != LcmLogStatus::kOk || failures > 0) {
    // docs/faults.md: a log that lost events is not put in place; the error names the file and errno.
    const std::string& why = sink_.telemetry().log().error();
    error = std::string("the log is incomplete and was not written: ") + (why.empty() ? to_string(ls) : why);
    return false;
  }
  return true;
}

void FswNode::abort() {
  if (!app_ || closed_) return;
  closed_ = true;
  stop_group_thread();
  sink_.telemetry().abort_log();
  sink_.close();
}

const fsw::FrameOutput& FswNode::last_frame() const {
  static const fsw::FrameOutput none{};
  return app_ ? app_->frame() : none;
}
const fsw::FlightAppHealth& FswNode::app_health() const {
  static const fsw::FlightAppHealth none{};
  return app_ ? app_->health() : none;
}
const fsw::ExecutiveHealth& FswNode::exec_health() const {
  static const fsw::ExecutiveHealth none{};
  return app_ ? app_->exec_health() : none;
}

}  // namespace hal
