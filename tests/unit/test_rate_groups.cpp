// The two rate groups (fsw/executive.hpp): the 200 Hz group releases the 1 Hz group with a fixed
// hand-off and lands its correction ekf_latency_frames later, so the outputs do not depend on when
// (or on which thread) the 1 Hz group ran, as long as it finished before that frame.
#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <functional>
#include <memory>
#include <vector>

#include "fsw/flight_app.hpp"
#include "fsw/nav_digest.hpp"
#include "sim/almanac.hpp"
#include "tools/montecarlo.hpp"
#include "sim/sensor_stream.hpp"

namespace {

struct Flight {
  std::uint64_t digest = fsw::kNavDigestSeed;
  std::vector<long> released, landed;  ///< navigation frame indices
  std::vector<fsw::NavState> nav;      ///< every frame's solution
  fsw::ExecutiveHealth health{};
};

/// How a test drives the 1 Hz group: called after every on_imu with the frame count so far;
/// returns whether to run the released group now.
using Policy = std::function<bool(const fsw::FlightApp<fsw::Layout24Full>&, long frame, long released_at)>;

/// Flies 12 s of the default scenario (the sensor stream of Monte Carlo run 0, given start) through the flight
/// application; inline = true runs the 1 Hz group inside on_imu, else as the policy says.
Flight fly(bool inline_group, const Policy& policy, int latency_frames = 10, int imu_samples_per_frame = 0) {
  sim::Scenario sc;
  sc.duration_s = 12.0;
  const sim::TruthTrack truth = sim::TruthTrack::generate(sc);
  const sim::AlmanacParseResult alm = sim::parse_yuma_file(sim::almanac_path(sc.gps));
  EXPECT_TRUE(alm.ok()) << alm.error;
  tools::MonteCarloConfig mc;
  mc.model_gps_errors = true;
  mc.models = {fsw::FilterModel::k24};
  sim::SensorStream stream(sc, truth, *alm.almanac, sc.seed);
  fsw::FlightAppConfig cfg = tools::flight_app_config(sc, mc);
  cfg.exec.ekf_group_inline = inline_group;
  cfg.exec.ekf_latency_frames = latency_frames;
  if (imu_samples_per_frame > 0) cfg.exec.imu_samples_per_frame = imu_samples_per_frame;
  auto app = std::make_unique<fsw::FlightApp<fsw::Layout24Full>>();
  EXPECT_EQ(app->init(cfg), fsw::Status::kOk);
  fsw::InputEvent ev;
  bool more = false;
  while ((more = stream.next(ev)) && ev.kind == fsw::InputEvent::Kind::kAlmanac) (void)app->on_almanac(ev.almanac);
  EXPECT_EQ(app->start_given(tools::initial_nav_state(truth, stream.imu_errors(), mc, sc.seed)), fsw::Status::kOk);
  Flight f;
  fsw::FrameOutput out;
  long frame = 0, pending_release = -1;
  for (; more; more = stream.next(ev)) {
    if (ev.kind == fsw::InputEvent::Kind::kGnssRaw) {
      EXPECT_EQ(app->on_gnss(ev.gnss), fsw::Status::kOk);
      continue;
    }
    EXPECT_EQ(app->on_imu(ev.imu, out), fsw::Status::kOk);
    if (!out.nav_valid) continue;
    if (out.ekf_released) {
      f.released.push_back(frame);
      pending_release = frame;
    }
    if (out.ekf_ran) f.landed.push_back(frame);
    fsw::nav_digest_add(f.digest, out.nav);
    f.nav.push_back(out.nav);
    ++frame;
    if (!inline_group && pending_release >= 0 && app->executive().ekf_group_busy() && policy(*app, frame, pending_release)) {
      EXPECT_EQ(app->run_ekf_group(), fsw::Status::kOk);
      pending_release = -1;
    }
  }
  f.health = app->executive().health();
  return f;
}

}  // namespace

