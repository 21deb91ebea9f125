// The EKF's position/velocity aid (loose coupling): a GNSS solution of the antenna. One aid unit of
// the filter (fsw/ekf.hpp), in the shape every aid follows: observation (the solution's position
// and velocity parts, each checked), variance, innovation, gate, then fuse; after a PVT runaway
// reset the next solution re-initialises position and velocity, ungated. Ekf::update_pvt runs it
// (fsw/src/ekf/aid_gnss_pvt.cpp) and returns one innovation record per axis (PvtInnovation in
// EkfUpdateReport::pvt_obs); the gate and the scalar update are the core's.
//
// LOOSELY COUPLED UPDATE
//   The antenna p_a = p + C_b_n l, v_a = v + C_b_n (w x l) (w = w_ib_b - C_n_b w_ie_n), read at
//   the solution's time plus tau_hat like the pseudoranges. Six sequential scalar updates in ENU,
//   position E N U then velocity E N U (axes uncorrelated), each gated with gate_chi2, Joseph form:
//     y_pos = d_a - enu_difference_m(llh_meas, llh_nav)  H: pos I, att [(C_b_n l) x], lever C_b_n,
//                                                          tau v_a (= v_n + C_b_n (w x l))
//     y_vel = v_a_hat - v_meas                           H: vel I, att [(C_b_n (w x l)) x]
//                                                          + [(w_ie_n x C_b_n l) x] - [w_ie_n x][(C_b_n l) x]
//                                                          (the Earth-rate part of w depends on the
//                                                          attitude too), lever C_b_n [w x], tau a_n
//   (d_a = C_b_n l + v_a dt: the predicted antenna relative to the INS solution; the velocity term
//   tau a_n is applied to v_a_hat as in the raw aid). The position is read
//   dt = t_meas + tau_hat - t_nav after nav (0 when the executive has aligned nav to the solution
//   and tau_hat = 0), so its rows also get dt times the velocity rows' nav, attitude and lever terms.
//   R = (pvt_sigma_scale * max(sigma, floor))^2 per axis. The clock and the channel errors are
//   not involved. pvt_measurement_model() is the model itself (tests check it by differences).
#pragma once

#include <Eigen/Core>

#include "fsw/frames.hpp"
#include "fsw/gnss.hpp"
#include "fsw/strapdown.hpp"

namespace fsw {

/// The loosely coupled measurement model at one solution (see the file comment): the predicted
/// antenna, the innovations (predicted minus measured) and the exact Jacobian of the predicted
/// measurement. lever_arm_b_m and time_offset_s are the filter's estimates, accel_enu_mps2 the
/// frame's kinematic acceleration (ENU).
struct PvtModel {
  Vec3 llh_ant = Vec3::Zero();         ///< predicted antenna position
  Vec3 vel_ant_enu_mps = Vec3::Zero(); ///< predicted antenna velocity
  Vec3 pos_innovation_m = Vec3::Zero();
  Vec3 vel_innovation_mps = Vec3::Zero();
  /// Rows: pos E N U, vel E N U. Columns: position (0..2), velocity (3..5), attitude phi (6..8),
  /// lever arm (9..11), time offset (12), in the error definitions of error_state.hpp.
  Eigen::Matrix<double, 6, 13> H = Eigen::Matrix<double, 6, 13>::Zero();
};
PvtModel pvt_measurement_model(const GnssPvtMeasurement& m, const NavState& nav, const Vec3& omega_ib_b_radps,
                               const Vec3& lever_arm_b_m, double time_offset_s, const Vec3& accel_enu_mps2);

/// Which parts of a solution can be used: the position (finite, latitude within +-90 deg, every
/// sigma > 0) and the velocity (present, finite, every sigma > 0).
struct PvtUsable {
  bool pos = false;
  bool vel = false;
};
PvtUsable pvt_usable(const GnssPvtMeasurement& m);

}  // namespace fsw
