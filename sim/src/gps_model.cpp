// Simulated GPS receiver (the model is stated in sim/include/sim/gps_model.hpp).
#include "sim/gps_model.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "sim/imu_model.hpp"

namespace sim {
namespace {

using fsw::kSpeedOfLight_mps;

enum Stream : std::uint64_t { kStreamGaussMarkov = 10, kStreamClock = 11, kStreamWhite = 12 };

/// Satellites well below the mask (by their receive-time position) skip the light-time solution.
constexpr double kPrefilterMargin_rad = 1e-3;
constexpr double kLightTimeTolerance_s = 1e-12;
constexpr int kLightTimeMaxIterations = 10;

/// R3(a): transmit-time ECEF -> receive-time ECEF for a signal flight time a / we.
Mat3 earth_rotation(double tau_s) {
  const double a = fsw::kGpsEarthRate_radps * tau_s;
  const double ca = std::cos(a), sa = std::sin(a);
  Mat3 r;
  r << ca, sa, 0.0, -sa, ca, 0.0, 0.0, 0.0, 1.0;
  return r;
}

struct Transit {
  double tau_s = 0.0;
  Vec3 sat_pos_tx_m = Vec3::Zero();    ///< transmit-time ECEF
  Vec3 sat_vel_tx_mps = Vec3::Zero();  ///< transmit-time ECEF
  Vec3 sat_pos_rx_frame_m = Vec3::Zero();  ///< R3(we tau) sat_pos_tx: receive-time ECEF
};

/// Light-time iteration: tau = |R3(we tau) r_sat(t_rx - tau) - r_rx| / c.
Transit solve_light_time(const AlmanacEntry& sat, int week, double tow_rx_s, const Vec3& r_rx_m, const Vec3& r_sat_rx_m) {
  Transit t;
  t.tau_s = (r_sat_rx_m - r_rx_m).norm() / kSpeedOfLight_mps;
  for (int i = 0; i < kLightTimeMaxIterations; ++i) {
    satellite_pv_ecef(sat, week, tow_rx_s - t.tau_s, t.sat_pos_tx_m, t.sat_vel_tx_mps);
    t.sat_pos_rx_frame_m = earth_rotation(t.tau_s) * t.sat_pos_tx_m;
    const double tau_new = (t.sat_pos_rx_frame_m - r_rx_m).norm() / kSpeedOfLight_mps;
    const double change = std::abs(tau_new - t.tau_s);
    t.tau_s = tau_new;
    if (change < kLightTimeTolerance_s) break;
  }
  // Final state at the converged flight time.
  satellite_pv_ecef(sat, week, tow_rx_s - t.tau_s, t.sat_pos_tx_m, t.sat_vel_tx_mps);
  t.sat_pos_rx_frame_m = earth_rotation(t.tau_s) * t.sat_pos_tx_m;
  return t;
}

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("GpsModel: " + what);
}

bool finite_non_negative(double v) { return std::isfinite(v) && v >= 0.0; }
bool finite_positive(double v) { return std::isfinite(v) && v > 0.0; }

}  // namespace


