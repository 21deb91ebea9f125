// sdins noise (tools/allan.hpp, tools/noise.hpp): the overlapping Allan deviation, its intervals,
// the noise-term readings and the rest detector, on simulated data of known noise made with the
// project's IMU model (sim/imu_model.hpp) and RNG.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "fsw/frames.hpp"
#include "sim/imu_model.hpp"
#include "sim/rng.hpp"
#include "sim/scenario.hpp"
#include "sim/trajectory.hpp"
#include "tools/allan.hpp"
#include "tools/noise.hpp"

namespace {

using fsw::Vec3;

/// Theoretical Allan variance of white rate noise N, a first-order Gauss-Markov bias (sigma, T)
/// and a bias random walk K (IEEE Std 952 annex C; the Gauss-Markov term from its autocovariance).
double avar_theory(double tau, double n, double gm_sigma, double gm_T, double k) {
  const double x = tau / gm_T;
  const double gm = gm_sigma > 0.0 ? 2.0 * gm_sigma * gm_sigma * gm_T / tau *
                                         (1.0 - (3.0 - 4.0 * std::exp(-x) + std::exp(-2.0 * x)) / (2.0 * x))
                                   : 0.0;
  return n * n / tau + gm + k * k * tau / 3.0;
}

/// A static sensor of the given errors: n samples of dt, zero truth rate, gravity on -z.
std::vector<fsw::ImuSample> static_samples(const sim::ImuErrors& e, std::uint64_t seed, double dt, long long n) {
  sim::ImuModel m(e, seed);
  std::vector<fsw::ImuSample> out;
  out.reserve(static_cast<std::size_t>(n));
  for (long long k = 0; k < n; ++k) {
    sim::TruthSample t;
    t.t_s = static_cast<double>(k + 1) * dt;
    t.dt_s = dt;
    t.dv_mps = Vec3(0.0, 0.0, -9.8 * dt);
    out.push_back(m.measure(t));
  }
  return out;
}

tools::RestSegment whole(const std::vector<fsw::ImuSample>& s) {
  return {0, s.size() - 1, s.front().t_s - s.front().dt_s, s.back().t_s};
}

}  // namespace

TEST(NoiseAllan, EdfFormulasOfNistSp1065) {
  // Table 5 at N = 1001 phase points: white rate noise at m = 1 has about 3/2 (N - 1) / m x 4/9 ...
  const double n = 1001;
  EXPECT_NEAR(tools::oadev_edf(tools::PowerLawNoise::kWhiteRate, n, 1), (1500.0 - 2.0 * 999.0 / 1001.0) * 4.0 / 9.0, 1e-9);
  EXPECT_NEAR(tools::oadev_edf(tools::PowerLawNoise::kRandomWalkRate, n, 100),
              999.0 / 100.0 * (1000.0 * 1000.0 - 300.0 * 1000.0 + 40000.0) / (998.0 * 998.0), 1e-9);
  EXPECT_NEAR(tools::oadev_edf(tools::PowerLawNoise::kFlickerRate, n, 10), 5.0 * n * n / (40.0 * (n + 30.0)), 1e-9);
  EXPECT_EQ(tools::oadev_edf(tools::PowerLawNoise::kWhiteRate, n, 501), 0.0);  // no second difference left
  // Chi-squared quantiles (boost): the median of chi2(2) is 2 ln 2.
  EXPECT_NEAR(tools::chi2_quantile(2.0, 0.5), 2.0 * std::log(2.0), 1e-12);
}

TEST(NoiseAllan, WhiteNoiseCurveFollowsTheoryAndOtherTermsAreUnsupported) {
  // White noise alone, 5 seeds x 6 axes: the curve inside its intervals, N read at 1 s with its
  // interval covering the truth at about 95%, and neither a floor nor a rising part claimed.
  sim::ImuErrors e;
  e.gyro_arw_rad_per_rts = 2e-3;
  e.accel_vrw_mps_per_rts = 5e-3;
  int trials = 0, covered = 0, k_claimed = 0, b_claimed = 0;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const auto s = static_samples(e, seed, 0.01, 30000);  // 300 s at 100 Hz
    const tools::NoiseAnalysis a = tools::analyse_noise(s, {whole(s)});
    ASSERT_EQ(a.axes.size(), 6u);
    for (const tools::AxisNoise& ax : a.axes) {
      const double n = ax.gyro ? e.gyro_arw_rad_per_rts : e.accel_vrw_mps_per_rts;
      int inside = 0;
      for (const tools::AllanPoint& p : ax.curve.points) inside += (p.avar_lo <= n * n / p.tau_s && n * n / p.tau_s <= p.avar_hi);
      EXPECT_GE(inside, static_cast<int>(0.8 * ax.curve.points.size())) << ax.name;
      EXPECT_TRUE(ax.reading.white.supported) << ax.name;
      EXPECT_NEAR(ax.reading.white.read_tau_s, 1.0, 0.01) << ax.name;
      ++trials;
      covered += ax.reading.white.lo <= n && n <= ax.reading.white.hi;
      k_claimed += ax.reading.rate_rw.supported;
      b_claimed += ax.reading.bias.supported;
      // When not supported, an upper bound above zero and the reason.
      if (!ax.reading.rate_rw.supported) EXPECT_GT(ax.reading.rate_rw.value, 0.0);
      if (!ax.reading.bias.supported) EXPECT_NE(ax.reading.bias.note.find("upper bound"), std::string::npos);
    }
  }
  std::printf("white noise only: N covered in %d of %d, K claimed in %d, B claimed in %d\n", covered, trials, k_claimed,
              b_claimed);
  EXPECT_GE(covered, 26);  // 30 trials at 95%: 28.5 expected, P(< 26) = 1.6%
  EXPECT_LE(k_claimed, 2);
  EXPECT_LE(b_claimed, 2);
}

