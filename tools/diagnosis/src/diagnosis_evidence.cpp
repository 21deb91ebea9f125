#include "tools/diagnosis_evidence.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

namespace tools {
namespace {

using fsw::Effect;

/// Least-squares line tag = a + b n over the counter pairs.
void fit_counter(RecordingEvidence& ev, const std::vector<std::pair<double, std::int32_t>>& pairs) {
  if (pairs.size() < 100) return;
  const double n0 = pairs.front().second, t0 = pairs.front().first;
  double sn = 0, st = 0, snn = 0, snt = 0;
  for (const auto& p : pairs) {
    const double n = p.second - n0, t = p.first - t0;
    sn += n;
    st += t;
    snn += n * n;
    snt += n * t;
  }
  const double m = static_cast<double>(pairs.size());
  const double den = m * snn - sn * sn;
  if (!(den > 0.0)) return;
  const double b = (m * snt - sn * st) / den, a = (st - b * sn) / m;
  if (!(b > 0.0)) return;
  const double rate = std::round(1.0 / b);
  if (!(rate >= 1.0)) return;
  double ss = 0.0;
  for (const auto& p : pairs) {
    const double r = (p.first - t0) - (a + b * (p.second - n0));
    ss += r * r;
  }
  // A counter that is a sample clock puts every tag within a fraction of a period of its line (the
  // walk's counter, a line number of a file mixing streams, sat 0.13 s RMS off at "152 Hz"): else it
  // is no clock, and says nothing about the drift.
  if (!(std::sqrt(ss / m) <= kCounterMaxResidualPeriods / rate)) {
    ev.counter_note = "the IMU counter is not a regular sample clock (tags " + std::to_string(std::sqrt(ss / m)) +
                      " s RMS off a line through it): not used";
    return;
  }
  ev.counter_samples = static_cast<int>(pairs.size());
  ev.counter_rate_hz = rate;
  ev.counter_stretch_ppm = (b * rate - 1.0) * 1e6;
  ev.counter_residual_rms_s = std::sqrt(ss / m);
}

/// The import summary beside the log, if it is one and has a clock pair.
void read_clock_fit(RecordingEvidence& ev, const std::string& log_path) {
  const std::string path = log_path + ".json";
  std::ifstream in(path);
  if (!in) return;  // no summary: no such evidence
  ev.summary_path = path;
  nlohmann::json j;
  try {
    in >> j;
  } catch (const std::exception& e) {
    ev.summary_note = "not JSON (" + std::string(e.what()) + "): not used";
    return;
  }
  if (j.is_object() && j.contains("imu") && j["imu"].is_object() && j["imu"].contains("seconds_per_imu_second") &&
      j["imu"]["seconds_per_imu_second"].is_number()) {
    ev.has_tick_ratio = true;
    ev.tick_stretch_ppm = (j["imu"]["seconds_per_imu_second"].get<double>() - 1.0) * 1e6;
  }
  if (!j.is_object() || !j.contains("time_fit") || !j["time_fit"].is_object()) {
    ev.summary_note = "no time_fit (no clock pair in this recording's import)";
    return;
  }
  const nlohmann::json& f = j["time_fit"];
  if (!f.contains("drift_ppm") || !f["drift_ppm"].is_number()) {
    ev.summary_note = "time_fit without a numeric drift_ppm: not used";
    return;
  }
  ev.has_clock_fit = true;
  ev.clock_fit_drift_ppm = f["drift_ppm"].get<double>();
  if (f.contains("residual_rms_s") && f["residual_rms_s"].is_number()) ev.clock_fit_residual_rms_s = f["residual_rms_s"].get<double>();
}

double correlation(const std::vector<double>& a, const std::vector<double>& b) {
  const double n = static_cast<double>(a.size());
  if (a.size() < 10) return 0.0;
  double ma = 0, mb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ma += a[i];
    mb += b[i];
  }
  ma /= n;
  mb /= n;
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return saa > 0.0 && sbb > 0.0 ? sab / std::sqrt(saa * sbb) : 0.0;
}

}  // namespace

double CumulativeRate::at(double x) const {
  std::size_t hint = 0;
  return at(x, hint);
}

