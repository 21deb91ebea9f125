// Chi-square quantiles and tail probabilities: the one definition used by the EKF's NIS test, the
// Monte Carlo's NEES bounds and the diagnosis' Wald tests (fsw rules: no heap, bounded loops).
#pragma once

#include <cmath>

namespace fsw {

/// Chi-square quantile with k degrees of freedom at the standard-normal quantile z (the upper
/// quantile for z > 0, the lower for z < 0), by the Wilson-Hilferty cube-root approximation
/// k (1 - 2/(9k) + z sqrt(2/(9k)))^3: within 1% for k >= 10, within a few % for k >= 3.
inline double chi2_quantile_wilson_hilferty(double k, double z) {
  const double a = 2.0 / (9.0 * k);
  const double c = 1.0 - a + z * std::sqrt(a);
  return k * c * c * c;
}

/// P(X > x) for X ~ chi-square with 1 degree of freedom (exact: erfc(sqrt(x / 2))).
inline double chi2_1_survival(double x) { return x <= 0.0 ? 1.0 : std::erfc(std::sqrt(0.5 * x)); }

/// x with P(X > x) = p for 1 degree of freedom, by bisection on chi2_1_survival (bounded: the
/// bracket stops growing where erfc underflows, 200 halvings reach machine precision). Infinity
/// for p <= 0, 0 for p >= 1.
inline double chi2_1_upper_quantile(double p) {
  if (!(p > 0.0)) return INFINITY;
  if (p >= 1.0) return 0.0;
  double lo = 0.0, hi = 1.0;
  for (int i = 0; i < 64 && chi2_1_survival(hi) > p; ++i) hi *= 2.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (chi2_1_survival(mid) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

/// P(X > x) for X ~ chi-square with k degrees of freedom, exact for integer k: the regularised
/// upper incomplete gamma function Q(k/2, x/2) by its finite sums (bounded: k/2 terms).
inline double chi2_survival(double x, int k) {
  if (k <= 1) return chi2_1_survival(x);
  if (x <= 0.0) return 1.0;
  const double h = 0.5 * x;
  double sum = 0.0;
  if (k % 2 == 0) {
    double term = 1.0;  // h^i / i!
    for (int i = 0; i < k / 2; ++i) {
      sum += term;
      term *= h / (i + 1);
    }
    return std::exp(-h) * sum;
  }
  double term = std::sqrt(h) / 0.88622692545275801;  // h^(1/2) / Gamma(3/2)
  for (int i = 0; i < (k - 1) / 2; ++i) {
    sum += term;
    term *= h / (i + 1.5);
  }
  return chi2_1_survival(x) + std::exp(-h) * sum;
}

/// x with P(X > x) = p for k degrees of freedom (bisection on chi2_survival, bounded).
inline double chi2_upper_quantile(double p, int k) {
  if (k <= 1) return chi2_1_upper_quantile(p);
  if (!(p > 0.0)) return INFINITY;
  if (p >= 1.0) return 0.0;
  double lo = 0.0, hi = static_cast<double>(k);
  for (int i = 0; i < 64 && chi2_survival(hi, k) > p; ++i) hi *= 2.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (chi2_survival(mid, k) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace fsw
