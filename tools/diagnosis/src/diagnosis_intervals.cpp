#include "tools/diagnosis_intervals.hpp"

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <limits>
#include <utility>
#include "tools/parallel.hpp"

namespace tools {
namespace {

using fsw::Effect;

/// A re-timed GNSS input arrives at most this long after its own time (apply_fixed_effect).
constexpr double kMaxRetimedLateness_s = 0.05;

/// A run's log-likelihood contributions, sorted by measurement key, and when it initialised.
struct Contributions {
  std::vector<std::pair<std::uint64_t, double>> terms;
  double init_t_s = 0.0;  ///< GNSS time of the initialising fix
  std::size_t size() const { return terms.size(); }
  const std::pair<std::uint64_t, double>& operator[](std::size_t i) const { return terms[i]; }
};

Contributions contributions(const DiagnosisRun& run) {
  Contributions c;
  c.terms.reserve(run.scalars.size());
  for (const DiagnosisRun::Scalar& s : run.scalars)
    c.terms.emplace_back(s.key, -0.5 * (std::log(2.0 * fsw::kPi * s.S) + s.nu * s.nu / s.S));
  std::sort(c.terms.begin(), c.terms.end());
  c.init_t_s = run.init_t_s;
  return c;
}

/// The model with `cand` held at each value: runs in parallel, results in input order. The
/// component is applied to the samples as each run reads them (ImuCorrection), not to a copy.
std::vector<Contributions> profile_runs(const RecordingView& data, const DiagnosisConfig& cfg,
                                        const std::vector<int>& model, int cand, const std::vector<double>& thetas,
                                        double t_ref_s) {
  const Candidate& c = diagnosis_candidates()[static_cast<std::size_t>(cand)];
  std::vector<int> fixed_model;
  for (int m : model)
    if (m != cand) fixed_model.push_back(m);
  std::vector<Contributions> out(thetas.size());
  for_each_parallel(thetas.size(), [&](std::size_t i) {
    DiagnosisConfig k = cfg;
    RecordingView v = data;
    ImuCorrection corr;
    RecordedData::Order order;
    if (c.effect == Effect::kAntennaLeverArm) {
      k.app.exec.ekf.lever_arm_b_m(c.component) += thetas[i] * fsw::effect_info(c.effect).unit_to_si;
    } else if (fixed_effect_correction(c, thetas[i], t_ref_s, corr)) {
      v.imu = &corr;
      if (corr.retimed()) {
        order = retimed_order(data, corr);
        v.order = &order;
      }
    }
    out[i] = contributions(run_diagnosis_model(v, k, fixed_model));
  });
  return out;
}

/// Log-likelihood of each run over the keys every run has, from kProfileBurnIn_s after the latest
/// initialisation among them; sets n to their number.
std::vector<double> common_log_likelihood(const std::vector<const Contributions*>& runs, double nav_rate_hz, int& n) {
  std::vector<double> ll(runs.size(), 0.0);
  n = 0;
  if (runs.empty()) return ll;
  double init_t_s = -1e300;
  for (const Contributions* r : runs) init_t_s = std::max(init_t_s, r->init_t_s);
  // The first key after the burn-in.
  const double first_t_s = init_t_s + kProfileBurnIn_s;
  const std::uint64_t first_key =
      first_t_s <= 0.0 ? 0 : DiagnosisRun::frame_key(static_cast<std::uint64_t>(std::ceil(first_t_s * nav_rate_hz)));
  std::vector<std::size_t> pos(runs.size(), 0);
  for (std::size_t r = 0; r < runs.size(); ++r)
    while (pos[r] < runs[r]->size() && (*runs[r])[pos[r]].first < first_key) ++pos[r];
  for (;;) {
    std::uint64_t kmax = 0;
    bool end = false;
    for (std::size_t r = 0; r < runs.size(); ++r) {
      if (pos[r] >= runs[r]->size()) {
        end = true;
        break;
      }
      kmax = std::max(kmax, (*runs[r])[pos[r]].first);
    }
    if (end) break;
    bool all = true;
    for (std::size_t r = 0; r < runs.size(); ++r) {
      while (pos[r] < runs[r]->size() && (*runs[r])[pos[r]].first < kmax) ++pos[r];
      if (pos[r] >= runs[r]->size() || (*runs[r])[pos[r]].first != kmax) all = false;
    }
    if (!all) continue;
    for (std::size_t r = 0; r < runs.size(); ++r) ll[r] += (*runs[r])[pos[r]++].second;
    ++n;
  }
  return ll;
}

/// The observations `gated` names ((GNSS frame, PRN); PRN 0: the GNSS solution of that frame) left
/// out of a recording: the selection a profile holds fixed. Its GNSS epochs and order stand in for
/// the recording's (view()); nothing else is copied.
struct Selection {
  const RecordedData* data = nullptr;
  bool selected = false;  ///< false: nothing gated, the recording as it is
  std::vector<fsw::GnssRawEpoch> gnss;
  RecordedData::Order order;
  RecordingView view() const {
    RecordingView v{data};
    if (selected) {
      v.gnss = &gnss;
      v.order = &order;
    }
    return v;
  }
};

Selection without_observations(const RecordedData& data, const std::vector<std::pair<std::uint64_t, std::uint8_t>>& gated,
                               double nav_rate_hz) {
  Selection sel;
  sel.data = &data;
  if (gated.empty()) return sel;
  sel.selected = true;
  sel.gnss = data.gnss;
  const auto frame_of = [nav_rate_hz](double t) { return static_cast<std::uint64_t>(std::llround(t * nav_rate_hz)); };
  const auto is_gated = [&gated](std::uint64_t f, std::uint8_t prn) {
    return std::find(gated.begin(), gated.end(), std::make_pair(f, prn)) != gated.end();
  };
  for (fsw::GnssRawEpoch& e : sel.gnss) {
    const std::uint64_t f = frame_of(e.t_s);
    int n = 0;
    for (int k = 0; k < e.n_meas; ++k)
      if (!is_gated(f, e.meas[static_cast<std::size_t>(k)].prn)) e.meas[static_cast<std::size_t>(n++)] = e.meas[static_cast<std::size_t>(k)];
    e.n_meas = n;
  }
  sel.order.reserve(data.order.size());
  for (const RecordedData::Event& ev : data.order)
    if (ev.kind != RecordedData::Kind::kPvt || !is_gated(frame_of(data.pvt[ev.index].t_s), 0)) sel.order.push_back(ev);
  return sel;
}

}  // namespace

bool profile_supported(Effect e) {
  return e != Effect::kTroposphericDelay && e != Effect::kIonosphericDelay && e != Effect::kCount;
}

bool fixed_effect_correction(const Candidate& c, double value, double t_ref_s, ImuCorrection& k) {
  k = ImuCorrection{};
  k.t_ref_s = t_ref_s;
  const double v = value * fsw::effect_info(c.effect).unit_to_si;
  switch (c.effect) {
    case Effect::kGyroMisalignment: {
      const auto ax = fsw::kGyroMisalignmentAxes[static_cast<std::size_t>(c.component)];
      k.Eg(ax.i, ax.j) = v;
      return true;
    }
    case Effect::kAccelMisalignment: {
      const auto ax = fsw::kAccelMisalignmentAxes[static_cast<std::size_t>(c.component)];
      k.Ea(ax.i, ax.j) = v;
      return true;
    }
    case Effect::kGyroScaleFactor: k.Eg(c.component, c.component) = v; return true;
    case Effect::kAccelScaleFactor: k.Ea(c.component, c.component) = v; return true;
    case Effect::kGyroGSensitivity: k.gs(c.component) = v; return true;
    case Effect::kImuGnssTimeOffset: k.offset_s = v; return true;
    case Effect::kImuClockDrift: k.drift = v; return true;
    default: return false;
  }
}

RecordedData::Order retimed_order(const RecordingView& v, const ImuCorrection& k) {
  // Arrival order on the corrected clock. A GNSS input arrived after a given IMU sample: that is
  // a fact of the recording, and it stays after that sample (whose tag is now corrected), unless
  // the corrected tag lies before the input's own time, when it arrives after the sample of its
  // time instead (the flight software holds an input until its time anyway). Keeping instead the
  // lag of the original tags behind the input's time carried the hidden offset itself into the
  // corrected data (in a simulation the epoch follows the IMU sample of its true time, whose tag
  // is late by the offset): measured on the coverage study's imu_gnss_time_offset, the profile's
  // maximum then sat 2-4 ms above the truth for either sign, its interval covering 5 of 20; then
  // 14 of 20, positive offsets still biased by the initialisation epoch (kProfileBurnIn_s); now
  // 20 of 20 (docs/diagnosis-intervals.md).
  const RecordedData::Order& in = v.events();
  const RecordedData& d = *v.data;
  const std::vector<fsw::GnssRawEpoch>& gnss = v.gnss_epochs();
  std::vector<double> key(in.size(), -1e300);
  double prev_new = -1e300, prev_key = -1e300;
  for (std::size_t i = 0; i < in.size(); ++i) {
    const RecordedData::Event& ev = in[i];
    switch (ev.kind) {
      case RecordedData::Kind::kImu:
        prev_new = k.tag(d.imu[ev.index].t_s);
        key[i] = prev_new;
        break;
      // Capped at the input's own time + kMaxRetimedLateness_s: a log is written in time-tag
      // order, so with IMU tags early by tau (a negative offset) an epoch sits after the IMU
      // sample of true time t + tau; kept there on the corrected clock it arrived tau late, and
      // at tau = 0.4 s every epoch was older than the executive's max_gnss_age_s (0.25 s) at use:
      // stale, no update at all (the corrected -400 ms flight, issue 26). The recording's order
      // says nothing of a latency that large; its tags are what is being corrected.
      case RecordedData::Kind::kGnss:
        key[i] = std::min(std::max(gnss[ev.index].t_s, prev_new), gnss[ev.index].t_s + kMaxRetimedLateness_s);
        break;
      case RecordedData::Kind::kPvt:
        key[i] = std::min(std::max(d.pvt[ev.index].t_s, prev_new), d.pvt[ev.index].t_s + kMaxRetimedLateness_s);
        break;
      case RecordedData::Kind::kAlmanac: key[i] = prev_key; break;
    }
    prev_key = key[i];
  }
  std::vector<std::size_t> idx(in.size());
  for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = i;
  // Ties: inputs that are not IMU samples after the sample (they arrived after it).
  std::stable_sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) {
    if (key[a] != key[b]) return key[a] < key[b];
    return (in[a].kind == RecordedData::Kind::kImu) && (in[b].kind != RecordedData::Kind::kImu);
  });
  RecordedData::Order order;
  order.reserve(idx.size());
  for (std::size_t i : idx) order.push_back(in[i]);
  return order;
}

