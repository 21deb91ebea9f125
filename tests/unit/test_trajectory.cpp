// Truth kinematics: the bank-to-turn flight timeline, the truth generator's increments, the rate
// table, and bit-exact determinism of truth + IMU model.
//
// Expectations come from the coordinated-turn law written out here (heading rate g tan(phi) / V,
// body rates q = psi_dot sin(phi), r = psi_dot cos(phi) at zero pitch, lateral specific force zero
// up to Coriolis / transport terms), from this file's own quadrature of the heading turned during a
// roll transition, and from closed-form integrals for the rate table.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fsw/frames.hpp"
#include "sim/imu_model.hpp"
#include "sim/scenario.hpp"
#include "sim/trajectory.hpp"
#include "tools/free_inertial.hpp"
#include "test_util.hpp"

namespace {

using fsw::Mat3;
using fsw::Vec3;
using sim::FlightPhase;

using fsw::kPi;
using test_util::kDeg;
constexpr double kOmegaEarth = 7.292115e-5;
// Normal gravity at 35 deg, 5000 m (the default start), from the closed-form WGS-84 expression
// evaluated independently (also pinned in test_frames.cpp).
constexpr double kG35at5000 = 9.7819226579;

/// The documented roll transition shape: s(x) = x - sin(2 pi x) / (2 pi).
double shape(double x) { return x - std::sin(2.0 * kPi * x) / (2.0 * kPi); }

/// Heading turned during one roll transition of length T to bank phi_b at speed V with the
/// coordination law psi_dot = g tan(phi) / V (composite Simpson, 20000 intervals).
double roll_heading_change(double g, double V, double phi_b, double T) {
  const int n = 20000;
  double sum = 0.0;
  for (int i = 0; i <= n; ++i) {
    const double x = static_cast<double>(i) / n;
    const double w = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
    sum += w * std::tan(phi_b * shape(x));
  }
  return g / V * T * sum / (3.0 * n);
}

std::unique_ptr<sim::FlightMotion> make(const sim::Scenario& sc) {
  std::string err;
  auto m = sim::FlightMotion::create(sc, err);
  EXPECT_TRUE(m) << err;
  return m;
}

double wrap_pi(double a) {
  while (a > kPi) a -= 2.0 * kPi;
  while (a < -kPi) a += 2.0 * kPi;
  return a;
}

/// FNV-1a over the raw bytes of doubles.
struct Fnv1a {
  std::uint64_t h = 0xCBF29CE484222325ULL;
  void add(double x) {
    unsigned char b[sizeof(double)];
    std::memcpy(b, &x, sizeof b);
    for (unsigned char c : b) {
      h ^= c;
      h *= 0x100000001B3ULL;
    }
  }
  void add(const Vec3& v) {
    for (int i = 0; i < 3; ++i) add(v(i));
  }
};

}  // namespace

// ------------------------------------------------------------------------------------------------
// FlightMotion
// ------------------------------------------------------------------------------------------------

namespace {

/// A perfect IMU flown free-inertial over the first 200 s of motion m stays on its truth (the
/// truth kinematics are consistent): position within 5 cm, velocity 1 mm/s, attitude 1e-8 rad.
void expect_free_inertial_on_truth(const sim::FlightMotion& m, const char* what) {
  tools::FreeInertialConfig cfg;
  cfg.duration_s = 200.0;
  double max_pos = 0.0, max_vel = 0.0, max_att = 0.0;
  fsw::Status st = fsw::Status::kOk;
  tools::run_free_inertial(
      m, nullptr, cfg,
      [&](const sim::TruthSample& truth, const fsw::NavState& nav) {
        const tools::NavErrors e = tools::nav_errors(nav, truth);
        max_pos = std::max(max_pos, e.pos_enu_m.norm());
        max_vel = std::max(max_vel, e.vel_enu_mps.norm());
        max_att = std::max(max_att, e.att_phi_enu_rad.norm());
      },
      &st);
  ASSERT_EQ(st, fsw::Status::kOk);
  std::printf("%s, perfect IMU free-inertial over 200 s: position %.2e m, velocity %.2e m/s, attitude %.2e rad\n",
              what, max_pos, max_vel, max_att);
  EXPECT_LT(max_pos, 0.05);
  EXPECT_LT(max_vel, 1e-3);
  EXPECT_LT(max_att, 1e-8);
}

}  // namespace

TEST(FlightMotion, SmoothStepShape) {
  EXPECT_EQ(sim::smooth_step(0.0), 0.0);
  EXPECT_EQ(sim::smooth_step(1.0), 1.0);
  EXPECT_EQ(sim::smooth_step(-0.5), 0.0);
  EXPECT_EQ(sim::smooth_step(1.5), 1.0);
  EXPECT_NEAR(sim::smooth_step(0.5), 0.5, 1e-15);
  const double e = 1e-5;
  for (double x : {0.1, 0.25, 0.5, 0.8, 0.97}) {
    EXPECT_NEAR(sim::smooth_step(x), shape(x), 1e-15);
    // The rate is the derivative of the shape.
    EXPECT_NEAR(sim::smooth_step_rate(x), (sim::smooth_step(x + e) - sim::smooth_step(x - e)) / (2 * e), 1e-9);
  }
  // Zero first and second derivatives at both ends.
  EXPECT_EQ(sim::smooth_step_rate(0.0), 0.0);
  EXPECT_EQ(sim::smooth_step_rate(1.0), 0.0);
  EXPECT_NEAR(sim::smooth_step_rate(e) / e, 0.0, 1e-3);
  EXPECT_NEAR(sim::smooth_step_rate(1.0 - e) / e, 0.0, 1e-3);
}

