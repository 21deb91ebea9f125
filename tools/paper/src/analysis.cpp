#include "tools/analysis.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

#include "fsw/alignment.hpp"
#include "sim/trajectory.hpp"
#include "tools/free_inertial.hpp"
#include "tools/parallel.hpp"

namespace tools {

using fsw::Mat3;
using fsw::Vec3;

AlignmentCase run_alignment_case(const std::string& name, const Vec3& accel_bias_b_mps2, const Vec3& gyro_bias_b_radps,
                                 double lat_rad, double heading_rad, double duration_s) {
  AlignmentCase c;
  c.name = name;
  c.accel_bias_b_mps2 = accel_bias_b_mps2;
  c.gyro_bias_b_radps = gyro_bias_b_radps;
  const Vec3 llh(lat_rad, 127.0 * fsw::kDegToRad, 100.0);
  const Mat3 C_b_n = fsw::C_b_n_from_euler(0.0, 0.0, heading_rad);
  const sim::TableMotion still(llh, C_b_n, Vec3::UnitZ(), 0.0);
  sim::ImuErrors e;
  e.accel_bias_mps2 = accel_bias_b_mps2;
  e.gyro_bias_radps = gyro_bias_b_radps;
  sim::ImuModel imu(e, 1);
  sim::TruthGenerator gen(still, 1000.0);
  fsw::CoarseAlignment align;
  const long long n = std::llround(duration_s * 1000.0);
  for (long long i = 0; i < n; ++i) align.add(imu.measure(gen.next()));
  Mat3 C_hat = Mat3::Identity();
  if (align.solve(lat_rad, C_hat) == fsw::Status::kOk) {
    c.phi_sim_rad = fsw::attitude_error_enu(C_hat, C_b_n);
  } else {
    c.phi_sim_rad.setConstant(std::nan(""));
  }
  c.phi_formula_rad = fsw::predicted_alignment_error(C_b_n * accel_bias_b_mps2, C_b_n * gyro_bias_b_radps, lat_rad,
                                                     fsw::normal_gravity_mps2(lat_rad, llh.z()));
  return c;
}

Vec3 rotation_error_formula(const Mat3& C_b_n0, const Mat3& M, const Vec3& axis_b, double rate_radps, double t_s) {
  const double th = rate_radps * t_s;
  const Vec3 Ma = M * axis_b;
  return -(C_b_n0 * (std::sin(th) * Ma + (1.0 - std::cos(th)) * axis_b.cross(Ma)));
}

RotationCase run_rotation_case(int axis, std::size_t component, double gamma_arcsec, double rate_dps,
                               double duration_s, double lat_rad) {
  static const char* kAxis = "xyz";
  RotationCase c;
  c.axis = axis;
  c.component = component;
  c.gamma_arcsec = gamma_arcsec;
  c.rate_dps = rate_dps;
  c.name = std::string(1, kAxis[axis]) + "_" + fsw::kEffectCatalogue[0].components[component] + "_" +
           std::to_string(static_cast<int>(std::lround(gamma_arcsec)));
  const Vec3 llh(lat_rad, 127.0 * fsw::kDegToRad, 100.0);
  const Mat3 C_b_n0 = fsw::C_b_n_from_euler(0.0, 0.0, 0.0);  // level, nose North
  const Vec3 a = Vec3::Unit(axis);
  const double w = rate_dps * fsw::kDegToRad;
  const sim::TableMotion table(llh, C_b_n0, a, w);
  sim::EffectSet fx;
  fx.set(fsw::Effect::kGyroMisalignment, component, gamma_arcsec);
  const sim::ImuErrors e = sim::imu_errors_from_effects(fx);
  sim::ImuModel imu(e, 1);
  FreeInertialConfig cfg;
  cfg.duration_s = duration_s;
  int frame = 0;
  run_free_inertial(table, &imu, cfg, [&](const sim::TruthSample& truth, const fsw::NavState& nav) {
    if (++frame % 10 != 0) return;  // 20 Hz series
    const Vec3 phi = fsw::attitude_error_enu(nav.C_b_n(), truth.C_b_n);
    const Vec3 f = rotation_error_formula(C_b_n0, e.gyro_misalignment_rad, a, w, truth.t_s);
    c.t_s.push_back(truth.t_s);
    c.phi_sim_rad.push_back(phi);
    c.phi_formula_rad.push_back(f);
    c.peak_formula_rad = std::max(c.peak_formula_rad, f.cwiseAbs().maxCoeff());
    c.max_deviation_rad = std::max(c.max_deviation_rad, (phi - f).cwiseAbs().maxCoeff());
  });
  return c;
}

namespace {

/// One bank-to-turn case in flight: its IMU (the one misalignment), what its per-frame callback
/// keeps, and the case's figures once the flight is over (finish()).
class BankTurnFlight {
 public:
  BankTurnFlight(const sim::FlightMotion& motion, std::size_t component, double gamma_arcsec)
      : motion_(motion), e_(errors(component, gamma_arcsec)), imu_(e_, 1) {
    c_.component = fsw::kEffectCatalogue[0].components[component];
    c_.gamma_arcsec = gamma_arcsec;
  }
  sim::ImuModel* imu() { return &imu_; }