void apply_fixed_effect(RecordedData& d, const Candidate& c, double value, double t_ref_s) {
  ImuCorrection k;
  if (!fixed_effect_correction(c, value, t_ref_s, k)) return;
  if (k.retimed()) d.order = retimed_order(RecordingView{&d}, k);  // from the tags as recorded
  for (fsw::ImuSample& s : d.imu) k.apply(s);
}

/// The parabola y = A t^2 + B t + C through three points (a minimum only where A > 0).
struct Parabola {
  double A = 0.0, B = 0.0, C = 0.0;
};

Parabola parabola_through(double x0, double x1, double x2, double y0, double y1, double y2) {
  const double den = (x0 - x1) * (x0 - x2) * (x1 - x2);
  Parabola p;
  p.A = (x2 * (y1 - y0) + x1 * (y0 - y2) + x0 * (y2 - y1)) / den;
  p.B = (x2 * x2 * (y0 - y1) + x1 * x1 * (y2 - y0) + x0 * x0 * (y1 - y2)) / den;
  p.C = y1 - p.A * x1 * x1 - p.B * x1;
  return p;
}

/// Where the deviance crosses level_z2 between t_in (below the level) and t_out (at or above it),
/// interpolated linearly in sqrt(deviance): the signed root of the deviance is linear in theta for
/// a Gaussian likelihood.
double level_crossing(double t_in, double t_out, double dev_in, double dev_out, double level_z2) {
  const double a = std::sqrt(std::max(0.0, dev_in)), b = std::sqrt(dev_out), r = std::sqrt(level_z2);
  return t_in + (t_out - t_in) * (r - a) / (b - a);
}