TEST(FlightMotion, DefaultTimelineAlternatesTurnsAndCoversDuration) {
  const sim::Scenario sc;
  auto m = make(sc);
  ASSERT_TRUE(m);
  const auto& tl = m->timeline();
  // Expected turn duration from the coordination law: two roll transitions of 5 s plus a constant
  // bank phase flying the rest of the 180 degrees at g tan(60 deg) / 250 m/s.
  const double g = kG35at5000, V = 250.0, phi = 60.0 * kDeg, T = 5.0;
  ASSERT_NEAR(fsw::normal_gravity_mps2(35.0 * kDeg, 5000.0), g, 1e-9);
  const double dpsi_roll = roll_heading_change(g, V, phi, T);
  const double psi_dot = g * std::tan(phi) / V;
  const double t_bank = (kPi - 2.0 * dpsi_roll) / psi_dot;
  std::printf("default turn: psi_dot %.4f deg/s, %.4f deg turned per roll transition, bank phase %.4f s, "
              "turn %.4f s\n", psi_dot / kDeg, dpsi_roll / kDeg, t_bank, t_bank + 2 * T);

  ASSERT_GE(tl.size(), 6u);
  EXPECT_EQ(tl[0].kind, FlightPhase::Kind::kStraight);
  EXPECT_EQ(tl[0].t0_s, 0.0);
  EXPECT_NEAR(tl[0].t1_s, 60.0, 1e-12);
  int turns = 0;
  double last_sign = -1.0;  // the first turn is to the right
  double t_expect = 60.0;   // start of the next phase from the schedule 60 s, [turn, 30 s, turn, 30 s]...
  for (std::size_t i = 0; i + 1 < tl.size(); ++i) {
    EXPECT_NEAR(tl[i].t1_s, tl[i + 1].t0_s, 1e-9) << "phases " << i << " and " << i + 1 << " are not contiguous";
    EXPECT_LT(tl[i].t0_s, tl[i].t1_s) << i;
  }
  for (std::size_t i = 1; i < tl.size(); ++i) {
    const FlightPhase& p = tl[i];
    if (p.kind == FlightPhase::Kind::kRollIn) {
      ASSERT_LT(i + 2, tl.size());
      const FlightPhase& b = tl[i + 1];
      const FlightPhase& o = tl[i + 2];
      ASSERT_EQ(b.kind, FlightPhase::Kind::kBank);
      ASSERT_EQ(o.kind, FlightPhase::Kind::kRollOut);
      EXPECT_NEAR(p.t0_s, t_expect, 1e-6) << "turn " << turns;
      EXPECT_NEAR(p.t1_s - p.t0_s, T, 1e-9);
      EXPECT_NEAR(b.t1_s - b.t0_s, t_bank, 1e-6) << "turn " << turns;
      EXPECT_NEAR(o.t1_s - o.t0_s, T, 1e-9);
      // Alternating right / left 60-degree bank turns.
      EXPECT_NEAR(p.bank_rad, -last_sign * phi, 1e-15) << "turn " << turns;
      EXPECT_EQ(b.bank_rad, p.bank_rad);
      EXPECT_EQ(o.bank_rad, p.bank_rad);
      EXPECT_EQ(p.turn, turns);
      EXPECT_EQ(b.turn, turns);
      EXPECT_EQ(o.turn, turns);
      EXPECT_EQ(p.segment, turns % 2 == 0 ? 1 : 3);
      last_sign = p.bank_rad > 0 ? 1.0 : -1.0;
      t_expect += 2 * T + t_bank;
      ++turns;
      i += 2;
    } else {
      ASSERT_EQ(p.kind, FlightPhase::Kind::kStraight);
      if (p.segment >= 0) {
        EXPECT_NEAR(p.t0_s, t_expect, 1e-6);
        EXPECT_NEAR(p.t1_s - p.t0_s, 30.0, 1e-9);
        EXPECT_EQ(p.turn, -1);
        t_expect += 30.0;
      }
    }
  }
  // Expected number of turns: turns start while the schedule is before 1800 s.
  int want_turns = 0;
  for (double t = 60.0; t < sc.duration_s; t += 2 * T + t_bank + 30.0) ++want_turns;
  EXPECT_EQ(turns, want_turns);
  EXPECT_GE(turns, 15);
  // The timeline covers the duration, and beyond it the aircraft flies straight.
  EXPECT_GE(tl.back().t1_s, sc.duration_s);
  double roll = 1.0, rate = 1.0;
  m->roll(sc.duration_s + 500.0, roll, rate);
  EXPECT_EQ(roll, 0.0);
  EXPECT_EQ(rate, 0.0);
}

TEST(FlightMotion, NoRepeatFliesStraightAfterLastSegment) {
  sim::Scenario sc;
  sc.repeat_from = std::nullopt;
  auto m = make(sc);
  ASSERT_TRUE(m);
  const auto& tl = m->timeline();
  for (std::size_t i = 0; i + 1 < tl.size(); ++i) {
    EXPECT_NEAR(tl[i].t1_s, tl[i + 1].t0_s, 1e-9) << "phases " << i << " and " << i + 1 << " are not contiguous";
  }
  EXPECT_GE(tl.back().t1_s, sc.duration_s);
  // Exactly the two turns of the segment list.
  int max_turn = -1;
  for (const auto& p : tl) max_turn = std::max(max_turn, p.turn);
  EXPECT_EQ(max_turn, 1);
  // The last segment (30 s straight) ends at 60 + 2 turns + 60 s; from then on: straight, no segment.
  const double dpsi_roll = roll_heading_change(kG35at5000, 250.0, 60.0 * kDeg, 5.0);
  const double turn = 10.0 + (kPi - 2.0 * dpsi_roll) / (kG35at5000 * std::tan(60.0 * kDeg) / 250.0);
  const double t_end = 60.0 + 2.0 * turn + 60.0;
  for (double t : {t_end + 0.5, 900.0, sc.duration_s - 1.0, sc.duration_s + 10.0}) {
    const sim::MotionPhase ph = m->phase(t);
    EXPECT_FALSE(ph.turning) << t;
    EXPECT_EQ(ph.turn, -1) << t;
    EXPECT_EQ(ph.segment, -1) << t;
    double r = 1.0, rr = 1.0;
    m->roll(t, r, rr);
    EXPECT_EQ(r, 0.0);
  }
  EXPECT_EQ(m->phase(t_end - 0.5).segment, 4);
  // Truth heading is constant after the last turn.
  sim::TruthGenerator gen(*m, 100.0);
  double psi_first = -1.0;
  while (gen.current().t_s < 600.0) {
    const sim::TruthSample& s = gen.next();
    if (s.t_s < t_end - 30.0) continue;
    const double psi = fsw::euler_from_C_b_n(s.C_b_n).z();
    if (psi_first < 0) psi_first = psi;
    ASSERT_NEAR(wrap_pi(psi - psi_first), 0.0, 1e-12) << s.t_s;
  }
  // Two 180-degree turns: back on the initial heading (North).
  EXPECT_NEAR(wrap_pi(psi_first), 0.0, 0.01 * kDeg);
}

