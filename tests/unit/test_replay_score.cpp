// The replay's scorer (tools/replay_score.hpp) on a solution with known errors against a known
// reference: constant offsets, an error that grows linearly in each outage, known sigmas.
#include <gtest/gtest.h>

#include <cmath>

#include "fsw/frames.hpp"
#include "tools/replay_score.hpp"

namespace {

tools::Reference straight_line(double t_end_s, double rate_hz) {
  tools::Reference r;
  const fsw::Vec3 llh0(0.8, 0.15, 400.0);
  for (int k = 0; k <= static_cast<int>(t_end_s * rate_hz); ++k) {
    tools::ReferenceSample s;
    s.t_s = k / rate_hz;
    s.vel_enu_mps = fsw::Vec3(10.0, 5.0, 0.0);
    s.llh = llh0 + fsw::llh_delta_from_enu(llh0, s.vel_enu_mps * s.t_s);
    s.q_b_n = fsw::Quat(fsw::C_b_n_from_euler(0.02, -0.01, 1.1));
    s.has_position = s.has_velocity = s.has_attitude = true;
    r.samples.push_back(s);
  }
  return r;
}

/// The reference at t (exactly, the line is straight) moved by d_enu, with velocity and heading offsets.
fsw::NavState solution(double t, const fsw::Vec3& d_enu, const fsw::Vec3& dv, double dheading_rad) {
  const fsw::Vec3 llh0(0.8, 0.15, 400.0);
  const fsw::Vec3 v(10.0, 5.0, 0.0);
  const fsw::Vec3 ref = llh0 + fsw::llh_delta_from_enu(llh0, v * t);
  fsw::NavState n;
  n.t_s = t;
  n.llh = ref + fsw::llh_delta_from_enu(ref, d_enu);
  n.vel_enu_mps = v + dv;
  n.q_b_n = fsw::Quat(fsw::C_b_n_from_euler(0.02, -0.01, 1.1 + dheading_rad));
  return n;
}

TEST(ReplayScore, AConstantErrorIsScoredExactly) {
  tools::ScoreOptions opt;
  tools::ReplayScorer sc(straight_line(100.0, 10.0), opt);
  const std::array<double, 6> sigma{1.0, 1.0, 1.0, 0.1, 0.1, 0.1};
  for (int k = 0; k < 100 * 200; ++k) {  // 200 Hz frames between the 10 Hz reference samples
    const double t = 0.0025 + k * 0.005;
    const fsw::NavState n = solution(t, fsw::Vec3(3.0, 4.0, -2.0), fsw::Vec3(0.1, 0.0, 0.0), 1.0 * fsw::kDegToRad);
    sc.on_frame(n, 0.0);
    if (k % 200 == 0) sc.on_ekf(n, 0.0, sigma);
  }
  const nlohmann::json j = sc.result();
  EXPECT_EQ(j["frames"]["scored"].get<int>(), 100 * 200);
  // Interpolating the straight line between samples is exact up to the curvature of lat/lon: 1e-6 m.
  EXPECT_NEAR(j["position"]["horizontal"]["rms_m"].get<double>(), 5.0, 1e-6);
  EXPECT_NEAR(j["position"]["horizontal"]["max_m"].get<double>(), 5.0, 1e-6);
  EXPECT_NEAR(j["position"]["vertical"]["rms_m"].get<double>(), 2.0, 1e-6);
  EXPECT_NEAR(j["velocity"]["norm"]["rms_mps"].get<double>(), 0.1, 1e-9);
  EXPECT_NEAR(j["attitude"]["heading"]["rms_deg"].get<double>(), 1.0, 1e-6);
  EXPECT_NEAR(j["attitude"]["roll"]["max_deg"].get<double>(), 0.0, 1e-6);
  EXPECT_NEAR(j["nees"]["position_mean"].get<double>(), 9.0 + 16.0 + 4.0, 1e-4);
  EXPECT_NEAR(j["nees"]["velocity_mean"].get<double>(), 1.0, 1e-6);
  EXPECT_DOUBLE_EQ(j["nees"]["position_above_95pct_fraction"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(j["nees"]["velocity_above_95pct_fraction"].get<double>(), 0.0);
  EXPECT_NE(j["nees"]["caveat"].get<std::string>().find("only as good as the reference"), std::string::npos);
}

TEST(ReplayScore, OutagesEndAndDriftAsTheErrorGrows) {
  tools::ScoreOptions opt;
  opt.outage_length_s = 10.0;
  opt.outage_period_s = 30.0;
  opt.outage_first_s = 5.0;
  opt.from_s = 1.0;
  tools::ReplayScorer sc(straight_line(100.0, 10.0), opt);
  const double init = 2.0;
  // East error 0.5 m/s x time since the outage began, inside outages; 0.1 m outside.
  for (int k = 0; k < 98 * 200; ++k) {
    const double t = init + k * 0.005;
    const double since = std::fmod(t - init - 5.0, 30.0);
    const bool in = t >= init + 5.0 && since < 10.0;
    const double e = in ? 0.5 * since : 0.1;
    const fsw::NavState n = solution(t, fsw::Vec3(e, 0.0, -0.2 * e), fsw::Vec3::Zero(), 0.0);
    sc.on_frame(n, init);
    if (k % 200 == 0) sc.on_ekf(n, init, {2.0, 2.0, 1.0, 0.1, 0.1, 0.1});
  }
  const nlohmann::json g = sc.result()["outages"];
  // Windows from 7, 37, 67 s; the one from 97 s starts 2.995 s before the data ends: incomplete.
  ASSERT_EQ(g["windows"].size(), 4u);
  EXPECT_EQ(g["complete"].get<int>(), 3);
  for (int w = 0; w < 3; ++w) {
    const auto& x = g["windows"][static_cast<std::size_t>(w)];
    EXPECT_NEAR(x["start_t_s"].get<double>(), 7.0 + 30.0 * w, 1e-9);
    EXPECT_NEAR(x["end_since_start_s"].get<double>(), 9.995, 1e-6);
    EXPECT_NEAR(x["end_horizontal_m"].get<double>(), 0.5 * 9.995, 1e-5);
    EXPECT_NEAR(x["end_vertical_m"].get<double>(), -0.1 * 9.995, 1e-5);
    // The last EKF run in the window: at 9 s since its start (runs every 1 s from init).
    EXPECT_NEAR(x["end_horizontal_nees"].get<double>(), std::pow(0.5 * 9.0 / 2.0, 2), 1e-6);
    EXPECT_NEAR(x["end_horizontal_sigma_m"].get<double>(), std::sqrt(8.0), 1e-12);
    // The drift curve: every 0.5 s, linear.
    const auto& c = x["curve"];
    ASSERT_GE(c.size(), 20u);
    for (const auto& p : c) EXPECT_NEAR(p[1].get<double>(), 0.5 * p[0].get<double>(), 1e-5);
  }
  EXPECT_FALSE(g["windows"][3]["complete"].get<bool>());
  EXPECT_NEAR(g["end_horizontal"]["rms_m"].get<double>(), 0.5 * 9.995, 1e-5);
  EXPECT_NEAR(g["end_horizontal_nees_mean"].get<double>(), std::pow(0.5 * 9.0 / 2.0, 2), 1e-6);
}

TEST(ReplayScore, FramesWithoutAReferenceAreCountedNotScored) {
  tools::Reference r = straight_line(20.0, 10.0);
  // A 5 s gap in the reference, and no attitude in it.
  tools::Reference gap;
  for (const auto& s : r.samples)
    if (s.t_s < 8.0 || s.t_s > 13.0) {
      gap.samples.push_back(s);
      gap.samples.back().has_attitude = false;
    }
  tools::ScoreOptions opt;
  tools::ReplayScorer sc(gap, opt);
  for (int k = 0; k < 19 * 100; ++k) sc.on_frame(solution(k * 0.01, fsw::Vec3(1.0, 0.0, 0.0), fsw::Vec3::Zero(), 0.0), 0.0);
  const nlohmann::json j = sc.result();
  EXPECT_NEAR(j["frames"]["without_reference"].get<double>(), 519.0, 1.0);  // between 7.9 and 13.1 s
  EXPECT_TRUE(j["attitude"]["heading"].is_null());
  EXPECT_NEAR(j["position"]["horizontal"]["rms_m"].get<double>(), 1.0, 1e-6);
  const std::string text = tools::ReplayScorer::text(j);
  EXPECT_NE(text.find("unlabelled"), std::string::npos);
  EXPECT_NE(text.find("heading no reference"), std::string::npos);
}

}  // namespace