  void on_frame(const sim::TruthSample& truth, const fsw::NavState& nav, double nav_rate_hz) {
    const Vec3 phi = fsw::attitude_error_enu(nav.C_b_n(), truth.C_b_n);
    // Equation (7) forcing of phi_U: -(C_b_n M omega_ib_b)_U, integrated at the frame rate.
    if (truth.phase.turning) forcing_u_ += -(truth.C_b_n * (e_.gyro_misalignment_rad * truth.omega_ib_b_radps)).z() / nav_rate_hz;
    if (was_turning_ && !truth.phase.turning) {
      c_.turn_end_t_s.push_back(truth.t_s);
      c_.turn_end_phi_u_rad.push_back(phi.z());
      c_.turn_end_phi_rad.push_back(phi);
      forced_per_turn_.push_back(forcing_u_);
      forcing_u_ = 0.0;
    }
    was_turning_ = truth.phase.turning;
    if (++frame_ % 100 == 0) {  // 2 Hz series
      double roll = 0.0, roll_rate = 0.0;
      motion_.roll(truth.t_s, roll, roll_rate);
      c_.t_s.push_back(truth.t_s);
      c_.phi_rad.push_back(phi);
      c_.roll_rad.push_back(roll);
    }
  }

  /// The growth per completed turn and its verdict, from what the flight kept.
  BankTurnCase finish() {
    BankTurnCase& c = c_;
    const double gamma_arcsec = c.gamma_arcsec;
    // Growth per completed turn: phi_U at the end of the last completed turn minus phi_U before the
    // first turn (zero: the run starts on truth), divided by the number of completed turns.
    const std::size_t n = c.turn_end_phi_u_rad.size();
    if (n > 0) {
      c.u_error_per_turn_arcsec = c.turn_end_phi_u_rad.back() / static_cast<double>(n) * fsw::kRadToArcsec;
      double forced = 0.0;
      for (double f : forced_per_turn_) forced += f;
      c.predicted_per_turn_arcsec = forced / static_cast<double>(n) * fsw::kRadToArcsec;
      c.coupled_per_turn_arcsec = c.u_error_per_turn_arcsec - c.predicted_per_turn_arcsec;
      c.tilt_per_turn_arcsec = c.turn_end_phi_rad.back().head<2>().norm() / static_cast<double>(n) * fsw::kRadToArcsec;
    }
    // Excursion of phi_U around the straight line through the turn ends.
    for (std::size_t i = 0; i < c.t_s.size(); ++i) {
      double turns_done = 0.0;
      for (double te : c.turn_end_t_s) turns_done += te <= c.t_s[i] ? 1.0 : 0.0;
      const double trend = turns_done * c.u_error_per_turn_arcsec;
      c.u_oscillation_arcsec = std::max(c.u_oscillation_arcsec, std::abs(c.phi_rad[i].z() * fsw::kRadToArcsec - trend));
    }
    // Accumulates: every completed turn changes phi_U with the same sign, the mean change per turn
    // exceeds 10% of the misalignment angle (the steady-turn forcing of eq. (7) is ~1.4 gamma), and
    // it is the turns' own eq. (7) forcing that produces it (within 25%), not tilt errors leaking
    // into phi_U through the Earth rate (a slow, second-order coupling).
    bool same_sign = n > 1;
    for (std::size_t i = 1; i < n; ++i) {
      const double d0 = c.turn_end_phi_u_rad[0];
      const double di = c.turn_end_phi_u_rad[i] - c.turn_end_phi_u_rad[i - 1];
      same_sign = same_sign && (d0 * di > 0.0);
    }
    c.accumulates = same_sign && std::abs(c.u_error_per_turn_arcsec) > 0.1 * gamma_arcsec &&
                    std::abs(c.coupled_per_turn_arcsec) < 0.25 * std::abs(c.u_error_per_turn_arcsec);
    return std::move(c_);
  }

