#include "tools/diagnosis.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "tools/diagnosis_intervals.hpp"

namespace tools {

using fsw::Effect;

double joint_wald_z2(const Eigen::VectorXd& x, const Eigen::MatrixXd& P, const Eigen::VectorXd& s0, double max_ratio,
                     int& dof) {
  dof = 0;
  const Eigen::Index n = x.size();
  if (n == 0 || P.rows() != n || P.cols() != n || s0.size() != n || !(s0.array() > 0.0).all() || !x.allFinite() ||
      !P.allFinite())
    return 0.0;
  // Scaled by the prior sigmas: Ps = D0^-1 P D0^-1 has eigenvalues mu = posterior / prior variance
  // along its eigenvectors; the null covariance of the scaled estimate is Ps (I - Ps), with
  // eigenvalues mu (1 - mu) along the same vectors.
  const Eigen::VectorXd inv = s0.cwiseInverse();
  const Eigen::MatrixXd Ps = inv.asDiagonal() * (0.5 * (P + P.transpose())) * inv.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Ps);
  if (es.info() != Eigen::Success) return 0.0;
  const Eigen::VectorXd y = inv.cwiseProduct(x);
  double z2 = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {  // eigenvalues ascending: the best-observed direction first
    const double mu = es.eigenvalues()(i);
    if (i > 0 && mu > max_ratio) break;
    if (!(mu > 0.0) || !(mu < 1.0)) continue;
    const double proj = es.eigenvectors().col(i).dot(y);
    z2 += proj * proj / (mu * (1.0 - mu));
    ++dof;
  }
  return z2;
}

// ---------------------------------------------------------------------------------------------
namespace {

/// Runs the models in parallel (one per extension set), results in input order.
std::vector<DiagnosisRun> run_models(const RecordedData& data, const DiagnosisConfig& cfg,
                                 const std::vector<std::vector<int>>& models, bool with_outages = false) {
  std::vector<DiagnosisRun> out(models.size());
  std::atomic<std::size_t> next{0};
  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  const unsigned n_threads = std::min<unsigned>(hw, static_cast<unsigned>(std::max<std::size_t>(1, models.size())));
  auto worker = [&]() {
    for (std::size_t i = next++; i < models.size(); i = next++) out[i] = run_diagnosis_model(data, cfg, models[i], with_outages);
  };
  std::vector<std::thread> threads;
  for (unsigned t = 1; t < n_threads; ++t) threads.emplace_back(worker);
  worker();
  for (std::thread& t : threads) t.join();
  return out;
}

/// Position of candidate c in a run's active list, or -1.
int position(const DiagnosisRun& run, int c) {
  for (std::size_t a = 0; a < run.active.size(); ++a)
    if (run.active[a] == c) return static_cast<int>(a);
  return -1;
}

}  // namespace

namespace {

/// A finding under construction: its lead component and the components the data cannot tell
/// apart from it (Finding::group).
struct Group {
  int lead = -1;
  std::vector<int> members;       ///< lead first
  std::vector<GroupMember> info;  ///< parallel to members
  /// Per candidate: that candidate alone on top of the model as it was when the lead was selected.
  std::vector<double> alone_est, alone_sig, alone_z2;
  std::vector<int> selection_model;  ///< the model the lead was selected on (without the lead)
  double z2 = 0.0;
  int dof = 1;
};

}  // namespace

double multiple_correlation(const Eigen::MatrixXd& R, int a, const std::vector<int>& b) {
  const Eigen::Index k = static_cast<Eigen::Index>(b.size());
  const auto valid = [&R](int i) { return i >= 0 && i < R.rows() && i < R.cols(); };
  if (!valid(a) || !std::all_of(b.begin(), b.end(), valid))
    throw std::logic_error("multiple_correlation: a position outside the correlation matrix");
  if (k == 0) return 0.0;
  Eigen::MatrixXd Rbb(k, k);
  Eigen::VectorXd rab(k);
  for (Eigen::Index i = 0; i < k; ++i) {
    rab(i) = R(a, b[static_cast<std::size_t>(i)]);
    for (Eigen::Index j = 0; j < k; ++j) Rbb(i, j) = R(b[static_cast<std::size_t>(i)], b[static_cast<std::size_t>(j)]);
  }
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod;
  cod.setThreshold(1e-9);
  cod.compute(Rbb);
  const double r2 = rab.dot(cod.solve(rab));
  return std::sqrt(std::clamp(r2, 0.0, 1.0));
}

