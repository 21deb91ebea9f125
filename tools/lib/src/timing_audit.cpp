#include "tools/timing_audit.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "fsw/flight_app.hpp"
#include "sim/almanac.hpp"
#include "sim/gps_model.hpp"
#include "sim/imu_model.hpp"
#include "tools/montecarlo.hpp"
#include "tools/run_sensors.hpp"

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

/// Everything one layout's pass records, per minor frame.
struct Pass {
  std::vector<double> tick_s;               ///< the frame's flight-application calls (on_gnss, on_imu)
  std::vector<unsigned char> tick_pre;
  std::vector<unsigned char> ekf_ran;       ///< the 1 Hz group ran in this frame
  std::vector<std::string> work;            ///< what the frame did (filled for the EKF frames only)
  std::vector<double> t_s;                  ///< navigation time at the frame's end
  std::vector<std::vector<double>> stage_s; ///< [stage][tick]
  std::vector<std::vector<unsigned char>> stage_pre;
  std::vector<int> sats;                    ///< satellites of each epoch the EKF used
  long ekf_updates = 0;
  long fsw_errors = 0;
  double wall_s = 0;
};

/// One line on what a minor frame did, from its output.
std::string frame_work(const fsw::FrameOutput& out, bool had_epoch, int epoch_sats) {
  std::string w;
  if (had_epoch) w = "FlightApp::on_gnss (raw epoch, " + std::to_string(epoch_sats) + " satellites from the almanac); ";
  w += "200 Hz group";
  if (out.ekf_ran) {
    w += " + 1 Hz group: propagate";
    if (out.ekf_updated)
      w += ", update (" + std::to_string(out.report.pr_used + out.report.pr_rejected) + " pseudoranges, " +
           std::to_string(out.report.prr_used + out.report.prr_rejected) + " rates" +
           (out.report.clock_initialised ? "; receiver clock set from the epoch" : "") + "), feedback";
    else
      w += " only (no epoch)";
  }
  return w;
}

