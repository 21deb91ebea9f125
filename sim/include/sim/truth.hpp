// Truth and the navigation error against it, in one module.
//
// Two truth types, for two uses: sim::TruthSample (trajectory.hpp) is the generator's full sample
// at the IMU rate (attitude as a DCM, rates, specific force, ideal increments); sim::TruthPoint is
// what a recording keeps of it, decimated (time, position, velocity, attitude as a quaternion),
// or a reference without attitude (an imported RTK solution, has_attitude false). truth_point()
// makes the second from the first. nav_errors() is the one definition of the navigation error
// (nav minus truth: ENU position, ENU velocity, attitude error phi of fsw/frames.hpp) for both.
#pragma once

#include <limits>

#include "fsw/frames.hpp"
#include "fsw/strapdown.hpp"
#include "sim/trajectory.hpp"

namespace sim {

/// A truth or reference sample (the TRUTH channel of a log; a recording's truth in memory).
struct TruthPoint {
  double t_s = 0.0;
  fsw::Vec3 llh = fsw::Vec3::Zero();
  fsw::Vec3 vel_enu_mps = fsw::Vec3::Zero();
  fsw::Quat q_b_n = fsw::Quat::Identity();
  bool has_attitude = true;  ///< false for a position/velocity reference (an imported GNSS solution)
};

inline TruthPoint truth_point(const TruthSample& t) {
  return TruthPoint{t.t_s, t.llh, t.vel_enu_mps, fsw::Quat(t.C_b_n), true};
}

/// Errors of a navigation solution against truth at one instant.
struct NavErrors {
  fsw::Vec3 pos_enu_m = fsw::Vec3::Zero();        ///< nav minus truth
  fsw::Vec3 vel_enu_mps = fsw::Vec3::Zero();      ///< nav minus truth
  fsw::Vec3 att_phi_enu_rad = fsw::Vec3::Zero();  ///< attitude error phi (frames.hpp)
};

inline NavErrors nav_errors(const fsw::NavState& nav, const TruthSample& truth) {
  NavErrors e;
  e.pos_enu_m = fsw::enu_difference_m(nav.llh, truth.llh);
  e.vel_enu_mps = nav.vel_enu_mps - truth.vel_enu_mps;
  e.att_phi_enu_rad = fsw::attitude_error_enu(nav.C_b_n(), truth.C_b_n);
  return e;
}

/// A reference without attitude gives a NaN attitude error.
inline NavErrors nav_errors(const fsw::NavState& nav, const TruthPoint& truth) {
  NavErrors e;
  e.pos_enu_m = fsw::enu_difference_m(nav.llh, truth.llh);
  e.vel_enu_mps = nav.vel_enu_mps - truth.vel_enu_mps;
  e.att_phi_enu_rad = truth.has_attitude ? fsw::attitude_error_enu(nav.C_b_n(), truth.q_b_n.toRotationMatrix())
                                         : fsw::Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  return e;
}

}  // namespace sim
