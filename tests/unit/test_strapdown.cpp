// FrameBuilder (coning / sculling compensation) and the Strapdown mechanization against motions
// whose exact answer is known in closed form.
//
// Coning: the classical coning motion C(t) = Rz(W t) Rx(theta) Rz(-W t) (body to reference); its
// body rate, the exact delta-thetas and the exact attitude at any time are closed-form.
// Sculling: angular oscillation about x, theta_x(t) = A sin(W t), with in-phase specific force
// B sin(W t) along body y; over whole periods the reference-frame velocity gain along z is exactly
// B J1(A) T (Bessel function), and each frame's exact dv_sf is a one-dimensional integral
// evaluated here by fine Simpson quadrature.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include "fsw/frames.hpp"
#include "fsw/strapdown.hpp"
#include "test_util.hpp"

namespace {

using fsw::FrameBuilder;
using fsw::FrameIncrement;
using fsw::ImuSample;
using fsw::Mat3;
using fsw::NavState;
using fsw::Quat;
using fsw::Status;
using fsw::Strapdown;
using fsw::Vec3;

using fsw::kPi;
using test_util::kDeg;
using test_util::kInf;
using test_util::kNaN;

Quat qx(double a) { return Quat(Eigen::AngleAxisd(a, Vec3::UnitX())); }
Quat qz(double a) { return Quat(Eigen::AngleAxisd(a, Vec3::UnitZ())); }
Mat3 Rx(double a) { return qx(a).toRotationMatrix(); }

/// Bessel function of the first kind, order 1 (power series; |x| << 1 here).
double bessel_j1(double x) {
  double term = 0.5 * x, sum = term;
  for (int m = 1; m < 20; ++m) {
    term *= -(0.25 * x * x) / (m * (m + 1.0));
    sum += term;
  }
  return sum;
}

/// Angle [rad] of the rotation between two attitudes.
double angle_between(const Quat& a, const Quat& b) { return 2.0 * std::asin(std::min(1.0, (a.inverse() * b).vec().norm())); }

ImuSample sample(double t, double dt, const Vec3& dth, const Vec3& dv) {
  ImuSample s;
  s.t_s = t;
  s.dt_s = dt;
  s.dtheta_rad = dth;
  s.dv_mps = dv;
  return s;
}

void expect_same_frame(const FrameIncrement& a, const FrameIncrement& b) {
  EXPECT_EQ(a.t_s, b.t_s);
  EXPECT_EQ(a.dt_s, b.dt_s);
  EXPECT_EQ(a.rotvec_rad, b.rotvec_rad);
  EXPECT_EQ(a.dv_sf_b_mps, b.dv_sf_b_mps);
  EXPECT_EQ(a.dtheta_sum_rad, b.dtheta_sum_rad);
  EXPECT_EQ(a.dv_sum_mps, b.dv_sum_mps);
}

// ------------------------------------------------------------------------------------------------
// Classical coning motion
// ------------------------------------------------------------------------------------------------
struct Coning {
  double theta;  // cone half-angle
  double W;      // coning frequency [rad/s]
  Quat q(double t) const { return qz(W * t) * qx(theta) * qz(-W * t); }
  Vec3 rate(double t) const {
    return W * Vec3(-std::sin(theta) * std::sin(W * t), std::sin(theta) * std::cos(W * t), std::cos(theta) - 1.0);
  }
  Vec3 dtheta(double t0, double t1) const {
    return Vec3(std::sin(theta) * (std::cos(W * t1) - std::cos(W * t0)),
                std::sin(theta) * (std::sin(W * t1) - std::sin(W * t0)), W * (std::cos(theta) - 1.0) * (t1 - t0));
  }
};

// ------------------------------------------------------------------------------------------------
// Sculling motion
// ------------------------------------------------------------------------------------------------
struct Sculling {
  double A;  // angular amplitude about x
  double W;
  double B;  // specific-force amplitude along body y
  double angle(double t) const { return A * std::sin(W * t); }
  Vec3 f_b(double t) const { return Vec3(0.0, B * std::sin(W * t), 0.0); }
  Vec3 dtheta(double t0, double t1) const { return Vec3(A * (std::sin(W * t1) - std::sin(W * t0)), 0.0, 0.0); }
  Vec3 dv(double t0, double t1) const { return Vec3(0.0, B / W * (std::cos(W * t0) - std::cos(W * t1)), 0.0); }
  /// Exact dv_sf in b(t0): int_t0^t1 Rx(angle(t) - angle(t0)) f_b(t) dt, composite Simpson (n even).
  Vec3 dv_sf_exact(double t0, double t1, int n = 400) const {
    const double h = (t1 - t0) / n;
    Vec3 sum = Vec3::Zero();
    for (int i = 0; i <= n; ++i) {
      const double t = t0 + i * h;
      const double w = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
      sum += w * (Rx(angle(t) - angle(t0)) * f_b(t));
    }
    return sum * h / 3.0;
  }
};

}  // namespace

