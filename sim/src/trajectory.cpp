#include "sim/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace sim {

using fsw::kDegToRad;
using fsw::kPi;

namespace {
/// The sine and cosine of one angle, kept for the next call with the same angle (the same bits,
/// so the same values: a memo of std::sin and std::cos). The truth asks again for angles it has
/// just used: an RK4 step starts at the state the last sample was evaluated at (its track and
/// latitude), and the roll and the pitch hold still through most of a flight. One set per thread:
/// generators on several threads keep their own.
struct SinCosMemo {
  bool valid = false;
  std::uint64_t bits = 0;
  double s = 0.0, c = 0.0;
  void of(double x, double& s_out, double& c_out) {
    std::uint64_t b = 0;
    std::memcpy(&b, &x, sizeof b);
    if (!valid || b != bits) {
      valid = true;
      bits = b;
      s = std::sin(x);
      c = std::cos(x);
    }
    s_out = s;
    c_out = c;
  }
};
thread_local SinCosMemo t_track, t_roll, t_pitch, t_lat;

/// The flight's ODE state rate: (track rate, lat rate, lon rate, height rate).
Motion::State flight_rate(double track_rate_radps, const Vec3& llh_rate) {
  Motion::State d = Motion::State::Zero();
  d(0) = track_rate_radps;
  d(1) = llh_rate.x();
  d(2) = llh_rate.y();
  d(3) = llh_rate.z();
  return d;
}

fsw::LatitudeTerms latitude_terms(double lat) {
  double s = 0.0, c = 0.0;
  t_lat.of(lat, s, c);
  return fsw::LatitudeTerms(lat, s, c);
}
}  // namespace

double smooth_step(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x - std::sin(2.0 * kPi * x) / (2.0 * kPi);
}

double smooth_step_rate(double x) {
  if (x <= 0.0 || x >= 1.0) return 0.0;
  return 1.0 - std::cos(2.0 * kPi * x);
}

EarthTerms EarthTerms::exact(double lat_rad) {
  const fsw::LatitudeTerms l = latitude_terms(lat_rad);  // one sine and cosine for all the terms
  EarthTerms e;
  e.sin_lat = l.sin_lat;
  e.cos_lat = l.cos_lat;
  e.tan_lat = std::tan(lat_rad);
  e.r_m_m = fsw::meridian_radius_m(l);
  e.r_n_m = fsw::normal_radius_m(l);
  e.sqrt_1_e2_s2 = fsw::sqrt_1_e2_s2(l.sin_lat);
  return e;
}

void imu_from_kinematics(const Kinematics& k, Vec3& omega_ib_b, Vec3& f_b) {
  imu_from_kinematics(k, EarthTerms::exact(k.llh.x()), omega_ib_b, f_b);
}

void imu_from_kinematics(const Kinematics& k, const EarthTerms& e, Vec3& omega_ib_b, Vec3& f_b) {
  const double h = k.llh.z();
  const Vec3 w_ie = fsw::omega_ie_n(fsw::LatitudeTerms(k.llh.x(), e.sin_lat, e.cos_lat));
  const Vec3 w_en = fsw::omega_en_n(e.r_m_m, e.r_n_m, e.tan_lat, h, k.vel_enu_mps);
  const Vec3 g_enu(0.0, 0.0, -fsw::normal_gravity_from_sin2_mps2(e.sin_lat * e.sin_lat, e.sqrt_1_e2_s2, h));
  const Mat3 C_n_b = k.C_b_n.transpose();
  omega_ib_b = k.omega_nb_b_radps + C_n_b * (w_ie + w_en);
  f_b = C_n_b * (k.acc_enu_mps2 + (2.0 * w_ie + w_en).cross(k.vel_enu_mps) - g_enu);
}

// ------------------------------------------------------------------------------------------------
// TruthGenerator
// ------------------------------------------------------------------------------------------------

TruthGenerator::TruthGenerator(const Motion& motion, double rate_hz) : motion_(motion), dt_s_(1.0 / rate_hz) {
  integ_.y0 = motion_.initial_state();
  compl_.y0 = integ_.y0;
  p_cur_ = evaluate(integ_.instants.of(motion_, 0.0), integ_.y0, nullptr);
  set_current(0.0, 0.0, p_cur_);
}

