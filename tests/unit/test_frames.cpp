// Frame conventions and the WGS-84 Earth model against hand-computed values
// (values from the closed-form WGS-84 expressions evaluated independently in Python).
#include <gtest/gtest.h>

#include "fsw/frames.hpp"

using namespace fsw;

TEST(Earth, RadiiOfCurvature) {
  EXPECT_NEAR(normal_radius_m(0.0), 6378137.0, 1e-6);
  EXPECT_NEAR(meridian_radius_m(0.0), 6335439.327293, 1e-5);
  EXPECT_NEAR(normal_radius_m(kPi / 2), 6399593.625758, 1e-5);
  EXPECT_NEAR(meridian_radius_m(kPi / 2), 6399593.625758, 1e-5);
  EXPECT_NEAR(meridian_radius_m(45 * kDegToRad), 6367381.815620, 1e-5);
  EXPECT_NEAR(normal_radius_m(45 * kDegToRad), 6388838.290121, 1e-5);
}

TEST(Earth, SomiglianaNormalGravityWithHeight) {
  EXPECT_NEAR(normal_gravity_mps2(0.0, 0.0), 9.7803253359, 1e-9);
  EXPECT_NEAR(normal_gravity_mps2(kPi / 2, 0.0), 9.8321849378, 1e-9);
  EXPECT_NEAR(normal_gravity_mps2(45 * kDegToRad, 0.0), 9.8061977694, 1e-9);
  EXPECT_NEAR(normal_gravity_mps2(45 * kDegToRad, 1000.0), 9.8031129435, 1e-9);
  EXPECT_NEAR(normal_gravity_mps2(35 * kDegToRad, 5000.0), 9.7819226579, 1e-9);
  const Vec3 g = gravity_enu_mps2(0.3, 100.0);
  EXPECT_EQ(g.x(), 0.0);
  EXPECT_EQ(g.y(), 0.0);
  EXPECT_LT(g.z(), -9.7);  // points down in ENU
}

TEST(Earth, EarthAndTransportRate) {
  const double lat = 35 * kDegToRad;
  const Vec3 w = omega_ie_n(lat);
  EXPECT_DOUBLE_EQ(w.x(), 0.0);
  EXPECT_NEAR(w.y(), 7.292115e-5 * 0.8191520443, 1e-14);
  EXPECT_NEAR(w.z(), 7.292115e-5 * 0.5735764364, 1e-14);
  // East velocity on the equator: rotation about North at v / (R_N + h).
  const Vec3 wen = omega_en_n(0.0, 1000.0, Vec3(250.0, 0.0, 0.0));
  EXPECT_NEAR(wen.y(), 250.0 / 6379137.0, 1e-15);
  EXPECT_NEAR(wen.x(), 0.0, 1e-18);
  EXPECT_NEAR(wen.z(), 0.0, 1e-18);
  // North velocity: rotation about West (negative East).
  const Vec3 wen2 = omega_en_n(0.0, 0.0, Vec3(0.0, 100.0, 0.0));
  EXPECT_NEAR(wen2.x(), -100.0 / 6335439.327293, 1e-15);
  // Position rates.
  const Vec3 r = llh_rate(Vec3(lat, 0.0, 0.0), Vec3(0.0, 0.0, 3.0));
  EXPECT_DOUBLE_EQ(r.z(), 3.0);
}

TEST(Earth, EcefRoundTripAndKnownPoints) {
  const Vec3 e0 = ecef_from_llh(Vec3(0, 0, 0));
  EXPECT_NEAR(e0.x(), 6378137.0, 1e-6);
  EXPECT_NEAR(e0.y(), 0.0, 1e-6);
  const Vec3 ep = ecef_from_llh(Vec3(kPi / 2, 0, 0));
  EXPECT_NEAR(ep.z(), 6356752.314245, 1e-5);
  for (double lat : {-80.0, -35.0, 0.0, 35.0, 89.0}) {
    const Vec3 llh(lat * kDegToRad, 2.2, 12345.0);
    const Vec3 back = llh_from_ecef(ecef_from_llh(llh));
    EXPECT_NEAR(back.x(), llh.x(), 1e-12);
    EXPECT_NEAR(back.y(), llh.y(), 1e-12);
    EXPECT_NEAR(back.z(), llh.z(), 1e-6);
  }
  // C_n_e columns are East, North, Up in ECEF: Up at (0,0) is +X, North is +Z, East is +Y.
  const Mat3 c = C_n_e(0.0, 0.0);
  EXPECT_TRUE(c.col(0).isApprox(Vec3(0, 1, 0)));
  EXPECT_TRUE(c.col(1).isApprox(Vec3(0, 0, 1)));
  EXPECT_TRUE(c.col(2).isApprox(Vec3(1, 0, 0)));
}