// ------------------------------------------------------------------------------------------------
// FrameBuilder
// ------------------------------------------------------------------------------------------------

TEST(FrameBuilder, ConfigureRange) {
  FrameBuilder fb;
  EXPECT_EQ(fb.configure(0), Status::kBadConfig);
  EXPECT_EQ(fb.configure(-3), Status::kBadConfig);
  EXPECT_EQ(fb.configure(FrameBuilder::kMaxSamplesPerFrame + 1), Status::kBadConfig);
  EXPECT_EQ(fb.configure(1), Status::kOk);
  EXPECT_EQ(fb.configure(FrameBuilder::kMaxSamplesPerFrame), Status::kOk);
  EXPECT_EQ(fb.samples_per_frame(), FrameBuilder::kMaxSamplesPerFrame);
  EXPECT_EQ(fb.configure(5), Status::kOk);
  // A rejected configuration keeps the previous one.
  EXPECT_EQ(fb.configure(0), Status::kBadConfig);
  EXPECT_EQ(fb.samples_per_frame(), 5);
}

TEST(FrameBuilder, CompletesFrameOnNthSample) {
  FrameBuilder fb;
  ASSERT_EQ(fb.configure(5), Status::kOk);
  const double dts[5] = {1.0e-3, 1.1e-3, 0.9e-3, 1.0e-3, 1.05e-3};
  Vec3 sum_th = Vec3::Zero(), sum_v = Vec3::Zero();
  double t = 10.0, sum_dt = 0.0;
  for (int frame = 0; frame < 3; ++frame) {
    sum_th.setZero();
    sum_v.setZero();
    sum_dt = 0.0;
    for (int k = 0; k < 5; ++k) {
      t += dts[k];
      const Vec3 th(1e-4 * (k + 1), -2e-4, 3e-5 * k * k), v(0.01, 0.002 * k, -0.0098);
      sum_th += th;
      sum_v += v;
      sum_dt += dts[k];
      const Status st = fb.add(sample(t, dts[k], th, v));
      EXPECT_EQ(st, k < 4 ? Status::kFrameIncomplete : Status::kOk) << "frame " << frame << " sample " << k;
    }
    const FrameIncrement& f = fb.frame();
    EXPECT_EQ(f.t_s, t);
    EXPECT_NEAR(f.dt_s, 5.05e-3, 1e-15);
    EXPECT_NEAR(f.dt_s, sum_dt, 1e-18);
    EXPECT_NEAR((f.dtheta_sum_rad - sum_th).norm(), 0.0, 1e-18);
    EXPECT_NEAR((f.dv_sum_mps - sum_v).norm(), 0.0, 1e-17);
    // The compensations are second order: small next to the sums but present.
    EXPECT_LT((f.rotvec_rad - sum_th).norm(), 1e-6);
    EXPECT_LT((f.dv_sf_b_mps - sum_v).norm(), 1e-4);
    EXPECT_GT((f.dv_sf_b_mps - sum_v).norm(), 1e-7);
  }
}

TEST(FrameBuilder, OneSamplePerFrame) {
  FrameBuilder fb;
  ASSERT_EQ(fb.configure(1), Status::kOk);
  for (int k = 1; k <= 4; ++k) {
    ASSERT_EQ(fb.add(sample(k * 5e-3, 5e-3, Vec3(1e-3, 0, 0), Vec3(0, 0, -0.05))), Status::kOk);
    EXPECT_EQ(fb.frame().dt_s, 5e-3);
    EXPECT_EQ(fb.frame().t_s, k * 5e-3);
  }
}

