// The recording's evidence (tools/diagnosis_evidence.hpp): the reference-lag correlation's
// cumulative-rotation lookup.
#include <gtest/gtest.h>

#include <cstddef>
#include <cstring>
#include <random>
#include <vector>

#include "tools/diagnosis_evidence.hpp"

namespace {

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(DiagnosisEvidence, HintedLookupOfTheCumulativeRateIsTheFullSearchBitForBit) {
  // Tags at a jittered 1 kHz over 20 s (20001 tags, more than the hint's window many times over).
  tools::CumulativeRate cum;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> jitter(-2e-4, 2e-4), rate(0.0, 1e-3);
  double t = 0.0, c = 0.0;
  for (int i = 0; i <= 20000; ++i) {
    cum.t.push_back(t + (i > 0 ? jitter(rng) : 0.0));
    cum.c.push_back(c);
    t += 1e-3;
    c += rate(rng);
  }
  // Ascending queries 0.1 s apart (the correlation's), with steps of many windows, backwards
  // jumps, both clamped ends and the tags themselves; a stale hint from another lookup too.
  std::vector<double> xs;
  for (double x = -0.5; x < 21.0; x += 0.1) xs.push_back(x);
  for (double x : {3.0, 2.0, 19.5, 0.0005, 20.0, 25.0, -1.0}) xs.push_back(x);
  for (std::size_t i = 0; i < cum.t.size(); i += 997) xs.push_back(cum.t[i]);
  std::size_t hint = 0, checked = 0;
  for (double x : xs) {
    const double want = cum.at(x), got = cum.at(x, hint);
    ASSERT_TRUE(same_bits(want, got)) << x;
    ++checked;
  }
  std::size_t stale = cum.t.size() - 2;
  EXPECT_TRUE(same_bits(cum.at(1.2345), cum.at(1.2345, stale)));
  EXPECT_EQ(checked, xs.size());
  // The lookup interpolates: halfway between two tags, halfway between their sums.
  const double mid = 0.5 * (cum.t[100] + cum.t[101]);
  EXPECT_NEAR(cum.at(mid), 0.5 * (cum.c[100] + cum.c[101]), 1e-15);
  EXPECT_EQ(cum.at(-5.0), cum.c.front());
  EXPECT_EQ(cum.at(50.0), cum.c.back());
}

}  // namespace
