// Diagnosis of measured data: which error the navigation model is missing, how large it is, and
// how much better navigation gets once the model includes it (`sdins diagnose`).
//
// METHOD (docs/diagnosis.md)
//   The candidates are the components of the effect catalogue (fsw/effect_catalogue.hpp): every
//   component is one state of the diagnosis model fsw::LayoutDiag, switched on by giving it a
//   prior sigma (DiagnosisConfig::prior) and off by freezing it at zero.
//   The test: for a random-constant state with prior variance p0 and posterior variance p, the
//   estimate under the null hypothesis (the effect is absent) is zero-mean with variance
//   (p0 - p) p / p0 in a linear-Gaussian model, so the Wald statistic
//   z^2 = x_hat^2 p0 / ((p0 - p) p) is chi-square with one degree of freedom.
//   1. Screening (forward selection, round 1): the baseline extended by each component alone.
//      A component is tested only if the data are informative about it (p <= max_variance_ratio
//      p0); the others are reported as unobservable with this data, never named. The threshold is
//      the upper chi-square(1) quantile at alpha / (number of tested components): a family-wise
//      false-alarm rate alpha per diagnosis (Bonferroni).
//   2. The most significant component above the threshold joins the model; the next round tries
//      each remaining component on top of it, until none is significant (max_findings rounds). A
//      component whose posterior correlation with one already in the model exceeds
//      max_correlation cannot be told apart from it with this data. Such a component joins that
//      finding's GROUP (the multiple correlation with the group's members is what counts), its
//      state joins the model, and the round is run again on the group's whole subspace before any
//      further component is tried: no later step builds on an arbitrary member. The finding is the
//      group: every member with the estimate it alone would need and its plausibility under its
//      prior (GroupMember), never one member as the cause.
//   3. The extended model (all selected components and groups) is run once more and the test
//      repeated there, per finding, with the joint Wald statistic of its components over the
//      directions the data observe (joint_wald_z2; for a separable finding the z^2 above).
//   4. Gain: baseline and extended model over the same data: innovation statistics (NIS,
//      innovation RMS per measurement type, log-likelihood over the measurements both used) and,
//      where the data carry truth or a reference trajectory, navigation error RMS and the error
//      after repeated GNSS outages (coasting).
//   Truth is never used in steps 1 to 3.
//
// LAYERS (includes point one way, downwards): tools/diagnosis_model.hpp (the recording, the
// candidates, the configuration, one model run) <- tools/diagnosis_result.hpp (what is reported)
// <- tools/diagnosis_intervals.hpp (the 95% intervals) <- this header and diagnosis.cpp (the
// search); the chain, the evidence and the separation are built on top.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "fsw/chi_square.hpp"
#include "tools/diagnosis_model.hpp"
#include "tools/diagnosis_result.hpp"

namespace tools {

/// The whole diagnosis. progress (optional) receives one line per step.
DiagnosisResult diagnose(const RecordedData& data, const DiagnosisConfig& cfg,
                         const std::function<void(const std::string&)>& progress = {});

/// Multiple correlation of active position a with the active positions b (posterior correlation
/// matrix R): how much of a the members b explain together. A group's members are nearly
/// collinear, so their block is inverted by a rank-revealing decomposition.
double multiple_correlation(const Eigen::MatrixXd& R, int a, const std::vector<int>& b);

/// Joint Wald statistic of random-constant states (catalogue units) whose estimate x, posterior
/// covariance P and prior sigmas s0 are given: under the null (all zero) x has covariance
/// P - P P0^-1 P; only directions whose posterior/prior variance ratio is at most max_ratio count
/// (at least the best-observed one). Returns z^2 and sets dof to the number of directions.
double joint_wald_z2(const Eigen::VectorXd& x, const Eigen::MatrixXd& P, const Eigen::VectorXd& s0, double max_ratio,
                     int& dof);
/// Chi-square: the one definition in fsw/chi_square.hpp.
using fsw::chi2_1_survival;
using fsw::chi2_1_upper_quantile;
using fsw::chi2_survival;
using fsw::chi2_upper_quantile;

}  // namespace tools