TEST(FrameBuilder, ConstantRateNeedsNoConingAndRotationTermMatchesExactIntegral) {
  // Constant rate w about z and constant specific force f along x: the rotation vector is exactly
  // w T (no coning), and the exact dv_sf in b(k-1) is int_0^T Rz(w t) f dt = f / w (sin wT, 1 - cos wT, 0).
  const double w = 1.0, f = 9.8, h = 1e-3;
  const int n = 5;
  const double T = n * h;
  FrameBuilder fb;
  ASSERT_EQ(fb.configure(n), Status::kOk);
  for (int frame = 0; frame < 2; ++frame) {
    for (int k = 0; k < n; ++k) {
      const Status st = fb.add(sample((frame * n + k + 1) * h, h, Vec3(0, 0, w * h), Vec3(f * h, 0, 0)));
      ASSERT_EQ(st, k + 1 < n ? Status::kFrameIncomplete : Status::kOk);
    }
    const FrameIncrement& fr = fb.frame();
    EXPECT_NEAR((fr.rotvec_rad - Vec3(0, 0, w * T)).norm(), 0.0, 1e-18);
    const Vec3 exact = f / w * Vec3(std::sin(w * T), 1.0 - std::cos(w * T), 0.0);
    const double err = (fr.dv_sf_b_mps - exact).norm();
    const double err_plain = (fr.dv_sum_mps - exact).norm();
    // Rotation compensation is exact to second order: the residual is the third-order term
    // f T (wT)^2 / 6 = 2.0e-7 m/s along x; without it the error is f T (wT) / 2 = 1.2e-4 m/s.
    if (frame == 0) std::printf("constant rate + force: dv_sf error %.3e m/s (bound f T (wT)^2/6 = %.3e), plain sum %.3e m/s\n", err,
                f * T * w * T * w * T / 6.0, err_plain);
    EXPECT_LT(err, 1.05 * f * T * (w * T) * (w * T) / 6.0);
    EXPECT_NEAR(err_plain, f * T * w * T / 2.0, 1e-3 * f * T * w * T);
  }
}

TEST(FrameBuilder, BadSamplesAreRejectedWithoutSideEffects) {
  FrameBuilder a, b;
  ASSERT_EQ(a.configure(5), Status::kOk);
  ASSERT_EQ(b.configure(5), Status::kOk);
  const Coning c{2.0 * kDeg, 2.0 * kPi * 7.0};
  const double h = 1e-3;
  const ImuSample bad[] = {
      sample(1.0, h, Vec3(kNaN, 0, 0), Vec3::Zero()),       sample(1.0, h, Vec3(0, kInf, 0), Vec3::Zero()),
      sample(1.0, h, Vec3::Zero(), Vec3(0, 0, kNaN)),       sample(1.0, h, Vec3::Zero(), Vec3(-kInf, 0, 0)),
      sample(1.0, 0.0, Vec3(1e-3, 0, 0), Vec3::Zero()),     sample(1.0, -h, Vec3(1e-3, 0, 0), Vec3::Zero()),
      sample(1.0, kNaN, Vec3(1e-3, 0, 0), Vec3::Zero()),    sample(1.0, kInf, Vec3(1e-3, 0, 0), Vec3::Zero()),
      sample(kNaN, h, Vec3(1e-3, 0, 0), Vec3::Zero()),
  };
  int bad_idx = 0, frames = 0;
  for (int k = 0; k < 40; ++k) {
    const double t0 = k * h, t1 = (k + 1) * h;
    const ImuSample s = sample(t1, h, c.dtheta(t0, t1), Vec3(0.001 * k, 0.01, -0.0098));
    // Builder a sees a bad sample before every sample (including the first of a frame and the
    // one that completes it), builder b only the good ones: the frames must be identical.
    EXPECT_EQ(a.add(bad[bad_idx]), Status::kBadInput) << "bad sample " << bad_idx;
    bad_idx = (bad_idx + 1) % 9;
    const Status sa = a.add(s), sb = b.add(s);
    ASSERT_EQ(sa, sb);
    if (sa == Status::kOk) {
      ++frames;
      expect_same_frame(a.frame(), b.frame());
    }
  }
  EXPECT_EQ(frames, 8);
  // reset() forgets the partial frame: 5 more samples are needed.
  ASSERT_EQ(a.add(sample(1.0, h, Vec3(1e-3, 0, 0), Vec3::Zero())), Status::kFrameIncomplete);
  a.reset();
  for (int k = 0; k < 4; ++k) EXPECT_EQ(a.add(sample(1.0, h, Vec3(1e-3, 0, 0), Vec3::Zero())), Status::kFrameIncomplete);
  EXPECT_EQ(a.add(sample(1.0, h, Vec3(1e-3, 0, 0), Vec3::Zero())), Status::kOk);
  EXPECT_NEAR(a.frame().dtheta_sum_rad.x(), 5e-3, 1e-18);
}