TEST(FlightMotion, TurnSmallerThanRollTransitionsIsRejected) {
  // 60 deg bank, 5 s roll-in and roll-out at 250 m/s: the transitions alone turn 2 * dpsi_roll.
  const double min_deg = 2.0 * roll_heading_change(kG35at5000, 250.0, 60.0 * kDeg, 5.0) / kDeg;
  std::printf("minimum heading change of a 60-deg, 5 s roll-time turn: %.6f deg\n", min_deg);
  sim::Scenario sc;
  sc.duration_s = 60.0;
  sc.repeat_from = std::nullopt;
  sc.segments = {sim::Segment{.type = sim::SegmentType::kStraight, .duration_s = 10.0},
                 sim::Segment{.type = sim::SegmentType::kTurn, .direction = sim::TurnDirection::kLeft,
                              .bank_deg = 60.0, .heading_change_deg = min_deg * (1.0 - 1e-5), .roll_time_s = 5.0}};
  std::string err;
  EXPECT_EQ(sim::FlightMotion::create(sc, err), nullptr);
  EXPECT_NE(err.find("segment 1"), std::string::npos) << err;
  EXPECT_NE(err.find("smaller"), std::string::npos) << err;
  // Just above the minimum is accepted, with an almost zero constant-bank phase, and flies it.
  sc.segments[1].heading_change_deg = min_deg * (1.0 + 1e-5);
  err.clear();
  auto m = sim::FlightMotion::create(sc, err);
  ASSERT_TRUE(m) << err;
  EXPECT_TRUE(err.empty());
  const FlightPhase& bank = m->timeline()[2];
  ASSERT_EQ(bank.kind, FlightPhase::Kind::kBank);
  EXPECT_GT(bank.t1_s - bank.t0_s, 0.0);
  EXPECT_LT(bank.t1_s - bank.t0_s, 1e-3);
  sim::TruthGenerator gen(*m, 1000.0);
  const double psi0 = fsw::euler_from_C_b_n(gen.current().C_b_n).z();
  while (gen.current().t_s < 25.0) gen.next();
  const double dpsi = wrap_pi(fsw::euler_from_C_b_n(gen.current().C_b_n).z() - psi0);
  EXPECT_NEAR(dpsi / kDeg, -min_deg, 0.01);
  // Any scenario without segments or with a non-positive speed is rejected too.
  sim::Scenario bad;
  bad.start.speed_mps = 0.0;
  err.clear();
  EXPECT_EQ(sim::FlightMotion::create(bad, err), nullptr);
  EXPECT_FALSE(err.empty());
}