// The stated 95% intervals of N, B and K cover the truth at about the stated rate: white noise +
// Gauss-Markov bias + bias random walk of known parameters, 40 seeds x 6 axes = 240 trials per
// term. B's truth is the theoretical curve's minimum / 0.664 (its definition on the curve).
TEST(NoiseAllan, StatedIntervalsCoverTheTruthOverSeeds) {
  sim::ImuErrors e;
  e.gyro_arw_rad_per_rts = 1e-3;
  e.accel_vrw_mps_per_rts = 2e-3;
  e.gyro_bias_instability_radps = 2e-4;
  e.accel_bias_instability_mps2 = 4e-4;
  e.bias_instability_tau_s = 5.0;
  e.gyro_bias_rw_radps_per_rts = 2e-5;
  e.accel_bias_rw_mps2_per_rts = 4e-5;
  const double dt = 0.02;
  const long long n = 60000;  // 1200 s at 50 Hz
  struct Count {
    int trials = 0, supported = 0, covered = 0;
  } cn, cb, ck;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    const auto s = static_samples(e, seed, dt, n);
    const tools::NoiseAnalysis a = tools::analyse_noise(s, {whole(s)});
    for (const tools::AxisNoise& ax : a.axes) {
      const double N = ax.gyro ? e.gyro_arw_rad_per_rts : e.accel_vrw_mps_per_rts;
      const double S = ax.gyro ? e.gyro_bias_instability_radps : e.accel_bias_instability_mps2;
      const double K = ax.gyro ? e.gyro_bias_rw_radps_per_rts : e.accel_bias_rw_mps2_per_rts;
      double min_avar = 1e300;
      for (double t = 0.02; t < 1200.0; t *= 1.01)
        min_avar = std::min(min_avar, avar_theory(t, N, S, e.bias_instability_tau_s, K));
      const double B = std::sqrt(min_avar) / tools::kFlickerFloorFactor;
      const auto tally = [](Count& c, const tools::NoiseTerm& t, double truth) {
        ++c.trials;
        if (!t.supported) return;
        ++c.supported;
        c.covered += (t.lo <= truth && truth <= t.hi);
      };
      tally(cn, ax.reading.white, N);
      tally(cb, ax.reading.bias, B);
      tally(ck, ax.reading.rate_rw, K);
    }
  }
  const auto report = [](const char* what, const Count& c) {
    std::printf("%s: supported in %d of %d trials, truth inside the stated 95%% interval in %d (%.1f%%)\n", what,
                c.supported, c.trials, c.covered, 100.0 * c.covered / std::max(1, c.supported));
  };
  report("N", cn);
  report("B", cb);
  report("K", ck);
  // N is read in every trial; the floor and the rising part in most (a Gauss-Markov drift makes a
  // hump, not the flicker plateau the reading assumes, and K rises above it late in the span).
  EXPECT_EQ(cn.supported, cn.trials);
  EXPECT_GE(cb.supported, 0.5 * cb.trials);
  EXPECT_GE(ck.supported, 0.4 * ck.trials);
  // About 95%: with 240 trials a true 95% gives 89.5 .. 98.5% at 3 sigma.
  for (const Count* c : {&cn, &cb, &ck}) {
    const double rate = static_cast<double>(c->covered) / c->supported;
    EXPECT_GE(rate, 0.895);
    EXPECT_LE(rate, 0.995);
  }
}

