// Software-in-the-loop Monte Carlo of the tightly coupled filters: truth simulator -> IMU and GPS
// error models -> raw receiver epochs and IMU samples -> fsw::FlightApp (15- and/or 24-state
// model, the same inputs for both; the flight application SIL, HIL and replay fly), with the
// statistics across runs that the paper's figures show.
//
// The truth trajectory does not depend on the seed, so it is generated once (sim::TruthTrack)
// and shared by every run's sensor stream (sim::SensorStream, the one every simulated run reads);
// each run draws its own IMU errors, GPS errors, clock and initial errors from
// seed = scenario seed + run index. Results are kept per run and reduced in run order, so
// the statistics are bit-identical for any number of threads or MPI ranks.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "cfg/flight_config.hpp"
#include "fsw/executive.hpp"
#include "fsw/filter_model.hpp"
#include "fsw/flight_app.hpp"
#include "sim/almanac.hpp"
#include "sim/imu_model.hpp"
#include "sim/scenario.hpp"
#include "sim/sensor_stream.hpp"
#include "sim/trajectory.hpp"

namespace tools {

/// The models (fsw/filter_model.hpp): k15, the 15-state model with the misalignments as Schmidt
/// consider states (consistent); k15c, the conventional 15-state model that ignores them, with the
/// paper's sensor noise only (untuned: grossly overconfident); k15t, the same conventional model
/// tuned once the way a practitioner would, its gyro noise raised (MonteCarloConfig::tuned15t_*)
/// until its NEES is consistent; k24: 24 states.
struct MonteCarloConfig {
  int runs = 100;
  int first_run = 0;               ///< run indices first_run .. first_run + runs - 1
  std::vector<fsw::FilterModel> models{fsw::FilterModel::k15, fsw::FilterModel::k24};
  int threads = 0;                 ///< 0: all hardware threads
  double init_pos_sigma_m = 5.0;   ///< per axis, drawn per run
  double init_vel_sigma_mps = 0.1; ///< per axis, drawn per run
  /// The tuned conventional 15-state filter (k15t): angle random walk and gyro-bias random walk
  /// that replace arw_rad_per_rts / the zero bias random walk for that model only. Set once per
  /// misalignment specification by `sdins paper --tune-15t` (docs/paper-verdict.md), not per run;
  /// the default is the value for the default scenario's 5 arcsec (32x the paper's ARW).
  double tuned15t_arw_rad_per_rts = 6.4e-6;
  double tuned15t_gyro_bias_rw_radps_per_rts = 0.0;
  /// Carry the GPS model's time-correlated errors as per-channel states (Layout15Full/24Full); false:
  /// the paper's plain layouts with the total error as white measurement noise.
  bool model_gps_errors = true;
  /// The flight configuration under the scenario overlay (executive_config): empty, the shipped
  /// config/default.toml (cfg::shipped_flight_config); set by `--flight-config FILE` of
  /// `sdins montecarlo` / `sdins paper` (tools::monte_carlo_flight_config).
  std::optional<cfg::FlightConfig> flight;
};

/// The flight configuration of `--filter-config FILE` for the Monte Carlo (the shipped file with
/// FILE on top; empty path: nullopt, the shipped file). Throws std::runtime_error with the file's
/// error, or when the file asks for a GNSS input the simulation does not produce (gnss.source
/// other than "raw": the Monte Carlo flies raw receiver epochs).
std::optional<cfg::FlightConfig> monte_carlo_flight_config(const std::string& path);

/// The executive configuration the Monte Carlo flies for a scenario: the shipped flight
/// configuration (config/default.toml, cfg::shipped_flight_config) with the scenario overlay on
/// top, the one place where a harness departs from that file (listed in config/README.md). The
/// overlay is what follows from the scenario the runs draw their sensors from: the IMU samples per
/// frame and the EKF rate (the scenario's IMU and GPS rates), the initial sigmas (the drawn initial
/// errors, the scenario's bias sigmas through the self-alignment formulas), the misalignment and
/// scale-factor sigmas (the scenario's, per misalignment level), the receiver clock's process noise
/// (the scenario's h0 / h_-2) and the GPS error model (the scenario's Gauss-Markov and white parts).
/// Everything else (the navigation rate, noise, gate, clock sigmas, guards) is the file's.
fsw::ExecutiveConfig executive_config(const sim::Scenario& sc, const MonteCarloConfig& mc);

/// The flight application's configuration for the Monte Carlo (and the paper and the timing
/// audit): the shipped file's, with executive_config's executive and InitMode::kGiven with its
/// initial sigmas, so every run starts from initial_nav_state through FlightApp::start_given and
/// then flies the same flight application as SIL, HIL and replay.
fsw::FlightAppConfig flight_app_config(const sim::Scenario& sc, const MonteCarloConfig& mc);
/// The configuration of one model: `base` (flight_app_config), with the k15t tuning
/// (MonteCarloConfig::tuned15t_*) for FilterModel::k15t.
fsw::FlightAppConfig model_config(const fsw::FlightAppConfig& base, const MonteCarloConfig& mc, fsw::FilterModel model);
/// The overlaid configuration of every model (model_config of flight_app_config) checked against
/// the flight software's rules (cfg::validate): throws std::runtime_error naming the overlay, the
/// file under it, the key, the value and the rule. run_many calls it before the first run.
void validate_overlay(const sim::Scenario& sc, const MonteCarloConfig& mc);

/// The executive's initial solution for a run: truth at t = 0 with the attitude error that
/// self-alignment leaves for the run's IMU biases and drawn position / velocity errors (seed: the
/// run's seed).
fsw::NavState initial_nav_state(const sim::TruthTrack& truth, const sim::ImuErrors& errors, const MonteCarloConfig& mc,
                                std::uint64_t seed);

/// Per-epoch quantities of one run and one model, after the epoch's feedback.
struct EpochRecord {
  float resid_att_rad[3];   ///< attitude error after feedback (INS error minus estimate, eq. 12)
  float pos_err_m[3];
  float vel_err_mps[3];
  float sigma_att_rad[3];   ///< filter sigma of phi
  float sigma_pos_m[3];
  float sigma_vel_mps[3];
  float nees;               ///< 9-state navigation NEES (position, velocity, attitude)
  float nees_att;           ///< 3-state attitude NEES
};

/// End-of-run estimates of the sensor errors (truth minus final compensation, i.e. the residual)
/// and the filter's sigma for them, in the layout's order of the sensor blocks.
struct SensorResidual {
  std::string name;   ///< e.g. "gyro_mis.yz"
  double residual = 0.0;
  double initial_sigma = 0.0;
  double sigma = 0.0;
  std::string unit;
  bool estimated = true;  ///< false for a Schmidt consider state (the filter carries but never corrects it)
};

struct RunResult {
  int run = 0;
  std::uint64_t seed = 0;
  std::vector<std::vector<EpochRecord>> epochs;  ///< [model][epoch]
  std::vector<std::vector<SensorResidual>> sensors;  ///< [model][state]
  /// [model]: the filter's final covariance of the sensor states, row-major k x k in the units and
  /// order of sensors[model].
  std::vector<std::vector<double>> sensor_cov;
  std::vector<fsw::ExecutiveHealth> health;      ///< [model]
  double wall_sim_s = 0.0;   ///< IMU and GPS error models
  double wall_mech_s = 0.0;  ///< 200 Hz rate group (all models)
  double wall_ekf_s = 0.0;   ///< ticks in which the 1 Hz EKF ran (all models), minus a mechanization frame
};

/// Flies one run (index `run`) through all models of the config.
RunResult run_one(const sim::Scenario& sc, const sim::TruthTrack& truth, const std::vector<sim::AlmanacEntry>& almanac,
                  const MonteCarloConfig& mc, int run);

/// Runs runs [first_run, first_run + runs) on `threads` threads; results in run order.
std::vector<RunResult> run_many(const sim::Scenario& sc, const sim::TruthTrack& truth,
                                const std::vector<sim::AlmanacEntry>& almanac, const MonteCarloConfig& mc);

/// Statistics across runs for one model.
struct ModelStats {
  fsw::FilterModel model = fsw::FilterModel::k15;
  int runs = 0;
  std::vector<double> t_s;
  std::vector<int> turning;                    ///< 1 while the aircraft turns
  std::vector<std::array<double, 3>> att_mean_rad, att_std_rad, att_filter_sigma_rad;
  std::vector<double> pos_rms_m, vel_rms_mps, pos_filter_sigma_m, vel_filter_sigma_mps;
  std::vector<double> nees_mean, nees_att_mean;
  double mean_nees = 0.0;        ///< time average of nees_mean over t >= nees_from_s
  double mean_nees_att = 0.0;
  double nees_from_s = 0.0;
  int nees_epochs = 0;           ///< epochs at t >= nees_from_s; 0: NEES not measured (mean_nees NaN)
  bool nees_measured() const { return nees_epochs > 0; }
  std::array<double, 2> nees_bounds{};      ///< 95% bounds of the run-averaged 9-dof NEES
  std::array<double, 2> nees_att_bounds{};  ///< ... of the 3-dof attitude NEES
  std::vector<SensorResidual> sensors;      ///< residual = RMS across runs, sigma = mean filter sigma
  std::vector<double> sensor_cov;           ///< mean across runs of RunResult::sensor_cov
  std::vector<std::vector<double>> sensor_residuals;  ///< [run][state]: truth minus final compensation
  fsw::ExecutiveHealth health{};            ///< summed over runs
};

/// One direction in the space of the misalignment states (normalised by their initial sigmas)
/// along which the filter's final covariance has an eigenvalue: the combinations the manoeuvres
/// make observable are those whose sigma fell well below the initial one.
struct MisalignmentCombination {
  std::vector<std::pair<std::string, double>> terms;  ///< (state, coefficient), |coef| >= 0.1, unit vector
  std::string label;          ///< e.g. "+0.71 gyro_mis.yz +0.70 gyro_mis.zy"
  double initial_sigma = 0.0; ///< [arcsec] along the direction (all misalignments share one unit)
  double final_sigma = 0.0;   ///< [arcsec] filter sigma along the direction
  double rms_residual = 0.0;  ///< [arcsec] RMS across runs of the residual projected on it
  bool observable = false;    ///< final_sigma <= kObservableSigmaRatio * initial_sigma
};
inline constexpr double kObservableSigmaRatio = 0.5;

/// Eigen-directions of the mean final misalignment covariance, most reduced first. Empty when
/// the model estimates no misalignment.
std::vector<MisalignmentCombination> misalignment_combinations(const ModelStats& s);

ModelStats reduce(const std::vector<RunResult>& results, std::size_t model_index, fsw::FilterModel model,
                  const sim::TruthTrack& truth);

/// Two-sided 95% bounds of the average of `runs` independent chi-square(dof) variables.
std::array<double, 2> chi2_mean_bounds(int dof, int runs);

/// Writes the per-epoch statistics as CSV (degrees for attitude).
void write_stats_csv(const ModelStats& s, const std::string& path);

}  // namespace tools