// One flight of the first two turns and every check on it (123 lines, over the ~120 the project
// keeps to): the checks read the accumulators of the one loop, and split apart they would pass
// about twenty of them through a struct without making either half readable alone.
TEST(FlightMotion, CoordinatedTurnsOfTheDefaultScenario) {
  // Fly the first two turns (right, then left) of the default scenario at 1 kHz.
  const sim::Scenario sc;
  auto m = make(sc);
  ASSERT_TRUE(m);
  const auto& tl = m->timeline();
  std::vector<const FlightPhase*> rollins;
  for (const auto& p : tl) {
    if (p.kind == FlightPhase::Kind::kRollIn && p.turn < 2) rollins.push_back(&p);
  }
  ASSERT_EQ(rollins.size(), 2u);
  const double t_stop = (rollins[1] + 2)->t1_s + 2.0;

  const double g = kG35at5000, V = 250.0, phi_b = 60.0 * kDeg;
  const double psi_dot = g * std::tan(phi_b) / V;
  const double q_exp = psi_dot * std::sin(phi_b);  // = 1.5 g / V
  const double r_exp = psi_dot * std::cos(phi_b);
  std::printf("steady 60-deg bank at 250 m/s: psi_dot %.4f deg/s, q %.4f deg/s, |r| %.4f deg/s, f_z %.4f m/s^2\n",
              psi_dot / kDeg, q_exp / kDeg, r_exp / kDeg, -g / std::cos(phi_b));
  // The brief's round numbers.
  EXPECT_NEAR(q_exp / kDeg, 3.4, 0.05);
  EXPECT_NEAR(r_exp / kDeg, 1.95, 0.02);

  sim::TruthGenerator gen(*m, 1000.0);
  const auto wall0 = std::chrono::steady_clock::now();
  double psi_unwrapped = 0.0, psi_prev = fsw::euler_from_C_b_n(gen.current().C_b_n).z();
  double psi_int = 0.0;  // integral of the Euler heading rate from the body rates (trapezoid)
  auto heading_rate = [](const sim::TruthSample& s) {
    const Vec3 e = fsw::euler_from_C_b_n(s.C_b_n);
    const Vec3& w = s.omega_nb_b_radps;
    return (w.y() * std::sin(e.x()) + w.z() * std::cos(e.x())) / std::cos(e.y());
  };
  double rate_prev = heading_rate(gen.current());
  double psi_start[2] = {0, 0}, psi_end[2] = {0, 0}, int_start[2] = {0, 0}, int_end[2] = {0, 0};
  double max_roll[2] = {0, 0}, min_roll[2] = {0, 0};
  double max_fy = 0.0, max_fx = 0.0, max_dspeed = 0.0, max_dh = 0.0, max_q_err = 0.0, max_r_err = 0.0,
         max_fz_err = 0.0;
  int bank_samples[2] = {0, 0};
  bool ended[2] = {false, false};
  double min_q_turn = 1.0, max_lat = 0.0;
  while (gen.current().t_s < t_stop) {
    const sim::TruthSample& s = gen.next();
    const double t = s.t_s;
    const Vec3 e = fsw::euler_from_C_b_n(s.C_b_n);
    psi_unwrapped += wrap_pi(e.z() - psi_prev);
    psi_prev = e.z();
    const double rate = heading_rate(s);
    psi_int += 0.5 * (rate + rate_prev) * s.dt_s;
    rate_prev = rate;
    for (int k = 0; k < 2; ++k) {
      const FlightPhase& in = *rollins[k];
      const FlightPhase& bank = *(rollins[k] + 1);
      const FlightPhase& out = *(rollins[k] + 2);
      // Straight flight just before / after the turn: the heading is constant there.
      if (t <= in.t0_s) {
        psi_start[k] = psi_unwrapped;
        int_start[k] = psi_int;
      }
      if (t >= out.t1_s && !ended[k]) {
        ended[k] = true;
        psi_end[k] = psi_unwrapped;
        int_end[k] = psi_int;
      }
      if (t > in.t0_s && t < out.t1_s) {
        max_roll[k] = std::max(max_roll[k], e.x());
        min_roll[k] = std::min(min_roll[k], e.x());
        min_q_turn = std::min(min_q_turn, s.omega_nb_b_radps.y());
      }
      if (t > bank.t0_s + 1e-6 && t < bank.t1_s - 1e-6) {
        ++bank_samples[k];
        const double sign = k == 0 ? 1.0 : -1.0;  // right, then left
        max_q_err = std::max(max_q_err, std::abs(s.omega_nb_b_radps.y() - q_exp));
        max_r_err = std::max(max_r_err, std::abs(s.omega_nb_b_radps.z() - sign * r_exp));
        max_fz_err = std::max(max_fz_err, std::abs(s.f_b_mps2.z() + g / std::cos(phi_b)));
        EXPECT_NEAR(s.omega_nb_b_radps.x(), 0.0, 1e-15);
      }
    }
    max_fy = std::max(max_fy, std::abs(s.f_b_mps2.y()));
    max_fx = std::max(max_fx, std::abs(s.f_b_mps2.x()));
    max_dspeed = std::max(max_dspeed, std::abs(s.vel_enu_mps.norm() - V));
    max_dh = std::max(max_dh, std::abs(s.llh.z() - 5000.0));
    max_lat = std::max(max_lat, s.llh.x());
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  for (int k = 0; k < 2; ++k) {
    const double dpsi = (psi_end[k] - psi_start[k]) / kDeg;
    const double dpsi_int = (int_end[k] - int_start[k]) / kDeg;
    std::printf("turn %d (%s): heading change %.6f deg (from attitude), %.6f deg (integrated body rates); "
                "roll %.4f..%.4f deg; %d steady-bank samples\n",
                k, k == 0 ? "right" : "left", dpsi, dpsi_int, min_roll[k] / kDeg, max_roll[k] / kDeg, bank_samples[k]);
    const double want = k == 0 ? 180.0 : -180.0;
    EXPECT_NEAR(dpsi, want, 0.01) << "turn " << k;
    EXPECT_NEAR(dpsi_int, want, 0.01) << "turn " << k;
    EXPECT_GE(bank_samples[k], static_cast<int>(((rollins[k] + 1)->t1_s - (rollins[k] + 1)->t0_s) * 1000.0) - 2);
    EXPECT_TRUE(ended[k]);
  }
  // Bank reaches +60 deg in the right turn and -60 deg in the left turn, and no more.
  EXPECT_NEAR(max_roll[0] / kDeg, 60.0, 1e-9);
  EXPECT_NEAR(min_roll[0], 0.0, 1e-12);
  EXPECT_NEAR(min_roll[1] / kDeg, -60.0, 1e-9);
  EXPECT_NEAR(max_roll[1], 0.0, 1e-12);
  std::printf("steady bank: max |q - q_exp| %.2e, |r - r_exp| %.2e rad/s, |f_z + 2g| %.2e m/s^2; whole flight: "
              "max |f_y| %.4f, |f_x| %.2e m/s^2, |speed - 250| %.2e m/s, |h - 5000| %.2e m (%.0f s flown in %.2f s)\n",
              max_q_err, max_r_err, max_fz_err, max_fy, max_fx, max_dspeed, max_dh, t_stop, wall);
  EXPECT_LT(max_q_err, 1e-12);
  EXPECT_LT(max_r_err, 1e-12);
  // Pitch rate is never negative in a level turn, in either direction.
  EXPECT_GE(min_q_turn, 0.0);
  // Coordinated: no lateral specific force except the Coriolis and transport-rate terms
  // |(2 omega_ie + omega_en) x v| <= (2 Omega + V / ((R_M + h) cos L)) V = 0.0485 m/s^2 (|omega_en| <=
  // V / ((R_M + h) cos L) because of its tan(L) vertical component; L <= 35.5 deg here), plus up to
  // 2e-4 m/s^2 from the change of normal gravity with latitude against the coordination law's
  // start-point g. An uncoordinated 60-deg bank would give g sin(60 deg) = 8.5 m/s^2.
  const double cor_bound =
      (2.0 * kOmegaEarth + V / ((fsw::meridian_radius_m(35.0 * kDeg) + 5000.0) * std::cos(35.5 * kDeg))) * V + 2e-4;
  EXPECT_LT(max_fy, cor_bound);
  EXPECT_LT(max_lat, 35.5 * kDeg);
  // Along the velocity neither gravity nor the Coriolis terms act, and the speed is constant.
  EXPECT_LT(max_fx, 1e-9);
  // Load factor 1 / cos(60 deg) = 2, again up to the Coriolis terms.
  EXPECT_LT(max_fz_err, cor_bound);
  EXPECT_LT(max_dspeed, 1e-9);
  EXPECT_LT(max_dh, 1e-9);
}

// ------------------------------------------------------------------------------------------------
// TruthGenerator
// ------------------------------------------------------------------------------------------------

TEST(TruthGenerator, IncrementsMatchInstantaneousRates) {
  // Through the first roll-in of the default flight (60..65 s), where the rates change fastest.
  const sim::Scenario sc;
  auto m = make(sc);
  ASSERT_TRUE(m);
  sim::TruthGenerator gen(*m, 1000.0);
  EXPECT_EQ(gen.current().t_s, 0.0);
  EXPECT_EQ(gen.current().dt_s, 0.0);
  Vec3 w_prev = gen.current().omega_ib_b_radps, f_prev = gen.current().f_b_mps2;
  double max_trap_w = 0.0, max_trap_f = 0.0, max_rect_w = 0.0, max_dw = 0.0;
  long n = 0;
  while (gen.current().t_s < 67.0) {
    const sim::TruthSample& s = gen.next();
    ++n;
    ASSERT_NEAR(s.t_s, n * 1e-3, 1e-12);
    ASSERT_NEAR(s.dt_s, 1e-3, 1e-13);  // difference of index-based times
    if (s.t_s < 58.0) {
      w_prev = s.omega_ib_b_radps;
      f_prev = s.f_b_mps2;
      continue;
    }
    // Trapezoid of the instantaneous rates: agrees to O(dt^3 * second derivative) ~ 1e-11.
    max_trap_w = std::max(max_trap_w, (s.dtheta_rad - 0.5 * (w_prev + s.omega_ib_b_radps) * s.dt_s).norm());
    max_trap_f = std::max(max_trap_f, (s.dv_mps - 0.5 * (f_prev + s.f_b_mps2) * s.dt_s).norm());
    // Rectangle with the end rate: O(dt^2) ~ 0.5 dt^2 |d omega / dt|.
    max_rect_w = std::max(max_rect_w, (s.dtheta_rad - s.omega_ib_b_radps * s.dt_s).norm());
    max_dw = std::max(max_dw, (s.omega_ib_b_radps - w_prev).norm());
    w_prev = s.omega_ib_b_radps;
    f_prev = s.f_b_mps2;
  }
  std::printf("roll-in increments: |dtheta - trapezoid| %.2e rad, |dv - trapezoid| %.2e m/s, "
              "|dtheta - omega dt| %.2e rad (0.5 dt |d omega| = %.2e)\n",
              max_trap_w, max_trap_f, max_rect_w, 0.5 * max_dw * 1e-3);
  EXPECT_LT(max_trap_w, 1e-10);
  EXPECT_LT(max_trap_f, 5e-9);
  EXPECT_LT(max_rect_w, 0.5 * max_dw * 1e-3 * 1.01 + 1e-10);
  EXPECT_GT(max_rect_w, 1e-8);  // the roll-in really changes the rates (peak roll acceleration 0.26 rad/s^2)
}

TEST(FlightMotion, AnchoredDerivativeIsTheExactOneWithinAStep) {
  // The RK4 stages' derivative from a step anchor (Taylor series of the track's and latitude's
  // sines and the radii) against the exact one: identical at the anchor, within the doubles'
  // rounding at every state one 1 ms step can reach (track +-1.3e-4 rad at the steepest turn,
  // latitude +-4e-8 rad at 250 m/s, height +-0.25 m), over tracks all round the circle.
  sim::Scenario sc;
  auto m = make(sc);
  ASSERT_TRUE(m);
  sim::Motion::Instant in;
  m->instant(62.3, in);  // in the first roll-in: speed, bank and heading rate all non-trivial
  double worst_ulps = 0.0;
  for (int i = 0; i < 64; ++i) {
    sim::Motion::State y0 = sim::Motion::State::Zero();
    y0(0) = -kPi + 2.0 * kPi * i / 64.0 + 0.01;
    y0(1) = (35.0 + 0.3 * (i % 7)) * kDeg;
    y0(2) = 127.0 * kDeg;
    y0(3) = 5000.0 + 10.0 * i;
    sim::Motion::StepAnchor a;
    m->anchor(y0, a);
    const sim::Motion::State exact0 = m->derivative(in, y0), anchored0 = m->derivative(in, y0, a);
    for (int k = 0; k < 4; ++k) ASSERT_EQ(std::memcmp(&exact0(k), &anchored0(k), sizeof(double)), 0) << i << " " << k;
    for (double dp : {-1.3e-4, -3e-5, 0.0, 7e-5, 1.3e-4})
      for (double dl : {-4e-8, 0.0, 4e-8}) {
        sim::Motion::State y = y0;
        y(0) += dp;
        y(1) += dl;
        y(3) += dl * 6e6;
        const sim::Motion::State e = m->derivative(in, y), t = m->derivative(in, y, a);
        // In ulps of the larger horizontal rate (a component near a zero of its sine is not
        // itself known to its own ulps).
        const double scale = std::max(std::abs(e(1)), std::abs(e(2)));
        for (int k = 1; k < 3; ++k)
          worst_ulps = std::max(worst_ulps, std::abs(t(k) - e(k)) / (scale * 2.220446049250313e-16));
        ASSERT_EQ(t(0), e(0));
        ASSERT_EQ(t(3), e(3));
      }
  }
  std::printf("anchored derivative against the exact one: worst %.2f ulp\n", worst_ulps);
  EXPECT_LT(worst_ulps, 8.0);
}

TEST(FlightMotion, AnchoredEvaluationIsTheExactOneWithinAStep) {
  // The truth's midpoint and end-of-step evaluations from the step anchor (the track's sine and
  // cosine, the latitude's sine, cosine and tangent, the radii and gravity's square root carried
  // by their Taylor series) against the exact evaluation and Earth terms: identical at the
  // anchor, within the doubles' rounding at every state one 1 ms step reaches, over tracks all
  // round the circle; the body rate and specific force they give likewise.
  sim::Scenario sc;
  auto m = make(sc);
  ASSERT_TRUE(m);
  sim::Motion::Instant in;
  m->instant(62.3, in);  // in the first roll-in
  double worst_ulps = 0.0, worst_imu_ulps = 0.0;
  const double eps = 2.220446049250313e-16;
  for (int i = 0; i < 64; ++i) {
    sim::Motion::State y0 = sim::Motion::State::Zero();
    y0(0) = -kPi + 2.0 * kPi * i / 64.0 + 0.01;
    y0(1) = (-60.0 + 2.0 * i) * kDeg;  // latitudes -60 .. 66 deg, both hemispheres
    y0(2) = 127.0 * kDeg;
    y0(3) = 5000.0 + 10.0 * i;
    sim::Motion::StepAnchor a;
    m->anchor(y0, a);
    for (double dp : {0.0, -1.3e-4, -3e-5, 7e-5, 1.3e-4})
      for (double dl : {0.0, -4e-8, 4e-8}) {
        sim::Motion::State y = y0;
        y(0) += dp;
        y(1) += dl;
        y(3) += dl * 6e6;
        const sim::Kinematics ke = m->eval(in, y);
        const sim::EarthTerms ee = sim::EarthTerms::exact(y(1));
        sim::EarthTerms ea;
        const sim::Kinematics ka = m->eval(in, y, a, ea);
        Vec3 we, fe, wa, fa;
        sim::imu_from_kinematics(ke, we, fe);
        sim::imu_from_kinematics(ka, ea, wa, fa);
        const double terms_e[6] = {ee.sin_lat, ee.cos_lat, ee.tan_lat, ee.r_m_m, ee.r_n_m, ee.sqrt_1_e2_s2};
        const double terms_a[6] = {ea.sin_lat, ea.cos_lat, ea.tan_lat, ea.r_m_m, ea.r_n_m, ea.sqrt_1_e2_s2};
        if (dp == 0.0 && dl == 0.0) {
          ASSERT_EQ(std::memcmp(terms_e, terms_a, sizeof terms_e), 0) << i;
          ASSERT_EQ(std::memcmp(ke.C_b_n.data(), ka.C_b_n.data(), 9 * sizeof(double)), 0) << i;
          ASSERT_EQ(std::memcmp(we.data(), wa.data(), 3 * sizeof(double)), 0) << i;
          ASSERT_EQ(std::memcmp(fe.data(), fa.data(), 3 * sizeof(double)), 0) << i;
        }
        // Each term in ulps of itself; the angles' sines and cosines in ulps of 1 (a component
        // near a zero of its sine is not itself known to its own ulps).
        for (int k = 0; k < 6; ++k) {
          const double scale = k < 2 ? 1.0 : std::abs(terms_e[k]);
          worst_ulps = std::max(worst_ulps, std::abs(terms_a[k] - terms_e[k]) / (scale * eps));
        }
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c)
            worst_ulps = std::max(worst_ulps, std::abs(ka.C_b_n(r, c) - ke.C_b_n(r, c)) / eps);
        worst_imu_ulps = std::max(worst_imu_ulps, (wa - we).norm() / (we.norm() * eps));
        worst_imu_ulps = std::max(worst_imu_ulps, (fa - fe).norm() / (fe.norm() * eps));
      }
  }
  std::printf("anchored evaluation against the exact one: terms worst %.2f ulp, rates and specific force %.2f ulp\n",
              worst_ulps, worst_imu_ulps);
  EXPECT_LT(worst_ulps, 8.0);
  EXPECT_LT(worst_imu_ulps, 16.0);
}

