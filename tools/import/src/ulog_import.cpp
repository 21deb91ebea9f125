// `sdins import ulog` (tools/ulog_import.hpp, docs/ulog.md): PX4 topics -> IMU, GNSS_PVT, TRUTH.
#include "tools/ulog_import.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

#include "fsw/frames.hpp"
#include "hal/lcm_channels.hpp"
#include "hal/lcm_convert.hpp"
#include "hal/lcm_log_sink.hpp"
#include "hal/time_tag_gate.hpp"
#include "tools/gps_utc.hpp"
#include "tools/importers.hpp"
#include "import_common.hpp"
#include "tools/number_text.hpp"

namespace tools {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::int64_t kWeek_us = static_cast<std::int64_t>(fsw::kSecondsPerWeek) * 1000000;

/// One topic instance of the file: fields by name, values by message index.
class Topic {
 public:
  Topic(const ulog::File& f, const ulog::Subscription* s) : f_(f), s_(s) {}
  bool present() const { return s_ != nullptr && !s_->data.empty(); }
  std::size_t size() const { return s_ == nullptr ? 0 : s_->data.size(); }
  const std::string& name() const { return s_->name; }
  int instance() const { return s_->multi_id; }
  const ulog::Field* field(const char* n) const { return s_ == nullptr ? nullptr : s_->format->field(n); }
  /// A field the import needs: throws naming the topic and field when the format lacks it.
  const ulog::Field& need(const char* n) const {
    const ulog::Field* fl = field(n);
    if (fl == nullptr) throw std::runtime_error("ULog topic " + s_->name + " has no field '" + n + "'");
    return *fl;
  }
  double get(std::size_t k, const ulog::Field* fl, std::uint32_t i = 0) const {
    return fl == nullptr ? kNaN : ulog::value(f_, s_->data[k], *fl, i);
  }
  std::uint64_t u64(std::size_t k, const ulog::Field* fl) const {
    return fl == nullptr ? 0 : ulog::value_u64(f_, s_->data[k], *fl);
  }
  /// The time the message's contents refer to: timestamp_sample where the format has it and it
  /// is set, else timestamp [us, boot clock].
  std::int64_t sample_time_us(std::size_t k) const {
    const std::uint64_t ts = u64(k, field("timestamp_sample"));
    return static_cast<std::int64_t>(ts > 0 ? ts : u64(k, field("timestamp")));
  }

