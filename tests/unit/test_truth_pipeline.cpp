// sim::TruthPipeline: the truth generator's integration on a thread of its own gives the
// generator's samples bit for bit, in order, and stops cleanly wherever its reader leaves it.
#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <string>

#include "sim/scenario.hpp"
#include "sim/trajectory.hpp"
#include "sim/truth_pipeline.hpp"

namespace {

bool same_bits(const fsw::Vec3& a, const fsw::Vec3& b) { return std::memcmp(a.data(), b.data(), sizeof(double) * 3) == 0; }

/// Every field of a sample, bit for bit.
void expect_same(const sim::TruthSample& a, const sim::TruthSample& b, long long k) {
  ASSERT_EQ(a.t_s, b.t_s) << "sample " << k;
  ASSERT_EQ(a.dt_s, b.dt_s) << "sample " << k;
  ASSERT_TRUE(same_bits(a.llh, b.llh)) << "sample " << k;
  ASSERT_TRUE(same_bits(a.vel_enu_mps, b.vel_enu_mps)) << "sample " << k;
  ASSERT_EQ(0, std::memcmp(a.C_b_n.data(), b.C_b_n.data(), sizeof(double) * 9)) << "sample " << k;
  ASSERT_TRUE(same_bits(a.omega_ib_b_radps, b.omega_ib_b_radps)) << "sample " << k;
  ASSERT_TRUE(same_bits(a.omega_nb_b_radps, b.omega_nb_b_radps)) << "sample " << k;
  ASSERT_TRUE(same_bits(a.f_b_mps2, b.f_b_mps2)) << "sample " << k;
  ASSERT_TRUE(same_bits(a.dtheta_rad, b.dtheta_rad)) << "sample " << k;
  ASSERT_TRUE(same_bits(a.dv_mps, b.dv_mps)) << "sample " << k;
  ASSERT_EQ(a.phase.segment, b.phase.segment) << "sample " << k;
  ASSERT_EQ(a.phase.turn, b.phase.turn) << "sample " << k;
  ASSERT_EQ(a.phase.turning, b.phase.turning) << "sample " << k;
}

struct PipelineFlight {
  sim::Scenario sc;
  std::unique_ptr<sim::FlightMotion> motion;
  PipelineFlight() {
    sc.duration_s = 120.0;  // the default flight's first turn starts within it
    std::string err;
    motion = sim::FlightMotion::create(sc, err);
    EXPECT_TRUE(motion) << err;
  }
};

TEST(TruthPipeline, GivesTheGeneratorsSamplesBitForBitAndGoesOnPastItsCount) {
  const PipelineFlight f;
  ASSERT_TRUE(f.motion);
  // Not a whole number of the pipeline's batches or rings, so the last hand-off is a short one.
  const long long n = 100'037;
  sim::TruthGenerator gen(*f.motion, 1000.0);
  sim::TruthPipeline pipe(*f.motion, 1000.0, n, sim::TruthThread::kOwn);
  expect_same(gen.current(), pipe.current(), 0);
  long long turning = 0;
  for (long long k = 1; k <= n + 5; ++k) {  // five past n: on without the thread
    const sim::TruthSample& a = gen.next();
    const sim::TruthSample& b = pipe.next();
    expect_same(a, b, k);
    if (::testing::Test::HasFatalFailure()) return;
    turning += a.phase.turning ? 1 : 0;
  }
  EXPECT_EQ(pipe.current().t_s, gen.current().t_s);
  EXPECT_GT(turning, 10'000);  // through a roll-in and a turn, not only a straight
}

TEST(TruthPipeline, StopsWhereverItsReaderLeavesIt) {
  const PipelineFlight f;
  ASSERT_TRUE(f.motion);
  const long long n = 120'000;
  { sim::TruthPipeline never_read(*f.motion, 1000.0, n, sim::TruthThread::kOwn); }  // no thread started
  for (long long read : {1LL, 255LL, 256LL, 4'097LL, 50'000LL}) {
    sim::TruthPipeline pipe(*f.motion, 1000.0, n, sim::TruthThread::kOwn);
    for (long long k = 0; k < read; ++k) pipe.next();
    EXPECT_NEAR(pipe.current().t_s, static_cast<double>(read) / 1000.0, 1e-9);
  }  // each destructor stops an integration that is waiting for a slot or still running, and joins it
  sim::TruthPipeline empty(*f.motion, 1000.0, 0, sim::TruthThread::kOwn);
  EXPECT_EQ(empty.next().t_s, 0.001);  // no samples asked for: the generator's, on the reader's thread
}

TEST(TruthPipeline, UnsplitIsTheGenerator) {
  const PipelineFlight f;
  ASSERT_TRUE(f.motion);
  sim::TruthGenerator gen(*f.motion, 1000.0);
  sim::TruthPipeline one(*f.motion, 1000.0, 3'000, sim::TruthThread::kReader);
  for (long long k = 1; k <= 3'010; ++k) {
    expect_same(gen.next(), one.next(), k);
    if (::testing::Test::HasFatalFailure()) return;
  }
}

}  // namespace
