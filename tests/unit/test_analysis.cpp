// Single-axis rotation and bank-to-turn analyses (paper section II) against closed forms.
#include <gtest/gtest.h>

#include <vector>

#include "tools/analysis.hpp"

using fsw::kDegToRad;

// Each (rotation axis, misalignment) pair that the rotation excites, at 5 and 10 arcsec: the
// simulated error must match the closed form within 2% of its peak.
TEST(SingleAxisRotation, SimulatedErrorMatchesClosedForm) {
  for (const tools::RotationPair p : tools::kExcitedRotationPairs) {
    for (double gamma : {5.0, 10.0}) {
      const auto c = tools::run_rotation_case(p.axis, p.component, gamma, 10.0, 72.0, 35.0 * kDegToRad);
      ASSERT_GT(c.peak_formula_rad, 1.5 * gamma * fsw::kArcsecToRad) << c.name;
      EXPECT_LT(c.max_deviation_rad, 0.02 * c.peak_formula_rad)
          << c.name << " deviation " << c.max_deviation_rad * fsw::kRadToArcsec << " arcsec of peak "
          << c.peak_formula_rad * fsw::kRadToArcsec;
    }
  }
}

TEST(SingleAxisRotation, UnexcitedMisalignmentLeavesNoError) {
  // Rotating about z does not excite gamma_zx (z gyro tilted toward x senses no rate).
  const auto c = tools::run_rotation_case(2, 4, 10.0, 10.0, 36.0, 35.0 * kDegToRad);
  EXPECT_LT(c.peak_formula_rad, 1e-12);
  EXPECT_LT(c.max_deviation_rad, 0.05 * 10.0 * fsw::kArcsecToRad);
}

TEST(BankToTurn, OnlyYzAndZyAccumulateHeadingError) {
  sim::Scenario sc;
  sc.duration_s = 600.0;  // about 7 turns: enough to tell accumulation from oscillation
#if defined(__SANITIZE_ADDRESS__)
  // Under the sanitizers (several times slower) one component that accumulates and one that does
  // not: the same code; the release stage checks all six.
  for (std::size_t k : {std::size_t{0}, std::size_t{3}}) {
#else
  for (std::size_t k = 0; k < 6; ++k) {
#endif
    const auto c = tools::run_bank_turn_case(sc, k, 20.0);
    ASSERT_GE(c.turn_end_t_s.size(), 5u) << c.component;
    const bool expect = c.component == "yz" || c.component == "zy";
    EXPECT_EQ(c.accumulates, expect) << c.component << ": " << c.u_error_per_turn_arcsec << " arcsec/turn";
    if (expect) {
      // Equation (7): phi_U grows by (gamma_yz + gamma_zy) (g / V) int sin^2(phi) dt per turn.
      EXPECT_GT(c.u_error_per_turn_arcsec, 20.0);
      EXPECT_NEAR(c.u_error_per_turn_arcsec, c.predicted_per_turn_arcsec, 0.05 * c.predicted_per_turn_arcsec);
    } else {
      EXPECT_LT(std::abs(c.u_error_per_turn_arcsec), 2.0) << c.component;
    }
  }
}

// Several bank-to-turn cases through one truth generator (run_bank_turn_cases: the analysis flies
// its six in one group per core) are each the case flown alone, bit for bit: the series, the turn
// ends and every figure; the order of the results is the order asked for.
TEST(BankToTurn, CasesFlownThroughOneTruthAreTheCasesFlownAlone) {
  sim::Scenario sc;
  sc.duration_s = 300.0;
  const std::vector<std::size_t> components = {3, 5, 0};
  const std::vector<tools::BankTurnCase> grouped = tools::run_bank_turn_cases(sc, components, 20.0, 1);
  const std::vector<tools::BankTurnCase> two_groups = tools::run_bank_turn_cases(sc, components, 20.0, 2);
  ASSERT_EQ(grouped.size(), components.size());
  ASSERT_EQ(two_groups.size(), components.size());
  for (std::size_t k = 0; k < components.size(); ++k) {
    const tools::BankTurnCase alone = tools::run_bank_turn_case(sc, components[k], 20.0);
    for (const tools::BankTurnCase* g : {&grouped[k], &two_groups[k]}) {
      EXPECT_EQ(g->component, alone.component);
      EXPECT_EQ(g->t_s, alone.t_s) << alone.component;
      EXPECT_EQ(g->phi_rad, alone.phi_rad) << alone.component;
      EXPECT_EQ(g->roll_rad, alone.roll_rad) << alone.component;
      EXPECT_EQ(g->turn_end_t_s, alone.turn_end_t_s) << alone.component;
      EXPECT_EQ(g->turn_end_phi_rad, alone.turn_end_phi_rad) << alone.component;
      EXPECT_EQ(g->u_error_per_turn_arcsec, alone.u_error_per_turn_arcsec) << alone.component;
      EXPECT_EQ(g->predicted_per_turn_arcsec, alone.predicted_per_turn_arcsec) << alone.component;
      EXPECT_EQ(g->tilt_per_turn_arcsec, alone.tilt_per_turn_arcsec) << alone.component;
      EXPECT_EQ(g->u_oscillation_arcsec, alone.u_oscillation_arcsec) << alone.component;
      EXPECT_EQ(g->accumulates, alone.accumulates) << alone.component;
    }
    EXPECT_GE(alone.turn_end_t_s.size(), 2u) << alone.component;  // the comparison saw turns
  }
}