 private:
  const ulog::File& f_;
  const ulog::Subscription* s_;
};

/// The messages of a topic whose time tags pass the time-tag gate (hal::TimeTagGate: a wild time
/// tag, e.g. a flipped bit, costs only its own message; a sustained jump is a new time base), in
/// order. Every message is counted in st.lines, the rejected ones under their reason.
std::vector<std::size_t> gated(const Topic& t, LineStats& st, double max_forward_s) {
  hal::TimeTagGateConfig cfg;
  cfg.max_forward_s = max_forward_s;
  cfg.max_backward_s = 1.0;
  cfg.strictly_increasing = true;
  hal::TimeTagFilter<std::size_t> filter(cfg);
  std::vector<std::size_t> out;
  const auto accept = [&](std::size_t k) { out.push_back(k); };
  const auto reject = [&](std::size_t k, hal::TimeTagRejection r) {
    st.reject(k + 1, hal::to_string(r));
  };
  for (std::size_t k = 0; k < t.size(); ++k) {
    ++st.lines;
    filter.push(static_cast<double>(t.sample_time_us(k)) * 1e-6, k, accept, reject);
  }
  filter.finish(accept, reject);
  st.time_base_changes += filter.stats().new_bases;
  st.last_time_jump = filter.stats().last_new_base_jump_s;
  return out;
}

// ---------------------------------------------------------------------------------------------
// What the log is

nlohmann::json describe_file(const ulog::File& f) {
  nlohmann::json info = nlohmann::json::object();
  for (const ulog::InfoValue& v : f.info) {
    const std::string t = v.text();
    if (!t.empty())
      info[v.key] = t;
    else if (std::isfinite(v.number()))
      info[v.key] = v.number();
  }
  nlohmann::json topics = nlohmann::json::array();
  for (const ulog::Subscription& s : f.subscriptions)
    topics.push_back({{"name", s.name}, {"multi_id", s.multi_id}, {"messages", s.data.size()}});
  nlohmann::json damage = {{"total", f.damage.total()}, {"bytes_skipped", f.damage.bytes_skipped}};
  nlohmann::json by = nlohmann::json::object();
  for (int d = 0; d < static_cast<int>(ulog::Damage::kCount); ++d)
    if (f.damage.counts[static_cast<std::size_t>(d)] > 0)
      by[ulog::to_string(static_cast<ulog::Damage>(d))] = f.damage.counts[static_cast<std::size_t>(d)];
  damage["by_reason"] = by;
  nlohmann::json ex = nlohmann::json::array();
  for (const ulog::DamageRecord& r : f.damage.examples) ex.push_back({{"offset", r.offset}, {"reason", ulog::to_string(r.reason)}});
  damage["examples"] = ex;
  nlohmann::json vehicle = nullptr;
  const Topic vs(f, f.find("vehicle_status"));
  if (vs.present()) {
    // vehicle_status.vehicle_type: 0 unknown, 1 rotary wing, 2 fixed wing, 3 rover, 4 airship.
    static const char* kTypes[] = {"unknown", "rotary_wing", "fixed_wing", "rover", "airship"};
    const double vt = vs.get(0, vs.field("vehicle_type"));
    const double vtol = vs.get(0, vs.field("is_vtol"));
    vehicle = {{"vehicle_type", std::isfinite(vt) && vt >= 0 && vt <= 4 ? kTypes[static_cast<int>(vt)] : "not logged"},
               {"is_vtol", std::isfinite(vtol) ? nlohmann::json(vtol != 0.0) : nlohmann::json(nullptr)}};
  }
  return {{"version", f.version},
          {"start_timestamp_us", f.start_timestamp_us},
          {"info", info},
          {"vehicle", vehicle},
          {"parameters", f.parameters.size()},
          {"parameter_changes", f.parameter_changes},
          {"messages", f.messages},
          {"data_messages", f.data_messages},
          {"topics", topics},
          {"log_texts", f.texts.size()},
          {"sync_messages", f.sync_messages},
          {"dropouts", {{"count", f.dropouts.size()}, {"total_ms", f.dropout_ms}}},
          {"appended_data", f.has_flag_bits && (f.incompat_flags[0] & ulog::kIncompatDataAppended) != 0},
          {"damage", damage}};
}

// ---------------------------------------------------------------------------------------------
// GNSS

struct GpsRow {
  std::int64_t boot_us = 0;  ///< when the UTC was valid on the boot clock (before the latency)
  std::int64_t utc_us = 0;
  hal::GnssPvtSample pvt;    ///< t_s, week, tow set later
};

/// The GNSS topic: the one asked for, or (auto) of vehicle_gps_position and sensor_gps the one
/// with more messages (vehicle_gps_position on a tie: PX4's selected / blended receiver).
Topic gnss_topic(const ulog::File& f, const UlogImportOptions& opt) {
  if (opt.gnss_topic != "auto") return Topic(f, f.find(opt.gnss_topic, opt.gnss_instance));
  const Topic a(f, f.find("vehicle_gps_position", opt.gnss_instance)), b(f, f.find("sensor_gps", opt.gnss_instance));
  return b.size() > a.size() ? b : a;
}

int quality_of_fix(int fix_type) {
  switch (fix_type) {  // PX4 fix_type: 3 3D, 4 RTCM code differential, 5 RTK float, 6 RTK fixed
    case 3: return sdins::gnss_pvt_t::QUALITY_SINGLE;
    case 4: return sdins::gnss_pvt_t::QUALITY_DGPS;
    case 5: return sdins::gnss_pvt_t::QUALITY_FLOAT;
    case 6: return sdins::gnss_pvt_t::QUALITY_FIX;
    default: return sdins::gnss_pvt_t::QUALITY_NONE;
  }
}

/// The fixes of the topic, position and velocity converted; the rest counted in `st`.
std::vector<GpsRow> read_gnss(const Topic& t, LineStats& st) {
  std::vector<GpsRow> out;
  if (!t.present()) return out;
  // Two schemas: PX4 <= 1.13 (lat/lon 1e-7 deg, alt_ellipsoid mm) and later (degrees, metres).
  const ulog::Field* lat_e7 = t.field("lat");
  const ulog::Field* lat_deg = t.field("latitude_deg");
  const ulog::Field* lon = lat_deg != nullptr ? t.field("longitude_deg") : t.field("lon");
  const ulog::Field* h = lat_deg != nullptr ? t.field("altitude_ellipsoid_m") : t.field("alt_ellipsoid");
  if ((lat_e7 == nullptr && lat_deg == nullptr) || lon == nullptr || h == nullptr)
    throw std::runtime_error("ULog topic " + t.name() + ": no latitude/longitude/ellipsoid height fields in its format");
  const double pos_scale = lat_deg != nullptr ? fsw::kDegToRad : 1e-7 * fsw::kDegToRad;
  const double h_scale = lat_deg != nullptr ? 1.0 : 1e-3;
  const ulog::Field* lat = lat_deg != nullptr ? lat_deg : lat_e7;
  const ulog::Field* msl = lat_deg != nullptr ? t.field("altitude_msl_m") : t.field("alt");
  const ulog::Field &utc = t.need("time_utc_usec"), &fix = t.need("fix_type"), &eph = t.need("eph"), &epv = t.need("epv");
  const ulog::Field* rel = t.field("timestamp_time_relative");
  const ulog::Field *vn = t.field("vel_n_m_s"), *ve = t.field("vel_e_m_s"), *vd = t.field("vel_d_m_s");
  const ulog::Field *vok = t.field("vel_ned_valid"), *sacc = t.field("s_variance_m_s"), *nsat = t.field("satellites_used");
  std::int64_t last_utc = 0;
  for (std::size_t k : gated(t, st, 10.0)) {
    const std::uint64_t line = k + 1;
    const int fx = static_cast<int>(t.get(k, &fix));
    const std::int64_t u = static_cast<std::int64_t>(t.u64(k, &utc));
    if (fx < 3 || quality_of_fix(fx) == sdins::gnss_pvt_t::QUALITY_NONE) {
      st.reject(line, fx == 8 ? "extrapolated fix (fix_type 8)" : "no 3D fix (fix_type < 3)");
      continue;
    }
    if (u < 946684800LL * 1000000LL) {  // before 2000-01-01: the receiver has no UTC yet
      st.reject(line, "no UTC time (time_utc_usec 0 or before 2000)");
      continue;
    }
    if (u <= last_utc) {
      st.reject(line, u == last_utc ? "duplicate epoch (same time_utc_usec)" : "time_utc_usec going backwards");
      continue;
    }
    GpsRow r;
    r.utc_us = u;
    const double r_rel = t.get(k, rel);
    r.boot_us = static_cast<std::int64_t>(t.u64(k, t.field("timestamp"))) +
                (std::isfinite(r_rel) ? static_cast<std::int64_t>(r_rel) : 0);
    hal::GnssPvtSample& p = r.pvt;
    p.llh = fsw::Vec3(t.get(k, lat) * pos_scale, t.get(k, lon) * pos_scale, t.get(k, h) * h_scale);
    const double e = t.get(k, &eph), v = t.get(k, &epv);
    p.pos_sigma_enu_m = fsw::Vec3(e, e, v);
    const double s = t.get(k, sacc);
    const bool has_vel = vn != nullptr && ve != nullptr && vd != nullptr && (vok == nullptr || t.get(k, vok) != 0.0) &&
                         std::isfinite(s) && s > 0.0;
    if (has_vel) {
      p.vel_enu_mps = fsw::Vec3(t.get(k, ve), t.get(k, vn), -t.get(k, vd));
      p.vel_sigma_enu_mps = fsw::Vec3::Constant(s);
    } else {
      p.vel_enu_mps = fsw::Vec3::Zero();
      p.vel_sigma_enu_mps = fsw::Vec3::Constant(hal::kGnssPvtNoVelocity);
      st.skip("fix without velocity (vel_ned_valid false or no speed accuracy)");
    }
    p.quality = quality_of_fix(fx);
    const double ns = t.get(k, nsat);
    p.n_sat = std::isfinite(ns) ? static_cast<int>(ns) : 0;
    if (!p.llh.allFinite() || !(e > 0.0) || !(v > 0.0)) {
      st.reject(line, "non-finite position or accuracy not positive");
      continue;
    }
    // A driver that does not fill the ellipsoidal height leaves it 0 beside a real MSL altitude:
    // no geoid here to convert the MSL one (the description-file import has it), so it is refused.
    if (t.get(k, h) == 0.0 && std::isfinite(t.get(k, msl)) && t.get(k, msl) != 0.0) {
      st.reject(line, "no ellipsoidal height (alt_ellipsoid 0 beside an MSL altitude)");
      continue;
    }
    last_utc = u;
    ++st.accepted;
    out.push_back(r);
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Clock

}  // namespace

double UlogClockFit::nav_s(std::int64_t boot_us, std::int64_t origin_us) const {
  return static_cast<double>(gps0_us - origin_us) * 1e-6 + offset_s +
         (1.0 + drift) * static_cast<double>(boot_us - boot0_us) * 1e-6;
}

UlogClockFit fit_boot_to_gps(const std::vector<std::pair<std::int64_t, std::int64_t>>& pairs) {
  if (pairs.empty()) throw std::runtime_error("no (boot time, UTC) pairs to fit the boot clock to GPS time");
  UlogClockFit c;
  c.boot0_us = pairs.front().first;
  c.gps0_us = gps_us_from_utc_us(pairs.front().second);
  c.gps_minus_utc_first_s = gps_minus_utc_s(pairs.front().second / 1000000);
  c.gps_minus_utc_last_s = gps_minus_utc_s(pairs.back().second / 1000000);
  // y - x = offset + drift * x in seconds from the first pair: small numbers, no cancellation.
  std::vector<double> x, d;
  for (const auto& [boot, utc] : pairs) {
    x.push_back(static_cast<double>(boot - c.boot0_us) * 1e-6);
    d.push_back(static_cast<double>(gps_us_from_utc_us(utc) - c.gps0_us) * 1e-6 - x.back());
  }
  std::vector<bool> use(x.size(), true);
  // Least squares of d = offset + drift x; the drift is kept only when it is significant (beyond
  // 3 standard errors): over a short log the time-stamp jitter would otherwise pose as a drift.
  const auto fit = [&]() {
    double n = 0, sx = 0, sd = 0;
    for (std::size_t i = 0; i < x.size(); ++i)
      if (use[i]) {
        n += 1;
        sx += x[i];
        sd += d[i];
      }
    const double mx = sx / n, md = sd / n;
    double sxx = 0, sxd = 0;
    for (std::size_t i = 0; i < x.size(); ++i)
      if (use[i]) {
        sxx += (x[i] - mx) * (x[i] - mx);
        sxd += (x[i] - mx) * (d[i] - md);
      }
    c.pairs = static_cast<std::size_t>(n);
    c.fitted_drift = sxx > 0.0 ? sxd / sxx : 0.0;
    double ssr = 0;
    for (std::size_t i = 0; i < x.size(); ++i)
      if (use[i]) ssr += std::pow(d[i] - md - c.fitted_drift * (x[i] - mx), 2);
    c.drift_sigma = (n > 2 && sxx > 0.0) ? std::sqrt(ssr / (n - 2) / sxx) : INFINITY;
    c.drift_significant = std::isfinite(c.drift_sigma) && std::abs(c.fitted_drift) > 3.0 * c.drift_sigma;
    c.drift = c.drift_significant ? c.fitted_drift : 0.0;
    c.offset_s = md - c.drift * mx;
  };
  const auto residual = [&](std::size_t i) { return d[i] - c.offset_s - c.drift * x[i]; };
  fit();
  // One outlier pass: residuals beyond 5 robust sigmas (1.4826 MAD) and beyond 1 ms.
  std::vector<double> a;
  for (std::size_t i = 0; i < x.size(); ++i) a.push_back(std::abs(residual(i)));
  std::vector<double> s = a;
  std::nth_element(s.begin(), s.begin() + static_cast<std::ptrdiff_t>(s.size() / 2), s.end());
  const double limit = std::max(5.0 * 1.4826 * s[s.size() / 2], 1e-3);
  for (std::size_t i = 0; i < x.size(); ++i)
    if (a[i] > limit) {
      use[i] = false;
      ++c.outliers;
    }
  if (c.outliers > 0 && c.outliers < x.size()) fit();
  double ss = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!use[i]) continue;
    ss += residual(i) * residual(i);
    c.residual_max_s = std::max(c.residual_max_s, std::abs(residual(i)));
  }
  c.residual_rms_s = c.pairs > 0 ? std::sqrt(ss / static_cast<double>(c.pairs)) : 0.0;
  return c;
}