void TruthGenerator::set_current(double t, double dt, const Point& p) {
  cur_.t_s = t;
  cur_.dt_s = dt;
  cur_.llh = p.k.llh;
  cur_.vel_enu_mps = p.k.vel_enu_mps;
  cur_.C_b_n = p.k.C_b_n;
  cur_.omega_ib_b_radps = p.omega_ib_b;
  cur_.omega_nb_b_radps = p.k.omega_nb_b_radps;
  cur_.f_b_mps2 = p.f_b;
  cur_.phase = motion_.phase(t);
}

const Motion::Instant& TruthGenerator::Instants::of(const Motion& m, double t) {
  for (int i = 0; i < 2; ++i)
    if (valid[i] && inst[i].t_s == t) return inst[i];
  Motion::Instant& in = inst[next];
  valid[next] = true;
  next ^= 1;
  m.instant(t, in);
  return in;
}

void TruthGenerator::Side::start(const Motion& m, double dt_s) {
  t0 = static_cast<double>(index) * dt_s;
  tm = (static_cast<double>(index) + 0.5) * dt_s;
  t1 = static_cast<double>(index + 1) * dt_s;
  m.anchor(y0, anchor);
}

TruthGenerator::Point TruthGenerator::evaluate(const Motion::Instant& in, const Motion::State& y,
                                               const Motion::StepAnchor* a) const {
  Point p;
  if (a == nullptr) {
    p.k = motion_.eval(in, y);
    imu_from_kinematics(p.k, p.omega_ib_b, p.f_b);
    return p;
  }
  EarthTerms earth;
  p.k = motion_.eval(in, y, *a, earth);
  imu_from_kinematics(p.k, earth, p.omega_ib_b, p.f_b);
  return p;
}

void TruthGenerator::integrate(Step& s) {
  // One classical RK4 step over [t0, t1] (its middle stages at tm, the sample's midpoint) and the
  // state at tm from the step's own stages: Hermite's third-order continuous extension of RK4 at
  // theta = 1/2, weights (5/24, 1/6, 1/6, -1/24). The midpoint costs no derivative of its own; the
  // motion is smooth within a step (tests: AgreesWithAnEightTimesFinerTruthThroughATurn).
  Side& d = integ_;
  d.start(motion_, dt_s_);
  const double h = d.t1 - d.t0;
  const Motion::State& y = d.y0;
  const Motion::Instant& mid = d.instants.of(motion_, d.tm);
  const Motion::State k1 = motion_.derivative(d.instants.of(motion_, d.t0), y, d.anchor);
  const Motion::State k2 = motion_.derivative(mid, y + 0.5 * h * k1, d.anchor);
  const Motion::State k3 = motion_.derivative(mid, y + 0.5 * h * k2, d.anchor);
  const Motion::State k4 = motion_.derivative(d.instants.of(motion_, d.t1), y + h * k3, d.anchor);
  s.y_mid = y + h * (5.0 / 24.0 * k1 + 1.0 / 6.0 * (k2 + k3) - 1.0 / 24.0 * k4);
  s.y1 = y + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
  d.y0 = s.y1;
  ++d.index;
}

const TruthSample& TruthGenerator::next() {
  // The integration's anchor and instants serve the evaluations too (the same values complete()
  // would take again); complete()'s side follows along.
  integrate(step_);
  compl_.index = integ_.index;
  compl_.y0 = integ_.y0;
  return complete(step_, integ_);
}

const TruthSample& TruthGenerator::complete(const Step& s) {
  Side& d = compl_;
  d.start(motion_, dt_s_);
  d.y0 = s.y1;
  ++d.index;
  return complete(s, d);
}

const TruthSample& TruthGenerator::complete(const Step& s, Side& d) {
  const Point pm = evaluate(d.instants.of(motion_, d.tm), s.y_mid, &d.anchor);  // both within the step
  const Point p1 = evaluate(d.instants.of(motion_, d.t1), s.y1, &d.anchor);
  const double h = d.t1 - d.t0;
  cur_.dtheta_rad = h / 6.0 * (p_cur_.omega_ib_b + 4.0 * pm.omega_ib_b + p1.omega_ib_b);
  cur_.dv_mps = h / 6.0 * (p_cur_.f_b + 4.0 * pm.f_b + p1.f_b);
  p_cur_ = p1;
  set_current(d.t1, h, p1);
  return cur_;
}

