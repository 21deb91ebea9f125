#include "tools/allan.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>
#include <stdexcept>

namespace tools {

const char* to_string(PowerLawNoise n) {
  switch (n) {
    case PowerLawNoise::kWhitePhase: return "white_phase";
    case PowerLawNoise::kFlickerPhase: return "flicker_phase";
    case PowerLawNoise::kWhiteRate: return "white_rate";
    case PowerLawNoise::kFlickerRate: return "flicker_rate";
    case PowerLawNoise::kRandomWalkRate: return "random_walk_rate";
  }
  return "?";
}

double oadev_edf(PowerLawNoise noise, double n, double m) {
  if (n <= 2.0 * m || m < 1.0) return 0.0;
  switch (noise) {
    case PowerLawNoise::kWhitePhase: return (n + 1.0) * (n - 2.0 * m) / (2.0 * (n - m));
    case PowerLawNoise::kFlickerPhase: {
      const double a = std::log(std::max((n - 1.0) / (2.0 * m), 1.0));
      const double b = std::log(std::max((2.0 * m + 1.0) * (n - 1.0) / 4.0, 1.0));
      return std::exp(std::sqrt(a * b));
    }
    case PowerLawNoise::kWhiteRate:
      return (3.0 * (n - 1.0) / (2.0 * m) - 2.0 * (n - 2.0) / n) * 4.0 * m * m / (4.0 * m * m + 5.0);
    case PowerLawNoise::kFlickerRate:
      return m < 2.0 ? 2.0 * (n - 2.0) / (2.3 * n - 4.9) : 5.0 * n * n / (4.0 * m * (n + 3.0 * m));
    case PowerLawNoise::kRandomWalkRate:
      return (n - 2.0) / m * ((n - 1.0) * (n - 1.0) - 3.0 * m * (n - 1.0) + 4.0 * m * m) / ((n - 3.0) * (n - 3.0));
  }
  return 0.0;
}

double chi2_quantile(double edf, double p) {
  const boost::math::chi_squared_distribution<double> d(edf);
  return boost::math::quantile(d, p);
}

std::vector<long long> allan_factors(long long longest, int per_octave, const std::vector<long long>& extra,
                                     long long min_terms) {
  const long long max_m = (longest - min_terms) / 2;
  std::set<long long> ms;
  for (int k = 0;; ++k) {
    const long long m = std::llround(std::pow(2.0, static_cast<double>(k) / per_octave));
    if (m > max_m) break;
    ms.insert(m);
  }
  for (long long m : extra)
    if (m >= 1 && m <= max_m) ms.insert(m);
  return {ms.begin(), ms.end()};
}

namespace {

void set_interval(AllanPoint& p, const std::vector<long long>& seg, double confidence) {
  p.edf = 0.0;
  for (long long n : seg) p.edf += oadev_edf(p.noise, static_cast<double>(n), static_cast<double>(p.m));
  const double alpha = 1.0 - confidence;
  if (p.edf <= 0.0) {
    p.avar_lo = 0.0;
    p.avar_hi = std::numeric_limits<double>::infinity();
    return;
  }
  p.avar_lo = p.avar * p.edf / chi2_quantile(p.edf, 1.0 - alpha / 2.0);
  p.avar_hi = p.avar * p.edf / chi2_quantile(p.edf, alpha / 2.0);
}

}  // namespace

AllanCurve overlapping_allan(const std::vector<std::vector<double>>& segments, double tau0_s,
                             const std::vector<long long>& ms, double confidence) {
  if (!(tau0_s > 0.0)) throw std::invalid_argument("overlapping_allan: tau0 must be positive");
  AllanCurve c;
  c.tau0_s = tau0_s;
  c.confidence = confidence;
  for (const auto& s : segments) c.segment_points.push_back(static_cast<long long>(s.size()));
  for (long long m : ms) {
    AllanPoint p;
    p.m = m;
    p.tau_s = static_cast<double>(m) * tau0_s;
    double sum = 0.0;
    for (const auto& x : segments) {
      const long long n = static_cast<long long>(x.size());
      for (long long i = 0; i + 2 * m < n; ++i) {
        const double d = x[i + 2 * m] - 2.0 * x[i + m] + x[i];
        sum += d * d;
      }
      p.terms += std::max(0LL, n - 2 * m);
    }
    if (p.terms == 0) continue;
    p.avar = sum / (2.0 * p.tau_s * p.tau_s * static_cast<double>(p.terms));
    set_interval(p, c.segment_points, confidence);
    if (p.edf > 0.0) c.points.push_back(p);
  }
  return c;
}

PowerLawNoise AllanModel::dominant(double tau) const {
  const std::array<double, 4> t{q2 / (tau * tau), n2 / tau, b2, k2 * tau};
  const std::array<PowerLawNoise, 4> kind{PowerLawNoise::kWhitePhase, PowerLawNoise::kWhiteRate,
                                          PowerLawNoise::kFlickerRate, PowerLawNoise::kRandomWalkRate};
  return kind[static_cast<std::size_t>(std::max_element(t.begin(), t.end()) - t.begin())];
}

namespace {

double basis(int j, double tau) {
  switch (j) {
    case 0: return 1.0 / (tau * tau);
    case 1: return 1.0 / tau;
    case 2: return 1.0;
    default: return tau;
  }
}

int dominant_index(const std::array<double, 4>& th, double tau) {
  const std::array<double, 4> t{th[0] / (tau * tau), th[1] / tau, th[2], th[3] * tau};
  return static_cast<int>(std::max_element(t.begin(), t.end()) - t.begin());
}

/// One weighted fit of every subset of the terms on points [first, end); the feasible one with the
/// smallest cost.
AllanModel fit_once(const AllanCurve& c, std::size_t first, const std::vector<double>& w) {
  const int n = static_cast<int>(c.points.size() - first);
  double best_cost = std::numeric_limits<double>::infinity();
  std::array<double, 4> best{0, 0, 0, 0};
  for (int mask = 1; mask < 16; ++mask) {
    std::vector<int> cols;
    for (int j = 0; j < 4; ++j)
      if (mask & (1 << j)) cols.push_back(j);
    if (static_cast<int>(cols.size()) > n) continue;
    Eigen::MatrixXd A(n, static_cast<int>(cols.size()));
    Eigen::VectorXd b(n);
    for (int i = 0; i < n; ++i) {
      const AllanPoint& p = c.points[first + static_cast<std::size_t>(i)];
      const double sw = std::sqrt(w[first + static_cast<std::size_t>(i)]);
      for (std::size_t k = 0; k < cols.size(); ++k) A(i, static_cast<int>(k)) = sw * basis(cols[k], p.tau_s);
      b(i) = sw * p.avar;
    }
    // Column scaling: the basis spans many decades.
    Eigen::VectorXd scale = A.colwise().norm().transpose();
    for (int k = 0; k < scale.size(); ++k)
      if (scale(k) > 0.0) A.col(k) /= scale(k);
    const Eigen::VectorXd x = A.colPivHouseholderQr().solve(b);
    bool feasible = true;
    std::array<double, 4> th{0, 0, 0, 0};
    for (std::size_t k = 0; k < cols.size(); ++k) {
      const double v = x(static_cast<int>(k)) / scale(static_cast<int>(k));
      if (!(v > 0.0) || !std::isfinite(v)) feasible = false;
      th[static_cast<std::size_t>(cols[k])] = v;
    }
    // The terms must take over from one another in their physical order along tau.
    for (std::size_t i = first; feasible && i + 1 < c.points.size(); ++i)
      feasible = dominant_index(th, c.points[i].tau_s) <= dominant_index(th, c.points[i + 1].tau_s);
    if (!feasible) continue;
    const double cost = (A * x - b).squaredNorm();
    if (cost < best_cost) {
      best_cost = cost;
      best = th;
    }
  }
  AllanModel m;
  m.q2 = best[0];
  m.n2 = best[1];
  m.b2 = best[2];
  m.k2 = best[3];
  return m;
}

}  // namespace

AllanModel fit_allan_model(const AllanCurve& c, std::size_t first) {
  std::vector<double> w(c.points.size());
  for (std::size_t i = 0; i < w.size(); ++i) w[i] = c.points[i].edf / (2.0 * c.points[i].avar * c.points[i].avar);
  AllanModel m = fit_once(c, first, w);
  // Reweight with the model's variance (the measured one biases the fit towards low points).
  for (int it = 0; it < 4; ++it) {
    for (std::size_t i = 0; i < w.size(); ++i) {
      const double v = m.avar(c.points[i].tau_s);
      if (v > 0.0) w[i] = c.points[i].edf / (2.0 * v * v);
    }
    m = fit_once(c, first, w);
  }
  return m;
}

double fit_rms_z(const AllanCurve& c, const AllanModel& m, std::size_t first) {
  double s = 0.0;
  std::size_t n = 0;
  for (std::size_t i = first; i < c.points.size(); ++i) {
    const AllanPoint& p = c.points[i];
    const double v = m.avar(p.tau_s);
    if (!(v > 0.0) || !(p.edf > 0.0)) return std::numeric_limits<double>::infinity();
    const double z = std::log(p.avar / v) / std::sqrt(2.0 / p.edf);
    s += z * z;
    ++n;
  }
  return n > 0 ? std::sqrt(s / static_cast<double>(n)) : std::numeric_limits<double>::infinity();
}

void set_dominant_noise(AllanCurve& c, const AllanModel& m) {
  for (AllanPoint& p : c.points) {
    p.noise = m.dominant(p.tau_s);
    set_interval(p, c.segment_points, c.confidence);
  }
}

namespace {

std::string fmt_tau(double t) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g s", t);
  return b;
}

/// N from the white-dominated point nearest tau = 1 s (log distance).
NoiseTerm read_white(const AllanCurve& c, const AllanModel& m, std::size_t first) {
  NoiseTerm r;
  const AllanPoint* best = nullptr;
  for (std::size_t i = first; i < c.points.size(); ++i)
    if (const AllanPoint& p = c.points[i];
        m.dominant(p.tau_s) == PowerLawNoise::kWhiteRate &&
        (best == nullptr || std::abs(std::log(p.tau_s)) < std::abs(std::log(best->tau_s))))
      best = &p;
  if (best != nullptr) {
    const double others = m.avar(best->tau_s) - m.n2 / best->tau_s;
    const double v = best->tau_s * (best->avar - others);
    if (v > 0.0) {
      r.supported = true;
      r.read_tau_s = best->tau_s;
      r.value = std::sqrt(v);
      r.lo = std::sqrt(std::max(0.0, best->tau_s * (best->avar_lo - others)));
      r.hi = std::sqrt(best->tau_s * (best->avar_hi - others));
      r.note = std::abs(best->tau_s - 1.0) < 0.02
                   ? "adev at tau = 1 s on the slope -1/2 line"
                   : "read at tau = " + fmt_tau(best->tau_s) + " and carried along the slope -1/2 line to 1 s (white "
                     "noise does not dominate at 1 s within the span)";
      return r;
    }
  }
  r.note = "white rate noise dominates at no measured tau";
  for (const AllanPoint& p : c.points) {
    const double ub = std::sqrt(p.tau_s * p.avar_hi);
    if (r.value == 0.0 || ub < r.value) {
      r.value = ub;
      r.read_tau_s = p.tau_s;
    }
  }
  r.note += "; 95% upper bound from tau = " + fmt_tau(r.read_tau_s);
  return r;
}

/// K from the random-walk-dominated point whose reading is tightest (relative interval).
NoiseTerm read_rate_rw(const AllanCurve& c, const AllanModel& m, std::size_t first) {
  NoiseTerm r;
  double best_width = std::numeric_limits<double>::infinity();
  for (std::size_t i = first; i < c.points.size(); ++i) {
    const AllanPoint& p = c.points[i];
    if (m.dominant(p.tau_s) != PowerLawNoise::kRandomWalkRate) continue;
    const double others = m.avar(p.tau_s) - m.k2 * p.tau_s;
    const double k2 = 3.0 * (p.avar - others) / p.tau_s;
    // Significant only when even the interval's lower end exceeds the other terms there.
    if (!(k2 > 0.0) || !(p.avar_lo > others)) continue;
    const double width = (p.avar_hi - p.avar_lo) / (p.avar - others);
    if (width < best_width) {
      best_width = width;
      r.supported = true;
      r.read_tau_s = p.tau_s;
      r.value = std::sqrt(k2);
      r.lo = std::sqrt(std::max(0.0, 3.0 * (p.avar_lo - others) / p.tau_s));
      r.hi = std::sqrt(3.0 * (p.avar_hi - others) / p.tau_s);
    }
  }
  if (r.supported) {
    r.note = "read at tau = " + fmt_tau(r.read_tau_s) + " on the slope +1/2 line (K = adev at tau = 3 s)";
    return r;
  }
  r.note = "the curve does not rise with slope +1/2 within the span (longest tau " +
           fmt_tau(c.points.empty() ? 0.0 : c.points.back().tau_s) + ")";
  for (const AllanPoint& p : c.points) {
    const double ub = std::sqrt(3.0 * p.avar_hi / p.tau_s);
    if (r.value == 0.0 || ub < r.value) {
      r.value = ub;
      r.read_tau_s = p.tau_s;
    }
  }
  r.note += "; 95% upper bound from tau = " + fmt_tau(r.read_tau_s);
  return r;
}

/// B from the floor: the measured point nearest the fitted curve's minimum, / 0.664.
NoiseTerm read_bias(const AllanCurve& c, const AllanModel& m, std::size_t first, double& floor_tau) {
  NoiseTerm r;
  const double t0 = c.points[first].tau_s, t1 = c.points.back().tau_s;
  floor_tau = t0;
  for (int i = 0; i <= 400; ++i) {
    const double t = t0 * std::pow(t1 / t0, i / 400.0);
    if (m.avar(t) < m.avar(floor_tau)) floor_tau = t;
  }
  const AllanPoint* p = &c.points[first];
  for (std::size_t i = first; i < c.points.size(); ++i)
    if (std::abs(std::log(c.points[i].tau_s / floor_tau)) < std::abs(std::log(p->tau_s / floor_tau))) p = &c.points[i];
  // A floor is a floor only when the curve is seen falling into it within the fit range.
  bool descent = false;
  for (std::size_t i = first; i < c.points.size() && c.points[i].tau_s < floor_tau; ++i) {
    const PowerLawNoise d = m.dominant(c.points[i].tau_s);
    descent |= d == PowerLawNoise::kWhiteRate || d == PowerLawNoise::kWhitePhase;
  }
  if (m.dominant(floor_tau) == PowerLawNoise::kFlickerRate && descent) {
    r.supported = true;
    r.read_tau_s = p->tau_s;
    r.value = std::sqrt(p->avar) / kFlickerFloorFactor;
    r.lo = std::sqrt(p->avar_lo) / kFlickerFloorFactor;
    r.hi = std::sqrt(p->avar_hi) / kFlickerFloorFactor;
    r.note = "floor at tau = " + fmt_tau(p->tau_s) + " (the fitted curve's minimum), adev / 0.664";
    return r;
  }
  r.value = std::sqrt(p->avar_hi) / kFlickerFloorFactor;
  r.read_tau_s = p->tau_s;
  r.note = m.dominant(floor_tau) == PowerLawNoise::kFlickerRate
               ? "the fitted curve is flat from the start of the fit range (no descent into a floor seen)"
               : std::string("no flat part within the span: at the fitted curve's minimum (tau = ") + fmt_tau(floor_tau) +
                     ") " + to_string(m.dominant(floor_tau)) + " noise dominates";
  r.note += "; 95% upper bound adev_hi / 0.664 at tau = " + fmt_tau(p->tau_s);
  return r;
}

}  // namespace

