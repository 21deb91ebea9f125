// The EKF's dead states (Ekf::live_states): sensor and extension states started with zero
// variance and driven by no noise keep rows and columns of P at exactly +0, so the update, the
// symmetrisation and the definiteness check leave them out. The filter must give the same bits as
// with the dense loops (set_dense_covariance_loops) on a flight that exercises every path: the
// transition through a turn, raw GNSS updates with channels bound and released, the feedback, a
// covariance repair, and a dead state brought back to life by a new covariance. The transition
// leaves the dead states' columns out (EkfTransition::set_dead_states) with the same bits, and an
// executive configured again forms the columns of its new filter.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "fsw/ekf.hpp"
#include "fsw/executive.hpp"
#include "fsw/gnss.hpp"
#include "fsw/strapdown.hpp"
#include "sim/scenario.hpp"
#include "sim/trajectory.hpp"

namespace {

using fsw::Block;
using fsw::LayoutDiag;
using fsw::Vec3;
using Ekf = fsw::Ekf<LayoutDiag>;
constexpr int N = LayoutDiag::kSize;

bool same_bits(const Ekf& a, const Ekf& b) {
  return std::memcmp(a.P().data(), b.P().data(), sizeof(double) * N * N) == 0 &&
         std::memcmp(a.x().data(), b.x().data(), sizeof(double) * N) == 0 &&
         a.health().cov_checks == b.health().cov_checks && a.health().cov_repairs == b.health().cov_repairs;
}

/// Seven satellites at fixed ENU directions, 22,000 km from the true position at t; PRNs change
/// every 20 s (one satellite set, then another that shares four of them), so channels are bound
/// and released; ranges carry a 100 m clock drifting 0.5 m/s and a few metres of fixed errors.
fsw::GnssEpoch epoch_at(const sim::TruthSample& t) {
  fsw::GnssEpoch ep;
  ep.t_s = t.t_s;
  ep.n_obs = 7;
  const double az[7] = {0.3, 1.2, 2.1, 3.0, 3.9, 4.8, 5.7}, el[7] = {0.3, 0.9, 0.6, 1.2, 0.45, 0.75, 1.0};
  const int set = static_cast<int>(t.t_s / 20.0) % 2;
  const fsw::Mat3 Cne = fsw::C_n_e(t.llh.x(), t.llh.y());
  const Vec3 r = fsw::ecef_from_llh(t.llh), v = Cne * t.vel_enu_mps;
  for (int k = 0; k < 7; ++k) {
    const Vec3 u_n(std::cos(el[k]) * std::sin(az[k]), std::cos(el[k]) * std::cos(az[k]), std::sin(el[k]));
    fsw::GnssObservation& o = ep.obs[static_cast<std::size_t>(k)];
    o.prn = static_cast<std::uint8_t>(k < 4 || set == 0 ? k + 1 : k + 11);
    o.sat_pos_ecef_m = r + Cne * u_n * 2.2e7;
    o.sat_vel_ecef_mps = Vec3(800.0 * k, -500.0, 2000.0 - 300.0 * k);
    const fsw::GnssGeometry g = fsw::gnss_geometry(o.sat_pos_ecef_m, o.sat_vel_ecef_mps, r, v);
    o.pseudorange_m = g.range_m + 100.0 + 0.5 * t.t_s + 2.0 * std::sin(3.0 * k + t.t_s);
    o.pseudorange_rate_mps = g.range_rate_mps + 0.5 + 0.05 * std::cos(2.0 * k + t.t_s);
  }
  return ep;
}

struct Frame {
  fsw::FrameIncrement inc;
  fsw::NavState nav;
  sim::TruthSample truth;  ///< at the frame's end
};

/// The raw IMU samples of the default flight from t0 to t1, with a gyro bias the filter can see,
/// and the truth at t0 and at each sample (truth[k + 1] is imu[k]'s).
void samples_of(double t0, double t1, std::vector<fsw::ImuSample>& imu, std::vector<sim::TruthSample>& truth) {
  sim::Scenario sc;
  sc.duration_s = t1 + 1.0;
  std::string err;
  auto motion = sim::FlightMotion::create(sc, err);
  if (!motion) return;
  sim::TruthGenerator gen(*motion, 1000.0);
  while (gen.current().t_s < t0 - 1e-9) gen.next();
  truth.push_back(gen.current());
  while (gen.current().t_s < t1 - 1e-9) {
    const sim::TruthSample& t = gen.next();
    fsw::ImuSample s;
    s.t_s = t.t_s;
    s.dt_s = t.dt_s;
    s.dtheta_rad = t.dtheta_rad + Vec3(2e-9, -1e-9, 3e-9);
    s.dv_mps = t.dv_mps;
    imu.push_back(s);
    truth.push_back(t);
  }
}

/// The INS's start: the truth a few metres and decimetres per second off.
fsw::NavState initial_nav(const sim::TruthSample& t) {
  fsw::NavState nav0;
  nav0.t_s = t.t_s;
  nav0.llh = t.llh + fsw::llh_delta_from_enu(t.llh, Vec3(3.0, -2.0, 1.0));
  nav0.vel_enu_mps = t.vel_enu_mps + Vec3(0.1, 0.05, -0.02);
  nav0.q_b_n = fsw::Quat(t.C_b_n);
  return nav0;
}

/// The navigation frames (increments, the INS solution and the truth at their end) of the default
/// flight from t0 to t1, mechanized from initial_nav() over samples_of().
std::vector<Frame> frames_of(double t0, double t1) {
  std::vector<fsw::ImuSample> imu;
  std::vector<sim::TruthSample> truth;
  samples_of(t0, t1, imu, truth);
  std::vector<Frame> out;
  if (truth.empty()) return out;
  fsw::Strapdown ins;
  ins.init(initial_nav(truth.front()));
  fsw::FrameBuilder fb;
  fb.configure(5);
  for (std::size_t k = 0; k < imu.size(); ++k) {
    if (fb.add(imu[k]) != fsw::Status::kOk) continue;
    ins.step(fb.frame());
    out.push_back({fb.frame(), ins.state(), truth[k + 1]});
  }
  return out;
}

/// Flies a and b side by side over truth from t0 to t1 (1 Hz updates, corrections taken); false
/// at the first epoch whose filters differ in a bit.
bool fly_side_by_side(Ekf& a, Ekf& b, double t0, double t1, int& epochs) {
  const std::vector<Frame> frames = frames_of(t0, t1);
  if (frames.empty()) return false;
  int n = 0;
  for (const Frame& f : frames) {
    a.accumulate(f.inc, f.nav);
    b.accumulate(f.inc, f.nav);
    if (++n % 200 != 0) continue;
    a.propagate();
    b.propagate();
    const fsw::GnssEpoch ep = epoch_at(f.truth);
    fsw::EkfUpdateReport ra, rb;
    a.update(ep, f.nav, f.truth.omega_ib_b_radps, ra);
    b.update(ep, f.nav, f.truth.omega_ib_b_radps, rb);
    Ekf::Vec xa, xb;
    a.take_correction(xa);
    b.take_correction(xb);
    ++epochs;
    if (!same_bits(a, b)) return false;
  }
  return true;
}

/// Ticks exec over the samples (five a frame, an epoch_at() at every whole second) and returns
/// the filter's P and x after each landed epoch, one after the other.
std::vector<double> fly_executive(fsw::Executive<LayoutDiag>& exec, const std::vector<fsw::ImuSample>& imu,
                                  const std::vector<sim::TruthSample>& truth) {
  std::vector<double> trace;
  fsw::FrameOutput out;
  fsw::GnssEpoch ep;
  for (std::size_t k = 0; k + 5 <= imu.size(); k += 5) {
    fsw::FrameInput in;
    in.imu = &imu[k];
    in.n_imu = 5;
    const sim::TruthSample& t = truth[k + 5];
    if (std::abs(t.t_s - std::round(t.t_s)) < 1e-6) {
      ep = epoch_at(t);
      in.gnss = &ep;
    }
    if (exec.tick(in, out) != fsw::Status::kOk) return {};
    if (!out.ekf_ran) continue;
    trace.insert(trace.end(), exec.ekf().P().data(), exec.ekf().P().data() + N * N);
    trace.insert(trace.end(), exec.ekf().x().data(), exec.ekf().x().data() + N);
  }
  return trace;
}

bool same_column(const fsw::EkfTransition<LayoutDiag>& a, const fsw::EkfTransition<LayoutDiag>& b, int c) {
  return std::memcmp(a.phi_nav().col(c).data(), b.phi_nav().col(c).data(), sizeof(double) * 9) == 0;
}

}  // namespace