// ------------------------------------------------------------------------------------------------
// FlightMotion
// ------------------------------------------------------------------------------------------------

namespace {
/// Heading turned during one roll transition of length T to bank phi_b at speed V:
/// int_0^T g tan(phi_b s(t/T)) / V dt (Gauss-Legendre on 64 panels; the integrand is smooth).
double transition_heading_change(double g, double V, double phi_b, double T) {
  static constexpr double xg[3] = {-0.7745966692414834, 0.0, 0.7745966692414834};
  static constexpr double wg[3] = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
  const int n = 64;
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double a = static_cast<double>(i) / n, b = static_cast<double>(i + 1) / n;
    for (int j = 0; j < 3; ++j) {
      const double x = 0.5 * (a + b) + 0.5 * (b - a) * xg[j];
      sum += wg[j] * 0.5 * (b - a) * std::tan(phi_b * smooth_step(x));
    }
  }
  return g / V * T * sum;
}

/// A coordinated turn's time at constant bank: its heading change less what the roll-in and the
/// roll-out turn, at the bank's turn rate. False (and error) when the transitions alone turn more.
bool turn_bank_time(double g, double V, const Segment& s, std::size_t idx, double& t_bank, std::string& error) {
  const double phi_b = s.bank_deg * kDegToRad;
  const double dpsi_roll = transition_heading_change(g, V, phi_b, s.roll_time_s);
  const double psi_rate = g * std::tan(phi_b) / V;
  t_bank = (s.heading_change_deg * kDegToRad - 2.0 * dpsi_roll) / psi_rate;
  if (!(t_bank < 0.0)) return true;
  error = "segment " + std::to_string(idx) + ": heading change " + std::to_string(s.heading_change_deg) +
          " deg is smaller than the " + std::to_string(2.0 * dpsi_roll / kDegToRad) +
          " deg turned during roll-in and roll-out";
  return false;
}
}  // namespace

