// The timing audit (tools/timing_audit.hpp): order statistics, and a short flight through the
// executive with a per-frame stage registered at the bus-decode extension point.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <stdexcept>

#include "tools/timing_audit.hpp"

namespace {

TEST(TimingAudit, NearestRankStatistics) {
  std::vector<double> v(1000);
  for (int i = 0; i < 1000; ++i) v[static_cast<std::size_t>(i)] = (1000 - i) * 1e-6;  // 1000 ... 1 us, unsorted
  const tools::TimingStats s = tools::timing_stats(v);
  EXPECT_EQ(s.n, 1000);
  EXPECT_DOUBLE_EQ(s.min_us, 1.0);
  EXPECT_DOUBLE_EQ(s.median_us, 500.0);
  EXPECT_DOUBLE_EQ(s.p99_us, 990.0);
  EXPECT_DOUBLE_EQ(s.p999_us, 999.0);
  EXPECT_DOUBLE_EQ(s.max_us, 1000.0);
  EXPECT_NEAR(s.mean_us, 500.5, 1e-9);
  EXPECT_NEAR(s.total_s, 500500e-6, 1e-12);
  const tools::TimingStats one = tools::timing_stats({3e-6});
  EXPECT_DOUBLE_EQ(one.median_us, 3.0);
  EXPECT_DOUBLE_EQ(one.p999_us, 3.0);
  EXPECT_EQ(tools::timing_stats({}).n, 0);
}

TEST(TimingAudit, FliesEveryLayoutAndTimesRegisteredStages) {
  sim::Scenario sc;
  sc.duration_s = 5.0;
  tools::TimingAuditConfig cfg;
  cfg.layouts = {"Layout15", "Layout24Full"};
  cfg.init_mode = fsw::InitMode::kGiven;  // the frame count is exact from the given start
  long prepared = 0, ran = 0;
  double checksum = 0.0, seen = 0.0;
  fsw::FrameInput last{};
  // A stand-in for the HAL's bus decode: prepare() sees the frame's input, run() works on it.
  cfg.frame_stages.push_back({"bus_decode_test",
                              [&](const fsw::FrameInput& in) {
                                ++prepared;
                                last = in;
                              },
                              [&] {
                                ++ran;
                                for (int k = 0; k < last.n_imu; ++k) checksum += last.imu[k].dv_mps.sum();
                                seen += last.n_imu;
                              }});
  const tools::TimingAuditResult r = tools::run_timing_audit(sc, cfg);
  EXPECT_EQ(r.frames, 1000);
  EXPECT_EQ(prepared, 2000);  // every frame of both layout passes
  EXPECT_EQ(ran, 2000);
  EXPECT_EQ(seen, 2000.0 * 5);  // 5 IMU samples per frame
  EXPECT_TRUE(std::isfinite(checksum));
  ASSERT_EQ(r.tasks.size(), 5u);
  EXPECT_EQ(r.tasks[0].name, "mech_200hz/Layout15");
  EXPECT_EQ(r.tasks[1].name, "ekf_1hz/Layout15");
  EXPECT_EQ(r.tasks[2].name, "mech_200hz/Layout24Full");
  EXPECT_EQ(r.tasks[3].name, "ekf_1hz/Layout24Full");
  const tools::TaskTiming& stage = r.tasks[4];
  EXPECT_EQ(stage.name, "bus_decode_test");
  EXPECT_EQ(stage.stats.n + stage.preempted, 2000);
  for (int i = 0; i < 4; i += 2) {
    const tools::TaskTiming& m = r.tasks[static_cast<std::size_t>(i)];
    const tools::TaskTiming& e = r.tasks[static_cast<std::size_t>(i + 1)];
    // Two groups timed apart: every frame is a 200 Hz frame; the 1 Hz group ran 4 times, within its
    // deadline: an epoch arrives after the IMU sample of its time (sim/sensor_stream.hpp), so the
    // frame after it releases its step (t = 1.005 ... 4.005 s); the epoch of t = 5 s comes after
    // the flight's last sample, and no frame follows to release it.
    EXPECT_EQ(m.stats.n + m.preempted, 1000) << m.name;
    EXPECT_EQ(e.stats.n + e.preempted, 4) << e.name;
    EXPECT_EQ(e.slips, 0) << e.name;
    EXPECT_EQ(m.slips, 0) << m.name;
    EXPECT_GT(e.response_max_us, 0.0) << e.name;
    EXPECT_GT(m.stats.median_us, 0.0);
    EXPECT_GT(e.stats.median_us, m.stats.median_us) << e.name;
    EXPECT_EQ(e.interval_frames_min, 200);
    EXPECT_EQ(e.interval_frames_max, 200);
  }
  ASSERT_EQ(r.layouts.size(), 2u);
  for (const tools::LayoutTiming& l : r.layouts) {
    EXPECT_EQ(l.ekf_updates, 4) << l.layout;  // the 5th correction would land 10 frames after the end
    EXPECT_EQ(l.init_frame, -1) << l.layout;
    EXPECT_EQ(l.fsw_errors, 0) << l.layout;
    EXPECT_GT(l.sats_min, 3) << l.layout;
    // The worst unpreempted minor frame, and what it did: one of the flight's frames, named work.
    EXPECT_GE(l.worst_frame_index, 0) << l.layout;
    EXPECT_LT(l.worst_frame_index, 1000) << l.layout;
    EXPECT_GT(l.worst_frame_us, 0.0) << l.layout;
    EXPECT_GT(l.worst_frame_t_s, 0.0) << l.layout;
    EXPECT_NE(l.worst_frame_work.find("200 Hz group"), std::string::npos) << l.worst_frame_work;
  }
  // The layout's share includes the stage: more than its two executive tasks alone.
  EXPECT_GE(r.layouts[0].fsw_cpu_share, r.tasks[0].cpu_share + r.tasks[1].cpu_share);
}

TEST(TimingAudit, TimesTheInFlightInitialisationAsHilFliesIt) {
  sim::Scenario sc;
  sc.duration_s = 4.0;
  tools::TimingAuditConfig cfg;
  cfg.layouts = {"Layout24Full"};
  const tools::TimingAuditResult r = tools::run_timing_audit(sc, cfg);  // init_mode kTrack: the default
  ASSERT_EQ(r.layouts.size(), 1u);
  const tools::LayoutTiming& l = r.layouts[0];
  // The first epoch (t = 1 s, after 0.2 s of levelling) initialises: it arrives after the IMU sample
  // of its time, so in frame 200 (frames before it are the levelling calls, a frame's samples each),
  // and its work is named.
  EXPECT_EQ(l.init_frame, 200);
  EXPECT_GT(l.init_frame_us, 0.0);
  // The frame in progress when the initialisation restarts the batching is lost: 799 or 800.
  EXPECT_GE(r.frames, 799);
  EXPECT_LE(r.frames, 800);
  ASSERT_EQ(r.tasks.size(), 2u);
  EXPECT_EQ(r.tasks[0].stats.n + r.tasks[0].preempted, r.frames);
  // Released by the frames after the epochs of t = 2 and 3 s; the epoch of t = 4 s comes after the
  // flight's last sample.
  EXPECT_EQ(r.tasks[1].stats.n + r.tasks[1].preempted, 2);
  EXPECT_GE(l.worst_frame_index, 0);
  if (l.worst_frame_index == l.init_frame) EXPECT_NE(l.worst_frame_work.find("initialising"), std::string::npos);
}

TEST(TimingAudit, RejectsWhatItCannotFly) {
  sim::Scenario sc;
  sc.duration_s = 1.0;
  tools::TimingAuditConfig cfg;
  cfg.layouts = {"Layout99"};
  EXPECT_THROW(tools::run_timing_audit(sc, cfg), std::runtime_error);
  cfg.layouts = {};
  EXPECT_THROW(tools::run_timing_audit(sc, cfg), std::runtime_error);
  cfg.layouts = {"Layout15"};
  cfg.frame_stages.push_back({"no_run", nullptr, nullptr});
  EXPECT_THROW(tools::run_timing_audit(sc, cfg), std::runtime_error);
}

}  // namespace
