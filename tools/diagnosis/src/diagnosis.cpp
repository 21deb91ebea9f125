#include "tools/diagnosis.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "tools/parallel.hpp"
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

/// One model run: its active candidates, with or without the GNSS outages.
struct ModelJob {
  std::vector<int> model;
  bool outages = false;
};

/// Runs the jobs in parallel, results in input order.
std::vector<DiagnosisRun> run_jobs(const RecordedData& data, const DiagnosisConfig& cfg, const std::vector<ModelJob>& jobs) {
  std::vector<DiagnosisRun> out(jobs.size());
  for_each_parallel(jobs.size(), [&](std::size_t i) { out[i] = run_diagnosis_model(data, cfg, jobs[i].model, jobs[i].outages); });
  return out;
}

/// The baseline model's runs, which depend on nothing the search finds: the baseline itself and,
/// with outages configured, the baseline coasting through them. They are run as spares in a
/// search step with an odd number of candidates, in the slot that would leave a core idle while
/// the step's last run finishes (same runs, same results; only when they run changes).
struct BaselineSpares {
  std::optional<DiagnosisRun> base, base_outages;
  /// The baseline's runs not yet made, first the plain one.
  std::vector<ModelJob> missing(const DiagnosisConfig& cfg) const {
    std::vector<ModelJob> m;
    if (!base) m.push_back({cfg.baseline_states, false});
    if (cfg.outage_length_s > 0.0 && !base_outages) m.push_back({cfg.baseline_states, true});
    return m;
  }
  void store(DiagnosisRun run, bool with_outages) { (with_outages ? base_outages : base) = std::move(run); }
};

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

namespace {

using Progress = std::function<void(const std::string&)>;

std::size_t at(int c) { return static_cast<std::size_t>(c); }

/// The model searched from: the baseline and every member of every finding (a group's whole subspace).
std::vector<int> search_model(const std::vector<int>& base, const std::vector<Group>& groups) {
  std::vector<int> m = base;
  for (const Group& g : groups) m.insert(m.end(), g.members.begin(), g.members.end());
  return m;
}

/// One step's results for the candidates run on top of the model.
struct StepScores {
  std::vector<double> est, sig, z2v;  ///< per candidate: alone on top of the model
  int best = -1;                      ///< the strongest candidate that joined no group
  double best_z2 = 0.0;
  std::string grown;                  ///< the candidates that joined a group in this step
};

/// The stepwise search of diagnose(): each step runs every candidate not yet in the model on top of
/// it; the first step screens them (unobservable ones are left out and the threshold is set); a
/// candidate explained by a baseline state or not separable from a finding's subspace is excluded
/// (joining that group); otherwise the strongest significant candidate becomes a new finding.
class GroupSearch {
 public:
  /// refs: every run's profile reference is kept there (a group member's interval starts from it).
  /// spares: the baseline runs, run in a step's idle slot (BaselineSpares).
  GroupSearch(const RecordedData& data, const DiagnosisConfig& cfg, DiagnosisResult& res, const Progress& say,
              ProfileReferences& refs, BaselineSpares& spares)
      : data_(data), cfg_(cfg), res_(res), say_(say), refs_(refs), spares_(spares), cands_(diagnosis_candidates()),
        nc_(static_cast<int>(cands_.size())), excluded_(at(nc_), false) {}

  /// Each step adds a finding, grows a group (then runs again on the larger subspace) or ends.
  std::vector<Group> run() {
    const int max_steps = cfg_.max_findings + nc_ + 1;
    for (int step = 1; step <= max_steps; ++step)
      if (!run_step(step)) break;
    return groups_;
  }

