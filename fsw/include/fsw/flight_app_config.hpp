// The flight application's configuration and health counters (fsw/flight_app.hpp), in their own
// header so that the application's units share them without including the application: the
// initialisation (fsw/initialiser.hpp) and the configuration rules (fsw/config_check.hpp).
// InitMode's meaning: fsw/initialiser.hpp.
#pragma once

#include <cstdint>

#include "fsw/executive.hpp"
#include "fsw/gnss_pvt.hpp"
#include "fsw/gps_orbit.hpp"

namespace fsw {

/// How the flight application gets its initial attitude (see the file header).
enum class InitMode : std::uint8_t {
  kTrack,             ///< in motion: heading = GNSS track + init_heading_offset_rad, levelling
  kStatic,            ///< at rest: levelling + gyrocompassing over alignment_s
  kVelocityMatching,  ///< in motion: IMU-integrated velocity matched to GNSS velocities (Wahba)
  kGiven,             ///< the harness gives the initial state: FlightApp::start_given() (see the file header)
};
inline const char* to_string(InitMode m) {
  switch (m) {
    case InitMode::kTrack: return "track";
    case InitMode::kStatic: return "static";
    case InitMode::kVelocityMatching: return "velocity_matching";
    case InitMode::kGiven: return "given";
  }
  return "unknown";
}

/// The most IMU samples the levelling averages (FlightAppConfig::levelling_samples).
inline constexpr int kMaxLevellingSamples = 1024;

struct FlightAppConfig {
  ExecutiveConfig exec{};  ///< exec.ekf's pos/vel/att sigmas are replaced by the init_* below
  int min_satellites_for_init = 5;
  double max_init_pdop = 6.0;
  double min_init_speed_mps = 20.0;
  int levelling_samples = 200;                      ///< IMU samples averaged for roll and pitch
  double init_pos_sigma_m = 30.0;
  double init_vel_sigma_mps = 1.0;
  Vec3 init_att_sigma_rad = Vec3(0.2, 0.2, 1.0) * kDegToRad;  ///< roll/pitch (levelling), heading (velocity)
  /// Heading of body x minus the GNSS track at initialisation (a sensor mounted at a yaw angle to
  /// the direction of travel) [rad]; used by both initialisations.
  double init_heading_offset_rad = 0.0;
  /// Solutions with quality (RTKLIB Q) outside 1..pvt_max_quality are rejected.
  int pvt_max_quality = 6;

  InitMode init_mode = InitMode::kTrack;
  // kStatic (and the rest detection of kVelocityMatching).
  double alignment_s = 60.0;                ///< stationary samples needed (kStatic) [s]
  double static_max_speed_mps = 0.2;        ///< an epoch at or below this ground speed is at rest
  double static_max_rate_dev_radps = 0.1 * kDegToRad;  ///< interval mean rate vs window mean
  double static_max_accel_dev_mps2 = 0.1;   ///< interval mean specific force vs window mean
  // kVelocityMatching.
  double vm_min_s = 2.0;                    ///< shortest window [s]
  double vm_max_s = 20.0;                   ///< a window without a determined heading restarts [s]
  double vm_max_heading_sigma_rad = 3.0 * kDegToRad;  ///< heading sigma that ends the window
  bool vm_rest_gyro_bias = true;            ///< subtract the rest window's mean rate
  double vm_rest_min_s = 1.0;               ///< rest needed for that estimate [s]
};

struct FlightAppHealth {
  std::uint32_t imu_received = 0;
  std::uint32_t imu_before_init = 0;     ///< used for levelling only
  std::uint32_t imu_rejected = 0;        ///< non-finite samples (levelling) or time not after the INS
  std::uint32_t gnss_received = 0;
  std::uint32_t gnss_rejected = 0;       ///< malformed raw epochs
  std::uint32_t gnss_before_init = 0;    ///< epochs that did not (yet) initialise
  std::uint32_t init_no_fix = 0;         ///< ... of which: no single-point solution / too few satellites
  std::uint32_t init_bad_geometry = 0;   ///< ... PDOP too large
  std::uint32_t init_too_slow = 0;       ///< ... speed too low for a velocity heading
  std::uint32_t init_not_level = 0;      ///< ... not enough IMU samples for levelling yet (kVelocityMatching:
                                         ///< no IMU history at the epoch's time)
  std::uint32_t init_moving = 0;         ///< ... kStatic: motion (GNSS speed or IMU) restarted the window
  std::uint32_t init_aligning = 0;       ///< ... alignment not complete yet (kStatic: window shorter than
                                         ///< alignment_s; kVelocityMatching: heading not determined yet)
  std::uint32_t init_align_restarts = 0; ///< ... kVelocityMatching: window older than vm_max_s restarted
  std::uint32_t init_align_failed = 0;   ///< ... the alignment could not be solved (degenerate data)
  std::uint32_t pvt_received = 0;
  std::uint32_t pvt_rejected = 0;        ///< quality out of range, non-finite fields, sigma <= 0
  std::uint32_t pvt_before_init = 0;     ///< solutions that did not (yet) initialise (init_* say why)
  std::uint32_t almanac_received = 0;
  std::uint32_t almanac_rejected = 0;
  GnssConversionStats conversion{};
  bool initialised = false;
  double init_t_s = 0.0;
  GnssPvt init_fix{};  ///< the initialising fix (from a PVT: position, velocity, n_used = n_sat, pdop 0)
  InitMode init_mode = InitMode::kTrack;
  double init_align_s = 0.0;             ///< length of the alignment window that initialised [s]
  Vec3 init_att_sigma_rad = Vec3::Zero();  ///< phi_E, phi_N, phi_U sigma the EKF started with
  Vec3 init_euler_rad = Vec3::Zero();      ///< initial roll, pitch, heading (euler_from_C_b_n)
  Vec3 vm_gyro_bias_radps = Vec3::Zero();  ///< kVelocityMatching: gyro bias (rest estimate + window's)
  Vec3 vm_accel_bias_mps2 = Vec3::Zero();  ///< kVelocityMatching: the window's accelerometer bias estimate
};

}  // namespace fsw