// The transition forms only the live states' columns of the navigation rows: each one the same
// bits as with every column formed, the dead ones exactly zero. A state brought back to life in the
// middle of an interval enters at the sub-step in progress: its column is the one of an interval
// that starts at that sub-step.
TEST(EkfDeadStates, TheTransitionFormsTheLiveColumnsWithTheSameBits) {
  const std::vector<Frame> frames = frames_of(60.0, 61.05);  // a turn: every sensor column driven
  ASSERT_GE(frames.size(), 200u);
  std::array<bool, N> dead{};
  const int ogm = LayoutDiag::offset(Block::kGyroMisalign), oas = LayoutDiag::offset(Block::kAccelScale);
  const int ogs = LayoutDiag::offset(Block::kGyroGSens);
  for (int i : {ogm + 1, ogm + 4, oas + 2, ogs, ogs + 1, ogs + 2, LayoutDiag::offset(Block::kIonoScale)})
    dead[static_cast<std::size_t>(i)] = true;
  constexpr int K = fsw::EkfTransition<LayoutDiag>::kNavCols;
  static fsw::EkfTransition<LayoutDiag> every, live, revived, late;
  live.set_dead_states(dead);
  revived.set_dead_states(dead);
  for (auto* t : {&every, &live, &revived, &late}) t->reset(10);
  for (int f = 0; f < 200; ++f) {
    const Frame& fr = frames[static_cast<std::size_t>(f)];
    if (f == 25) revived.set_dead_states({});  // in the third sub-step (frames 20-29)
    if (f >= 20) ASSERT_EQ(late.accumulate(fr.inc, fr.nav), fsw::Status::kOk);
    for (auto* t : {&every, &live, &revived}) ASSERT_EQ(t->accumulate(fr.inc, fr.nav), fsw::Status::kOk);
  }
  for (auto* t : {&every, &live, &revived, &late}) t->flush();
  int formed = 0;
  for (int c = 0; c < K; ++c) {
    ASSERT_TRUE(every.phi_nav().col(c).cwiseAbs().maxCoeff() > 0.0) << "column " << c << " is not driven";
    if (!dead[static_cast<std::size_t>(c)]) {
      EXPECT_TRUE(same_column(live, every, c)) << "column " << c;
      EXPECT_TRUE(same_column(revived, every, c)) << "column " << c;
      ++formed;
      continue;
    }
    for (int r = 0; r < 9; ++r) {
      EXPECT_EQ(live.phi_nav()(r, c), 0.0);
      EXPECT_FALSE(std::signbit(live.phi_nav()(r, c)));
    }
    EXPECT_TRUE(same_column(revived, late, c)) << "column " << c;
    EXPECT_FALSE(same_column(revived, every, c)) << "column " << c;
  }
  EXPECT_EQ(formed, K - 6);
  EXPECT_EQ(live.interval_s(), every.interval_s());
}

