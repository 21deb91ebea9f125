// Truth kinematics and the ideal IMU output.
//
// A Motion describes a trajectory as a small ODE state y (integrated here with RK4) plus
// closed-form functions of (t, y) for everything else: position, ENU velocity and its time
// derivative, attitude and the body rate relative to the navigation frame. The TruthGenerator
// turns any Motion into mutually consistent truth samples at the IMU rate (1 kHz by default):
//   omega_ib_b = omega_nb_b + C_n_b (omega_ie_n + omega_en_n)
//   f_b        = C_n_b (dv/dt + (2 omega_ie_n + omega_en_n) x v - g_n)
// and the ideal incremental outputs delta-theta = int omega_ib_b dt, delta-v = int f_b dt over
// each sample interval (Simpson's rule on the half-step RK4 grid), which is exactly what an
// error-free integrating gyro and accelerometer triad would deliver.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "fsw/frames.hpp"
#include "sim/scenario.hpp"

namespace sim {

using fsw::Mat3;
using fsw::Quat;
using fsw::Vec3;

/// Continuous truth at one instant.
struct Kinematics {
  Vec3 llh = Vec3::Zero();               ///< lat [rad], lon [rad], h [m]
  Vec3 vel_enu_mps = Vec3::Zero();       ///< ENU velocity
  Vec3 acc_enu_mps2 = Vec3::Zero();      ///< time derivative of the ENU velocity components
  Mat3 C_b_n = Mat3::Identity();
  Vec3 omega_nb_b_radps = Vec3::Zero();  ///< body rate relative to the navigation frame
};

/// What the trajectory is doing at an instant (for plots and per-turn analysis).
struct MotionPhase {
  int segment = -1;   ///< index into the scenario's segment list, -1 outside any segment
  int turn = -1;      ///< running number of the turn being flown (0, 1, ...), -1 when not turning
  bool turning = false;
};

/// The latitude's Earth-model terms imu_from_kinematics takes (its sine, cosine and tangent, the
/// radii of curvature, and gravity's sqrt(1 - e2 sin^2)): exact() from libm, or carried from a
/// step's start by Motion::eval(in, y, a, earth).
struct EarthTerms {
  double sin_lat = 0.0, cos_lat = 1.0, tan_lat = 0.0;
  double r_m_m = 0.0, r_n_m = 0.0;
  double sqrt_1_e2_s2 = 1.0;
  static EarthTerms exact(double lat_rad);
};

class Motion {
 public:
  static constexpr int kMaxStates = 6;
  using State = Eigen::Matrix<double, kMaxStates, 1>;

  /// What derivative() and eval() need of the time alone (a motion's own values: the flight's
  /// roll, speed and flight path at t), computed once per instant: the TruthGenerator asks for
  /// six evaluations per sample (four derivatives, two kinematics) at three instants, the first
  /// of them the previous sample's last. Default: just the time.
  struct Instant {
    double t_s = 0.0;
    double v[12] = {};
  };
  virtual ~Motion() = default;
  virtual State initial_state() const = 0;
  virtual State derivative(double t_s, const State& y) const = 0;
  virtual Kinematics eval(double t_s, const State& y) const = 0;
  virtual MotionPhase phase(double /*t_s*/) const { return {}; }
  /// The instant t's time-only terms; derivative(in, y) and eval(in, y) give exactly what
  /// derivative(t, y) and eval(t, y) give.
  virtual void instant(double t_s, Instant& in) const { in.t_s = t_s; }
  virtual State derivative(const Instant& in, const State& y) const { return derivative(in.t_s, y); }
  virtual Kinematics eval(const Instant& in, const State& y) const { return eval(in.t_s, y); }