namespace {

// ---------------------------------------------------------------------------------------------
// IMU

struct BootImu {
  std::int64_t boot_us = 0;  ///< end of the interval
  double dt_boot_s = 0.0;
  hal::ImuRecord rec;        ///< increments, counter, status; t_s/dt_s set later
};

struct ImuReadStats {
  LineStats lines;
  std::uint64_t gaps = 0;            ///< intervals over 1.5 integration intervals (lost samples)
  double longest_gap_s = 0.0;
  double max_interval_mismatch_s = 0.0;  ///< |interval - integration interval| of normal samples
  double max_accel_time_offset_s = 0.0;  ///< sensor_combined: |accelerometer_timestamp_relative|
  std::uint64_t clipped = 0;
  double covered_s = 0.0;            ///< sum of the integration intervals
};

/// The samples an IMU reader keeps, with the time and the counter of the last one.
struct KeptImu {
  std::vector<BootImu> samples;
  std::int64_t prev_us = 0;
  std::int32_t counter = 0;

  /// Time since the previous sample kept (the integration interval idt_s for the first).
  double since_s(std::int64_t ts_us, double idt_s) const {
    return samples.empty() ? idt_s : static_cast<double>(ts_us - prev_us) * 1e-6;
  }
  bool increasing(std::int64_t ts_us) const { return samples.empty() || ts_us > prev_us; }

