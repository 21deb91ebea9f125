#include "hal/lcm_types.hpp"

#include <cinttypes>
#include <cstdio>
#include <type_traits>

#include "fsw/error_state.hpp"
#include "fsw/executive.hpp"
#include "fsw/gps_orbit.hpp"
#include "hal/lcm_channels.hpp"

namespace hal {

void LcmRow::clear() {
  names_.clear();
  cells_.clear();
}

void LcmRow::add(const std::string& name, double v) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.17g", v);  // round-trips every double exactly
  names_.push_back(name);
  cells_.emplace_back(buf);
}

void LcmRow::add(const std::string& name, std::int64_t v) {
  names_.push_back(name);
  cells_.push_back(std::to_string(v));
}

void LcmRow::add_empty(const std::string& name) {
  names_.push_back(name);
  cells_.emplace_back();
}

namespace {

void add_time(const std::int64_t utime, double t_s, LcmRow& row) {
  row.add("utime", utime);
  row.add("t_s", t_s);
}

// Components of each error-state block (fsw::Block order) with their units, for the names of
// the ekf_state_t sigma columns.
struct BlockComponents {
  const char* names[fsw::kGnssErrorChannels];
};
const BlockComponents kBlockComponents[fsw::kBlockCount] = {
    {{"E_m", "N_m", "U_m"}},
    {{"E_mps", "N_mps", "U_mps"}},
    {{"E_rad", "N_rad", "U_rad"}},
    {{"x_mps2", "y_mps2", "z_mps2"}},
    {{"x_radps", "y_radps", "z_radps"}},
    {{"yx_rad", "zx_rad", "zy_rad"}},
    {{"xy_rad", "xz_rad", "yx_rad", "yz_rad", "zx_rad", "zy_rad"}},
    {{"x", "y", "z"}},  // scale factors: dimensionless
    {{"x", "y", "z"}},
    {{"bias_m", "drift_mps"}},
    {{"ch00_m", "ch01_m", "ch02_m", "ch03_m", "ch04_m", "ch05_m", "ch06_m", "ch07_m", "ch08_m", "ch09_m", "ch10_m",
      "ch11_m"}},
    {{"ch00_mps", "ch01_mps", "ch02_mps", "ch03_mps", "ch04_mps", "ch05_mps", "ch06_mps", "ch07_mps", "ch08_mps",
      "ch09_mps", "ch10_mps", "ch11_mps"}},
    {{"x_radps_per_mps2", "y_radps_per_mps2", "z_radps_per_mps2"}},
    {{"s"}},
    {{"x_m", "y_m", "z_m"}},
    {{"scale"}},
    {{"scale"}},
    {{"s_per_s"}},
};

}  // namespace

// ---------------------------------------------------------------------------------------------
// Field visitors: the CSV columns of each type, in field order.

template <>
struct LcmFields<sdins::imu_sample_t> {
  static void visit(const sdins::imu_sample_t& m, LcmRow& r) {
    add_time(m.utime, m.t_s, r);
    r.add("dt_s", m.dt_s);
    r.add_array("dtheta_rad", m.dtheta_rad, 3);
    r.add_array("dv_mps", m.dv_mps, 3);
    r.add("counter", m.counter);
    r.add("status", m.status);
  }
};

template <>
struct LcmFields<sdins::gnss_raw_epoch_t> {
  // All 16 measurement slots are columns (a fixed header); slots >= n_meas are empty.
  static void visit(const sdins::gnss_raw_epoch_t& m, LcmRow& r) {
    add_time(m.utime, m.t_s, r);
    r.add("gps_week", m.gps_week);
    r.add("gps_tow_s", m.gps_tow_s);
    r.add("n_meas", m.n_meas);
    for (int k = 0; k < 16; ++k) {
      const std::string p = "meas[" + std::to_string(k) + "].";
      if (k < m.n_meas) {
        r.add(p + "prn", m.meas[k].prn);
        r.add(p + "pseudorange_m", m.meas[k].pseudorange_m);
        r.add(p + "pseudorange_rate_mps", m.meas[k].pseudorange_rate_mps);
        r.add(p + "cn0_dbhz", m.meas[k].cn0_dbhz);
      } else {
        for (const char* f : {"prn", "pseudorange_m", "pseudorange_rate_mps", "cn0_dbhz"}) r.add_empty(p + f);
      }
    }
  }
};

