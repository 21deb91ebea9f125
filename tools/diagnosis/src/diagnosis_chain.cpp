#include "tools/diagnosis_chain.hpp"

#include <algorithm>
#include <limits>
#include <cstdio>
#include <cmath>
#include <map>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include "tools/parallel.hpp"
#include "tools/diagnosis_intervals.hpp"

namespace tools {
namespace {

using fsw::Effect;

std::string finding_name(const Finding& f) {
  return std::string(fsw::effect_info(f.effect).name) + (f.component.empty() ? "" : "." + f.component);
}

/// What a stage applies: its most significant timing/geometry finding, separable, or a group
/// whose most plausible member is a timing/geometry component with plausibility at least
/// kChainMemberPlausibility (the data fit the members alike; the priors rule the others out: a 250
/// ms offset on a coordinated-turn flight is a group with a 60 m lever arm x). The next stage
/// checks the choice: had another member been the cause, the group is found again.
struct Pick {
  const Finding* finding = nullptr;
  std::string name, unit, method;
  double value = 0.0;
  Finding as_found;  ///< the finding as reported when applied (a group: headline the member's)
};

Pick to_apply(const DiagnosisResult& r) {
  Pick p;
  for (const Finding& f : r.findings) {  // most significant first
    // A profile not bounded within the range searched does not determine the value (its maximum
    // can sit at the edge of the range: psins-tc's offset at +0.416 s, the range's end): never
    // applied.
    if (f.interval.is_profile() && !f.interval.bounded) continue;
    if (f.separable()) {
      if (!chain_applicable(f.effect) || !std::isfinite(f.estimate)) continue;
      p.finding = &f;
      p.name = finding_name(f);
      p.unit = f.unit;
      p.method = f.estimate_method;
      p.value = f.estimate;
      p.as_found = f;
      return p;
    }
    const auto best = std::max_element(f.group.begin(), f.group.end(), [](const GroupMember& a, const GroupMember& b) {
      return a.plausibility < b.plausibility;
    });
    if (best == f.group.end() || !(best->plausibility >= kChainMemberPlausibility) || !chain_applicable(best->effect))
      continue;
    if (best->alone_interval.is_profile() && !best->alone_interval.bounded) continue;
    const bool profile = best->alone_interval.is_profile();
    p.finding = &f;
    p.name = best->name;
    p.unit = best->unit;
    p.method = profile ? "profile_maximum" : "filter";
    p.value = profile ? best->alone_interval.estimate : best->alone_estimate;
    if (!std::isfinite(p.value)) continue;
    p.as_found = f;
    p.as_found.effect = best->effect;
    p.as_found.component = best->component;
    p.as_found.unit = best->unit;
    p.as_found.estimate = p.value;
    p.as_found.filter_estimate = best->alone_estimate;
    p.as_found.filter_sigma = best->alone_sigma;
    p.as_found.estimate_method = p.method;
    p.as_found.interval = best->alone_interval;
    p.as_found.sigma = (best->alone_interval.hi - best->alone_interval.lo) / (2.0 * 1.959963984540054);
    return p;
  }
  return p;
}

/// A finding's values shifted by what was applied of its component before the stage that found it.
Finding shifted(Finding f, double before) {
  f.estimate += before;
  f.filter_estimate += before;
  f.interval.lo += before;
  f.interval.hi += before;
  f.interval.estimate += before;
  return f;
}

/// Each run's Gaussian log-likelihood over the measurements (scalar keys) every run used, and how
/// many they are: each key counted once per run, summed in the run's own order.
struct CommonLl {
  double ll = 0.0;
  int measurements = 0;
};
std::vector<CommonLl> common_log_likelihood(const std::vector<const DiagnosisRun*>& runs) {
  std::unordered_map<std::uint64_t, int> count;
  std::unordered_set<std::uint64_t> seen;
  for (const DiagnosisRun* r : runs) {
    seen.clear();
    for (const DiagnosisRun::Scalar& s : r->scalars)
      if (seen.insert(s.key).second) ++count[s.key];
  }
  const int n = static_cast<int>(runs.size());
  std::vector<CommonLl> out(runs.size());
  for (std::size_t i = 0; i < runs.size(); ++i) {
    seen.clear();
    for (const DiagnosisRun::Scalar& s : runs[i]->scalars) {
      if (count[s.key] != n || !seen.insert(s.key).second) continue;
      out[i].ll += -0.5 * (std::log(2.0 * fsw::kPi * s.S) + s.nu * s.nu / s.S);
      ++out[i].measurements;
    }
  }
  return out;
}

/// The baseline runs' log-likelihood over the measurements every stage used.
void chain_log_likelihood(std::vector<ChainStage>& stages, const std::vector<const DiagnosisRun*>& runs) {
  const std::vector<CommonLl> c = common_log_likelihood(runs);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    stages[i].base_log_likelihood = c[i].ll;
    stages[i].common_measurements = c[i].measurements;
  }
}

/// The runs' log-likelihood over the keys every run used (a run that never initialised: -1e300).
std::vector<double> common_ll(const std::vector<DiagnosisRun>& runs) {
  std::vector<const DiagnosisRun*> p;
  for (const DiagnosisRun& r : runs) p.push_back(&r);
  const std::vector<CommonLl> c = common_log_likelihood(p);
  std::vector<double> ll;
  for (std::size_t i = 0; i < runs.size(); ++i) ll.push_back(runs[i].initialised ? c[i].ll : -1e300);
  return ll;
}

}  // namespace

