#include "tools/noise.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "fsw/frames.hpp"
#include "fsw/gnss_pvt.hpp"
#include "fsw/gps_orbit.hpp"
#include "hal/lcm_log_sink.hpp"
#include "sim/rng.hpp"
#include "tools/number_text.hpp"
#include "import_common.hpp"  // median

namespace tools {
namespace {

using import_detail::median;

constexpr const char* kAxisNames[6] = {"gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z"};
constexpr double kRadpsToDegph = 1.0 / fsw::kDegPerHourToRadps;

/// The median of the k smallest values: the reference of a window statistic.
double quiet_reference(std::vector<double> v, std::size_t k) {
  if (v.empty()) return 0.0;
  k = std::clamp<std::size_t>(k, 1, v.size());
  std::partial_sort(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[(k - 1) / 2];
}


}  // namespace

NoiseInput read_noise_input(const std::string& path) {
  hal::LcmReplayConfig rc;
  rc.gnss_pvt_channel = hal::kLcmChannelGnssPvt;
  hal::LcmReplayReader reader;
  if (reader.open(path, rc) != hal::LcmLogStatus::kOk) throw std::runtime_error("cannot read " + path + ": " + reader.error());
  NoiseInput in;
  fsw::GpsAlmanacTable almanac;
  std::vector<SpeedFix> raw_speed, pvt_speed;
  fsw::InputEvent ev;
  while (reader.next(ev) == hal::LcmLogStatus::kOk) {
    switch (ev.kind) {
      case fsw::InputEvent::Kind::kImu: in.imu.push_back(ev.imu); break;
      case fsw::InputEvent::Kind::kAlmanac: (void)almanac.set(ev.almanac); break;
      case fsw::InputEvent::Kind::kGnssPvt:
        if (!in.have_position) {
          in.have_position = true;
          in.lat_rad = ev.pvt.llh.x();
          in.h_m = ev.pvt.llh.z();
        }
        if (ev.pvt.has_velocity)
          pvt_speed.push_back({ev.t_s, std::hypot(ev.pvt.vel_enu_mps.x(), ev.pvt.vel_enu_mps.y())});
        break;
      case fsw::InputEvent::Kind::kGnssRaw: {
        fsw::GnssEpoch ep;
        fsw::GnssConversionStats cs;
        fsw::GnssPvt fix;
        if (fsw::gnss_epoch_from_raw(ev.gnss, almanac, nullptr, ep, cs) != fsw::Status::kOk ||
            fsw::gnss_pvt(ep, fix) != fsw::Status::kOk) {
          ++in.raw_epochs_without_fix;
          break;
        }
        const fsw::Vec3 llh = fsw::llh_from_ecef(fix.r_ecef_m);
        const fsw::Vec3 v = fsw::C_n_e(llh.x(), llh.y()).transpose() * fix.v_ecef_mps;
        raw_speed.push_back({ev.t_s, std::hypot(v.x(), v.y())});
        if (!in.have_position) {
          in.have_position = true;
          in.lat_rad = llh.x();
          in.h_m = llh.z();
        }
        break;
      }
    }
  }
  const hal::LcmReplayStats& st = reader.stats();
  in.imu_rejected = st.imu.rejected();
  in.imu_counter_gaps = st.imu_counter_gaps;
  in.log_rejections = reader.log_stats().total_rejections();
  if (!pvt_speed.empty()) {
    in.speed = std::move(pvt_speed);
    in.speed_source = "GNSS_PVT";
  } else if (!raw_speed.empty()) {
    in.speed = std::move(raw_speed);
    in.speed_source = "GNSS_RAW";
  }
  if (in.imu.empty()) throw std::runtime_error(path + ": no IMU samples on channel IMU (sdins noise needs the IMU channel)");
  return in;
}

namespace {

/// Whether the GNSS says the window [t0, t1) is at rest: 1 at rest, 0 moving, -1 no solution near.
int gnss_rest(const std::vector<SpeedFix>& sp, double t0, double t1, const RestDetectorConfig& cfg) {
  auto it = std::lower_bound(sp.begin(), sp.end(), t0, [](const SpeedFix& s, double t) { return s.t_s < t; });
  bool any = false;
  for (auto j = it; j != sp.end() && j->t_s < t1; ++j) {
    any = true;
    if (j->ground_speed_mps > cfg.max_speed_mps) return 0;
  }
  if (any) return 1;
  // None inside: the nearest one within the age limit.
  const SpeedFix* near = nullptr;
  if (it != sp.end() && it->t_s - t1 <= cfg.speed_max_age_s) near = &*it;
  if (it != sp.begin() && t0 - std::prev(it)->t_s <= cfg.speed_max_age_s &&
      (near == nullptr || t0 - std::prev(it)->t_s < near->t_s - t1))
    near = &*std::prev(it);
  if (near == nullptr) return -1;
  return near->ground_speed_mps <= cfg.max_speed_mps ? 1 : 0;
}

}  // namespace

RestDetection detect_rest(const NoiseInput& in, const RestDetectorConfig& cfg) {
  RestDetection d;
  d.cfg = cfg;
  const std::vector<fsw::ImuSample>& imu = in.imu;
  std::vector<double> dts;
  for (const auto& s : imu) dts.push_back(s.dt_s);
  d.median_dt_s = median(dts);
  // Windows: [start, end) sample index ranges.
  std::vector<std::pair<std::size_t, std::size_t>> win;
  const double t_first = imu.front().t_s - imu.front().dt_s;
  for (std::size_t i = 0; i < imu.size();) {
    const double w0 = t_first + std::floor((imu[i].t_s - t_first) / cfg.window_s) * cfg.window_s;
    std::size_t j = i;
    while (j < imu.size() && imu[j].t_s < w0 + cfg.window_s) ++j;
    if (j == i) ++j;
    win.emplace_back(i, j);
    d.window_t_s.push_back(w0);
    i = j;
  }
  d.windows = win.size();
  for (const auto& [a, b] : win) {
    const double n = static_cast<double>(b - a);
    double sf = 0.0, sf2 = 0.0;
    fsw::Vec3 w = fsw::Vec3::Zero(), w2 = fsw::Vec3::Zero();
    for (std::size_t k = a; k < b; ++k) {
      const double f = (imu[k].dv_mps / imu[k].dt_s).norm();
      const fsw::Vec3 r = imu[k].dtheta_rad / imu[k].dt_s;
      sf += f;
      sf2 += f * f;
      w += r;
      w2 += r.cwiseProduct(r);
    }
    const double var_f = n > 1 ? std::max(0.0, (sf2 - sf * sf / n) / (n - 1)) : 0.0;
    fsw::Vec3 var_w = fsw::Vec3::Zero();
    if (n > 1) var_w = ((w2 - w.cwiseProduct(w) / n) / (n - 1)).cwiseMax(0.0);
    d.window_sf_std.push_back(std::sqrt(var_f));
    d.window_rate_std.push_back(std::sqrt(var_w.sum()));
  }
  const std::size_t k = static_cast<std::size_t>(std::max(1.0, std::round(cfg.min_rest_s / cfg.window_s / 2.0)));
  d.ref_sf_std_mps2 = quiet_reference(d.window_sf_std, k);
  d.ref_rate_std_radps = quiet_reference(d.window_rate_std, k);
  d.thr_sf_std_mps2 = cfg.threshold_factor * d.ref_sf_std_mps2;
  d.thr_rate_std_radps = cfg.threshold_factor * d.ref_rate_std_radps;
  d.gnss_used = cfg.use_gnss && !in.speed.empty();
  d.window_rest.assign(win.size(), 0);
  for (std::size_t w = 0; w < win.size(); ++w) {
    const bool quiet = d.window_sf_std[w] <= d.thr_sf_std_mps2 && d.window_rate_std[w] <= d.thr_rate_std_radps &&
                       win[w].second - win[w].first >= 2;
    if (quiet) ++d.windows_quiet_imu;
    int g = 1;
    if (d.gnss_used) {
      g = gnss_rest(in.speed, d.window_t_s[w], d.window_t_s[w] + cfg.window_s, cfg);
      if (quiet && g == 0) ++d.windows_moving_gnss;
      if (quiet && g < 0) ++d.windows_no_gnss;
    }
    d.window_rest[w] = quiet && g == 1 ? 1 : 0;
  }
  // Runs of rest windows, split at IMU gaps, trimmed, at least min_rest_s.
  const double max_gap = cfg.max_gap_factor * d.median_dt_s;
  auto close_run = [&](std::size_t first, std::size_t last) {  // sample indices, inclusive
    const double t0 = imu[first].t_s - imu[first].dt_s + cfg.margin_s, t1 = imu[last].t_s - cfg.margin_s;
    std::size_t a = first, b = last;
    while (a <= b && imu[a].t_s - imu[a].dt_s < t0) ++a;
    while (b > a && imu[b].t_s > t1) --b;
    if (a >= b) return;
    RestSegment s{a, b, imu[a].t_s - imu[a].dt_s, imu[b].t_s};
    if (s.duration_s() >= cfg.min_rest_s) d.segments.push_back(s);
  };
  bool open = false;
  std::size_t run_first = 0, run_last = 0;
  for (std::size_t w = 0; w < win.size(); ++w) {
    for (std::size_t i = win[w].first; i < win[w].second; ++i) {
      const bool rest = d.window_rest[w] == 1 && !(imu[i].dt_s > max_gap);
      if (rest && !open) {
        open = true;
        run_first = i;
      }
      if (!rest && open) {
        open = false;
        close_run(run_first, run_last);
      }
      if (rest) run_last = i;
    }
  }
  if (open) close_run(run_first, run_last);
  return d;
}

namespace {

/// The integral of component c of the increments over [first, last], linear in time between the
/// samples, at t_start + g tau0 for g = 0 .. while inside.
std::vector<double> phase_series(const std::vector<fsw::ImuSample>& imu, std::size_t first, std::size_t last,
                                 double tau0, int c) {
  std::vector<double> x;
  const double t_start = imu[first].t_s - imu[first].dt_s;
  double acc_prev = 0.0, t_prev = t_start;
  std::size_t i = first;
  for (long long g = 0;; ++g) {
    const double t = t_start + static_cast<double>(g) * tau0;
    while (i <= last && imu[i].t_s < t - 1e-9 * tau0) {
      acc_prev += c < 3 ? imu[i].dtheta_rad(c) : imu[i].dv_mps(c - 3);
      t_prev = imu[i].t_s;
      ++i;
    }
    if (i > last) {
      if (std::abs(t - t_prev) <= 1e-9 * tau0) x.push_back(acc_prev);
      break;
    }
    const double inc = c < 3 ? imu[i].dtheta_rad(c) : imu[i].dv_mps(c - 3);
    const double t0 = imu[i].t_s - imu[i].dt_s;  // the interval (t0, t_i] holds inc
    const double u = std::clamp((t - std::max(t0, t_prev)) / (imu[i].t_s - std::max(t0, t_prev)), 0.0, 1.0);
    x.push_back(acc_prev + u * inc);
  }
  return x;
}

}  // namespace

NoiseAnalysis analyse_noise(const std::vector<fsw::ImuSample>& imu, const std::vector<RestSegment>& segments) {
  NoiseAnalysis a;
  std::vector<double> dts;
  long long longest = 0;
  for (const RestSegment& s : segments) {
    for (std::size_t i = s.first; i <= s.last; ++i) dts.push_back(imu[i].dt_s);
    a.segment_s.push_back(s.duration_s());
    a.rest_s += s.duration_s();
  }
  if (dts.empty()) throw std::runtime_error("no rest segment: nothing to analyse");
  a.tau0_s = median(dts);
  for (const RestSegment& s : segments)
    longest = std::max(longest, static_cast<long long>(std::floor(s.duration_s() / a.tau0_s)) + 1);
  const std::vector<long long> ms =
      allan_factors(longest, 4, {std::llround(1.0 / a.tau0_s), std::llround(3.0 / a.tau0_s)});
  for (int c = 0; c < 6; ++c) {
    AxisNoise ax;
    ax.name = kAxisNames[c];
    ax.gyro = c < 3;
    std::vector<std::vector<double>> series;
    double sum = 0.0, span = 0.0;
    for (const RestSegment& s : segments) {
      series.push_back(phase_series(imu, s.first, s.last, a.tau0_s, c));
      for (std::size_t i = s.first; i <= s.last; ++i) sum += c < 3 ? imu[i].dtheta_rad(c) : imu[i].dv_mps(c - 3);
      span += s.duration_s();
    }
    ax.mean = sum / span;
    ax.curve = overlapping_allan(series, a.tau0_s, ms);
    ax.reading = read_noise_terms(ax.curve);
    a.axes.push_back(std::move(ax));
  }
  return a;
}

NoiseAnalysis analyse_simulated_rest(const sim::ImuErrors& errors, const std::vector<double>& segment_s, double tau0_s,
                                     double lat_rad, std::uint64_t seed) {
  sim::ImuModel model(errors, seed);
  // Level, north-aligned body (x north, y east, z down): Earth rate and gravity in body axes.
  const double g = fsw::normal_gravity_mps2(lat_rad, 0.0);
  const fsw::Vec3 w_b(fsw::wgs84::omega_ie_radps * std::cos(lat_rad), 0.0, -fsw::wgs84::omega_ie_radps * std::sin(lat_rad));
  const fsw::Vec3 f_b(0.0, 0.0, -g);
  std::vector<fsw::ImuSample> imu;
  std::vector<RestSegment> segs;
  double t = 0.0;
  for (double len : segment_s) {
    const long long n = static_cast<long long>(std::floor(len / tau0_s));
    RestSegment s;
    s.first = imu.size();
    for (long long k = 0; k < n; ++k) {
      sim::TruthSample ts;
      t += tau0_s;
      ts.t_s = t;
      ts.dt_s = tau0_s;
      ts.dtheta_rad = w_b * tau0_s;
      ts.dv_mps = f_b * tau0_s;
      imu.push_back(model.measure(ts));
    }
    s.last = imu.size() - 1;
    s.t_begin_s = imu[s.first].t_s - imu[s.first].dt_s;
    s.t_end_s = imu[s.last].t_s;
    segs.push_back(s);
    t += 10.0;  // the segments are separate runs of the same sensor (a gap between them)
  }
  return analyse_noise(imu, segs);
}

namespace {

struct Worst {
  double value = 0.0, lo = 0.0, hi = 0.0;
  std::string axis;
  bool supported = false;
};

/// The largest reading of a term over one triad (the filter has one value per triad).
Worst worst(const NoiseAnalysis& a, bool gyro, NoiseTerm NoiseReading::*term) {
  Worst w;
  for (const AxisNoise& ax : a.axes) {
    if (ax.gyro != gyro) continue;
    const NoiseTerm& t = ax.reading.*term;
    if (t.value > w.value) w = {t.value, t.lo, t.hi, ax.name, t.supported};
  }
  return w;
}

/// The random walk the filter's bias state gets: K when read, else the Gauss-Markov equivalent of
/// B (driving noise 2 B^2 / T, T = floor tau / 1.89: a Gauss-Markov adev peaks at 1.89 T), else the
/// 95% upper bound of K. The text says which.
double bias_rw_for_filter(const NoiseAnalysis& a, bool gyro, std::string& why) {
  const Worst k = worst(a, gyro, &NoiseReading::rate_rw);
  if (k.supported) {
    why = "rate random walk K read on the slope +1/2 line (" + k.axis + ", 95% " + fmt("%.3g", k.lo) + " .. " +
          fmt("%.3g", k.hi) + ")";
    return k.value;
  }
  double best = 0.0;
  for (const AxisNoise& ax : a.axes) {
    if (ax.gyro != gyro || !ax.reading.bias.supported) continue;
    const double T = ax.reading.floor_tau_s / 1.89;
    const double q = ax.reading.bias.value * std::sqrt(2.0 / T);
    if (q > best) {
      best = q;
      why = "no +1/2 slope within the rest; the bias instability B = " + fmt("%.3g", ax.reading.bias.value) + " (" +
            ax.name + ") as a Gauss-Markov drift of T = " + fmt("%.3g", T) +
            " s (floor tau / 1.89), driving noise sqrt(2 B^2 / T)";
    }
  }
  if (best > 0.0) return best;
  why = "neither K nor a floor within the rest: the 95% upper bound of K (" + k.axis + "), an upper limit, not a reading";
  return k.value;
}

}  // namespace

nlohmann::json filter_values_json(const NoiseAnalysis& a, const NoiseInput& in) {
  nlohmann::json j;
  const Worst nw = worst(a, true, &NoiseReading::white), na = worst(a, false, &NoiseReading::white);
  const double to_deg_rthr = 60.0 / fsw::kDegToRad;
  j["arw_deg_per_rthr"] = {{"value", nw.value * to_deg_rthr}, {"lo95", nw.lo * to_deg_rthr}, {"hi95", nw.hi * to_deg_rthr},
                           {"axis", nw.axis}, {"supported", nw.supported}};
  j["vrw_mps_per_rthr"] = {{"value", na.value * 60.0}, {"lo95", na.lo * 60.0}, {"hi95", na.hi * 60.0},
                           {"axis", na.axis}, {"supported", na.supported}};
  std::string why_g, why_a;
  j["gyro_bias_rw_radps_per_rts"] = {{"value", bias_rw_for_filter(a, true, why_g)}, {"source", why_g}};
  j["accel_bias_rw_mps2_per_rts"] = {{"value", bias_rw_for_filter(a, false, why_a)}, {"source", why_a}};
  // At rest the mean rate is bias + Earth rate. Up = -f / |f| (levelling); with the latitude the
  // Earth rate's up part is known (bias along up exact), its horizontal part only in magnitude
  // (heading unknown): the horizontal bias lies between | |w_h| - W cos L | and |w_h| + W cos L.
  const fsw::Vec3 f(a.axes[3].mean, a.axes[4].mean, a.axes[5].mean);
  const fsw::Vec3 w(a.axes[0].mean, a.axes[1].mean, a.axes[2].mean);
  const fsw::Vec3 up = -f.normalized();
  const double W = fsw::wgs84::omega_ie_radps;
  const double lat = in.have_position ? in.lat_rad : 0.0;
  const double w_up = w.dot(up), w_h = (w - w_up * up).norm();
  const double b_up = in.have_position ? w_up - W * std::sin(lat) : w_up;
  const double bh_lo = in.have_position ? std::abs(w_h - W * std::cos(lat)) : std::max(0.0, w_h - W);
  const double bh_hi = w_h + W * (in.have_position ? std::cos(lat) : 1.0);
  const double b_up_tol = in.have_position ? 0.0 : W;
  j["gyro_bias"] = {{"up_degph", b_up * kRadpsToDegph},
                    {"up_uncertainty_degph", b_up_tol * kRadpsToDegph},
                    {"horizontal_min_degph", bh_lo * kRadpsToDegph},
                    {"horizontal_max_degph", bh_hi * kRadpsToDegph}};
  const double seen = std::max(std::abs(b_up) + b_up_tol, bh_hi);
  j["gyro_bias_sigma_degph"] = {
      {"value", seen * kRadpsToDegph},
      {"source", "the largest bias this turn-on can have: up " + fmt("%.3g", b_up * kRadpsToDegph) + " deg/h" +
                     (in.have_position ? " (Earth rate removed at the GNSS latitude)" : " +- 15.04 (no latitude)") +
                     ", horizontal " + fmt("%.3g", bh_lo * kRadpsToDegph) + " .. " + fmt("%.3g", bh_hi * kRadpsToDegph) +
                     " deg/h (the Earth rate's horizontal part, heading unknown)"}};
  const double g = in.have_position ? fsw::normal_gravity_mps2(in.lat_rad, in.h_m) : fsw::kStandardGravity_mps2;
  j["accel_vertical_residual_mg"] = (f.norm() - g) / fsw::kStandardGravity_mps2 * 1e3;
  j["gravity_from"] = in.have_position ? "normal gravity at the first GNSS fix" : "standard gravity (no GNSS position)";
  return j;
}

std::string filter_config_toml(const NoiseAnalysis& a, const NoiseInput& in, const std::string& source) {
  const nlohmann::json v = filter_values_json(a, in);
  std::ostringstream o;
  o << "# Filter configuration values from the sensor's own noise (sdins noise, docs/noise.md): the\n"
    << "# overlapping Allan deviation over " << fmt("%.1f", a.rest_s) << " s of rest in " << source << " (";
  for (std::size_t i = 0; i < a.segment_s.size(); ++i) o << (i ? ", " : "") << fmt("%.1f s", a.segment_s[i]);
  o << " segments, tau0 " << fmt("%.4g", a.tau0_s) << " s). One value per triad: the largest axis.\n"
    << "# Apply with --filter-config on top of a data set's file; review before flying it.\n[imu]\n";
  auto white = [&](const char* key, const char* unit, const nlohmann::json& t) {
    o << "# " << (t["supported"].get<bool>() ? "" : "NOT SUPPORTED (upper bound): ") << "white noise read at the "
      << "Allan curve's slope -1/2 line, axis " << t["axis"].get<std::string>() << ", 95% "
      << fmt("%.4g", t["lo95"].get<double>()) << " .. " << fmt("%.4g", t["hi95"].get<double>()) << " " << unit << "\n"
      << key << " = " << fmt("%.4g", t["value"].get<double>()) << "\n";
  };
  white("arw_deg_per_rthr", "deg/sqrt(h)", v["arw_deg_per_rthr"]);
  white("vrw_mps_per_rthr", "m/s/sqrt(h)", v["vrw_mps_per_rthr"]);
  o << "# " << v["gyro_bias_rw_radps_per_rts"]["source"].get<std::string>() << "\n"
    << "gyro_bias_rw_radps_per_rts = " << fmt("%.4g", v["gyro_bias_rw_radps_per_rts"]["value"].get<double>()) << "\n"
    << "# " << v["accel_bias_rw_mps2_per_rts"]["source"].get<std::string>() << "\n"
    << "accel_bias_rw_mps2_per_rts = " << fmt("%.4g", v["accel_bias_rw_mps2_per_rts"]["value"].get<double>()) << "\n"
    << "# One turn-on's bias (a sigma over turn-ons needs several recordings), " << v["gyro_bias_sigma_degph"]["source"].get<std::string>()
    << "; mean rates";
  for (int c = 0; c < 3; ++c) o << " " << fmt("%.4g", a.axes[static_cast<std::size_t>(c)].mean * kRadpsToDegph);
  o << " deg/h\ngyro_bias_sigma_degph = " << fmt("%.4g", v["gyro_bias_sigma_degph"]["value"].get<double>()) << "\n"
    << "# accel_bias_sigma_mg is not written: at rest a horizontal accelerometer bias is indistinguishable from\n"
    << "# tilt; only the bias along gravity shows, |mean f| - g = "
    << fmt("%.3g", v["accel_vertical_residual_mg"].get<double>()) << " mg (" << v["gravity_from"].get<std::string>()
    << "), a lower bound.\n";
  return o.str();
}

sim::ImuErrors imu_errors_from_analysis(const NoiseAnalysis& a) {
  sim::ImuErrors e;
  const Worst nw = worst(a, true, &NoiseReading::white), na = worst(a, false, &NoiseReading::white);
  e.gyro_arw_rad_per_rts = nw.value;
  e.accel_vrw_mps_per_rts = na.value;
  const Worst bg = worst(a, true, &NoiseReading::bias), ba = worst(a, false, &NoiseReading::bias);
  double floor_tau = 0.0;
  for (const AxisNoise& ax : a.axes)
    if (ax.reading.bias.supported) floor_tau = std::max(floor_tau, ax.reading.floor_tau_s);
  if (floor_tau > 0.0) {
    // A first-order Gauss-Markov drift whose adev peaks at the floor: peak 0.62 sigma at 1.89 T.
    e.bias_instability_tau_s = floor_tau / 1.89;
    e.gyro_bias_instability_radps = bg.supported ? bg.value * kFlickerFloorFactor / 0.62 : 0.0;
    e.accel_bias_instability_mps2 = ba.supported ? ba.value * kFlickerFloorFactor / 0.62 : 0.0;
  }
  const Worst kg = worst(a, true, &NoiseReading::rate_rw), ka = worst(a, false, &NoiseReading::rate_rw);
  e.gyro_bias_rw_radps_per_rts = kg.supported ? kg.value : 0.0;
  e.accel_bias_rw_mps2_per_rts = ka.supported ? ka.value : 0.0;
  return e;
}

std::string scenario_imu_toml(const sim::ImuErrors& e) {
  std::ostringstream o;
  o << "[imu]  # the noise keys of sim/scenarios/README.md that reproduce the recording's terms\n"
    << "gyro_arw_deg_per_rthr = " << fmt("%.4g", e.gyro_arw_rad_per_rts * 60.0 / fsw::kDegToRad) << "\n"
    << "accel_vrw_ug_per_rthz = " << fmt("%.4g", e.accel_vrw_mps_per_rts / fsw::kMicroG_mps2) << "\n"
    << "gyro_bias_instability_degph = " << fmt("%.4g", e.gyro_bias_instability_radps * kRadpsToDegph) << "\n"
    << "accel_bias_instability_ug = " << fmt("%.4g", e.accel_bias_instability_mps2 / fsw::kMicroG_mps2) << "\n"
    << "bias_instability_tau_s = " << fmt("%.4g", e.bias_instability_tau_s) << "\n"
    << "gyro_bias_rw_degph_per_rthr = " << fmt("%.4g", e.gyro_bias_rw_radps_per_rts * 60.0 * kRadpsToDegph) << "\n"
    << "accel_bias_rw_ug_per_rthr = " << fmt("%.4g", e.accel_bias_rw_mps2_per_rts * 60.0 / fsw::kMicroG_mps2) << "\n";
  return o.str();
}

namespace {

nlohmann::json term_json(const NoiseTerm& t) {
  return {{"supported", t.supported}, {"value", t.value}, {"lo95", t.lo}, {"hi95", t.hi}, {"read_tau_s", t.read_tau_s},
          {"note", t.note}};
}

}  // namespace

nlohmann::json to_json(const NoiseAnalysis& a) {
  nlohmann::json j;
  j["tau0_s"] = a.tau0_s;
  j["rest_s"] = a.rest_s;
  j["segment_s"] = a.segment_s;
  j["axes"] = nlohmann::json::array();
  for (const AxisNoise& ax : a.axes) {
    nlohmann::json c;
    c["name"] = ax.name;
    c["unit"] = ax.gyro ? "rad/s" : "m/s^2";
    c["mean"] = ax.mean;
    const NoiseReading& r = ax.reading;
    c["model"] = {{"q2", r.model.q2}, {"n2", r.model.n2}, {"b2", r.model.b2}, {"k2", r.model.k2}};
    c["white"] = term_json(r.white);
    c["bias_instability"] = term_json(r.bias);
    c["rate_random_walk"] = term_json(r.rate_rw);
    c["floor_tau_s"] = r.floor_tau_s;
    c["fit"] = {{"from_tau_s", r.fit_from_tau_s}, {"rms_z", r.fit_rms_z}, {"adequate", r.fit_adequate}};
    nlohmann::json pts = nlohmann::json::array();
    for (const AllanPoint& p : ax.curve.points)
      pts.push_back({{"tau_s", p.tau_s}, {"m", p.m}, {"adev", std::sqrt(p.avar)}, {"lo95", std::sqrt(p.avar_lo)},
                     {"hi95", std::sqrt(p.avar_hi)}, {"edf", p.edf}, {"noise", to_string(p.noise)},
                     {"model_adev", std::sqrt(r.model.avar(p.tau_s))}});
    c["curve"] = pts;
    j["axes"].push_back(c);
  }
  return j;
}

nlohmann::json to_json(const RestDetection& d) {
  nlohmann::json j;
  j["detector"] = {{"window_s", d.cfg.window_s},
                   {"threshold_factor", d.cfg.threshold_factor},
                   {"min_rest_s", d.cfg.min_rest_s},
                   {"margin_s", d.cfg.margin_s},
                   {"max_speed_mps", d.cfg.max_speed_mps},
                   {"gnss_used", d.gnss_used}};
  j["median_dt_s"] = d.median_dt_s;
  j["reference"] = {{"sf_std_mps2", d.ref_sf_std_mps2}, {"rate_std_radps", d.ref_rate_std_radps}};
  j["threshold"] = {{"sf_std_mps2", d.thr_sf_std_mps2}, {"rate_std_radps", d.thr_rate_std_radps}};
  j["windows"] = {{"total", d.windows},
                  {"quiet_imu", d.windows_quiet_imu},
                  {"quiet_but_moving_gnss", d.windows_moving_gnss},
                  {"quiet_without_gnss", d.windows_no_gnss}};
  j["segments"] = nlohmann::json::array();
  for (const RestSegment& s : d.segments)
    j["segments"].push_back({{"t_begin_s", s.t_begin_s}, {"t_end_s", s.t_end_s}, {"duration_s", s.duration_s()},
                             {"samples", s.last - s.first + 1}});
  j["window_t_s"] = d.window_t_s;
  j["window_sf_std_mps2"] = d.window_sf_std;
  j["window_rate_std_radps"] = d.window_rate_std;
  j["window_rest"] = d.window_rest;
  return j;
}

namespace {

/// A term in display units: gyro N deg/sqrt(h), B deg/h, K deg/h/sqrt(h); accel N m/s/sqrt(h),
/// B ug, K ug/sqrt(h).
double display(bool gyro, int term, double v) {
  const double per_rth = 60.0;
  if (gyro) {
    if (term == 0) return v / fsw::kDegToRad * per_rth;
    if (term == 1) return v * kRadpsToDegph;
    return v * kRadpsToDegph * per_rth;
  }
  if (term == 0) return v * per_rth;
  if (term == 1) return v / fsw::kMicroG_mps2;
  return v / fsw::kMicroG_mps2 * per_rth;
}
const char* unit(bool gyro, int term) {
  static const char* g[3] = {"deg/rt-h", "deg/h", "deg/h/rt-h"};
  static const char* a[3] = {"m/s/rt-h", "ug", "ug/rt-h"};
  return gyro ? g[term] : a[term];
}
const NoiseTerm& term_of(const NoiseReading& r, int t) { return t == 0 ? r.white : t == 1 ? r.bias : r.rate_rw; }
const char* kTermNames[3] = {"white (N)", "bias instability (B)", "rate random walk (K)"};
const char* kTermKeys[3] = {"white", "bias_instability", "rate_random_walk"};

std::string term_text(bool gyro, int t, const NoiseTerm& x) {
  char b[160];
  if (x.supported)
    std::snprintf(b, sizeof b, "%9.4g [%9.4g, %9.4g] %s", display(gyro, t, x.value), display(gyro, t, x.lo),
                  display(gyro, t, x.hi), unit(gyro, t));
  else
    std::snprintf(b, sizeof b, "   < %-9.4g (not supported)  %s", display(gyro, t, x.value), unit(gyro, t));
  return b;
}

}  // namespace

std::string noise_summary_text(const RestDetection& d, const NoiseAnalysis& a) {
  std::ostringstream o;
  o << "rest detector: " << d.windows << " windows of " << fmt("%.3g", d.cfg.window_s) << " s, quiet when the std of |f| <= "
    << fmt("%.3g", d.thr_sf_std_mps2) << " m/s^2 and of the rate <= " << fmt("%.3g", d.thr_rate_std_radps / fsw::kDegToRad)
    << " deg/s (" << fmt("%.3g", d.cfg.threshold_factor) << " x the quiet reference "
    << fmt("%.3g", d.ref_sf_std_mps2) << " m/s^2, " << fmt("%.3g", d.ref_rate_std_radps / fsw::kDegToRad) << " deg/s); "
    << d.windows_quiet_imu << " quiet";
  if (d.gnss_used)
    o << ", of which " << d.windows_moving_gnss << " moving by GNSS (speed > " << fmt("%.3g", d.cfg.max_speed_mps)
      << " m/s) and " << d.windows_no_gnss << " without a GNSS solution near";
  else
    o << "; no GNSS speed used: a smooth motion at constant velocity would pass as rest";
  o << "\nrest segments (min " << fmt("%.3g", d.cfg.min_rest_s) << " s, " << fmt("%.3g", d.cfg.margin_s)
    << " s trimmed at each end):";
  for (const RestSegment& s : d.segments)
    o << " [" << fmt("%.3f", s.t_begin_s) << ", " << fmt("%.3f", s.t_end_s) << "] s (" << fmt("%.1f", s.duration_s())
      << " s)";
  o << "\n";
  if (a.axes.empty()) return o.str();
  o << "Allan analysis over " << fmt("%.1f", a.rest_s) << " s, tau0 " << fmt("%.4g", a.tau0_s)
    << " s; 95% intervals (chi-squared, NIST SP 1065 edf):\n";
  for (const AxisNoise& ax : a.axes) {
    o << "  " << ax.name << ": mean " << fmt("%.5g", ax.gyro ? ax.mean * kRadpsToDegph : ax.mean)
      << (ax.gyro ? " deg/h" : " m/s^2") << "; model fitted from tau " << fmt("%.3g", ax.reading.fit_from_tau_s)
      << " s, RMS deviation " << fmt("%.2g", ax.reading.fit_rms_z) << " sd"
      << (ax.reading.fit_adequate ? "" : " (NOT adequate: the readings below are doubtful)") << "\n";
    for (int t = 0; t < 3; ++t)
      o << "    " << kTermNames[t] << std::string(22 - std::string(kTermNames[t]).size(), ' ')
        << term_text(ax.gyro, t, term_of(ax.reading, t)) << "  " << term_of(ax.reading, t).note << "\n";
  }
  return o.str();
}

nlohmann::json compare_json(const NoiseAnalysis& data, const NoiseAnalysis& model) {
  nlohmann::json j = nlohmann::json::array();
  for (std::size_t i = 0; i < data.axes.size() && i < model.axes.size(); ++i) {
    const AxisNoise& d = data.axes[i];
    const AxisNoise& m = model.axes[i];
    nlohmann::json c;
    c["axis"] = d.name;
    for (int t = 0; t < 3; ++t) {
      const NoiseTerm& a = term_of(d.reading, t);
      const NoiseTerm& b = term_of(m.reading, t);
      c[kTermKeys[t]] = {{"data", display(d.gyro, t, a.value)},
                         {"data_supported", a.supported},
                         {"model", display(d.gyro, t, b.value)},
                         {"model_supported", b.supported},
                         {"unit", unit(d.gyro, t)}};
    }
    // The curves side by side: model adev / data adev at tau = 1 s, the extremes over tau, and
    // how many of the data's 95% intervals hold the model's curve.
    double r1 = 0.0, rmin = 1e300, rmax = 0.0, tmin = 0.0, tmax = 0.0;
    int inside = 0, n = 0;
    for (const AllanPoint& p : d.curve.points)
      for (const AllanPoint& q : m.curve.points)
        if (p.m == q.m) {
          const double r = std::sqrt(q.avar / p.avar);
          if (std::abs(p.tau_s - 1.0) < 0.5 * p.tau_s / 1.0 && (r1 == 0.0 || std::abs(p.tau_s - 1.0) < 0.02)) r1 = r;
          if (r < rmin) rmin = r, tmin = p.tau_s;
          if (r > rmax) rmax = r, tmax = p.tau_s;
          inside += p.avar_lo <= q.avar && q.avar <= p.avar_hi;
          ++n;
        }
    c["adev_ratio_model_over_data"] = {{"at_1s", r1}, {"min", rmin}, {"min_tau_s", tmin}, {"max", rmax},
                                       {"max_tau_s", tmax}, {"points_inside_data_95", inside}, {"points", n}};
    j.push_back(c);
  }
  return j;
}

std::string compare_text(const NoiseAnalysis& data, const NoiseAnalysis& model, const std::string& model_name) {
  std::ostringstream o;
  o << "data against " << model_name << " (the same rest lengths and tau0; '<': an upper bound):\n";
  const nlohmann::json j = compare_json(data, model);
  for (const auto& c : j) {
    o << "  " << c["axis"].get<std::string>() << ":";
    for (int t = 0; t < 3; ++t) {
      const auto& x = c[kTermKeys[t]];
      o << "  " << (t == 0 ? "N" : t == 1 ? "B" : "K") << " " << fmt("%.3g", x["data"].get<double>())
        << (x["data_supported"].get<bool>() ? "" : "<") << " vs " << fmt("%.3g", x["model"].get<double>())
        << (x["model_supported"].get<bool>() ? "" : "<") << " " << x["unit"].get<std::string>();
    }
    const auto& r = c["adev_ratio_model_over_data"];
    o << ";  adev model/data " << fmt("%.3g", r["at_1s"].get<double>()) << " at 1 s, " << fmt("%.3g", r["min"].get<double>())
      << " (tau " << fmt("%.3g", r["min_tau_s"].get<double>()) << " s) .. " << fmt("%.3g", r["max"].get<double>())
      << " (tau " << fmt("%.3g", r["max_tau_s"].get<double>()) << " s), " << r["points_inside_data_95"].get<int>() << "/"
      << r["points"].get<int>() << " points inside the data's 95%\n";
  }
  return o.str();
}

std::string segments_text(const std::vector<NoiseAnalysis>& each, nlohmann::json& j) {
  std::ostringstream o;
  o << "each rest segment alone, white noise N (95%):\n";
  std::vector<std::string> disagree;
  for (std::size_t c = 0; c < 6; ++c) {
    const bool gyro = c < 3;
    o << "  " << std::left << std::setw(8) << kAxisNames[c] << std::right << " " << unit(gyro, 0) << ":";
    double max_lo = 0.0, min_hi = 1e300;
    bool all = true;
    nlohmann::json row = nlohmann::json::array();
    for (const NoiseAnalysis& a : each) {
      const NoiseTerm& t = a.axes[c].reading.white;
      char b[96];
      if (t.supported)
        std::snprintf(b, sizeof b, "%9.4g [%.4g, %.4g]", display(gyro, 0, t.value), display(gyro, 0, t.lo),
                      display(gyro, 0, t.hi));
      else
        std::snprintf(b, sizeof b, "%9s", ("< " + fmt("%.4g", display(gyro, 0, t.value))).c_str());
      o << "  " << std::left << std::setw(30) << b << std::right;
      row.push_back(term_json(t));
      all &= t.supported;
      if (t.supported) {
        max_lo = std::max(max_lo, t.lo);
        min_hi = std::min(min_hi, t.hi);
      }
    }
    const bool apart = all && max_lo > min_hi;
    if (apart) disagree.push_back(kAxisNames[c]);
    o << (apart ? "  <- the segments' intervals do not overlap" : "") << "\n";
    j.push_back({{"axis", kAxisNames[c]}, {"white", row}, {"disagree", apart}});
  }
  if (!disagree.empty()) {
    o << "  the noise differs between the rests on";
    for (const auto& a : disagree) o << " " << a;
    o << ": the pooled reading mixes them (--segment K analyses one)\n";
  }
  return o.str();
}

std::string imu_errors_text(const sim::ImuErrors& e) {
  std::ostringstream o;
  o << "ARW " << fmt("%.3g", e.gyro_arw_rad_per_rts * 60.0 / fsw::kDegToRad) << " deg/rt-h, VRW "
    << fmt("%.3g", e.accel_vrw_mps_per_rts * 60.0) << " m/s/rt-h, Gauss-Markov drift "
    << fmt("%.3g", e.gyro_bias_instability_radps * kRadpsToDegph) << " deg/h / "
    << fmt("%.3g", e.accel_bias_instability_mps2 / fsw::kMicroG_mps2) << " ug (tau " << fmt("%.4g", e.bias_instability_tau_s)
    << " s), bias random walk " << fmt("%.3g", e.gyro_bias_rw_radps_per_rts * 60.0 * kRadpsToDegph) << " deg/h/rt-h / "
    << fmt("%.3g", e.accel_bias_rw_mps2_per_rts * 60.0 / fsw::kMicroG_mps2) << " ug/rt-h; constant bias "
    << fmt("%.3g", e.gyro_bias_radps.cwiseAbs().maxCoeff() * kRadpsToDegph) << " deg/h / "
    << fmt("%.3g", e.accel_bias_mps2.cwiseAbs().maxCoeff() / fsw::kMicroG_mps2) << " ug (largest axis of the draw)";
  return o.str();
}

}  // namespace tools
