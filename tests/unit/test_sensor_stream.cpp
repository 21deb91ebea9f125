// The one simulated sensor stream (sim/sensor_stream.hpp): its event order, and the same events
// from both truth sources (generated alongside, or a shared track).
#include <gtest/gtest.h>

#include <cstring>
#include <stdexcept>
#include <thread>
#include <vector>

#include "sim/almanac.hpp"
#include "sim/sensor_stream.hpp"

namespace {

sim::Scenario short_flight() {
  sim::Scenario sc;
  sc.duration_s = 3.0;
  return sc;
}

std::vector<fsw::InputEvent> all_events(sim::SensorStream& s, std::vector<sim::TruthSample>* epoch_truth = nullptr) {
  std::vector<fsw::InputEvent> out;
  fsw::InputEvent ev;
  while (s.next(ev)) {
    out.push_back(ev);
    if (epoch_truth != nullptr && ev.kind == fsw::InputEvent::Kind::kGnssRaw) epoch_truth->push_back(s.epoch_truth());
  }
  return out;
}

}  // namespace

TEST(SensorStream, AlmanacFirstThenEachEpochRightAfterTheImuSampleOfItsTime) {
  const sim::Scenario sc = short_flight();
  sim::SensorStream s(sc, 7);
  const std::vector<fsw::InputEvent> ev = all_events(s);
  const std::size_t n_alm = s.almanac().size();
  ASSERT_GT(n_alm, 20u);
  for (std::size_t i = 0; i < n_alm; ++i) EXPECT_EQ(ev[i].kind, fsw::InputEvent::Kind::kAlmanac) << i;
  const int spe = s.samples_per_epoch();
  EXPECT_EQ(spe, static_cast<int>(sc.imu.rate_hz / sc.gps.rate_hz));
  long long imu = 0, epochs = 0;
  for (std::size_t i = n_alm; i < ev.size(); ++i) {
    if (ev[i].kind == fsw::InputEvent::Kind::kImu) {
      ++imu;
      continue;
    }
    ASSERT_EQ(ev[i].kind, fsw::InputEvent::Kind::kGnssRaw) << i;
    ++epochs;
    // Right after the IMU sample of its own time, the spe-th sample since the last epoch.
    ASSERT_EQ(ev[i - 1].kind, fsw::InputEvent::Kind::kImu) << i;
    EXPECT_EQ(imu, epochs * spe) << i;
    EXPECT_NEAR(ev[i - 1].imu.t_s, static_cast<double>(epochs) / sc.gps.rate_hz, 1e-9) << i;
    EXPECT_GT(ev[i].gnss.n_meas, 4) << i;
  }
  EXPECT_EQ(imu, s.total_samples());
  EXPECT_EQ(imu, static_cast<long long>(sc.duration_s * sc.imu.rate_hz));
  EXPECT_EQ(epochs, static_cast<long long>(sc.duration_s * sc.gps.rate_hz));
}

TEST(SensorStream, SharedTruthTrackGivesTheSameEventsAsTheLiveGenerator) {
  const sim::Scenario sc = short_flight();
  sim::SensorStream live(sc, 11);
  std::vector<sim::TruthSample> live_truth, track_truth;
  const std::vector<fsw::InputEvent> a = all_events(live, &live_truth);

  const sim::TruthTrack track = sim::TruthTrack::generate(sc);
  const sim::AlmanacParseResult alm = sim::parse_yuma_file(sim::almanac_path(sc.gps));
  ASSERT_TRUE(alm.ok()) << alm.error;
  sim::SensorStream shared(sc, track, *alm.almanac, 11);
  const std::vector<fsw::InputEvent> b = all_events(shared, &track_truth);

  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].kind, b[i].kind) << i;
    EXPECT_EQ(a[i].t_s, b[i].t_s) << i;
    switch (a[i].kind) {
      case fsw::InputEvent::Kind::kImu:
        EXPECT_EQ(std::memcmp(&a[i].imu, &b[i].imu, sizeof a[i].imu), 0) << i;
        break;
      case fsw::InputEvent::Kind::kGnssRaw:
        ASSERT_EQ(a[i].gnss.n_meas, b[i].gnss.n_meas) << i;
        for (int k = 0; k < a[i].gnss.n_meas; ++k) {
          EXPECT_EQ(a[i].gnss.meas[static_cast<std::size_t>(k)].prn, b[i].gnss.meas[static_cast<std::size_t>(k)].prn);
          EXPECT_EQ(a[i].gnss.meas[static_cast<std::size_t>(k)].pseudorange_m, b[i].gnss.meas[static_cast<std::size_t>(k)].pseudorange_m);
        }
        break;
      default:
        break;
    }
  }
  ASSERT_EQ(live_truth.size(), track_truth.size());
  for (std::size_t k = 0; k < live_truth.size(); ++k) {
    EXPECT_EQ(live_truth[k].t_s, track_truth[k].t_s);
    EXPECT_EQ(live_truth[k].llh, track_truth[k].llh);
    EXPECT_EQ(live_truth[k].C_b_n, track_truth[k].C_b_n);
  }
  // The track must fit the scenario it is read with.
  sim::Scenario other = sc;
  other.gps.rate_hz = 2.0;
  EXPECT_THROW(sim::SensorStream(other, track, *alm.almanac, 11), std::runtime_error);
}

