// Self-alignment errors against the paper's section II expressions (within 5%).
#include <gtest/gtest.h>

#include "fsw/alignment.hpp"
#include "tools/analysis.hpp"

using fsw::kDegToRad;
using fsw::Vec3;

namespace {
constexpr double kUg = fsw::kMicroG_mps2;
constexpr double kDph = fsw::kDegPerHourToRadps;
const double kLat = 35.0 * kDegToRad;

void expect_within_5pct(const tools::AlignmentCase& c, int axis) {
  const double f = c.phi_formula_rad(axis), s = c.phi_sim_rad(axis);
  ASSERT_GT(std::abs(f), 1e-7) << c.name;
  EXPECT_NEAR(s, f, 0.05 * std::abs(f)) << c.name << " axis " << axis;
}
}  // namespace

TEST(Alignment, LevellingErrorsFollowAccelerometerBias) {
  // Body x North, y East: a y-accelerometer bias is an East bias -> phi_N = dA_E / g.
  const auto east = tools::run_alignment_case("accel_y", Vec3(0, 100 * kUg, 0), Vec3::Zero(), kLat, 0.0, 120.0);
  expect_within_5pct(east, 1);
  EXPECT_NEAR(east.phi_formula_rad(1), 100 * kUg / fsw::normal_gravity_mps2(kLat, 100.0), 1e-12);
  // x-accelerometer bias is a North bias -> phi_E = -dA_N / g.
  const auto north = tools::run_alignment_case("accel_x", Vec3(100 * kUg, 0, 0), Vec3::Zero(), kLat, 0.0, 120.0);
  expect_within_5pct(north, 0);
  EXPECT_LT(north.phi_sim_rad(0), 0.0);
}

TEST(Alignment, GyrocompassHeadingErrorFollowsEastGyroBias) {
  // Heading North: body y is East. phi_U magnitude eps_E / (Omega cos L) as in the paper.
  const auto c = tools::run_alignment_case("gyro_y", Vec3::Zero(), Vec3(0, 0.01 * kDph, 0), kLat, 0.0, 120.0);
  expect_within_5pct(c, 2);
  EXPECT_NEAR(std::abs(c.phi_formula_rad(2)),
              0.01 * kDph / (fsw::wgs84::omega_ie_radps * std::cos(kLat)), 1e-12);
  // A North gyro bias does not disturb the heading (first order).
  const auto n = tools::run_alignment_case("gyro_x", Vec3::Zero(), Vec3(0.01 * kDph, 0, 0), kLat, 0.0, 120.0);
  EXPECT_LT(std::abs(n.phi_sim_rad(2)), 0.05 * std::abs(c.phi_sim_rad(2)));
}

TEST(Alignment, CombinedBiasesAtArbitraryHeading) {
  const Vec3 ab(70 * kUg, -100 * kUg, 40 * kUg), gb(0.01 * kDph, -0.007 * kDph, 0.004 * kDph);
  const auto c = tools::run_alignment_case("combined", ab, gb, kLat, 37.0 * kDegToRad, 120.0);
  for (int axis = 0; axis < 3; ++axis) expect_within_5pct(c, axis);
}

TEST(Alignment, RejectsBadInputAndUndefinedGeometry) {
  fsw::CoarseAlignment a;
  fsw::Mat3 C;
  EXPECT_EQ(a.solve(kLat, C), fsw::Status::kNotConverged);  // no data
  fsw::ImuSample s;
  s.dt_s = 0.001;
  s.dv_mps = Vec3(0, 0, std::nan(""));
  EXPECT_EQ(a.add(s), fsw::Status::kBadInput);
  s.dv_mps = Vec3(0, 0, -9.8e-3);
  EXPECT_EQ(a.add(s), fsw::Status::kOk);
  EXPECT_EQ(a.solve(kLat, C), fsw::Status::kNotConverged);  // no Earth rate sensed
}