NoiseReading read_noise_terms(AllanCurve& c) {
  NoiseReading r;
  if (c.points.size() < 2) {
    r.white.note = r.bias.note = r.rate_rw.note = "too few Allan points (the rest is too short)";
    return r;
  }
  // The fit range: the first start index from which the model is adequate (the intervals for the
  // noise types of that fit), else the one with the smallest deviation.
  const std::size_t min_points = 5;
  const std::size_t last_start = c.points.size() > min_points ? c.points.size() - min_points : 0;
  std::size_t first = 0;
  double best_z = std::numeric_limits<double>::infinity();
  AllanModel best;
  const AllanCurve white_only = c;
  for (std::size_t s = 0; s <= last_start; ++s) {
    AllanCurve t = white_only;
    AllanModel m = fit_allan_model(t, s);
    set_dominant_noise(t, m);
    m = fit_allan_model(t, s);
    set_dominant_noise(t, m);
    const double z = fit_rms_z(t, m, s);
    if (z < best_z) {
      best_z = z;
      best = m;
      first = s;
    }
    if (z <= kAdequateRmsZ) break;
  }
  r.model = best;
  set_dominant_noise(c, r.model);
  r.fit_from_tau_s = c.points[first].tau_s;
  r.fit_rms_z = best_z;
  r.fit_adequate = best_z <= kAdequateRmsZ;
  r.white = read_white(c, r.model, first);
  r.rate_rw = read_rate_rw(c, r.model, first);
  r.bias = read_bias(c, r.model, first, r.floor_tau_s);
  if (!r.fit_adequate) {
    char b[48];
    std::snprintf(b, sizeof b, "%.3g", best_z);
    const std::string why = std::string("; the model does not describe the curve (RMS deviation ") + b +
                            " sd from tau = " + fmt_tau(r.fit_from_tau_s) + ")";
    for (NoiseTerm* t : {&r.white, &r.bias, &r.rate_rw}) t->note += why;
  }
  return r;
}

}  // namespace tools