template <>
struct LcmFields<sdins::gps_almanac_t> {
  static void visit(const sdins::gps_almanac_t& m, LcmRow& r) {
    add_time(m.utime, m.t_s, r);
    r.add("prn", m.prn);
    r.add("health", m.health);
    r.add("eccentricity", m.eccentricity);
    r.add("toa_s", m.toa_s);
    r.add("inclination_rad", m.inclination_rad);
    r.add("omega_dot_radps", m.omega_dot_radps);
    r.add("sqrt_a_sqrtm", m.sqrt_a_sqrtm);
    r.add("omega0_rad", m.omega0_rad);
    r.add("arg_perigee_rad", m.arg_perigee_rad);
    r.add("mean_anomaly_rad", m.mean_anomaly_rad);
    r.add("af0_s", m.af0_s);
    r.add("af1_sps", m.af1_sps);
    r.add("week_mod_1024", m.week_mod_1024);
  }
};

template <>
struct LcmFields<sdins::gnss_pvt_t> {
  static void visit(const sdins::gnss_pvt_t& m, LcmRow& r) {
    add_time(m.utime, m.t_s, r);
    r.add("gps_week", m.gps_week);
    r.add("gps_tow_s", m.gps_tow_s);
    r.add("lat_rad", m.llh[0]);
    r.add("lon_rad", m.llh[1]);
    r.add("height_m", m.llh[2]);
    r.add_array("vel_enu_mps", m.vel_enu_mps, 3);
    r.add_array("pos_sigma_enu_m", m.pos_sigma_enu_m, 3);
    r.add_array("vel_sigma_enu_mps", m.vel_sigma_enu_mps, 3);
    r.add("quality", m.quality);
    r.add("n_sat", m.n_sat);
  }
};

template <class M>
void visit_pose(const M& m, LcmRow& r) {
  add_time(m.utime, m.t_s, r);
  r.add("lat_rad", m.lat_rad);
  r.add("lon_rad", m.lon_rad);
  r.add("height_m", m.height_m);
  r.add_array("vel_enu_mps", m.vel_enu_mps, 3);
  r.add_array("q_b_n_wxyz", m.q_b_n_wxyz, 4);
  r.add("roll_rad", m.roll_rad);
  r.add("pitch_rad", m.pitch_rad);
  r.add("heading_rad", m.heading_rad);
}

template <>
struct LcmFields<sdins::nav_solution_t> {
  static void visit(const sdins::nav_solution_t& m, LcmRow& r) {
    visit_pose(m, r);
    r.add("valid", m.valid);
    r.add("ekf_updated", m.ekf_updated);
  }
};

template <>
struct LcmFields<sdins::truth_t> {
  static void visit(const sdins::truth_t& m, LcmRow& r) { visit_pose(m, r); }
};

template <>
struct LcmFields<sdins::ekf_state_t> {
  // sigma columns are named after the state they belong to (sigma_att_U_rad, ...) from the
  // message's block offsets; a state no block claims keeps the name sigma[i] (unit of its block
  // unknown). Only the model's n_states sigmas are columns.
  static void visit(const sdins::ekf_state_t& m, LcmRow& r) {
    add_time(m.utime, m.t_s, r);
    r.add("n_states", m.n_states);
    r.add("consider_mask", m.consider_mask);
    constexpr int kMaxSigma = static_cast<int>(sizeof(m.sigma) / sizeof(m.sigma[0]));
    const int n = m.n_states < 0 ? 0 : (m.n_states > kMaxSigma ? kMaxSigma : m.n_states);
    std::vector<std::string> names(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) names[static_cast<std::size_t>(i)] = "sigma[" + std::to_string(i) + "]";
    for (int b = 0; b < fsw::kBlockCount; ++b) {
      const int off = m.block_offset[b];
      if (off < 0) continue;
      for (int c = 0; c < fsw::kBlockSize[b]; ++c)
        if (off + c < n)
          names[static_cast<std::size_t>(off + c)] =
              std::string("sigma_") + fsw::kBlockName[b] + "_" + kBlockComponents[b].names[c];
    }
    for (int i = 0; i < n; ++i) r.add(names[static_cast<std::size_t>(i)], m.sigma[i]);
    r.add_array("accel_bias_mps2", m.accel_bias_mps2, 3);
    r.add_array("gyro_bias_radps", m.gyro_bias_radps, 3);
    r.add_array("accel_scale_factor", m.accel_scale_factor, 3);
    r.add_array("gyro_scale_factor", m.gyro_scale_factor, 3);
    r.add_array("accel_misalign_rad", m.accel_misalign_rad, 3);
    r.add_array("gyro_misalign_rad", m.gyro_misalign_rad, 6);
    r.add("clock_bias_m", m.clock_bias_m);
    r.add("clock_drift_mps", m.clock_drift_mps);
    r.add("clock_initialised", m.clock_initialised);
    r.add_array("channel_prn", m.channel_prn, 12);
  }
};