TEST(FrameBuilder, ClassicalConingMotion) {
  // 1 deg half-angle cone at 10 Hz: the uncompensated coning drift is of order
  // W theta^2 (W T)^2 / 12 ~ 1.6e-4 rad/s at a 5 ms frame. 1 kHz samples, 5 per frame, 10 s.
  const Coning c{1.0 * kDeg, 2.0 * kPi * 10.0};
  const double h = 1e-3, t_end = 10.0;
  const int n_per = 5;
  const long n = std::lround(t_end / h);

  // Sanity of the closed form: body rate = C^T dC/dt (central difference) and d(dtheta)/dt = rate.
  for (double t : {0.013, 0.2777, 3.1}) {
    const double e = 1e-6;
    const Mat3 C = c.q(t).toRotationMatrix();
    const Mat3 dC = (c.q(t + e).toRotationMatrix() - c.q(t - e).toRotationMatrix()) / (2.0 * e);
    const Mat3 W = C.transpose() * dC;  // [w x]
    EXPECT_NEAR((Vec3(W(2, 1), W(0, 2), W(1, 0)) - c.rate(t)).norm(), 0.0, 1e-8);
    EXPECT_NEAR(((c.dtheta(0.0, t + e) - c.dtheta(0.0, t - e)) / (2.0 * e) - c.rate(t)).norm(), 0.0, 1e-8);
  }

  FrameBuilder fb;
  ASSERT_EQ(fb.configure(n_per), Status::kOk);
  Quat q_comp = c.q(0.0), q_plain = c.q(0.0);
  double max_frame_err = 0.0, max_frame_err_plain = 0.0;
  double t_prev_frame = 0.0;
  for (long k = 0; k < n; ++k) {
    const double t0 = k * h, t1 = (k + 1) * h;
    const Status st = fb.add(sample(t1, h, c.dtheta(t0, t1), Vec3::Zero()));
    if (st == Status::kFrameIncomplete) continue;
    ASSERT_EQ(st, Status::kOk);
    const FrameIncrement& f = fb.frame();
    // Exact frame rotation vector b(k-1) -> b(k).
    const Vec3 exact = fsw::rotvec_from_quat(c.q(t_prev_frame).inverse() * c.q(t1));
    max_frame_err = std::max(max_frame_err, (f.rotvec_rad - exact).norm());
    max_frame_err_plain = std::max(max_frame_err_plain, (f.dtheta_sum_rad - exact).norm());
    q_comp = (q_comp * fsw::quat_from_rotvec(f.rotvec_rad)).normalized();
    q_plain = (q_plain * fsw::quat_from_rotvec(f.dtheta_sum_rad)).normalized();
    t_prev_frame = t1;
  }
  const double err = angle_between(q_comp, c.q(t_end));
  const double err_plain = angle_between(q_plain, c.q(t_end));
  const double factor = err_plain / err;
  std::printf("coning (1 deg, 10 Hz, 5 x 1 kHz samples/frame, %.0f s): attitude error compensated %.3e rad "
              "(%.2e arcsec), plain sum %.3e rad (%.1f arcsec), improvement x%.0f; max per-frame rotvec error "
              "%.2e vs %.2e rad\n",
              t_end, err, err / fsw::kArcsecToRad, err_plain, err_plain / fsw::kArcsecToRad, factor, max_frame_err,
              max_frame_err_plain);
  // Uncompensated drift: the frame coning term 1/2 int alpha x omega dt of this motion is, along z,
  // W sin^2(theta) / 2 * (T - sin(W T) / W) per frame, i.e. a steady drift the plain sum misses.
  const double T = n_per * h;
  const double drift_plain =
      0.5 * c.W * std::sin(c.theta) * std::sin(c.theta) * (1.0 - std::sin(c.W * T) / (c.W * T)) * t_end;
  EXPECT_NEAR(err_plain, drift_plain, 0.02 * drift_plain);
  // Compensated: residual drift below 1e-8 rad/s (0.002 deg/h) and at least 1e4 times better.
  EXPECT_LT(err, 1e-8 * t_end);
  EXPECT_GT(factor, 1e4);
  // Per frame, alpha + beta neglects the third-order Bortz term (1/12) int phi x (phi x omega) dt,
  // of size (W theta T)^3 / 36 = 4.6e-9 rad here: bound the per-frame error by three times that,
  // against a plain-sum error of the second-order coning term (W theta T)^2 (W T) / 12 = 7.8e-7 rad.
  const double wtt = c.W * c.theta * T;
  EXPECT_LT(max_frame_err, 3.0 * wtt * wtt * wtt / 36.0);
  EXPECT_NEAR(max_frame_err_plain, wtt * wtt * c.W * T / 12.0, 0.05 * wtt * wtt * c.W * T / 12.0);
}