  /// What derivative() needs of a state that changes little within one integration step (the
  /// flight's track and latitude sines and cosines, its radii of curvature), taken exactly at the
  /// step's first state y0 by anchor(); derivative(in, y, a) carries them to the step's other
  /// states by their Taylor series, whose remainders lie below the doubles' rounding for the
  /// changes one 1 ms step makes. At y0 itself it gives derivative(in, y0) bit for bit. Default:
  /// no anchor, derivative(in, y).
  struct StepAnchor {
    double v[13] = {};
  };
  virtual void anchor(const State& /*y0*/, StepAnchor& /*a*/) const {}
  virtual State derivative(const Instant& in, const State& y, const StepAnchor& /*a*/) const {
    return derivative(in, y);
  }
  /// eval(in, y) and the Earth terms at y's latitude, for a state y within the step anchored by a
  /// (the truth's midpoint and end of a step), carried from the anchor like derivative(in, y, a):
  /// at y0 itself, eval(in, y0) and EarthTerms::exact bit for bit. Default: those two.
  virtual Kinematics eval(const Instant& in, const State& y, const StepAnchor& /*a*/, EarthTerms& earth) const {
    Kinematics k = eval(in, y);
    earth = EarthTerms::exact(k.llh.x());
    return k;
  }
};

/// One truth sample: the state at t_s and the ideal IMU increments over (t_s - dt_s, t_s].
struct TruthSample {
  double t_s = 0.0;
  double dt_s = 0.0;
  Vec3 llh = Vec3::Zero();
  Vec3 vel_enu_mps = Vec3::Zero();
  Mat3 C_b_n = Mat3::Identity();
  Vec3 omega_ib_b_radps = Vec3::Zero();  ///< instantaneous at t_s
  Vec3 omega_nb_b_radps = Vec3::Zero();  ///< instantaneous at t_s
  Vec3 f_b_mps2 = Vec3::Zero();          ///< instantaneous at t_s
  Vec3 dtheta_rad = Vec3::Zero();        ///< ideal gyro increment over the last interval
  Vec3 dv_mps = Vec3::Zero();            ///< ideal accelerometer increment over the last interval
  MotionPhase phase{};
};

/// Steps a Motion at a fixed rate, producing truth samples. Deterministic.
///
/// A sample is two halves: integrate() advances the motion's ODE by one RK4 step (sequential: each
/// step starts from the last) and hands its midpoint and end states on in a Step; complete() turns
/// a Step into the sample (the kinematics, rates and specific force at the midpoint and the end,
/// carried from the step's anchor, and the Simpson increments). next() is the two in turn, sharing
/// the step's anchor and instants; TruthPipeline (truth_pipeline.hpp) runs them on two threads,
/// where complete() takes the anchor and instants again from the step's start (the same pure
/// functions of the same bits, so the same sample) instead of receiving them: a Step is two cache
/// lines, where the anchor and instants would add five more to move between the cores. The halves
/// touch disjoint members, so one thread may integrate while another completes, each in step order.
class TruthGenerator {
 public:
  /// What complete() needs of an integration step over (t0, t1]: its midpoint and end states.
  struct Step {
    Motion::State y_mid = Motion::State::Zero();
    Motion::State y1 = Motion::State::Zero();
  };

  TruthGenerator(const Motion& motion, double rate_hz);
  /// The sample at t = 0 (no increments), then the last one made.
  const TruthSample& current() const { return cur_; }
  /// Advances one sample interval and returns the new sample.
  const TruthSample& next();
  /// The first half: the next RK4 step into s.
  void integrate(Step& s);
  /// The second half: the sample of s, which must be the step after the last one completed.
  const TruthSample& complete(const Step& s);