GpsModel::GpsModel(const GpsConfig& cfg, std::vector<AlmanacEntry> almanac, const EffectSet& effects,
                   std::uint64_t seed)
    : cfg_(cfg),
      almanac_(std::move(almanac)),
      rng_gm_(seed, kStreamGaussMarkov),
      rng_clock_(seed, kStreamClock),
      rng_white_(seed, kStreamWhite) {
  require(cfg_.start_week >= 0, "start_week must be >= 0");
  require(std::isfinite(cfg_.start_tow_s) && cfg_.start_tow_s >= 0.0 && cfg_.start_tow_s < kSecondsPerWeek,
          "start_tow_s must be in [0, 604800)");
  require(std::isfinite(cfg_.rate_hz) && cfg_.rate_hz > 0.0 && cfg_.rate_hz <= 20.0, "rate_hz must be in (0, 20]");
  require(std::isfinite(cfg_.elevation_mask_deg) && cfg_.elevation_mask_deg >= 0.0 && cfg_.elevation_mask_deg < 90.0,
          "elevation_mask_deg must be in [0, 90)");
  require(finite_non_negative(cfg_.pseudorange_gm_sigma_m) && finite_non_negative(cfg_.pseudorange_rate_gm_sigma_mps) &&
              finite_non_negative(cfg_.pseudorange_white_sigma_m) &&
              finite_non_negative(cfg_.pseudorange_rate_white_sigma_mps) &&
              finite_non_negative(cfg_.clock_bias_sigma_m) && finite_non_negative(cfg_.clock_drift_sigma_mps) &&
              finite_non_negative(cfg_.clock_h0_s) && finite_non_negative(cfg_.clock_h_minus2_per_s),
          "sigmas and clock coefficients must be finite and >= 0");
  require(finite_positive(cfg_.pseudorange_gm_tau_s) && finite_positive(cfg_.pseudorange_rate_gm_tau_s),
          "Gauss-Markov correlation times must be finite and > 0");
  require(cfg_.max_channels >= 1 && cfg_.max_channels <= fsw::kMaxGnssChannels, "max_channels must be in [1, 16]");
  require(!almanac_.empty(), "empty almanac");
  std::sort(almanac_.begin(), almanac_.end(), [](const AlmanacEntry& a, const AlmanacEntry& b) { return a.prn < b.prn; });
  for (std::size_t i = 0; i < almanac_.size(); ++i) {
    require(almanac_[i].prn >= 1 && almanac_[i].prn <= kMaxGpsPrn, "almanac PRN outside 1..32");
    require(i == 0 || almanac_[i].prn != almanac_[i - 1].prn, "almanac PRN repeated");
  }
  for (std::size_t k = 0; k < 3; ++k) lever_arm_b_m_(static_cast<int>(k)) = effects.si(Effect::kAntennaLeverArm, k);
  tropo_scale_ = effects.si(Effect::kTroposphericDelay);
  iono_scale_ = effects.si(Effect::kIonosphericDelay);
  require(lever_arm_b_m_.allFinite() && std::isfinite(tropo_scale_) && std::isfinite(iono_scale_),
          "effects must be finite");
}

double GpsModel::pseudorange_error_m(int prn) const {
  return (prn >= 1 && prn <= kMaxGpsPrn) ? gm_pr_m_[static_cast<std::size_t>(prn - 1)] : 0.0;
}

double GpsModel::pseudorange_rate_error_mps(int prn) const {
  return (prn >= 1 && prn <= kMaxGpsPrn) ? gm_prr_mps_[static_cast<std::size_t>(prn - 1)] : 0.0;
}

void GpsModel::start() {
  // Fixed draw order: changing it changes every seeded run.
  for (std::size_t i = 0; i < gm_pr_m_.size(); ++i) {
    gm_pr_m_[i] = cfg_.pseudorange_gm_sigma_m * rng_gm_.normal();
    gm_prr_mps_[i] = cfg_.pseudorange_rate_gm_sigma_mps * rng_gm_.normal();
  }
  clock_.bias_m = cfg_.clock_bias_sigma_m * rng_clock_.normal();
  clock_.drift_mps = cfg_.clock_drift_sigma_mps * rng_clock_.normal();
}

void GpsModel::propagate(double dt_s) {
  const double a_pr = std::exp(-dt_s / cfg_.pseudorange_gm_tau_s);
  const double a_prr = std::exp(-dt_s / cfg_.pseudorange_rate_gm_tau_s);
  const double q_pr = cfg_.pseudorange_gm_sigma_m * std::sqrt(1.0 - a_pr * a_pr);
  const double q_prr = cfg_.pseudorange_rate_gm_sigma_mps * std::sqrt(1.0 - a_prr * a_prr);
  for (std::size_t i = 0; i < gm_pr_m_.size(); ++i) {
    gm_pr_m_[i] = a_pr * gm_pr_m_[i] + q_pr * rng_gm_.normal();
    gm_prr_mps_[i] = a_prr * gm_prr_mps_[i] + q_prr * rng_gm_.normal();
  }
  // Two-state clock: exact discretisation, process noise drawn through the Cholesky factor of Q.
  const double s_bias = fsw::clock_bias_psd_m2ps(cfg_.clock_h0_s);                // [m^2/s]
  const double s_drift = fsw::clock_drift_psd_m2ps3(cfg_.clock_h_minus2_per_s);  // [m^2/s^3]
  const double T = dt_s;
  const double q11 = s_bias * T + s_drift * T * T * T / 3.0;
  const double q12 = s_drift * T * T / 2.0;
  const double q22 = s_drift * T;
  const double l11 = std::sqrt(std::max(q11, 0.0));
  const double l21 = l11 > 0.0 ? q12 / l11 : 0.0;
  const double l22 = std::sqrt(std::max(q22 - l21 * l21, 0.0));
  const double n1 = rng_clock_.normal(), n2 = rng_clock_.normal();
  clock_.bias_m += clock_.drift_mps * T + l11 * n1;
  clock_.drift_mps += l21 * n1 + l22 * n2;
}

