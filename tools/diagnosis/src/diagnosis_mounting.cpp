#include "tools/diagnosis_mounting.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <stdexcept>

#include "fsw/driver.hpp"
#include "fsw/frames.hpp"
#include "tools/diagnosis_intervals.hpp"
#include "tools/number_text.hpp"

namespace tools {
namespace {

using fsw::Block;
using fsw::LayoutDiag;

constexpr double kZ975 = 1.959963984540054;

/// Student t, 97.5% quantile, for 1..30 degrees of freedom (standard table values).
double t975(int dof) {
  static constexpr double kT[] = {12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228,
                                  2.201,  2.179, 2.160, 2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086,
                                  2.080,  2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042};
  if (dof < 1) return std::numeric_limits<double>::infinity();
  return dof <= 30 ? kT[dof - 1] : kZ975;
}

/// The mounting angles of a direction of travel u in the IMU's axes (x forward, y right, z down).
double yaw_of(const fsw::Vec3& u) { return std::atan2(-u.y(), u.x()) * fsw::kRadToDeg; }
double pitch_of(const fsw::Vec3& u) { return std::asin(std::clamp(u.z() / u.norm(), -1.0, 1.0)) * fsw::kRadToDeg; }

double wrap180(double a) {
  a = std::fmod(a + 180.0, 360.0);
  return (a < 0.0 ? a + 360.0 : a) - 180.0;
}

double mean(const std::vector<double>& v, std::size_t a, std::size_t b) {
  double s = 0.0;
  for (std::size_t i = a; i < b; ++i) s += v[i];
  return b > a ? s / static_cast<double>(b - a) : 0.0;
}

/// One angle from its epochs' values (already unwrapped) and attitude sigmas.
MountingAngle angle_from(const std::vector<double>& x, const std::vector<double>& att_sigma, int blocks, double t) {
  MountingAngle a;
  const std::size_t n = x.size();
  a.estimate_deg = mean(x, 0, n);
  double ss = 0.0, att2 = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    ss += (x[i] - a.estimate_deg) * (x[i] - a.estimate_deg);
    att2 += att_sigma[i] * att_sigma[i];
  }
  a.spread_deg = n > 1 ? std::sqrt(ss / static_cast<double>(n - 1)) : 0.0;
  a.attitude_sigma_deg = n > 0 ? std::sqrt(att2 / static_cast<double>(n)) : 0.0;
  std::vector<double> m;
  for (int b = 0; b < blocks; ++b) m.push_back(mean(x, n * static_cast<std::size_t>(b) / static_cast<std::size_t>(blocks),
                                                    n * static_cast<std::size_t>(b + 1) / static_cast<std::size_t>(blocks)));
  const double mm = mean(m, 0, m.size());
  double bs = 0.0;
  for (double v : m) bs += (v - mm) * (v - mm);
  a.scatter_se_deg = blocks > 1 ? std::sqrt(bs / (blocks - 1) / blocks) : 0.0;
  a.sigma_deg = std::hypot(a.scatter_se_deg, a.attitude_sigma_deg);
  const double half = std::hypot(t * a.scatter_se_deg, kZ975 * a.attitude_sigma_deg);
  a.lo_deg = a.estimate_deg - half;
  a.hi_deg = a.estimate_deg + half;
  a.first_half_deg = mean(x, 0, n / 2);
  a.second_half_deg = mean(x, n / 2, n);
  a.z2 = a.sigma_deg > 0.0 ? (a.estimate_deg / a.sigma_deg) * (a.estimate_deg / a.sigma_deg) : 0.0;
  a.named = a.z2 > kMountingDeviance;
  return a;
}


std::string angle_text(const MountingAngle& a) {
  return fmt("%.2f", a.estimate_deg) + " deg, 95% [" + fmt("%.2f", a.lo_deg) + ", " + fmt("%.2f", a.hi_deg) +
         "] (scatter " + fmt("%.2f", a.scatter_se_deg) + ", attitude " + fmt("%.2f", a.attitude_sigma_deg) +
         " deg 1-sigma; halves " + fmt("%.2f", a.first_half_deg) + " / " + fmt("%.2f", a.second_half_deg) + ")";
}

}  // namespace