  /// Keeps s (its increments set), as both readers do: the interval statistics (since_s over 1.5
  /// integration intervals idt_s is a gap: lost samples), the counter advanced by the samples the
  /// interval held, the clipping status and the counts.
  void keep(BootImu& s, double since, double idt_s, bool accel_clipped, bool gyro_clipped, ImuReadStats& st) {
    if (since > 1.5 * idt_s) {
      ++st.gaps;
      st.longest_gap_s = std::max(st.longest_gap_s, since);
    } else {
      st.max_interval_mismatch_s = std::max(st.max_interval_mismatch_s, std::abs(since - idt_s));
    }
    counter += samples.empty() ? 0 : std::max<std::int32_t>(1, static_cast<std::int32_t>(std::lround(since / idt_s)));
    s.rec.counter = counter;
    if (accel_clipped) s.rec.status |= sdins::imu_sample_t::STATUS_ACCEL_SATURATED;
    if (gyro_clipped) s.rec.status |= sdins::imu_sample_t::STATUS_GYRO_SATURATED;
    if (s.rec.status != 0) ++st.clipped;
    st.covered_s += idt_s;
    prev_us = s.boot_us;
    ++st.lines.accepted;
    samples.push_back(s);
  }
};

/// sensor_combined: mean rates over the integration interval ending at `timestamp`; the
/// increments cover the interval since the previous sample (rate x interval).
std::vector<BootImu> read_sensor_combined(const Topic& t, ImuReadStats& st) {
  const ulog::Field &g = t.need("gyro_rad"), &gdt = t.need("gyro_integral_dt"), &a = t.need("accelerometer_m_s2"),
                    &adt = t.need("accelerometer_integral_dt");
  const ulog::Field *arel = t.field("accelerometer_timestamp_relative"), *aclip = t.field("accelerometer_clipping"),
                    *gclip = t.field("gyro_clipping");
  KeptImu kept;
  for (std::size_t k : gated(t, st.lines, 1.0)) {
    const std::uint64_t line = k + 1;
    const std::int64_t ts = t.sample_time_us(k);
    const double idt = t.get(k, &gdt) * 1e-6;
    const double rel = t.get(k, arel);
    if (std::isfinite(rel) && rel == 2147483647.0) {  // RELATIVE_TIMESTAMP_INVALID: no accelerometer sample
      st.lines.reject(line, "accelerometer invalid (accelerometer_timestamp_relative = INT32_MAX)");
      continue;
    }
    if (!(idt > 0.0) || !(t.get(k, &adt) > 0.0)) {
      st.lines.reject(line, "integration interval 0");
      continue;
    }
    if (!kept.increasing(ts)) {
      st.lines.reject(line, "timestamp not increasing");
      continue;
    }
    BootImu s;
    s.boot_us = ts;
    s.dt_boot_s = kept.since_s(ts, idt);
    if (std::isfinite(rel)) st.max_accel_time_offset_s = std::max(st.max_accel_time_offset_s, std::abs(rel) * 1e-6);
    for (int i = 0; i < 3; ++i) {
      s.rec.sample.dtheta_rad[i] = t.get(k, &g, static_cast<std::uint32_t>(i)) * s.dt_boot_s;
      s.rec.sample.dv_mps[i] = t.get(k, &a, static_cast<std::uint32_t>(i)) * s.dt_boot_s;
    }
    kept.keep(s, s.dt_boot_s, idt, t.get(k, aclip) > 0.0, t.get(k, gclip) > 0.0, st);
  }
  return kept.samples;
}

/// vehicle_imu: increments over delta_angle_dt ending at timestamp_sample, as logged.
std::vector<BootImu> read_vehicle_imu(const Topic& t, ImuReadStats& st) {
  const ulog::Field &da = t.need("delta_angle"), &dv = t.need("delta_velocity"), &dadt = t.need("delta_angle_dt");
  const ulog::Field *vclip = t.field("delta_velocity_clipping"), *aclip = t.field("delta_angle_clipping");
  KeptImu kept;
  for (std::size_t k : gated(t, st.lines, 1.0)) {
    const std::uint64_t line = k + 1;
    const std::int64_t ts = t.sample_time_us(k);
    const double idt = t.get(k, &dadt) * 1e-6;
    if (!(idt > 0.0)) {
      st.lines.reject(line, "integration interval 0");
      continue;
    }
    if (!kept.increasing(ts)) {
      st.lines.reject(line, "timestamp_sample not increasing");
      continue;
    }
    BootImu s;
    s.boot_us = ts;
    s.dt_boot_s = idt;  // the increments cover their own interval; a longer gap before it is lost data
    const double since = kept.since_s(ts, idt);
    for (int i = 0; i < 3; ++i) {
      s.rec.sample.dtheta_rad[i] = t.get(k, &da, static_cast<std::uint32_t>(i));
      s.rec.sample.dv_mps[i] = t.get(k, &dv, static_cast<std::uint32_t>(i));
    }
    kept.keep(s, since, idt, t.get(k, vclip) > 0.0, t.get(k, aclip) > 0.0, st);
  }
  return kept.samples;
}

/// Fraction of the topic's time span its integration intervals cover (1: no lost samples).
double coverage(const Topic& t, const char* dt_field) {
  const ulog::Field* f = t.field(dt_field);
  if (!t.present() || f == nullptr || t.size() < 2) return 0.0;
  double sum = 0.0;
  for (std::size_t k = 1; k < t.size(); ++k) sum += t.get(k, f) * 1e-6;
  const double span = static_cast<double>(t.sample_time_us(t.size() - 1) - t.sample_time_us(0)) * 1e-6;
  return span > 0.0 ? sum / span : 0.0;
}

// ---------------------------------------------------------------------------------------------
// Reference

struct RefRow {
  std::int64_t boot_us = 0;
  fsw::Vec3 llh = fsw::Vec3::Constant(kNaN);
  fsw::Vec3 vel_enu_mps = fsw::Vec3::Constant(kNaN);
  fsw::Mat3 C_b_n = fsw::Mat3::Constant(kNaN);
  bool has_attitude = false;
};

/// A topic's messages in strictly increasing sample time (a message going back in time is left
/// out): times and message indices.
struct Series {
  std::vector<std::int64_t> t;
  std::vector<std::size_t> k;
};
Series series(const Topic& topic, std::uint64_t& dropped) {
  Series s;
  LineStats st;
  for (std::size_t k : gated(topic, st, 10.0)) {
    const std::int64_t t = topic.sample_time_us(k);
    if (!s.t.empty() && t <= s.t.back()) {
      ++dropped;
      continue;
    }
    s.t.push_back(t);
    s.k.push_back(k);
  }
  dropped += st.rejected;
  return s;
}

/// Linear interpolation at boot time `t` between the bracketing messages of s no further apart
/// than max_gap_us, both passing ok(message); false when there are none.
template <class Ok, class Get>
bool interpolate(const Series& s, std::int64_t t, std::int64_t max_gap_us, Ok ok, Get get, fsw::Vec3& out) {
  const auto it = std::lower_bound(s.t.begin(), s.t.end(), t);
  if (it == s.t.end()) return false;
  const std::size_t j = static_cast<std::size_t>(it - s.t.begin());
  if (s.t[j] == t) {
    if (!ok(s.k[j])) return false;
    out = get(s.k[j]);
    return out.allFinite();
  }
  if (j == 0 || s.t[j] - s.t[j - 1] > max_gap_us || !ok(s.k[j]) || !ok(s.k[j - 1])) return false;
  const double w = static_cast<double>(t - s.t[j - 1]) / static_cast<double>(s.t[j] - s.t[j - 1]);
  out = (1.0 - w) * get(s.k[j - 1]) + w * get(s.k[j]);
  return out.allFinite();
}

struct RefStats {
  std::uint64_t samples = 0, with_position = 0, with_velocity = 0, with_attitude = 0;
  std::uint64_t position_resets = 0, attitude_resets = 0;
  std::uint64_t out_of_order = 0;  ///< estimate messages going back in time (left out)
  std::string timeline;
};

/// PX4's estimate at the attitude's times (at most 50 Hz; without attitude: the global
/// position's times). Samples with none of position, velocity and attitude are left out.
std::vector<RefRow> read_reference(const ulog::File& f, RefStats& st) {
  const Topic gp(f, f.find("vehicle_global_position")), lp(f, f.find("vehicle_local_position")),
      att(f, f.find("vehicle_attitude"));
  const Series tg = series(gp, st.out_of_order), tl = series(lp, st.out_of_order), ta = series(att, st.out_of_order);
  const ulog::Field *glat = gp.field("lat"), *glon = gp.field("lon"), *gh = gp.field("alt_ellipsoid"),
                    *greset = gp.field("lat_lon_reset_counter");
  const ulog::Field *vx = lp.field("vx"), *vy = lp.field("vy"), *vz = lp.field("vz"), *vxy_ok = lp.field("v_xy_valid"),
                    *vz_ok = lp.field("v_z_valid");
  const ulog::Field* q = att.field("q");
  const ulog::Field* qreset = att.field("quat_reset_counter");
  for (std::size_t k = 1; k < gp.size(); ++k)
    if (gp.get(k, greset) != gp.get(k - 1, greset)) ++st.position_resets;
  for (std::size_t k = 1; k < att.size(); ++k)
    if (att.get(k, qreset) != att.get(k - 1, qreset)) ++st.attitude_resets;
  const auto pos_ok = [&](std::size_t) { return glat != nullptr && glon != nullptr && gh != nullptr; };
  const auto pos_at = [&](std::size_t k) {
    return fsw::Vec3(gp.get(k, glat) * fsw::kDegToRad, gp.get(k, glon) * fsw::kDegToRad, gp.get(k, gh));
  };
  const auto vel_ok = [&](std::size_t k) {
    return vx != nullptr && (vxy_ok == nullptr || lp.get(k, vxy_ok) != 0.0) && (vz_ok == nullptr || lp.get(k, vz_ok) != 0.0);
  };
  const auto vel_at = [&](std::size_t k) { return fsw::Vec3(lp.get(k, vy), lp.get(k, vx), -lp.get(k, vz)); };
  const bool by_attitude = att.present() && q != nullptr;
  st.timeline = by_attitude ? "vehicle_attitude (at most 50 Hz)" : "vehicle_global_position";
  const Series& line = by_attitude ? ta : tg;
  fsw::Mat3 T_ned_enu;
  T_ned_enu << 0, 1, 0, 1, 0, 0, 0, 0, -1;
  std::vector<RefRow> out;
  std::int64_t last = 0;
  for (std::size_t i = 0; i < line.t.size(); ++i) {
    if (!out.empty() && line.t[i] - last < 20000) continue;  // 50 Hz at most
    RefRow r;
    r.boot_us = line.t[i];
    fsw::Vec3 v;
    if (interpolate(tg, r.boot_us, 1000000, pos_ok, pos_at, v)) {
      // No interpolation across a position reset (lat_lon_reset_counter changes).
      const auto j = static_cast<std::size_t>(std::lower_bound(tg.t.begin(), tg.t.end(), r.boot_us) - tg.t.begin());
      const bool across_reset = j > 0 && tg.t[j] != r.boot_us && gp.get(tg.k[j], greset) != gp.get(tg.k[j - 1], greset);
      if (!across_reset) r.llh = v;
    }
    if (interpolate(tl, r.boot_us, 500000, vel_ok, vel_at, v)) r.vel_enu_mps = v;
    if (by_attitude) {
      const std::size_t k = line.k[i];
      const fsw::Quat qq(att.get(k, q, 0), att.get(k, q, 1), att.get(k, q, 2), att.get(k, q, 3));
      if (qq.coeffs().allFinite() && std::abs(qq.norm() - 1.0) < 1e-3) {
        r.C_b_n = T_ned_enu * qq.normalized().toRotationMatrix();
        r.has_attitude = true;
      }
    }
    const bool p = r.llh.allFinite(), vv = r.vel_enu_mps.allFinite();
    if (!p && !vv && !r.has_attitude) continue;
    st.with_position += p ? 1 : 0;
    st.with_velocity += vv ? 1 : 0;
    st.with_attitude += r.has_attitude ? 1 : 0;
    last = r.boot_us;
    out.push_back(r);
  }
  st.samples = out.size();
  return out;
}

// ---------------------------------------------------------------------------------------------
// The log

struct Converted {
  std::vector<hal::ImuRecord> imu;
  std::vector<hal::GnssPvtSample> pvt;
  std::vector<RefRow> truth;
  std::vector<double> truth_t_s;
};

/// The log through the import engine's one writer (import_common.hpp: time order; at equal times
/// the IMU sample ending then, the solution, the reference).
nlohmann::json write_ulog_log(const std::string& path, const Converted& c) {
  import_detail::Collected out;
  out.imu = c.imu;
  out.pvt = c.pvt;
  out.truth.reserve(c.truth.size());
  for (std::size_t i = 0; i < c.truth.size(); ++i) {
    const RefRow& r = c.truth[i];
    import_detail::ReferenceEpoch e;
    e.t_s = c.truth_t_s[i];
    e.llh = r.llh;
    e.vel_enu_mps = r.vel_enu_mps;
    e.has_attitude = r.has_attitude;
    e.C_b_n = r.C_b_n;
    out.truth.push_back(e);
  }
  return import_detail::write_log(path, out);
}

/// IMU records and solutions through the replay's input validation (hal::from_msg): what the
/// replay would reject is counted here and not written.
void validate(Converted& c, LineStats& imu_lines, LineStats& gnss_lines) {
  std::vector<hal::ImuRecord> imu;
  for (const hal::ImuRecord& r : c.imu) {
    sdins::imu_sample_t m{};
    hal::to_msg(r, m);
    hal::ImuRecord back;
    const hal::LcmInputStatus s = hal::from_msg(m, back);
    if (s != hal::LcmInputStatus::kOk && s != hal::LcmInputStatus::kSensorFlagged) {
      imu_lines.reject(static_cast<std::uint64_t>(r.counter) + 1, std::string("IMU input validation: ") + hal::to_string(s));
      --imu_lines.accepted;
      continue;
    }
    imu.push_back(r);
  }
  c.imu.swap(imu);
  std::vector<hal::GnssPvtSample> pvt;
  for (const hal::GnssPvtSample& p : c.pvt) {
    sdins::gnss_pvt_t m{};
    hal::to_msg(p, m);
    hal::GnssPvtSample back;
    const hal::LcmInputStatus s = hal::from_msg(m, back);
    if (s != hal::LcmInputStatus::kOk) {
      gnss_lines.reject(0, std::string("GNSS_PVT input validation: ") + hal::to_string(s));
      --gnss_lines.accepted;
      continue;
    }
    pvt.push_back(p);
  }
  c.pvt.swap(pvt);
}

nlohmann::json reference_label(const RefStats& rs, bool wanted) {
  const bool pos = rs.with_position > 0, vel = rs.with_velocity > 0, att = rs.with_attitude > 0;
  std::string source;
  if (pos) source = "vehicle_global_position";
  if (att) source += std::string(source.empty() ? "" : "+") + "vehicle_attitude";
  if (!wanted || rs.samples == 0) return nullptr;
  return {{"kind", "autopilot_estimate"},
          {"source", source.empty() ? "vehicle_local_position" : source},
          {"has_attitude", att},
          {"has_position", pos},
          {"has_velocity", vel},
          {"velocity_source", vel ? "vehicle_local_position (vx, vy, vz where v_xy_valid and v_z_valid)" : ""},
          {"timeline", rs.timeline},
          {"note", "PX4's own EKF2 estimate, not an independent truth: errors against it include its errors"}};
}

double param(const ulog::File& f, const char* name) {
  const auto it = f.parameters.find(name);
  return it == f.parameters.end() ? kNaN : it->second;
}

nlohmann::json time_fit_json(const UlogClockFit& clock, const UlogImportOptions& opt, double ekf2_delay_ms,
                             std::int64_t last_utc_us) {
  const GpsTime first_fix = fsw::gps_time(0, clock.gps_s(clock.boot0_us));
  return {
      {"pairs", clock.pairs},
      {"outliers", clock.outliers},
      {"first_fix_boot_s", static_cast<double>(clock.boot0_us) * 1e-6},
      {"first_fix_gps_week", first_fix.week},
      {"first_fix_gps_tow_s", first_fix.tow_s},
      {"offset_s", clock.offset_s},
      {"drift_ppm", clock.drift * 1e6},
      {"fitted_drift_ppm", clock.fitted_drift * 1e6},
      {"fitted_drift_sigma_ppm", std::isfinite(clock.drift_sigma) ? nlohmann::json(clock.drift_sigma * 1e6) : nlohmann::json(nullptr)},
      {"drift_applied", clock.drift_significant},
      {"residual_rms_ms", clock.residual_rms_s * 1e3},
      {"residual_max_ms", clock.residual_max_s * 1e3},
      {"gps_minus_utc_s", clock.gps_minus_utc_first_s},
      {"leap_second_in_log", clock.gps_minus_utc_first_s != clock.gps_minus_utc_last_s},
      {"leap_table_valid", last_utc_us / 1000000 < kLeapTableValidUntilUnix_s},
      {"gnss_latency_applied_s", opt.gnss_latency_s},
      {"px4_ekf2_gps_delay_ms", std::isfinite(ekf2_delay_ms) ? nlohmann::json(ekf2_delay_ms) : nlohmann::json(nullptr)},
      {"definition", "GPS time = GPS(first pair) + offset + (1 + drift) (boot - boot of the first pair); pairs: "
                     "(timestamp + timestamp_time_relative - latency, time_utc_usec + GPS-UTC) of the GNSS fixes"}};
}

UlogStreams recording_streams(const Converted& c, const std::string& imu_source, const std::string& gnss_source,
                              const std::string& ref_source, const LineStats& gnss_lines) {
  UlogStreams r;
  r.imu = import_detail::stream_of("imu", imu_source, c.imu, [](const hal::ImuRecord& x) { return x.sample.t_s; });
  const auto dup = gnss_lines.by_reason.find("duplicate epoch (same time_utc_usec)");
  r.gnss = import_detail::stream_of("gnss_pvt", gnss_source, c.pvt, [](const hal::GnssPvtSample& p) { return p.t_s; },
                                    dup == gnss_lines.by_reason.end() ? 0 : dup->second);
  r.reference = summarize_stream("reference", ref_source, c.truth_t_s);
  if (r.imu.count > 0 && r.gnss.count > 0)
    r.imu_gnss_overlap_s = std::max(0.0, std::min(r.imu.t_last_s, r.gnss.t_last_s) - std::max(r.imu.t_first_s, r.gnss.t_first_s));
  return r;
}

nlohmann::json imu_json(const Topic& it, const std::string& imu_name, const ImuReadStats& is, const StreamSummary& si,
                        double vi_cov) {
  return {{"topic", it.name()},
          {"instance", it.instance()},
          {"lines", is.lines.to_json()},
          {"axes", "PX4 body FRD = body x forward, y right, z down (no change)"},
          {"increments", imu_name == "vehicle_imu"
                             ? "delta_angle / delta_velocity as logged, over delta_angle_dt ending at timestamp_sample"
                             : "gyro_rad and accelerometer_m_s2 (means over the integration interval) times the "
                               "interval since the previous sample, ending at timestamp"},
          {"gaps", is.gaps},
          {"longest_gap_s", is.longest_gap_s},
          {"max_interval_mismatch_s", is.max_interval_mismatch_s},
          {"max_accel_time_offset_s", is.max_accel_time_offset_s},
          {"clipped_samples", is.clipped},
          {"coverage", si.span_s > 0 ? is.covered_s / si.span_s : 0.0},
          {"vehicle_imu_coverage", vi_cov}};
}

}  // namespace