double CumulativeRate::at(double x, std::size_t& hint) const {
  if (t.empty()) return 0.0;
  if (x <= t.front()) return c.front();
  if (x >= t.back()) return c.back();
  // k = the first tag after x (std::upper_bound over all of t). With t[hint - 1] <= x every tag
  // before hint is <= x, so k >= hint: searched in a window from hint, then beyond it.
  std::size_t k = 0;
  if (hint >= 1 && hint < t.size() && t[hint - 1] <= x) {
    const std::size_t end = std::min(t.size(), hint + kWindow);
    k = static_cast<std::size_t>(std::upper_bound(t.begin() + static_cast<std::ptrdiff_t>(hint),
                                                  t.begin() + static_cast<std::ptrdiff_t>(end), x) - t.begin());
    if (k == end && end < t.size())
      k = static_cast<std::size_t>(std::upper_bound(t.begin() + static_cast<std::ptrdiff_t>(end), t.end(), x) - t.begin());
  } else {
    k = static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), x) - t.begin());
  }
  hint = k;
  const double u = (x - t[k - 1]) / (t[k] - t[k - 1]);
  return c[k - 1] + u * (c[k] - c[k - 1]);
}

void reference_lag(RecordingEvidence& ev, const RecordedData& data) {
  const std::vector<TruthPoint>& tr = data.truth;
  if (tr.size() < 50 || data.imu.size() < 100) return;
  const bool attitude = std::all_of(tr.begin(), tr.end(), [](const TruthPoint& p) { return p.has_attitude; });
  // The reference's rate magnitude per interval [t_k, t_k+1] (midpoint samples).
  std::vector<double> t0, t1, ref;
  for (std::size_t k = 0; k + 1 < tr.size(); ++k) {
    const double dt = tr[k + 1].t_s - tr[k].t_s;
    if (!(dt > 0.0) || dt > 1.0) continue;
    double w = 0.0;
    if (attitude) {
      w = fsw::rotvec_from_quat(tr[k].q_b_n.conjugate() * tr[k + 1].q_b_n).norm() / dt;
    } else {
      const fsw::Vec3 &v0 = tr[k].vel_enu_mps, &v1 = tr[k + 1].vel_enu_mps;
      if (std::hypot(v0.x(), v0.y()) < 2.0 || std::hypot(v1.x(), v1.y()) < 2.0) continue;  // no course at rest
      double d = std::atan2(v1.x(), v1.y()) - std::atan2(v0.x(), v0.y());
      d = std::remainder(d, 2.0 * fsw::kPi);
      w = std::abs(d) / dt;
    }
    t0.push_back(tr[k].t_s);
    t1.push_back(tr[k + 1].t_s);
    ref.push_back(w);
  }
  if (ref.size() < 50) return;
  CumulativeRate cum;
  cum.t.reserve(data.imu.size() + 1);
  cum.c.reserve(data.imu.size() + 1);
  double c = 0.0;
  for (const fsw::ImuSample& s : data.imu) {
    if (!cum.t.empty() && !(s.t_s > cum.t.back())) continue;
    if (cum.t.empty()) {
      cum.t.push_back(s.t_s - s.dt_s);
      cum.c.push_back(0.0);
    }
    c += s.dtheta_rad.norm();
    cum.t.push_back(s.t_s);
    cum.c.push_back(c);
  }
  const double lo_t = cum.t.front() + kMaxReferenceLag_s, hi_t = cum.t.back() - kMaxReferenceLag_s;
  const auto corr_at = [&](double lag) {
    std::vector<double> a, b;
    std::size_t hint0 = 0, hint1 = 0;  // the reference's times ascend: each lookup starts at the last
    for (std::size_t k = 0; k < ref.size(); ++k) {
      if (t0[k] < lo_t || t1[k] > hi_t) continue;
      a.push_back(ref[k]);
      b.push_back((cum.at(t1[k] + lag, hint1) - cum.at(t0[k] + lag, hint0)) / (t1[k] - t0[k]));
    }
    return std::make_pair(correlation(a, b), static_cast<int>(a.size()));
  };
  // Coarse grid, then a finer one about the best lag, then the parabola's vertex.
  double best = 0.0, best_r = -2.0;
  int n_best = 0;
  for (double step : {0.01, 0.001}) {
    const double centre = best;
    const double reach = step == 0.01 ? kMaxReferenceLag_s : 0.02;
    for (double lag = centre - reach; lag <= centre + reach + 1e-12; lag += step) {
      const auto r = corr_at(lag);
      if (r.first > best_r) {
        best_r = r.first;
        best = lag;
        n_best = r.second;
      }
    }
  }
  const double h = 0.001, ym = corr_at(best - h).first, yp = corr_at(best + h).first;
  const double curv = ym - 2.0 * best_r + yp;
  if (curv < 0.0) best += std::clamp(0.5 * h * (ym - yp) / curv, -h, h);
  ev.has_reference_lag = best_r > 0.3;  // below: no usable correlation (a straight, level flight)
  ev.reference_kind = attitude ? "attitude" : "course";
  ev.reference_lag_s = best;
  ev.reference_correlation = best_r;
  ev.reference_samples = n_best;
}