MountingFromTravel mounting_from_samples(const std::vector<double>& yaw_deg, const std::vector<double>& pitch_deg,
                                         const std::vector<double>& yaw_att_sigma_deg,
                                         const std::vector<double>& pitch_att_sigma_deg) {
  MountingFromTravel m;
  const std::size_t n = yaw_deg.size();
  if (pitch_deg.size() != n || yaw_att_sigma_deg.size() != n || pitch_att_sigma_deg.size() != n)
    throw std::invalid_argument("mounting_from_samples: the four series differ in length");
  m.epochs = static_cast<int>(n);
  if (m.epochs < kMountingMinEpochs) {
    m.why = std::to_string(n) + " epochs at speed, fewer than " + std::to_string(kMountingMinEpochs);
    return m;
  }
  m.determined = true;
  m.blocks = kMountingBlocks;
  m.t_quantile = t975(m.blocks - 1);
  // Yaw about its circular mean, so that a mounting near +-180 deg does not average to 0.
  double s = 0.0, c = 0.0;
  for (double y : yaw_deg) {
    s += std::sin(y * fsw::kDegToRad);
    c += std::cos(y * fsw::kDegToRad);
  }
  const double centre = std::atan2(s, c) * fsw::kRadToDeg;
  std::vector<double> yaw(n);
  for (std::size_t i = 0; i < n; ++i) yaw[i] = centre + wrap180(yaw_deg[i] - centre);
  m.yaw = angle_from(yaw, yaw_att_sigma_deg, m.blocks, m.t_quantile);
  m.pitch = angle_from(pitch_deg, pitch_att_sigma_deg, m.blocks, m.t_quantile);
  m.found = m.yaw.named || m.pitch.named;
  return m;
}

MountingFromTravel estimate_mounting_from_travel(const RecordedData& data, const DiagnosisConfig& cfg) {
  // The baseline (the 15-state model and the receiver's states): every catalogue component frozen.
  fsw::FlightAppConfig app_cfg = cfg.app;
  app_cfg.exec.ekf.frozen_states = 0;
  for (const Candidate& c : diagnosis_candidates()) app_cfg.exec.ekf.frozen_states |= std::uint64_t{1} << c.state;
  auto driver = std::make_unique<fsw::FlightDriver<LayoutDiag>>();  // the 56-state application: not on the stack
  const auto& app = driver->app();
  MountingFromTravel none;
  none.why = "the flight configuration does not initialise";
  if (driver->init(app_cfg) != fsw::Status::kOk) return none;
  std::vector<double> yaw, pitch, yaw_att, pitch_att;
  double min_speed = kMountingMinSpeed_mps;
  const auto keep = [&](const fsw::InputEvent& in) {
    const bool raw = in.kind == fsw::InputEvent::Kind::kGnssRaw, pvt = in.kind == fsw::InputEvent::Kind::kGnssPvt;
    return (!raw && !pvt) || cfg.gnss_source == (raw ? cfg::GnssSource::kRaw : cfg::GnssSource::kPvt);
  };
  const auto observe = [&](const fsw::InputEvent& in, fsw::Status st, const fsw::FrameOutput& out) {
    if (in.kind != fsw::InputEvent::Kind::kImu || st != fsw::Status::kOk || !out.nav_valid || !app.initialised()) return;
    if (!out.ekf_ran || !out.ekf_updated || out.nav.t_s < app.health().init_t_s + kProfileBurnIn_s) return;
    const auto& P = app.executive().ekf().P();
    const int iv = LayoutDiag::offset(Block::kVelocity), ia = LayoutDiag::offset(Block::kAttitude);
    const double speed = out.nav.vel_enu_mps.norm();
    const double vel_sigma_h = std::sqrt(std::max(0.0, P(iv, iv) + P(iv + 1, iv + 1)));
    const double threshold = std::max(kMountingMinSpeed_mps, kMountingSpeedSigmas * vel_sigma_h);
    if (!(speed >= threshold)) return;
    min_speed = std::max(min_speed, threshold);
    const fsw::Mat3 C_n_b = out.nav.C_b_n().transpose();
    const fsw::Vec3 w = out.nav.vel_enu_mps / speed;
    const fsw::Vec3 u = C_n_b * w;
    // The filter's attitude error phi (ENU) mapped onto each angle: the gradient by differences.
    const Eigen::Matrix3d P_phi = P.template block<3, 3>(ia, ia);
    Eigen::Vector3d g_yaw, g_pitch;
    constexpr double kStep_rad = 1e-6;
    for (int k = 0; k < 3; ++k) {
      const fsw::Vec3 phi = fsw::Vec3::Unit(k) * kStep_rad;
      const fsw::Vec3 uk = C_n_b * (w + phi.cross(w));
      g_yaw(k) = wrap180(yaw_of(uk) - yaw_of(u)) / kStep_rad;
      g_pitch(k) = (pitch_of(uk) - pitch_of(u)) / kStep_rad;
    }
    yaw.push_back(yaw_of(u));
    pitch.push_back(pitch_of(u));
    yaw_att.push_back(std::sqrt(std::max(0.0, g_yaw.dot(P_phi * g_yaw))));
    pitch_att.push_back(std::sqrt(std::max(0.0, g_pitch.dot(P_phi * g_pitch))));
  };
  RecordedSource recording(data);
  auto inputs = fsw::filtered(recording, keep);
  auto observer = fsw::after_each(observe);
  fsw::drive(inputs, *driver, observer);
  MountingFromTravel m = mounting_from_samples(yaw, pitch, yaw_att, pitch_att);
  m.min_speed_mps = min_speed;
  m.heading_offset_configured_deg = cfg.app.init_heading_offset_rad * fsw::kRadToDeg;
  m.track_init = cfg.app.init_mode == fsw::InitMode::kTrack;
  if (!app.initialised()) m.why = "the flight software never initialised";
  return m;
}