namespace {

bool same_imu_events(const std::vector<fsw::InputEvent>& a, const std::vector<fsw::InputEvent>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].kind != b[i].kind || std::memcmp(&a[i].t_s, &b[i].t_s, sizeof a[i].t_s) != 0) return false;
    if (a[i].kind == fsw::InputEvent::Kind::kImu && std::memcmp(&a[i].imu, &b[i].imu, sizeof a[i].imu) != 0) return false;
  }
  return true;
}

}  // namespace

// A track read while it is integrated on another thread (TruthTrack::prepare / fill, what the
// Monte Carlo does): two streams that start before the first sample is published read the same
// events, bit for bit, as from a track generated whole; each waits where it is ahead.
TEST(SensorStream, TrackReadWhileItIsGeneratedGivesTheSameEvents) {
  sim::Scenario sc = short_flight();
  sc.duration_s = 12.0;  // 12 publications of TruthTrack::kPublishSamples
  const sim::AlmanacParseResult alm = sim::parse_yuma_file(sim::almanac_path(sc.gps));
  ASSERT_TRUE(alm.ok()) << alm.error;
  const sim::TruthTrack whole = sim::TruthTrack::generate(sc);
  EXPECT_EQ(whole.progress, nullptr);
  sim::SensorStream ref(sc, whole, *alm.almanac, 5);
  const std::vector<fsw::InputEvent> want = all_events(ref);

  sim::TruthTrack growing = sim::TruthTrack::prepare(sc);
  ASSERT_NE(growing.progress, nullptr);
  ASSERT_EQ(growing.imu.size(), whole.imu.size());
  ASSERT_EQ(growing.epochs.size(), whole.epochs.size());
  std::vector<fsw::InputEvent> got1, got2;
  std::thread r1([&] {
    sim::SensorStream s(sc, growing, *alm.almanac, 5);
    got1 = all_events(s);
  });
  std::thread r2([&] {
    sim::SensorStream s(sc, growing, *alm.almanac, 5);
    got2 = all_events(s);
  });
  std::thread gen([&] { growing.fill(); });
  gen.join();
  r1.join();
  r2.join();
  EXPECT_TRUE(same_imu_events(want, got1));
  EXPECT_TRUE(same_imu_events(want, got2));
  for (std::size_t k = 0; k < whole.epochs.size(); ++k) EXPECT_EQ(whole.epochs[k].llh, growing.epochs[k].llh) << k;
  EXPECT_GT(growing.generate_wall_s, 0.0);
}

// A fill stopped early (an aborted Monte Carlo) fails a reader that needs a sample it never
// wrote, with an error, instead of leaving it waiting.
TEST(SensorStream, AStoppedTrackFailsItsReaderInsteadOfHanging) {
  sim::Scenario sc = short_flight();
  sc.duration_s = 5.0;
  const sim::AlmanacParseResult alm = sim::parse_yuma_file(sim::almanac_path(sc.gps));
  ASSERT_TRUE(alm.ok()) << alm.error;
  sim::TruthTrack growing = sim::TruthTrack::prepare(sc);
  growing.stop_fill();  // stops at its first publication: samples 1..kPublishSamples written
  growing.fill();
  EXPECT_THROW(growing.wait_for(0), std::runtime_error);  // stopped: no sample is promised
  sim::SensorStream s(sc, growing, *alm.almanac, 5);
  std::thread reader([&] { EXPECT_THROW(all_events(s), std::runtime_error); });
  reader.join();  // returns: the reader failed, it did not wait for ever
}