std::unique_ptr<FlightMotion> FlightMotion::create(const Scenario& sc, std::string& error) {
  std::unique_ptr<FlightMotion> m(new FlightMotion());
  m->start_ = sc.start;
  m->g_coord_mps2_ = fsw::normal_gravity_mps2(sc.start.lat_deg * kDegToRad, sc.start.alt_m);
  double V = sc.start.speed_mps;
  if (!(V > 0.0) || sc.segments.empty()) {
    error = "scenario needs a positive speed and at least one segment";
    return nullptr;
  }
  constexpr double kMinSpeed_mps = 20.0;
  double t = 0.0;
  std::size_t idx = 0;
  int turn = 0;
  // A phase at constant speed V and level flight.
  const auto level = [&V](FlightPhase::Kind kind, double t0, double t1, double bank, int seg, int trn, bool coord) {
    return FlightPhase{kind, t0, t1, bank, seg, trn, V, V, 0.0, 0.0, coord};
  };
  // A transition in (transition_s), a hold (duration_s, may be 0) and a transition back, wings
  // level and straight: set(phase, is_in, is_out) gives each phase its start and end values.
  const auto push_in_hold_out = [&](const Segment& s, int seg, const auto& set) {
    const double T = s.transition_s;
    FlightPhase in = level(FlightPhase::Kind::kStraight, t, t + T, 0.0, seg, -1, true);
    set(in, true, false);
    m->phases_.push_back(in);
    if (s.duration_s > 0.0) {
      FlightPhase hold = level(FlightPhase::Kind::kStraight, t + T, t + T + s.duration_s, 0.0, seg, -1, true);
      set(hold, false, false);
      m->phases_.push_back(hold);
    }
    FlightPhase out =
        level(FlightPhase::Kind::kStraight, t + T + s.duration_s, t + 2.0 * T + s.duration_s, 0.0, seg, -1, true);
    set(out, false, true);
    m->phases_.push_back(out);
    t += 2.0 * T + s.duration_s;
  };
  while (t < sc.duration_s) {
    if (idx >= sc.segments.size()) {
      // No repeat: the closing straight phase below starts here (pushing one that ends at
      // duration + 1 as well would overlap it and break the contiguous-timeline invariant).
      if (!sc.repeat_from) break;
      idx = *sc.repeat_from;
    }
    const Segment& s = sc.segments[idx];
    const int seg = static_cast<int>(idx);
    const double sign = s.direction == TurnDirection::kRight ? 1.0 : -1.0;
    switch (s.type) {
      case SegmentType::kStraight:
        m->phases_.push_back(level(FlightPhase::Kind::kStraight, t, t + s.duration_s, 0.0, seg, -1, true));
        t += s.duration_s;
        break;
      case SegmentType::kTurn: {
        const double phi_b = s.bank_deg * kDegToRad;
        const double T = s.roll_time_s;
        double t_bank = 0.0;
        if (!turn_bank_time(m->g_coord_mps2_, V, s, idx, t_bank, error)) return nullptr;
        m->phases_.push_back(level(FlightPhase::Kind::kRollIn, t, t + T, sign * phi_b, seg, turn, true));
        m->phases_.push_back(level(FlightPhase::Kind::kBank, t + T, t + T + t_bank, sign * phi_b, seg, turn, true));
        m->phases_.push_back(
            level(FlightPhase::Kind::kRollOut, t + T + t_bank, t + 2.0 * T + t_bank, sign * phi_b, seg, turn, true));
        t += 2.0 * T + t_bank;
        ++turn;
        break;
      }
      case SegmentType::kRoll: {
        const double phi_b = sign * s.bank_deg * kDegToRad;
        const double T = s.roll_time_s;
        m->phases_.push_back(level(FlightPhase::Kind::kRollIn, t, t + T, phi_b, seg, -1, false));
        if (s.duration_s > 0.0)
          m->phases_.push_back(level(FlightPhase::Kind::kBank, t + T, t + T + s.duration_s, phi_b, seg, -1, false));
        m->phases_.push_back(
            level(FlightPhase::Kind::kRollOut, t + T + s.duration_s, t + 2.0 * T + s.duration_s, phi_b, seg, -1, false));
        t += 2.0 * T + s.duration_s;
        break;
      }
      case SegmentType::kSpeedChange: {
        const double v1 = V + s.delta_speed_mps;
        if (!(v1 >= kMinSpeed_mps)) {
          error = "segment " + std::to_string(idx) + ": the speed change of " + std::to_string(s.delta_speed_mps) +
                  " m/s from " + std::to_string(V) + " m/s leaves less than " + std::to_string(kMinSpeed_mps) + " m/s";
          return nullptr;
        }
        FlightPhase p = level(FlightPhase::Kind::kStraight, t, t + s.duration_s, 0.0, seg, -1, true);
        p.v1_mps = v1;
        m->phases_.push_back(p);
        V = v1;
        t += s.duration_s;
        break;
      }
      case SegmentType::kClimb: {
        // Pull-up to the flight-path angle, hold, push-over back to level.
        const double g1 = s.flight_path_deg * kDegToRad;
        push_in_hold_out(s, seg, [g1](FlightPhase& p, bool in, bool out) {
          p.gamma0_rad = in ? 0.0 : g1;
          p.gamma1_rad = out ? 0.0 : g1;
        });
        break;
      }
      case SegmentType::kCrab: {
        // Wings level and straight: only the nose moves off the track (kinematics: the velocity
        // is unchanged, the attitude's yaw is track + crab, the body yaw rate the crab's rate).
        const double c1 = sign * s.crab_deg * kDegToRad;
        push_in_hold_out(s, seg, [c1](FlightPhase& p, bool in, bool out) {
          p.crab0_rad = in ? 0.0 : c1;
          p.crab1_rad = out ? 0.0 : c1;
        });
        break;
      }
    }
    ++idx;
  }
  // Past the end of the timeline the aircraft flies straight.
  m->phases_.push_back(level(FlightPhase::Kind::kStraight, t, 1e300, 0.0, -1, -1, true));
  return m;
}