/// Flies the scenario through the flight application (as the Monte Carlo does: FlightApp started
/// from the run's given state, raw receiver epochs, IMU samples) and times every call it makes.
template <class Layout>
Pass fly(const sim::Scenario& sc, const TruthTrack& truth, const std::vector<sim::AlmanacEntry>& almanac,
         const MonteCarloConfig& mc, const TimingAuditConfig& cfg, double overhead_s) {
  const auto w0 = Clock::now();
  const std::uint64_t seed = sc.seed + static_cast<std::uint64_t>(cfg.run);
  RunSensors sensors(sc, truth, almanac, seed);
  const fsw::FlightAppConfig acfg = flight_app_config(sc, mc);
  auto app = std::make_unique<fsw::FlightApp<Layout>>();  // the 56-state executives are ~100 KB
  fsw::Status st0 = app->init(acfg);
  if (st0 == fsw::Status::kOk) {
    for (const sim::AlmanacEntry& a : sensors.almanac()) (void)app->on_almanac(a);  // a rejected element is counted
    st0 = app->start_given(initial_nav_state(truth, sensors.errors(), mc, seed));
  }
  if (st0 != fsw::Status::kOk) throw std::runtime_error("timing audit: flight application init failed");

  Pass p;
  const std::size_t n_frames = truth.imu.size() / static_cast<std::size_t>(acfg.exec.imu_samples_per_frame);
  p.tick_s.reserve(n_frames);
  p.ekf_ran.reserve(n_frames);
  p.tick_pre.reserve(n_frames);
  p.work.reserve(n_frames);
  p.t_s.reserve(n_frames);
  p.stage_s.assign(cfg.frame_stages.size(), {});
  p.stage_pre.assign(cfg.frame_stages.size(), {});
  for (auto& s : p.stage_s) s.reserve(n_frames);
  for (auto& s : p.stage_pre) s.reserve(n_frames);

  std::array<fsw::ImuSample, fsw::FrameBuilder::kMaxSamplesPerFrame> frame{};
  int n_in_frame = 0;
  fsw::FrameOutput out;
  bool frame_has_epoch = false;
  double frame_s = 0.0;
  unsigned char frame_pre = 0;
  fsw::Status status = fsw::Status::kOk;
  for (std::size_t j = 0; j < truth.imu.size(); ++j) {
    fsw::ImuSample sample;
    const bool is_epoch = sensors.measure(j, sample) != nullptr;
    frame[static_cast<std::size_t>(n_in_frame++)] = sample;
    unsigned char pre = 0;
    if (is_epoch) {  // delivered before the IMU sample of its time, as the Monte Carlo does
      frame_has_epoch = true;
      frame_s += timed([&] { status = app->on_gnss(sensors.raw()); }, overhead_s, pre);
      frame_pre |= pre;
      if (status != fsw::Status::kOk) throw std::runtime_error("timing audit: FlightApp::on_gnss failed");
    }
    if (n_in_frame == acfg.exec.imu_samples_per_frame) {  // the frame's stages see its input first
      fsw::FrameInput in;
      in.imu = frame.data();
      in.n_imu = n_in_frame;
      in.gnss = frame_has_epoch ? &sensors.epoch() : nullptr;
      for (std::size_t s = 0; s < cfg.frame_stages.size(); ++s) {
        const FrameStage& stg = cfg.frame_stages[s];
        if (stg.prepare) stg.prepare(in);
        unsigned char spre = 0;
        p.stage_s[s].push_back(timed([&stg] { stg.run(); }, overhead_s, spre));
        p.stage_pre[s].push_back(spre);
      }
    }
    frame_s += timed([&] { status = app->on_imu(sample, out); }, overhead_s, pre);
    frame_pre |= pre;
    if (status != fsw::Status::kOk) throw std::runtime_error("timing audit: FlightApp::on_imu failed");
    if (n_in_frame < acfg.exec.imu_samples_per_frame) continue;
    if (!out.nav_valid) throw std::runtime_error("timing audit: a full minor frame produced no solution");
    p.tick_s.push_back(frame_s);
    p.tick_pre.push_back(frame_pre);
    p.ekf_ran.push_back(out.ekf_ran ? 1 : 0);
    p.t_s.push_back(out.nav.t_s);
    p.work.push_back(out.ekf_ran || frame_has_epoch ? frame_work(out, frame_has_epoch, sensors.epoch().n_obs)
                                                    : std::string());
    if (out.ekf_updated) p.sats.push_back(sensors.epoch().n_obs);
    n_in_frame = 0;
    frame_has_epoch = false;
    frame_s = 0.0;
    frame_pre = 0;
  }
  p.ekf_updates = app->executive().health().ekf_updates;
  p.fsw_errors = app->executive().health().fsw_errors;
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

}  // namespace

TimingStats timing_stats(std::vector<double> v) {
  TimingStats s;
  s.n = static_cast<long>(v.size());
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  auto rank = [&v](double q) {  // nearest rank: the smallest value with at least q of the samples at or below it
    const std::size_t r = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
    return v[std::min(v.size() - 1, r == 0 ? 0 : r - 1)] * 1e6;
  };
  for (double x : v) s.total_s += x;
  s.min_us = v.front() * 1e6;
  s.max_us = v.back() * 1e6;
  s.median_us = rank(0.5);
  s.p99_us = rank(0.99);
  s.p999_us = rank(0.999);
  s.mean_us = s.total_s / static_cast<double>(v.size()) * 1e6;
  return s;
}

