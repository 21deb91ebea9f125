#include "tools/gps_ephemeris.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <vector>

#include "fsw/gnss.hpp"
#include "fsw/gps_orbit.hpp"

namespace tools {
namespace {

constexpr double kGM = fsw::kGpsGM_m3ps2;
constexpr double kWe = fsw::kGpsOmegaE_radps;
constexpr double kRelF = -4.442807633e-10;  // IS-GPS-200 relativistic constant F [s/m^(1/2)]
constexpr double kWeek = fsw::kSecondsPerWeek;

double wrap_pi(double a) {
  a = std::remainder(a, 2.0 * fsw::kPi);
  return a;
}

// Parameters of the fit, in this order.
enum Param { kE = 0, kI0, kOmegaDot, kSqrtA, kOmega0, kArgPerigee, kM0, kParams };

void set_params(fsw::GpsAlmanac& a, const double* p) {
  a.eccentricity = p[kE];
  a.inclination_rad = p[kI0];
  a.omega_dot_radps = p[kOmegaDot];
  a.sqrt_a_sqrtm = p[kSqrtA];
  a.omega0_rad = p[kOmega0];
  a.arg_perigee_rad = p[kArgPerigee];
  a.mean_anomaly_rad = p[kM0];
}

}  // namespace

bool ephemeris_valid(const GpsEphemeris& e) {
  const double v[] = {e.toe_s,   e.toc_s,   e.af0_s,        e.af1_sps,      e.af2_sps2,   e.crs_m,
                      e.crc_m,   e.cus_rad, e.cuc_rad,      e.cis_rad,      e.cic_rad,    e.delta_n_radps,
                      e.m0_rad,  e.eccentricity, e.sqrt_a_sqrtm, e.omega0_rad, e.i0_rad, e.arg_perigee_rad,
                      e.omega_dot_radps, e.idot_radps, e.tgd_s};
  for (double x : v)
    if (!std::isfinite(x)) return false;
  return e.prn >= 1 && e.prn <= fsw::kMaxGpsPrn && e.week >= 0 && e.eccentricity >= 0.0 && e.eccentricity < 0.1 &&
         e.sqrt_a_sqrtm > 4000.0 && e.sqrt_a_sqrtm < 6000.0 && e.toe_s >= 0.0 && e.toe_s < kWeek;
}

double ephemeris_tk_s(const GpsEphemeris& eph, int week, double tow_s) {
  return static_cast<double>(week - eph.week) * kWeek + (tow_s - eph.toe_s);
}

void ephemeris_position_clock(const GpsEphemeris& eph, int week, double tow_s, fsw::Vec3& r_ecef_m, double& clock_s) {
  const double a = eph.sqrt_a_sqrtm * eph.sqrt_a_sqrtm;
  const double tk = ephemeris_tk_s(eph, week, tow_s);
  const double n = std::sqrt(kGM / (a * a * a)) + eph.delta_n_radps;
  const double m = eph.m0_rad + n * tk;
  const double e = eph.eccentricity;
  const double ea = fsw::eccentric_anomaly_rad(m, e);
  const double nu = std::atan2(std::sqrt(1.0 - e * e) * std::sin(ea), std::cos(ea) - e);
  const double phi = nu + eph.arg_perigee_rad;
  const double s2 = std::sin(2.0 * phi), c2 = std::cos(2.0 * phi);
  const double u = phi + eph.cus_rad * s2 + eph.cuc_rad * c2;
  const double r = a * (1.0 - e * std::cos(ea)) + eph.crs_m * s2 + eph.crc_m * c2;
  const double inc = eph.i0_rad + eph.cis_rad * s2 + eph.cic_rad * c2 + eph.idot_radps * tk;
  const double node = eph.omega0_rad + (eph.omega_dot_radps - kWe) * tk - kWe * eph.toe_s;
  const double xp = r * std::cos(u), yp = r * std::sin(u);
  const double cn = std::cos(node), sn = std::sin(node), ci = std::cos(inc), si = std::sin(inc);
  r_ecef_m = fsw::Vec3(xp * cn - yp * ci * sn, xp * sn + yp * ci * cn, yp * si);
  const double dt = static_cast<double>(week - eph.week) * kWeek + (tow_s - eph.toc_s);
  clock_s = eph.af0_s + eph.af1_sps * dt + eph.af2_sps2 * dt * dt + kRelF * e * eph.sqrt_a_sqrtm * std::sin(ea) -
            eph.tgd_s;
}

namespace {

/// The ephemeris' Keplerian elements moved to the almanac's toa (toa_week, toa): the fit's start.
void initial_elements(const GpsEphemeris& eph, int toa_week, double toa, double* p) {
  const double tk0 = ephemeris_tk_s(eph, toa_week, toa);
  const double a0 = eph.sqrt_a_sqrtm * eph.sqrt_a_sqrtm;
  p[kE] = eph.eccentricity;
  p[kI0] = eph.i0_rad + eph.idot_radps * tk0;
  p[kOmegaDot] = eph.omega_dot_radps;
  p[kSqrtA] = eph.sqrt_a_sqrtm;
  p[kOmega0] = wrap_pi(eph.omega0_rad + (eph.omega_dot_radps - kWe) * tk0 + kWe * (toa - eph.toe_s));
  p[kArgPerigee] = eph.arg_perigee_rad;
  p[kM0] = wrap_pi(eph.m0_rad + (std::sqrt(kGM / (a0 * a0 * a0)) + eph.delta_n_radps) * tk0);
}

/// The ephemeris' positions and clock at the fit epochs: about 60 over the window (2 .. 30 s
/// apart), ends included; times in seconds of start_week (not normalised).
struct FitEpochs {
  int start_week = 0;
  std::vector<double> t;
  std::vector<fsw::Vec3> r;
  std::vector<double> clock;
  int size() const { return static_cast<int>(t.size()); }
};

FitEpochs fit_epochs(const GpsEphemeris& eph, int start_week, double start_tow_s, double span_s) {
  const int n_fit = std::clamp(static_cast<int>(std::ceil(span_s / 2.0)), 2, 60) + 1;
  FitEpochs f;
  f.start_week = start_week;
  f.t.resize(static_cast<std::size_t>(n_fit));
  f.r.resize(f.t.size());
  f.clock.resize(f.t.size());
  for (int j = 0; j < n_fit; ++j) {
    const auto u = static_cast<std::size_t>(j);
    f.t[u] = start_tow_s + span_s * j / (n_fit - 1);
    ephemeris_position_clock(eph, start_week, f.t[u], f.r[u], f.clock[u]);
  }
  return f;
}

/// The almanac alm with orbit elements q against the ephemeris positions of the fit epochs.
void orbit_residuals(const fsw::GpsAlmanac& alm, const double* q, const FitEpochs& f, Eigen::VectorXd& res) {
  fsw::GpsAlmanac a = alm;
  set_params(a, q);
  res.resize(3 * f.size());
  for (int j = 0; j < f.size(); ++j) {
    fsw::Vec3 r, v;
    const fsw::GpsTime g = fsw::gps_time(f.start_week, f.t[static_cast<std::size_t>(j)]);
    fsw::satellite_pv_ecef(a, g.week, g.tow_s, r, v);
    res.segment<3>(3 * j) = r - f.r[static_cast<std::size_t>(j)];
  }
}

/// Gauss-Newton on the orbit elements p (from their initial values; at most 30 iterations, a step
/// kept only when it does not raise the residual); sets fit.iterations and fit.converged.
void fit_orbit(const fsw::GpsAlmanac& alm, const FitEpochs& f, double* p, AlmanacFit& fit) {
  // Finite-difference steps (central differences), about 1 mm of orbit each.
  const double h[kParams] = {1e-10, 1e-10, 1e-14, 1e-7, 1e-10, 1e-10, 1e-10};
  Eigen::VectorXd res, rp, rm;
  orbit_residuals(alm, p, f, res);
  for (int it = 0; it < 30; ++it) {
    fit.iterations = it + 1;
    Eigen::MatrixXd J(3 * f.size(), kParams);
    for (int k = 0; k < kParams; ++k) {
      double q[kParams];
      std::copy(p, p + kParams, q);
      q[k] = p[k] + h[k];
      orbit_residuals(alm, q, f, rp);
      q[k] = p[k] - h[k];
      orbit_residuals(alm, q, f, rm);
      J.col(k) = (rp - rm) / (2.0 * h[k]);
    }
    // Column scaling, then a rank-revealing minimum-norm solve (e, omega and M0 are nearly
    // degenerate for near-circular orbits over a short arc).
    Eigen::VectorXd scale(kParams);
    for (int k = 0; k < kParams; ++k) scale[k] = J.col(k).norm() > 0.0 ? 1.0 / J.col(k).norm() : 1.0;
    const Eigen::MatrixXd Js = J * scale.asDiagonal();
    Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(Js);
    cod.setThreshold(1e-10);
    const Eigen::VectorXd dx = -(scale.asDiagonal() * cod.solve(res)).eval();
    double q[kParams];
    for (int k = 0; k < kParams; ++k) q[k] = p[k] + dx[k];
    if (q[kE] < 0.0) {  // the same orbit with e > 0: perigee and mean anomaly half a turn on
      q[kE] = -q[kE];
      q[kArgPerigee] += fsw::kPi;
      q[kM0] += fsw::kPi;
    }
    Eigen::VectorXd res_new;
    orbit_residuals(alm, q, f, res_new);
    const double before = res.norm(), after = res_new.norm();
    if (after <= before) {
      std::copy(q, q + kParams, p);
      res = res_new;
    }
    if (!(after < before) || before - after < 1e-6 * before + 1e-6) {
      fit.converged = std::isfinite(res.norm());
      break;
    }
  }
}

/// af0 + af1 (t - toa) of alm by least squares on the ephemeris clock at the fit epochs.
void fit_clock(const FitEpochs& f, fsw::GpsAlmanac& alm) {
  Eigen::MatrixXd A(f.size(), 2);
  Eigen::VectorXd b(f.size());
  for (int j = 0; j < f.size(); ++j) {
    const fsw::GpsTime g = fsw::gps_time(f.start_week, f.t[static_cast<std::size_t>(j)]);
    A(j, 0) = 1.0;
    A(j, 1) = fsw::time_from_applicability_s(alm, g.week, g.tow_s);
    b[j] = f.clock[static_cast<std::size_t>(j)];
  }
  const Eigen::Vector2d x = A.colPivHouseholderQr().solve(b);
  alm.af0_s = x[0];
  alm.af1_sps = x[1];
}

/// The fitted almanac's errors against the ephemeris on a finer grid than the fit's (every ~1 s,
/// at most 2000 epochs): fit.samples and the worst and RMS errors.
void evaluate_fit(const GpsEphemeris& eph, int start_week, double start_tow_s, double span_s, AlmanacFit& fit) {
  const fsw::GpsAlmanac& alm = fit.almanac;
  const int n_eval = std::clamp(static_cast<int>(std::ceil(span_s)), 10, 2000) + 1;
  double sum2 = 0.0;
  for (int j = 0; j < n_eval; ++j) {
    const fsw::GpsTime g = fsw::gps_time(start_week, start_tow_s + span_s * j / (n_eval - 1));
    const int w = g.week;
    const double t = g.tow_s;
    fsw::Vec3 r_e, r_p, r_m, r_a, v_a;
    double c_e = 0.0, c_dummy = 0.0;
    ephemeris_position_clock(eph, w, t, r_e, c_e);
    constexpr double kH = 0.01;
    ephemeris_position_clock(eph, w, t + kH, r_p, c_dummy);
    ephemeris_position_clock(eph, w, t - kH, r_m, c_dummy);
    const fsw::Vec3 v_e = (r_p - r_m) / (2.0 * kH);
    fsw::satellite_pv_ecef(alm, w, t, r_a, v_a);
    const double c_a = fsw::satellite_clock_bias_s(alm, w, t);
    const double dp = (r_a - r_e).norm();
    sum2 += dp * dp;
    fit.max_pos_err_m = std::max(fit.max_pos_err_m, dp);
    fit.max_clock_err_m = std::max(fit.max_clock_err_m, fsw::kSpeedOfLight_mps * std::abs(c_a - c_e));
    fit.max_vel_err_mps = std::max(fit.max_vel_err_mps, (v_a - v_e).norm());
  }
  fit.samples = n_eval;
  fit.rms_pos_err_m = std::sqrt(sum2 / n_eval);
}

}  // namespace

AlmanacFit fit_almanac(const GpsEphemeris& eph, int start_week, double start_tow_s, double span_s) {
  AlmanacFit fit;
  span_s = std::max(span_s, 1.0);
  // toa: the window's centre, a whole second.
  const fsw::GpsTime toa_time = fsw::gps_time(start_week, std::round(start_tow_s + 0.5 * span_s));
  const int toa_week = toa_time.week;
  const double toa = toa_time.tow_s;
  fsw::GpsAlmanac& alm = fit.almanac;
  alm.prn = eph.prn;
  alm.health = eph.health;
  alm.toa_s = toa;
  alm.week_mod_1024 = toa_week % 1024;

  double p[kParams];
  initial_elements(eph, toa_week, toa, p);
  const FitEpochs epochs = fit_epochs(eph, start_week, start_tow_s, span_s);
  fit_orbit(alm, epochs, p, fit);
  p[kOmega0] = wrap_pi(p[kOmega0]);
  p[kArgPerigee] = wrap_pi(p[kArgPerigee]);
  p[kM0] = wrap_pi(p[kM0]);
  set_params(alm, p);
  fit_clock(epochs, alm);
  evaluate_fit(eph, start_week, start_tow_s, span_s, fit);
  if (!std::isfinite(fit.max_pos_err_m) || !std::isfinite(fit.max_clock_err_m)) fit.converged = false;
  return fit;
}

}  // namespace tools