template <>
struct LcmFields<sdins::filter_health_t> {
  static void visit(const sdins::filter_health_t& m, LcmRow& r) {
    add_time(m.utime, m.t_s, r);
#define SDINS_ADD_COUNTER(type, name, doc) r.add(#name, m.name);
#define SDINS_ADD_CONVERSION(type, name, doc) r.add("conv_" #name, m.conv_##name);
    FSW_EXECUTIVE_HEALTH_COUNTERS(SDINS_ADD_COUNTER)
    FSW_GNSS_CONVERSION_COUNTERS(SDINS_ADD_CONVERSION)
    FSW_EXECUTIVE_PVT_COUNTERS(SDINS_ADD_COUNTER)
#undef SDINS_ADD_COUNTER
#undef SDINS_ADD_CONVERSION
    r.add("ekf_updated", m.ekf_updated);
    r.add("clock_initialised", m.clock_initialised);
    r.add("gate_chi2", m.gate_chi2);
    r.add("epoch_pr_used", m.epoch_pr_used);
    r.add("epoch_prr_used", m.epoch_prr_used);
    r.add("epoch_pr_rejected", m.epoch_pr_rejected);
    r.add("epoch_prr_rejected", m.epoch_prr_rejected);
    r.add("epoch_obs_invalid", m.epoch_obs_invalid);
    r.add("epoch_obs_no_channel", m.epoch_obs_no_channel);
    r.add("n_obs", m.n_obs);
    // Per-observation arrays: all 16 slots are columns, slots >= n_obs empty.
    r.add_array("prn", m.prn, 16, m.n_obs);
    r.add_array("pr_outcome", m.pr_outcome, 16, m.n_obs);
    r.add_array("prr_outcome", m.prr_outcome, 16, m.n_obs);
    r.add_array("pr_innovation_m", m.pr_innovation_m, 16, m.n_obs);
    r.add_array("pr_innovation_sigma_m", m.pr_innovation_sigma_m, 16, m.n_obs);
    r.add_array("pr_normalised", m.pr_normalised, 16, m.n_obs);
    r.add_array("prr_innovation_mps", m.prr_innovation_mps, 16, m.n_obs);
    r.add_array("prr_innovation_sigma_mps", m.prr_innovation_sigma_mps, 16, m.n_obs);
    r.add_array("prr_normalised", m.prr_normalised, 16, m.n_obs);
    // The loosely coupled update's six scalars (pos E, N, U, vel E, N, U), empty without one.
    r.add("pvt_update", m.pvt_update);
    r.add("epoch_pos_used", m.epoch_pos_used);
    r.add("epoch_vel_used", m.epoch_vel_used);
    r.add("epoch_pos_rejected", m.epoch_pos_rejected);
    r.add("epoch_vel_rejected", m.epoch_vel_rejected);
    const int n_pvt = m.pvt_update ? 6 : 0;
    r.add_array("pvt_outcome", m.pvt_outcome, 6, n_pvt);
    r.add_array("pvt_innovation", m.pvt_innovation, 6, n_pvt);
    r.add_array("pvt_innovation_sigma", m.pvt_innovation_sigma, 6, n_pvt);
    r.add_array("pvt_normalised", m.pvt_normalised, 6, n_pvt);
  }
};