// An executive configured again with a filter that has fewer dead states forms the columns its
// new filter needs from the first frame: it flies the bits of a new executive.
TEST(EkfDeadStates, AnExecutiveConfiguredAgainFormsTheColumnsOfItsNewFilter) {
  std::vector<fsw::ImuSample> imu;
  std::vector<sim::TruthSample> truth;
  samples_of(60.0, 66.0, imu, truth);
  ASSERT_EQ(imu.size(), 6000u);
  fsw::ExecutiveConfig frozen, live;
  frozen.ekf.lever_arm_sigma_m = live.ekf.lever_arm_sigma_m = 0.5;
  frozen.ekf.time_offset_sigma_s = live.ekf.time_offset_sigma_s = 0.01;
  const int ogm = LayoutDiag::offset(Block::kGyroMisalign), oas = LayoutDiag::offset(Block::kAccelScale);
  frozen.ekf.frozen_states = (std::uint64_t{1} << (ogm + 1)) | (std::uint64_t{1} << (ogm + 4)) | (std::uint64_t{1} << (oas + 2));
  const fsw::NavState nav0 = initial_nav(truth.front());
  static fsw::Executive<LayoutDiag> again, fresh;  // 66-state filters: not on the test's stack
  ASSERT_EQ(again.init(frozen, nav0), fsw::Status::kOk);
  ASSERT_EQ(fly_executive(again, imu, truth).size(), 5u * (N * N + N));  // its transitions skip three columns
  ASSERT_EQ(again.ekf().live_states(), N - 9);
  ASSERT_EQ(again.init(live, nav0), fsw::Status::kOk);
  ASSERT_EQ(fresh.init(live, nav0), fsw::Status::kOk);
  EXPECT_EQ(again.ekf().live_states(), N - 6);
  const std::vector<double> a = fly_executive(again, imu, truth), f = fly_executive(fresh, imu, truth);
  ASSERT_EQ(a.size(), 5u * (N * N + N));
  ASSERT_EQ(a.size(), f.size());
  EXPECT_EQ(std::memcmp(a.data(), f.data(), sizeof(double) * a.size()), 0);
}