/// The drift's reference: the first GNSS measurement of the configured source (the filter's is
/// its first update; the offset, when in the model, absorbs the difference).
double first_gnss_time_s(const RecordedData& data, const DiagnosisConfig& cfg) {
  double t_ref_s = data.imu.empty() ? 0.0 : data.imu.front().t_s;
  for (const RecordedData::Event& ev : data.order) {
    if (ev.kind == RecordedData::Kind::kGnss && cfg.gnss_source == cfg::GnssSource::kRaw) {
      t_ref_s = data.gnss[ev.index].t_s;
      break;
    }
    if (ev.kind == RecordedData::Kind::kPvt && cfg.gnss_source == cfg::GnssSource::kPvt) {
      t_ref_s = data.pvt[ev.index].t_s;
      break;
    }
  }
  return t_ref_s;
}

/// Resolve the maximum: the doubling steps can leave it between two points far apart, where a
/// sharp or skewed profile's parabolic vertex lies beyond the crossing read off the coarse grid
/// (seen on the walk's clock drift: the maximum outside its own interval). While that is so, the
/// gaps beside the best point are halved: the points to run next, none when the vertex is inside.
std::vector<double> refinement_points(const std::vector<double>& theta, const std::vector<std::size_t>& order,
                                      const std::vector<double>& dev, double level_z2) {
  const std::size_t b = static_cast<std::size_t>(std::min_element(dev.begin(), dev.end()) - dev.begin());
  const double x0 = theta[order[b > 0 ? b - 1 : b]], x1 = theta[order[b]],
               x2 = theta[order[b + 1 < dev.size() ? b + 1 : b]];
  double vertex = x1;
  if (b > 0 && b + 1 < dev.size()) {
    const Parabola q = parabola_through(x0, x1, x2, dev[b - 1], dev[b], dev[b + 1]);
    if (q.A > 0.0) vertex = std::clamp(-q.B / (2.0 * q.A), x0, x2);
  }
  const auto crossing = [&](std::size_t i, std::size_t j) {
    return level_crossing(theta[order[i]], theta[order[j]], dev[i], dev[j], level_z2);
  };
  const bool below_lo = b > 0 && dev[b - 1] >= level_z2 && vertex < crossing(b, b - 1);
  const bool above_hi = b + 1 < dev.size() && dev[b + 1] >= level_z2 && vertex > crossing(b, b + 1);
  std::vector<double> mid;
  if (below_lo || above_hi) {
    if (b > 0) mid.push_back(0.5 * (x0 + x1));
    if (b + 1 < dev.size()) mid.push_back(0.5 * (x1 + x2));
  }
  return mid;
}