MountingEstimate estimate_mounting_yaw(const RecordedData& data, const DiagnosisConfig& cfg) {
  MountingEstimate m;
  if (cfg.app.init_mode != fsw::InitMode::kTrack) return m;
  m.searched = true;
  DiagnosisConfig k = cfg;
  k.app.exec.ekf.gate_chi2 = std::numeric_limits<double>::max();  // one data set for every value
  k.outage_length_s = 0.0;
  std::vector<double> theta;
  std::vector<DiagnosisRun> runs;
  const auto add = [&](const std::vector<double>& t) {
    std::vector<DiagnosisRun> r(t.size());
    for_each_parallel(t.size(), [&](std::size_t i) {
      DiagnosisConfig c = k;
      c.app.init_heading_offset_rad += t[i] * fsw::kDegToRad;
      r[i] = run_diagnosis_model(data, c, cfg.baseline_states);
      r[i].est_trace.clear();
      r[i].sigma_trace.clear();
    });
    for (std::size_t i = 0; i < t.size(); ++i) {
      theta.push_back(t[i]);
      runs.push_back(std::move(r[i]));
    }
    m.runs += static_cast<int>(t.size());
  };
  const auto best_of = [&]() {
    const std::vector<double> ll = common_ll(runs);
    return static_cast<std::size_t>(std::max_element(ll.begin(), ll.end()) - ll.begin());
  };
  // Screen at 45 deg steps (8 runs); the full search only when a rotated start beats the one
  // configured (a mounting within about 20 deg of it: the filter's heading converges from there).
  std::vector<double> grid;
  for (int d = -180; d < 180; d += 45) grid.push_back(d);
  add(grid);
  bool beaten = false;
  {
    const std::vector<double> ll = common_ll(runs);
    double at0 = -1e300;
    for (std::size_t i = 0; i < theta.size(); ++i)
      if (theta[i] == 0.0) at0 = ll[i];
    for (std::size_t i = 0; i < theta.size(); ++i) beaten = beaten || 2.0 * (ll[i] - at0) > kMountingDeviance;
  }
  if (beaten) {
    grid.clear();
    for (int d = -180; d < 180; d += 15)
      if (d % 45 != 0) grid.push_back(d);
    add(grid);
  }
  for (double step = 7.5; beaten && step >= 0.5; step /= 2.0) {
    const double b = theta[best_of()];
    add({b - step, b + step});
  }
  const std::vector<double> ll = common_ll(runs);
  std::vector<std::size_t> idx(theta.size());
  for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = i;
  std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) { return theta[a] < theta[b]; });
  const double ll_max = *std::max_element(ll.begin(), ll.end());
  for (std::size_t i : idx) {
    m.theta_deg.push_back(theta[i]);
    m.deviance.push_back(2.0 * (ll_max - ll[i]));
  }
  const std::size_t b = best_of();
  m.yaw_deg = theta[b];
  // The parabola through the best point and its nearest neighbours on either side.
  std::size_t lo = b, hi = b;
  for (std::size_t i = 0; i < theta.size(); ++i) {
    if (theta[i] < theta[b] && (lo == b || theta[i] > theta[lo])) lo = i;
    if (theta[i] > theta[b] && (hi == b || theta[i] < theta[hi])) hi = i;
  }
  m.lo_deg = m.hi_deg = m.yaw_deg;
  if (lo != b && hi != b) {
    const double x0 = theta[lo], x1 = theta[b], x2 = theta[hi];
    const double y0 = 2.0 * (ll_max - ll[lo]), y1 = 0.0, y2 = 2.0 * (ll_max - ll[hi]);
    const double den = (x0 - x1) * (x0 - x2) * (x1 - x2);
    const double A = (x2 * (y1 - y0) + x1 * (y0 - y2) + x0 * (y2 - y1)) / den;
    const double B = (x2 * x2 * (y0 - y1) + x1 * x1 * (y2 - y0) + x0 * x0 * (y1 - y2)) / den;
    if (A > 0.0) {
      const double v = std::clamp(-B / (2.0 * A), x0, x2);
      const double C = y1 - A * x1 * x1 - B * x1, y_min = A * v * v + B * v + C;
      const double half = std::sqrt(std::max(0.0, kDeviance95 + y_min) / A);
      m.yaw_deg = v;
      m.lo_deg = v - half;
      m.hi_deg = v + half;
    }
  }
  for (std::size_t i = 0; i < theta.size(); ++i)
    if (theta[i] == 0.0) m.deviance_at_configured = 2.0 * (ll_max - ll[i]);
  m.found = beaten && m.deviance_at_configured > kMountingDeviance && (m.lo_deg > 0.0 || m.hi_deg < 0.0);
  if (!beaten) m.yaw_deg = m.lo_deg = m.hi_deg = 0.0;  // the screen: no rotated start fits better
  return m;
}

