// The analyses of the reference paper's section II: self-alignment error, attitude error under
// single-axis rotation with one gyro misalignment, and the bank-to-turn accumulation of the
// vertical attitude error. Each one runs the real fsw code on simulator data and compares the
// simulated error with the closed-form expression.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "fsw/frames.hpp"
#include "sim/imu_model.hpp"
#include "sim/scenario.hpp"

namespace tools {

// ---- Self-alignment -----------------------------------------------------------------------------
struct AlignmentCase {
  std::string name;
  fsw::Vec3 accel_bias_b_mps2 = fsw::Vec3::Zero();
  fsw::Vec3 gyro_bias_b_radps = fsw::Vec3::Zero();
  fsw::Vec3 phi_sim_rad = fsw::Vec3::Zero();      ///< alignment error from the simulation
  fsw::Vec3 phi_formula_rad = fsw::Vec3::Zero();  ///< fsw::predicted_alignment_error
};

/// Aligns a stationary IMU (heading_rad, latitude lat_rad) with the given biases for duration_s.
AlignmentCase run_alignment_case(const std::string& name, const fsw::Vec3& accel_bias_b_mps2,
                                 const fsw::Vec3& gyro_bias_b_radps, double lat_rad, double heading_rad,
                                 double duration_s);

// ---- Single-axis rotation ------------------------------------------------------------------------
struct RotationCase {
  std::string name;       ///< e.g. "z_xz_5"
  int axis = 2;           ///< body axis rotated about (0 x, 1 y, 2 z)
  std::size_t component;  ///< gyro misalignment component index (catalogue order xy xz yx yz zx zy)
  double gamma_arcsec = 5.0;
  double rate_dps = 10.0;
  std::vector<double> t_s;
  std::vector<fsw::Vec3> phi_sim_rad;
  std::vector<fsw::Vec3> phi_formula_rad;
  double peak_formula_rad = 0.0;   ///< largest |component| of the closed form over the run
  double max_deviation_rad = 0.0;  ///< largest |sim - formula| over all components and times
};

/// Closed form (short-time, Earth-rate coupling neglected) of the attitude error when rotating at
/// rate w about body unit axis a from C_b_n0 with misalignment matrix M:
///   phi(t) = -C_b_n0 [ sin(w t) (M a) + (1 - cos(w t)) (a x M a) ]
fsw::Vec3 rotation_error_formula(const fsw::Mat3& C_b_n0, const fsw::Mat3& M, const fsw::Vec3& axis_b,
                                 double rate_radps, double t_s);

/// The (rotation axis, gyro misalignment) pairs that a single-axis rotation excites: rotating about
/// body axis j excites gamma_ij (catalogue order xy=0 xz=1 yx=2 yz=3 zx=4 zy=5).
struct RotationPair {
  int axis;
  std::size_t component;
};
inline constexpr RotationPair kExcitedRotationPairs[6] = {{2, 1}, {2, 3}, {1, 0}, {1, 5}, {0, 2}, {0, 4}};

RotationCase run_rotation_case(int axis, std::size_t component, double gamma_arcsec, double rate_dps,
                               double duration_s, double lat_rad);

// ---- Bank-to-turn -------------------------------------------------------------------------------
struct BankTurnCase {
  std::string component;  ///< xy xz yx yz zx zy
  double gamma_arcsec = 20.0;
  std::vector<double> t_s;          ///< decimated time series (every 0.5 s)
  std::vector<fsw::Vec3> phi_rad;
  std::vector<double> roll_rad;
  std::vector<double> turn_end_t_s;      ///< end of each completed turn
  std::vector<double> turn_end_phi_u_rad;
  std::vector<fsw::Vec3> turn_end_phi_rad;
  double u_error_per_turn_arcsec = 0.0;  ///< mean growth of phi_U per completed turn
  double predicted_per_turn_arcsec = 0.0;  ///< direct eq. (7) forcing of phi_U per turn
  double coupled_per_turn_arcsec = 0.0;    ///< the rest: tilt errors leaking into phi_U via Earth rate
  double tilt_per_turn_arcsec = 0.0;       ///< mean growth of the horizontal (E, N) error per turn
  double u_oscillation_arcsec = 0.0;       ///< largest excursion of phi_U from its per-turn trend
  bool accumulates = false;  ///< phi_U grows turn after turn, driven by the turns themselves
};

/// Flies the scenario free-inertially with only one gyro misalignment (vertical channel held to
/// truth: an ideal altimeter, since unaided height diverges) and measures phi_U turn by turn.
BankTurnCase run_bank_turn_case(const sim::Scenario& sc, std::size_t component, double gamma_arcsec);
/// The same for several components (misalignment indices), in `groups` groups side by side
/// (tools::for_each_parallel): each group flies its cases through one truth generator
/// (run_free_inertial of several flights), so the truth is integrated once per group, not per
/// case. Each case is the one run_bank_turn_case gives, bit for bit, in the order of components.
std::vector<BankTurnCase> run_bank_turn_cases(const sim::Scenario& sc, const std::vector<std::size_t>& components,
                                              double gamma_arcsec, int groups);

}  // namespace tools
