// The EKF's raw-GNSS aid (tight coupling): the pseudorange and pseudorange rate of every satellite
// of an epoch. One aid unit of the filter (fsw/ekf.hpp), in the shape every aid follows:
// observation (the antenna at the epoch, each satellite's predicted range and rate), variance,
// innovation, gate, then fuse; the first usable epoch resets the clock instead. Ekf::update runs
// it (fsw/src/ekf/aid_gnss_raw.cpp) and returns one innovation record per observation
// (ObservationInnovation in EkfUpdateReport::obs); the gate and the scalar update are the core's.
//
// MEASUREMENTS (sequential scalar updates, Joseph form, symmetry enforced)
//   y = z_hat - z = H dx + noise,  z_hat from gnss_geometry() at the antenna (lever arm) with the
//   clock estimate; pseudorange H: position -e_n^T, attitude -e_n^T [(C_b_n l) x], clock bias 1;
//   pseudorange rate H: velocity -e_n^T, clock drift 1 (e_n: unit line of sight receiver ->
//   satellite in ENU). Every scalar is gated: (y - H dx)^2 / (H P H^T + R) > gate_chi2 rejects it
//   (counted). The INS solution at the frame closest to the epoch is extrapolated to the epoch's
//   time tag with its velocity.
//
// CLOCK. The first epoch with a usable observation sets the clock bias and drift to the mean of
// its pseudorange and pseudorange-rate residuals; its measurements are not used twice.
//
// EXTENSION BLOCKS OF THE DIAGNOSIS MODEL (LayoutDiag; each a random constant, estimate fed back)
//   time offset tau (IMU tag minus GNSS time): the INS is read at the epoch's time tag plus
//     tau_hat; H_pr = -e_n^T v_n, H_prr = -e_n^T a_n (a_n: the frame's acceleration).
//   lever arm l: the antenna at l_hat; H_pr = -e_n^T C_b_n, H_prr = -e_n^T C_b_n [w x]
//     (w = w_ib_b - w_ie_b).
//   tropospheric / ionospheric scale s: z_hat += s_hat * D, H_pr = D, with D the model delay
//     (fsw/gnss_delays.hpp, the simulator's too; s = 1 is the full model): troposphere
//     saastamoinen_delay_m(lat, h_ant, el), ionosphere klobuchar_delay_m(kKlobucharDefault,
//     epoch.gps_tow_s, lat, lon, az, el); lat / lon of the INS, el / az of the predicted line of
//     sight in ENU. Their rates (< 1 cm/s) are left out.
//   A block whose initial sigma is zero stays exactly zero (it has no process noise): the
//   diagnosis switches extensions on and off that way.
//
// TIME-CORRELATED MEASUREMENT ERRORS (layouts with kRangeError / kRangeRateError): each tracked
//   satellite is bound to a channel; the channel's first-order Gauss-Markov error is a state
//   (H = 1), propagated with a = exp(-T / tau) and Qd = sigma^2 (1 - a^2). A newly tracked
//   satellite takes a free channel, whose state restarts at zero with variance sigma^2 and no
//   correlation; a satellite that is not in the epoch releases its channel. With no channel left
//   the correlated error's variance joins the white noise (counted in obs_no_channel).
#pragma once

#include "fsw/frames.hpp"
#include "fsw/gnss.hpp"
#include "fsw/strapdown.hpp"

namespace fsw {

/// The antenna at an epoch's time tag as the INS predicts it: what every scalar of the epoch shares.
struct GnssRawAntenna {
  double lat_rad = 0.0;                  ///< the INS solution's latitude ...
  double lon_rad = 0.0;                  ///< ... and longitude (the delay models' position)
  double h_m = 0.0;                      ///< the antenna's ellipsoidal height
  Mat3 C_n_e = Mat3::Identity();         ///< ENU -> ECEF at the INS solution
  Mat3 C_b_n = Mat3::Identity();         ///< the INS attitude
  Vec3 lever_enu_m = Vec3::Zero();       ///< C_b_n l: IMU reference point -> antenna, ENU
  Vec3 omega_rel_b_radps = Vec3::Zero(); ///< w = w_ib_b - w_ie_b, the body rate relative to the Earth
  Vec3 ins_vel_enu_mps = Vec3::Zero();   ///< the INS velocity (the time-offset term of the pseudorange)
  Vec3 accel_enu_mps2 = Vec3::Zero();    ///< the frame's kinematic acceleration (specific force plus
                                         ///< gravity; Coriolis left out), for the time-offset terms
  Vec3 r_ecef_m = Vec3::Zero();          ///< antenna position at the epoch's INS time tag
  Vec3 v_ecef_mps = Vec3::Zero();        ///< antenna velocity (relative to ECEF)
};

/// The antenna at GNSS time t_s: the INS solution nav (at the frame closest to the epoch, body rate
/// omega_ib_b_radps, specific force f_enu_mps2 of the filter's last frame) read at t_s plus
/// time_offset_s, moved by the lever arm lever_arm_b_m. offset_moves_velocity: the velocity is
/// moved by the acceleration over time_offset_s too (the layouts with time-offset states).
GnssRawAntenna gnss_raw_antenna(double t_s, const NavState& nav, const Vec3& omega_ib_b_radps,
                                const Vec3& lever_arm_b_m, double time_offset_s, const Vec3& f_enu_mps2,
                                bool offset_moves_velocity);

/// An observation's data can be used: finite, and a satellite radius within 1e7..1e8 m.
bool gnss_observation_usable(const GnssObservation& o);

/// The prediction of one satellite's observation from the antenna.
struct GnssRawPrediction {
  GnssGeometry geo{};          ///< range (modelled delays included when asked), range rate, line of sight
  double tropo_delay_m = 0.0;  ///< the modelled delays D (zero when not asked for)
  double iono_delay_m = 0.0;
};

/// The predicted range and range rate of observation o seen from antenna a. with_delays: the
/// modelled tropospheric and ionospheric delays (at GNSS time of week gps_tow_s) scaled by
/// tropo_scale / iono_scale join the predicted range (the diagnosis' delay-scale blocks).
GnssRawPrediction gnss_raw_predict(const GnssObservation& o, const GnssRawAntenna& a, double gps_tow_s,
                                   bool with_delays, double tropo_scale, double iono_scale);

/// The unit line of sight receiver -> satellite in ENU at the antenna (e_n of the file comment).
inline Vec3 gnss_los_enu(const GnssRawPrediction& p, const GnssRawAntenna& a) {
  return a.C_n_e.transpose() * p.geo.los_ecef;
}

}  // namespace fsw
