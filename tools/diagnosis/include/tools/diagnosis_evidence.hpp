// Evidence the recording itself carries about the diagnosis' timing findings (issue 26;
// docs/diagnosis.md, "Evidence the recording carries"). Nothing here changes a finding: each check
// puts what the evidence says beside the finding and flags a finding the evidence contradicts.
//
//   - The IMU's own sample counter (imu_counter of the IMU channel, RecordedData::imu_counter_tags):
//     a least-squares line tag = a + b n. If the sensor samples at its nominal rate on its own
//     oscillator (the nominal rate: 1 / b rounded to a whole Hz), the tags are stretched against
//     it by b rate - 1: the IMU clock drift the tags imply, within the oscillator's tolerance
//     (kCounterToleranceppm).
//   - An import's clock pair (`time_fit` of the import summary `<log>.json`, written beside the log
//     by `sdins import`; absent: no such evidence): GPS = offset + slope local over the GNSS rows.
//     IMU tags mapped through that fit carry no residual drift beyond its fit; tags left on the
//     local clock drift by -(slope - 1). A drift finding farther than kClockFitTolerance_ppm from
//     both is contradicted.
//   - A reference (TRUTH): the lag of the IMU's angular-rate magnitude against the reference's
//     (from its attitude, or without attitude the magnitude of its course rate, a ground vehicle's
//     yaw rate) by cross-correlation: the IMU tags' offset against the reference's time, beside an
//     IMU-GNSS time offset finding (a reference on GNSS time: RTK; an autopilot's estimate carries
//     its own filter lag).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "tools/diagnosis.hpp"

namespace tools {

/// An IMU oscillator's frequency tolerance assumed for the counter evidence [ppm].
inline constexpr double kCounterTolerance_ppm = 50.0;
/// The counter is a sample clock only if its tags lie within this many periods (RMS) of a line.
inline constexpr double kCounterMaxResidualPeriods = 0.25;
/// How far a drift finding may lie from the clock pair's figures [ppm].
inline constexpr double kClockFitTolerance_ppm = 20.0;
/// Lags searched by the cross-correlation: +- this [s].
inline constexpr double kMaxReferenceLag_s = 1.0;

/// Cumulative |rotation| of the IMU against its tags: C(t), piecewise linear between the tags t
/// (strictly ascending), clamped to its ends. at(x, hint) gives at(x) exactly (the same segment
/// and the same arithmetic) and starts its search at hint, the segment of the caller's last
/// lookup: the reference-lag correlation asks for ascending times, 244 lags x 2 per reference
/// interval, which a search over all of a long recording's tags each time made most of the
/// evidence's cost.
struct CumulativeRate {
  static constexpr std::size_t kWindow = 512;  ///< tags searched from the hint before the rest
  hal::LargeVector<double> t, c;  ///< one entry per IMU sample (huge pages)
  double at(double x) const;
  double at(double x, std::size_t& hint) const;
};

/// What the evidence says about one finding.
struct EvidenceCheck {
  std::string finding;      ///< "imu_clock_drift"
  std::string source;       ///< what the evidence is
  double evidence = 0.0;    ///< its figure, in the finding's unit
  double tolerance = 0.0;   ///< how far the finding may lie from it
  std::string unit;
  double finding_estimate = 0.0, finding_lo = 0.0, finding_hi = 0.0;
  bool contradicts = false;  ///< the finding's whole interval farther than tolerance from every figure
  std::string note;
};

struct RecordingEvidence {
  // The IMU counter.
  int counter_samples = 0;
  double counter_rate_hz = 0.0;       ///< nominal rate taken (1 / b, rounded)
  double counter_stretch_ppm = 0.0;   ///< b rate - 1
  double counter_residual_rms_s = 0.0;
  std::string counter_note;           ///< why a counter present was not used
  // The import's clock pair.
  bool has_clock_fit = false;
  double clock_fit_drift_ppm = 0.0;
  double clock_fit_residual_rms_s = 0.0;
  // The import's tick mapping (`imu.seconds_per_imu_second` of the summary: GPS seconds the importer
  // gave one second of the IMU's own tick, e.g. an RTKLIB tag file's span over the tick span).
  bool has_tick_ratio = false;
  double tick_stretch_ppm = 0.0;      ///< (ratio - 1) 1e6: the tags' stretch against the IMU's ticks
  std::string summary_path;           ///< the summary read ("" none)
  std::string summary_note;           ///< why it was not used, if so
  // The reference's lag.
  bool has_reference_lag = false;
  std::string reference_kind;         ///< "attitude" or "course"
  double reference_lag_s = 0.0;       ///< IMU tag - reference time of the best correlation
  double reference_correlation = 0.0;
  int reference_samples = 0;
  std::string reference_note;         ///< on which data the lag was measured
  std::vector<EvidenceCheck> checks;
};

/// The evidence of the recording as given (not corrected); log_path: the recording, whose
/// summary `<log_path>.json` is read when present (tolerating its absence and foreign sidecars).
RecordingEvidence recording_evidence(const RecordedData& data, const std::string& log_path);

/// Measures the reference's lag (RecordingEvidence::reference_*) on data. The lag is a statement about
/// the tags of that data: a time-offset finding that the chain reports on a recording it also
/// re-timed for a clock drift (the offset at the drift's reference time) is compared with the lag
/// measured on the recording with every other correction applied, plus the offset applied.
void reference_lag(RecordingEvidence& ev, const RecordedData& data);

/// Puts the evidence beside each timing finding (findings on the recording as given: the chain's
/// totals) and flags contradictions.
void check_findings(RecordingEvidence& ev, const std::vector<Finding>& findings);

}  // namespace tools
