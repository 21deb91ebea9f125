// Intervals of the diagnosis' findings that cover the truth at their stated rate (issue 18, part 1;
// docs/diagnosis-intervals.md).
//
// The forward filter's sigma of a random-constant effect is the posterior of a linear-Gaussian
// model: it holds only where the model holds. The interval here is the PROFILE LIKELIHOOD over the
// whole recording: the selected model is run again with the finding's component held fixed at a
// value theta (its state frozen, the effect applied to the data or the model exactly: the IMU
// compensation of that component applied to the increments, the IMU time re-scaled or shifted, the
// lever arm set), every other state estimated as before, and the Gaussian log-likelihood of the
// innovations l(theta) summed over the measurements every run used. The 95% interval is
// {theta : 2 (l_max - l(theta)) <= 3.84} (chi-square, 1 dof), the estimate its maximum.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "tools/diagnosis_model.hpp"
#include "tools/diagnosis_result.hpp"

namespace tools {

/// The profile-likelihood interval of one component (catalogue units).
struct ProfileInterval {
  /// false: the component cannot be held fixed this way (delay scales), or the runs at different
  /// values share fewer than half the reference run's measurements (no likelihood to compare)
  bool available = false;
  double estimate = 0.0;    ///< the maximum of the profile likelihood
  double lo = 0.0, hi = 0.0;
  bool lo_bounded = false, hi_bounded = false;  ///< the deviance crossed 3.84 inside the grid searched
  int runs = 0;             ///< model runs spent
  int measurements = 0;     ///< scalar measurements common to every run (the likelihood's support)
  int gated = 0;            ///< observations the gate rejected at the estimate, left out of every run
  /// Runs left out: their flight software used fewer than kProfileMinShare of the measurements of
  /// the run at the filter's estimate (no likelihood of the same data); the search stops there.
  int incomparable = 0;
  std::vector<double> theta, deviance;  ///< the curve: 2 (l_max - l(theta)), sorted by theta
  /// The deviance at the filter's estimate x (a point of the curve). Where the model describes the
  /// data, the forward filter and the profile estimate the same thing and x lies near the maximum
  /// (a deviance of order 1). A deviance above kModelAgreementDeviance says they disagree: the
  /// model does not describe this component's effect on these data (an unmodelled effect, a wrong
  /// noise model), and the interval, which assumes it does, is not a calibrated statement.
  double deviance_at_filter = 0.0;
  bool model_agrees() const;
};

/// chi-square(1) at p = 0.001: the deviance at the filter's estimate above which the filter and the
/// profile likelihood disagree about a component (ProfileInterval::deviance_at_filter).
inline constexpr double kModelAgreementDeviance = 10.827566170662733;
inline bool ProfileInterval::model_agrees() const { return deviance_at_filter <= kModelAgreementDeviance; }

/// The profile likelihood compares the runs from this long after the latest initialisation among
/// them. When the flight software initialises depends on the data a run sees: re-timed IMU data put
/// a different number of samples before the first GNSS epoch, and the levelling count it needs can
/// then move the initialisation by an epoch. The runs' first updates after it are dominated by the
/// initial covariance (measured: an initialisation 1 s later cost the first common update 59 units
/// of deviance, a step in l(theta) at the truth that pushed the time-offset profile 2-4 ms off for
/// positive offsets); 10 s later the difference was below 0.5.
inline constexpr double kProfileBurnIn_s = 10.0;

/// A profile run counts only if its flight software used at least this share of the measurements
/// the run at the filter's estimate used (ProfileInterval::incomparable).
inline constexpr double kProfileMinShare = 0.9;

/// The filter's interval, x +- 1.96 s.
ReportedInterval filter_interval(double x, double s);
/// A profile interval as reported.
ReportedInterval reported_interval(const ProfileInterval& pi);

/// True when a component can be held fixed at a value (every effect except the delay scales).
bool profile_supported(fsw::Effect e);

/// Applies a component of an IMU or timing effect to the data in place as a known correction (catalogue
/// units): what the flight software would see with that component calibrated out. t_ref_s: the
/// reference time of the clock drift (IMU time; the offset at t_ref is unchanged).
void apply_fixed_effect(RecordedData& data, const Candidate& c, double value, double t_ref_s);
/// The same correction as samples pass (RecordingView::imu): false when c is not an IMU or timing
/// effect (nothing to apply to the samples).
bool fixed_effect_correction(const Candidate& c, double value, double t_ref_s, ImuCorrection& out);
/// The arrival order of v's inputs on the clock that k corrects (apply_fixed_effect's order).
RecordedData::Order retimed_order(const RecordingView& v, const ImuCorrection& k);

/// The deviance that bounds a 95% interval: the chi-square quantile of 1 degree of freedom.
inline constexpr double kDeviance95 = 3.841458820694124;

/// What a profile takes from the run of its model with the component estimated (its reference
/// run, on the same data and configuration, without outages): the observations that run's gate
/// rejected (the data selection the profile holds fixed) and how many scalars it used.
struct ProfileReference {
  std::vector<std::pair<std::uint64_t, std::uint8_t>> gated;
  std::size_t scalars = 0;
  static ProfileReference of(const DiagnosisRun& r) { return {r.gated, r.scalars.size()}; }
};
/// The references of the runs a diagnosis has already made, by model (its active candidates, in
/// order): a profile of one of these models does not run it again.
using ProfileReferences = std::map<std::vector<int>, ProfileReference>;

/// The profile-likelihood interval of candidate `cand` in `model` (indices into
/// diagnosis_candidates(); cand must be in model), started from the filter's estimate x and sigma
/// s (catalogue units). level_z2: the deviance that bounds the interval (3.84 for 95%). ref: the
/// model's reference run when it has been made already (nullptr: it is run here).
ProfileInterval profile_interval(const RecordedData& data, const DiagnosisConfig& cfg, const std::vector<int>& model,
                                 int cand, double x, double s, double level_z2 = kDeviance95,
                                 const ProfileReference* ref = nullptr);

/// A component's interval on top of a model whether or not it is a finding (`sdins diagnose
/// --profile`): the model plus cand run once for the filter's estimate and sigma (returned in
/// filter_x, filter_s), then the profile likelihood from there. Returns an unavailable interval
/// when the model run does not initialise.
ProfileInterval profile_component(const RecordedData& data, const DiagnosisConfig& cfg, std::vector<int> model,
                                  int cand, double& filter_x, double& filter_s);

/// The candidate index of "effect.component" (or a scalar effect's name); -1 when unknown.
int candidate_index(const std::string& name);

/// Sets every finding's 95% interval: the filter's own (estimate +- 1.96 sigma), replaced for a
/// separable finding by the profile-likelihood interval in the extended model (res.extended.active)
/// when cfg.profile_intervals. Called by diagnose(); progress as there.
/// known: the references of the runs already made on this data and cfg (diagnose()'s search).
void add_finding_intervals(DiagnosisResult& res, const RecordedData& data, const DiagnosisConfig& cfg,
                           const std::function<void(const std::string&)>& progress = {},
                           const ProfileReferences& known = {});

/// Sets each member's prior_z (from its profile maximum where the member's interval is a profile
/// the filter agrees with, else from alone_estimate) and the group's plausibilities.
void set_group_plausibility(std::vector<GroupMember>& group);

/// The headline of every finding: the profile likelihood's maximum (and half-width / 1.96 as its
/// sigma) whenever the finding's interval is a profile, the filter's estimate and sigma otherwise;
/// the filter's figure stays in filter_estimate / filter_sigma. Called by diagnose() once the
/// intervals are set. (The drive's drift headline was the filter's 161.5 ppm above a profile
/// interval of [205.7, 277.3]: a user reads the first number.)
void set_headline_estimates(std::vector<Finding>& findings);

}  // namespace tools