TEST(RateGroups, CorrectionLandsAtItsFrameWhereverTheOneHertzGroupRan) {
  const Flight inline_run = fly(true, nullptr);
  // Released every 200 frames (1 Hz epochs), each correction lands exactly 10 frames later.
  ASSERT_GE(inline_run.released.size(), 11u);
  ASSERT_GE(inline_run.landed.size(), inline_run.released.size() - 1);
  for (std::size_t i = 0; i < inline_run.landed.size(); ++i)
    EXPECT_EQ(inline_run.landed[i], inline_run.released[i] + 10) << i;
  for (std::size_t i = 1; i < inline_run.released.size(); ++i)
    EXPECT_EQ(inline_run.released[i] - inline_run.released[i - 1], 200) << i;
  EXPECT_GT(inline_run.health.ekf_updates, 10u);
  EXPECT_EQ(inline_run.health.ekf_slips, 0u);
  EXPECT_EQ(inline_run.health.ekf_late, 0u);
  EXPECT_EQ(inline_run.health.fsw_errors, 0u);

  // The 1 Hz group run right after the release, in the middle of its window, or at the last moment
  // (the frame before its correction is due): bit-identical outputs.
  const Flight early = fly(false, [](const auto&, long, long) { return true; });
  const Flight middle = fly(false, [](const auto&, long frame, long rel) { return frame >= rel + 5; });
  const Flight last = fly(false, [](const auto& app, long, long) { return app.ekf_result_due_next_frame(); });
  for (const Flight* f : {&early, &middle, &last}) {
    EXPECT_EQ(f->digest, inline_run.digest);
    EXPECT_EQ(f->landed, inline_run.landed);
    EXPECT_EQ(f->health.ekf_late, 0u);
    EXPECT_EQ(f->health.ekf_updates, inline_run.health.ekf_updates);
  }
}

TEST(RateGroups, LateCorrectionIsCountedAndStillConsistent) {
  const Flight on_time = fly(true, nullptr);
  // The 1 Hz group finishes 30 frames after its release, 20 after its correction was due: every
  // correction is late (counted) and lands when ready, propagated over the longer span.
  const Flight late = fly(false, [](const auto&, long frame, long rel) { return frame >= rel + 30; });
  EXPECT_EQ(late.health.ekf_late, late.released.size() - (late.landed.size() < late.released.size() ? 1 : 0));
  ASSERT_FALSE(late.landed.empty());
  for (std::size_t i = 0; i < late.landed.size(); ++i) EXPECT_EQ(late.landed[i], late.released[i] + 30) << i;
  EXPECT_NE(late.digest, on_time.digest);
  // Same physics: once both runs have landed an epoch's correction (between the late landing and
  // the next release), the propagated correction leaves the solution where the on-time one is, to
  // well below the filter's own uncertainty (metres, cm/s). Before the late landing they differ by
  // the correction itself.
  double max_dp = 0.0, max_dv = 0.0;
  std::vector<std::size_t> frames;
  for (std::size_t i = 1; i + 1 < late.released.size() && i < late.landed.size(); ++i)
    for (long k = late.landed[i]; k < late.released[i + 1]; ++k) frames.push_back(static_cast<std::size_t>(k));
  ASSERT_GT(frames.size(), 1000u);
  for (std::size_t k : frames) {
    ASSERT_LT(k, std::min(on_time.nav.size(), late.nav.size()));
    const fsw::NavState& a = on_time.nav[k];
    const fsw::NavState& b = late.nav[k];
    max_dp = std::max(max_dp, fsw::enu_difference_m(a.llh, b.llh).norm());
    max_dv = std::max(max_dv, (a.vel_enu_mps - b.vel_enu_mps).norm());
  }
  std::printf("late corrections vs on time: max position difference %.3f m, velocity %.4f m/s\n", max_dp, max_dv);
  EXPECT_LT(max_dp, 0.5);
  EXPECT_LT(max_dv, 0.05);
}

TEST(RateGroups, ReleaseWhileBusyIsASlipAndTheIntervalGrows) {
  // The 1 Hz group never finishes within its period: each due release finds the previous one still
  // out and is deferred (counted once per deferral), and the interval keeps growing.
  const Flight slow = fly(false, [](const auto&, long frame, long rel) { return frame >= rel + 250; });
  EXPECT_GT(slow.health.ekf_slips, 0u);
  for (std::size_t i = 1; i < slow.released.size(); ++i) EXPECT_GT(slow.released[i] - slow.released[i - 1], 200) << i;
  EXPECT_EQ(slow.health.fsw_errors, 0u);
}

TEST(RateGroups, LatencyMustFitTheEkfPeriod) {
  fsw::FlightAppConfig cfg;
  auto app = std::make_unique<fsw::FlightApp<fsw::Layout15Full>>();
  for (int bad : {0, cfg.exec.frames_per_ekf}) {
    cfg.exec.ekf_latency_frames = bad;
    EXPECT_EQ(app->init(cfg), fsw::Status::kBadConfig) << bad;
  }
  cfg.exec.ekf_latency_frames = cfg.exec.frames_per_ekf - 1;
  EXPECT_EQ(app->init(cfg), fsw::Status::kOk);
}