nlohmann::json mounting_json(const MountingFromTravel& m) {
  const auto angle = [](const MountingAngle& a) {
    return nlohmann::json{{"estimate_deg", a.estimate_deg},
                          {"interval_95_deg", {a.lo_deg, a.hi_deg}},
                          {"sigma_deg", a.sigma_deg},
                          {"scatter_se_deg", a.scatter_se_deg},
                          {"attitude_sigma_deg", a.attitude_sigma_deg},
                          {"spread_deg", a.spread_deg},
                          {"halves_deg", {a.first_half_deg, a.second_half_deg}},
                          {"statistic", a.z2},
                          {"named", a.named}};
  };
  nlohmann::json j = {{"method", "direction of travel in the IMU's axes (the navigation solution's velocity turned by its "
                                 "attitude), mean over the epochs at speed, block-means scatter plus the filter's attitude sigma"},
                      {"assumption", "the vehicle's velocity lies along its own x axis on average (no mean sideslip, crab "
                                     "or angle of attack)"},
                      {"determined", m.determined},
                      {"found", m.found},
                      {"epochs", m.epochs},
                      {"blocks", m.blocks},
                      {"min_speed_mps", m.min_speed_mps},
                      {"t_quantile", m.t_quantile},
                      {"threshold", kMountingDeviance},
                      {"applied", m.yaw.named && m.track_init ? nlohmann::json("init.heading_offset_deg")
                                                          : nlohmann::json(nullptr)}};
  if (!m.determined) j["why"] = m.why;
  if (m.determined) {
    j["yaw"] = angle(m.yaw);
    j["pitch"] = angle(m.pitch);
  }
  return j;
}

std::vector<std::string> mounting_terminal_lines(const MountingFromTravel& m) {
  if (!m.determined) return {"mounting (direction of travel): not determined: " + m.why};
  const auto line = [&](const char* name, const MountingAngle& a) {
    return std::string("mounting ") + name + " (direction of travel, " + std::to_string(m.epochs) + " epochs at >= " +
           fmt("%.2f", m.min_speed_mps) + " m/s): " + (a.named ? "found " : "not named (interval at p = 0.001 holds 0): ") +
           angle_text(a);
  };
  std::vector<std::string> v = {line("yaw", m.yaw), line("pitch", m.pitch)};
  if (m.yaw.named)
    v.push_back(m.track_init ? "mounting: the yaw is the track initialisation's init.heading_offset_deg (applied before every search)"
                             : "mounting: not applied (this initialisation does not use the track; with init.mode = \"track\" "
                               "set init.heading_offset_deg = " + fmt("%.1f", m.yaw.estimate_deg) + ")");
  if (m.pitch.named) v.push_back("mounting: the pitch enters no part of the model (the levelling carries it): reported only");
  return v;
}

std::string mounting_report_md(const MountingFromTravel& m) {
  std::string s = "## The mounting\n\n";
  if (!m.determined) return s + "Not determined from the direction of travel: " + m.why + ".\n\n";
  s += "The direction of travel in the IMU's axes (the navigation solution's velocity turned into them), over " +
       std::to_string(m.epochs) + " GNSS-updated epochs at >= " + fmt("%.2f", m.min_speed_mps) +
       " m/s; the interval adds the scatter of " + std::to_string(m.blocks) +
       " block means (Student t) and the filter's own attitude sigma, taken as fully correlated. It assumes the vehicle "
       "moves along its own x axis on average (an aircraft's angle of attack adds to the pitch, a crab angle to the "
       "yaw).\n\n| angle | estimate | 95% interval | scatter s.e. | attitude sigma | first / second half | named |\n"
       "|---|---|---|---|---|---|---|\n";
  const auto row = [&](const char* name, const MountingAngle& a) {
    s += std::string("| ") + name + " | " + fmt("%.2f", a.estimate_deg) + " deg | [" + fmt("%.2f", a.lo_deg) + ", " +
         fmt("%.2f", a.hi_deg) + "] | " + fmt("%.2f", a.scatter_se_deg) + " | " + fmt("%.2f", a.attitude_sigma_deg) + " | " +
         fmt("%.2f", a.first_half_deg) + " / " + fmt("%.2f", a.second_half_deg) + " | " + (a.named ? "**yes**" : "no") + " |\n";
  };
  row("yaw (IMU heading minus track)", m.yaw);
  row("pitch (IMU pitch above the flight path)", m.pitch);
  if (m.pitch.named) s += "\nThe pitch enters no part of the model (the levelling carries the sensor's attitude): reported only.\n";
  if (m.yaw.named)
    s += m.track_init ? "\nThe yaw is applied to `init.heading_offset_deg` (the track initialisation) before every search.\n"
                      : "\nNot applied: this initialisation does not use the track (with `init.mode = \"track\"`, "
                        "`init.heading_offset_deg = " + fmt("%.1f", m.yaw.estimate_deg) + "`).\n";
  return s + "\n";
}

}  // namespace tools