RecordingEvidence recording_evidence(const RecordedData& data, const std::string& log_path) {
  RecordingEvidence ev;
  fit_counter(ev, data.imu_counter_tags);
  if (!log_path.empty()) read_clock_fit(ev, log_path);
  reference_lag(ev, data);
  return ev;
}

void check_findings(RecordingEvidence& ev, const std::vector<Finding>& findings) {
  ev.checks.clear();
  const auto far = [](const Finding& f, double value, double tol) {
    return f.interval.lo > value + tol || f.interval.hi < value - tol;
  };
  for (const Finding& f : findings) {
    EvidenceCheck c;
    c.finding = std::string(fsw::effect_info(f.effect).name) + (f.component.empty() ? "" : "." + f.component);
    c.unit = f.unit;
    c.finding_estimate = f.estimate;
    c.finding_lo = f.interval.lo;
    c.finding_hi = f.interval.hi;
    if (f.effect == Effect::kImuClockDrift) {
      if (ev.counter_samples > 0) {
        EvidenceCheck k = c;
        k.source = "the IMU's own sample counter against its time tags (" + std::to_string(ev.counter_samples) +
                   " samples, nominal " + std::to_string(static_cast<int>(ev.counter_rate_hz)) + " Hz)";
        k.evidence = ev.counter_stretch_ppm;
        k.tolerance = kCounterTolerance_ppm;
        k.contradicts = far(f, k.evidence, k.tolerance);
        k.note = "the tags' stretch against the sensor's sample clock, if the sensor samples at its nominal rate "
                 "(an oscillator within the tolerance)";
        ev.checks.push_back(k);
      }
      if (ev.has_tick_ratio) {
        EvidenceCheck k = c;
        k.source = "the import's mapping of the IMU's own tick (imu.seconds_per_imu_second of " + ev.summary_path + ")";
        k.evidence = ev.tick_stretch_ppm;
        k.tolerance = kCounterTolerance_ppm;
        k.contradicts = far(f, k.evidence, k.tolerance);
        k.note = "the tags' stretch against the IMU's tick records, if the IMU's oscillator keeps GPS time within the "
                 "tolerance";
        ev.checks.push_back(k);
      }
      if (ev.has_clock_fit) {
        EvidenceCheck k = c;
        k.source = "the import's clock pair (time_fit of " + ev.summary_path + ")";
        k.evidence = -ev.clock_fit_drift_ppm;
        k.tolerance = kClockFitTolerance_ppm;
        k.contradicts = far(f, 0.0, k.tolerance) && far(f, k.evidence, k.tolerance);
        char b[200];
        std::snprintf(b, sizeof b,
                      "the local clock drifts %+.2f ppm against GPS: IMU tags mapped through the fit keep ~0, tags "
                      "left on the local clock %+.2f ppm",
                      ev.clock_fit_drift_ppm, -ev.clock_fit_drift_ppm);
        k.note = b;
        ev.checks.push_back(k);
      }
    }
    if (f.effect == Effect::kImuGnssTimeOffset && ev.has_reference_lag) {
      EvidenceCheck k = c;
      char b[160];
      std::snprintf(b, sizeof b, "the reference's %s rate against the IMU's gyro rate (correlation %.3f over %d intervals)",
                    ev.reference_kind.c_str(), ev.reference_correlation, ev.reference_samples);
      k.source = b;
      k.evidence = ev.reference_lag_s;
      k.tolerance = 0.02;
      k.contradicts = far(f, k.evidence, k.tolerance);
      k.note = "the IMU tags' lag behind the reference's time (a reference on GNSS time: RTK; an autopilot's "
               "estimate adds its own filter lag)";
      ev.checks.push_back(k);
    }
  }
}

}  // namespace tools