TEST(FrameBuilder, ConingCompensationImprovesWithMoreSamplesPerFrame) {
  // Same coning, 5 ms frames built from 1, 2, 5 and 10 samples. The recursive algorithm with the
  // previous-sample term is fourth order in the sample interval h for coning: the residual drift
  // must fall as h^4 (factor (n2 / n1)^4 from n1 to n2 samples per frame, within 30%).
  const Coning c{1.0 * kDeg, 2.0 * kPi * 10.0};
  const double T = 5e-3, t_end = 10.0;
  double prev_err = 1.0;
  int prev_n = 0;
  for (int n_per : {1, 2, 5, 10}) {
    const double h = T / n_per;
    FrameBuilder fb;
    ASSERT_EQ(fb.configure(n_per), Status::kOk);
    Quat q = c.q(0.0);
    const long n = std::lround(t_end / h);
    for (long k = 0; k < n; ++k) {
      const double t0 = k * h, t1 = (k + 1) * h;
      if (fb.add(sample(t1, h, c.dtheta(t0, t1), Vec3::Zero())) == Status::kOk) {
        q = (q * fsw::quat_from_rotvec(fb.frame().rotvec_rad)).normalized();
      }
    }
    const double err = angle_between(q, c.q(t_end));
    std::printf("coning, %2d samples/frame: attitude error after %.0f s %.3e rad\n", n_per, t_end, err);
    if (prev_n > 0) {
      const double want = std::pow(static_cast<double>(n_per) / prev_n, 4.0);
      std::printf("  error ratio %d -> %d samples/frame: %.1f (h^4 scaling: %.1f)\n", prev_n, n_per, prev_err / err,
                  want);
      EXPECT_NEAR(prev_err / err, want, 0.3 * want) << prev_n << " -> " << n_per << " samples per frame";
    }
    prev_err = err;
    prev_n = n_per;
  }
}