 private:
  /// One step; false when the search ends.
  bool run_step(int step) {
    const std::vector<int>& base = cfg_.baseline_states;
    const std::vector<int> m0 = search_model(base, groups_);
    std::vector<std::vector<int>> models;
    std::vector<int> which;
    for (int c = 0; c < nc_; ++c) {
      if (excluded_[at(c)] || std::find(m0.begin(), m0.end(), c) != m0.end()) continue;
      std::vector<int> m = m0;
      m.push_back(c);
      models.push_back(m);
      which.push_back(c);
    }
    if (models.empty()) return false;
    say_("step " + std::to_string(step) + ": " + std::to_string(models.size()) + " candidate models of " +
         std::to_string(m0.size() - base.size() + 1) + " extension states");
    std::vector<DiagnosisRun> runs = run_step_models(std::move(models));
    for (std::size_t k = 0; k < runs.size(); ++k) refs_[runs[k].active] = ProfileReference::of(runs[k]);
    if (!screened_) {
      res_.screening_z2.assign(at(nc_), 0.0);
      res_.screening_ratio.assign(at(nc_), 1.0);
    }
    StepScores sc;
    sc.est.assign(at(nc_), 0.0);
    sc.sig.assign(at(nc_), 0.0);
    sc.z2v.assign(at(nc_), 0.0);
    for (std::size_t k = 0; k < runs.size(); ++k) score_candidate(which[k], runs[k], sc);
    if (!screened_) {
      res_.threshold_z2 =
          res_.tested > 0 ? chi2_1_upper_quantile(cfg_.alpha / static_cast<double>(res_.tested)) : INFINITY;
      screened_ = true;
    }
    if (!sc.grown.empty()) {  // the search continues from the groups' whole subspace
      say_("step " + std::to_string(step) + ": not separable: " + sc.grown + "; searching again with the group");
      return true;
    }
    if (sc.best < 0 || !(sc.best_z2 > res_.threshold_z2)) {
      say_("step " + std::to_string(step) + ": no further significant component");
      return false;
    }
    if (static_cast<int>(groups_.size()) >= cfg_.max_findings) return false;
    std::ostringstream s;
    s << "step " << step << ": " << candidate_name(cands_[at(sc.best)]) << " z^2 " << sc.best_z2 << " (threshold "
      << res_.threshold_z2 << ")";
    say_(s.str());
    Group g;
    g.lead = sc.best;
    g.members = {sc.best};
    g.alone_est = sc.est;
    g.alone_sig = sc.sig;
    g.alone_z2 = sc.z2v;
    g.selection_model = m0;
    g.info = {member(sc.best, g, 1.0, 1.0)};
    groups_.push_back(g);
    return true;
  }

  /// The step's models in parallel, results in their order; with an odd count and a baseline
  /// spare left (BaselineSpares), that spare takes the slot a core would idle in.
  std::vector<DiagnosisRun> run_step_models(std::vector<std::vector<int>> models) {
    std::vector<ModelJob> jobs;
    for (std::vector<int>& m : models) jobs.push_back({std::move(m), false});
    const std::vector<ModelJob> missing = spares_.missing(cfg_);
    const bool spare = jobs.size() % 2 == 1 && !missing.empty();
    if (spare) jobs.push_back(missing.front());
    std::vector<DiagnosisRun> out = run_jobs(data_, cfg_, jobs);
    if (spare) {
      spares_.store(std::move(out.back()), jobs.back().outages);
      out.pop_back();
    }
    return out;
  }

  /// Candidate c's run on top of the model: screened (first step), excluded when explained by a
  /// baseline state or when it joins a group, else a contender for the step's best.
  void score_candidate(int c, const DiagnosisRun& r, StepScores& sc) {
    const int a = position(r, c);
    if (!r.initialised || a < 0) return;
    const std::size_t ua = static_cast<std::size_t>(a);
    sc.est[at(c)] = r.estimate[ua];
    sc.sig[at(c)] = r.sigma[ua];
    sc.z2v[at(c)] = r.z2[ua];
    const double ratio = r.sigma[ua] * r.sigma[ua] / (r.prior_sigma[ua] * r.prior_sigma[ua]);
    if (!screened_) {
      res_.screening_z2[at(c)] = r.z2[ua];
      res_.screening_ratio[at(c)] = ratio;
      if (ratio > cfg_.max_variance_ratio) {
        excluded_[at(c)] = true;
        res_.unobservable.push_back(candidate_name(cands_[at(c)]));
        return;
      }
      ++res_.tested;
    }
    // Explained by a baseline state: named with it, never on its own.
    bool confound = false;
    for (int s : cfg_.baseline_states) {
      const double rho = r.correlation(a, position(r, s));
      if (std::abs(rho) > cfg_.max_correlation) {
        res_.confounded_with_baseline.push_back(candidate_name(cands_[at(c)]) + " ~ " + candidate_name(cands_[at(s)]));
        confound = true;
      }
    }
    // Not separable from a finding's subspace: joins that group.
    for (std::size_t gi = 0; !confound && gi < groups_.size(); ++gi) {
      Group& g = groups_[gi];
      // The members this run carries: one that joined earlier in this step is not in this
      // step's models (m0 + c), and has no row in r.correlation (reading it overran the matrix;
      // found by ASan on a whole diagnosis).
      std::vector<int> pos;
      for (int mbr : g.members)
        if (const int p = position(r, mbr); p >= 0) pos.push_back(p);
      const double R = multiple_correlation(r.correlation, a, pos);
      if (R > cfg_.max_correlation) {
        g.info.push_back(member(c, g, r.correlation(a, position(r, g.lead)), R));
        g.members.push_back(c);
        sc.grown += (sc.grown.empty() ? "" : ", ") + candidate_name(cands_[at(c)]) + " joins " +
                    candidate_name(cands_[at(g.lead)]);
        confound = true;
      }
    }
    if (confound) {
      excluded_[at(c)] = true;
      return;
    }
    if (r.z2[ua] > sc.best_z2) {
      sc.best_z2 = r.z2[ua];
      sc.best = c;
    }
  }

