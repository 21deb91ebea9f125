// Frame conventions and the WGS-84 Earth model: the one place they are stated.
//
// FRAMES
//   i  inertial (ECI); e  Earth-fixed (ECEF, WGS-84).
//   n  navigation frame: local-level ENU (x East, y North, z Up), as in the reference paper.
//   b  body frame, aircraft convention: x forward (nose), y right wing, z down.
//
// DIRECTION COSINE MATRICES
//   C_b_n maps body-frame components to navigation-frame components: v_n = C_b_n * v_b.
//   C_a_b in general maps a-frame components to b-frame components. The quaternion q_b_n is the
//   Hamilton unit quaternion (Eigen convention) with q_b_n.toRotationMatrix() == C_b_n.
//
// EULER ANGLES (aircraft convention, relative to local North-East-Down)
//   heading psi (true, from North towards East, clockwise seen from above), pitch theta (nose up
//   positive), roll phi (right wing down positive). C_b_ned = Rz(psi) * Ry(theta) * Rx(phi) and
//   C_b_n = C_ned_enu * C_b_ned. A right (clockwise) turn has phi > 0 and psi increasing.
//
// ANGULAR RATES
//   omega_a_b_c: rate of frame b relative to frame a, in frame c components.
//   omega_ie_n  Earth rate in n; omega_en_n transport rate; omega_in_n = omega_ie_n + omega_en_n.
//   omega_ib_b  what a gyro triad senses; f_b specific force, what an accelerometer triad senses.
//
// ATTITUDE ERROR (the paper's phi, in ENU components phi_E, phi_N, phi_U)
//   Computed attitude C_b_n_hat = (I - [phi x]) * C_b_n_true. phi_U is the heading (vertical-axis)
//   attitude error. C_hat ~ Rot(-phi) C_true, so a positive phi_U means the computed frame is
//   rotated clockwise (seen from above) relative to truth: the computed heading exceeds the true
//   heading by phi_U (for small tilts).
//
// POSITION  geodetic latitude L [rad], longitude lambda [rad], ellipsoidal height h [m].
#pragma once