UlogImportResult import_ulog_file(const ulog::File& f, const UlogImportOptions& opt) {
  if (opt.log_path.empty()) throw std::runtime_error("no output log (--log)");
  nlohmann::json sum;
  sum["format"] = "ulog";
  sum["input"] = opt.path;
  sum["ulog"] = describe_file(f);

  // GNSS and the clock.
  const Topic gt = gnss_topic(f, opt);
  if (!gt.present())
    throw std::runtime_error(opt.path + ": no GNSS messages (vehicle_gps_position / sensor_gps instance " +
                             std::to_string(opt.gnss_instance) + "): the boot clock cannot be put on GPS time");
  LineStats gnss_lines;
  std::vector<GpsRow> gps = read_gnss(gt, gnss_lines);
  if (gps.empty()) {
    std::string why;
    for (const auto& [reason, n] : gnss_lines.by_reason) why += "; " + reason + ": " + std::to_string(n);
    throw std::runtime_error(opt.path + ": " + gt.name() + " has no usable fix (" + std::to_string(gnss_lines.lines) +
                             " messages" + why + "): the boot clock cannot be put on GPS time");
  }
  const std::int64_t latency_us = static_cast<std::int64_t>(std::llround(opt.gnss_latency_s * 1e6));
  std::vector<std::pair<std::int64_t, std::int64_t>> pairs;
  for (const GpsRow& r : gps) pairs.emplace_back(r.boot_us - latency_us, r.utc_us);
  const UlogClockFit clock = fit_boot_to_gps(pairs);

  // IMU: the topic asked for, or vehicle_imu when it covers its span (true increments), else
  // sensor_combined (rates over every interval).
  const Topic sc(f, f.find("sensor_combined", opt.imu_instance)), vi(f, f.find("vehicle_imu", opt.imu_instance));
  const double vi_cov = coverage(vi, "delta_angle_dt");
  std::string imu_name = opt.imu_topic;
  if (imu_name == "auto") imu_name = vi.present() && (vi_cov >= 0.95 || !sc.present()) ? "vehicle_imu" : "sensor_combined";
  const Topic& it = imu_name == "vehicle_imu" ? vi : sc;
  if (!it.present())
    throw std::runtime_error(opt.path + ": no " + imu_name + " messages (instance " + std::to_string(opt.imu_instance) + ")");
  ImuReadStats is;
  std::vector<BootImu> imu = imu_name == "vehicle_imu" ? read_vehicle_imu(it, is) : read_sensor_combined(it, is);

  RefStats rs;
  std::vector<RefRow> ref = opt.reference ? read_reference(f, rs) : std::vector<RefRow>{};

  // The navigation time scale: the GPS week of the earliest sample.
  double first_gps = clock.gps_s(gps.front().boot_us - latency_us);
  if (!imu.empty()) first_gps = std::min(first_gps, clock.gps_s(imu.front().boot_us));
  for (const GpsRow& r : gps) first_gps = std::min(first_gps, static_cast<double>(gps_us_from_utc_us(r.utc_us)) * 1e-6);
  const int week0 = fsw::gps_time(0, first_gps).week;
  const std::int64_t week0_us = static_cast<std::int64_t>(week0) * kWeek_us;

  Converted c;
  for (const BootImu& b : imu) {
    hal::ImuRecord r = b.rec;
    r.sample.t_s = clock.nav_s(b.boot_us, week0_us);
    r.sample.dt_s = b.dt_boot_s * (1.0 + clock.drift);
    c.imu.push_back(r);
  }
  for (const GpsRow& g : gps) {
    hal::GnssPvtSample p = g.pvt;
    const std::int64_t gus = gps_us_from_utc_us(g.utc_us);  // the receiver's own time of the fix
    const GpsTime fix = gps_time_from_count(gus, 1000000);
    p.gps_week = fix.week;
    p.gps_tow_s = fix.tow_s;
    p.t_s = static_cast<double>(gus - week0_us) * 1e-6;
    c.pvt.push_back(p);
  }
  for (const RefRow& r : ref) {
    c.truth.push_back(r);
    c.truth_t_s.push_back(clock.nav_s(r.boot_us, week0_us));
  }
  validate(c, is.lines, gnss_lines);

  // Summary.
  sum["time_scale"] = {{"gps_week0", week0},
                       {"definition", "t_s = GPS time in seconds since the start of GPS week " + std::to_string(week0) +
                                          " (= GPS time of week within that week)"}};
  sum["time_fit"] = time_fit_json(clock, opt, param(f, "EKF2_GPS_DELAY"), gps.back().utc_us);
  UlogImportResult res;
  res.streams = recording_streams(c, it.name() + " instance " + std::to_string(it.instance()),
                                  gt.name() + " instance " + std::to_string(gt.instance()), rs.timeline, gnss_lines);
  sum["imu"] = imu_json(it, imu_name, is, res.streams.imu, vi_cov);
  std::uint64_t no_vel = 0;
  for (const hal::GnssPvtSample& p : c.pvt) no_vel += p.has_velocity() ? 0 : 1;
  sum["gnss_pvt"] = {{"topic", gt.name()},
                     {"instance", gt.instance()},
                     {"lines", gnss_lines.to_json()},
                     {"without_velocity", no_vel},
                     {"sigmas", "eph -> East and North, epv -> Up, s_variance_m_s (speed accuracy) -> each velocity axis"},
                     {"velocity", "NED -> ENU (E = vel_e_m_s, N = vel_n_m_s, U = -vel_d_m_s)"},
                     {"quality", "fix_type 3 -> 5 single, 4 -> 4 DGPS, 5 -> 2 RTK float, 6 -> 1 RTK fixed"}};
  sum["truth"] = {{"samples", res.streams.reference.to_json()},
                  {"with_position", rs.with_position},
                  {"with_velocity", rs.with_velocity},
                  {"with_attitude", rs.with_attitude},
                  {"position_resets", rs.position_resets},
                  {"attitude_resets", rs.attitude_resets},
                  {"out_of_order_left_out", rs.out_of_order},
                  {"attitude", "vehicle_attitude.q (FRD -> NED) turned to body -> ENU"}};
  sum["reference"] = reference_label(rs, opt.reference);
  // Every stream in the one shape (tools/stream_summary.hpp): what the starting-configuration
  // generator reads (tools::starting_filter_config) and the summary prints.
  sum["imu"]["samples"] = res.streams.imu.to_json();
  sum["gnss_pvt"]["samples"] = res.streams.gnss.to_json();
  sum["gnss_pvt"]["by_quality"] = import_detail::by_quality_json(c.pvt);
  sum["imu_gnss_overlap_s"] = res.streams.imu_gnss_overlap_s;
  sum["speed"] = import_detail::pvt_speed_json(c.pvt);
  sum["log"] = write_ulog_log(opt.log_path, c);
  sum["rejected_lines_total"] = is.lines.rejected + gnss_lines.rejected;
  res.summary = sum;
  return res;
}

