#include "hal/lcm_convert.hpp"

#include <limits>

#include "fsw/effect_catalogue.hpp"
#include "fsw/frames.hpp"

namespace hal {
namespace {

bool finite3(const double* v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }
double norm3(const double* v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

void attitude_to_msg(const fsw::Quat& q_b_n, double* q_wxyz, double& roll, double& pitch, double& heading) {
  q_wxyz[0] = q_b_n.w();
  q_wxyz[1] = q_b_n.x();
  q_wxyz[2] = q_b_n.y();
  q_wxyz[3] = q_b_n.z();
  const fsw::Vec3 e = fsw::euler_from_C_b_n(q_b_n.toRotationMatrix());
  roll = e.x();
  pitch = e.y();
  heading = e.z();
}

std::int8_t outcome_code(fsw::InnovationOutcome o) {
  switch (o) {
    case fsw::InnovationOutcome::kNotProcessed: return sdins::filter_health_t::OUTCOME_NOT_PROCESSED;
    case fsw::InnovationOutcome::kUsed: return sdins::filter_health_t::OUTCOME_USED;
    case fsw::InnovationOutcome::kGated: return sdins::filter_health_t::OUTCOME_GATED;
    case fsw::InnovationOutcome::kInvalid: return sdins::filter_health_t::OUTCOME_INVALID;
  }
  return sdins::filter_health_t::OUTCOME_NOT_PROCESSED;
}

}  // namespace

const char* to_string(LcmInputStatus s) {
  switch (s) {
    case LcmInputStatus::kOk: return "ok";
    case LcmInputStatus::kMeasurementsDropped: return "measurements_dropped";
    case LcmInputStatus::kDecodeFailed: return "decode_failed";
    case LcmInputStatus::kWrongType: return "wrong_type";
    case LcmInputStatus::kNonFinite: return "non_finite";
    case LcmInputStatus::kOutOfRange: return "out_of_range";
    case LcmInputStatus::kSensorFlagged: return "sensor_flagged";
    case LcmInputStatus::kCount: break;
  }
  return "unknown";
}

std::uint64_t LcmInputStats::rejected() const {
  std::uint64_t n = 0;
  for (int s = 0; s < static_cast<int>(LcmInputStatus::kCount); ++s) n += by_status[s];
  return n - accepted();
}

std::int64_t utime_from_t_s(double t_s) {
  const double us = t_s * 1e6;
  if (!std::isfinite(us) || std::abs(us) >= 9.2e18) return std::numeric_limits<std::int64_t>::min();
  return std::llround(us);
}

std::int64_t lcm_fingerprint(const void* data, std::size_t len) {
  if (data == nullptr || len < 8) return 0;
  const auto* b = static_cast<const unsigned char*>(data);
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | b[i];
  return static_cast<std::int64_t>(v);
}

// ---------------------------------------------------------------------------------------------
void to_msg(const ImuRecord& in, sdins::imu_sample_t& out) {
  out.utime = utime_from_t_s(in.sample.t_s);
  out.t_s = in.sample.t_s;
  out.dt_s = in.sample.dt_s;
  for (int i = 0; i < 3; ++i) {
    out.dtheta_rad[i] = in.sample.dtheta_rad[i];
    out.dv_mps[i] = in.sample.dv_mps[i];
  }
  out.counter = in.counter;
  out.status = in.status;
}

LcmInputStatus from_msg(const sdins::imu_sample_t& in, ImuRecord& out, const ImuInputLimits& limits) {
  if (!std::isfinite(in.t_s) || !std::isfinite(in.dt_s) || !finite3(in.dtheta_rad) || !finite3(in.dv_mps))
    return LcmInputStatus::kNonFinite;
  if (!(in.dt_s > 0.0) || in.dt_s > limits.max_dt_s || norm3(in.dtheta_rad) > limits.max_rate_radps * in.dt_s ||
      norm3(in.dv_mps) > limits.max_accel_mps2 * in.dt_s)
    return LcmInputStatus::kOutOfRange;
  constexpr int kInvalidBits = sdins::imu_sample_t::STATUS_GYRO_INVALID | sdins::imu_sample_t::STATUS_ACCEL_INVALID;
  if ((in.status & kInvalidBits) != 0) return LcmInputStatus::kSensorFlagged;
  out.sample.t_s = in.t_s;
  out.sample.dt_s = in.dt_s;
  for (int i = 0; i < 3; ++i) {
    out.sample.dtheta_rad[i] = in.dtheta_rad[i];
    out.sample.dv_mps[i] = in.dv_mps[i];
  }
  out.counter = in.counter;
  out.status = in.status;
  return LcmInputStatus::kOk;
}

// ---------------------------------------------------------------------------------------------
void to_msg(const fsw::GnssRawEpoch& in, sdins::gnss_raw_epoch_t& out) {
  static_assert(fsw::kMaxGnssChannels == static_cast<int>(sizeof(out.meas) / sizeof(out.meas[0])),
                "gnss_raw_epoch_t.meas must hold fsw::kMaxGnssChannels entries");
  out.utime = utime_from_t_s(in.t_s);
  out.t_s = in.t_s;
  out.gps_week = in.gps_week;
  out.gps_tow_s = in.gps_tow_s;
  out.n_meas = in.n_meas;
  for (int k = 0; k < fsw::kMaxGnssChannels; ++k) {
    const fsw::GnssRawMeasurement& m = in.meas[static_cast<std::size_t>(k)];
    out.meas[k].prn = m.prn;
    out.meas[k].pseudorange_m = m.pseudorange_m;
    out.meas[k].pseudorange_rate_mps = m.pseudorange_rate_mps;
    out.meas[k].cn0_dbhz = m.cn0_dbhz;
  }
}

LcmInputStatus from_msg(const sdins::gnss_raw_epoch_t& in, fsw::GnssRawEpoch& out, int& n_dropped) {
  n_dropped = 0;
  if (!std::isfinite(in.t_s) || !std::isfinite(in.gps_tow_s)) return LcmInputStatus::kNonFinite;
  if (in.n_meas < 0 || in.n_meas > fsw::kMaxGnssChannels || in.gps_week < 0 || in.gps_tow_s < 0.0 ||
      in.gps_tow_s >= fsw::kSecondsPerWeek)
    return LcmInputStatus::kOutOfRange;
  for (int k = 0; k < in.n_meas; ++k)
    if (in.meas[k].prn < 0 || in.meas[k].prn > 255) return LcmInputStatus::kOutOfRange;
  out.t_s = in.t_s;
  out.gps_week = in.gps_week;
  out.gps_tow_s = in.gps_tow_s;
  int n = 0;
  for (int k = 0; k < fsw::kMaxGnssChannels; ++k) {
    const sdins::gnss_raw_meas_t& m = in.meas[k];
    const bool in_epoch = k < in.n_meas;
    if (in_epoch &&
        (!std::isfinite(m.pseudorange_m) || !std::isfinite(m.pseudorange_rate_mps) || !std::isfinite(m.cn0_dbhz))) {
      ++n_dropped;
      continue;
    }
    if (!in_epoch && n_dropped > 0) break;  // entries were removed: the tail is cleared below
    fsw::GnssRawMeasurement& o = out.meas[static_cast<std::size_t>(n++)];
    o.prn = static_cast<std::uint8_t>(m.prn);  // valid entries checked to be 0..255; the tail is copied as is
    o.pseudorange_m = m.pseudorange_m;
    o.pseudorange_rate_mps = m.pseudorange_rate_mps;
    o.cn0_dbhz = m.cn0_dbhz;
  }
  for (int k = n; k < fsw::kMaxGnssChannels; ++k) out.meas[static_cast<std::size_t>(k)] = fsw::GnssRawMeasurement{};
  out.n_meas = in.n_meas - n_dropped;
  return n_dropped > 0 ? LcmInputStatus::kMeasurementsDropped : LcmInputStatus::kOk;
}

// ---------------------------------------------------------------------------------------------
void to_msg(const fsw::GpsAlmanac& in, double t_s, sdins::gps_almanac_t& out) {
  out.utime = utime_from_t_s(t_s);
  out.t_s = t_s;
  out.prn = in.prn;
  out.health = in.health;
  out.eccentricity = in.eccentricity;
  out.toa_s = in.toa_s;
  out.inclination_rad = in.inclination_rad;
  out.omega_dot_radps = in.omega_dot_radps;
  out.sqrt_a_sqrtm = in.sqrt_a_sqrtm;
  out.omega0_rad = in.omega0_rad;
  out.arg_perigee_rad = in.arg_perigee_rad;
  out.mean_anomaly_rad = in.mean_anomaly_rad;
  out.af0_s = in.af0_s;
  out.af1_sps = in.af1_sps;
  out.week_mod_1024 = in.week_mod_1024;
}

LcmInputStatus from_msg(const sdins::gps_almanac_t& in, fsw::GpsAlmanac& out) {
  const double values[] = {in.t_s,         in.eccentricity, in.toa_s,           in.inclination_rad,
                           in.omega_dot_radps, in.sqrt_a_sqrtm, in.omega0_rad, in.arg_perigee_rad,
                           in.mean_anomaly_rad, in.af0_s,     in.af1_sps};
  for (double v : values)
    if (!std::isfinite(v)) return LcmInputStatus::kNonFinite;
  fsw::GpsAlmanac a;
  a.prn = in.prn;
  a.health = in.health;
  a.eccentricity = in.eccentricity;
  a.toa_s = in.toa_s;
  a.inclination_rad = in.inclination_rad;
  a.omega_dot_radps = in.omega_dot_radps;
  a.sqrt_a_sqrtm = in.sqrt_a_sqrtm;
  a.omega0_rad = in.omega0_rad;
  a.arg_perigee_rad = in.arg_perigee_rad;
  a.mean_anomaly_rad = in.mean_anomaly_rad;
  a.af0_s = in.af0_s;
  a.af1_sps = in.af1_sps;
  a.week_mod_1024 = in.week_mod_1024;
  if (!fsw::almanac_valid(a)) return LcmInputStatus::kOutOfRange;
  out = a;
  return LcmInputStatus::kOk;
}

// ---------------------------------------------------------------------------------------------
namespace {
/// The fields GnssPvtSample and gnss_pvt_t share (same names on both sides), in either direction.
template <class From, class To>
void copy_pvt_fields(const From& in, To& out) {
  out.t_s = in.t_s;
  out.gps_week = in.gps_week;
  out.gps_tow_s = in.gps_tow_s;
  for (int i = 0; i < 3; ++i) {
    out.llh[i] = in.llh[i];
    out.vel_enu_mps[i] = in.vel_enu_mps[i];
    out.pos_sigma_enu_m[i] = in.pos_sigma_enu_m[i];
    out.vel_sigma_enu_mps[i] = in.vel_sigma_enu_mps[i];
  }
  out.quality = in.quality;
  out.n_sat = in.n_sat;
}
}  // namespace

void to_msg(const GnssPvtSample& in, sdins::gnss_pvt_t& out) {
  out.utime = utime_from_t_s(in.t_s);
  copy_pvt_fields(in, out);
}

LcmInputStatus from_msg(const sdins::gnss_pvt_t& in, GnssPvtSample& out, const GnssPvtLimits& limits) {
  if (!std::isfinite(in.t_s) || !std::isfinite(in.gps_tow_s) || !finite3(in.llh) || !finite3(in.vel_enu_mps) ||
      !finite3(in.pos_sigma_enu_m) || !finite3(in.vel_sigma_enu_mps))
    return LcmInputStatus::kNonFinite;
  if (in.gps_week < 0 || in.gps_tow_s < 0.0 || in.gps_tow_s >= fsw::kSecondsPerWeek)
    return LcmInputStatus::kOutOfRange;
  if (std::abs(in.llh[0]) > 0.5 * fsw::kPi || std::abs(in.llh[1]) > fsw::kPi || in.llh[2] < limits.min_height_m ||
      in.llh[2] > limits.max_height_m)
    return LcmInputStatus::kOutOfRange;
  if (norm3(in.vel_enu_mps) > limits.max_speed_mps) return LcmInputStatus::kOutOfRange;
  for (int i = 0; i < 3; ++i)
    if (!(in.pos_sigma_enu_m[i] >= 0.0) || in.pos_sigma_enu_m[i] > limits.max_pos_sigma_m)
      return LcmInputStatus::kOutOfRange;
  const bool no_velocity = in.vel_sigma_enu_mps[0] < 0.0 && in.vel_sigma_enu_mps[1] < 0.0 && in.vel_sigma_enu_mps[2] < 0.0;
  if (no_velocity) {
    if (norm3(in.vel_enu_mps) != 0.0) return LcmInputStatus::kOutOfRange;
  } else {
    for (int i = 0; i < 3; ++i)
      if (!(in.vel_sigma_enu_mps[i] >= 0.0) || in.vel_sigma_enu_mps[i] > limits.max_vel_sigma_mps)
        return LcmInputStatus::kOutOfRange;
  }
  if (in.quality < sdins::gnss_pvt_t::QUALITY_NONE || in.quality > sdins::gnss_pvt_t::QUALITY_DR || in.n_sat < 0 ||
      in.n_sat > 255)
    return LcmInputStatus::kOutOfRange;
  copy_pvt_fields(in, out);
  return LcmInputStatus::kOk;
}

// ---------------------------------------------------------------------------------------------
namespace {
/// The time, position and velocity fields nav_solution_t and truth_t share.
template <class Msg>
void time_position_velocity_to_msg(double t_s, const fsw::Vec3& llh, const fsw::Vec3& vel_enu_mps, Msg& out) {
  out.utime = utime_from_t_s(t_s);
  out.t_s = t_s;
  out.lat_rad = llh.x();
  out.lon_rad = llh.y();
  out.height_m = llh.z();
  for (int i = 0; i < 3; ++i) out.vel_enu_mps[i] = vel_enu_mps[i];
}
}  // namespace

void to_msg(const fsw::NavState& nav, bool valid, bool ekf_updated, sdins::nav_solution_t& out) {
  time_position_velocity_to_msg(nav.t_s, nav.llh, nav.vel_enu_mps, out);
  attitude_to_msg(nav.q_b_n, out.q_b_n_wxyz, out.roll_rad, out.pitch_rad, out.heading_rad);
  out.valid = valid ? 1 : 0;
  out.ekf_updated = ekf_updated ? 1 : 0;
}

void truth_to_msg(double t_s, const fsw::Vec3& llh, const fsw::Vec3& vel_enu_mps, const fsw::Mat3& C_b_n,
                  sdins::truth_t& out) {
  time_position_velocity_to_msg(t_s, llh, vel_enu_mps, out);
  fsw::Quat q(C_b_n);
  q.normalize();
  if (q.w() < 0.0) q.coeffs() *= -1.0;  // one sign for the same attitude
  attitude_to_msg(q, out.q_b_n_wxyz, out.roll_rad, out.pitch_rad, out.heading_rad);
}

void reference_to_msg(double t_s, const fsw::Vec3& llh, const fsw::Vec3& vel_enu_mps, sdins::truth_t& out) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  time_position_velocity_to_msg(t_s, llh, vel_enu_mps, out);
  for (double& q : out.q_b_n_wxyz) q = kNaN;
  out.roll_rad = kNaN;
  out.pitch_rad = kNaN;
  out.heading_rad = kNaN;
}

void compensation_to_msg(const fsw::ImuCompensation& comp, sdins::ekf_state_t& out) {
  for (int i = 0; i < 3; ++i) {
    out.accel_bias_mps2[i] = comp.accel_bias_mps2[i];
    out.gyro_bias_radps[i] = comp.gyro_bias_radps[i];
    out.accel_scale_factor[i] = comp.accel_error(i, i);
    out.gyro_scale_factor[i] = comp.gyro_error(i, i);
  }
  for (int k = 0; k < 3; ++k)
    out.accel_misalign_rad[k] = comp.accel_error(fsw::kAccelMisalignmentAxes[k].i, fsw::kAccelMisalignmentAxes[k].j);
  for (int k = 0; k < 6; ++k)
    out.gyro_misalign_rad[k] = comp.gyro_error(fsw::kGyroMisalignmentAxes[k].i, fsw::kGyroMisalignmentAxes[k].j);
}

void to_msg(double t_s, const fsw::ExecutiveHealth& h, const fsw::GnssConversionStats& conv,
            const fsw::FrameOutput& frame, double gate_chi2, sdins::filter_health_t& out) {
  out = sdins::filter_health_t{};
  out.utime = utime_from_t_s(t_s);
  out.t_s = t_s;
  // The message carries every counter of the lists (fsw/executive.hpp, fsw/gps_orbit.hpp), in
  // the message's order: a counter added to a list and not to filter_health_t.lcm fails to compile.
#define SDINS_COPY_COUNTER(type, name, doc) out.name = h.name;
#define SDINS_COPY_CONVERSION(type, name, doc) out.conv_##name = conv.name;
  FSW_EXECUTIVE_HEALTH_COUNTERS(SDINS_COPY_COUNTER)
  FSW_GNSS_CONVERSION_COUNTERS(SDINS_COPY_CONVERSION)
  FSW_EXECUTIVE_PVT_COUNTERS(SDINS_COPY_COUNTER)
#undef SDINS_COPY_COUNTER
#undef SDINS_COPY_CONVERSION

  const fsw::EkfUpdateReport& r = frame.report;
  out.ekf_updated = frame.ekf_updated ? 1 : 0;
  out.clock_initialised = r.clock_initialised ? 1 : 0;
  out.gate_chi2 = gate_chi2;
  out.epoch_pr_used = r.pr_used;
  out.epoch_prr_used = r.prr_used;
  out.epoch_pr_rejected = r.pr_rejected;
  out.epoch_prr_rejected = r.prr_rejected;
  out.epoch_obs_invalid = r.obs_invalid;
  out.epoch_obs_no_channel = r.obs_no_channel;
  out.pvt_update = r.pvt ? 1 : 0;
  out.epoch_pos_used = r.pos_used;
  out.epoch_vel_used = r.vel_used;
  out.epoch_pos_rejected = r.pos_rejected;
  out.epoch_vel_rejected = r.vel_rejected;
  if (r.pvt) {
    for (int k = 0; k < 6; ++k) {
      const fsw::PvtInnovation& o = r.pvt_obs[static_cast<std::size_t>(k)];
      out.pvt_outcome[k] = outcome_code(o.outcome);
      if ((o.outcome == fsw::InnovationOutcome::kUsed || o.outcome == fsw::InnovationOutcome::kGated) &&
          o.variance > 0.0) {
        out.pvt_innovation[k] = o.innovation;
        out.pvt_innovation_sigma[k] = std::sqrt(o.variance);
        out.pvt_normalised[k] = o.innovation / out.pvt_innovation_sigma[k];
      }
    }
  }
  const int n = r.n_obs < 0 ? 0 : (r.n_obs > fsw::kMaxGnssChannels ? fsw::kMaxGnssChannels : r.n_obs);
  out.n_obs = n;
  for (int k = 0; k < n; ++k) {
    const fsw::ObservationInnovation& o = r.obs[static_cast<std::size_t>(k)];
    out.prn[k] = o.prn;
    out.pr_outcome[k] = outcome_code(o.pr_outcome);
    out.prr_outcome[k] = outcome_code(o.prr_outcome);
    const bool pr_done = o.pr_outcome == fsw::InnovationOutcome::kUsed || o.pr_outcome == fsw::InnovationOutcome::kGated;
    const bool prr_done =
        o.prr_outcome == fsw::InnovationOutcome::kUsed || o.prr_outcome == fsw::InnovationOutcome::kGated;
    if (pr_done) {
      out.pr_innovation_m[k] = o.pr_innovation_m;
      out.pr_innovation_sigma_m[k] = std::sqrt(o.pr_variance_m2);
      out.pr_normalised[k] = o.pr_innovation_m / out.pr_innovation_sigma_m[k];
    }
    if (prr_done) {
      out.prr_innovation_mps[k] = o.prr_innovation_mps;
      out.prr_innovation_sigma_mps[k] = std::sqrt(o.prr_variance_m2ps2);
      out.prr_normalised[k] = o.prr_innovation_mps / out.prr_innovation_sigma_mps[k];
    }
  }
}

}  // namespace hal
