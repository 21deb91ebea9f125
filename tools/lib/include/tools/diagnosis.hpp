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
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "fsw/chi_square.hpp"
#include "fsw/effect_catalogue.hpp"
#include "fsw/error_state.hpp"
#include "fsw/filter_model.hpp"
#include "fsw/flight_app.hpp"
#include "fsw/gps_orbit.hpp"
#include "fsw/input_event.hpp"
#include "fsw/strapdown.hpp"
#include "cfg/flight_config.hpp"
#include "sim/scenario.hpp"
#include "sim/truth.hpp"

namespace tools {

/// A truth or reference sample (TRUTH channel): sim/truth.hpp, with the navigation-error metric.
using sim::TruthPoint;

/// A recording in memory, in arrival order: the inputs of the flight software and, separately,
/// truth (used only to score navigation). Stored by type (an fsw::InputEvent is about 1 KiB, an
/// IMU sample 64 B) with an index of the arrival order; input_event() gives the flight
/// application's input type for one entry of the order.
struct RecordedData {
  enum class Kind : std::uint8_t { kAlmanac, kImu, kGnss, kPvt };
  struct Event {
    Kind kind;
    std::uint32_t index;  ///< into almanac, imu, gnss or pvt
  };
  std::vector<fsw::GpsAlmanac> almanac;
  std::vector<fsw::ImuSample> imu;
  std::vector<fsw::GnssRawEpoch> gnss;
  std::vector<fsw::GnssPvtMeasurement> pvt;  ///< GNSS position/velocity solutions (GNSS_PVT)
  std::vector<Event> order;
  std::vector<TruthPoint> truth;  ///< time-ordered; empty without truth
  /// (time tag, the sensor's own sample counter) of every IMU input that carried one (imported
  /// recordings): a second clock, read only as evidence (tools/diagnosis_evidence.hpp).
  std::vector<std::pair<double, std::int32_t>> imu_counter_tags;
  std::string description;
  int damaged_stretches = 0;                ///< IMU holes > kDamagedImuGap_s (exclude_damaged_stretches)
  std::uint64_t excluded_imu_samples = 0;   ///< IMU samples outside the stretch kept

  /// Fills ev (kind, t_s and that kind's payload; the other payloads are left as they are) with the
  /// input of e. An almanac element's t_s is 0 (the recording keeps no receive time for it).
  void input_event(const Event& e, fsw::InputEvent& ev) const;
  /// Appends ev's payload to its array and its entry to the order (the inverse of input_event).
  void push(const fsw::InputEvent& ev);
};

/// A recording as an event source of the one driver (fsw/driver.hpp): its inputs in arrival order,
/// one InputEvent filled per delivery (RecordedData::input_event).
class RecordedSource {
 public:
  explicit RecordedSource(const RecordedData& d) : d_(d) {}
  const fsw::InputEvent* next() {
    if (k_ >= d_.order.size()) return nullptr;
    d_.input_event(d_.order[k_++], ev_);
    return &ev_;
  }