void GpsModel::measure(const TruthSample& truth, fsw::GnssEpoch& out) noexcept {
  const double t = truth.t_s;
  if (!started_) {
    start();
    started_ = true;
  } else {
    propagate(std::max(t - t_last_s_, 0.0));
  }
  t_last_s_ = t;
  for (std::size_t i = 0; i < white_pr_m_.size(); ++i) {
    white_pr_m_[i] = cfg_.pseudorange_white_sigma_m * rng_white_.normal();
    white_prr_mps_[i] = cfg_.pseudorange_rate_white_sigma_mps * rng_white_.normal();
  }

  // GPS time of the receive instant.
  const fsw::GpsTime rx = fsw::gps_time(cfg_.start_week, cfg_.start_tow_s + t);
  const int week = rx.week;
  const double tow = rx.tow_s;

  out = fsw::GnssEpoch{};
  out.t_s = t;
  out.gps_week = week;
  out.gps_tow_s = tow;

  Vec3 llh_ant, vel_ant_enu;
  antenna_truth(truth, lever_arm_b_m_, llh_ant, vel_ant_enu);
  const Vec3 r_rx = fsw::ecef_from_llh(llh_ant);
  const Vec3 v_rx = fsw::C_n_e(llh_ant.x(), llh_ant.y()) * vel_ant_enu;
  const double mask_rad = cfg_.elevation_mask_deg * fsw::kDegToRad;

  struct Candidate {
    std::size_t index = 0;  ///< into almanac_
    double elevation_rad = 0.0;
    Transit transit{};
  };
  std::array<Candidate, kMaxGpsPrn> cand{};
  std::size_t n = 0;
  for (std::size_t i = 0; i < almanac_.size(); ++i) {
    const AlmanacEntry& sat = almanac_[i];
    if (sat.health != 0) continue;
    Vec3 r_now, v_now;
    satellite_pv_ecef(sat, week, tow, r_now, v_now);
    if (look_angles(llh_ant, r_now).elevation_rad < mask_rad - kPrefilterMargin_rad) continue;
    const Transit tr = solve_light_time(sat, week, tow, r_rx, r_now);
    const double el = look_angles(llh_ant, tr.sat_pos_rx_frame_m).elevation_rad;
    if (!(el >= mask_rad)) continue;
    cand[n++] = Candidate{i, el, tr};
  }
  const auto max_channels = static_cast<std::size_t>(cfg_.max_channels);
  if (n > max_channels) {
    std::sort(cand.begin(), cand.begin() + static_cast<std::ptrdiff_t>(n), [](const Candidate& a, const Candidate& b) {
      return a.elevation_rad != b.elevation_rad ? a.elevation_rad > b.elevation_rad : a.index < b.index;
    });
    n = max_channels;
  }
  std::sort(cand.begin(), cand.begin() + static_cast<std::ptrdiff_t>(n),
            [](const Candidate& a, const Candidate& b) { return a.index < b.index; });

  const bool delays = tropo_scale_ != 0.0 || iono_scale_ != 0.0;
  // Scale 1 = the full model delay; tow_s is the GPS time of week (Klobuchar's local time).
  const auto delay_m = [&](const Vec3& llh_rx, const Vec3& r_sat, double tow_s) {
    const LookAngles la = look_angles(llh_rx, r_sat);
    double d = 0.0;
    if (tropo_scale_ != 0.0) d += tropo_scale_ * saastamoinen_delay_m(llh_rx.x(), llh_rx.z(), la.elevation_rad);
    if (iono_scale_ != 0.0)
      d += iono_scale_ *
           klobuchar_delay_m(kKlobucharDefault, tow_s, llh_rx.x(), llh_rx.y(), la.azimuth_rad, la.elevation_rad);
    return d;
  };

  // The receiver's positions +-0.5 s along its velocity for the delays' rates: the same for every
  // satellite, so converted once an epoch.
  const double h = 0.5;
  const Vec3 llh_plus = delays ? fsw::llh_from_ecef(r_rx + h * v_rx) : Vec3::Zero();
  const Vec3 llh_minus = delays ? fsw::llh_from_ecef(r_rx - h * v_rx) : Vec3::Zero();
  for (std::size_t k = 0; k < n; ++k) {
    const Candidate& c = cand[k];
    const AlmanacEntry& sat = almanac_[c.index];
    const auto slot = static_cast<std::size_t>(sat.prn - 1);
    const fsw::GnssGeometry g = fsw::gnss_geometry(c.transit.sat_pos_tx_m, c.transit.sat_vel_tx_mps, r_rx, v_rx);
    double delay = 0.0, delay_rate = 0.0;
    if (delays) {
      delay = delay_m(llh_ant, c.transit.sat_pos_rx_frame_m, tow);
      // Central difference over +-0.5 s of linearly extrapolated positions (receive-time ECEF)
      // and of the time.
      const Vec3 v_sat = earth_rotation(c.transit.tau_s) * c.transit.sat_vel_tx_mps;
      const double d_plus = delay_m(llh_plus, c.transit.sat_pos_rx_frame_m + h * v_sat, tow + h);
      const double d_minus = delay_m(llh_minus, c.transit.sat_pos_rx_frame_m - h * v_sat, tow - h);
      delay_rate = (d_plus - d_minus) / (2.0 * h);
    }
    fsw::GnssObservation& o = out.obs[k];
    o.prn = static_cast<std::uint8_t>(sat.prn);
    o.sat_pos_ecef_m = c.transit.sat_pos_tx_m;
    o.sat_vel_ecef_mps = c.transit.sat_vel_tx_mps;
    o.pseudorange_m = g.range_m + clock_.bias_m + gm_pr_m_[slot] + white_pr_m_[slot] + delay;
    o.pseudorange_rate_mps = g.range_rate_mps + clock_.drift_mps + gm_prr_mps_[slot] + white_prr_mps_[slot] + delay_rate;
    o.elevation_rad = c.elevation_rad;
  }
  out.n_obs = static_cast<int>(n);
}