const FlightPhase& FlightMotion::phase_at(double t_s) const {
  // First phase whose end is after t (phases are contiguous and sorted).
  auto it = std::upper_bound(phases_.begin(), phases_.end(), t_s,
                             [](double t, const FlightPhase& p) { return t < p.t1_s; });
  if (it == phases_.end()) return phases_.back();
  return *it;
}

void FlightMotion::roll(double t_s, double& roll_rad, double& roll_rate_radps) const {
  roll_in(phase_at(t_s), t_s, roll_rad, roll_rate_radps);
}

void FlightMotion::roll_in(const FlightPhase& p, double t_s, double& roll_rad, double& roll_rate_radps) {
  const double T = p.t1_s - p.t0_s;
  switch (p.kind) {
    case FlightPhase::Kind::kStraight:
      roll_rad = 0.0;
      roll_rate_radps = 0.0;
      return;
    case FlightPhase::Kind::kBank:
      roll_rad = p.bank_rad;
      roll_rate_radps = 0.0;
      return;
    case FlightPhase::Kind::kRollIn: {
      const double x = (t_s - p.t0_s) / T;
      roll_rad = p.bank_rad * smooth_step(x);
      roll_rate_radps = p.bank_rad * smooth_step_rate(x) / T;
      return;
    }
    case FlightPhase::Kind::kRollOut: {
      const double x = (t_s - p.t0_s) / T;
      roll_rad = p.bank_rad * (1.0 - smooth_step(x));
      roll_rate_radps = -p.bank_rad * smooth_step_rate(x) / T;
      return;
    }
  }
}

Motion::State FlightMotion::initial_state() const {
  State y = State::Zero();
  y(0) = start_.heading_deg * kDegToRad;
  y(1) = start_.lat_deg * kDegToRad;
  y(2) = start_.lon_deg * kDegToRad;
  y(3) = start_.alt_m;
  return y;
}

namespace {
/// The value and rate of a quantity going from a0 to a1 over the phase (smooth_step shape).
void blend(const FlightPhase& p, double t_s, double a0, double a1, double& a, double& a_rate) {
  const double T = p.t1_s - p.t0_s;
  if (a0 == a1 || !(T > 0.0) || !(T < 1e299)) {
    a = a1;
    a_rate = 0.0;
    return;
  }
  const double x = std::clamp((t_s - p.t0_s) / T, 0.0, 1.0);
  a = a0 + (a1 - a0) * smooth_step(x);
  a_rate = (a1 - a0) * smooth_step_rate(x) / T;
}
}  // namespace

void FlightMotion::speed(double t_s, double& v_mps, double& v_rate_mps2) const {
  const FlightPhase& p = phase_at(t_s);
  blend(p, t_s, p.v0_mps, p.v1_mps, v_mps, v_rate_mps2);
}

void FlightMotion::flight_path(double t_s, double& gamma_rad, double& gamma_rate_radps) const {
  const FlightPhase& p = phase_at(t_s);
  blend(p, t_s, p.gamma0_rad, p.gamma1_rad, gamma_rad, gamma_rate_radps);
}

void FlightMotion::crab(double t_s, double& crab_rad, double& crab_rate_radps) const {
  const FlightPhase& p = phase_at(t_s);
  blend(p, t_s, p.crab0_rad, p.crab1_rad, crab_rad, crab_rate_radps);
}

namespace {
/// The coordination law g tan(phi) / V of a coordinated phase (0 for an uncoordinated one), from tan(phi).
double turn_rate(const FlightPhase& p, double g, double tan_phi, double V) {
  return p.coordinated ? g * tan_phi / V : 0.0;
}
}  // namespace

double FlightMotion::heading_rate(const FlightPhase& p, double phi, double V) const {
  return turn_rate(p, g_coord_mps2_, std::tan(phi), V);
}