TEST(EkfDeadStates, SkippingThemGivesTheDenseLoopsBitsInATurningFlight) {
  fsw::EkfConfig cfg;
  cfg.lever_arm_sigma_m = 0.5;
  cfg.time_offset_sigma_s = 0.01;
  const int ogm = LayoutDiag::offset(Block::kGyroMisalign), oas = LayoutDiag::offset(Block::kAccelScale);
  cfg.frozen_states = (std::uint64_t{1} << (ogm + 1)) | (std::uint64_t{1} << (ogm + 4)) | (std::uint64_t{1} << (oas + 2));
  static Ekf a, b;  // 66 x 66 matrices: not on the test's stack
  ASSERT_EQ(a.init(cfg), fsw::Status::kOk);
  ASSERT_EQ(b.init(cfg), fsw::Status::kOk);
  b.set_dense_covariance_loops(true);
  // Dead: g-sensitivity (3), time drift, tropo and iono scales (block sigma 0) and the three
  // frozen components; the frozen misalignments are driven by the turn's specific force and rate
  // through Phi's navigation rows, which must not bring them to life.
  EXPECT_EQ(a.live_states(), N - 9);
  EXPECT_EQ(b.live_states(), N);

  int epochs = 0;
  ASSERT_TRUE(fly_side_by_side(a, b, 60.0, 140.0, epochs)) << "first difference after " << epochs << " epochs";
  ASSERT_EQ(epochs, 80);
  EXPECT_GT(a.health().cov_checks, 70u);
  // The dead rows and columns are +0, not merely zero.
  for (int i : {ogm + 1, ogm + 4, oas + 2, LayoutDiag::offset(Block::kIonoScale)})
    for (int k = 0; k < N; ++k) {
      ASSERT_EQ(a.P()(i, k), 0.0);
      ASSERT_FALSE(std::signbit(a.P()(i, k)));
      ASSERT_FALSE(std::signbit(a.P()(k, i)));
    }
  // The live ones learned something (the filter ran): the lever arm's variance dropped.
  EXPECT_LT(a.P()(LayoutDiag::offset(Block::kLeverArm), LayoutDiag::offset(Block::kLeverArm)), 0.25);

  // A covariance with a variance on a dead state (the iono scale) and a correlation of 1.5
  // between position and attitude: the iono scale lives again, the repair is the dense one's.
  Ekf::Mat P = a.P();
  const int oi = LayoutDiag::offset(Block::kIonoScale);
  P(oi, oi) = 0.04;
  const double s0 = std::sqrt(P(0, 0)), s6 = std::sqrt(P(6, 6));
  P(0, 6) = P(6, 0) = 1.5 * s0 * s6;
  ASSERT_EQ(a.set_covariance(P), fsw::Status::kOk);
  ASSERT_EQ(b.set_covariance(P), fsw::Status::kOk);
  EXPECT_EQ(a.live_states(), N - 8);
  EXPECT_EQ(a.health().cov_repairs, 1u);
  ASSERT_TRUE(same_bits(a, b));
  ASSERT_TRUE(fly_side_by_side(a, b, 140.0, 170.0, epochs)) << "first difference after " << epochs << " epochs";
  EXPECT_LT(a.P()(oi, oi), 0.04);  // the range rows see the iono scale: it is estimated again
}
