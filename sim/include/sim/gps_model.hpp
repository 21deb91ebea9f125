// The simulated GPS receiver: truth-side pseudorange and pseudorange-rate measurements from the
// almanac constellation, made consistent with the flight software's measurement model
// (fsw::gnss_geometry in fsw/include/fsw/gnss.hpp).
//
// TIME  An epoch at scenario time t (the truth sample's t_s, the navigation time scale) is the
// GPS time (start_week, start_tow_s + t), normalised to [0, 604800) s of the week.
//
// SIGNAL  The antenna truth is sim::antenna_truth() with the antenna_lever_arm effect. For each
// healthy satellite the transmit time is found by light-time iteration in the ECEF frame of the
// receive time: tau <- |R3(we tau) r_sat(t_rx - tau) - r_rx| / c until tau changes by < 1e-12 s
// (we = IS-GPS-200 Earth rate, R3(a) the rotation of transmit-time ECEF into receive-time ECEF).
// The observation carries r_sat(t_rx - tau), v_sat(t_rx - tau) (transmit-time ECEF), as a real
// receiver would from the broadcast ephemeris. The elevation (look_angles() of R3(we tau) r_sat
// from the true antenna position) selects satellites: elevation >= elevation_mask_deg; when more
// than max_channels are visible the highest ones are kept; the epoch lists them by PRN.
//
// MEASUREMENTS  (g = fsw::gnss_geometry(sat_pos_tx, sat_vel_tx, r_ant, v_ant), Sagnac included)
//   pseudorange      = g.range_m        + b   + x_pr(prn)  + n_pr  + s_T T + s_I I
//   pseudorange rate = g.range_rate_mps + d   + x_prr(prn) + n_prr + d/dt(s_T T + s_I I)
//   b, d          receiver clock bias [m] and drift [m/s]: two-state random process, b' = d + w_b,
//                 d' = w_d, PSDs S_b = h0/2 c^2 [m^2/s], S_d = 2 pi^2 h_-2 c^2 [m^2/s^3]; exact
//                 discretisation over T: Phi = [[1, T], [0, 1]],
//                 Q = [[S_b T + S_d T^3/3, S_d T^2/2], [S_d T^2/2, S_d T]]; b(0), d(0) drawn with
//                 clock_bias_sigma_m, clock_drift_sigma_mps.
//   x_pr, x_prr   first-order Gauss-Markov errors per PRN (sigma, tau from the config), exact
//                 discretisation x <- a x + sigma sqrt(1 - a^2) n, a = exp(-T/tau), started from
//                 the stationary distribution N(0, sigma^2). All 32 PRN slots are advanced every
//                 epoch in PRN order, so the draws do not depend on visibility.
//   n_pr, n_prr   white noise, drawn every epoch for all 32 PRN slots in PRN order.
//   T  tropospheric delay, fsw::saastamoinen_delay_m(lat, h, el) of the antenna (Saastamoinen,
//      standard atmosphere, relative humidity 0.7, DO-229 mapping); s_T the tropospheric_delay
//      effect (scale, 1 = the full model delay).
//   I  ionospheric L1 delay, fsw::klobuchar_delay_m(fsw::kKlobucharDefault, tow, lat, lon, az, el)
//      (IS-GPS-200 Klobuchar with RTKLIB's default coefficients); s_I the ionospheric_delay effect.
//   el, az: look_angles() of R3(we tau) r_sat from the antenna (fsw/gnss_delays.hpp has the models).
//   The delay rate (about 1 cm/s at most, for low satellites) is a central difference over
//   +-0.5 s of the linearly extrapolated receiver and satellite positions and of the GPS time
//   (the Klobuchar delay follows the local time); 0 when both scales are 0.
// The satellite clock is not simulated: the measurements are "satellite clock removed".
// The range rate is fsw::gnss_geometry's e . (v_sat_i - v_rx_i), which leaves out the light-time
// factor of the exact derivative of the range, e . v_sat_i (1 - rhodot / c): the pseudorange rate
// differs from d/dt of the pseudorange by (e . v_sat_i) rhodot / c, up to ~3 mm/s.
//
// RANDOM STREAMS  Rng(seed, 10): Gauss-Markov errors; Rng(seed, 11): receiver clock;
// Rng(seed, 12): white noise (the IMU model uses streams 1 and 2).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "fsw/gnss.hpp"
#include "sim/almanac.hpp"
#include "sim/effects.hpp"
#include "sim/rng.hpp"
#include "sim/scenario.hpp"
#include "sim/trajectory.hpp"