// The configuration must match the IMU: imu_samples_per_frame samples make one navigation frame of
// 1 / nav_rate_hz. A mismatch (the coverage study once flew a 200 Hz IMU with the 1 kHz default of
// 5 samples per frame: 25 ms frames and an "1 Hz" EKF every 5 s) is counted in every 1 s window of
// nav_rate_hz frames, not taken silently; the matching configuration counts none.
TEST(RateGroups, AFrameRateThatDoesNotMatchTheImuIsCounted) {
  const auto inline_policy = [](const auto&, long, long) { return true; };
  const Flight ok = fly(true, inline_policy);
  EXPECT_GT(ok.health.nav_frames, 2000u);
  EXPECT_EQ(ok.health.frame_rate_mismatch, 0u);
  const Flight wrong = fly(true, inline_policy, 10, 2);  // the default scenario's IMU is 1 kHz: 2 ms frames
  EXPECT_GT(wrong.health.nav_frames, 5000u);
  EXPECT_EQ(wrong.health.frame_rate_mismatch, wrong.health.nav_frames / 200);  // nav_rate_hz 200
}

// The executive's units on their own: the 200 Hz group completes a navigation frame every
// imu_samples_per_frame samples (counting them), accumulates it into the interval it hands over
// at a release, and aligns the solution to an aid's time tag; the 1 Hz group without an aid
// propagates only and reports the request's release time.
TEST(RateGroupUnits, NavigationGroupFramesHandsOverAndAligns) {
  fsw::ExecutiveConfig cfg;
  cfg.imu_samples_per_frame = 5;
  fsw::NavState start;
  start.t_s = 10.0;
  start.llh = fsw::Vec3(0.6, 2.0, 100.0);
  start.vel_enu_mps = fsw::Vec3(0.0, 50.0, 0.0);
  static fsw::NavGroup<fsw::Layout15> nav;
  ASSERT_EQ(nav.configure(cfg, start), fsw::Status::kOk);
  nav.reset(cfg);
  fsw::ExecutiveHealth h;
  int frames = 0;
  for (int k = 1; k <= 12; ++k) {
    fsw::ImuSample s;
    s.t_s = 10.0 + 0.001 * k;
    s.dt_s = 0.001;
    s.dv_mps = fsw::Vec3(0.0, 0.0, -9.8 * s.dt_s);  // level, body z down
    s.dtheta_rad = fsw::Vec3::Zero();
    const bool frame = nav.add_sample(s, h);
    EXPECT_EQ(frame, k % 5 == 0) << k;
    frames += frame ? 1 : 0;
  }
  EXPECT_EQ(frames, 2);
  EXPECT_EQ(h.imu_samples, 12u);
  EXPECT_EQ(h.nav_frames, 2u);
  EXPECT_EQ(h.imu_rejected + h.fsw_errors, 0u);
  EXPECT_EQ(nav.samples_to_frame_end(), 3);
  EXPECT_NEAR(nav.ins().state().t_s, 10.010, 1e-12);
  // The interval accumulated so far is handed over; the next one starts empty.
  const int closed = nav.hand_over_interval();
  EXPECT_EQ(closed, 0);
  EXPECT_EQ(nav.transition(0).frames(), 2);
  EXPECT_EQ(nav.transition(1).frames(), 0);
  // Aligned 0.1 s back: the position moves back along the velocity.
  const fsw::NavState& now = nav.ins().state();
  const fsw::NavState at = nav.aligned(now.t_s - 0.1);
  EXPECT_NEAR(at.t_s, now.t_s - 0.1, 1e-12);
  EXPECT_NEAR(fsw::enu_difference_m(now.llh, at.llh).y(), 0.1 * now.vel_enu_mps.y(), 1e-3);

  static fsw::EkfGroup<fsw::Layout15> ekf;
  ASSERT_EQ(ekf.init(cfg.ekf), fsw::Status::kOk);
  fsw::EkfRequest<fsw::Layout15> rq;
  rq.aid = fsw::EkfRequest<fsw::Layout15>::Aid::kNone;
  rq.t_s = now.t_s;
  static fsw::EkfResult<fsw::Layout15> r;
  const double p0 = ekf.ekf().P()(0, 0);
  ekf.run(rq, nav.transition(closed), r);
  EXPECT_FALSE(r.updated);
  EXPECT_FALSE(r.correction_valid);
  EXPECT_EQ(r.fsw_errors, 0u);
  EXPECT_EQ(r.output.t_s, now.t_s);
  EXPECT_GT(ekf.ekf().P()(0, 0), p0);  // propagated over the 10 ms interval
}
