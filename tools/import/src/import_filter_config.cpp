// The starting filter configuration of an imported recording (tools/import_describe.hpp): the
// rates and the GNSS source follow from the import summary's streams; every value says where it
// came from. The sensor noise is a consumer-MEMS starting point for the user to replace.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <utility>

#include "tools/import_describe.hpp"

namespace tools {
namespace {

std::string num(double v, const char* f = "%.6g") {
  char b[64];
  std::snprintf(b, sizeof(b), f, v);
  std::string s = b;
  if (s.find_first_of(".eE") == std::string::npos && s.find("inf") == std::string::npos && s.find("nan") == std::string::npos)
    s += ".0";
  return s;
}

/// j[key], or null when j has no such key (const operator[] must not be used for a missing key).
const nlohmann::json& at(const nlohmann::json& j, const char* key) {
  static const nlohmann::json kNull;
  return j.is_object() && j.contains(key) ? j[key] : kNull;
}

/// A number of j (null, missing or not a number: def).
double number_at(const nlohmann::json& j, const char* key, double def) {
  const nlohmann::json& v = at(j, key);
  return v.is_number() ? v.get<double>() : def;
}

/// A stream's rates (tools/stream_summary.hpp): {mean, nominal}, 0 with fewer than two samples.
std::pair<double, double> rates_of(const nlohmann::json& samples) {
  if (number_at(samples, "count", 0) < 2) return {0.0, 0.0};
  return {number_at(samples, "mean_rate_hz", 0.0), number_at(samples, "rate_hz", 0.0)};
}

/// The navigation rate from the IMU's: samples per frame so that frames run at <= 200 Hz.
struct Rates {
  double imu_hz = 0.0, nav_hz = 0.0, gnss_hz = 0.0, ekf_hz = 0.0;
  int samples_per_frame = 1, frames_per_ekf = 0, latency_frames = 1;
  std::string imu_from, gnss_from;
};

Rates rates_from(const nlohmann::json& s) {
  Rates r;
  if (at(s, "imu").is_object()) {
    const auto& i = at(s, "imu");
    // The mean rate over the span, unless gaps make it differ from the median interval's by more
    // than 2 % (quantised time tags make single intervals, and so the median, jitter).
    const auto [mean, med] = rates_of(at(i, "samples"));
    if (mean > 0.0 && (med <= 0.0 || std::abs(mean - med) <= 0.02 * mean)) {
      r.imu_hz = mean;
      r.imu_from = "the IMU's mean rate over its span";
    } else if (med > 0.0) {
      r.imu_hz = med;
      r.imu_from = "the IMU's median interval (its mean rate counts gaps)";
    }
  }
  if (!(r.imu_hz > 0.0)) {
    r.imu_hz = 200.0;
    r.imu_from = "no IMU in the import: the flight software's 200 Hz";
  }
  // A rate within 1 % of a multiple of 200 Hz counts as that multiple (a clock ratio away from it).
  r.samples_per_frame = std::max(1, static_cast<int>(std::ceil(r.imu_hz / 200.0 - 0.01)));
  r.nav_hz = r.imu_hz / r.samples_per_frame;
  // Whole hertz when the rate is within 1 % of one (the measured rate is a clock ratio away from it).
  if (std::abs(r.nav_hz - std::round(r.nav_hz)) <= 0.01 * r.nav_hz) r.nav_hz = std::round(r.nav_hz);
  // The GNSS: the nominal rate (median interval), so that lost epochs do not slow the EKF.
  const auto gnss_rate = [&](const char* key, const char* what) {
    const auto [mean, nominal] = rates_of(at(at(s, key), "samples"));
    const double hz = nominal > 0.0 ? nominal : mean;
    if (hz > r.gnss_hz) {
      r.gnss_hz = hz;
      r.gnss_from = what;
    }
  };
  gnss_rate("gnss_pvt", "the GNSS solutions' rate");
  gnss_rate("gnss_raw", "the raw epochs' rate");
  if (!(r.gnss_hz > 0.0)) {
    r.gnss_hz = 1.0;
    r.gnss_from = "no GNSS in the import: 1 Hz";
  }
  r.frames_per_ekf = std::max(2, static_cast<int>(std::lround(r.nav_hz / r.gnss_hz)));
  r.ekf_hz = r.nav_hz / r.frames_per_ekf;
  // 50 ms (the 1 Hz group's deadline at 200 Hz), and always below the frames of one EKF step.
  r.latency_frames = std::clamp(static_cast<int>(std::lround(0.05 * r.nav_hz)), 1, r.frames_per_ekf - 1);
  return r;
}

}  // namespace

std::string starting_filter_config(const nlohmann::json& s, const std::string& name) {
  const Rates r = rates_from(s);
  std::ostringstream o;
  o << "# Starting filter configuration written by `sdins import` for "
    << (at(s, "input").is_string() ? at(s, "input").get<std::string>() : std::string("?")) << ".\n"
    << "# Every value below says where it came from; the rates follow the data, the sensor noise is a\n"
    << "# consumer-MEMS starting point: replace it with your IMU's datasheet values (config/README.md).\n"
    << "# Use: sdins replay LOG --filter-config THIS_FILE\n";
  o << "name = \"" << name << "\"\n";
  o << "description = \"Imported recording (starting configuration from the import summary)\"\n\n";

  const double wait_s = std::min(0.2, 0.4 / r.ekf_hz);
  o << "[executive]\n"
    << "imu_samples_per_frame = " << r.samples_per_frame << "   # " << r.imu_from << ": " << num(r.imu_hz, "%.2f")
    << " Hz IMU, navigation frames at <= 200 Hz\n"
    << "nav_rate_hz = " << num(r.nav_hz, "%.10g") << "   # IMU rate / imu_samples_per_frame\n"
    << "ekf_rate_hz = " << num(r.ekf_hz, "%.10g") << "   # " << r.gnss_from << " " << num(r.gnss_hz, "%.3f")
    << " Hz: one EKF step per GNSS epoch, " << r.frames_per_ekf << " navigation frames each\n"
    << "ekf_latency_frames = " << r.latency_frames << "   # 50 ms of frames, below the " << r.frames_per_ekf
    << " frames per EKF step (nav_rate_hz / ekf_rate_hz)\n"
    << "gnss_wait_s = " << num(wait_s) << "   # min(0.2 s, 0.4 EKF intervals): how long a due EKF step waits for its epoch\n"
    << "max_gnss_age_s = " << num(wait_s) << "   # an epoch older than this at use is stale (as gnss_wait_s)\n"
    << "frame_budget_s = " << num(1.0 / r.nav_hz) << "   # one navigation frame\n\n";

  // GNSS: raw pseudoranges when the import fitted almanacs for at least four satellites, else solutions.
  std::size_t almanac_prns = 0;
  almanac_prns = at(at(s, "almanac"), "written").size();
  const bool have_pvt = number_at(at(at(s, "gnss_pvt"), "samples"), "count", 0) > 0;
  const bool raw = almanac_prns >= 4 && !have_pvt;
  o << "[gnss]\n";
  if (raw) {
    o << "source = \"raw\"   # raw epochs with almanacs fitted for " << almanac_prns << " satellites (>= 4)\n";
  } else {
    int max_q = 1;
    if (have_pvt && at(at(s, "gnss_pvt"), "by_quality").is_object())
      for (const auto& [k, v] : at(at(s, "gnss_pvt"), "by_quality").items()) {
        const int q = std::stoi(k);
        if (q >= 1 && q <= 6 && v.get<std::uint64_t>() > 0) max_q = std::max(max_q, q);
      }
    o << "source = \"pvt\"   # "
      << (have_pvt ? "GNSS solutions in the log" + std::string(almanac_prns > 0 ? " (raw epochs too, but with almanacs for " +
                                                                                       std::to_string(almanac_prns) + " satellites)" : "")
                   : std::string("no GNSS solutions: edit (the raw path needs almanacs for >= 4 satellites)"))
      << "\n"
      << "pvt_max_quality = " << max_q << "   # the worst solution kind present (1 fixed, 2 float, 3 SBAS, 4 DGPS, 5 single, 6 PPP)\n"
      << "pvt_pos_sigma_floor_m = 0.3   # the shipped data sets' floor: a solver's cm sigmas ignore timing and lever arm\n"
      << "pvt_vel_sigma_floor_mps = 0.1\n";
  }
  o << "\n";
  o << "[imu]\n"
    << "# Consumer MEMS (the GNSS_IMU board of config/datasets/gnss-imu-drive.toml): replace with your IMU's values.\n"
    << "arw_deg_per_rthr = 1.0\n"
    << "vrw_mps_per_rthr = 0.3\n"
    << "gyro_bias_sigma_degph = 1000.0\n"
    << "accel_bias_sigma_mg = 30.0\n"
    << "gyro_bias_rw_radps_per_rts = 5e-4\n"
    << "accel_bias_rw_mps2_per_rts = 1e-3\n\n";

  double min_speed = 3.0;
  std::string speed_from = "no velocity in the import: the shipped default";
  if (at(s, "speed").is_object()) {
    const double p90 = number_at(at(s, "speed"), "p90_mps", 0.0);
    min_speed = std::clamp(0.3 * p90, 0.5, 5.0);
    speed_from = "0.3 x the 90th percentile horizontal speed " + num(p90, "%.2f") + " m/s of the " +
                 (at(at(s, "speed"), "source").is_string() ? at(at(s, "speed"), "source").get<std::string>() : std::string("GNSS solutions")) + ", within [0.5, 5] m/s";
  }
  o << "[init]\n"
    << "mode = \"track\"   # heading from the GNSS track once moving; \"static\" for a long rest with a gyro that senses the Earth rate,\n"
    << "                 # \"velocity_matching\" for an unknown mounting yaw (docs/import.md, Initialisation modes)\n"
    << "min_speed_mps = " << num(min_speed, "%.2f") << "   # " << speed_from << "\n"
    << "levelling_samples = " << std::max(1, static_cast<int>(std::lround(r.nav_hz))) << "   # 1 s of specific force\n";
  return o.str();
}

}  // namespace tools