UlogImportResult import_ulog(const UlogImportOptions& opt) {
  const ulog::File f = ulog::read(opt.path);
  return import_ulog_file(f, opt);
}

namespace {
std::string counts_text(const nlohmann::json& l) {
  std::string s = std::to_string(l["lines"].get<std::uint64_t>()) + " messages, " +
                  std::to_string(l["accepted"].get<std::uint64_t>()) + " used, " +
                  std::to_string(l["rejected"].get<std::uint64_t>()) + " rejected";
  for (const auto& [k, v] : l["rejected_by_reason"].items()) s += "; " + k + ": " + std::to_string(v.get<std::uint64_t>());
  for (const auto& [k, v] : l["skipped"].items()) s += "; " + std::to_string(v.get<std::uint64_t>()) + " " + k;
  return s;
}
}  // namespace

std::string ulog_import_summary_text(const nlohmann::json& j) {
  std::ostringstream o;
  const auto& u = j["ulog"];
  const auto& info = u["info"];
  const auto txt = [&](const char* k) { return info.contains(k) && info[k].is_string() ? info[k].get<std::string>() : std::string("?"); };
  o << "import ulog " << j["input"].get<std::string>() << " -> " << j["log"]["path"].get<std::string>() << "\n";
  o << "log:          ULog v" << u["version"].get<int>() << ", sys_name " << txt("sys_name") << ", ver_hw " << txt("ver_hw")
    << ", ver_sw_branch " << txt("ver_sw_branch") << ", OS " << txt("sys_os_name");
  if (!u["vehicle"].is_null())
    o << ", vehicle_type " << u["vehicle"]["vehicle_type"].get<std::string>()
      << (u["vehicle"]["is_vtol"].is_boolean() && u["vehicle"]["is_vtol"].get<bool>() ? " (VTOL)" : "");
  o << "\n              " << u["data_messages"].get<std::uint64_t>() << " data messages in " << u["topics"].size()
    << " topic instances, " << u["sync_messages"].get<std::uint64_t>() << " sync, " << u["dropouts"]["count"].get<std::uint64_t>()
    << " dropouts (" << u["dropouts"]["total_ms"].get<std::uint64_t>() << " ms); damage: " << u["damage"]["total"].get<std::uint64_t>();
  for (const auto& [k, v] : u["damage"]["by_reason"].items()) o << " " << k << " " << v.get<std::uint64_t>();
  o << " (" << u["damage"]["bytes_skipped"].get<std::uint64_t>() << " bytes skipped)\n";
  const auto& tf = j["time_fit"];
  o << "time:         boot clock -> GPS time from " << tf["pairs"].get<std::size_t>() << " GNSS fixes ("
    << tf["outliers"].get<std::size_t>() << " outliers): boot " << fmt("%.6f", tf["first_fix_boot_s"].get<double>())
    << " s = GPS week " << tf["first_fix_gps_week"].get<int>() << " tow " << fmt("%.6f", tf["first_fix_gps_tow_s"].get<double>())
    << " s; drift " << fmt("%.2f", tf["fitted_drift_ppm"].get<double>()) << " +- "
    << (tf["fitted_drift_sigma_ppm"].is_null() ? std::string("?") : fmt("%.2f", tf["fitted_drift_sigma_ppm"].get<double>()))
    << " ppm " << (tf["drift_applied"].get<bool>() ? "(applied)" : "(not significant at 3 sigma: not applied)")
    << "; residual RMS " << fmt("%.3f", tf["residual_rms_ms"].get<double>()) << " ms (max "
    << fmt("%.3f", tf["residual_max_ms"].get<double>()) << "); GPS-UTC " << tf["gps_minus_utc_s"].get<int>()
    << " s applied; latency applied " << fmt("%.3f", tf["gnss_latency_applied_s"].get<double>()) << " s";
  if (!tf["px4_ekf2_gps_delay_ms"].is_null())
    o << " (PX4 assumed EKF2_GPS_DELAY " << fmt("%.0f", tf["px4_ekf2_gps_delay_ms"].get<double>())
      << " ms: --gnss-latency to apply it)";
  o << "\n";
  if (!tf["leap_table_valid"].get<bool>()) o << "WARNING:      the log is later than the leap-second table's validity: GPS-UTC assumed\n";
  o << "time scale:   " << j["time_scale"]["definition"].get<std::string>() << "\n";
  o << "IMU:          " << j["imu"]["topic"].get<std::string>() << " " << counts_text(j["imu"]["lines"]) << "\n              "
    << stream_summary_text(j["imu"]["samples"]) << "; coverage " << fmt("%.4f", j["imu"]["coverage"].get<double>()) << ", "
    << j["imu"]["clipped_samples"].get<std::uint64_t>() << " clipped; " << j["imu"]["axes"].get<std::string>() << "\n";
  o << "GNSS_PVT:     " << j["gnss_pvt"]["topic"].get<std::string>() << " " << counts_text(j["gnss_pvt"]["lines"]) << "\n              "
    << stream_summary_text(j["gnss_pvt"]["samples"]) << "\n";
  const auto& t = j["truth"];
  o << "TRUTH:        PX4's estimate (" << t["with_position"].get<std::uint64_t>() << " with position, "
    << t["with_velocity"].get<std::uint64_t>() << " velocity, " << t["with_attitude"].get<std::uint64_t>()
    << " attitude; resets: " << t["position_resets"].get<std::uint64_t>() << " position, "
    << t["attitude_resets"].get<std::uint64_t>() << " attitude)";
  if (!j["reference"].is_null()) o << ", reference '" << j["reference"]["kind"].get<std::string>() << "' from " << j["reference"]["source"].get<std::string>();
  o << "\n              " << stream_summary_text(t["samples"]);
  o << "\nlog:          " << j["log"]["path"].get<std::string>() << ", " << j["log"]["events"].get<std::uint64_t>() << " events (";
  bool first = true;
  for (const auto& [k, v] : j["log"]["per_channel"].items()) {
    o << (first ? "" : ", ") << k << " " << v.get<std::uint64_t>();
    first = false;
  }
  o << ")\n";
  return o.str();
}

}  // namespace tools
