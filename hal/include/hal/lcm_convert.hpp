// Conversions between the flight software's types and the LCM messages (hal/lcm/*.lcm).
//
// Flight-side direction (to_msg: navigation solution, EKF state, health; and the raw inputs for
// logging): fills a caller-owned message, no allocation (every message type has fixed-size
// arrays only), no exceptions.
// Input direction (decode_exact + from_msg: IMU samples, raw GNSS epochs, almanac): checks the
// bytes (exact encoded size, fingerprint of the expected type), then the values (NaN/Inf,
// out-of-range, sensor status), and returns a status; the caller counts it in LcmInputStats.
// For valid input, to_msg followed by from_msg reproduces the fsw struct bit for bit, so a log
// replays exactly what the flight software received.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "fsw/ekf.hpp"
#include "fsw/error_state.hpp"
#include "fsw/executive.hpp"
#include "fsw/gps_orbit.hpp"
#include "fsw/strapdown.hpp"
#include "sdins/ekf_state_t.hpp"
#include "sdins/filter_health_t.hpp"
#include "sdins/gnss_pvt_t.hpp"
#include "sdins/gnss_raw_epoch_t.hpp"
#include "sdins/gps_almanac_t.hpp"
#include "sdins/imu_sample_t.hpp"
#include "sdins/nav_solution_t.hpp"
#include "sdins/truth_t.hpp"

namespace hal {

/// What became of one received message (decode + validation).
enum class LcmInputStatus : std::uint8_t {
  kOk = 0,
  kMeasurementsDropped,  ///< GNSS epoch accepted, but non-finite measurements were removed from it
  kDecodeFailed,         ///< too short, or its length is not the type's encoded size
  kWrongType,            ///< fingerprint of another type (or of no known type)
  kNonFinite,            ///< NaN or Inf in a field the flight software uses
  kOutOfRange,           ///< a value outside its plausible range (see the from_msg comments)
  kSensorFlagged,        ///< IMU status bits say the gyro or accelerometer data are invalid
  kCount
};

const char* to_string(LcmInputStatus s);

/// Counts of every input status; accepted() = ok + measurements dropped.
struct LcmInputStats {
  std::uint64_t by_status[static_cast<int>(LcmInputStatus::kCount)] = {};
  std::uint64_t measurements_dropped = 0;  ///< GNSS measurements removed from accepted epochs

