#include "tools/diagnosis_chain.hpp"

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <map>
#include <set>

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

/// The baseline runs' log-likelihood over the measurements every stage used.
void chain_log_likelihood(std::vector<ChainStage>& stages, const std::vector<const DiagnosisRun*>& runs) {
  std::map<std::uint64_t, int> count;
  for (const DiagnosisRun* r : runs) {
    std::set<std::uint64_t> keys;
    for (const DiagnosisRun::Scalar& s : r->scalars) keys.insert(s.key);
    for (std::uint64_t k : keys) ++count[k];
  }
  const int n = static_cast<int>(runs.size());
  for (std::size_t i = 0; i < runs.size(); ++i) {
    double ll = 0.0;
    int m = 0;
    std::set<std::uint64_t> seen;
    for (const DiagnosisRun::Scalar& s : runs[i]->scalars) {
      if (count[s.key] != n || !seen.insert(s.key).second) continue;
      ll += -0.5 * (std::log(2.0 * fsw::kPi * s.S) + s.nu * s.nu / s.S);
      ++m;
    }
    stages[i].base_log_likelihood = ll;
    stages[i].common_measurements = m;
  }
}

}  // namespace

bool chain_applicable(Effect e) {
  return e == Effect::kImuGnssTimeOffset || e == Effect::kImuClockDrift || e == Effect::kAntennaLeverArm;
}

double drift_reference_time(const RecordedData& data, const DiagnosisConfig& cfg) {
  double t_ref_s = data.imu.empty() ? 0.0 : data.imu.front().t_s;
  for (const RecordedData::Event& ev : data.order) {
    if (ev.kind == RecordedData::Kind::kGnss && cfg.gnss_source == sim::GnssSource::kRaw) return data.gnss[ev.index].t_s;
    if (ev.kind == RecordedData::Kind::kPvt && cfg.gnss_source == sim::GnssSource::kPvt) return data.pvt[ev.index].t_s;
  }
  return t_ref_s;
}

void apply_correction(RecordedData& data, DiagnosisConfig& cfg, int candidate, double value) {
  const Candidate& c = diagnosis_candidates()[static_cast<std::size_t>(candidate)];
  if (c.effect == Effect::kAntennaLeverArm) {
    cfg.app.exec.ekf.lever_arm_b_m(c.component) += value * fsw::effect_info(c.effect).unit_to_si;
    return;
  }
  data = with_fixed_effect(data, c, value, drift_reference_time(data, cfg));
}

DiagnosisChain diagnose_chain(const RecordedData& data, const DiagnosisConfig& cfg,
                              const std::function<void(const std::string&)>& progress) {
  DiagnosisChain ch;
  ch.corrected = data;
  ch.corrected_cfg = cfg;
  std::map<int, double> total;          // per candidate: applied so far
  std::map<int, Finding> last_found;    // per applied candidate: the last stage's finding, shifted
  std::vector<int> applied_order;
  std::vector<DiagnosisResult> results;
  std::set<std::string> ever_found;
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
    DiagnosisResult r = diagnose(ch.corrected, ch.corrected_cfg, [&](const std::string& m) {
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