namespace {

/// Every event of a stream by GPS steps (what `sdins sil` reads), with the full truth it offers
/// after each step (SensorStream::full_truth).
struct Steps {
  std::vector<sim::SensorStep> steps;
  std::vector<sim::TruthSample> truth;
};
Steps all_steps(sim::SensorStream& s) {
  Steps out;
  sim::SensorStep step;
  while (s.next(step)) {
    out.steps.push_back(step);
    const sim::TruthSample* t = s.full_truth();
    EXPECT_NE(t, nullptr) << "no full truth after step " << out.steps.size();
    if (t != nullptr) out.truth.push_back(*t);
  }
  return out;
}

bool same_truth(const sim::TruthSample& a, const sim::TruthSample& b) {
  return a.t_s == b.t_s && a.llh == b.llh && a.vel_enu_mps == b.vel_enu_mps && a.C_b_n == b.C_b_n;
}

}  // namespace

// A track read while its fill thread integrates it gives the steps and the full truth of the live
// generator, bit for bit, through a short last step (no epoch) and the truth after it (the last
// sample's).
TEST(SensorStream, TrackBeingFilledGivesTheLiveGeneratorsStepsAndTruth) {
  sim::Scenario sc = short_flight();
  sc.duration_s = 12.5;
  sim::SensorStream live(sc, 3);
  const Steps want = all_steps(live);
  ASSERT_FALSE(want.steps.back().has_epoch);
  const sim::AlmanacParseResult alm = sim::parse_yuma_file(sim::almanac_path(sc.gps));
  ASSERT_TRUE(alm.ok()) << alm.error;
  sim::TruthTrack track = sim::TruthTrack::prepare(sc);
  sim::SensorStream s(sc, track, *alm.almanac, 3);
  sim::TruthFillThread fill(track);
  const Steps got = all_steps(s);
  fill.complete();
  ASSERT_EQ(got.steps.size(), want.steps.size());
  ASSERT_EQ(got.truth.size(), want.truth.size());
  for (std::size_t k = 0; k < want.steps.size(); ++k) {
    const sim::SensorStep &a = want.steps[k], &b = got.steps[k];
    ASSERT_EQ(a.imu.size(), b.imu.size()) << k;
    EXPECT_EQ(std::memcmp(a.imu.data(), b.imu.data(), a.imu.size() * sizeof a.imu[0]), 0) << "step " << k;
    EXPECT_EQ(a.has_epoch, b.has_epoch) << k;
    if (a.has_epoch) EXPECT_EQ(std::memcmp(&a.epoch, &b.epoch, sizeof a.epoch), 0) << "step " << k;
    EXPECT_TRUE(same_truth(want.truth[k], got.truth[k])) << "step " << k;
  }
}

// A reader that stops (an error in the run) leaves the integration running; the fill thread's
// destructor stops it at its next publication and returns. Where it stops depends on the
// threads' timing; a stop asked before the integration starts is exact: fill() returns at its
// first publication, and a wait past it fails instead of hanging.
TEST(SensorStream, TrackFillStopsWhenItsReaderGoesAway) {
  sim::Scenario sc = short_flight();
  sc.duration_s = 600.0;
  const sim::AlmanacParseResult alm = sim::parse_yuma_file(sim::almanac_path(sc.gps));
  ASSERT_TRUE(alm.ok()) << alm.error;
  sim::TruthTrack track = sim::TruthTrack::prepare(sc);
  {
    sim::SensorStream s(sc, track, *alm.almanac, 3);
    sim::TruthFillThread fill(track);
    sim::SensorStep step;
    for (int k = 0; k < 2; ++k) ASSERT_TRUE(s.next(step));
  }  // the reader stops after 2 s of 600: the destructor must return
  sim::TruthTrack stopped = sim::TruthTrack::prepare(sc);
  stopped.stop_fill();
  stopped.fill();
  EXPECT_THROW(stopped.wait_for(stopped.samples() - 1), std::runtime_error);
}
