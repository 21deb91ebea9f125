// The diagnosis' model layer (docs/diagnosis.md): a recording in memory, the candidates (the
// components of the effect catalogue as states of fsw::LayoutDiag), the configuration, and one run
// of the diagnosis model with a set of candidates active. The search (tools/diagnosis.hpp) and the
// intervals (tools/diagnosis_intervals.hpp) are built on it; it knows neither.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "fsw/effect_catalogue.hpp"
#include "fsw/error_state.hpp"
#include "fsw/filter_model.hpp"
#include "fsw/flight_app.hpp"
#include "fsw/gps_orbit.hpp"
#include "fsw/input_event.hpp"
#include "fsw/strapdown.hpp"
#include "cfg/flight_config.hpp"
#include "hal/large_array.hpp"
#include "sim/scenario.hpp"
#include "sim/truth.hpp"
#include "tools/reference.hpp"

namespace tools {

/// A truth or reference sample (TRUTH channel): sim/truth.hpp, with the navigation-error metric.
using sim::TruthPoint;

/// A recording in memory, in arrival order: the inputs of the flight software and, separately,
/// truth (used only to score navigation). Stored by type (an fsw::InputEvent is about 1 KiB, an
/// IMU sample 64 B) with an index of the arrival order; RecordingView::input_event gives the
/// flight application's input type for one entry of the order.
struct RecordedData {
  enum class Kind : std::uint8_t { kAlmanac, kImu, kGnss, kPvt };
  struct Event {
    Kind kind;
    std::uint32_t index;  ///< into almanac, imu, gnss or pvt
  };
  std::vector<fsw::GpsAlmanac> almanac;
  hal::LargeVector<fsw::ImuSample> imu;  ///< 1.8 M samples for 1800 s: huge pages (hal/large_array.hpp)
  std::vector<fsw::GnssRawEpoch> gnss;
  std::vector<fsw::GnssPvtMeasurement> pvt;  ///< GNSS position/velocity solutions (GNSS_PVT)
  using Order = hal::LargeVector<Event>;  ///< an arrival order (as large as imu: huge pages)
  Order order;
  std::vector<TruthPoint> truth;  ///< time-ordered; empty without truth
  /// (time tag, the sensor's own sample counter) of every IMU input that carried one (imported
  /// recordings): a second clock, read only as evidence (tools/diagnosis_evidence.hpp).
  std::vector<std::pair<double, std::int32_t>> imu_counter_tags;
  std::string description;
  int damaged_stretches = 0;                ///< IMU holes > kDamagedImuGap_s (exclude_damaged_stretches)
  std::uint64_t excluded_imu_samples = 0;   ///< IMU samples outside the stretch kept

  /// Appends ev's payload to its array and its entry to the order (the inverse of RecordingView::input_event).
  void push(const fsw::InputEvent& ev);
};

/// One fixed component applied to the IMU samples as a run reads them (apply_fixed_effect,
/// tools/diagnosis_intervals.hpp): the compensation of fsw::ImuCompensation with that component
/// set (its sign convention: the estimate is the error that is removed), and the tags re-timed for
/// a clock offset or drift (sim::ImuModel tags at t (1 + drift) + offset; tag() restores t).
struct ImuCorrection {
  fsw::Mat3 Eg = fsw::Mat3::Zero(), Ea = fsw::Mat3::Zero();
  fsw::Vec3 gs = fsw::Vec3::Zero();
  double offset_s = 0.0, drift = 0.0, t_ref_s = 0.0;
  bool retimed() const { return offset_s != 0.0 || drift != 0.0; }
  double tag(double t_s) const { return t_s - offset_s - drift * (t_s - t_ref_s); }
  void apply(fsw::ImuSample& s) const {
    const fsw::Vec3 dth = s.dtheta_rad, dv = s.dv_mps;
    s.dtheta_rad = dth - Eg * dth - gs.cwiseProduct(dv);
    s.dv_mps = dv - Ea * dv;
    s.t_s = tag(s.t_s);
    s.dt_s = s.dt_s / (1.0 + drift);
  }
};

/// What one run reads: a recording and, in place of its own, optionally another arrival order and
/// other GNSS epochs (a data selection, a re-timed order), with its IMU samples corrected as they
/// pass. Nothing of the recording is copied: a profile likelihood runs the model many times on
/// the same 1800000 samples, each with its own correction.
struct RecordingView {
  const RecordedData* data = nullptr;
  const RecordedData::Order* order = nullptr;  ///< nullptr: data->order
  const std::vector<fsw::GnssRawEpoch>* gnss = nullptr;     ///< nullptr: data->gnss
  const ImuCorrection* imu = nullptr;                       ///< nullptr: the samples as recorded

  const RecordedData::Order& events() const { return order ? *order : data->order; }
  const std::vector<fsw::GnssRawEpoch>& gnss_epochs() const { return gnss ? *gnss : data->gnss; }
  /// Fills ev (kind, t_s and that kind's payload; the other payloads are left as they are) with the
  /// input of e as this view gives it. An almanac element's t_s is 0 (the recording keeps no
  /// receive time for it).
  void input_event(const RecordedData::Event& e, fsw::InputEvent& ev) const;
};

/// A recording as an event source of the one driver (fsw/driver.hpp): its inputs in arrival order,
/// one InputEvent filled per delivery (RecordingView::input_event).
class RecordedSource {
 public:
  explicit RecordedSource(const RecordedData& d) : v_{&d} {}
  explicit RecordedSource(const RecordingView& v) : v_(v) {}
  const fsw::InputEvent* next() {
    const RecordedData::Order& order = v_.events();
    if (k_ >= order.size()) return nullptr;
    v_.input_event(order[k_++], ev_);
    return &ev_;
  }

 private:
  RecordingView v_;
  std::size_t k_ = 0;
  fsw::InputEvent ev_{};
};

/// An IMU hole longer than this is a damaged stretch of a log (lost or rejected events).
inline constexpr double kDamagedImuGap_s = 0.1;
/// Keeps the longest stretch of d without an IMU hole longer than kDamagedImuGap_s (and the GNSS
/// inputs within it; almanacs all), counting the holes and the samples left out (docs/faults.md).
void exclude_damaged_stretches(RecordedData& d);

/// The diagnosis' reference from the one TRUTH reader (tools/reference.hpp), with its rule on top:
/// a sample scores position and velocity together, so one without both is rejected, and so is
/// one whose attitude is there but is not a unit quaternion; one without attitude (an imported
/// GNSS solution) is kept with has_attitude false. `rejected`: the reader's rejections plus these.
std::vector<TruthPoint> diagnosis_truth(const Reference& ref, std::uint64_t& rejected);

/// Reads an LCM log (IMU, GNSS_RAW, GNSS_PVT, GPS_ALMANAC through hal::LcmReplayReader; TRUTH
/// through diagnosis_truth).
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
/// The same on a view of a recording (a selection, a correction applied as the samples pass).
DiagnosisRun run_diagnosis_model(const RecordingView& data, const DiagnosisConfig& cfg, const std::vector<int>& active,
                             bool with_outages = false);

/// Log-likelihood of both runs over the scalar measurements both used: fills a.innovations and
/// b.innovations' log_likelihood and common.
void compare_likelihood(DiagnosisRun& a, DiagnosisRun& b);

/// The prior 1-sigma of effect e in SI units (DiagnosisConfig::prior holds catalogue units).
double prior_sigma_si(const DiagnosisConfig& cfg, fsw::Effect e);

}  // namespace tools