TEST(TruthGenerator, AgreesWithAnEightTimesFinerTruthThroughATurn) {
  // The default flight's first turn (roll-in at 60 s, bank, roll-out) at 1 kHz against the same
  // motion at 8 kHz: the states at the shared instants, and each 1 ms increment against the sum of
  // the eight fine ones (both are integrals of the same rates). What the generator's step and its
  // midpoint add must stay at round-off, far below any error the navigation reports.
  sim::Scenario sc;
  auto m = make(sc);
  ASSERT_TRUE(m);
  sim::TruthGenerator coarse(*m, 1000.0), fine(*m, 8000.0);
  const double R = 6.378e6;
  double max_pos_m = 0.0, max_att_rad = 0.0, max_dth_rad = 0.0, max_dv_mps = 0.0, max_vel_mps = 0.0;
  while (coarse.current().t_s < 130.0) {
    const sim::TruthSample& c = coarse.next();
    Vec3 dth = Vec3::Zero(), dv = Vec3::Zero();
    for (int i = 0; i < 8; ++i) {
      const sim::TruthSample& f = fine.next();
      dth += f.dtheta_rad;
      dv += f.dv_mps;
    }
    const sim::TruthSample& f = fine.current();
    ASSERT_NEAR(f.t_s, c.t_s, 1e-12);
    const Vec3 dllh = c.llh - f.llh;
    max_pos_m = std::max(max_pos_m, std::hypot(dllh.x() * R, dllh.y() * R * std::cos(c.llh.x()), dllh.z()));
    max_vel_mps = std::max(max_vel_mps, (c.vel_enu_mps - f.vel_enu_mps).norm());
    max_att_rad = std::max(max_att_rad, (c.C_b_n.transpose() * f.C_b_n - Mat3::Identity()).cwiseAbs().maxCoeff());
    max_dth_rad = std::max(max_dth_rad, (c.dtheta_rad - dth).norm());
    max_dv_mps = std::max(max_dv_mps, (c.dv_mps - dv).norm());
  }
  std::printf("1 kHz against 8 kHz truth over 130 s: position %.2e m, velocity %.2e m/s, attitude %.2e rad, "
              "dtheta %.2e rad, dv %.2e m/s\n", max_pos_m, max_vel_mps, max_att_rad, max_dth_rad, max_dv_mps);
  // Measured 7.0e-7 m, 4.1e-9 m/s, 1.6e-11 rad, 1.0e-12 rad, 6.1e-15 m/s (the 2 kHz RK4 this step
  // replaced: 9.8e-7, 5.1e-9, 2.0e-11, 1.0e-12, 5.3e-15). The increments' part comes from the
  // steps that hold a roll transition's start or end, where the rates' second derivative jumps.
  EXPECT_LT(max_pos_m, 2e-6);
  EXPECT_LT(max_vel_mps, 1e-8);
  EXPECT_LT(max_att_rad, 5e-11);
  EXPECT_LT(max_dth_rad, 3e-12);
  EXPECT_LT(max_dv_mps, 3e-14);
}