TEST(FrameBuilder, ScullingMotionPerFrameAndOverWholePeriods) {
  // 1 deg angular oscillation about x at 10 Hz with in-phase 1 m/s^2 along body y: the rectified
  // reference-frame acceleration along z is exactly B J1(A) = 8.7e-3 m/s^2 on average.
  const Sculling s{1.0 * kDeg, 2.0 * kPi * 10.0, 1.0};
  const double h = 1e-3, t_end = 10.0;  // 100 whole periods
  const int n_per = 5;
  FrameBuilder fb;
  ASSERT_EQ(fb.configure(n_per), Status::kOk);
  Vec3 v_comp = Vec3::Zero(), v_plain = Vec3::Zero();
  double max_err = 0.0, max_err_plain = 0.0, t_prev = 0.0;
  const long n = std::lround(t_end / h);
  for (long k = 0; k < n; ++k) {
    const double t0 = k * h, t1 = (k + 1) * h;
    const Status st = fb.add(sample(t1, h, s.dtheta(t0, t1), s.dv(t0, t1)));
    if (st == Status::kFrameIncomplete) continue;
    ASSERT_EQ(st, Status::kOk);
    const FrameIncrement& f = fb.frame();
    const Vec3 exact = s.dv_sf_exact(t_prev, t1);
    max_err = std::max(max_err, (f.dv_sf_b_mps - exact).norm());
    max_err_plain = std::max(max_err_plain, (f.dv_sum_mps - exact).norm());
    const Mat3 C_ref_b = Rx(s.angle(t_prev));  // exact attitude at the start of the frame
    v_comp += C_ref_b * f.dv_sf_b_mps;
    v_plain += C_ref_b * f.dv_sum_mps;
    t_prev = t1;
  }
  const double vz_exact = s.B * bessel_j1(s.A) * t_end;
  const double err = (v_comp - Vec3(0.0, 0.0, vz_exact)).norm();
  const double err_plain = (v_plain - Vec3(0.0, 0.0, vz_exact)).norm();
  std::printf("sculling (1 deg, 10 Hz, 1 m/s^2, %.0f s): exact v_z %.6e m/s; velocity error compensated %.3e, "
              "plain sum %.3e m/s (x%.0f); max per-frame dv_sf error %.2e vs %.2e m/s\n",
              t_end, vz_exact, err, err_plain, err_plain / err, max_err, max_err_plain);
  // J1(x) = x/2 - x^3/16 + x^5/384 - ...: 0.0872632 m/s for A = 1 deg over 10 s.
  EXPECT_NEAR(vz_exact, s.B * (s.A / 2 - std::pow(s.A, 3) / 16 + std::pow(s.A, 5) / 384) * t_end, 1e-14);
  EXPECT_LT(err, 1e-6 * vz_exact);
  EXPECT_GT(err_plain / err, 1e4);
  // Per frame, the algorithm neglects third-order terms such as (1/6) alpha x (alpha x nu), of size
  // (A W T)^2 (B T) / 6 = 2.5e-8 m/s here; without compensation the error is second order,
  // |alpha x nu| / 2 ~ (A W T)(B T) / 2 = 1.4e-5 m/s at most.
  const double a = s.A * s.W * 5e-3, nu = s.B * 5e-3;
  EXPECT_LT(max_err, a * a * nu / 6.0);
  EXPECT_GT(max_err_plain, 0.25 * a * nu);
}

// ------------------------------------------------------------------------------------------------
// Strapdown
// ------------------------------------------------------------------------------------------------

namespace {
NavState nav_at(double lat_deg, double h_m, const Mat3& C_b_n) {
  NavState s;
  s.t_s = 0.0;
  s.llh = Vec3(lat_deg * kDeg, 127.0 * kDeg, h_m);
  s.vel_enu_mps.setZero();
  s.q_b_n = Quat(C_b_n);
  return s;
}

void expect_same_state(const NavState& a, const NavState& b) {
  EXPECT_EQ(a.t_s, b.t_s);
  EXPECT_EQ(a.llh, b.llh);
  EXPECT_EQ(a.vel_enu_mps, b.vel_enu_mps);
  EXPECT_EQ(a.q_b_n.coeffs(), b.q_b_n.coeffs());
}
}  // namespace

TEST(Strapdown, InitValidatesInput) {
  const Mat3 C = fsw::C_b_n_from_euler(0.1, -0.05, 2.0);
  Strapdown sd;
  EXPECT_FALSE(sd.initialised());
  NavState s = nav_at(35.0, 100.0, C);
  s.llh.x() = kNaN;
  EXPECT_EQ(sd.init(s), Status::kBadInput);
  s = nav_at(35.0, 100.0, C);
  s.vel_enu_mps.y() = kInf;
  EXPECT_EQ(sd.init(s), Status::kBadInput);
  s = nav_at(35.0, 100.0, C);
  s.q_b_n.w() = kNaN;
  EXPECT_EQ(sd.init(s), Status::kBadInput);
  EXPECT_EQ(sd.init(nav_at(90.001, 0.0, C)), Status::kBadInput);
  EXPECT_EQ(sd.init(nav_at(-91.0, 0.0, C)), Status::kBadInput);
  EXPECT_FALSE(sd.initialised());
  // Stepping or correcting before a successful init is refused.
  FrameIncrement inc;
  inc.dt_s = 5e-3;
  inc.t_s = 5e-3;
  EXPECT_EQ(sd.step(inc), Status::kNotInitialised);
  EXPECT_EQ(sd.correct(Vec3::Zero(), Vec3::Zero(), Vec3::Zero()), Status::kNotInitialised);
  // Valid: latitudes up to the poles; a non-unit quaternion is normalised.
  EXPECT_EQ(sd.init(nav_at(-89.9, 0.0, C)), Status::kOk);
  s = nav_at(35.0, 100.0, C);
  s.q_b_n.coeffs() *= 3.0;
  EXPECT_EQ(sd.init(s), Status::kOk);
  EXPECT_TRUE(sd.initialised());
  EXPECT_NEAR(sd.state().q_b_n.norm(), 1.0, 1e-15);
  EXPECT_NEAR((sd.state().C_b_n() - C).cwiseAbs().maxCoeff(), 0.0, 1e-15);
}