/// The profile read off its comparable runs (theta[order[i]] with deviance dev[i]): the points,
/// the maximum (the parabola through the best point and its neighbours) and the crossings of
/// level_z2 outward from it.
void read_profile(ProfileInterval& pi, const std::vector<double>& theta, const std::vector<std::size_t>& order,
                  const std::vector<double>& dev, double x, double level_z2) {
  const std::size_t n = order.size();
  pi.theta.resize(n);
  pi.deviance = dev;
  for (std::size_t i = 0; i < n; ++i) {
    pi.theta[i] = theta[order[i]];
    if (theta[order[i]] == x) pi.deviance_at_filter = dev[i];  // the first point run
  }
  const std::size_t best = static_cast<std::size_t>(std::min_element(dev.begin(), dev.end()) - dev.begin());
  pi.estimate = pi.theta[best];
  if (best > 0 && best + 1 < n) {
    const double x0 = pi.theta[best - 1], x1 = pi.theta[best], x2 = pi.theta[best + 1];
    const Parabola q = parabola_through(x0, x1, x2, dev[best - 1], dev[best], dev[best + 1]);
    if (q.A > 0.0) {
      pi.estimate = std::clamp(-q.B / (2.0 * q.A), x0, x2);
      // The deviance is relative to the best point run; measured from the parabola's minimum at
      // the estimate instead, the filter's estimate next to it gets its own distance, not 0.
      const double y_min = q.A * pi.estimate * pi.estimate + q.B * pi.estimate + q.C;
      if (y_min < 0.0) pi.deviance_at_filter -= y_min;
    }
  }
  const auto cross = [&](std::size_t i, std::size_t j) {  // i inside (below level), j outside
    return level_crossing(pi.theta[i], pi.theta[j], dev[i], dev[j], level_z2);
  };
  pi.lo = pi.theta.front();
  for (std::size_t i = best; i > 0; --i)
    if (dev[i - 1] >= level_z2) {
      pi.lo = cross(i, i - 1);
      pi.lo_bounded = true;
      break;
    }
  pi.hi = pi.theta.back();
  for (std::size_t i = best; i + 1 < n; ++i)
    if (dev[i + 1] >= level_z2) {
      pi.hi = cross(i, i + 1);
      pi.hi_bounded = true;
      break;
    }
  pi.available = true;
}