 private:
  static sim::ImuErrors errors(std::size_t component, double gamma_arcsec) {
    sim::EffectSet fx;
    fx.set(fsw::Effect::kGyroMisalignment, component, gamma_arcsec);
    return sim::imu_errors_from_effects(fx);
  }

  const sim::FlightMotion& motion_;
  const sim::ImuErrors e_;
  sim::ImuModel imu_;
  BankTurnCase c_;
  int frame_ = 0;
  bool was_turning_ = false;
  double forcing_u_ = 0.0;  // integral of the eq. (7) forcing term over the current turn
  std::vector<double> forced_per_turn_;
};

}  // namespace

std::vector<BankTurnCase> run_bank_turn_cases(const sim::Scenario& sc, const std::vector<std::size_t>& components,
                                              double gamma_arcsec, int groups) {
  std::vector<BankTurnCase> out(components.size());
  if (components.empty()) return out;
  const std::size_t ng = std::min(static_cast<std::size_t>(std::max(groups, 1)), components.size());
  // Group g flies cases g, g + ng, g + 2 ng, ... through one truth generator.
  for_each_parallel(ng, [&](std::size_t g) {
    std::string err;
    auto motion = sim::FlightMotion::create(sc, err);
    if (!motion) return;  // no case filled: the caller sees no turn
    std::vector<std::size_t> mine;
    for (std::size_t k = g; k < components.size(); k += ng) mine.push_back(k);
    std::vector<std::unique_ptr<BankTurnFlight>> flights;
    std::vector<FreeInertialFlight> fl;
    FreeInertialConfig cfg;
    cfg.duration_s = sc.duration_s;
    cfg.hold_vertical_to_truth = true;
    for (std::size_t k : mine) {
      flights.push_back(std::make_unique<BankTurnFlight>(*motion, components[k], gamma_arcsec));
      BankTurnFlight* f = flights.back().get();
      fl.push_back({f->imu(), [f, &cfg](const sim::TruthSample& t, const fsw::NavState& n) { f->on_frame(t, n, cfg.nav_rate_hz); }});
    }
    run_free_inertial(*motion, cfg, fl);
    for (std::size_t j = 0; j < mine.size(); ++j) out[mine[j]] = flights[j]->finish();
  });
  return out;
}

BankTurnCase run_bank_turn_case(const sim::Scenario& sc, std::size_t component, double gamma_arcsec) {
  return run_bank_turn_cases(sc, {component}, gamma_arcsec, 1).front();
}

}  // namespace tools