TEST(Strapdown, BadIncrementLeavesStateUnchanged) {
  const Mat3 C = fsw::C_b_n_from_euler(0.1, -0.05, 2.0);
  Strapdown sd;
  ASSERT_EQ(sd.init(nav_at(35.0, 100.0, C)), Status::kOk);
  FrameIncrement good;
  good.t_s = 5e-3;
  good.dt_s = 5e-3;
  good.rotvec_rad = Vec3(1e-4, 2e-4, -1e-4);
  good.dtheta_sum_rad = good.rotvec_rad;
  good.dv_sf_b_mps = C.transpose() * Vec3(0.0, 0.0, 9.79 * 5e-3);
  good.dv_sum_mps = good.dv_sf_b_mps;
  ASSERT_EQ(sd.step(good), Status::kOk);
  const NavState before = sd.state();
  const Vec3 f_before = sd.f_enu_mps2(), w_before = sd.omega_ib_b_radps();
  FrameIncrement bad = good;
  bad.t_s = 10e-3;
  bad.rotvec_rad.y() = kNaN;
  EXPECT_EQ(sd.step(bad), Status::kBadInput);
  bad = good;
  bad.dv_sf_b_mps.z() = -kInf;
  EXPECT_EQ(sd.step(bad), Status::kBadInput);
  bad = good;
  bad.dt_s = 0.0;
  EXPECT_EQ(sd.step(bad), Status::kBadInput);
  bad.dt_s = kNaN;
  EXPECT_EQ(sd.step(bad), Status::kBadInput);
  expect_same_state(sd.state(), before);
  EXPECT_EQ(sd.f_enu_mps2(), f_before);
  EXPECT_EQ(sd.omega_ib_b_radps(), w_before);
  EXPECT_EQ(sd.correct(Vec3(kNaN, 0, 0), Vec3::Zero(), Vec3::Zero()), Status::kBadInput);
  EXPECT_EQ(sd.correct(Vec3::Zero(), Vec3::Zero(), Vec3(0, kInf, 0)), Status::kBadInput);
  expect_same_state(sd.state(), before);
}