TEST(TruthGenerator, StationaryTableSensesEarthRateAndGravity) {
  const double L = 35.0 * kDeg;
  const Mat3 C0 = fsw::C_b_n_from_euler(10.0 * kDeg, -5.0 * kDeg, 30.0 * kDeg);
  const Vec3 llh(L, 127.0 * kDeg, 5000.0);
  sim::TableMotion table(llh, C0, Vec3(0, 0, 1), 0.0);
  sim::TruthGenerator gen(table, 1000.0);
  const Vec3 w_b = C0.transpose() * (kOmegaEarth * Vec3(0.0, std::cos(L), std::sin(L)));
  const Vec3 f_b = C0.transpose() * Vec3(0.0, 0.0, kG35at5000);  // reaction to gravity: Up
  for (int k = 0; k < 1000; ++k) {
    const sim::TruthSample& s = gen.next();
    ASSERT_NEAR((s.dtheta_rad - w_b * 1e-3).norm(), 0.0, 1e-20);
    ASSERT_NEAR((s.dv_mps - f_b * 1e-3).norm(), 0.0, 1e-12);  // gravity pinned to 1e-10 m/s^2
    ASSERT_NEAR((s.omega_ib_b_radps - w_b).norm(), 0.0, 1e-18);
    ASSERT_EQ(s.vel_enu_mps, Vec3::Zero());
    ASSERT_EQ(s.llh, llh);
    ASSERT_NEAR((s.C_b_n - C0).cwiseAbs().maxCoeff(), 0.0, 1e-15);
  }
  EXPECT_NEAR(gen.current().omega_ib_b_radps.norm(), 7.292115e-5, 1e-17);
  EXPECT_NEAR(gen.current().f_b_mps2.norm(), kG35at5000, 1e-9);
}

