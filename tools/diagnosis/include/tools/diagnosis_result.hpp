// What a diagnosis reports (`sdins diagnose`, docs/diagnosis.md): findings, their confounded
// groups and 95% intervals. Types only: filled by the search (tools/diagnosis.hpp) and the
// intervals (tools/diagnosis_intervals.hpp).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "fsw/effect_catalogue.hpp"
#include "tools/diagnosis_model.hpp"

namespace tools {

/// A reported 95% interval (catalogue units, docs/diagnosis-intervals.md).
struct ReportedInterval {
  double lo = 0.0, hi = 0.0;
  /// "profile_likelihood" (2 (l_max - l) <= 3.84 over the whole recording) or "filter" (the
  /// filter's estimate +- 1.96 sigma).
  std::string method = "filter";
  double estimate = 0.0;  ///< the profile's maximum (method "filter": the filter's estimate)
  /// false: the likelihood did not fall by 3.84 within the range searched on one side (the
  /// interval is then that range).
  bool bounded = true;
  int runs = 0;  ///< model runs of the profile
  /// Profile intervals: the deviance at the filter's estimate, and whether it is at most
  /// kModelAgreementDeviance (diagnosis_intervals.hpp). false: the filter and the profile disagree,
  /// the model does not describe the component's effect on the data, and the interval is reported
  /// as not calibrated.
  double deviance_at_filter = 0.0;
  bool model_agrees = true;
  bool is_profile() const { return method == "profile_likelihood"; }
};

/// One member of a confounded group (Finding::group).
struct GroupMember {
  std::string name;  ///< "effect.component"
  fsw::Effect effect = fsw::Effect::kCount;
  std::string component;
  std::string unit;
  /// Posterior correlation with the group's lead component in the run where it joined (the lead
  /// itself: 1), and the multiple correlation with the members already in the group then.
  double correlation = 1.0, multiple_correlation = 1.0;
  /// The estimate this member alone would need: the member alone on top of the model as it was
  /// when the group's lead was selected (catalogue units), its sigma and Wald z^2 there.
  double alone_estimate = 0.0, alone_sigma = 0.0, alone_z2 = 0.0;
  double prior_sigma = 0.0;  ///< the member's prior 1-sigma (catalogue units)
  /// alone_estimate / prior_sigma: how many prior sigmas the member alone would need.
  double prior_z = 0.0;
  /// exp(-prior_z^2 / 2) normalised over the group: the members' relative plausibility under their
  /// priors, given that the data fit each alone equally well (prior only: not a probability that
  /// the data establish).
  double plausibility = 0.0;
  /// The 95% interval of the value this member alone would need: the profile likelihood of the
  /// member alone on top of the model at the lead's selection, or alone_estimate +- 1.96
  /// alone_sigma where there is no profile. prior_z and plausibility use the profile's maximum when
  /// there is one and the filter agrees with it.
  ReportedInterval alone_interval;
};

struct Finding {
  fsw::Effect effect;     ///< the lead component (the most significant when it was selected)
  std::string component;  ///< "" for scalar effects
  /// Separable: the extended model's estimate and sigma. A group: the lead's alone_estimate and
  /// alone_sigma (the group's members share the extended model's information and are not told
  /// apart there; every member's own value is in group).
  double estimate = 0.0, sigma = 0.0;  ///< catalogue units
  std::string unit;
  /// Joint Wald statistic of the finding's components in the extended model over the directions
  /// the data observe (dof of them; one for a separable finding: the classic z^2).
  double z2 = 0.0;
  int dof = 1;
  double threshold_z2 = 0.0;  ///< the finding's threshold (chi-square, dof, at alpha / tested)
  double p_value = 0.0;
  /// Components the data cannot tell apart from the lead ("effect.component"), with their
  /// posterior correlation; empty when it is separable.
  std::vector<std::pair<std::string, double>> confounded_with;
  /// The confounded group, lead first: empty when the finding is separable. The finding is the
  /// group, not its lead.
  std::vector<GroupMember> group;
  bool separable() const { return group.empty(); }
  /// The model the lead was selected on (indices into diagnosis_candidates(), the baseline's
  /// included, the lead not): where each group member's "alone" value is measured.
  std::vector<int> selection_model;
  /// The 95% interval (a group: its lead's alone interval).
  ReportedInterval interval;
  /// The forward filter's own figure (extended model; a group: the lead's alone value), kept beside
  /// the headline: where the interval is a profile likelihood, estimate is the profile's maximum
  /// and sigma its half-width / 1.96 (set_headline_estimates, docs/diagnosis-intervals.md).
  double filter_estimate = 0.0, filter_sigma = 0.0;
  /// "profile_maximum" or "filter": where estimate comes from.
  std::string estimate_method = "filter";
};

struct DiagnosisResult {
  std::string baseline = "15";
  double threshold_z2 = 0.0;  ///< per-component threshold (Bonferroni)
  int tested = 0;
  std::vector<std::string> unobservable;  ///< candidates the data are not informative about
  std::vector<std::string> confounded_with_baseline;  ///< "candidate ~ baseline state": explained by the baseline
  std::vector<Finding> findings;          ///< most significant first
  std::vector<std::string> extended_model;  ///< "effect.component" states added to the baseline
  std::vector<double> screening_z2;     ///< per candidate: z^2 in the baseline + that component alone
  std::vector<double> screening_ratio;  ///< per candidate: posterior / prior variance there
  DiagnosisRun base, extended;
};

}  // namespace tools