 private:
  struct Point {
    Kinematics k;
    Vec3 omega_ib_b;
    Vec3 f_b;
  };
  /// The motion's Instants of the last two times asked for (an RK4 step asks for its middle three
  /// times, and a step's end is the next step's start).
  struct Instants {
    Motion::Instant inst[2]{};
    bool valid[2] = {false, false};
    int next = 0;  ///< the slot the next new instant goes into
    const Motion::Instant& of(const Motion& m, double t);
  };
  /// One side's own count and state: the step index, the state the step starts from, its anchor.
  struct Side {
    long long index = 0;
    Motion::State y0 = Motion::State::Zero();
    Motion::StepAnchor anchor{};
    Instants instants;
    double t0 = 0.0, tm = 0.0, t1 = 0.0;
    /// The step's times from the integer index (no drift by accumulation) and its anchor at y0.
    void start(const Motion& m, double dt_s);
  };
  /// The point at (in, y): exactly (a == nullptr), or with the terms carried from the step's anchor.
  Point evaluate(const Motion::Instant& in, const Motion::State& y, const Motion::StepAnchor* a) const;
  /// complete()'s work given the step's side (its times, anchor and instants).
  const TruthSample& complete(const Step& s, Side& side);
  void set_current(double t, double dt, const Point& p);

  // Read by both halves; each half's own members on cache lines of their own from here on (the
  // halves may run on two threads, and a line one writes and the other reads moves between the
  // cores at every write: 0.15 us a sample, when motion_ shared a line with integ_).
  const Motion& motion_;
  double dt_s_;
  alignas(64) Side integ_;  ///< integrate()'s (and next()'s)
  Step step_{};             ///< next()'s
  alignas(64) Side compl_;  ///< complete()'s, with the sample below
  TruthSample cur_{};
  Point p_cur_{};
};

/// Specific force and inertial body rate from kinematics (the equations above).
void imu_from_kinematics(const Kinematics& k, Vec3& omega_ib_b, Vec3& f_b);
/// The same with the Earth terms at k's latitude given.
void imu_from_kinematics(const Kinematics& k, const EarthTerms& earth, Vec3& omega_ib_b, Vec3& f_b);

// ------------------------------------------------------------------------------------------------
// Motions
// ------------------------------------------------------------------------------------------------

/// One phase of a flight timeline. Over the phase the speed goes from v0_mps to v1_mps, the
/// flight-path angle from gamma0_rad to gamma1_rad and the crab angle (heading minus track) from
/// crab0_rad to crab1_rad (smooth_step shape; equal ends: constant); the bank follows kind. A coordinated phase turns at g tan(phi) / V; an uncoordinated one (a roll
/// without turning) holds the heading.
struct FlightPhase {
  enum class Kind { kStraight, kRollIn, kBank, kRollOut };
  Kind kind = Kind::kStraight;
  double t0_s = 0.0;
  double t1_s = 0.0;
  double bank_rad = 0.0;  ///< signed target bank (+ right)
  int segment = -1;
  int turn = -1;          ///< running turn number (coordinated turns only), -1 otherwise
  double v0_mps = 0.0, v1_mps = 0.0;
  double gamma0_rad = 0.0, gamma1_rad = 0.0;
  bool coordinated = true;
  double crab0_rad = 0.0, crab1_rad = 0.0;
};

/// The scenario flight: coordinated bank-to-turn segments, speed changes, climbs (pull-up and
/// push-over), rolls without turning and crabs (scenario.hpp, Segment). ODE state y = (track, lat,
/// lon, h); the body heading is the track plus the crab angle.
class FlightMotion final : public Motion {
 public:
  /// Builds the timeline up to the scenario duration; returns nullptr and an error message when
  /// a turn is too small for its roll-in/roll-out time.
  static std::unique_ptr<FlightMotion> create(const Scenario& sc, std::string& error);

