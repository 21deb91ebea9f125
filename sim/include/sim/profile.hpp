// Externally generated trajectory profiles (position, velocity and attitude sampled in time) and
// their representation as a continuous Motion, so that the TruthGenerator can derive the ideal
// IMU output from them.
//
// FILE FORMAT (the layout of P. D. Groves' textbook software profiles, e.g. Profile_3.csv)
//   No header, one sample per line, 10 comma-separated numbers:
//   time [s], latitude [deg], longitude [deg], ellipsoidal height [m],
//   velocity north, east, down [m/s], roll, pitch, yaw (heading) [deg].
//   The Euler angles are relative to local North-East-Down with the convention of frames.hpp
//   (C_b_ned = Rz(yaw) Ry(pitch) Rx(roll)). Times must be strictly increasing. Blank lines are
//   ignored; anything else that is not 10 finite numbers is rejected with its line number.
//   On load everything is converted to SI and to the project's ENU navigation frame.
//
// CONTINUOUS REPRESENTATION (ProfileMotion)
//   * Velocity: each ENU component is a not-a-knot cubic spline through the samples (C2), so the
//     truth velocity equals the profile velocity at every sample and acc_enu is its exact
//     derivative.
//   * Position: NOT interpolated. It is the ODE state (lat, lon, h), integrated from the first
//     sample's position with that same velocity spline, so position and velocity are exactly
//     consistent. Its distance from the profile's own positions measures how self-consistent the
//     profile is (for Profile_3 the profile positions are the trapezoidal integral of its
//     velocities to within the printed precision, see tests/unit/test_profile.cpp).
//   * Attitude: roll, pitch and the unwrapped heading are not-a-knot cubic splines through the
//     samples; C_b_n follows from frames.hpp and omega_nb_b from the exact Euler-angle rates, so
//     the attitude and the body rate are analytically consistent and the attitude equals the
//     profile's at every sample. (Euler angles are singular at pitch = +/-90 deg; profiles with
//     |pitch| above kMaxAbsPitchDeg are rejected.)
//   The truth is therefore: velocity and attitude as sampled by the profile, position as the
//   integral of that velocity. The samples are honoured as they are, jitter included: Profile_3's
//   velocities carry about +/-2 mm/s of rounding jitter, which the spline turns into up to
//   0.2 m/s^2 of acceleration at the 100 Hz scale in straight flight. That is part of the motion
//   the ideal IMU output then describes (smoothing it would make the truth depart from the
//   profile's velocities and from the positions the profile integrated from them). Motion time 0 is the first sample's time; beyond the first and
//   last samples the end polynomials of the splines are continued.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "sim/trajectory.hpp"

namespace sim {

/// One profile sample in SI units and the ENU navigation frame.
struct ProfileRow {
  double t_s = 0.0;
  Vec3 llh = Vec3::Zero();          ///< lat [rad], lon [rad], h [m]
  Vec3 vel_enu_mps = Vec3::Zero();  ///< ENU velocity (converted from the file's NED)
  Vec3 euler_rad = Vec3::Zero();    ///< roll, pitch, heading [rad], as in the file (not unwrapped)
  Mat3 C_b_n() const { return fsw::C_b_n_from_euler(euler_rad.x(), euler_rad.y(), euler_rad.z()); }
};

struct ProfileLoadResult {
  std::vector<ProfileRow> rows;
  std::string error;  ///< empty on success; otherwise "<source>:<line>: <reason>" (or "<source>: ...")
  bool ok() const { return error.empty(); }
};

/// Reads a profile file. Never throws; on any problem returns no rows and an error message.
ProfileLoadResult load_profile(const std::string& path);
/// Parses profile text; `source` names it in error messages.
ProfileLoadResult parse_profile_text(const std::string& text, const std::string& source);

/// Interpolating cubic spline with not-a-knot end conditions (the spline is a single cubic over
/// the first two and over the last two intervals), for strictly increasing knots. It reproduces
/// any cubic polynomial exactly. With fewer than 4 knots it degrades to the interpolating
/// polynomial of degree n - 1 (constant, line, parabola).
class CubicSpline {
 public:
  CubicSpline() = default;
  /// x strictly increasing, x.size() == y.size() >= 1 (checked by the caller).
  CubicSpline(std::vector<double> x, const std::vector<double>& y);

  double value(double x) const;
  double derivative(double x) const;
  double second_derivative(double x) const;

 private:
  /// Interval index i with x in [x_i, x_{i+1}); clamped to the first/last interval outside.
  std::size_t interval(double x) const;

  std::vector<double> x_;
  // Polynomial on interval i in u = x - x_i: a_i + b_i u + c_i u^2 + d_i u^3.
  std::vector<double> a_, b_, c_, d_;
};

/// A sampled profile as a smooth Motion (see the file comment). ODE state y = (lat, lon, h).
class ProfileMotion final : public Motion {
 public:
  static constexpr double kMaxAbsPitchDeg = 85.0;

  /// Needs at least 4 rows with strictly increasing times and |pitch| <= kMaxAbsPitchDeg;
  /// otherwise returns nullptr and an error message.
  static std::unique_ptr<ProfileMotion> create(std::vector<ProfileRow> rows, std::string& error);

  State initial_state() const override;
  State derivative(double t_s, const State& y) const override;
  Kinematics eval(double t_s, const State& y) const override;
  using Motion::derivative;
  using Motion::eval;

  const std::vector<ProfileRow>& rows() const { return rows_; }
  /// Profile time of motion time 0 (the first row's time).
  double start_time_s() const { return rows_.front().t_s; }
  /// Motion time span covered by the rows.
  double duration_s() const { return rows_.back().t_s - rows_.front().t_s; }

  /// Interpolated ENU velocity and its derivative at motion time t.
  Vec3 velocity_enu(double t_s) const;
  Vec3 acceleration_enu(double t_s) const;
  /// Interpolated attitude at motion time t.
  Mat3 C_b_n(double t_s) const;

 private:
  ProfileMotion() = default;

  std::vector<ProfileRow> rows_;
  CubicSpline vel_[3];    ///< E, N, U over profile time
  CubicSpline euler_[3];  ///< roll, pitch, unwrapped heading over profile time
};

}  // namespace sim