void GpsModel::raw(const fsw::GnssEpoch& epoch, fsw::GnssRawEpoch& out) const noexcept {
  out = fsw::GnssRawEpoch{};
  out.t_s = epoch.t_s;
  // A receiver tags its epochs with its own clock: GPS time plus the clock bias. That is what makes
  // tow - rho / c the exact transmit time on the receiver side.
  const fsw::GpsTime tag = fsw::gps_time(epoch.gps_week, epoch.gps_tow_s + clock_.bias_m / kSpeedOfLight_mps);
  out.gps_week = tag.week;
  out.gps_tow_s = tag.tow_s;
  int n = 0;
  for (int i = 0; i < epoch.n_obs; ++i) {
    const fsw::GnssObservation& o = epoch.obs[static_cast<std::size_t>(i)];
    const auto it = std::lower_bound(almanac_.begin(), almanac_.end(), static_cast<int>(o.prn),
                                     [](const AlmanacEntry& a, int prn) { return a.prn < prn; });
    if (it == almanac_.end() || it->prn != o.prn) continue;  // cannot happen: measure() uses almanac_
    const fsw::GpsTime tx = fsw::gps_time(epoch.gps_week, epoch.gps_tow_s - o.pseudorange_m / kSpeedOfLight_mps);
    const double dt_sat_s = satellite_clock_bias_s(*it, tx.week, tx.tow_s);
    fsw::GnssRawMeasurement& m = out.meas[static_cast<std::size_t>(n++)];
    m.prn = o.prn;
    m.pseudorange_m = o.pseudorange_m - kSpeedOfLight_mps * dt_sat_s;
    m.pseudorange_rate_mps = o.pseudorange_rate_mps - kSpeedOfLight_mps * it->af1_sps;
    m.cn0_dbhz = 30.0 + 20.0 * std::sin(o.elevation_rad);
  }
  out.n_meas = n;
}

}  // namespace sim