bool chain_applicable(Effect e) {
  return e == Effect::kImuGnssTimeOffset || e == Effect::kImuClockDrift || e == Effect::kAntennaLeverArm;
}

double drift_reference_time(const RecordedData& data, const DiagnosisConfig& cfg) {
  double t_ref_s = data.imu.empty() ? 0.0 : data.imu.front().t_s;
  for (const RecordedData::Event& ev : data.order) {
    if (ev.kind == RecordedData::Kind::kGnss && cfg.gnss_source == cfg::GnssSource::kRaw) return data.gnss[ev.index].t_s;
    if (ev.kind == RecordedData::Kind::kPvt && cfg.gnss_source == cfg::GnssSource::kPvt) return data.pvt[ev.index].t_s;
  }
  return t_ref_s;
}

void apply_correction(RecordedData& data, DiagnosisConfig& cfg, int candidate, double value) {
  const Candidate& c = diagnosis_candidates()[static_cast<std::size_t>(candidate)];
  if (c.effect == Effect::kAntennaLeverArm) {
    cfg.app.exec.ekf.lever_arm_b_m(c.component) += value * fsw::effect_info(c.effect).unit_to_si;
    return;
  }
  apply_fixed_effect(data, c, value, drift_reference_time(data, cfg));
}

/// The mounting from the direction of travel, on the recording initialised as the chain will
/// (the profile's yaw applied): a named yaw becomes the track initialisation's heading offset.
static void apply_mounting_from_travel(DiagnosisChain& ch, const RecordedData& data,
                                const std::function<void(const std::string&)>& progress) {
  ch.travel = estimate_mounting_from_travel(data, ch.corrected_cfg);
  if (progress)
    for (const std::string& line : mounting_terminal_lines(ch.travel)) progress(line);
  if (ch.travel.found && ch.travel.track_init && ch.travel.yaw.named)
    ch.corrected_cfg.app.init_heading_offset_rad = ch.travel.yaw.estimate_deg * fsw::kDegToRad;
}