#include <algorithm>
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace fsw {

using Vec3 = Eigen::Matrix<double, 3, 1>;
using Mat3 = Eigen::Matrix<double, 3, 3>;
using Quat = Eigen::Quaternion<double>;

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kDegToRad = kPi / 180.0;
inline constexpr double kRadToDeg = 180.0 / kPi;
inline constexpr double kArcsecToRad = kDegToRad / 3600.0;
inline constexpr double kRadToArcsec = 1.0 / kArcsecToRad;
inline constexpr double kDegPerHourToRadps = kDegToRad / 3600.0;
/// Conventional standard gravity, used only for unit conversions (ug, deg/h/g), never for navigation.
inline constexpr double kStandardGravity_mps2 = 9.80665;
inline constexpr double kMicroG_mps2 = 1e-6 * kStandardGravity_mps2;

/// WGS-84 defining and derived constants (NIMA TR8350.2).
namespace wgs84 {
inline constexpr double a_m = 6378137.0;                       ///< semi-major axis
inline constexpr double f = 1.0 / 298.257223563;               ///< flattening
inline constexpr double b_m = a_m * (1.0 - f);                 ///< semi-minor axis
inline constexpr double e2 = f * (2.0 - f);                    ///< first eccentricity squared
inline constexpr double omega_ie_radps = 7.292115e-5;          ///< Earth rotation rate
inline constexpr double GM_m3ps2 = 3.986004418e14;             ///< gravitational constant
inline constexpr double gamma_e_mps2 = 9.7803253359;           ///< normal gravity at equator
inline constexpr double gamma_p_mps2 = 9.8321849378;           ///< normal gravity at pole
inline constexpr double k_somigliana = (b_m * gamma_p_mps2) / (a_m * gamma_e_mps2) - 1.0;
inline constexpr double m = omega_ie_radps * omega_ie_radps * a_m * a_m * b_m / GM_m3ps2;
}  // namespace wgs84

/// Skew-symmetric (cross-product) matrix: skew(a) * b == a.cross(b).
inline Mat3 skew(const Vec3& a) {
  Mat3 s;
  s << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return s;
}

/// Rotation-vector to quaternion (exact; series near zero). q represents the rotation by |rv| about rv.
inline Quat quat_from_rotvec(const Vec3& rv) {
  const double a2 = rv.squaredNorm();
  double s = 0.0;  // sin(|rv|/2)/|rv|
  double c = 0.0;  // cos(|rv|/2)
  if (a2 < 1e-8) {
    s = 0.5 - a2 / 48.0 + a2 * a2 / 3840.0;
    c = 1.0 - a2 / 8.0 + a2 * a2 / 384.0;
  } else {
    const double a = std::sqrt(a2);
    s = std::sin(0.5 * a) / a;
    c = std::cos(0.5 * a);
  }
  return Quat(c, s * rv.x(), s * rv.y(), s * rv.z());
}

/// Quaternion to rotation vector (inverse of quat_from_rotvec, shortest rotation).
inline Vec3 rotvec_from_quat(Quat q) {
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  const Vec3 v = q.vec();
  const double sn = v.norm();
  if (sn < 1e-12) return 2.0 * v;
  const double angle = 2.0 * std::atan2(sn, q.w());
  return v * (angle / sn);
}

/// Permutation between local North-East-Down and East-North-Up (its own inverse).
inline Mat3 C_ned_enu() {
  Mat3 c;
  c << 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0;
  return c;
}

/// The sines and cosines of Euler angles (roll, pitch, heading): C_b_n_from_euler and
/// omega_nb_b_from_euler_rates take them, and their angle overloads build them, so a caller that
/// needs both at the same angles (the truth's kinematics) pays for each sine once, with the same
/// bits as the overloads.
struct EulerTerms {
  double sin_roll, cos_roll, sin_pitch, cos_pitch, sin_heading, cos_heading;
  static EulerTerms of(double roll_rad, double pitch_rad, double heading_rad) {
    return {std::sin(roll_rad), std::cos(roll_rad),       std::sin(pitch_rad),
            std::cos(pitch_rad), std::sin(heading_rad), std::cos(heading_rad)};
  }
};

/// Euler angles (roll, pitch, heading) -> C_b_n (n = ENU). See conventions above.
inline Mat3 C_b_n_from_euler(const EulerTerms& e) {
  const double cr = e.cos_roll, sr = e.sin_roll, cp = e.cos_pitch, sp = e.sin_pitch;
  const double ch = e.cos_heading, sh = e.sin_heading;
  Mat3 c_b_ned;
  c_b_ned << cp * ch, -cr * sh + sr * sp * ch, sr * sh + cr * sp * ch,  //
      cp * sh, cr * ch + sr * sp * sh, -sr * ch + cr * sp * sh,          //
      -sp, sr * cp, cr * cp;
  return C_ned_enu() * c_b_ned;
}
inline Mat3 C_b_n_from_euler(double roll_rad, double pitch_rad, double heading_rad) {
  return C_b_n_from_euler(EulerTerms::of(roll_rad, pitch_rad, heading_rad));
}

/// C_b_n -> Euler angles (roll, pitch, heading) [rad]; heading in [0, 2 pi).
inline Vec3 euler_from_C_b_n(const Mat3& C_b_n) {
  const Mat3 c = C_ned_enu() * C_b_n;  // C_b_ned
  const double pitch = std::asin(std::clamp(-c(2, 0), -1.0, 1.0));
  const double roll = std::atan2(c(2, 1), c(2, 2));
  double heading = std::atan2(c(1, 0), c(0, 0));
  if (heading < 0.0) heading += 2.0 * kPi;
  return Vec3(roll, pitch, heading);
}

/// Body angular rate relative to the navigation frame from Euler angles and their rates (the
/// heading's sine and cosine are not used).
inline Vec3 omega_nb_b_from_euler_rates(const EulerTerms& e, double roll_rate, double pitch_rate,
                                        double heading_rate) {
  const double cr = e.cos_roll, sr = e.sin_roll, cp = e.cos_pitch, sp = e.sin_pitch;
  return Vec3(roll_rate - heading_rate * sp, pitch_rate * cr + heading_rate * sr * cp,
              -pitch_rate * sr + heading_rate * cr * cp);
}
inline Vec3 omega_nb_b_from_euler_rates(double roll, double pitch, double roll_rate, double pitch_rate,
                                        double heading_rate) {
  const EulerTerms e{std::sin(roll), std::cos(roll), std::sin(pitch), std::cos(pitch), 0.0, 1.0};
  return omega_nb_b_from_euler_rates(e, roll_rate, pitch_rate, heading_rate);
}

/// Attitude error phi (ENU) between a computed and a true C_b_n: C_hat = (I - [phi x]) C_true.
inline Vec3 attitude_error_enu(const Mat3& C_b_n_hat, const Mat3& C_b_n_true) {
  // C_true * C_hat^T = (I - [phi x])^T ~ I + [phi x]; exact via the rotation vector.
  const Quat dq(C_b_n_true * C_b_n_hat.transpose());
  return rotvec_from_quat(dq);
}

// ------------------------------------------------------------------------------------------------
// WGS-84 Earth model
// ------------------------------------------------------------------------------------------------

/// The trigonometry of one geodetic latitude, computed once (one sin/cos pair): the Earth-model
/// functions below take it, and their latitude overloads build it, so each formula is written
/// once and a caller that needs several of them at one latitude (the strapdown step: radii, Earth
/// rate, transport rate and gravity at the same midpoint) pays for the sine once, with the same
/// bits as the overloads (the same operations in the same order).
struct LatitudeTerms {
  double lat_rad, sin_lat, cos_lat;
  explicit LatitudeTerms(double lat) : lat_rad(lat), sin_lat(std::sin(lat)), cos_lat(std::cos(lat)) {}
  /// From a sine and cosine the caller already has of this latitude (std::sin and std::cos of it).
  LatitudeTerms(double lat, double s, double c) : lat_rad(lat), sin_lat(s), cos_lat(c) {}
};

/// Meridian radius of curvature R_M (north-south) [m], from the sine of the latitude.
inline double meridian_radius_from_sin_m(double s) {
  const double d = 1.0 - wgs84::e2 * s * s;
  return wgs84::a_m * (1.0 - wgs84::e2) / (d * std::sqrt(d));
}
inline double meridian_radius_m(const LatitudeTerms& l) { return meridian_radius_from_sin_m(l.sin_lat); }
/// Meridian radius of curvature R_M (north-south) [m].
inline double meridian_radius_m(double lat_rad) { return meridian_radius_from_sin_m(std::sin(lat_rad)); }

/// Normal (prime-vertical) radius of curvature R_N (east-west) [m], from the sine of the latitude.
inline double normal_radius_from_sin_m(double s) { return wgs84::a_m / std::sqrt(1.0 - wgs84::e2 * s * s); }
inline double normal_radius_m(const LatitudeTerms& l) { return normal_radius_from_sin_m(l.sin_lat); }
/// Normal (prime-vertical) radius of curvature R_N (east-west) [m].
inline double normal_radius_m(double lat_rad) { return normal_radius_from_sin_m(std::sin(lat_rad)); }

/// sqrt(1 - e2 sin^2(lat)) from the latitude's sine: Somigliana's denominator below.
inline double sqrt_1_e2_s2(double sin_lat) { return std::sqrt(1.0 - wgs84::e2 * (sin_lat * sin_lat)); }

/// Normal gravity magnitude: Somigliana on the ellipsoid with the second-order height term
/// (NIMA TR8350.2 eq. 4-1 and 4-3). Points along the ellipsoid normal, downwards. This one from
/// the latitude's squared sine s2 and root_1_e2_s2 = sqrt_1_e2_s2(sin) (a caller that carries
/// them: the truth's evaluations within a step).
inline double normal_gravity_from_sin2_mps2(double s2, double root_1_e2_s2, double h_m) {
  const double g0 = wgs84::gamma_e_mps2 * (1.0 + wgs84::k_somigliana * s2) / root_1_e2_s2;
  const double a = wgs84::a_m;
  return g0 * (1.0 - 2.0 / a * (1.0 + wgs84::f + wgs84::m - 2.0 * wgs84::f * s2) * h_m + 3.0 * h_m * h_m / (a * a));
}
inline double normal_gravity_mps2(const LatitudeTerms& l, double h_m) {
  return normal_gravity_from_sin2_mps2(l.sin_lat * l.sin_lat, sqrt_1_e2_s2(l.sin_lat), h_m);
}
inline double normal_gravity_mps2(double lat_rad, double h_m) { return normal_gravity_mps2(LatitudeTerms(lat_rad), h_m); }

/// Gravity vector in ENU (normal gravity, deflection of the vertical neglected).
inline Vec3 gravity_enu_mps2(const LatitudeTerms& l, double h_m) { return Vec3(0.0, 0.0, -normal_gravity_mps2(l, h_m)); }
inline Vec3 gravity_enu_mps2(double lat_rad, double h_m) { return gravity_enu_mps2(LatitudeTerms(lat_rad), h_m); }

/// Earth rate in ENU.
inline Vec3 omega_ie_n(const LatitudeTerms& l) {
  return Vec3(0.0, wgs84::omega_ie_radps * l.cos_lat, wgs84::omega_ie_radps * l.sin_lat);
}
inline Vec3 omega_ie_n(double lat_rad) { return omega_ie_n(LatitudeTerms(lat_rad)); }

/// Transport rate in ENU from the radii of curvature R_M, R_N and the latitude's tangent there (a
/// caller that has them: the truth's evaluations within a step), the height and ENU velocity.
inline Vec3 omega_en_n(double r_m_m, double r_n_m, double tan_lat, double h_m, const Vec3& vel_enu_mps) {
  const double rm = r_m_m + h_m;
  const double rn = r_n_m + h_m;
  return Vec3(-vel_enu_mps.y() / rm, vel_enu_mps.x() / rn, vel_enu_mps.x() * tan_lat / rn);
}
/// Transport rate in ENU for position (lat, h) and ENU velocity.
inline Vec3 omega_en_n(const LatitudeTerms& l, double h_m, const Vec3& vel_enu_mps) {
  return omega_en_n(meridian_radius_m(l), normal_radius_m(l), std::tan(l.lat_rad), h_m, vel_enu_mps);
}
inline Vec3 omega_en_n(double lat_rad, double h_m, const Vec3& vel_enu_mps) {
  return omega_en_n(LatitudeTerms(lat_rad), h_m, vel_enu_mps);
}

/// Rate of change of (lat, lon, h) for an ENU velocity, from the radii of curvature R_M, R_N and
/// the cosine of the latitude there (a caller that has them: the truth's RK4 stages).
inline Vec3 llh_rate(double r_m_m, double r_n_m, double cos_lat, double h_m, const Vec3& vel_enu_mps) {
  return Vec3(vel_enu_mps.y() / (r_m_m + h_m), vel_enu_mps.x() / ((r_n_m + h_m) * cos_lat), vel_enu_mps.z());
}
/// Rate of change of (lat, lon, h) for an ENU velocity.
inline Vec3 llh_rate(const Vec3& llh, const Vec3& vel_enu_mps) {
  const LatitudeTerms l(llh.x());
  return llh_rate(meridian_radius_m(l), normal_radius_m(l), l.cos_lat, llh.z(), vel_enu_mps);
}

/// Small (lat, lon, h) change for an ENU displacement [m] at llh (the same map as llh_rate).
inline Vec3 llh_delta_from_enu(const Vec3& llh, const Vec3& d_enu_m) { return llh_rate(llh, d_enu_m); }

/// Geodetic (lat, lon, h) -> ECEF [m].
inline Vec3 ecef_from_llh(const Vec3& llh) {
  const double lat = llh.x(), lon = llh.y(), h = llh.z();
  const double rn = normal_radius_m(lat);
  const double cl = std::cos(lat);
  return Vec3((rn + h) * cl * std::cos(lon), (rn + h) * cl * std::sin(lon), (rn * (1.0 - wgs84::e2) + h) * std::sin(lat));
}

/// ECEF -> geodetic (lat, lon, h); iterative, converges to < 1e-9 m within a few iterations.
inline Vec3 llh_from_ecef(const Vec3& r_e) {
  const double p = std::hypot(r_e.x(), r_e.y());
  const double lon = std::atan2(r_e.y(), r_e.x());
  double lat = std::atan2(r_e.z(), p * (1.0 - wgs84::e2));
  double h = 0.0;
  for (int i = 0; i < 8; ++i) {
    const double rn = normal_radius_m(lat);
    const double cl = std::cos(lat);
    h = (std::abs(cl) > 1e-9) ? p / cl - rn : std::abs(r_e.z()) - wgs84::b_m;
    lat = std::atan2(r_e.z(), p * (1.0 - wgs84::e2 * rn / (rn + h)));
  }
  return Vec3(lat, lon, h);
}

/// C_n_e: ENU -> ECEF rotation at (lat, lon).
inline Mat3 C_n_e(double lat_rad, double lon_rad) {
  const double sl = std::sin(lat_rad), cl = std::cos(lat_rad);
  const double so = std::sin(lon_rad), co = std::cos(lon_rad);
  Mat3 c;
  c << -so, -sl * co, cl * co,  //
      co, -sl * so, cl * so,    //
      0.0, cl, sl;
  return c;
}

/// Position difference a - b of two (lat, lon, h) points in ENU metres, with the radii of b: the
/// exact inverse of llh_delta_from_enu at b (enu_difference_m(b + llh_delta_from_enu(b, d), b) == d
/// up to rounding). Ekf::update_pvt forms its position innovation with it.
inline Vec3 enu_difference_m(const Vec3& llh_a, const Vec3& llh_b) {
  const double lat = llh_b.x();
  return Vec3((llh_a.y() - llh_b.y()) * (normal_radius_m(lat) + llh_b.z()) * std::cos(lat),
              (llh_a.x() - llh_b.x()) * (meridian_radius_m(lat) + llh_b.z()), llh_a.z() - llh_b.z());
}

}  // namespace fsw