  void record(LcmInputStatus s) { ++by_status[static_cast<int>(s)]; }
  std::uint64_t count(LcmInputStatus s) const { return by_status[static_cast<int>(s)]; }
  std::uint64_t accepted() const { return count(LcmInputStatus::kOk) + count(LcmInputStatus::kMeasurementsDropped); }
  std::uint64_t rejected() const;
};

/// Microseconds on the navigation time scale: round(t_s * 1e6); INT64_MIN for a non-finite or
/// unrepresentable time.
std::int64_t utime_from_t_s(double t_s);

/// The 64-bit fingerprint LCM puts in the first 8 bytes of every message (big-endian); 0 when
/// fewer than 8 bytes.
std::int64_t lcm_fingerprint(const void* data, std::size_t len);

/// Decodes data into msg when it is exactly one message of type Msg.
template <class Msg>
LcmInputStatus decode_exact(const void* data, std::size_t len, Msg& msg) {
  if (data == nullptr || len < 8) return LcmInputStatus::kDecodeFailed;
  if (lcm_fingerprint(data, len) != Msg::getHash()) return LcmInputStatus::kWrongType;
  if (len > 0x7fffffffu) return LcmInputStatus::kDecodeFailed;
  const int n = msg.decode(data, 0, static_cast<int>(len));
  if (n < 0 || static_cast<std::size_t>(n) != len) return LcmInputStatus::kDecodeFailed;
  return LcmInputStatus::kOk;
}

// ---------------------------------------------------------------------------------------------
// Raw inputs

/// One IMU sample as it travels: the fsw sample plus the sensor's counter and status bits.
struct ImuRecord {
  fsw::ImuSample sample{};
  std::int32_t counter = 0;
  std::int16_t status = 0;  ///< sdins::imu_sample_t::STATUS_* bits
};

/// Plausibility limits of an IMU sample (per-sample increments are checked against rate * dt).
struct ImuInputLimits {
  double max_dt_s = 1.0;             ///< 0 < dt_s <= max_dt_s
  double max_rate_radps = 100.0;     ///< |dtheta| <= max_rate * dt (about 5700 deg/s)
  double max_accel_mps2 = 2000.0;    ///< |dv| <= max_accel * dt (about 200 g)
};

void to_msg(const ImuRecord& in, sdins::imu_sample_t& out);
/// kNonFinite: any of t_s, dt_s, dtheta, dv; kOutOfRange: dt_s or an increment outside
/// ImuInputLimits; kSensorFlagged: STATUS_GYRO_INVALID or STATUS_ACCEL_INVALID set (saturation
/// and BIT bits are passed through in out.status).
LcmInputStatus from_msg(const sdins::imu_sample_t& in, ImuRecord& out, const ImuInputLimits& limits = {});

void to_msg(const fsw::GnssRawEpoch& in, sdins::gnss_raw_epoch_t& out);
/// Epoch level: kNonFinite for t_s or gps_tow_s; kOutOfRange for n_meas outside 0..16,
/// gps_tow_s outside [0, 604800), gps_week < 0, or a valid entry's PRN outside 0..255 (fsw holds
/// it in a uint8). Measurement level: an entry with a non-finite pseudorange, rate or C/N0 is
/// removed (the later entries move up, order kept) and counted in n_dropped; the result is then
/// kMeasurementsDropped. The flight software would leave such a measurement out anyway
/// (fsw::gnss_epoch_from_raw), so the navigation output is the same. Entries beyond n_meas are
/// copied verbatim (bit-exact round trip) unless entries were removed (then they are zero).
LcmInputStatus from_msg(const sdins::gnss_raw_epoch_t& in, fsw::GnssRawEpoch& out, int& n_dropped);

void to_msg(const fsw::GpsAlmanac& in, double t_s, sdins::gps_almanac_t& out);
/// kNonFinite for any non-finite element or t_s; kOutOfRange when fsw::almanac_valid() fails
/// (PRN 1..32, eccentricity, sqrt(A), angles, clock terms, toa).
LcmInputStatus from_msg(const sdins::gps_almanac_t& in, fsw::GpsAlmanac& out);

// ---------------------------------------------------------------------------------------------
// GNSS position/velocity solutions (channel GNSS_PVT)

/// One GNSS position/velocity solution as decoded from GNSS_PVT (sdins.gnss_pvt_t): e.g. a line of
/// an RTKLIB .pos file. Host-side input type; to_fsw() gives the flight software's measurement.
struct GnssPvtSample {
  double t_s = 0.0;                     ///< navigation time scale [s]
  int gps_week = 0;                     ///< GPS time of the solution: full week ...
  double gps_tow_s = 0.0;               ///< ... and seconds of the week
  fsw::Vec3 llh = fsw::Vec3::Zero();    ///< WGS-84 latitude, longitude [rad], ellipsoidal height [m]
  fsw::Vec3 vel_enu_mps = fsw::Vec3::Zero();
  fsw::Vec3 pos_sigma_enu_m = fsw::Vec3::Zero();
  /// All three negative (kGnssPvtNoVelocity): the solution has no velocity (vel_enu_mps is 0).
  fsw::Vec3 vel_sigma_enu_mps = fsw::Vec3::Zero();
  int quality = 0;                      ///< sdins::gnss_pvt_t::QUALITY_* (RTKLIB Q)
  int n_sat = 0;
  bool has_velocity() const { return vel_sigma_enu_mps.x() >= 0.0; }
};

/// vel_sigma_enu_mps of a solution without velocity.
inline constexpr double kGnssPvtNoVelocity = -1.0;

/// The flight software's measurement of a solution (fsw::GnssPvtMeasurement, the input of the
/// loosely coupled update): the same values; a solution without velocity has has_velocity false.
inline fsw::GnssPvtMeasurement to_fsw(const GnssPvtSample& s) {
  fsw::GnssPvtMeasurement m;
  m.t_s = s.t_s;
  m.gps_week = s.gps_week;
  m.gps_tow_s = s.gps_tow_s;
  m.llh = s.llh;
  m.vel_enu_mps = s.vel_enu_mps;
  m.pos_sigma_enu_m = s.pos_sigma_enu_m;
  m.vel_sigma_enu_mps = s.vel_sigma_enu_mps;
  m.has_velocity = s.has_velocity();
  m.quality = s.quality;
  m.n_sat = s.n_sat;
  return m;
}

/// The solution of a measurement (the inverse of to_fsw: to_fsw keeps every field, the velocity
/// sigmas of a solution without velocity included, so the round trip is exact).
inline GnssPvtSample from_fsw(const fsw::GnssPvtMeasurement& m) {
  GnssPvtSample s;
  s.t_s = m.t_s;
  s.gps_week = m.gps_week;
  s.gps_tow_s = m.gps_tow_s;
  s.llh = m.llh;
  s.vel_enu_mps = m.vel_enu_mps;
  s.pos_sigma_enu_m = m.pos_sigma_enu_m;
  s.vel_sigma_enu_mps = m.has_velocity ? m.vel_sigma_enu_mps : fsw::Vec3::Constant(kGnssPvtNoVelocity);
  s.quality = m.quality;
  s.n_sat = m.n_sat;
  return s;
}

/// Plausibility limits of a GNSS solution.
struct GnssPvtLimits {
  double min_height_m = -1000.0;
  double max_height_m = 100000.0;
  double max_speed_mps = 10000.0;
  double max_pos_sigma_m = 1.0e5;
  double max_vel_sigma_mps = 1.0e4;
};

void to_msg(const GnssPvtSample& in, sdins::gnss_pvt_t& out);
/// kNonFinite: any of t_s, gps_tow_s, llh, velocity, sigmas; kOutOfRange: gps_week < 0,
/// gps_tow_s outside [0, 604800), |lat| > pi/2, |lon| > pi, height or speed outside GnssPvtLimits,
/// a position sigma negative or above the limit, velocity sigmas neither all >= 0 (and within the
/// limit) nor all negative (no velocity, then the velocity must be 0), quality outside 0..7,
/// n_sat outside 0..255.
LcmInputStatus from_msg(const sdins::gnss_pvt_t& in, GnssPvtSample& out, const GnssPvtLimits& limits = {});

// ---------------------------------------------------------------------------------------------
// Flight-software outputs

/// valid: a navigation frame completed in this tick; ekf_updated: the EKF ran an update in it.
void to_msg(const fsw::NavState& nav, bool valid, bool ekf_updated, sdins::nav_solution_t& out);

/// Simulator truth with the same conventions as the navigation solution.
void truth_to_msg(double t_s, const fsw::Vec3& llh, const fsw::Vec3& vel_enu_mps, const fsw::Mat3& C_b_n,
                  sdins::truth_t& out);

/// A reference position and velocity without attitude (e.g. an RTK solution used as the reference
/// of a recording): attitude fields are NaN.
void reference_to_msg(double t_s, const fsw::Vec3& llh, const fsw::Vec3& vel_enu_mps, sdins::truth_t& out);

/// The non-template part of the EKF state: the accumulated IMU compensation.
void compensation_to_msg(const fsw::ImuCompensation& comp, sdins::ekf_state_t& out);

/// EKF model, estimates (IMU compensation, clock) and the 1-sigma of every state: the executive's
/// published output of one epoch (fsw::EkfOutput, time out.t_s).
template <class Layout>
void to_msg(const fsw::EkfOutput<Layout>& ekf, const fsw::ImuCompensation& comp, sdins::ekf_state_t& out) {
  constexpr int N = Layout::kSize;
  static_assert(N <= static_cast<int>(sizeof(out.sigma) / sizeof(out.sigma[0])), "ekf_state_t.sigma too small");
  static_assert(fsw::kBlockCount == static_cast<int>(sizeof(out.block_offset) / sizeof(out.block_offset[0])));
  static_assert(fsw::kGnssErrorChannels == static_cast<int>(sizeof(out.channel_prn) / sizeof(out.channel_prn[0])));
  out = sdins::ekf_state_t{};
  out.utime = utime_from_t_s(ekf.t_s);
  out.t_s = ekf.t_s;
  out.n_states = N;
  out.consider_mask = 0;
  for (int b = 0; b < fsw::kBlockCount; ++b) {
    const auto blk = static_cast<fsw::Block>(b);
    out.block_offset[b] = static_cast<std::int16_t>(Layout::offset(blk));
    if (Layout::has(blk) && Layout::is_consider(blk)) out.consider_mask |= (1 << b);
  }
  for (int i = 0; i < N; ++i) out.sigma[i] = ekf.sigma(i);  // NaN for a broken covariance: shown, not hidden
  compensation_to_msg(comp, out);
  out.clock_bias_m = ekf.clock_bias_m;
  out.clock_drift_mps = ekf.clock_drift_mps;
  out.clock_initialised = ekf.clock_initialised ? 1 : 0;
  for (int s = 0; s < fsw::kGnssErrorChannels; ++s) out.channel_prn[s] = ekf.channel_prn[s];
}

/// The same from a filter read directly at time t_s (tools that run their own Ekf).
template <class Layout>
void to_msg(const fsw::Ekf<Layout>& ekf, const fsw::ImuCompensation& comp, double t_s, sdins::ekf_state_t& out) {
  fsw::EkfOutput<Layout> o;
  ekf.output(t_s, o);
  to_msg(o, comp, out);
}

/// Executive health, conversion counters and the EKF report of the last run (frame.report,
/// frame.ekf_updated) at time t_s; gate_chi2 is the EKF's innovation gate.
void to_msg(double t_s, const fsw::ExecutiveHealth& health, const fsw::GnssConversionStats& conversion,
            const fsw::FrameOutput& frame, double gate_chi2, sdins::filter_health_t& out);

}  // namespace hal