// derivative() and eval() run ten times per 1 kHz truth sample at four to six distinct instants:
// everything that depends on t alone is computed once per instant, from its phase found once.
// The trigonometry of the instant is skipped where its bits are known without the call (measured:
// tan and the flight path's sincos were 7% of `sdins fly`): tan(+-0) and sin(+-0) are +-0 and
// cos(+-0) is 1 (wings level, level flight), and a roll equal to the one this Instant held before
// (a bank held; the generator reuses two Instants in turn) has the tangent it kept in v[11].
// v[11] == tan(v[0]) always: a new Instant's zeros are, and every call keeps it.
void FlightMotion::instant(double t_s, Instant& in) const {
  const FlightPhase& p = phase_at(t_s);
  double* v = in.v;
  in.t_s = t_s;
  const double prev_roll = v[0], prev_tan_roll = v[11];
  roll_in(p, t_s, v[0], v[1]);
  v[11] = v[0] == 0.0 ? v[0] : (v[0] == prev_roll ? prev_tan_roll : std::tan(v[0]));
  blend(p, t_s, p.v0_mps, p.v1_mps, v[2], v[3]);
  blend(p, t_s, p.gamma0_rad, p.gamma1_rad, v[4], v[5]);
  blend(p, t_s, p.crab0_rad, p.crab1_rad, v[6], v[7]);
  v[8] = turn_rate(p, g_coord_mps2_, v[11], v[2]);  // heading_rate() with tan(roll) known
  // Level flight (flight path +-0): sin is the angle itself (+-0) and cos 1, the bits sin and cos give.
  const bool level_path = v[4] == 0.0;
  v[9] = level_path ? v[4] : std::sin(v[4]);
  v[10] = level_path ? 1.0 : std::cos(v[4]);
}

Motion::State FlightMotion::derivative(double t_s, const State& y) const {
  Instant in;
  instant(t_s, in);
  return derivative(in, y);
}

Motion::State FlightMotion::derivative(const Instant& in, const State& y) const {
  const double V = in.v[2], sg = in.v[9], cg = in.v[10];
  const double ch = V * cg;
  double s_trk = 0.0, c_trk = 0.0;
  t_track.of(y(0), s_trk, c_trk);
  const Vec3 v(ch * s_trk, ch * c_trk, V * sg);
  return flight_rate(in.v[8], fsw::llh_rate(Vec3(y(1), y(2), y(3)), v));
}

void FlightMotion::anchor(const State& y0, StepAnchor& a) const {
  double s_trk = 0.0, c_trk = 0.0;
  t_track.of(y0(0), s_trk, c_trk);
  const EarthTerms e = EarthTerms::exact(y0(1));
  // dR_M/dlat = 3 R_M e2 s c / d and dR_N/dlat = R_N e2 s c / d, d = 1 - e2 s^2;
  // d sqrt(d)/dlat = -e2 s c / sqrt(d).
  const double e2sc = fsw::wgs84::e2 * e.sin_lat * e.cos_lat;
  const double k = e2sc / (1.0 - fsw::wgs84::e2 * e.sin_lat * e.sin_lat);
  a.v[0] = y0(0);
  a.v[1] = s_trk;
  a.v[2] = c_trk;
  a.v[3] = y0(1);
  a.v[4] = e.sin_lat;
  a.v[5] = e.cos_lat;
  a.v[6] = e.r_m_m;
  a.v[7] = e.r_n_m;
  a.v[8] = 3.0 * e.r_m_m * k;
  a.v[9] = e.r_n_m * k;
  a.v[10] = e.tan_lat;
  a.v[11] = e.sqrt_1_e2_s2;
  a.v[12] = -e2sc / e.sqrt_1_e2_s2;
}