  GroupMember member(int c, const Group& g, double rho, double multiple) const {
    const Candidate& cand = cands_[at(c)];
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
    gm.prior_sigma = cfg_.prior[static_cast<std::size_t>(cand.effect)];
    return gm;
  }

  const RecordedData& data_;
  const DiagnosisConfig& cfg_;
  DiagnosisResult& res_;
  const Progress& say_;
  ProfileReferences& refs_;
  BaselineSpares& spares_;
  const std::vector<Candidate>& cands_;
  const int nc_;
  std::vector<bool> excluded_;  ///< unobservable, explained by the baseline, or in a group
  bool screened_ = false;
  std::vector<Group> groups_;
};

/// A group's joint Wald statistic in the extended run (g.z2, g.dof); false when the run lacks a member.
bool joint_statistic(const DiagnosisRun& ext, const DiagnosisConfig& cfg, Group& g) {
  const Eigen::Index k = static_cast<Eigen::Index>(g.members.size());
  Eigen::VectorXd x(k), s0(k);
  Eigen::MatrixXd P(k, k);
  std::vector<int> pos;
  for (int mbr : g.members) pos.push_back(position(ext, mbr));
  bool ok = ext.initialised;
  for (int p : pos) ok = ok && p >= 0;
  if (!ok) return false;
  for (Eigen::Index i = 0; i < k; ++i) {
    const std::size_t pi = static_cast<std::size_t>(pos[static_cast<std::size_t>(i)]);
    x(i) = ext.estimate[pi];
    s0(i) = ext.prior_sigma[pi];
    for (Eigen::Index j = 0; j < k; ++j) {
      const std::size_t pj = static_cast<std::size_t>(pos[static_cast<std::size_t>(j)]);
      P(i, j) = ext.correlation(static_cast<Eigen::Index>(pi), static_cast<Eigen::Index>(pj)) *
                ext.sigma[pi] * ext.sigma[pj];
    }
  }
  g.z2 = joint_wald_z2(x, P, s0, cfg.max_variance_ratio, g.dof);
  return true;
}

/// The extended model: confirmed in one run with every finding, each by its joint statistic; the
/// findings below their threshold are dropped and the rest run again (at most
/// cfg.max_confirmation_passes times).
/// The first pass runs beside it whatever of the baseline's runs the search left (into spares) and,
/// with outages configured, the extended model coasting through them (into ext_outages: valid
/// while no finding is dropped).
/// Each extended run's profile reference goes into refs.
void confirm_groups(const RecordedData& data, const DiagnosisConfig& cfg, double alpha_each, std::vector<Group>& groups,
                    DiagnosisResult& res, BaselineSpares& spares, std::optional<DiagnosisRun>& ext_outages,
                    ProfileReferences& refs, const Progress& say) {
  for (int pass = 0; !groups.empty(); ++pass) {
    say("extended model: baseline + " + std::to_string(groups.size()) + " findings");
    const std::vector<int> model = search_model(cfg.baseline_states, groups);
    if (pass == 0) {
      // The extended run, its outage run, and the baseline's runs not yet made, in that order.
      const bool outages = cfg.outage_length_s > 0.0;
      std::vector<ModelJob> jobs = {{model, false}};
      if (outages) jobs.push_back({model, true});
      const std::size_t first_spare = jobs.size();
      for (ModelJob& j : spares.missing(cfg)) jobs.push_back(std::move(j));
      std::vector<DiagnosisRun> runs = run_jobs(data, cfg, jobs);
      res.extended = std::move(runs[0]);
      if (outages) ext_outages = std::move(runs[1]);
      for (std::size_t k = first_spare; k < jobs.size(); ++k) spares.store(std::move(runs[k]), jobs[k].outages);
    } else {
      res.extended = run_diagnosis_model(data, cfg, model);
      ext_outages.reset();  // of a model with the dropped findings
    }
    refs[res.extended.active] = ProfileReference::of(res.extended);
    std::vector<Group> keep;
    for (Group& g : groups) {
      if (!joint_statistic(res.extended, cfg, g)) continue;
      if (g.z2 > chi2_upper_quantile(alpha_each, std::max(g.dof, 1))) keep.push_back(g);
    }
    if (keep.size() == groups.size() || pass + 1 >= cfg.max_confirmation_passes) break;
    groups = keep;
  }
}

/// The baseline's run, the likelihoods on common measurements, and both models coasting through
/// the GNSS outages (the runs already made are taken from spares and ext_outages; with no
/// findings the extended model is the baseline and coasts once).
void score_baseline_and_outages(const RecordedData& data, const DiagnosisConfig& cfg, bool no_findings,
                                BaselineSpares& spares, std::optional<DiagnosisRun>& ext_outages, DiagnosisResult& res,
                                const Progress& say) {
  const std::vector<int>& base = cfg.baseline_states;
  say("baseline model");
  res.base = spares.base ? std::move(*spares.base) : run_diagnosis_model(data, cfg, base);
  if (no_findings) res.extended = res.base;
  compare_likelihood(res.base, res.extended);
  if (cfg.outage_length_s > 0.0) {  // with a reference: the coasting error; always: the re-acquisition NIS
    say("GNSS outages: " + std::to_string(cfg.outage_length_s) + " s every " + std::to_string(cfg.outage_period_s) +
        " s, baseline and extended model coasting");
    const bool ext_is_base = no_findings || res.extended.active == base;
    if (ext_is_base) ext_outages.reset();
    std::vector<ModelJob> jobs;
    if (!spares.base_outages) jobs.push_back({base, true});
    if (!ext_outages && !ext_is_base) jobs.push_back({res.extended.active, true});
    std::vector<DiagnosisRun> o = run_jobs(data, cfg, jobs);
    for (std::size_t k = 0; k < jobs.size(); ++k) {
      if (jobs[k].model == base) spares.base_outages = std::move(o[k]);
      else ext_outages = std::move(o[k]);
    }
    res.base.outages = spares.base_outages->outages;
    res.extended.outages = ext_outages ? ext_outages->outages : res.base.outages;
  }
}

/// The findings of the confirmed groups, strongest first.
void findings_from_groups(const std::vector<Group>& groups, double alpha_each, DiagnosisResult& res) {
  const std::vector<Candidate>& cands = diagnosis_candidates();
  for (const Group& g : groups) {
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
}

}  // namespace

DiagnosisResult diagnose(const RecordedData& data, const DiagnosisConfig& cfg,
                         const std::function<void(const std::string&)>& progress) {
  const Progress say = [&progress](const std::string& s) {
    if (progress) progress(s);
  };
  DiagnosisResult res;
  res.baseline = fsw::to_string(cfg.baseline);
  ProfileReferences refs;  // the runs' data selections, for the intervals' profiles
  BaselineSpares spares;
  std::vector<Group> groups = GroupSearch(data, cfg, res, say, refs, spares).run();
  const double alpha_each = res.tested > 0 ? cfg.alpha / static_cast<double>(res.tested) : 0.0;
  std::optional<DiagnosisRun> ext_outages;
  confirm_groups(data, cfg, alpha_each, groups, res, spares, ext_outages, refs, say);
  score_baseline_and_outages(data, cfg, groups.empty(), spares, ext_outages, res, say);
  findings_from_groups(groups, alpha_each, res);
  add_finding_intervals(res, data, cfg, progress, refs);
  set_headline_estimates(res.findings);
  return res;
}

}  // namespace tools