ProfileInterval profile_interval(const RecordedData& data, const DiagnosisConfig& cfg, const std::vector<int>& model,
                                 int cand, double x, double s, double level_z2, const ProfileReference* known) {
  ProfileInterval pi;
  const Candidate& c = diagnosis_candidates()[static_cast<std::size_t>(cand)];
  if (!profile_supported(c.effect) || !(s > 0.0) || !std::isfinite(x)) return pi;
  const double t_ref_s = first_gnss_time_s(data, cfg);
  // The data selection held fixed. The innovation gate chooses its measurements by their
  // innovations, which move with theta: runs at different theta would gate different measurements
  // (a 10.83 gate rejects about 1 in 1000 good scalars, 4 to 6 of a 600 s flight), each
  // switch a step in l(theta) of a few units, and no likelihood over one data set (measured: the
  // lever arm y on simulated flights, a profile maximum 1.5 sigma from the filter's estimate and
  // intervals that missed the truth). The model with the component estimated (the run that gave
  // x) gates once; its gated observations are left out of the data, and the profile runs, on
  // that fixed selection, are not gated.
  const ProfileReference ref = known ? *known : ProfileReference::of(run_diagnosis_model(data, cfg, model));
  const Selection selected = without_observations(data, ref.gated, cfg.app.exec.nav_rate_hz);
  DiagnosisConfig ungated = cfg;
  ungated.app.exec.ekf.gate_chi2 = std::numeric_limits<double>::max();
  pi.gated = static_cast<int>(ref.gated.size());
  pi.runs = 1;
  const double prior = cfg.prior[static_cast<std::size_t>(c.effect)];
  const double max_reach = std::max(30.0 * s, 6.0 * prior);  // no interval beyond this from x
  std::vector<double> theta;
  std::vector<Contributions> runs;
  const auto add = [&](const std::vector<double>& t) {
    std::vector<Contributions> r = profile_runs(selected.view(), ungated, model, cand, t, t_ref_s);
    for (std::size_t i = 0; i < t.size(); ++i) {
      theta.push_back(t[i]);
      runs.push_back(std::move(r[i]));
    }
    pi.runs += static_cast<int>(t.size());
  };
  // A Gaussian likelihood crosses 3.84 at x +- 1.96 s: three runs bound it; a flatter or shifted
  // one is followed outward with doubling steps.
  add({x - 2.0 * s, x, x + 2.0 * s});
  double step_lo = 2.0 * s, step_hi = 2.0 * s;
  int refine = 0;
  std::vector<double> dev;
  std::vector<std::size_t> order;
  // A run whose flight software used far fewer measurements than the run at the filter's estimate
  // (re-timed data it no longer takes: stale or rejected epochs, a late initialisation) has no
  // likelihood of the same data: it is left out, and the search does not go further on its side
  // (that end of the interval is then not bounded). Measured on the walk's clock drift: at -1069
  // ppm 1488 scalars against 2712 at the estimate; compared over what that run kept, it had
  // dragged the profile's maximum to -1447 ppm.
  const std::size_t n_at_x = runs[1].size();  // the runs are x - 2s, x, x + 2s first
  const auto comparable = [&](std::size_t i) {
    return static_cast<double>(runs[i].size()) >= kProfileMinShare * static_cast<double>(n_at_x);
  };
  bool stop_lo = false, stop_hi = false;
  for (int iter = 0;; ++iter) {
    std::vector<std::size_t> all(theta.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
    std::sort(all.begin(), all.end(), [&](std::size_t a, std::size_t b) { return theta[a] < theta[b]; });
    order.clear();
    for (std::size_t i : all)
      if (comparable(i)) order.push_back(i);
    pi.incomparable = static_cast<int>(all.size() - order.size());
    if (order.size() < 3) return pi;
    stop_lo = stop_lo || !comparable(all.front());
    stop_hi = stop_hi || !comparable(all.back());
    std::vector<const Contributions*> ptr;
    for (std::size_t i : order) ptr.push_back(&runs[i]);
    const std::vector<double> ll = common_log_likelihood(ptr, cfg.app.exec.nav_rate_hz, pi.measurements);
    // The runs must compare the same measurements: a schedule that moves with theta (an EKF step
    // slower than the GNSS epochs, phased by the initialisation time) leaves them few or none in
    // common, and a likelihood over nothing is flat. Then there is no profile (the filter's own
    // interval is kept), and no more runs are spent following a flat curve outward.
    if (2 * static_cast<std::size_t>(pi.measurements) < ref.scalars) return pi;
    const double ll_max = *std::max_element(ll.begin(), ll.end());
    dev.assign(ll.size(), 0.0);
    for (std::size_t i = 0; i < ll.size(); ++i) dev[i] = 2.0 * (ll_max - ll[i]);
    const double t_lo = theta[order.front()], t_hi = theta[order.back()];
    std::vector<double> more;
    if (dev.front() < level_z2 && x - t_lo < max_reach && !stop_lo) more.push_back(t_lo - step_lo);
    if (dev.back() < level_z2 && t_hi - x < max_reach && !stop_hi) more.push_back(t_hi + step_hi);
    if (more.empty() || iter >= 8) {
      if (refine >= 4) break;  // at most 4 rounds of refinement_points; a Gaussian profile needs none
      const std::vector<double> mid = refinement_points(theta, order, dev, level_z2);
      if (mid.empty()) break;
      ++refine;
      add(mid);
      continue;
    }
    if (dev.front() < level_z2) step_lo *= 2.0;
    if (dev.back() < level_z2) step_hi *= 2.0;
    add(more);
  }
  read_profile(pi, theta, order, dev, x, level_z2);
  return pi;
}

int candidate_index(const std::string& name) {
  const std::vector<Candidate>& cands = diagnosis_candidates();
  for (std::size_t i = 0; i < cands.size(); ++i)
    if (candidate_name(cands[i]) == name) return static_cast<int>(i);
  return -1;
}

ProfileInterval profile_component(const RecordedData& data, const DiagnosisConfig& cfg, std::vector<int> model,
                                  int cand, double& filter_x, double& filter_s) {
  if (std::find(model.begin(), model.end(), cand) == model.end()) model.push_back(cand);
  const DiagnosisRun run = run_diagnosis_model(data, cfg, model);
  filter_x = 0.0;
  filter_s = 0.0;
  for (std::size_t a = 0; a < run.active.size() && a < run.estimate.size(); ++a)
    if (run.active[a] == cand) {
      filter_x = run.estimate[a];
      filter_s = run.sigma[a];
    }
  if (!run.initialised) return {};
  const ProfileReference ref = ProfileReference::of(run);
  return profile_interval(data, cfg, model, cand, filter_x, filter_s, kDeviance95, &ref);
}

namespace {

/// A progress line with the profile curve.
void report_curve(const std::function<void(const std::string&)>& progress, const ProfileInterval& pi) {
  if (!progress) return;
  std::string curve = "  profile (value: deviance):";
  char b[64];
  for (std::size_t i = 0; i < pi.theta.size(); ++i) {
    std::snprintf(b, sizeof b, " %.4g: %.2f", pi.theta[i], pi.deviance[i]);
    curve += b;
  }
  progress(curve + " over " + std::to_string(pi.measurements) + " common measurements" +
           (pi.incomparable > 0 ? "; " + std::to_string(pi.incomparable) +
                                      " run(s) left out beyond it (the flight software used under 90% of the measurements)"
                                : ""));
}

}  // namespace

ReportedInterval filter_interval(double x, double s) {
  constexpr double kZ95 = 1.959963984540054;
  ReportedInterval r;
  r.method = "filter";
  r.lo = x - kZ95 * s;
  r.hi = x + kZ95 * s;
  r.estimate = x;
  return r;
}

ReportedInterval reported_interval(const ProfileInterval& pi) {
  ReportedInterval r;
  r.method = "profile_likelihood";
  r.lo = pi.lo;
  r.hi = pi.hi;
  r.estimate = pi.estimate;
  r.bounded = pi.lo_bounded && pi.hi_bounded;
  r.runs = pi.runs;
  r.deviance_at_filter = pi.deviance_at_filter;
  r.model_agrees = pi.model_agrees();
  return r;
}

void add_finding_intervals(DiagnosisResult& res, const RecordedData& data, const DiagnosisConfig& cfg,
                           const std::function<void(const std::string&)>& progress, const ProfileReferences& known) {
  const bool profile = cfg.profile_intervals && res.extended.initialised;
  // Every interval first as the filter's; the profile intervals are then independent jobs (a
  // finding, or a group member alone on top of the model at the lead's selection, where its alone
  // estimate was measured: the filter's alone sigma is that of a model that does not hold when the
  // member is not the cause, and was measured optimistic, docs/diagnosis-intervals.md:
  // gyro_misalignment.zy, 0 of 20), run side by side and reported in this order.
  struct Job {
    std::vector<int> model;
    int cand;
    double x, s;
    std::string what;
    ReportedInterval* out;
    ProfileInterval pi;
  };
  std::vector<Job> jobs;
  const auto interval = [&](std::vector<int> model, int cand, double x, double s, std::string what, ReportedInterval& out) {
    out = filter_interval(x, s);
    if (cand < 0 || !profile || !profile_supported(diagnosis_candidates()[static_cast<std::size_t>(cand)].effect)) return;
    jobs.push_back(Job{std::move(model), cand, x, s, std::move(what), &out, {}});
  };
  for (Finding& f : res.findings) {
    if (f.separable()) {
      const std::string name = std::string(fsw::effect_info(f.effect).name) + (f.component.empty() ? "" : "." + f.component);
      interval(res.extended.active, candidate_index(name), f.estimate, f.sigma, name, f.interval);
      continue;
    }
    for (GroupMember& m : f.group) {
      const int cand = candidate_index(m.name);
      std::vector<int> model = f.selection_model;
      model.push_back(cand);
      interval(std::move(model), cand, m.alone_estimate, m.alone_sigma, "group member " + m.name + " alone",
               m.alone_interval);
    }
  }
  for_each_parallel(jobs.size(), [&](std::size_t i) {
    Job& j = jobs[i];
    const auto ref = known.find(j.model);
    j.pi = profile_interval(data, cfg, j.model, j.cand, j.x, j.s, kDeviance95,
                            ref == known.end() ? nullptr : &ref->second);
  });
  for (const Job& j : jobs) {
    if (progress) progress("interval: profile likelihood of " + j.what);
    if (!j.pi.available) continue;  // the filter's interval stays
    report_curve(progress, j.pi);
    *j.out = reported_interval(j.pi);
  }
  for (Finding& f : res.findings) {
    if (f.separable()) continue;
    set_group_plausibility(f.group);
    f.interval = f.group.front().alone_interval;  // the group's: its lead's
  }
}

void set_group_plausibility(std::vector<GroupMember>& group) {
  double sum = 0.0;
  for (GroupMember& m : group) {
    const bool profile = m.alone_interval.is_profile() && m.alone_interval.model_agrees;
    const double x = profile ? m.alone_interval.estimate : m.alone_estimate;
    m.prior_z = m.prior_sigma > 0.0 ? x / m.prior_sigma : 0.0;
    sum += std::exp(-0.5 * m.prior_z * m.prior_z);
  }
  for (GroupMember& m : group) m.plausibility = sum > 0.0 ? std::exp(-0.5 * m.prior_z * m.prior_z) / sum : 0.0;
}

void set_headline_estimates(std::vector<Finding>& findings) {
  constexpr double kZ95 = 1.959963984540054;
  for (Finding& f : findings) {
    if (f.interval.is_profile()) {
      f.estimate = f.interval.estimate;
      f.sigma = (f.interval.hi - f.interval.lo) / (2.0 * kZ95);
      f.estimate_method = "profile_maximum";
    } else {
      f.estimate = f.filter_estimate;
      f.sigma = f.filter_sigma;
      f.estimate_method = "filter";
    }
  }
}

}  // namespace tools