DiagnosisResult diagnose(const RecordedData& data, const DiagnosisConfig& cfg,
                         const std::function<void(const std::string&)>& progress) {
  const std::vector<Candidate>& cands = diagnosis_candidates();
  const int nc = static_cast<int>(cands.size());
  const auto at = [](int c) { return static_cast<std::size_t>(c); };
  auto say = [&progress](const std::string& s) {
    if (progress) progress(s);
  };
  DiagnosisResult res;
  res.baseline = fsw::to_string(cfg.baseline);
  const std::vector<int>& base = cfg.baseline_states;
  auto in = [](const std::vector<int>& v, int c) { return std::find(v.begin(), v.end(), c) != v.end(); };
  std::vector<Group> groups;
  // The model searched from: the baseline and every member of every finding (a group's whole subspace).
  const auto model = [&]() {
    std::vector<int> m = base;
    for (const Group& g : groups) m.insert(m.end(), g.members.begin(), g.members.end());
    return m;
  };
  const auto member = [&](int c, const Group& g, double rho, double multiple) {
    const Candidate& cand = cands[at(c)];
    const fsw::EffectInfo& info = fsw::effect_info(cand.effect);
    GroupMember gm;
    gm.name = candidate_name(cand);
    gm.effect = cand.effect;
    gm.component = info.n_components > 1 ? info.components[cand.component] : "";
    gm.unit = info.unit;
    gm.correlation = rho;
    gm.multiple_correlation = multiple;
    gm.alone_estimate = g.alone_est[at(c)];
    gm.alone_sigma = g.alone_sig[at(c)];
    gm.alone_z2 = g.alone_z2[at(c)];
    gm.prior_sigma = cfg.prior[static_cast<std::size_t>(cand.effect)];
    return gm;
  };
  std::vector<bool> excluded(at(nc), false);  // unobservable, explained by the baseline, or in a group
  bool screened = false;
  // Each step adds a finding, grows a group (then runs again on the larger subspace) or ends.
  const int max_steps = cfg.max_findings + nc + 1;
  for (int step = 1; step <= max_steps; ++step) {
    const std::vector<int> m0 = model();
    std::vector<std::vector<int>> models;
    std::vector<int> which;
    for (int c = 0; c < nc; ++c) {
      if (excluded[at(c)] || in(m0, c)) continue;
      std::vector<int> m = m0;
      m.push_back(c);
      models.push_back(m);
      which.push_back(c);
    }
    if (models.empty()) break;
    say("step " + std::to_string(step) + ": " + std::to_string(models.size()) + " candidate models of " +
        std::to_string(m0.size() - base.size() + 1) + " extension states");
    std::vector<DiagnosisRun> runs = run_models(data, cfg, models);
    if (!screened) {
      res.screening_z2.assign(at(nc), 0.0);
      res.screening_ratio.assign(at(nc), 1.0);
    }
    std::vector<double> est(at(nc), 0.0), sig(at(nc), 0.0), z2v(at(nc), 0.0);
    int best = -1;
    double best_z2 = 0.0;
    std::string grown;
    for (std::size_t k = 0; k < runs.size(); ++k) {
      const int c = which[k];
      const DiagnosisRun& r = runs[k];
      const int a = position(r, c);
      if (!r.initialised || a < 0) continue;
      const std::size_t ua = static_cast<std::size_t>(a);
      est[at(c)] = r.estimate[ua];
      sig[at(c)] = r.sigma[ua];
      z2v[at(c)] = r.z2[ua];
      const double ratio = r.sigma[ua] * r.sigma[ua] / (r.prior_sigma[ua] * r.prior_sigma[ua]);
      if (!screened) {
        res.screening_z2[at(c)] = r.z2[ua];
        res.screening_ratio[at(c)] = ratio;
        if (ratio > cfg.max_variance_ratio) {
          excluded[at(c)] = true;
          res.unobservable.push_back(candidate_name(cands[at(c)]));
          continue;
        }
        ++res.tested;
      }
      // Explained by a baseline state: named with it, never on its own.
      bool confound = false;
      for (int s : base) {
        const double rho = r.correlation(a, position(r, s));
        if (std::abs(rho) > cfg.max_correlation) {
          res.confounded_with_baseline.push_back(candidate_name(cands[at(c)]) + " ~ " + candidate_name(cands[at(s)]));
          confound = true;
        }
      }
      // Not separable from a finding's subspace: joins that group.
      for (std::size_t gi = 0; !confound && gi < groups.size(); ++gi) {
        Group& g = groups[gi];
        // The members this run carries: one that joined earlier in this step is not in this
        // step's models (m0 + c), and has no row in r.correlation (reading it overran the matrix;
        // found by ASan on a whole diagnosis).
        std::vector<int> pos;
        for (int mbr : g.members)
          if (const int p = position(r, mbr); p >= 0) pos.push_back(p);
        const double R = multiple_correlation(r.correlation, a, pos);
        if (R > cfg.max_correlation) {
          g.info.push_back(member(c, g, r.correlation(a, position(r, g.lead)), R));
          g.members.push_back(c);
          grown += (grown.empty() ? "" : ", ") + candidate_name(cands[at(c)]) + " joins " +
                   candidate_name(cands[at(g.lead)]);
          confound = true;
        }
      }
      if (confound) {
        excluded[at(c)] = true;
        continue;
      }
      if (r.z2[ua] > best_z2) {
        best_z2 = r.z2[ua];
        best = c;
      }
    }
    if (!screened) {
      res.threshold_z2 =
          res.tested > 0 ? chi2_1_upper_quantile(cfg.alpha / static_cast<double>(res.tested)) : INFINITY;
      screened = true;
    }
    if (!grown.empty()) {  // the search continues from the groups' whole subspace
      say("step " + std::to_string(step) + ": not separable: " + grown + "; searching again with the group");
      continue;
    }
    if (best < 0 || !(best_z2 > res.threshold_z2)) {
      say("step " + std::to_string(step) + ": no further significant component");
      break;
    }
    if (static_cast<int>(groups.size()) >= cfg.max_findings) break;
    std::ostringstream s;
    s << "step " << step << ": " << candidate_name(cands[at(best)]) << " z^2 " << best_z2 << " (threshold "
      << res.threshold_z2 << ")";
    say(s.str());
    Group g;
    g.lead = best;
    g.members = {best};
    g.alone_est = est;
    g.alone_sig = sig;
    g.alone_z2 = z2v;
    g.selection_model = m0;
    g.info = {member(best, g, 1.0, 1.0)};
    groups.push_back(g);
  }

  // The extended model: confirmed in one run with every finding, each by its joint statistic.
  const double alpha_each = res.tested > 0 ? cfg.alpha / static_cast<double>(res.tested) : 0.0;
  for (int pass = 0; !groups.empty(); ++pass) {
    say("extended model: baseline + " + std::to_string(groups.size()) + " findings");
    res.extended = run_diagnosis_model(data, cfg, model());
    std::vector<Group> keep;
    for (Group& g : groups) {
      const Eigen::Index k = static_cast<Eigen::Index>(g.members.size());
      Eigen::VectorXd x(k), s0(k);
      Eigen::MatrixXd P(k, k);
      std::vector<int> pos;
      for (int mbr : g.members) pos.push_back(position(res.extended, mbr));
      bool ok = res.extended.initialised;
      for (int p : pos) ok = ok && p >= 0;
      if (!ok) continue;
      for (Eigen::Index i = 0; i < k; ++i) {
        const std::size_t pi = static_cast<std::size_t>(pos[static_cast<std::size_t>(i)]);
        x(i) = res.extended.estimate[pi];
        s0(i) = res.extended.prior_sigma[pi];
        for (Eigen::Index j = 0; j < k; ++j) {
          const std::size_t pj = static_cast<std::size_t>(pos[static_cast<std::size_t>(j)]);
          P(i, j) = res.extended.correlation(static_cast<Eigen::Index>(pi), static_cast<Eigen::Index>(pj)) *
                    res.extended.sigma[pi] * res.extended.sigma[pj];
        }
      }
      g.z2 = joint_wald_z2(x, P, s0, cfg.max_variance_ratio, g.dof);
      if (g.z2 > chi2_upper_quantile(alpha_each, std::max(g.dof, 1))) keep.push_back(g);
    }
    if (keep.size() == groups.size() || pass + 1 >= cfg.max_confirmation_passes) break;
    groups = keep;
  }
  say("baseline model");
  res.base = run_diagnosis_model(data, cfg, base);
  if (groups.empty()) res.extended = res.base;
  compare_likelihood(res.base, res.extended);
  if (cfg.outage_length_s > 0.0) {  // with a reference: the coasting error; always: the re-acquisition NIS
    say("GNSS outages: " + std::to_string(cfg.outage_length_s) + " s every " + std::to_string(cfg.outage_period_s) +
        " s, baseline and extended model coasting");
    std::vector<DiagnosisRun> o = run_models(data, cfg, {base, res.extended.active}, true);
    res.base.outages = o[0].outages;
    res.extended.outages = o[1].outages;
  }

  for (Group& g : groups) {
    const int a = position(res.extended, g.lead);
    if (a < 0) continue;
    const std::size_t ua = static_cast<std::size_t>(a);
    const Candidate& cand = cands[at(g.lead)];
    const fsw::EffectInfo& info = fsw::effect_info(cand.effect);
    Finding f;
    f.effect = cand.effect;
    f.component = info.n_components > 1 ? info.components[cand.component] : "";
    f.unit = info.unit;
    f.z2 = g.z2;
    f.dof = std::max(g.dof, 1);
    f.threshold_z2 = chi2_upper_quantile(alpha_each, f.dof);
    f.p_value = chi2_survival(f.z2, f.dof);
    f.selection_model = g.selection_model;
    if (g.members.size() == 1) {
      f.estimate = res.extended.estimate[ua];
      f.sigma = res.extended.sigma[ua];
    } else {
      f.estimate = g.info.front().alone_estimate;
      f.sigma = g.info.front().alone_sigma;
      f.group = g.info;
      for (std::size_t i = 1; i < g.info.size(); ++i) f.confounded_with.emplace_back(g.info[i].name, g.info[i].correlation);
    }
    f.filter_estimate = f.estimate;
    f.filter_sigma = f.sigma;
    res.findings.push_back(f);
    for (int mbr : g.members) res.extended_model.push_back(candidate_name(cands[at(mbr)]));
  }
  std::sort(res.findings.begin(), res.findings.end(), [](const Finding& x, const Finding& y) { return x.z2 > y.z2; });
  add_finding_intervals(res, data, cfg, progress);
  set_headline_estimates(res.findings);
  return res;
}

}  // namespace tools