TEST(Frames, BodyAxesFromEulerAngles) {
  // Level, heading North: nose North, right wing East, body z Down.
  Mat3 c = C_b_n_from_euler(0, 0, 0);
  EXPECT_TRUE((c * Vec3(1, 0, 0)).isApprox(Vec3(0, 1, 0)));
  EXPECT_TRUE((c * Vec3(0, 1, 0)).isApprox(Vec3(1, 0, 0)));
  EXPECT_TRUE((c * Vec3(0, 0, 1)).isApprox(Vec3(0, 0, -1)));
  // Heading 90 deg: nose East.
  c = C_b_n_from_euler(0, 0, kPi / 2);
  EXPECT_TRUE((c * Vec3(1, 0, 0)).isApprox(Vec3(1, 0, 0)));
  // Pitch up 10 deg: nose has a positive Up component.
  c = C_b_n_from_euler(0, 10 * kDegToRad, 0);
  EXPECT_NEAR((c * Vec3(1, 0, 0)).z(), std::sin(10 * kDegToRad), 1e-15);
  // Roll right 30 deg: right wing down.
  c = C_b_n_from_euler(30 * kDegToRad, 0, 0);
  EXPECT_NEAR((c * Vec3(0, 1, 0)).z(), -0.5, 1e-15);
  // Round trip.
  const Vec3 e = euler_from_C_b_n(C_b_n_from_euler(-0.7, 0.2, 4.0));
  EXPECT_NEAR(e.x(), -0.7, 1e-13);
  EXPECT_NEAR(e.y(), 0.2, 1e-13);
  EXPECT_NEAR(e.z(), 4.0, 1e-13);
  EXPECT_TRUE(Quat(c).toRotationMatrix().isApprox(c));
}

TEST(Frames, EulerRatesToBodyRate) {
  // Level heading rate (right turn seen from above) is a positive rate about body z (down).
  Vec3 w = omega_nb_b_from_euler_rates(0, 0, 0, 0, 0.1);
  EXPECT_TRUE(w.isApprox(Vec3(0, 0, 0.1)));
  // Banked 60 deg right, heading rate r: body pitch rate r sin(60) > 0, yaw rate r cos(60).
  w = omega_nb_b_from_euler_rates(kPi / 3, 0, 0, 0, 0.1);
  EXPECT_NEAR(w.y(), 0.1 * std::sin(kPi / 3), 1e-15);
  EXPECT_NEAR(w.z(), 0.05, 1e-15);
  // Left turn: negative bank and heading rate, the pitch rate stays positive.
  w = omega_nb_b_from_euler_rates(-kPi / 3, 0, 0, 0, -0.1);
  EXPECT_GT(w.y(), 0.0);
  EXPECT_LT(w.z(), 0.0);
}

TEST(Frames, AttitudeErrorDefinition) {
  const Mat3 c_true = C_b_n_from_euler(0.3, -0.1, 1.0);
  const Vec3 phi(2e-5, -3e-5, 1e-4);
  const Mat3 c_hat = (Mat3::Identity() - skew(phi)) * c_true;
  EXPECT_TRUE(attitude_error_enu(c_hat, c_true).isApprox(phi, 1e-4));
  // phi_U > 0: computed heading larger than truth.
  const Mat3 c_hat2 = quat_from_rotvec(-Vec3(0, 0, 1e-3)).toRotationMatrix() * C_b_n_from_euler(0, 0, 1.0);
  EXPECT_NEAR(attitude_error_enu(c_hat2, C_b_n_from_euler(0, 0, 1.0)).z(), 1e-3, 1e-12);
  EXPECT_NEAR(euler_from_C_b_n(c_hat2).z(), 1.0 + 1e-3, 1e-12);
}

TEST(Frames, RotationVectorQuaternionRoundTrip) {
  for (const Vec3& rv : {Vec3(1e-9, 0, 0), Vec3(0.01, -0.02, 0.03), Vec3(1.0, 2.0, -0.5)}) {
    EXPECT_TRUE(rotvec_from_quat(quat_from_rotvec(rv)).isApprox(rv, 1e-12));
  }
  EXPECT_TRUE(skew(Vec3(1, 2, 3)) * Vec3(-1, 0.5, 4) == Vec3(1, 2, 3).cross(Vec3(-1, 0.5, 4)));
}