TEST(TruthGenerator, RotatingTableIntegratesRatePlusEarthRate) {
  // 10 deg/s about a skew body axis for exactly one revolution (36 s): the Earth-rate component
  // perpendicular to the axis averages out, so
  //   sum dtheta = axis * (rate T + (axis . C_n_b0 omega_ie_n) T),  sum dv = axis * (axis . C_n_b0 g_up) T.
  const double L = 35.0 * kDeg, rate = 10.0 * kDeg, T = 36.0;
  const Mat3 C0 = fsw::C_b_n_from_euler(10.0 * kDeg, -5.0 * kDeg, 30.0 * kDeg);
  const Vec3 axis = Vec3(1.0, 2.0, -2.0) / 3.0;
  sim::TableMotion table(Vec3(L, 127.0 * kDeg, 5000.0), C0, Vec3(1.0, 2.0, -2.0), rate);
  sim::TruthGenerator gen(table, 1000.0);
  Vec3 sum_th = Vec3::Zero(), sum_dv = Vec3::Zero();
  const long n = 36000;
  for (long k = 0; k < n; ++k) {
    const sim::TruthSample& s = gen.next();
    sum_th += s.dtheta_rad;
    sum_dv += s.dv_mps;
  }
  EXPECT_NEAR(gen.current().t_s, T, 1e-9);
  const Vec3 w_ie_b0 = C0.transpose() * (kOmegaEarth * Vec3(0.0, std::cos(L), std::sin(L)));
  const Vec3 g_b0 = C0.transpose() * Vec3(0.0, 0.0, kG35at5000);
  const Vec3 want_th = axis * (rate * T + axis.dot(w_ie_b0) * T);
  const Vec3 want_dv = axis * axis.dot(g_b0) * T;
  std::printf("rotating table: |sum dtheta - expected| %.2e rad (Earth-rate part %.3e rad), |sum dv - expected| "
              "%.2e m/s\n", (sum_th - want_th).norm(), axis.dot(w_ie_b0) * T, (sum_dv - want_dv).norm());
  EXPECT_LT((sum_th - want_th).norm(), 1e-10);
  EXPECT_GT(std::abs(axis.dot(w_ie_b0) * T), 1e-4);  // the Earth-rate part is far above the tolerance
  EXPECT_LT((sum_dv - want_dv).norm(), 1e-8);
  // After one revolution the table is back at its initial attitude.
  EXPECT_NEAR((gen.current().C_b_n - C0).cwiseAbs().maxCoeff(), 0.0, 1e-12);
  // The instantaneous body rate relative to n is the table rate about the axis.
  EXPECT_NEAR((gen.current().omega_nb_b_radps - axis * rate).norm(), 0.0, 1e-15);
}

TEST(TruthGenerator, TruthPlusImuModelIsBitIdenticalPerSeed) {
  sim::Scenario sc;
  sc.duration_s = 60.0;
  sc.segments = {sim::Segment{.type = sim::SegmentType::kStraight, .duration_s = 10.0},
                 sim::Segment{.type = sim::SegmentType::kTurn, .direction = sim::TurnDirection::kRight,
                              .bank_deg = 45.0, .heading_change_deg = 90.0, .roll_time_s = 4.0}};
  sc.repeat_from = std::nullopt;
  sc.imu.errors = sim::ImuErrorSet::kPaper;
  sc.imu.sigmas.gyro_arw_deg_per_rthr = 0.05;
  sc.imu.sigmas.accel_vrw_ug_per_rthz = 30.0;
  sc.imu.sigmas.gyro_bias_instability_degph = 0.003;
  sc.imu.sigmas.accel_bias_instability_ug = 10.0;
  sc.effects.set(fsw::Effect::kGyroGSensitivity, 1, 0.5);
  auto run = [&](std::uint64_t seed) {
    auto m = make(sc);
    sim::TruthGenerator gen(*m, 1000.0);
    sim::ImuModel imu(sim::draw_imu_errors(sc.imu, sc.effects, seed), seed);
    Fnv1a h;
    while (gen.current().t_s < sc.duration_s) {
      const sim::TruthSample& t = gen.next();
      const fsw::ImuSample s = imu.measure(t);
      h.add(s.t_s);
      h.add(s.dt_s);
      h.add(s.dtheta_rad);
      h.add(s.dv_mps);
      h.add(t.llh);
      h.add(t.vel_enu_mps);
    }
    return h.h;
  };
  const std::uint64_t a = run(7), b = run(7), c = run(8);
  std::printf("60 s truth + IMU hash: seed 7 %016llx, again %016llx, seed 8 %016llx\n",
              static_cast<unsigned long long>(a), static_cast<unsigned long long>(b),
              static_cast<unsigned long long>(c));
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}