namespace sim {

using fsw::kMaxGpsPrn;

// The delay models are the flight software's (fsw/gnss_delays.hpp), so the diagnosis's extension
// states and the truth side use one definition.
using fsw::klobuchar_delay_m;
using fsw::kKlobucharDefault;
using fsw::saastamoinen_delay_m;

struct GpsClockState {
  double bias_m = 0.0;     ///< c * receiver clock bias
  double drift_mps = 0.0;  ///< c * receiver clock drift
};

class GpsModel {
 public:
  /// almanac: already parsed (parse_yuma_file); seed: the run's seed; effects: the scenario's.
  /// Throws std::invalid_argument on an invalid configuration (values outside the scenario
  /// schema's ranges, an empty almanac, PRNs outside 1..32 or repeated).
  GpsModel(const GpsConfig& cfg, std::vector<AlmanacEntry> almanac, const EffectSet& effects, std::uint64_t seed);

  /// The measurement epoch at truth.t_s (the caller passes the truth sample of the epoch time,
  /// t_s = k / rate_hz). Advances the random processes by the time since the previous call (the
  /// first call starts them; a time going backwards advances by 0). Never throws.
  void measure(const TruthSample& truth, fsw::GnssEpoch& out) noexcept;

  /// The same epoch as a receiver reports it on the bus (fsw::GnssRawEpoch): time tag on the
  /// receiver clock (GPS time + bias / c of the last measure(), so call it right after), PRN, pseudorange
  /// with the satellite clock error put back (c * (af0 + af1 tk) subtracted), rate with c * af1
  /// subtracted, and a nominal C/N0 of 30 + 20 sin(elevation) dB-Hz. fsw::gnss_epoch_from_raw with
  /// the same almanac inverts it (satellite positions recomputed at tow - rho / c: < 1 mm apart).
  void raw(const fsw::GnssEpoch& epoch, fsw::GnssRawEpoch& out) const noexcept;
  /// The almanac the model flies (sorted by PRN), for delivery to the flight software.
  const std::vector<AlmanacEntry>& almanac() const { return almanac_; }

  /// Truth receiver clock at the last epoch.
  const GpsClockState& clock() const { return clock_; }
  /// Current Gauss-Markov errors of a PRN (0 for a PRN outside 1..32).
  double pseudorange_error_m(int prn) const;
  double pseudorange_rate_error_mps(int prn) const;
  const GpsConfig& config() const { return cfg_; }

 private:
  void start();
  void propagate(double dt_s);

  GpsConfig cfg_;
  std::vector<AlmanacEntry> almanac_;  ///< sorted by PRN
  Vec3 lever_arm_b_m_ = Vec3::Zero();
  double tropo_scale_ = 0.0;
  double iono_scale_ = 0.0;
  Rng rng_gm_;
  Rng rng_clock_;
  Rng rng_white_;
  bool started_ = false;
  double t_last_s_ = 0.0;
  GpsClockState clock_{};
  std::array<double, kMaxGpsPrn> gm_pr_m_{};
  std::array<double, kMaxGpsPrn> gm_prr_mps_{};
  std::array<double, kMaxGpsPrn> white_pr_m_{};
  std::array<double, kMaxGpsPrn> white_prr_mps_{};
};

}  // namespace sim