DiagnosisChain diagnose_chain(const RecordedData& data, const DiagnosisConfig& cfg,
                              const std::function<void(const std::string&)>& progress) {
  DiagnosisChain ch;
  const RecordedData* searched = &data;  // the recording as corrected so far (ch.corrected once it is)
  ch.corrected_cfg = cfg;
  std::map<int, double> total;          // per candidate: applied so far
  std::map<int, Finding> last_found;    // per applied candidate: the last stage's finding, shifted
  std::vector<int> applied_order;
  std::vector<DiagnosisResult> results;
  std::set<std::string> ever_found;
  // The mounting first: a track initialisation off by the mounting yaw spoils every search after.
  ch.mounting = estimate_mounting_yaw(data, cfg);
  if (ch.mounting.found) {
    ch.corrected_cfg.app.init_heading_offset_rad += ch.mounting.yaw_deg * fsw::kDegToRad;
    if (progress) {
      char b[200];
      std::snprintf(b, sizeof b, "mounting yaw %.2f deg [%.2f, %.2f] (profile over the track initialisation's heading "
                    "offset, %d runs): applied to init.heading_offset_deg", ch.mounting.yaw_deg, ch.mounting.lo_deg,
                    ch.mounting.hi_deg, ch.mounting.runs);
      progress(b);
    }
  }
  apply_mounting_from_travel(ch, data, progress);
  for (int stage = 1; stage <= kMaxChainStages; ++stage) {
    ChainStage st;
    st.stage = stage;
    st.applied_before = ch.applied;
    const std::string prefix = "chain stage " + std::to_string(stage) + ": ";
    if (progress) {
      std::string what = "the recording as given";
      if (!ch.applied.empty()) {
        what = "after applying";
        char b[128];
        for (const AppliedCorrection& a : ch.applied) {
          std::snprintf(b, sizeof b, " %s %+.5g %s;", a.name.c_str(), a.value, a.unit.c_str());
          what += b;
        }
        what.pop_back();
      }
      progress(prefix + "searching " + what);
    }
    DiagnosisResult r = diagnose(*searched, ch.corrected_cfg, [&](const std::string& m) {
      if (progress) progress(prefix + m);
    });
    st.findings = r.findings;
    st.extended_gain = r.extended.innovations.log_likelihood - r.base.innovations.log_likelihood;
    st.base_nis = r.base.innovations.nis_mean;
    st.extended_nis = r.extended.innovations.nis_mean;
    for (const Finding& f : r.findings) ever_found.insert(finding_name(f));
    const Pick pick = stage < kMaxChainStages ? to_apply(r) : Pick{};
    if (pick.finding) {
      const int cand = candidate_index(pick.name);
      const double before = total.count(cand) ? total[cand] : 0.0;
      AppliedCorrection a;
      a.name = pick.name;
      a.candidate = cand;
      a.value = pick.value;
      a.total = before + pick.value;
      a.unit = pick.unit;
      a.source = pick.method;
      a.stage = stage;
      a.from_group = !pick.finding->separable();
      st.applied_after = a.name;
      last_found[cand] = shifted(pick.as_found, before);
      if (!total.count(cand)) applied_order.push_back(cand);
      total[cand] = a.total;
      ch.applied.push_back(a);
      if (diagnosis_candidates()[static_cast<std::size_t>(cand)].effect != Effect::kAntennaLeverArm &&
          !ch.recording_corrected) {  // the first correction of the data itself: the copy it goes into
        ch.corrected = data;
        ch.recording_corrected = true;
        searched = &ch.corrected;
      }
      apply_correction(ch.corrected, ch.corrected_cfg, cand, pick.value);
    }
    ch.stages.push_back(st);
    results.push_back(std::move(r));
    if (!pick.finding) break;
  }
  ch.first = results.front();
  ch.last = results.back();
  std::vector<const DiagnosisRun*> bases;
  for (const DiagnosisResult& r : results) bases.push_back(&r.base);
  chain_log_likelihood(ch.stages, bases);
  // Reported: the applied components, then the last stage's other findings (a last-stage finding
  // of an applied component is its residual: added to the total).
  for (int cand : applied_order) ch.findings.push_back(last_found[cand]);
  std::set<std::string> reported;
  for (int cand : applied_order) reported.insert(candidate_name(diagnosis_candidates()[static_cast<std::size_t>(cand)]));
  for (const Finding& f : ch.last.findings) {
    const int cand = candidate_index(finding_name(f));
    if (total.count(cand) && f.separable()) {
      for (Finding& g : ch.findings)
        if (finding_name(g) == finding_name(f)) g = shifted(f, total[cand]);
      continue;
    }
    ch.findings.push_back(f);
    reported.insert(finding_name(f));
  }
  for (const std::string& n : ever_found)
    if (!reported.count(n)) ch.vanished.push_back(n);
  return ch;
}

}  // namespace tools