TEST(Strapdown, StationaryImuStaysPutFor600s) {
  // Exact increments of an IMU at rest on the Earth at 35 deg N, 100 m, arbitrary attitude:
  // the gyros sense Earth rate Omega (0, cos L, sin L) (ENU) and the accelerometers the reaction
  // to normal gravity, both constant in the body frame.
  const double lat = 35.0, h_m = 100.0, L = lat * kDeg;
  const Mat3 C = fsw::C_b_n_from_euler(3.0 * kDeg, -2.0 * kDeg, 123.0 * kDeg);
  const Vec3 w_ie_n = 7.292115e-5 * Vec3(0.0, std::cos(L), std::sin(L));
  const double g = fsw::normal_gravity_mps2(L, h_m);
  const Vec3 w_b = C.transpose() * w_ie_n;
  const Vec3 f_b = C.transpose() * Vec3(0.0, 0.0, g);
  const double h = 1e-3, t_end = 600.0;
  FrameBuilder fb;
  ASSERT_EQ(fb.configure(5), Status::kOk);
  Strapdown sd;
  const NavState s0 = nav_at(lat, h_m, C);
  ASSERT_EQ(sd.init(s0), Status::kOk);
  const auto wall0 = std::chrono::steady_clock::now();
  const long n = std::lround(t_end / h);
  double max_pos = 0.0, max_vel = 0.0, max_att = 0.0;
  for (long k = 0; k < n; ++k) {
    const Status st = fb.add(sample((k + 1) * h, h, w_b * h, f_b * h));
    if (st == Status::kFrameIncomplete) continue;
    ASSERT_EQ(st, Status::kOk);
    ASSERT_EQ(sd.step(fb.frame()), Status::kOk);
    const NavState& s = sd.state();
    max_pos = std::max(max_pos, fsw::enu_difference_m(s.llh, s0.llh).norm());
    max_vel = std::max(max_vel, s.vel_enu_mps.norm());
    max_att = std::max(max_att, fsw::attitude_error_enu(s.C_b_n(), C).norm());
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  std::printf("stationary 600 s: max position error %.3e m, velocity %.3e m/s, attitude %.3e rad (%.2f s wall)\n",
              max_pos, max_vel, max_att, wall);
  EXPECT_NEAR(sd.state().t_s, t_end, 1e-9);
  EXPECT_LT(max_pos, 1e-3);
  EXPECT_LT(max_vel, 1e-5);
  EXPECT_LT(max_att, 1e-10);
  // Frame-average outputs: the specific force in n is the reaction to gravity (Up), the body rate Earth rate.
  EXPECT_NEAR((sd.f_enu_mps2() - Vec3(0.0, 0.0, g)).norm(), 0.0, 1e-9);
  EXPECT_NEAR((sd.omega_ib_b_radps() - w_b).norm(), 0.0, 1e-15);
}

TEST(Strapdown, CorrectSubtractsTheDocumentedErrors) {
  const Mat3 C_true = fsw::C_b_n_from_euler(5.0 * kDeg, 2.0 * kDeg, 250.0 * kDeg);
  const NavState truth = [&] {
    NavState s = nav_at(35.0, 5000.0, C_true);
    s.vel_enu_mps = Vec3(-200.0, 120.0, 1.5);
    return s;
  }();
  const Vec3 phi(3e-4, -2e-4, 1e-3);  // ENU attitude error [rad]
  const Vec3 dvel(0.3, -0.2, 0.05);
  const Vec3 dpos(12.0, -7.0, 3.0);   // ENU metres
  // Erroneous solution: C_hat = Rot(-phi) C_true (frames.hpp), velocity and position offset.
  NavState bad = truth;
  bad.q_b_n = fsw::quat_from_rotvec(-phi) * Quat(C_true);
  bad.vel_enu_mps += dvel;
  const double L = truth.llh.x(), hh = truth.llh.z();
  bad.llh += Vec3(dpos.y() / (fsw::meridian_radius_m(L) + hh),
                  dpos.x() / ((fsw::normal_radius_m(L) + hh) * std::cos(L)), dpos.z());
  // The attitude error of the erroneous solution is phi by the frames.hpp definition.
  EXPECT_NEAR((fsw::attitude_error_enu(bad.C_b_n(), C_true) - phi).norm(), 0.0, 1e-15);
  // Small-angle form: C_hat ~ (I - [phi x]) C_true.
  EXPECT_NEAR((bad.C_b_n() - (Mat3::Identity() - fsw::skew(phi)) * C_true).cwiseAbs().maxCoeff(), 0.0,
              phi.squaredNorm());

  Strapdown sd;
  ASSERT_EQ(sd.init(bad), Status::kOk);
  ASSERT_EQ(sd.correct(dpos, dvel, phi), Status::kOk);
  const NavState& s = sd.state();
  EXPECT_LT(fsw::attitude_error_enu(s.C_b_n(), C_true).norm(), 1e-12);
  EXPECT_LT((s.vel_enu_mps - truth.vel_enu_mps).norm(), 1e-12);
  // Position: the metres-to-radians conversion uses the radii and cos(lat) at the (erroneous) current
  // position: a second-order residual of about |dE| tan(L) |dN| / R = 9e-6 m here.
  const double second_order = std::abs(dpos.x()) * std::tan(L) * std::abs(dpos.y()) / 6.37e6;
  EXPECT_LT(fsw::enu_difference_m(s.llh, truth.llh).norm(), 3.0 * second_order);
  EXPECT_NEAR(s.llh.z(), truth.llh.z(), 1e-9);

  // Sign check: correcting with the opposite sign doubles the error instead.
  Strapdown wrong;
  ASSERT_EQ(wrong.init(bad), Status::kOk);
  ASSERT_EQ(wrong.correct(-dpos, -dvel, -phi), Status::kOk);
  EXPECT_NEAR((fsw::attitude_error_enu(wrong.state().C_b_n(), C_true) - 2.0 * phi).norm(), 0.0, 1e-12);
  EXPECT_NEAR((wrong.state().vel_enu_mps - truth.vel_enu_mps - 2.0 * dvel).norm(), 0.0, 1e-12);
  EXPECT_NEAR((fsw::enu_difference_m(wrong.state().llh, truth.llh) - 2.0 * dpos).norm(), 0.0, 1e-4);
}