namespace {
// Within one step the track moves by at most |heading rate| h (1.3e-4 rad at 1 kHz): its sine
// and cosine to the third power, remainder dp^4 / 24 < 1e-17. The latitude moves by about
// V h / R (4e-8 rad): its sine, cosine and tangent to the second power, the radii and gravity's
// square root to the first, leave remainders of about 1e-23, 1e-10 m (R_M'' dl^2 / 2) and 1e-17,
// below the rounding of each. At dp = dl = 0 every correction is an exact zero and the terms are
// the anchor's bits.

/// The track's sine and cosine at psi from the step anchor a.
void carried_track(const Motion::StepAnchor& a, double psi, double& s_trk, double& c_trk) {
  const double dp = psi - a.v[0], dp2 = dp * dp;
  s_trk = a.v[1] + (a.v[2] * dp - a.v[1] * dp2 * 0.5 - a.v[2] * dp2 * dp * (1.0 / 6.0));
  c_trk = a.v[2] - (a.v[1] * dp + a.v[2] * dp2 * 0.5 - a.v[1] * dp2 * dp * (1.0 / 6.0));
}

/// The Earth terms at latitude lat from the step anchor a (its cosine and radii are what the
/// RK4 stages take).
EarthTerms carried_earth(const Motion::StepAnchor& a, double lat) {
  const double dl = lat - a.v[3], dl2 = dl * dl;
  const double t = a.v[10], sec2 = 1.0 + t * t;
  EarthTerms e;
  e.sin_lat = a.v[4] + (a.v[5] * dl - a.v[4] * dl2 * 0.5);
  e.cos_lat = a.v[5] - (a.v[4] * dl + a.v[5] * dl2 * 0.5);
  e.tan_lat = t + (sec2 * dl + t * sec2 * dl2);
  e.r_m_m = a.v[6] + a.v[8] * dl;
  e.r_n_m = a.v[7] + a.v[9] * dl;
  e.sqrt_1_e2_s2 = a.v[11] + a.v[12] * dl;
  return e;
}
}  // namespace

Motion::State FlightMotion::derivative(const Instant& in, const State& y, const StepAnchor& a) const {
  const double V = in.v[2], sg = in.v[9], cg = in.v[10];
  const double ch = V * cg;
  double s_trk = 0.0, c_trk = 0.0;
  carried_track(a, y(0), s_trk, c_trk);
  const double dl = y(1) - a.v[3];
  const double c_lat = a.v[5] - (a.v[4] * dl + a.v[5] * dl * dl * 0.5);
  const double rm = a.v[6] + a.v[8] * dl, rn = a.v[7] + a.v[9] * dl;
  return flight_rate(in.v[8], fsw::llh_rate(rm, rn, c_lat, y(3), Vec3(ch * s_trk, ch * c_trk, V * sg)));
}

Kinematics FlightMotion::eval(double t_s, const State& y) const {
  Instant in;
  instant(t_s, in);
  return eval(in, y);
}

Kinematics FlightMotion::eval(const Instant& in, const State& y) const {
  double sp = 0.0, cp = 0.0;
  t_track.of(y(0), sp, cp);
  return eval_with_track(in, y, sp, cp);
}

Kinematics FlightMotion::eval(const Instant& in, const State& y, const StepAnchor& a, EarthTerms& earth) const {
  double sp = 0.0, cp = 0.0;
  carried_track(a, y(0), sp, cp);
  earth = carried_earth(a, y(1));
  return eval_with_track(in, y, sp, cp);
}

Kinematics FlightMotion::eval_with_track(const Instant& in, const State& y, double sp, double cp) const {
  const double phi = in.v[0], phi_dot = in.v[1], V = in.v[2], V_dot = in.v[3], gam = in.v[4], gam_dot = in.v[5];
  const double beta = in.v[6], beta_dot = in.v[7], psi_dot = in.v[8], sg = in.v[9], cg = in.v[10];
  const double psi = y(0);  // the track, whose sine and cosine are sp and cp
  const double theta = start_.pitch_deg * kDegToRad + gam;
  Kinematics k;
  k.llh = Vec3(y(1), y(2), y(3));
  k.vel_enu_mps = V * Vec3(cg * sp, cg * cp, sg);
  // d/dt of V (cos g sin psi, cos g cos psi, sin g).
  k.acc_enu_mps2 = V_dot * Vec3(cg * sp, cg * cp, sg) + V * gam_dot * Vec3(-sg * sp, -sg * cp, cg) +
                   V * psi_dot * Vec3(cg * cp, -cg * sp, 0.0);
  // The body heading is the track plus the crab angle; the velocity above follows the track only.
  // Without crab the heading's sine and cosine are the track's; with it, through the track's memo.
  double sh = sp, ch = cp;
  if (beta != 0.0) t_track.of(psi + beta, sh, ch);
  double sr = 0.0, cr = 0.0, s_pitch = 0.0, c_pitch = 0.0;
  t_roll.of(phi, sr, cr);
  t_pitch.of(theta, s_pitch, c_pitch);
  const fsw::EulerTerms e{sr, cr, s_pitch, c_pitch, sh, ch};
  k.C_b_n = fsw::C_b_n_from_euler(e);
  k.omega_nb_b_radps = fsw::omega_nb_b_from_euler_rates(e, phi_dot, gam_dot, psi_dot + beta_dot);
  return k;
}