 private:
  const RecordedData& d_;
  std::size_t k_ = 0;
  fsw::InputEvent ev_{};
};

/// An IMU hole longer than this is a damaged stretch of a log (lost or rejected events).
inline constexpr double kDamagedImuGap_s = 0.1;
/// Keeps the longest stretch of d without an IMU hole longer than kDamagedImuGap_s (and the GNSS
/// inputs within it; almanacs all), counting the holes and the samples left out (docs/faults.md).
void exclude_damaged_stretches(RecordedData& d);

/// Reads an LCM log (IMU, GNSS_RAW, GNSS_PVT, GPS_ALMANAC through hal::LcmReplayReader; TRUTH).
/// Returns false with a message when the log cannot be read or has no IMU or GNSS data; rejections
/// are summarised in `report`.
bool load_recorded_data(const std::string& path, RecordedData& out, std::string& error, std::string& report);

/// Flies a scenario through the simulator (sim::SensorStream) into memory, with truth at
/// truth_rate_hz: the same data `sdins sim --log` writes, without the file.
RecordedData record_scenario(const sim::Scenario& sc, std::uint64_t seed, double truth_rate_hz = 10.0);

/// One candidate: a component of a catalogue effect and its state in fsw::LayoutDiag.
struct Candidate {
  fsw::Effect effect;
  int component;  ///< index into the effect's components
  int state;      ///< index in LayoutDiag
};
/// Every component of the catalogue, in catalogue order.
const std::vector<Candidate>& diagnosis_candidates();
/// "gyro_misalignment.xy" (or the effect name alone for scalar effects).
std::string candidate_name(const Candidate& c);

struct DiagnosisConfig {
  fsw::FlightAppConfig app{};  ///< the baseline model's configuration (the extension sigmas are set per run)
  /// Which GNSS input the filter takes: raw pseudoranges/rates or position/velocity solutions.
  cfg::GnssSource gnss_source = cfg::GnssSource::kRaw;
  /// Prior 1-sigma of each effect in catalogue units (index fsw::Effect).
  std::array<double, fsw::kEffectCount> prior{};
  double alpha = 0.05;               ///< family-wise false-alarm rate of one diagnosis
  double max_variance_ratio = 0.25;  ///< p / p0 above which a component counts as unobservable
  double max_correlation = 0.9;      ///< |posterior correlation| above which two components are not told apart
  int max_confirmation_passes = 3;
  int max_findings = 4;              ///< forward-selection rounds
  double gain_skip_s = 60.0;         ///< navigation errors are scored from initialisation + this
  // Gain on coasting, the way the field measures it: GNSS withheld for outage_length_s every
  // outage_period_s, from init + outage_first_s; 0 length: no outage runs.
  double outage_length_s = 15.0;
  double outage_period_s = 60.0;
  double outage_first_s = 120.0;
  /// The baseline (fsw/filter_model.hpp): 15 (no extension) or 24 (the paper's 24-state model: the
  /// 9 misalignments are part of the baseline, never candidates). Set with set_diagnosis_baseline().
  fsw::FilterModel baseline = fsw::FilterModel::k15;
  /// Each separable finding's 95% interval from the profile likelihood over the whole recording
  /// (tools/diagnosis_intervals.hpp, docs/diagnosis-intervals.md); false: the filter's sigma only.
  bool profile_intervals = true;
  std::vector<int> baseline_states;  ///< candidates that are always in the model
};
/// Sets the baseline model (15 or 24); false for a model that is not a diagnosis baseline.
bool set_diagnosis_baseline(DiagnosisConfig& cfg, fsw::FilterModel model);
/// The defaults: the shipped flight configuration (config/default.toml: the simulated receiver and
/// IMU of the project, priors that cover the realistic range of each effect, the outage pattern).
DiagnosisConfig default_diagnosis_config();

/// A data set's flight configuration (cfg::FlightConfig, config/README.md): the filter, its GNSS
/// input, and the priors and outage pattern the file sets.
void apply_flight_config(DiagnosisConfig& cfg, const cfg::FlightConfig& f);

/// Innovation statistics of one run.
struct InnovationStats {
  int epochs = 0;
  int pr_used = 0, prr_used = 0, rejected = 0;
  int pos_used = 0, vel_used = 0;  ///< loosely coupled scalars (per axis)
  double nis_mean = 0.0;      ///< mean NIS per scalar measurement (1 for a consistent filter)
  double pr_rms_m = 0.0;      ///< innovation RMS per measurement type
  double prr_rms_mps = 0.0;
  double pos_rms_m = 0.0;     ///< loosely coupled: position and velocity innovation RMS per axis
  double vel_rms_mps = 0.0;
  double log_likelihood = 0.0;  ///< sum over the measurements counted in `common`
  int common = 0;              ///< measurements used by both models compared
};

/// Navigation error RMS against truth/reference.
struct NavErrorStats {
  bool available = false;
  int samples = 0;
  int attitude_samples = 0;  ///< of which with a reference attitude (tilt/heading: NaN without)
  double pos_rms_m = 0.0, vel_rms_mps = 0.0;
  double tilt_rms_deg = 0.0, heading_rms_deg = 0.0;
  double heading_final_deg = 0.0;
};

/// Coasting through GNSS outages against truth/reference: the error at the end of each window.
struct OutageStats {
  int windows = 0;
  int epochs_withheld = 0;
  double horizontal_rms_m = 0.0, horizontal_max_m = 0.0;
  double velocity_rms_mps = 0.0;
  /// The filter's own horizontal position 1-sigma at the end of each window (sqrt(P_EE + P_NN)),
  /// RMS over the windows, and the mean 2-dof NEES of the horizontal error there (2 for a filter
  /// that knows its coasting error; far above 2: the coasting error has a cause outside the model).
  double predicted_horizontal_rms_m = 0.0;
  double horizontal_nees_mean = 0.0;
  /// Without a reference: the first measurement update after each outage compares the coasted
  /// solution with GNSS. Its NIS per position scalar (loosely coupled) or per pseudorange (tightly
  /// coupled), used or gated, averaged over the outages: 1 when the model explains its coasting
  /// error, far above 1 when a cause outside the model dominates (the same verdict as the NEES,
  /// from the data alone).
  int reacquisitions = 0;
  double reacquisition_nis_mean = 0.0;
};

/// One run of the diagnosis model (fsw::LayoutDiag) with a set of active candidates.
struct DiagnosisRun {
  std::vector<int> active;  ///< indices into diagnosis_candidates()
  bool initialised = false;
  double init_t_s = 0.0;
  // Per active candidate, at the end (catalogue units).
  std::vector<double> estimate, sigma, prior_sigma, z2;
  Eigen::MatrixXd correlation;  ///< posterior correlation of the active candidates
  InnovationStats innovations;
  NavErrorStats nav;
  OutageStats outages;  ///< only in runs with outages
  // Per-epoch traces for the report.
  std::vector<double> t_s, pr_rms_m, prr_rms_mps, pos_rms_m, vel_rms_mps, heading_err_deg;
  std::vector<std::vector<double>> est_trace, sigma_trace;  ///< [epoch][active]
  // Scalar innovations (key: epoch, observation, type) for the likelihood comparison.
  struct Scalar {
    std::uint64_t key;  ///< frame_key(GNSS frame) | observation << 1 | (1 for a rate)
    double nu, S;
  };
  /// The lowest key of a GNSS epoch's frame (round(t * nav_rate_hz)): the bits below hold the
  /// observation (raw: its index < 16; solution axes 16-21) and the type.
  static constexpr std::uint64_t frame_key(std::uint64_t frame) { return frame << 6; }
  std::vector<Scalar> scalars;
  /// The observations the innovation gate rejected: (GNSS epoch frame, PRN; 0 for a GNSS solution),
  /// the data selection a profile likelihood holds fixed (diagnosis_intervals.cpp).
  std::vector<std::pair<std::uint64_t, std::uint8_t>> gated;
  fsw::ExecutiveHealth exec_health{};  ///< the flight software's counters at the end of the run
};

/// Runs the diagnosis model on the data with the given candidates active. with_outages: GNSS is
/// withheld over the configured windows and the coasting error scored (needs truth).
DiagnosisRun run_diagnosis_model(const RecordedData& data, const DiagnosisConfig& cfg, const std::vector<int>& active,
                             bool with_outages = false);

/// Log-likelihood of both runs over the scalar measurements both used: fills a.innovations and
/// b.innovations' log_likelihood and common.
void compare_likelihood(DiagnosisRun& a, DiagnosisRun& b);

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

/// The headline of every finding: the profile likelihood's maximum (and half-width / 1.96 as its
/// sigma) whenever the finding's interval is a profile, the filter's estimate and sigma otherwise;
/// the filter's figure stays in filter_estimate / filter_sigma. Called by diagnose() once the
/// intervals are set. (The drive's drift headline was the filter's 161.5 ppm above a profile
/// interval of [205.7, 277.3]: a user reads the first number.)
void set_headline_estimates(std::vector<Finding>& findings);

/// Sets each member's prior_z (from its profile maximum where the member's interval is a profile
/// the filter agrees with, else from alone_estimate) and the group's plausibilities.
void set_group_plausibility(std::vector<GroupMember>& group);

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
