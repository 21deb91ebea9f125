// The acceptance and claim logic of `sdins paper` (tools/paper_verdict.hpp) on synthetic
// statistics: physically consistent numbers pass, and each check fails when its own quantity is
// moved past its limit while everything else stays. Plus the tilt-kick integral on a real truth
// track against its closed-form bound, and the turn patterns.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>

#include "sim/scenario.hpp"
#include "tools/montecarlo.hpp"
#include "tools/paper_verdict.hpp"

namespace {

using tools::paper::Check;
using tools::paper::LevelSummary;
using tools::paper::ModelSummary;

ModelSummary model(const std::string& name, double e, double n, double u, double u_first, int runs = 100) {
  ModelSummary m;
  m.model = name;
  m.runs = runs;
  m.final_sigma_deg = {e, n, u};
  m.initial_u_sigma_deg = 0.046;
  m.u_after_first_turn_deg = u_first;
  for (int k = 1; k <= 1800; ++k) {
    m.t_s.push_back(k);
    m.u_sigma_deg.push_back(u);  // flat at the final value: the last-300-s ratio is the final one
  }
  m.mean_nees = 9.0;
  m.nees_bounds = {8.19, 9.85};
  m.pr_used = 1000;
  return m;
}

tools::MisalignmentCombination heading_combo(double rms_over_sigma) {
  tools::MisalignmentCombination c;
  c.terms = {{"gyro_mis.yz", 0.71}, {"gyro_mis.zy", 0.70}};
  c.label = "+0.71 gyro_mis.yz +0.70 gyro_mis.zy";
  c.initial_sigma = 15.0;
  c.final_sigma = 3.0;
  c.rms_residual = 3.0 * rms_over_sigma;
  c.observable = true;
  return c;
}

/// Numbers shaped like the 100-run measurement (docs/paper-verdict.md).
std::vector<LevelSummary> good() {
  LevelSummary lo, hi;
  lo.misalignment_arcsec = 5.0;
  lo.predicted_east_excess_deg = 0.0034;
  lo.models = {model("15", 0.0066, 0.0117, 0.0089, 0.0135), model("24", 0.0035, 0.0115, 0.0065, 0.0134)};
  lo.models[1].combinations = {heading_combo(0.97)};
  hi.misalignment_arcsec = 15.0;
  hi.predicted_east_excess_deg = 0.0102;
  hi.models = {model("15", 0.0110, 0.0123, 0.0134, 0.0136), model("24", 0.0045, 0.0117, 0.0076, 0.0140)};
  hi.models[1].combinations = {heading_combo(0.99)};
  return {lo, hi};
}

ModelSummary& m(std::vector<LevelSummary>& l, double level, const std::string& name) {
  for (auto& x : l)
    if (x.misalignment_arcsec == level)
      for (auto& y : x.models)
        if (y.model == name) return y;
  throw std::runtime_error("no such model");
}

void set_u(ModelSummary& x, double u) {
  x.final_sigma_deg[2] = u;
  for (auto& v : x.u_sigma_deg) v = u;
}

const Check* find(const std::vector<Check>& checks, const std::string& prefix) {
  for (const auto& c : checks)
    if (c.name.rfind(prefix, 0) == 0) return &c;
  return nullptr;
}

TEST(PaperVerdict, PhysicallyConsistentStatisticsPassEveryCheck) {
  const auto checks = tools::paper::acceptance(good());
  for (const auto& c : checks) EXPECT_TRUE(c.pass) << c.name << " value " << c.value << " limit " << c.limit;
  EXPECT_TRUE(tools::paper::all_pass(checks));
  // Per level: 2 pseudoranges used, 2 NEES, N, E order, U first turn, 24 falling, heading
  // combination (9); at 15 arcsec also the E excess, 15 flat and the two U ratios (4); one
  // cross-level comparison.
  EXPECT_EQ(checks.size(), 9u + 13u + 1u);
  EXPECT_FALSE(tools::paper::all_pass({}));
}

struct Breaker {
  const char* check;  ///< name prefix of the check that must fail
  std::function<void(std::vector<LevelSummary>&)> apply;
};

TEST(PaperVerdict, EachCheckFailsOnItsOwnQuantity) {
  const std::vector<Breaker> breakers = {
      {"mean NEES of the 15-state filter, 5 arcsec", [](auto& l) { m(l, 5, "15").mean_nees = 12.0; }},
      {"mean NEES of the 24-state filter, 15 arcsec", [](auto& l) { m(l, 15, "24").mean_nees = 7.0; }},
      // No pseudorange used (docs/faults.md): a NEES in bounds says nothing about the aided filter.
      {"pseudoranges used by the 24-state filter, 5 arcsec", [](auto& l) { m(l, 5, "24").pr_used = 0; }},
      {"mean NEES of the 24-state filter, 5 arcsec", [](auto& l) { m(l, 5, "24").pr_used = 0; }},
      {"N residual sigma, 15 vs 24 state, 15 arcsec", [](auto& l) { m(l, 15, "15").final_sigma_deg[1] = 0.0150; }},
      {"E residual sigma, 24 at most 15 state, 5 arcsec", [](auto& l) { m(l, 5, "24").final_sigma_deg[0] = 0.0070; }},
      {"E excess", [](auto& l) { l[1].predicted_east_excess_deg = 0.0060; }},  // measured 0.0100: +67%
      {"E excess", [](auto& l) { l[1].predicted_east_excess_deg = 0.0160; }},  // -37%
      {"U sigma after the first turn, 15 vs 24 state, 15 arcsec",
       [](auto& l) { m(l, 15, "24").u_after_first_turn_deg = 0.0160; }},
      {"24-state U sigma keeps falling, 5 arcsec", [](auto& l) { set_u(m(l, 5, "24"), 0.0100); }},
      {"15-state U sigma stays flat, 15 arcsec", [](auto& l) { set_u(m(l, 15, "15"), 0.0180); }},
      {"15-state U sigma stays flat, 15 arcsec", [](auto& l) { m(l, 15, "15").u_after_first_turn_deg = 0.0200; }},
      {"U ratio 24/15 at the end, 15 arcsec", [](auto& l) { m(l, 15, "24").final_sigma_deg[2] = 0.0085; }},
      {"U ratio 24/15 over the last", [](auto& l) {
         for (auto& v : m(l, 15, "24").u_sigma_deg) v = 0.0100;  // the end value alone stays 0.0076
       }},
      {"U ratio 24/15 smaller at 15 arcsec", [](auto& l) { set_u(m(l, 5, "24"), 0.0045); }},
      {"gamma_yz + gamma_zy observable in the 24-state filter and converged, 15 arcsec",
       [](auto& l) { m(l, 15, "24").combinations[0].rms_residual = 3.0 * 1.3; }},
      {"gamma_yz + gamma_zy observable in the 24-state filter and converged, 5 arcsec",
       [](auto& l) { m(l, 5, "24").combinations[0].observable = false; }},
      {"gamma_yz + gamma_zy observable in the 24-state filter and converged, 5 arcsec",
       [](auto& l) { m(l, 5, "24").combinations[0].terms = {{"gyro_mis.xy", 0.71}, {"gyro_mis.yx", 0.71}}; }},
  };
  for (const auto& b : breakers) {
    SCOPED_TRACE(b.check);
    auto levels = good();
    b.apply(levels);
    const auto checks = tools::paper::acceptance(levels);
    const Check* c = find(checks, b.check);
    ASSERT_NE(c, nullptr);
    EXPECT_FALSE(c->pass) << c->value << " vs " << c->limit << " .. " << c->limit2;
    EXPECT_FALSE(tools::paper::all_pass(checks));
  }
}

TEST(PaperVerdict, AMissingModelFailsTheLevel) {
  auto levels = good();
  levels[0].models.pop_back();  // no 24-state model at 5 arcsec
  const auto checks = tools::paper::acceptance(levels);
  ASSERT_NE(find(checks, "15- and 24-state models flown, 5 arcsec"), nullptr);
  EXPECT_FALSE(tools::paper::all_pass(checks));
}

TEST(PaperVerdict, MetricsFollowTheirDefinitions) {
  const auto x = tools::paper::level_metrics(good()[1]);
  EXPECT_NEAR(x.e_excess_deg, std::sqrt(0.0110 * 0.0110 - 0.0045 * 0.0045), 1e-12);
  EXPECT_NEAR(x.u_ratio_end, 0.0076 / 0.0134, 1e-12);
  EXPECT_NEAR(x.u_ratio_last300, 0.0076 / 0.0134, 1e-9);
  EXPECT_NEAR(x.u24_end_over_first, 0.0076 / 0.0140, 1e-12);
  EXPECT_NEAR(x.n_ratio, 0.0123 / 0.0117, 1e-12);
  // The RMS bound of 100 unit samples (99%): about 1.16.
  EXPECT_NEAR(tools::paper::rms_chi2_bound(100), 1.16, 0.01);
}

tools::paper::AnalysisSummary analysis_ok() {
  tools::paper::AnalysisSummary a;
  a.ran = true;
  a.single_axis_cases = 10;
  a.single_axis_max_deviation_pct = 0.22;
  a.accumulating = {"yz", "zy"};
  a.yz_per_turn_arcsec = 27.0;
  a.yz_predicted_arcsec = 27.3;
  a.zy_per_turn_arcsec = 28.0;
  a.zy_predicted_arcsec = 27.2;
  a.gamma_arcsec = 20.0;
  return a;
}

std::string verdict(const std::vector<tools::paper::Claim>& claims, const std::string& id) {
  for (const auto& c : claims)
    if (c.id == id) return c.verdict;
  return "missing";
}

TEST(PaperVerdict, ClaimVerdictsFollowTheNumbers) {
  auto levels = good();
  levels[1].models.push_back(model("15c", 0.054, 0.025, 0.044, 0.0140));
  auto c = tools::paper::claims(levels, analysis_ok());
  EXPECT_EQ(c.size(), 8u);
  EXPECT_EQ(verdict(c, "horizontal_similar"), "not reproduced");  // E 2.4x at 15 arcsec
  EXPECT_EQ(verdict(c, "bias_heading_equal"), "reproduced");
  EXPECT_EQ(verdict(c, "15_not_removed"), "reproduced");
  EXPECT_EQ(verdict(c, "24_removes"), "reproduced");
  EXPECT_EQ(verdict(c, "gap_grows"), "reproduced");
  EXPECT_EQ(verdict(c, "15_as_large_as_initial"), "not reproduced");  // 0.0134 of 0.046
  EXPECT_EQ(verdict(c, "single_axis"), "reproduced");
  EXPECT_EQ(verdict(c, "bank_turn"), "reproduced");
  for (const auto& x : c) {
    EXPECT_FALSE(x.measured.empty()) << x.id;
    EXPECT_EQ(x.verdict == "reproduced", x.cause.empty()) << x.id << ": " << x.cause;
  }
  // The cause of the accumulated-error claim points at the untuned filter when it matches.
  for (const auto& x : c) {
    if (x.id == "15_as_large_as_initial") EXPECT_NE(x.cause.find("15c"), std::string::npos) << x.cause;
    if (x.id == "single_axis") EXPECT_EQ(x.measured.rfind("10 cases:", 0), 0u) << x.measured;
  }

  // The same claims flip when their numbers do.
  m(levels, 5, "24").final_sigma_deg[0] = 0.0060;
  m(levels, 15, "24").final_sigma_deg[0] = 0.0100;
  m(levels, 15, "15").final_sigma_deg[2] = 0.040;
  m(levels, 15, "15").u_after_first_turn_deg = 0.0140;
  m(levels, 15, "24").u_after_first_turn_deg = 0.0180;
  auto an = analysis_ok();
  an.accumulating = {"yz", "zy", "xy"};
  an.single_axis_max_deviation_pct = 4.0;
  c = tools::paper::claims(levels, an);
  EXPECT_EQ(verdict(c, "15_not_removed"), "reproduced");  // 0.040 / 0.0140: it grows
  EXPECT_EQ(verdict(c, "horizontal_similar"), "reproduced");
  EXPECT_EQ(verdict(c, "bias_heading_equal"), "not reproduced");  // 1.29x
  EXPECT_EQ(verdict(c, "15_as_large_as_initial"), "reproduced");  // 0.040 of 0.046
  EXPECT_EQ(verdict(c, "bank_turn"), "reproduced qualitatively");
  EXPECT_EQ(verdict(c, "single_axis"), "reproduced qualitatively");

  set_u(m(levels, 5, "24"), 0.0020);  // the gap no longer grows with the misalignment
  set_u(m(levels, 15, "24"), 0.0190);  // and the 24-state U no longer falls at 15 arcsec (first turn 0.0180)
  c = tools::paper::claims(levels, {});
  EXPECT_EQ(verdict(c, "gap_grows"), "not reproduced");
  EXPECT_EQ(verdict(c, "24_removes"), "not reproduced");
  set_u(m(levels, 15, "24"), 0.0050);  // 24-state U end / first turn 0.28
  set_u(m(levels, 15, "15"), 0.0100);  // the 15-state U falls to 0.71 of its first-turn value ...
  c = tools::paper::claims(levels, {});
  EXPECT_EQ(verdict(c, "15_not_removed"), "reproduced qualitatively");  // ... but less than the 24-state's
  set_u(m(levels, 15, "15"), 0.0030);
  c = tools::paper::claims(levels, {});
  EXPECT_EQ(verdict(c, "15_not_removed"), "not reproduced");  // 0.21, below the 24-state's 0.28
  EXPECT_EQ(verdict(c, "single_axis"), "not run");
  EXPECT_EQ(verdict(c, "bank_turn"), "not run");
}

TEST(PaperVerdict, TiltKickOfOneTurnMatchesTheBankTurnGeometry) {
  // The default flight, long enough for two turns: 60 s straight, a right 180-degree turn at
  // 60 deg bank, 30 s straight, a left one. gamma_xy couples the pitch rate q = psi' sin(bank)
  // into the x gyro, whose axis sweeps the East half circle: the East kick is at most
  // 2 sin(60 deg) = 1.732 (reached when the whole heading change is flown at full bank), the
  // North kick vanishes by symmetry, and the left turn kicks East the same way.
  sim::Scenario sc;
  sc.duration_s = 260.0;
  const auto kicks = tools::paper::turn_kicks(sim::TruthTrack::generate(sc));
  ASSERT_EQ(kicks.size(), 2u);
  for (const auto& k : kicks) {
    const double e_xy = k.per_rad[0][0], n_xy = k.per_rad[0][1];
    EXPECT_GT(std::abs(e_xy), 1.5);
    EXPECT_LE(std::abs(e_xy), 2.0 * std::sin(60.0 * M_PI / 180.0) + 1e-3);
    EXPECT_LT(std::abs(n_xy), 0.05);
    // gamma_yx: the roll rate into the y gyro, at roll-in and roll-out: the y axis points to the
    // right of the nose, which has turned 180 degrees in between, so both add (at most 2 sin 60).
    EXPECT_GT(std::abs(k.per_rad[2][0]), 1.0);
    EXPECT_LE(std::abs(k.per_rad[2][0]), 2.0 * std::sin(60.0 * M_PI / 180.0) + 1e-3);
  }
  EXPECT_GT(kicks[0].per_rad[0][0] * kicks[1].per_rad[0][0], 0.0) << "alternating turns kick East the same way";
  EXPECT_GT(kicks[0].per_rad[2][0] * kicks[1].per_rad[2][0], 0.0);
  const double pred = tools::paper::predicted_east_excess_deg(kicks, 15.0);
  EXPECT_NEAR(pred, 15.0 / 3600.0 * std::hypot(kicks[1].per_rad[0][0], kicks[1].per_rad[2][0]), 1e-12);
  EXPECT_EQ(tools::paper::predicted_east_excess_deg({}, 15.0), 0.0);

  // Racetrack: the second right turn flies the West half circle: its gamma_xy kick reverses.
  const auto pats = tools::paper::turn_patterns(sc);
  const auto& race = pats[3];
  ASSERT_EQ(race.name, "racetrack");
  const auto rk = tools::paper::turn_kicks(sim::TruthTrack::generate(race.scenario));
  ASSERT_EQ(rk.size(), 2u);
  EXPECT_LT(rk[0].per_rad[0][0] * rk[1].per_rad[0][0], 0.0);
}

TEST(PaperVerdict, TurnPatternsChangeOnlyTheTurns) {
  const sim::Scenario base;
  const auto pats = tools::paper::turn_patterns(base);
  ASSERT_EQ(pats.size(), 4u);
  const double want[4] = {180.0, 90.0, 360.0, 180.0};
  for (std::size_t p = 0; p < pats.size(); ++p) {
    ASSERT_EQ(pats[p].scenario.segments.size(), base.segments.size());
    int turn = 0;
    for (std::size_t s = 0; s < base.segments.size(); ++s) {
      const auto& a = base.segments[s];
      const auto& b = pats[p].scenario.segments[s];
      EXPECT_EQ(a.type, b.type);
      EXPECT_EQ(a.bank_deg, b.bank_deg);
      if (a.type != sim::SegmentType::kTurn) {
        EXPECT_EQ(a.duration_s, b.duration_s);
        continue;
      }
      EXPECT_EQ(b.heading_change_deg, want[p]) << pats[p].name;
      const bool right = p == 3 || turn % 2 == 0;
      EXPECT_EQ(b.direction == sim::TurnDirection::kRight, right) << pats[p].name << " turn " << turn;
      ++turn;
    }
  }
}

TEST(PaperVerdict, PatternParagraphNamesThePatternsThatGiveThePapersResult) {
  std::vector<LevelSummary> l = good();
  const auto alt = tools::paper::pattern_result("alternating_180", l[1], {});
  EXPECT_NEAR(alt.ratio24_15[2], 0.0076 / 0.0134, 1e-12);
  EXPECT_TRUE(alt.heading_combination_observable);
  EXPECT_EQ(alt.observable.size(), 1u);
  set_u(m(l, 15, "24"), 0.0120);  // a pattern where the 24-state filter gains little
  m(l, 15, "24").combinations.clear();
  const auto race = tools::paper::pattern_result("racetrack", l[1], {});
  EXPECT_FALSE(race.heading_combination_observable);
  const std::string p = tools::paper::pattern_paragraph({alt, race}, 15.0);
  const auto in = p.find("in: "), not_in = p.find("not in: ");
  ASSERT_NE(in, std::string::npos);
  ASSERT_NE(not_in, std::string::npos);
  EXPECT_LT(p.find("alternating_180"), not_in) << p;
  EXPECT_GT(p.find("racetrack ("), not_in) << p;
}

}  // namespace
