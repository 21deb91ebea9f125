// The manoeuvre that separates a confounded group (issue 18, part 3; docs/diagnosis-separation.md).
//
// METHOD
//   For a finding that is a group (Finding::group: components the flight cannot tell apart), the
//   candidates are short sequences of scenario segments appended to the flown flight: a wings-level
//   speed change, a pull-up and push-over, a roll without turning, turns at half the bank, turns at
//   half the speed, a full turn the other way, a crab both ways (the nose off the track)
//   (separation_candidates()). Each is judged by the diagnosis model itself: the
//   flown scenario with the candidate appended (sim::append_segments) is simulated and the extended
//   model (the baseline and every finding's members: DiagnosisResult::extended.active) is run over
//   it (run_diagnosis_model). Its posterior covariance at the end is the prediction: the covariance
//   of a Kalman filter depends on the trajectory and the measurement geometry, not on the measured
//   values, so the simulated flight predicts what the next flight would give. The group's
//   correlation is the largest multiple correlation of a member with the other members (for a pair
//   |rho|): the criterion by which members joined the group (DiagnosisConfig::max_correlation).
//   One simulated flight serves every group at once (they share the extended model).
//   The suggestion is the candidate with the lowest predicted correlation; when none brings a group
//   below max_correlation, candidates are combined greedily (the best so far followed by each of the
//   kCombineBest best single ones, the same one again included), up to kMaxCombined of them.
//   A simulated recording's scenario is known from its sidecar (scenario_from_sidecar); for a
//   measured recording none is, and the candidates are listed without a prediction.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "sim/scenario.hpp"
#include "tools/diagnosis.hpp"

namespace tools {

/// One way of flying on (a candidate or a combination of candidates).
struct SeparationTrial {
  std::string label;                   ///< "wings-level speed change" (" + " between combined ones)
  std::vector<sim::Segment> segments;  ///< appended to the flown flight, in order
  double added_s = 0.0;                ///< flight time they add [s]
  /// Per group (DiagnosisResult::findings order; NaN for a separable finding): the members' predicted
  /// correlation after the segments, and per member its multiple correlation with the other members
  /// and its predicted posterior sigma (catalogue units).
  std::vector<double> correlation;
  std::vector<std::vector<double>> member_correlation, member_sigma;
  bool evaluated = false;
  std::string error;  ///< why it could not be evaluated
};

/// The suggestion for one finding (empty members: the finding is separable, nothing to suggest).
struct Separation {
  std::vector<std::string> members;  ///< "effect.component", the group's lead first
  double max_correlation = 0.9;      ///< the threshold the members must get below
  double flown_correlation = 0.0;    ///< the members' correlation in the extended model on the data diagnosed
  bool predicted = false;            ///< false: no scenario is known (a measured recording): segments only
  std::string note;                  ///< how the suggestion was found, or why there is no prediction
  std::string label;
  std::vector<sim::Segment> segments;  ///< the suggestion (the best trial)
  std::string segments_toml;           ///< the same in scenario-file syntax ([[trajectory.segment]] entries)
  std::string scenario_toml;           ///< the flown scenario with the segments appended; "" when unknown
  double added_s = 0.0;
  double predicted_correlation = 0.0;  ///< the members' correlation after the segments (when predicted)
  std::vector<double> member_correlation, member_sigma;  ///< per member, after the segments
  bool separates = false;  ///< predicted_correlation < max_correlation
};

/// Where a prediction starts from: the scenario of the flight diagnosed, when known.
struct FlownScenario {
  bool known = false;
  sim::Scenario scenario;
  std::string source;  ///< e.g. "sidecar run.lcmlog.json: built-in scenario, seed 7, 600 s"
  std::string note;    ///< why it is not known
};

/// The scenario a simulated log was flown from, as its `sdins sim` sidecar (LOG.json) describes it:
/// the scenario file it names (relative: to the working directory, else to the log's directory;
/// "": the built-in one) with the sidecar's seed, duration, truth error set and effects. known is
/// false, with the reason in note, for a log without a sidecar (a measured recording), a sidecar that
/// cannot be read or a scenario file that is gone or no longer matches.
FlownScenario scenario_from_sidecar(const std::string& log_path);

/// The candidate segment sequences for a flight that ends as `flown` does (its final speed and the
/// direction and bank of its last turn set the speed change, the turn the other way and the bank).
std::vector<SeparationTrial> separation_candidates(const sim::Scenario& flown);
/// The same for an unknown flight (a measured recording): built for the default aircraft speed.
std::vector<SeparationTrial> separation_candidates();

/// The most combined candidates in one suggestion, and how many of the best single candidates a
/// combination round tries after the best so far.
inline constexpr int kMaxCombined = 3;
inline constexpr int kCombineBest = 3;
/// The IMU rate of the simulated flights of a prediction (the navigation rate): a fifth of the
/// simulator's work at its default 1000 Hz, the same trajectory for the covariance.
inline constexpr int kPredictionImuRate_hz = 200;

/// Largest multiple correlation of a member with the other members (positions into the posterior
/// correlation matrix R); for a pair |rho|. per_member (optional) receives each member's.
double group_correlation(const Eigen::MatrixXd& R, const std::vector<int>& positions,
                         std::vector<double>* per_member = nullptr);

/// A suggestion per finding of r (same order; separable findings get an empty Separation). flown:
/// the scenario of the data diagnosed (known = false: candidates without prediction). trials
/// (optional) receives every trial evaluated, for the report.
std::vector<Separation> suggest_separations(const DiagnosisResult& r, const DiagnosisConfig& cfg,
                                            const FlownScenario& flown,
                                            const std::function<void(const std::string&)>& progress = {},
                                            std::vector<SeparationTrial>* trials = nullptr);

}  // namespace tools