// ---------------------------------------------------------------------------------------------
namespace {

template <class Msg>
LcmInputStatus time_of(const void* data, std::size_t len, double& t_s) {
  Msg m{};
  const LcmInputStatus st = decode_exact(data, len, m);
  if (st == LcmInputStatus::kOk) t_s = m.t_s;
  return st;
}

template <class Msg>
LcmInputStatus row_of(const void* data, std::size_t len, LcmRow& row) {
  row.clear();
  Msg m{};
  const LcmInputStatus st = decode_exact(data, len, m);
  if (st == LcmInputStatus::kOk) LcmFields<Msg>::visit(m, row);
  return st;
}

/// The flight software's input conversion (nullptr for the output types).
template <class Msg>
struct InputOf {
  static constexpr LcmInputStatus (*kFn)(const void*, std::size_t, int&) = nullptr;
};
template <class Msg, class Out>
LcmInputStatus input_of(const void* data, std::size_t len, int& values_dropped) {
  values_dropped = 0;
  Msg m{};
  LcmInputStatus st = decode_exact(data, len, m);
  Out out{};
  if (st != LcmInputStatus::kOk) return st;
  if constexpr (std::is_same_v<Msg, sdins::gnss_raw_epoch_t>)
    return from_msg(m, out, values_dropped);
  else
    return from_msg(m, out);
}
template <>
struct InputOf<sdins::imu_sample_t> {
  static constexpr LcmInputStatus (*kFn)(const void*, std::size_t, int&) = &input_of<sdins::imu_sample_t, ImuRecord>;
};
template <>
struct InputOf<sdins::gnss_raw_epoch_t> {
  static constexpr LcmInputStatus (*kFn)(const void*, std::size_t, int&) =
      &input_of<sdins::gnss_raw_epoch_t, fsw::GnssRawEpoch>;
};
template <>
struct InputOf<sdins::gps_almanac_t> {
  static constexpr LcmInputStatus (*kFn)(const void*, std::size_t, int&) = &input_of<sdins::gps_almanac_t, fsw::GpsAlmanac>;
};
template <>
struct InputOf<sdins::gnss_pvt_t> {
  static constexpr LcmInputStatus (*kFn)(const void*, std::size_t, int&) = &input_of<sdins::gnss_pvt_t, GnssPvtSample>;
};

template <class Msg>
LcmTypeInfo make_lcm_type() {
  return LcmTypeInfo{std::string("sdins.") + Msg::getTypeName(), Msg::getHash(), &time_of<Msg>, &row_of<Msg>,
                     InputOf<Msg>::kFn};
}

}  // namespace

const std::vector<LcmTypeInfo>& lcm_types() {
  // One line per message type.
  static const std::vector<LcmTypeInfo> kTypes = {
      make_lcm_type<sdins::imu_sample_t>(),    make_lcm_type<sdins::gnss_raw_epoch_t>(),
      make_lcm_type<sdins::gps_almanac_t>(),   make_lcm_type<sdins::nav_solution_t>(),
      make_lcm_type<sdins::ekf_state_t>(),     make_lcm_type<sdins::filter_health_t>(),
      make_lcm_type<sdins::truth_t>(),         make_lcm_type<sdins::gnss_pvt_t>(),
  };
  return kTypes;
}

const LcmTypeInfo* find_lcm_type(std::int64_t fingerprint) {
  for (const LcmTypeInfo& t : lcm_types())
    if (t.fingerprint == fingerprint) return &t;
  return nullptr;
}

const LcmTypeInfo* find_lcm_type(std::string_view name) {
  for (const LcmTypeInfo& t : lcm_types())
    if (t.name == name) return &t;
  return nullptr;
}

const LcmTypeInfo* lcm_channel_type(std::string_view channel) {
  for (const LcmChannelInfo& c : kLcmChannels)
    if (channel == c.channel) return find_lcm_type(std::string_view(c.type_name));
  return nullptr;
}

}  // namespace hal