MotionPhase FlightMotion::phase(double t_s) const {
  const FlightPhase& p = phase_at(t_s);
  MotionPhase mp;
  mp.segment = p.segment;
  mp.turn = p.turn;
  mp.turning = p.turn >= 0;
  return mp;
}

// ------------------------------------------------------------------------------------------------
// Unrolled segments
// ------------------------------------------------------------------------------------------------

namespace {
/// The phases FlightMotion::create makes of one segment.
std::size_t phase_count(const Segment& s) {
  switch (s.type) {
    case SegmentType::kStraight:
    case SegmentType::kSpeedChange: return 1;
    case SegmentType::kTurn: return 3;
    case SegmentType::kClimb:
    case SegmentType::kRoll:
    case SegmentType::kCrab: return s.duration_s > 0.0 ? 3 : 2;
  }
  return 1;
}
}  // namespace

bool flown_segments(const Scenario& sc, FlownSegments& out, std::string& error) {
  out = FlownSegments{};
  const std::unique_ptr<FlightMotion> m = FlightMotion::create(sc, error);
  if (!m) return false;
  const std::vector<FlightPhase>& ph = m->timeline();
  // The last phase is the open-ended straight after the timeline; the others are the segments'
  // phases, segment after segment in the order create() walked the list.
  const std::size_t n = ph.size() - 1;
  std::size_t p = 0, idx = 0;
  while (p < n) {
    if (idx >= sc.segments.size()) {
      if (!sc.repeat_from) break;
      idx = *sc.repeat_from;
    }
    const Segment& s = sc.segments[idx];
    const std::size_t k = phase_count(s);
    if (p + k > n || ph[p].segment != static_cast<int>(idx)) {
      error = "internal error: the timeline does not follow the segment list at segment " + std::to_string(idx);
      return false;
    }
    out.segments.push_back(s);
    p += k;
    out.end_s = ph[p - 1].t1_s;
    ++idx;
  }
  if (out.end_s < sc.duration_s) {  // no repeat: straight until duration_s
    Segment fill;
    fill.type = SegmentType::kStraight;
    fill.duration_s = sc.duration_s - out.end_s;
    out.segments.push_back(fill);
    out.end_s = sc.duration_s;
  }
  return true;
}

bool append_segments(const Scenario& sc, const std::vector<Segment>& extra, Scenario& out, std::string& error) {
  FlownSegments flown;
  if (!flown_segments(sc, flown, error)) return false;
  out = sc;
  out.segments = flown.segments;
  out.segments.insert(out.segments.end(), extra.begin(), extra.end());
  out.repeat_from = std::nullopt;
  // The end of the new timeline: build it past any length and read where its segments end.
  Scenario probe = out;
  probe.duration_s = 1e12;
  const std::unique_ptr<FlightMotion> m = FlightMotion::create(probe, error);
  if (!m) return false;
  out.duration_s = m->timeline().back().t0_s;
  return true;
}

// ------------------------------------------------------------------------------------------------
// TableMotion
// ------------------------------------------------------------------------------------------------

TableMotion::TableMotion(const Vec3& llh, const Mat3& C_b_n0, const Vec3& axis_b, double rate_radps)
    : llh_(llh), C_b_n0_(C_b_n0), axis_b_(axis_b.normalized()), rate_radps_(rate_radps) {}

Kinematics TableMotion::eval(double t_s, const State& /*y*/) const {
  Kinematics k;
  k.llh = llh_;
  k.C_b_n = C_b_n0_ * fsw::quat_from_rotvec(axis_b_ * (rate_radps_ * t_s)).toRotationMatrix();
  k.omega_nb_b_radps = axis_b_ * rate_radps_;
  return k;
}

}  // namespace sim