TimingAuditResult run_timing_audit(const sim::Scenario& sc, const TimingAuditConfig& cfg) {
  for (const std::string& l : cfg.layouts)
    if (l != "Layout15" && l != "Layout24" && l != "Layout15Full" && l != "Layout24Full")
      throw std::runtime_error("timing audit: unknown layout '" + l + "' (Layout15, Layout24, Layout15Full, Layout24Full)");
  for (const FrameStage& st : cfg.frame_stages)
    if (st.name.empty() || !st.run) throw std::runtime_error("timing audit: a frame stage needs a name and run()");
  const TruthTrack truth = TruthTrack::generate(sc);
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
    const fsw::ExecutiveConfig ecfg = flight_app_config(sc, mc).exec;
    Pass p;
    if (l == "Layout15") p = fly<fsw::Layout15>(sc, truth, *alm.almanac, mc, cfg, overhead_s);
    if (l == "Layout24") p = fly<fsw::Layout24>(sc, truth, *alm.almanac, mc, cfg, overhead_s);
    if (l == "Layout15Full") p = fly<fsw::Layout15Full>(sc, truth, *alm.almanac, mc, cfg, overhead_s);
    if (l == "Layout24Full") p = fly<fsw::Layout24Full>(sc, truth, *alm.almanac, mc, cfg, overhead_s);
    r.frames = static_cast<long>(p.tick_s.size());
    const double period_s = 1.0 / ecfg.nav_rate_hz;

    std::vector<std::size_t> mech_k, ekf_k, all_k;
    int min_iv = 0, max_iv = 0;
    long last = -1;
    for (std::size_t k = 0; k < p.tick_s.size(); ++k) {
      all_k.push_back(k);
      if (p.ekf_ran[k]) {
        ekf_k.push_back(k);
        if (last >= 0) {
          const int iv = static_cast<int>(static_cast<long>(k) - last);
          min_iv = min_iv == 0 ? iv : std::min(min_iv, iv);
          max_iv = std::max(max_iv, iv);
        }
        last = static_cast<long>(k);
      } else {
        mech_k.push_back(k);
      }
    }
    // The schedule: each tick's stages and tick; a preempted sample counts as its task's largest
    // unpreempted one.
    const double mech_cap = max_unpreempted(p.tick_s, p.tick_pre, mech_k);
    const double ekf_cap = max_unpreempted(p.tick_s, p.tick_pre, ekf_k);
    std::vector<double> exec(p.tick_s.size(), 0.0);
    for (std::size_t k = 0; k < exec.size(); ++k) {
      exec[k] = p.tick_pre[k] ? (p.ekf_ran[k] ? ekf_cap : mech_cap) : p.tick_s[k];
      for (std::size_t s = 0; s < p.stage_s.size(); ++s)
        exec[k] += p.stage_pre[s][k] ? max_unpreempted(p.stage_s[s], p.stage_pre[s], all_k) : p.stage_s[s][k];
    }
    const Schedule sch = schedule(exec, period_s);
    TaskTiming tm;
    tm.name = "mech_200hz/" + l;
    tm.layout = l;
    tm.description = "FlightApp::on_imu calls of a minor frame without the 1 Hz group (batching; on the frame's last "
                     "sample Executive::tick: IMU compensation, coning/sculling, strapdown step, Ekf::accumulate, every "
                     "10th frame a transition-matrix sub-step)";
    tm.nominal_rate_hz = ecfg.nav_rate_hz;
    fill_stats(tm, p.tick_s, p.tick_pre, mech_k);
    // Share of one core: the mean unpreempted time at the task's rate (preempted samples say
    // nothing about the task).
    tm.cpu_share = tm.stats.mean_us * 1e-6 * static_cast<double>(mech_k.size()) / r.flight_s;
    add_schedule(tm, sch, mech_k);
    TaskTiming te;
    te.name = "ekf_1hz/" + l;
    te.layout = l;
    te.description = "FlightApp calls of the minor frame that runs the 1 Hz group: on_gnss with the raw epoch "
                     "(satellite positions from the almanac), the frame's on_imu calls with its 200 Hz work, then "
                     "Ekf::propagate, update with the epoch (pseudorange and rate per satellite) and feedback";
    te.nominal_rate_hz = ecfg.nav_rate_hz / ecfg.frames_per_ekf;
    fill_stats(te, p.tick_s, p.tick_pre, ekf_k);
    te.cpu_share = te.stats.mean_us * 1e-6 * static_cast<double>(ekf_k.size()) / r.flight_s;
    te.interval_frames_min = min_iv;
    te.interval_frames_max = max_iv;
    add_schedule(te, sch, ekf_k);
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
    lt.ekf_updates = p.ekf_updates;
    lt.fsw_errors = p.fsw_errors;
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
        lt.worst_frame_work = p.work[k].empty() ? "200 Hz group only" : p.work[k];
      }
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
