// The IMU's mounting on the vehicle from the direction of travel (issue 26; docs/diagnosis.md, "The
// mounting").
//
// A vehicle whose velocity lies along its own body x axis (a car, a walker facing where they walk,
// an aircraft without sideslip or angle of attack) travels, seen from an IMU mounted at an angle,
// along a fixed direction of the IMU's axes. The navigation solution carries the IMU's attitude
// (levelled, then corrected by the filter), so the velocity turned into the IMU's axes,
// u = C_b_n^T v_n / |v|, gives that direction at every epoch at speed:
//   yaw   = atan2(-u_y, u_x)   the mounting yaw: the IMU's heading minus the track (x forward, y
//                              right, z down: positive with the IMU's x axis right of the travel)
//   pitch = asin(u_z)          the mounting pitch: the IMU's pitch above the flight path (positive
//                              with the IMU's nose up against the direction of travel)
// i.e. the rotation C_s_b = Ry(pitch) Rz(yaw) of the sensor axes against the vehicle's; for a yaw or
// a pitch alone these are the simulator's ImuConfig::mounting_rpy_deg. A rotation about the direction
// of travel itself (a roll of the mounting; the "pitch" of a sensor turned 90 deg in yaw) does not
// move u: it is not determined here.
//
// The estimate is the mean over the epochs used. Its 95% interval adds two parts:
//  - the scatter: the means of 6 consecutive blocks of the epochs, their standard error with the
//    Student t quantile (5 dof). Few, long blocks keep their means close to independent where the
//    epochs are correlated (a walker's sway, a turn, the filter's own wander): on first-order
//    autoregressive series of 300 epochs it covers 94% at a correlation of 0.8 per epoch and 93% at
//    0.9, where 20 blocks covered 83% and a plain standard error over the epochs about half;
//  - the attitude: the filter's own attitude sigma mapped onto each angle, RMS over the epochs, and
//    taken as fully correlated (an attitude error does not average out over a recording).
// It fails where the vehicle's velocity is not along its x axis on average: an aircraft's angle of
// attack adds to the pitch and a crab angle in a crosswind to the yaw, a car's sideslip in turns
// (small) to the yaw. The first and the second half of the recording are reported apart as a check.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tools/diagnosis_model.hpp"

namespace tools {

/// chi-square(1) at p = 0.001: the threshold of both mounting estimates (the initial heading
/// profile's deviance, tools/diagnosis_chain.hpp, and an angle's z^2 here).
inline constexpr double kMountingDeviance = 10.827566170662733;

/// One angle of the mounting.
struct MountingAngle {
  double estimate_deg = 0.0;
  double lo_deg = 0.0, hi_deg = 0.0;     ///< 95%
  double sigma_deg = 0.0;                ///< sqrt(scatter_se^2 + attitude_sigma^2)
  double scatter_se_deg = 0.0;           ///< standard error of the mean from the block means
  double attitude_sigma_deg = 0.0;       ///< the filter's attitude sigma on this angle, RMS
  double spread_deg = 0.0;               ///< standard deviation of the epochs' values
  double first_half_deg = 0.0, second_half_deg = 0.0;  ///< means of the two halves of the epochs
  double z2 = 0.0;                       ///< (estimate / sigma)^2
  bool named = false;                    ///< z2 above kMountingDeviance (the interval at p = 0.001 excludes 0)
};

/// The mounting from the direction of travel (above).
struct MountingFromTravel {
  bool determined = false;  ///< enough epochs at speed (kMountingMinEpochs); otherwise `why`
  std::string why;
  bool found = false;       ///< yaw or pitch named
  MountingAngle yaw, pitch;
  int epochs = 0;           ///< epochs used
  int blocks = 0;
  double min_speed_mps = 0.0;  ///< the speed threshold used
  double t_quantile = 0.0;     ///< Student t, 97.5%, blocks - 1 dof
  double heading_offset_configured_deg = 0.0;  ///< init.heading_offset_deg of the run
  bool track_init = false;     ///< the initialisation uses the track: applied to init.heading_offset_deg
};

/// Epochs used: GNSS-updated navigation epochs from kProfileBurnIn_s after initialisation at a speed
/// of at least max(kMountingMinSpeed_mps, kMountingSpeedSigmas x the filter's horizontal velocity sigma).
inline constexpr double kMountingMinSpeed_mps = 0.5;
inline constexpr double kMountingSpeedSigmas = 5.0;
inline constexpr int kMountingMinEpochs = 20;
inline constexpr int kMountingBlocks = 6;

/// Runs the baseline model (every catalogue component frozen) over the recording and estimates the
/// mounting from the direction of travel in the IMU's axes.
MountingFromTravel estimate_mounting_from_travel(const RecordedData& data, const DiagnosisConfig& cfg);

/// The estimate from per-epoch yaw/pitch values [deg] and their attitude sigmas [deg] (the part
/// above that needs no flight: tested alone). Yaw values are unwrapped about their circular mean.
MountingFromTravel mounting_from_samples(const std::vector<double>& yaw_deg, const std::vector<double>& pitch_deg,
                                         const std::vector<double>& yaw_att_sigma_deg,
                                         const std::vector<double>& pitch_att_sigma_deg);

/// The JSON object (docs/diagnosis.md, "The mounting").
nlohmann::json mounting_json(const MountingFromTravel& m);
/// One line per angle for the terminal ("mounting yaw (direction of travel): ...").
std::vector<std::string> mounting_terminal_lines(const MountingFromTravel& m);
/// The report.md paragraph.
std::string mounting_report_md(const MountingFromTravel& m);

}  // namespace tools
