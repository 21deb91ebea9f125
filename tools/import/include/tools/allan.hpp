// The overlapping Allan variance of a rate sensor's output and the IEEE Std 952 reading of its
// noise terms (docs/noise.md).
//
// Input is "phase" data: the integrated sensor output (angle [rad] of a gyro, velocity [m/s] of
// an accelerometer) sampled every tau0 on one or more uninterrupted segments. For averaging factor
// m (tau = m tau0) the overlapping estimator pools all segments (NIST SP 1065 eq. 11):
//   avar(tau) = sum_seg sum_i (x[i+2m] - 2 x[i+m] + x[i])^2 / (2 tau^2 sum_seg (N_seg - 2m)).
// Its confidence interval is chi-squared with the equivalent degrees of freedom of NIST SP 1065
// Table 5 (Howe, Allan and Barnes 1981) for the noise type that dominates at that tau, summed over
// the segments (independent).
//
// Noise model of a rate sensor (IEEE Std 952-1997 annex C), in rate units [u/s] for a rate u/s:
//   avar(tau) = 3 Q^2 / tau^2 + N^2 / tau + (2 ln 2 / pi) B^2 + K^2 tau / 3
// Q quantization [u], N white rate noise (angle / velocity random walk) [u/sqrt(s)], B bias
// instability [u/s] (flicker floor: adev = 0.664 B), K rate random walk [u/s/sqrt(s)]. The terms
// are fitted to the curve (non-negative weighted least squares), then each coefficient is READ
// at one tau with that tau's chi-squared interval, the fitted other terms subtracted:
//   N at tau = 1 s on the slope -1/2 line; K at tau = 3 s on the slope +1/2 line (read where the
//   K term dominates); B from the floor (the fitted curve's minimum) / 0.664.
// A term is "supported" only when it dominates the fitted curve at a measured tau; otherwise the
// reading says why and gives the 95% upper bound the span allows.
#pragma once

#include <string>
#include <vector>

namespace tools {

/// The power-law noise types of NIST SP 1065 in rate-sensor terms.
enum class PowerLawNoise {
  kWhitePhase,     ///< alpha = +2: quantization (slope -1 in adev)
  kFlickerPhase,   ///< alpha = +1
  kWhiteRate,      ///< alpha = 0, "white FM": angle / velocity random walk (slope -1/2)
  kFlickerRate,    ///< alpha = -1, "flicker FM": bias instability (slope 0)
  kRandomWalkRate  ///< alpha = -2, "random-walk FM": rate random walk (slope +1/2)
};
const char* to_string(PowerLawNoise n);

/// Equivalent degrees of freedom of the overlapping Allan variance of n_phase phase points at
/// averaging factor m (NIST SP 1065 Table 5); 0 when n_phase <= 2 m.
double oadev_edf(PowerLawNoise noise, double n_phase, double m);

/// Quantile p of the chi-squared distribution with edf degrees of freedom (boost::math).
double chi2_quantile(double edf, double p);

struct AllanPoint {
  double tau_s = 0.0;
  long long m = 0;
  long long terms = 0;    ///< second differences pooled
  double avar = 0.0;      ///< [u^2/s^2]
  double edf = 0.0;       ///< for the noise type below
  PowerLawNoise noise = PowerLawNoise::kWhiteRate;  ///< dominant type (from the fit) the edf is for
  double avar_lo = 0.0;   ///< the confidence interval of avar (level of the curve)
  double avar_hi = 0.0;
};

struct AllanCurve {
  double tau0_s = 0.0;
  std::vector<long long> segment_points;  ///< phase points per segment
  std::vector<AllanPoint> points;         ///< increasing tau
  double confidence = 0.95;
};

/// Averaging factors: 1, then steps of 2^(1/per_octave) (rounded, distinct), plus the given extra
/// ones, all with at least min_terms second differences in the longest segment.
std::vector<long long> allan_factors(long long longest_segment_points, int per_octave,
                                     const std::vector<long long>& extra, long long min_terms = 2);

/// The overlapping Allan variance at the factors ms of the segments' phase data. Every point's edf
/// and interval are for white rate noise until set_dominant_noise() is called.
AllanCurve overlapping_allan(const std::vector<std::vector<double>>& segments, double tau0_s,
                             const std::vector<long long>& ms, double confidence = 0.95);

/// IEEE Std 952 model coefficients in Allan-variance units (all >= 0).
struct AllanModel {
  double q2 = 0.0;  ///< 3 Q^2 coefficient of tau^-2
  double n2 = 0.0;  ///< N^2, coefficient of tau^-1
  double b2 = 0.0;  ///< (2 ln2 / pi) B^2, the flat part
  double k2 = 0.0;  ///< K^2 / 3, coefficient of tau
  double avar(double tau_s) const { return q2 / (tau_s * tau_s) + n2 / tau_s + b2 + k2 * tau_s; }
  /// The largest term at tau.
  PowerLawNoise dominant(double tau_s) const;
};

/// Weighted non-negative least squares of the model on the curve's points from index first on:
/// every subset of the four terms solved, the best feasible kept; weights edf / (2 model^2),
/// iterated. Feasible: every coefficient > 0 and the terms dominate in their physical order along
/// tau (quantization, white, flicker floor, random walk), so a slope -1 tail after a floor (the
/// decay of a vibration) is not read as quantization.
AllanModel fit_allan_model(const AllanCurve& c, std::size_t first = 0);
/// RMS of (ln avar - ln model) / sqrt(2 / edf) over the points from first on.
double fit_rms_z(const AllanCurve& c, const AllanModel& m, std::size_t first = 0);
/// Sets every point's noise type to the model's dominant one and recomputes edf and interval.
void set_dominant_noise(AllanCurve& c, const AllanModel& m);

struct NoiseTerm {
  bool supported = false;
  double value = 0.0;  ///< the reading (supported), else the 95% upper bound (0: none)
  double lo = 0.0;     ///< confidence interval (supported)
  double hi = 0.0;
  double read_tau_s = 0.0;  ///< the tau it was read at
  std::string note;         ///< how it was read, or why the span does not support it
};

struct NoiseReading {
  AllanModel model;
  NoiseTerm white;     ///< N [u/sqrt(s)]
  NoiseTerm bias;      ///< B [u/s]
  NoiseTerm rate_rw;   ///< K [u/s/sqrt(s)]
  double floor_tau_s = 0.0;  ///< tau of the fitted curve's minimum within the span
  double fit_from_tau_s = 0.0;  ///< the fit (and every reading) uses the points from this tau on
  double fit_rms_z = 0.0;       ///< RMS of (ln avar - ln model) / sd(ln avar) over those points
  bool fit_adequate = false;    ///< fit_rms_z <= kAdequateRmsZ
};

/// The model describes the curve from fit_from_tau_s when the RMS log deviation in units of each
/// point's own sd(ln avar) = sqrt(2 / edf) is at most this (points overlap, so they are correlated:
/// a lenient limit).
constexpr double kAdequateRmsZ = 2.0;

/// Fits the model, sets the dominant noise types, and reads N, B and K (see the header comment).
/// The fit range starts at the shortest tau from which the model is adequate (at least 5 points
/// left; a sensor's low-pass filter or a vibration shapes the short taus with features the model
/// lacks); without any, the range with the smallest RMS deviation, and the readings say so.
NoiseReading read_noise_terms(AllanCurve& c);

/// The coefficient relating the flicker floor to B: adev_floor = 0.664 B (sqrt(2 ln2 / pi)).
constexpr double kFlickerFloorFactor = 0.6643;

}  // namespace tools
