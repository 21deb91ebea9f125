// The flight application: everything between the decoded sensor inputs and the navigation
// output, the same in SIL (simulator in-process), HIL (CAN bus) and replay (LCM log).
//
//   on_almanac(GpsAlmanac)   -> the almanac table (flight code validates every element)
//   on_gnss(GnssRawEpoch)    -> satellite positions from the almanac (gnss_epoch_from_raw); before
//                               initialisation: a single-point solution that may initialise
//   on_gnss_pvt(GnssPvtMeasurement) -> a position/velocity solution (loosely coupled update);
//                               before initialisation: may initialise (land vehicles)
//   on_imu(ImuSample)        -> before initialisation: levelling; after: batched into the
//                               executive's minor frames (200 Hz mechanization, 1 Hz EKF)
//
// In-motion initialisation (no host, no ground alignment): at the first epoch with at least
// min_satellites_for_init satellites, PDOP <= max_init_pdop and a speed >= min_init_speed_mps,
// position and velocity come from the single-point solution, roll and pitch from the mean
// specific force of the last levelling_samples IMU samples (unaccelerated flight), heading from
// the GNSS velocity (zero sideslip). The EKF starts with the configured uncertainty of that
// initialisation and removes the rest once the turns make heading observable.
//
// From a position/velocity solution (on_gnss_pvt, e.g. a car with an RTK receiver): with
// has_velocity, a ground speed >= min_init_speed_mps (a car can use 3 m/s) and the levelling
// samples, position = the antenna's moved back by the lever arm (exec.ekf.lever_arm_b_m, rotated
// with the initial attitude), velocity = the solution's, heading = the GNSS track plus
// init_heading_offset_rad, roll and pitch from levelling. Heading from the track assumes the
// vehicle moves along body x (no sideslip: true for cars and aircraft; a sensor mounted at a yaw
// angle to the direction of travel states that angle in init_heading_offset_rad); levelling
// assumes no acceleration over the levelling window. After initialisation the solutions go to
// the executive; raw epochs and solutions may both arrive, the executive uses what it gets.
#pragma once

#include <array>
#include <cstdint>

#include "fsw/executive.hpp"
#include "fsw/gnss_pvt.hpp"
#include "fsw/gps_orbit.hpp"

namespace fsw {

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
  std::uint32_t init_not_level = 0;      ///< ... not enough IMU samples for levelling yet
  std::uint32_t pvt_received = 0;
  std::uint32_t pvt_rejected = 0;        ///< quality out of range, non-finite fields, sigma <= 0
  std::uint32_t pvt_before_init = 0;     ///< solutions that did not (yet) initialise (init_* say why)
  std::uint32_t almanac_received = 0;
  std::uint32_t almanac_rejected = 0;
  GnssConversionStats conversion{};
  bool initialised = false;
  double init_t_s = 0.0;
  GnssPvt init_fix{};  ///< the initialising fix (from a PVT: position, velocity, n_used = n_sat, pdop 0)
};

template <class Layout>
class FlightApp {
 public:
  Status init(const FlightAppConfig& cfg);
  Status on_almanac(const GpsAlmanac& sat);
  Status on_gnss(const GnssRawEpoch& raw);
  /// One GNSS position/velocity solution. kBadInput (counted in pvt_rejected) when invalid.
  Status on_gnss_pvt(const GnssPvtMeasurement& m);
  /// One IMU sample. out.nav_valid is set when the sample completed a minor frame.
  Status on_imu(const ImuSample& s, FrameOutput& out);
  /// Measured execution time of the previous tick, passed to the executive (real-time mode).
  void set_prev_tick_exec_s(double s) { prev_tick_exec_s_ = s; }

  bool initialised() const { return health_.initialised; }
  const Executive<Layout>& executive() const { return exec_; }
  const FlightAppHealth& health() const { return health_; }
  const GpsAlmanacTable& almanac() const { return almanac_; }

 private:
  Status try_initialise(const GnssEpoch& epoch);
  Status try_initialise_pvt(const GnssPvtMeasurement& m);
  /// Roll and pitch [rad] from the mean specific force of the levelling samples.
  void levelled_roll_pitch(double& roll, double& pitch) const;

  static constexpr int kMaxLevelling = 1024;
  FlightAppConfig cfg_{};
  bool configured_ = false;
  Executive<Layout> exec_{};
  GpsAlmanacTable almanac_{};
  FlightAppHealth health_{};
  std::array<Vec3, kMaxLevelling> level_dv_{};
  std::array<double, kMaxLevelling> level_dt_{};
  int level_head_ = 0;
  int level_count_ = 0;
  std::array<ImuSample, FrameBuilder::kMaxSamplesPerFrame> batch_{};
  int n_batch_ = 0;
  GnssEpoch epoch_{};
  bool have_epoch_ = false;
  GnssPvtMeasurement pvt_{};
  bool have_pvt_ = false;
  double prev_tick_exec_s_ = -1.0;
};

extern template class FlightApp<Layout15Full>;
extern template class FlightApp<Layout24Full>;
extern template class FlightApp<LayoutDiag>;

}  // namespace fsw
