// Findings that survive their predecessors (issue 26; docs/diagnosis.md, "The chain").
//
// A timing or geometry finding (the IMU-GNSS time offset, the IMU clock drift, an antenna lever
// arm component) changes what every other component sees: a 0.2 s offset on an aircraft makes a
// lever arm and an accelerometer scale factor look significant. So after each such finding the
// diagnosis applies it, exactly, to the data (the IMU re-timed: apply_fixed_effect) or to the model
// (the configured antenna moved), at the profile likelihood's maximum (the large values are not
// taken from the linearised state), and searches again from the corrected recording. The most
// significant timing/geometry finding of a stage is applied; a finding is reported only if the
// stage after everything before it was applied still finds it. The chain ends when a stage finds
// no timing/geometry finding (its other findings are then the final ones) or after
// kMaxChainStages. A component found again in a later stage is a residual: its values add up, and
// the reported interval is the last stage's profile shifted by what was applied before it.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "tools/diagnosis.hpp"
#include "tools/diagnosis_mounting.hpp"

namespace tools {

/// At most this many searches (each a whole diagnosis of the corrected recording).
inline constexpr int kMaxChainStages = 5;
/// A group is applied through its most plausible member only when that member's plausibility
/// under the priors (GroupMember::plausibility) is at least this.
inline constexpr double kChainMemberPlausibility = 0.99;

/// True for the effects the chain applies to the data or the model.
bool chain_applicable(fsw::Effect e);

/// A correction applied to the recording (time offset, clock drift) or to the model (lever arm).
struct AppliedCorrection {
  std::string name;       ///< "effect.component" (catalogue name)
  int candidate = -1;     ///< index into diagnosis_candidates()
  double value = 0.0;     ///< applied in this step (catalogue units)
  double total = 0.0;     ///< the component's total after this step (its earlier steps added)
  std::string unit;
  std::string source;     ///< "profile_maximum" or "filter"
  int stage = 0;          ///< the stage (1-based) that found it
  /// true: the most plausible member of a group the data cannot separate (plausibility >=
  /// kChainMemberPlausibility under the priors); the next stage is the check.
  bool from_group = false;
};

/// One search of the chain.
struct ChainStage {
  int stage = 0;                              ///< 1-based
  std::vector<AppliedCorrection> applied_before;  ///< everything applied to the data/model searched
  std::vector<Finding> findings;              ///< what this search found (headline as diagnose())
  /// The baseline model's log-likelihood on this stage's data, over the measurements common to
  /// every stage's baseline run (comparable along the chain), and that count.
  double base_log_likelihood = 0.0;
  int common_measurements = 0;
  /// The stage's extended model: log-likelihood gain over its own baseline (compare_likelihood).
  double extended_gain = 0.0;
  double base_nis = 0.0, extended_nis = 0.0;
  std::string applied_after;                  ///< the finding applied after this stage ("": the chain ends)
};

/// The mounting yaw of an IMU initialised from the GNSS track (init mode "track": heading = track +
/// init.heading_offset_deg): a fixed rotation about the vehicle's vertical between the IMU and the
/// direction of travel, e.g. a sensor mounted sideways. An estimated initial quantity, not a filter
/// state: the baseline is run ungated with the heading offset held at each value (a 15 deg grid
/// over the circle, then halving steps about the best to 0.5 deg) and the profile of its
/// log-likelihood gives the estimate and the 95% interval (a parabola through the finest points).
/// Found when the offset configured lies at a deviance above kMountingDeviance.
struct MountingEstimate {
  bool searched = false;     ///< false: the initialisation does not use the track
  bool found = false;
  double yaw_deg = 0.0;      ///< the offset to add to init.heading_offset_deg (profile maximum)
  double lo_deg = 0.0, hi_deg = 0.0;
  double deviance_at_configured = 0.0;  ///< at the configured offset (what is added: 0)
  int runs = 0;
  std::vector<double> theta_deg, deviance;  ///< the curve, sorted
};
/// kMountingDeviance: tools/diagnosis_mounting.hpp.
MountingEstimate estimate_mounting_yaw(const RecordedData& data, const DiagnosisConfig& cfg);

struct DiagnosisChain {
  MountingEstimate mounting;  ///< searched first; applied to the initialisation when found
  /// The mounting from the direction of travel (tools/diagnosis_mounting.hpp), on a run initialised
  /// with `mounting` applied: the finding. Its yaw, when named, is the track initialisation's
  /// heading offset of every search (replacing the profile's).
  MountingFromTravel travel;
  std::vector<ChainStage> stages;
  std::vector<AppliedCorrection> applied;  ///< in order
  /// The findings reported: each applied component (its total, the interval of the last stage that
  /// found it shifted by what was applied before), then the last stage's other findings.
  std::vector<Finding> findings;
  /// Findings of earlier stages that a later stage, after the corrections, no longer found.
  std::vector<std::string> vanished;
  DiagnosisResult first;   ///< stage 1: the search on the recording as given
  DiagnosisResult last;    ///< the last stage: on the corrected recording
  /// The recording with every timing correction applied, made when the first one is (a copy of a
  /// 30-minute recording is 130 MB): empty while recording_corrected is false, when the recording
  /// as given is the one every stage searched.
  RecordedData corrected;
  bool recording_corrected = false;
  DiagnosisConfig corrected_cfg;  ///< the configuration with every geometry correction applied
};

/// The drift's reference time of a recording (the first GNSS input of the configured source, as
/// profile_interval uses).
double drift_reference_time(const RecordedData& data, const DiagnosisConfig& cfg);

/// Applies a component's value to the data (time offset, drift) or the configuration (lever arm).
void apply_correction(RecordedData& data, DiagnosisConfig& cfg, int candidate, double value);

/// The chain of diagnoses (above). progress as diagnose()'s.
DiagnosisChain diagnose_chain(const RecordedData& data, const DiagnosisConfig& cfg,
                              const std::function<void(const std::string&)>& progress = {});

}  // namespace tools