TEST(NoiseAllan, IrregularIntervalsGiveTheSameWhiteNoise) {
  // The walk's IMU has 6-9 ms intervals: the increments are integrated and resampled on the
  // median interval. White noise of a known density, jittered intervals: N within its interval.
  sim::ImuErrors e;
  e.gyro_arw_rad_per_rts = 1e-3;
  e.accel_vrw_mps_per_rts = 3e-3;
  sim::ImuModel m(e, 5);
  sim::Rng r(77);
  std::vector<fsw::ImuSample> s;
  double t = 0.0;
  for (int k = 0; k < 30000; ++k) {
    sim::TruthSample ts;
    ts.dt_s = 0.006 + 0.003 * r.uniform();
    t += ts.dt_s;
    ts.t_s = t;
    s.push_back(m.measure(ts));
  }
  const tools::NoiseAnalysis a = tools::analyse_noise(s, {whole(s)});
  for (const tools::AxisNoise& ax : a.axes) {
    const double n = ax.gyro ? e.gyro_arw_rad_per_rts : e.accel_vrw_mps_per_rts;
    EXPECT_TRUE(ax.reading.white.supported);
    EXPECT_NEAR(ax.reading.white.value / n, 1.0, 0.15) << ax.name;
  }
}

TEST(NoiseSim, BiasRandomWalkGrowsAsItsDensity) {
  // The model's new bias random walk: after T the bias has variance K^2 T (per axis).
  sim::ImuErrors e;
  e.gyro_bias_rw_radps_per_rts = 1e-4;
  e.accel_bias_rw_mps2_per_rts = 1e-3;
  const double dt = 0.01, T = 100.0;
  double vg = 0.0, va = 0.0;
  const int runs = 60;
  for (int seed = 1; seed <= runs; ++seed) {
    const auto s = static_samples(e, static_cast<std::uint64_t>(seed), dt, static_cast<long long>(T / dt));
    for (int i = 0; i < 3; ++i) {
      vg += std::pow(s.back().dtheta_rad(i) / dt, 2);
      va += std::pow(s.back().dv_mps(i) / dt - (i == 2 ? -9.8 : 0.0), 2);
    }
  }
  vg /= 3 * runs;
  va /= 3 * runs;
  // 180 samples of a chi2(1) scaled: relative sigma sqrt(2/180) = 11%; tolerance 35%.
  EXPECT_NEAR(vg / (1e-8 * T), 1.0, 0.35);
  EXPECT_NEAR(va / (1e-6 * T), 1.0, 0.35);
}

// The rest detector on a simulated flight with a known rest span: 60 s at rest, then the default
// bank-to-turn flight (a 60 s straight first, then turns) with a 250 m/s GNSS speed. With GNSS the
// segment is the rest less the 1 s margins; from the IMU alone the unaccelerated straight is
// indistinguishable from rest and the segment runs on into it (the stated limitation).
TEST(NoiseRest, FindsTheRestSpanOfASimulatedFlight) {
  const double dt = 0.01, rest_s = 60.0;
  sim::ImuErrors e;
  e.gyro_arw_rad_per_rts = 5e-4;
  e.accel_vrw_mps_per_rts = 2e-3;
  sim::ImuModel m(e, 9);
  tools::NoiseInput in;
  for (int k = 1; k <= static_cast<int>(rest_s / dt); ++k) {
    sim::TruthSample ts;
    ts.t_s = k * dt;
    ts.dt_s = dt;
    ts.dv_mps = Vec3(0.0, 0.0, -9.8 * dt);
    in.imu.push_back(m.measure(ts));
  }
  sim::Scenario sc;
  sc.duration_s = 200.0;
  std::string err;
  auto motion = sim::FlightMotion::create(sc, err);
  ASSERT_TRUE(motion) << err;
  sim::TruthGenerator gen(*motion, 1.0 / dt);
  for (int k = 0; k < static_cast<int>(sc.duration_s / dt); ++k) {
    sim::TruthSample ts = gen.next();
    ts.t_s += rest_s;
    in.imu.push_back(m.measure(ts));
  }
  for (int k = 0; k <= static_cast<int>(rest_s + sc.duration_s); ++k)
    in.speed.push_back({static_cast<double>(k), k <= rest_s ? 0.0 : sc.start.speed_mps});
  in.speed_source = "test";
  tools::RestDetectorConfig cfg;
  const tools::RestDetection d = tools::detect_rest(in, cfg);
  ASSERT_EQ(d.segments.size(), 1u);
  EXPECT_NEAR(d.segments[0].t_begin_s, cfg.margin_s, 0.05);
  EXPECT_NEAR(d.segments[0].t_end_s, rest_s - cfg.margin_s, 1.05);  // the window containing the last fix
  EXPECT_GT(d.windows_moving_gnss, 50u);  // the straight flight: quiet, but 250 m/s
  cfg.use_gnss = false;
  const tools::RestDetection imu_only = tools::detect_rest(in, cfg);
  ASSERT_GE(imu_only.segments.size(), 1u);
  EXPECT_GT(imu_only.segments[0].t_end_s, rest_s + 30.0);
  EXPECT_LT(imu_only.segments[0].t_end_s, rest_s + 61.0);  // the first turn ends it
}