namespace {

// The manoeuvres that separate confounded effects (scenario.hpp, Segment): a speed change, a climb
// (pull-up, hold, push-over), a roll without turning. Their kinematics are what they say (speed,
// flight-path angle and climb, heading held through the roll, bank reached), and the ideal IMU
// increments the generator makes from them are consistent with the truth trajectory: the fsw
// mechanization flown free-inertial on them (perfect IMU, truth start, the vertical channel left
// free over 200 s) stays on it to the level of the straight-and-level default flight.
TEST(FlightMotion, SpeedChangeClimbAndRollWithoutTurning) {
  sim::Scenario sc;
  sc.duration_s = 200.0;
  sc.repeat_from.reset();
  sim::Segment straight{.type = sim::SegmentType::kStraight, .duration_s = 20.0};
  sim::Segment speed{.type = sim::SegmentType::kSpeedChange, .duration_s = 20.0, .delta_speed_mps = 50.0};
  sim::Segment climb{.type = sim::SegmentType::kClimb, .duration_s = 20.0, .flight_path_deg = 10.0, .transition_s = 10.0};
  sim::Segment roll{.type = sim::SegmentType::kRoll, .duration_s = 5.0, .direction = sim::TurnDirection::kLeft,
                    .bank_deg = 30.0, .roll_time_s = 3.0};
  sc.segments = {straight, speed, straight, climb, straight, roll, straight};
  auto m = make(sc);
  ASSERT_TRUE(m);
  sim::TruthGenerator gen(*m, 1000.0);
  const double V0 = sc.start.speed_mps;
  double h_climb0 = 0.0, psi_roll0 = 0.0, max_bank = 0.0, max_vz = 0.0, max_pitch_rate = 0.0;
  const auto heading = [](const sim::TruthSample& s) { return std::atan2(s.C_b_n(0, 0), s.C_b_n(1, 0)); };
  while (gen.current().t_s < 160.0 - 1e-9) {
    const sim::TruthSample& s = gen.next();
    const double t = s.t_s;
    if (std::abs(t - 19.0) < 5e-4) EXPECT_NEAR(s.vel_enu_mps.norm(), V0, 1e-6);
    if (std::abs(t - 41.0) < 5e-4) EXPECT_NEAR(s.vel_enu_mps.norm(), V0 + 50.0, 1e-6);
    if (std::abs(t - 60.0) < 5e-4) h_climb0 = s.llh.z();
    // climb: 60 s pull-up 10 s, hold 20 s at 10 deg, push-over 10 s: ends 100 s.
    if (t > 70.0 && t < 90.0) EXPECT_NEAR(s.vel_enu_mps.z(), (V0 + 50.0) * std::sin(10.0 * kDeg), 1e-6);
    max_vz = std::max(max_vz, s.vel_enu_mps.z());
    max_pitch_rate = std::max(max_pitch_rate, std::abs(s.omega_nb_b_radps.y()));
    if (std::abs(t - 100.0) < 5e-4) {
      EXPECT_NEAR(s.vel_enu_mps.z(), 0.0, 1e-9);
      // Gained: the hold (20 s) plus the two transitions (each half of their 10 s at full rate).
      EXPECT_NEAR(s.llh.z() - h_climb0, (V0 + 50.0) * std::sin(10.0 * kDeg) * 30.0, 0.05 * 300.0 * 0.1736 * 30.0);
    }
    // roll: 120 s, 3 s in, 5 s hold at -30 deg (left), 3 s out: ends 131 s; heading held.
    if (std::abs(t - 120.0) < 5e-4) psi_roll0 = heading(s);
    if (t > 120.0 && t < 135.0) {
      EXPECT_NEAR(heading(s), psi_roll0, 1e-9);
      const double bank = std::atan2(-s.C_b_n(2, 1), -s.C_b_n(2, 2));
      max_bank = std::max(max_bank, -bank);
    }
    EXPECT_FALSE(s.phase.turning);
  }
  EXPECT_NEAR(max_bank, 30.0 * kDeg, 1e-9);
  EXPECT_GT(max_vz, 50.0);
  EXPECT_GT(max_pitch_rate, 0.01);  // pull-up and push-over pitch the body

  expect_free_inertial_on_truth(*m, "manoeuvres");
}

// A crab (the nose off the track, wings level, the velocity unchanged: the heading a crosswind
// needs) moves only the attitude: the velocity keeps its direction and size, the body heading
// reaches track + crab and comes back, the body x axis leaves the velocity by the crab angle, and
// the ideal IMU made from it flies free-inertial on the truth like the other segments.
TEST(FlightMotion, CrabTurnsTheNoseOffTheTrackWithTheVelocityUnchanged) {
  sim::Scenario sc;
  sc.duration_s = 200.0;
  sc.repeat_from.reset();
  sc.start.heading_deg = 30.0;
  sim::Segment straight{.type = sim::SegmentType::kStraight, .duration_s = 20.0};
  sim::Segment right{.type = sim::SegmentType::kCrab, .duration_s = 30.0, .direction = sim::TurnDirection::kRight,
                     .transition_s = 10.0, .crab_deg = 15.0};
  sim::Segment left = right;
  left.direction = sim::TurnDirection::kLeft;
  left.duration_s = 0.0;  // in and out at once
  sc.segments = {straight, right, straight, left, straight};
  auto m = make(sc);
  ASSERT_TRUE(m);
  sim::TruthGenerator gen(*m, 1000.0);
  const double V0 = sc.start.speed_mps;
  const Vec3 v0 = gen.current().vel_enu_mps;
  const Vec3 f_n0 = gen.current().C_b_n * gen.current().f_b_mps2;
  const auto heading = [](const sim::TruthSample& s) { return std::atan2(s.C_b_n(0, 0), s.C_b_n(1, 0)); };
  double max_crab = 0.0, min_crab = 0.0, max_yaw_rate = 0.0, max_lat_f = 0.0;
  while (gen.current().t_s < 140.0 - 1e-9) {
    const sim::TruthSample& s = gen.next();
    const double t = s.t_s;
    // The velocity: the start's, to the solver's precision (no turn, no speed change, no climb).
    EXPECT_NEAR((s.vel_enu_mps - v0).norm(), 0.0, 1e-6) << t;
    // Angle of body x from the velocity, + nose right of the track.
    const Vec3 x_n = s.C_b_n.col(0);
    const double crab = std::atan2(x_n.x() * v0.y() - x_n.y() * v0.x(), x_n.head<2>().dot(v0.head<2>()));
    max_crab = std::max(max_crab, crab);
    min_crab = std::min(min_crab, crab);
    // right: 20 s in 10 s, hold 30 s (30..60), out 10 s: ends 70 s; left: 90 s in 10, out 10: 110 s.
    if (t > 30.0 && t < 60.0) EXPECT_NEAR(crab, 15.0 * kDeg, 1e-9) << t;
    if (t < 20.0 || (t > 70.0 && t < 90.0) || t > 110.0) EXPECT_NEAR(crab, 0.0, 1e-9) << t;
    EXPECT_NEAR(heading(s), 30.0 * kDeg + crab, 1e-9);
    EXPECT_NEAR(s.vel_enu_mps.norm(), V0, 1e-6);
    max_yaw_rate = std::max(max_yaw_rate, std::abs(s.omega_nb_b_radps.z()));
    max_lat_f = std::max(max_lat_f, (s.C_b_n * s.f_b_mps2 - f_n0).norm());
    EXPECT_FALSE(s.phase.turning);
  }
  EXPECT_NEAR(max_crab, 15.0 * kDeg, 1e-9);
  EXPECT_NEAR(min_crab, -15.0 * kDeg, 1e-9);
  // smooth_step: peak rate twice the mean, 2 x 15 deg / 10 s.
  EXPECT_NEAR(max_yaw_rate, 2.0 * 15.0 * kDeg / 10.0, 1e-4);
  // The specific force in the navigation frame stays that of the straight flight (no side force: the
  // velocity does not turn; what changes is gravity and the transport rate along 35 km).
  EXPECT_LT(max_lat_f, 1e-3);

  expect_free_inertial_on_truth(*m, "crab");
}

TEST(FlightMotion, SpeedChangeBelowTheMinimumIsRejected) {
  sim::Scenario sc;
  sc.segments = {sim::Segment{.type = sim::SegmentType::kSpeedChange, .duration_s = 10.0, .delta_speed_mps = -240.0}};
  std::string err;
  EXPECT_EQ(sim::FlightMotion::create(sc, err), nullptr);
  EXPECT_NE(err.find("leaves less than"), std::string::npos) << err;
}

}  // namespace
