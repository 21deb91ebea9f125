#include "tools/timing_audit.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "fsw/driver.hpp"
#include "fsw/flight_app.hpp"
#include "sim/almanac.hpp"
#include "sim/sensor_stream.hpp"
#include "tools/montecarlo.hpp"

namespace tools {
namespace {

using Clock = std::chrono::steady_clock;

double to_s(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

/// Median cost of one pair of clock reads (what a timed sample contains besides the work).
double timer_overhead_s() {
  constexpr int kN = 20001;
  std::vector<double> d(kN);
  for (int i = 0; i < kN; ++i) {
    const auto a = Clock::now();
    const auto b = Clock::now();
    d[static_cast<std::size_t>(i)] = to_s(b - a);
  }
  std::nth_element(d.begin(), d.begin() + kN / 2, d.end());
  return d[kN / 2];
}

/// Context switches of the calling thread so far (voluntary + involuntary).
long context_switches() {
  rusage ru{};
  if (getrusage(RUSAGE_THREAD, &ru) != 0) return 0;
  return ru.ru_nvcsw + ru.ru_nivcsw;
}

/// Times one call: wall seconds minus the timer overhead; preempted when the thread was switched
/// out meanwhile (the counters are read outside the timed interval).
template <class F>
double timed(F&& f, double overhead_s, unsigned char& preempted) {
  const long cs0 = context_switches();
  const auto a = Clock::now();
  f();
  const auto b = Clock::now();
  preempted = context_switches() != cs0 ? 1 : 0;
  return std::max(0.0, to_s(b - a) - overhead_s);
}

/// Everything one layout's pass records, per minor frame (200 Hz group) and per 1 Hz run.
struct Pass {
  std::vector<double> tick_s;               ///< the frame's 200 Hz group calls (on_gnss, on_imu)
  std::vector<unsigned char> tick_pre;
  std::vector<unsigned char> landed;        ///< a 1 Hz correction landed in this frame
  std::vector<unsigned char> initialised;   ///< the flight application was initialised at the frame's end
  std::vector<std::string> work;            ///< what the frame did (filled for frames with GNSS or 1 Hz work)
  std::vector<double> t_s;                  ///< navigation time at the frame's end (before init: the IMU's)
  std::vector<std::vector<double>> stage_s; ///< [stage][tick]
  std::vector<std::vector<unsigned char>> stage_pre;
  std::vector<double> ekf_s;                ///< each 1 Hz run (run_ekf_group), apart from the frames
  std::vector<unsigned char> ekf_pre;
  std::vector<std::size_t> ekf_release;     ///< the frame that released it
  std::vector<int> sats;                    ///< satellites of each epoch the EKF used
  long init_frame = -1;                     ///< the frame in which the flight application initialised
  long ekf_updates = 0;
  long fsw_errors = 0;
  long ekf_slips = 0, ekf_late = 0;         ///< the executive's own counters (lockstep: both 0)
  double wall_s = 0;
};

/// One line on what a minor frame's 200 Hz group did, from its output.
std::string frame_work(const fsw::FrameOutput& out, bool had_epoch, int epoch_sats, bool init_now) {
  std::string w;
  if (had_epoch)
    w = std::string(init_now ? "FlightApp::on_gnss initialising (single-point fix, levelling, heading from the track; "
                             : "FlightApp::on_gnss (raw epoch, ") +
        std::to_string(epoch_sats) + " satellites from the almanac); ";
  w += "200 Hz group";
  if (out.ekf_released) w += " releasing the 1 Hz group (transition closed, request filled)";
  if (out.ekf_ran) {
    w += std::string(out.ekf_released ? "," : "") + " landing a 1 Hz correction";
    if (out.ekf_updated)
      w += " (" + std::to_string(out.report.pr_used + out.report.pr_rejected) + " pseudoranges, " +
           std::to_string(out.report.prr_used + out.report.prr_rejected) + " rates)";
    else
      w += " (propagation only)";
  }
  return w;
}

/// The timing audit's observer of the flight driver (fsw/driver.hpp): times every 200 Hz group
/// call (a raw epoch's, an IMU sample's) between before() and after(), sums them per minor frame,
/// runs (and times) the 1 Hz group after the frame that released it, as a lower-priority task
/// would, and runs the configured frame stages on each frame's input.
template <class Layout>
struct FrameTimer {
  fsw::FlightDriver<Layout>& driver;
  const sim::SensorStream& stream;
  const TimingAuditConfig& cfg;
  const double overhead_s;
  Pass& p;
  std::array<fsw::ImuSample, 2 * fsw::FrameBuilder::kMaxSamplesPerFrame> frame{};
  int n_in_frame = 0;
  bool frame_has_epoch = false, frame_init = false, was_initialised = false;
  double frame_s = 0.0;
  unsigned char frame_pre = 0;
  long cs0 = 0;
  Clock::time_point t0{};

  static bool is_timed(const fsw::InputEvent& ev) {
    return ev.kind == fsw::InputEvent::Kind::kGnssRaw || ev.kind == fsw::InputEvent::Kind::kImu;
  }
  void before(const fsw::InputEvent& ev) {
    if (!is_timed(ev)) return;
    was_initialised = driver.app().initialised();
    cs0 = context_switches();  // read outside the timed interval (as timed())
    t0 = Clock::now();
  }
  void after(const fsw::InputEvent& ev, fsw::Status status, const fsw::FrameOutput& out) {
    if (!is_timed(ev)) return;
    const auto t1 = Clock::now();
    frame_pre |= context_switches() != cs0 ? 1 : 0;
    frame_s += std::max(0.0, to_s(t1 - t0) - overhead_s);
    const fsw::FlightApp<Layout>& app = driver.app();
    // The stream's order (sim/sensor_stream.hpp): an epoch arrives after the IMU sample of its
    // time, so it belongs to the next frame, the one whose end releases its EKF step.
    if (ev.kind == fsw::InputEvent::Kind::kGnssRaw) {
      frame_has_epoch = true;
      if (!was_initialised && app.initialised()) frame_init = true;
      if (status != fsw::Status::kOk) throw std::runtime_error("timing audit: FlightApp::on_gnss failed");
      return;
    }
    const fsw::ImuSample& sample = ev.imu;
    if (n_in_frame < static_cast<int>(frame.size())) frame[static_cast<std::size_t>(n_in_frame++)] = sample;
    if (status != fsw::Status::kOk) throw std::runtime_error("timing audit: FlightApp::on_imu failed");
    // A frame ends where the flight application closes it (FrameOutput::frame_closed: a navigation
    // frame, or before initialisation a frame's worth of samples).
    if (out.frame_closed || n_in_frame >= static_cast<int>(frame.size())) close_frame(out, sample);
  }
  void close_frame(const fsw::FrameOutput& out, const fsw::ImuSample& sample) {
    const fsw::FlightApp<Layout>& app = driver.app();
    fsw::FrameInput in;  // the frame's stages see its input (untimed prepare), timed apart
    in.imu = frame.data();
    in.n_imu = n_in_frame;
    in.gnss = frame_has_epoch ? &stream.epoch() : nullptr;
    for (std::size_t s = 0; s < cfg.frame_stages.size(); ++s) {
      const FrameStage& stg = cfg.frame_stages[s];
      if (stg.prepare) stg.prepare(in);
      unsigned char spre = 0;
      p.stage_s[s].push_back(timed([&stg] { stg.run(); }, overhead_s, spre));
      p.stage_pre[s].push_back(spre);
    }
    const std::size_t k = p.tick_s.size();
    p.tick_s.push_back(frame_s);
    p.tick_pre.push_back(frame_pre);
    p.landed.push_back(out.ekf_ran ? 1 : 0);
    p.initialised.push_back(app.initialised() ? 1 : 0);
    p.t_s.push_back(out.nav_valid ? out.nav.t_s : sample.t_s);
    if (frame_init) p.init_frame = static_cast<long>(k);
    p.work.push_back(out.ekf_ran || out.ekf_released || frame_has_epoch
                         ? frame_work(out, frame_has_epoch, stream.epoch().n_obs, frame_init)
                         : std::string());
    if (out.ekf_updated) p.sats.push_back(out.report.n_obs);
    if (out.ekf_released) {  // the 1 Hz group, after the frame that released it
      unsigned char epre = 0;
      fsw::Status status = fsw::Status::kOk;
      p.ekf_s.push_back(timed([&] { status = driver.app().run_ekf_group(); }, overhead_s, epre));
      p.ekf_pre.push_back(epre);
      p.ekf_release.push_back(k);
      if (status != fsw::Status::kOk) throw std::runtime_error("timing audit: FlightApp::run_ekf_group failed");
    }
    n_in_frame = 0;
    frame_has_epoch = false;
    frame_init = false;
    frame_s = 0.0;
    frame_pre = 0;
  }
};

/// Flies the scenario through the flight application (the one simulated sensor stream,
/// sim/sensor_stream.hpp, on the shared truth: raw receiver epochs, IMU samples) with its two rate
/// groups timed apart: every 200 Hz frame (its on_gnss and on_imu calls) and every run of the 1 Hz group (run_ekf_group, called after the frame that
/// released it, as a lower-priority task would run). Initialisation as cfg.init_mode: kTrack is what
/// HIL flies (in-motion initialisation from the first good epoch; the frames before it are the
/// levelling calls, grouped by the frame's IMU samples), kGiven the Monte Carlo's start.
template <class Layout>
Pass fly(const sim::Scenario& sc, const sim::TruthTrack& truth, const std::vector<sim::AlmanacEntry>& almanac,
         const MonteCarloConfig& mc, const TimingAuditConfig& cfg, double overhead_s) {
  const auto w0 = Clock::now();
  const std::uint64_t seed = sc.seed + static_cast<std::uint64_t>(cfg.run);
  sim::SensorStream stream(sc, truth, almanac, seed);
  fsw::FlightAppConfig acfg = flight_app_config(sc, mc);
  acfg.exec.ekf_group_inline = false;  // the 1 Hz group is run (and timed) apart
  acfg.init_mode = cfg.init_mode;
  auto driver = std::make_unique<fsw::FlightDriver<Layout>>();  // the 56-state executives are ~100 KB
  if (driver->init(acfg) != fsw::Status::kOk) throw std::runtime_error("timing audit: flight application init failed");
  // The almanac (untimed, power-up), then the given start for kGiven.
  fsw::NoObserver untimed;
  const fsw::InputEvent* first = stream.next();
  for (; first != nullptr && first->kind == fsw::InputEvent::Kind::kAlmanac; first = stream.next())
    (void)driver->step(*first, untimed);
  if (cfg.init_mode == fsw::InitMode::kGiven &&
      driver->start_given(initial_nav_state(truth, stream.imu_errors(), mc, seed)) != fsw::Status::kOk)
    throw std::runtime_error("timing audit: flight application start failed");

  Pass p;
  const int spf = acfg.exec.imu_samples_per_frame;
  const std::size_t n_frames = truth.imu.size() / static_cast<std::size_t>(spf);
  for (auto* v : {&p.tick_s, &p.t_s}) v->reserve(n_frames);
  for (auto* v : {&p.tick_pre, &p.landed, &p.initialised}) v->reserve(n_frames);
  p.work.reserve(n_frames);
  p.stage_s.assign(cfg.frame_stages.size(), {});
  p.stage_pre.assign(cfg.frame_stages.size(), {});
  for (auto& s : p.stage_s) s.reserve(n_frames);
  for (auto& s : p.stage_pre) s.reserve(n_frames);

  FrameTimer<Layout> timer{*driver, stream, cfg, overhead_s, p};
  if (first != nullptr) {
    (void)driver->step(*first, timer);
    fsw::drive(stream, *driver, timer);
  }
  const fsw::FlightApp<Layout>* app = &driver->app();
  if (!app->initialised()) throw std::runtime_error("timing audit: the flight application never initialised");
  const fsw::ExecutiveHealth& h = app->executive().health();
  p.ekf_updates = h.ekf_updates;
  p.fsw_errors = h.fsw_errors;
  p.ekf_slips = h.ekf_slips;
  p.ekf_late = h.ekf_late;
  p.wall_s = to_s(Clock::now() - w0);
  return p;
}

/// Largest sample of the given ticks that was not preempted.
double max_unpreempted(const std::vector<double>& t, const std::vector<unsigned char>& pre, const std::vector<std::size_t>& ks) {
  double m = 0.0;
  for (std::size_t k : ks)
    if (!pre[k]) m = std::max(m, t[k]);
  return m;
}

/// Start delays on one core at real time: tick k released at k * period. exec_s: per tick, with
/// preempted samples already replaced.
struct Schedule {
  std::vector<double> jitter_s;
  std::vector<unsigned char> miss;
};
Schedule schedule(const std::vector<double>& exec_s, double period_s) {
  Schedule s;
  const std::size_t n = exec_s.size();
  s.jitter_s.resize(n);
  s.miss.resize(n);
  double finish = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const double release = static_cast<double>(k) * period_s;
    const double exec = exec_s[k];
    const double start = std::max(release, finish);
    finish = start + exec;
    s.jitter_s[k] = start - release;
    s.miss[k] = finish > release + period_s ? 1 : 0;
  }
  return s;
}

/// Statistics of the unpreempted samples among ticks ks; the preempted ones counted.
void fill_stats(TaskTiming& t, const std::vector<double>& v, const std::vector<unsigned char>& pre,
                const std::vector<std::size_t>& ks) {
  std::vector<double> keep;
  keep.reserve(ks.size());
  for (std::size_t k : ks) {
    t.max_including_preempted_us = std::max(t.max_including_preempted_us, v[k] * 1e6);
    if (pre[k])
      ++t.preempted;
    else
      keep.push_back(v[k]);
  }
  t.stats = timing_stats(keep);
}

/// Fills the schedule figures of a task from the ticks it owns.
void add_schedule(TaskTiming& t, const Schedule& s, const std::vector<std::size_t>& ticks) {
  std::vector<double> j;
  j.reserve(ticks.size());
  for (std::size_t k : ticks) {
    j.push_back(s.jitter_s[k]);
    t.deadline_misses += s.miss[k];
  }
  const TimingStats js = timing_stats(j);
  t.release_jitter_max_us = js.max_us;
  t.release_jitter_p99_us = js.p99_us;
}

/// The 1 Hz group's timing over one pass: its statistics, and its slips and response times on a
/// preemptive single-core schedule behind the 200 Hz group's frames (exec, sch).
TaskTiming ekf_group_timing(const Pass& p, const Schedule& sch, const std::vector<double>& exec,
                            const fsw::ExecutiveConfig& ecfg, const std::string& l, double flight_s) {
  const double period_s = 1.0 / ecfg.nav_rate_hz;
  int min_iv = 0, max_iv = 0;
  for (std::size_t i = 1; i < p.ekf_release.size(); ++i) {
    const int iv = static_cast<int>(p.ekf_release[i] - p.ekf_release[i - 1]);
    min_iv = min_iv == 0 ? iv : std::min(min_iv, iv);
    max_iv = std::max(max_iv, iv);
  }
  TaskTiming te;
  te.name = "ekf_1hz/" + l;
  te.layout = l;
  te.description = "the 1 Hz group: one run of FlightApp::run_ekf_group (Ekf::propagate over the released interval, "
                   "update with the epoch: pseudorange and rate per satellite, the correction), run after the frame "
                   "that released it; its deadline is the frame at which the correction lands (ekf_latency_frames)";
  te.nominal_rate_hz = ecfg.nav_rate_hz / ecfg.frames_per_ekf;
  {
    std::vector<std::size_t> ek(p.ekf_s.size());
    for (std::size_t i = 0; i < ek.size(); ++i) ek[i] = i;
    fill_stats(te, p.ekf_s, p.ekf_pre, ek);
    const double ekf_cap = max_unpreempted(p.ekf_s, p.ekf_pre, ek);
    // Preemptive schedule: a run released at frame R gets what the 200 Hz group leaves of frames
    // R, R+1, ...; it slips when it has not finished before frame R + L's 200 Hz work.
    for (std::size_t i = 0; i < p.ekf_s.size(); ++i) {
      double left = p.ekf_pre[i] ? ekf_cap : p.ekf_s[i];
      const std::size_t R = p.ekf_release[i];
      const std::size_t L = static_cast<std::size_t>(ecfg.ekf_latency_frames);
      double finish_s = -1.0;
      for (std::size_t f = R; f < R + L && f < exec.size(); ++f) {
        const double release = static_cast<double>(f) * period_s;
        const double busy_until = release + sch.jitter_s[f] + exec[f];
        const double idle = std::max(0.0, release + period_s - busy_until);
        if (left <= idle) {
          finish_s = busy_until + left - static_cast<double>(R) * period_s;
          break;
        }
        left -= idle;
      }
      if (finish_s < 0.0) ++te.slips;
      else te.response_max_us = std::max(te.response_max_us, finish_s * 1e6);
    }
  }
  te.cpu_share = te.stats.mean_us * 1e-6 * static_cast<double>(p.ekf_s.size()) / flight_s;
  te.interval_frames_min = min_iv;
  te.interval_frames_max = max_iv;
  te.deadline_misses = te.slips;
  return te;
}

/// What one pass counted and where its worst unpreempted minor frame was, and what it did.
void describe_pass(LayoutTiming& lt, const Pass& p) {
  lt.ekf_updates = p.ekf_updates;
  lt.fsw_errors = p.fsw_errors;
  lt.ekf_slips_counted = p.ekf_slips;
  lt.ekf_late_counted = p.ekf_late;
  lt.init_frame = p.init_frame;
  if (p.init_frame >= 0) {
    lt.init_frame_us = p.tick_s[static_cast<std::size_t>(p.init_frame)] * 1e6;
    lt.init_frame_preempted = p.tick_pre[static_cast<std::size_t>(p.init_frame)] != 0;
  }
  if (!p.sats.empty()) {
    std::vector<int> s = p.sats;
    std::sort(s.begin(), s.end());
    lt.sats_min = s.front();
    lt.sats_max = s.back();
    lt.sats_median = s[(s.size() - 1) / 2];
  }
  lt.wall_s = p.wall_s;
  // The worst minor frame that was not preempted, and what it did.
  for (std::size_t k = 0; k < p.tick_s.size(); ++k)
    if (!p.tick_pre[k] && p.tick_s[k] * 1e6 > lt.worst_frame_us) {
      lt.worst_frame_us = p.tick_s[k] * 1e6;
      lt.worst_frame_index = static_cast<long>(k);
      lt.worst_frame_t_s = p.t_s[k];
      lt.worst_frame_work = p.work[k].empty() ? (p.initialised[k] ? "200 Hz group only" : "levelling before initialisation")
                                              : p.work[k];
    }
}

}  // namespace

TimingAuditResult run_timing_audit(const sim::Scenario& sc, const TimingAuditConfig& cfg) {
  for (const std::string& l : cfg.layouts)
    if (l != "Layout15" && l != "Layout24" && l != "Layout15Full" && l != "Layout24Full")
      throw std::runtime_error("timing audit: unknown layout '" + l + "' (Layout15, Layout24, Layout15Full, Layout24Full)");
  for (const FrameStage& st : cfg.frame_stages)
    if (st.name.empty() || !st.run) throw std::runtime_error("timing audit: a frame stage needs a name and run()");
  const sim::TruthTrack truth = sim::TruthTrack::generate(sc);
  const sim::AlmanacParseResult alm = sim::parse_yuma_file(sim::almanac_path(sc.gps));
  if (!alm.ok()) throw std::runtime_error(alm.error);

  TimingAuditResult r;
  r.scenario = sc.name;
  r.flight_s = truth.imu.empty() ? 0.0 : truth.imu.back().t_s - truth.epochs.front().t_s;
  const double overhead_s = timer_overhead_s();
  r.timer_overhead_ns = overhead_s * 1e9;
  if (!(r.flight_s > 0.0)) throw std::runtime_error("timing audit: the scenario has no flight time");

  if (cfg.layouts.empty()) throw std::runtime_error("timing audit: no layout to fly");
  std::vector<std::vector<double>> stage_samples(cfg.frame_stages.size());
  std::vector<std::vector<unsigned char>> stage_pre(cfg.frame_stages.size());
  std::vector<std::vector<double>> stage_jitter(cfg.frame_stages.size());
  std::vector<long> stage_misses(cfg.frame_stages.size(), 0);
  for (const std::string& l : cfg.layouts) {
    MonteCarloConfig mc;
    mc.model_gps_errors = l == "Layout15Full" || l == "Layout24Full";
    mc.models = {l == "Layout15" || l == "Layout15Full" ? fsw::FilterModel::k15 : fsw::FilterModel::k24};
    validate_overlay(sc, mc);  // refused with the overlay, file, key, value and rule before the flight
    const fsw::ExecutiveConfig ecfg = flight_app_config(sc, mc).exec;
    Pass p;
    if (l == "Layout15") p = fly<fsw::Layout15>(sc, truth, *alm.almanac, mc, cfg, overhead_s);
    if (l == "Layout24") p = fly<fsw::Layout24>(sc, truth, *alm.almanac, mc, cfg, overhead_s);
    if (l == "Layout15Full") p = fly<fsw::Layout15Full>(sc, truth, *alm.almanac, mc, cfg, overhead_s);
    if (l == "Layout24Full") p = fly<fsw::Layout24Full>(sc, truth, *alm.almanac, mc, cfg, overhead_s);
    r.frames = static_cast<long>(p.tick_s.size());
    const double period_s = 1.0 / ecfg.nav_rate_hz;

    std::vector<std::size_t> all_k;
    for (std::size_t k = 0; k < p.tick_s.size(); ++k) all_k.push_back(k);
    // The single-core schedule: the 200 Hz group (and the frame stages) first in every frame; a
    // preempted sample counts as its task's largest unpreempted one.
    const double nav_cap = max_unpreempted(p.tick_s, p.tick_pre, all_k);
    std::vector<double> exec(p.tick_s.size(), 0.0);
    for (std::size_t k = 0; k < exec.size(); ++k) {
      exec[k] = p.tick_pre[k] ? nav_cap : p.tick_s[k];
      for (std::size_t s = 0; s < p.stage_s.size(); ++s)
        exec[k] += p.stage_pre[s][k] ? max_unpreempted(p.stage_s[s], p.stage_pre[s], all_k) : p.stage_s[s][k];
    }
    const Schedule sch = schedule(exec, period_s);
    TaskTiming tm;
    tm.name = "mech_200hz/" + l;
    tm.layout = l;
    tm.description = "the 200 Hz group: every minor frame's FlightApp calls (on_gnss with a raw epoch: satellite "
                     "positions from the almanac, and the initialisation attempt before it succeeds; the frame's "
                     "on_imu calls: levelling before initialisation, after it Executive::tick: IMU compensation, "
                     "coning/sculling, strapdown step, transition accumulation, releasing the 1 Hz group and landing "
                     "its correction); initialisation included";
    tm.nominal_rate_hz = ecfg.nav_rate_hz;
    fill_stats(tm, p.tick_s, p.tick_pre, all_k);
    tm.cpu_share = tm.stats.mean_us * 1e-6 * static_cast<double>(all_k.size()) / r.flight_s;
    add_schedule(tm, sch, all_k);
    tm.slips = tm.deadline_misses;
    const TaskTiming te = ekf_group_timing(p, sch, exec, ecfg, l, r.flight_s);
    r.tasks.push_back(tm);
    r.tasks.push_back(te);

    LayoutTiming lt;
    lt.layout = l;
    lt.fsw_cpu_share = tm.cpu_share + te.cpu_share;
    for (std::size_t s = 0; s < p.stage_s.size(); ++s) {
      TaskTiming one;
      fill_stats(one, p.stage_s[s], p.stage_pre[s], all_k);
      lt.fsw_cpu_share += one.stats.mean_us * 1e-6 * static_cast<double>(all_k.size()) / r.flight_s;
      stage_samples[s].insert(stage_samples[s].end(), p.stage_s[s].begin(), p.stage_s[s].end());
      stage_pre[s].insert(stage_pre[s].end(), p.stage_pre[s].begin(), p.stage_pre[s].end());
      stage_jitter[s].insert(stage_jitter[s].end(), sch.jitter_s.begin(), sch.jitter_s.end());
      for (unsigned char m : sch.miss) stage_misses[s] += m;
    }
    describe_pass(lt, p);
    r.layouts.push_back(lt);
  }
  for (std::size_t s = 0; s < cfg.frame_stages.size(); ++s) {
    TaskTiming t;
    t.name = cfg.frame_stages[s].name;
    t.description = "per-frame stage before the executive tick (all layout passes)";
    t.nominal_rate_hz = 200.0;
    std::vector<std::size_t> ks(stage_samples[s].size());
    for (std::size_t k = 0; k < ks.size(); ++k) ks[k] = k;
    fill_stats(t, stage_samples[s], stage_pre[s], ks);
    // Every pass flies the whole scenario: the share of one core is per pass.
    t.cpu_share = t.stats.mean_us * 1e-6 * static_cast<double>(r.frames) / r.flight_s;
    const TimingStats js = timing_stats(stage_jitter[s]);
    t.release_jitter_max_us = js.max_us;
    t.release_jitter_p99_us = js.p99_us;
    t.deadline_misses = stage_misses[s];
    r.tasks.push_back(t);
  }
  return r;
}

}  // namespace tools