  State initial_state() const override;
  State derivative(double t_s, const State& y) const override;
  Kinematics eval(double t_s, const State& y) const override;
  MotionPhase phase(double t_s) const override;
  /// v = roll, roll rate, speed, its rate, flight path, its rate, crab, its rate, heading rate,
  /// sin and cos of the flight path (the one computation derivative() and eval() use).
  void instant(double t_s, Instant& in) const override;
  State derivative(const Instant& in, const State& y) const override;
  Kinematics eval(const Instant& in, const State& y) const override;
  /// a.v = track, its sine and cosine, latitude, its sine and cosine, R_M, R_N and their
  /// derivatives by the latitude, the latitude's tangent, gravity's sqrt(1 - e2 sin^2) and its
  /// derivative by the latitude.
  void anchor(const State& y0, StepAnchor& a) const override;
  State derivative(const Instant& in, const State& y, const StepAnchor& a) const override;
  Kinematics eval(const Instant& in, const State& y, const StepAnchor& a, EarthTerms& earth) const override;

  const std::vector<FlightPhase>& timeline() const { return phases_; }
  /// Roll angle [rad] and roll rate [rad/s] at t.
  void roll(double t_s, double& roll_rad, double& roll_rate_radps) const;
  /// Speed [m/s] and its rate [m/s^2] at t.
  void speed(double t_s, double& v_mps, double& v_rate_mps2) const;
  /// Flight-path angle [rad] and its rate [rad/s] at t.
  void flight_path(double t_s, double& gamma_rad, double& gamma_rate_radps) const;
  /// Crab angle (body heading minus track, + nose right) [rad] and its rate [rad/s] at t.
  void crab(double t_s, double& crab_rad, double& crab_rate_radps) const;

 private:
  FlightMotion() = default;
  const FlightPhase& phase_at(double t_s) const;
  /// Heading rate [rad/s] in phase p for roll phi and speed V.
  double heading_rate(const FlightPhase& p, double phi, double V) const;
  /// Roll angle and rate at t within phase p (roll() once the phase is known).
  static void roll_in(const FlightPhase& p, double t_s, double& roll_rad, double& roll_rate_radps);
  /// eval(in, y) given the track's sine sp and cosine cp.
  Kinematics eval_with_track(const Instant& in, const State& y, double sp, double cp) const;

  StartState start_{};
  double g_coord_mps2_ = 9.8;  ///< gravity used by the coordination law g tan(phi) / V
  std::vector<FlightPhase> phases_;
};

/// The segments a scenario flies within its duration, in order, its repeats unrolled: every segment
/// started before duration_s, the last one completed, so end_s (when it ends) may be after
/// duration_s; a segment list that ends before duration_s without a repeat is followed by the
/// straight that fills the flight. The same timeline as FlightMotion::create.
struct FlownSegments {
  std::vector<Segment> segments;
  double end_s = 0.0;
};
bool flown_segments(const Scenario& sc, FlownSegments& out, std::string& error);

/// The scenario flown as it was (flown_segments: its last segment completed), then the segments
/// `extra`, with no repeat; duration_s is when the last extra segment ends. Everything else (start,
/// seed, IMU, effects, GPS) is sc's, so the flight up to sc.duration_s is the one sc flies.
bool append_segments(const Scenario& sc, const std::vector<Segment>& extra, Scenario& out, std::string& error);

/// A stationary IMU on a rate table: fixed position, zero velocity, initial attitude C_b_n0,
/// rotating about a body axis at a constant rate from t = 0 (the paper's section II tests).
class TableMotion final : public Motion {
 public:
  TableMotion(const Vec3& llh, const Mat3& C_b_n0, const Vec3& axis_b, double rate_radps);
  State initial_state() const override { return State::Zero(); }
  State derivative(double, const State&) const override { return State::Zero(); }
  Kinematics eval(double t_s, const State& y) const override;
  using Motion::derivative;
  using Motion::eval;

 private:
  Vec3 llh_;
  Mat3 C_b_n0_;
  Vec3 axis_b_;
  double rate_radps_;
};

/// Roll transition shape: s(0) = 0, s(1) = 1, with zero first and second derivative at both ends.
double smooth_step(double x);
double smooth_step_rate(double x);  ///< ds/dx

}  // namespace sim
