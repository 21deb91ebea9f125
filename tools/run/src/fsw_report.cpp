#include "tools/fsw_report.hpp"

#include "tools/timing_stats.hpp"

#include <cinttypes>
#include <cstdio>

namespace tools {

using nlohmann::json;

std::string digest_hex(std::uint64_t d) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "%016" PRIx64, d);
  return buf;
}

json can_rx_json(const hal::CanRxHealth& h) {
  json j = json::object();
  h.for_each([&j](const char* name, std::uint32_t v) { j[name] = v; });
  j["rejections"] = h.rejections();
  return j;
}

json last_nav_json(const fsw::NavState& n) {
  return {{"t_s", n.t_s},
          {"lat_deg", n.llh.x() * fsw::kRadToDeg},
          {"lon_deg", n.llh.y() * fsw::kRadToDeg},
          {"height_m", n.llh.z()},
          {"vel_enu_mps", {n.vel_enu_mps.x(), n.vel_enu_mps.y(), n.vel_enu_mps.z()}},
          {"q_b_n_wxyz", {n.q_b_n.w(), n.q_b_n.x(), n.q_b_n.y(), n.q_b_n.z()}}};
}

json app_json(const fsw::FlightAppHealth& a) {
  return {{"imu_received", a.imu_received},       {"imu_before_init", a.imu_before_init},
          {"imu_rejected", a.imu_rejected},       {"gnss_received", a.gnss_received},
          {"gnss_rejected", a.gnss_rejected},     {"gnss_before_init", a.gnss_before_init},
          {"init_no_fix", a.init_no_fix},         {"init_bad_geometry", a.init_bad_geometry},
          {"init_too_slow", a.init_too_slow},     {"init_not_level", a.init_not_level},
          {"almanac_received", a.almanac_received}, {"almanac_rejected", a.almanac_rejected},
          {"gnss_no_almanac", a.conversion.no_almanac}, {"gnss_unhealthy", a.conversion.unhealthy},
          {"gnss_invalid", a.conversion.invalid}, {"gnss_duplicate_prn", a.conversion.duplicate_prn},
          {"init_satellites", a.init_fix.n_used}, {"init_pdop", a.init_fix.pdop},
          {"pvt_received", a.pvt_received},       {"pvt_rejected", a.pvt_rejected},
          {"pvt_before_init", a.pvt_before_init},
          {"init_moving", a.init_moving},         {"init_aligning", a.init_aligning},
          {"init_align_restarts", a.init_align_restarts}, {"init_align_failed", a.init_align_failed},
          {"init_mode", fsw::to_string(a.init_mode)}, {"init_align_s", a.init_align_s},
          {"init_roll_deg", a.init_euler_rad.x() * fsw::kRadToDeg},
          {"init_pitch_deg", a.init_euler_rad.y() * fsw::kRadToDeg},
          {"init_heading_deg", a.init_euler_rad.z() * fsw::kRadToDeg},
          {"init_att_sigma_deg", {a.init_att_sigma_rad.x() * fsw::kRadToDeg, a.init_att_sigma_rad.y() * fsw::kRadToDeg,
                                  a.init_att_sigma_rad.z() * fsw::kRadToDeg}},
          {"init_vm_gyro_bias_dps", {a.vm_gyro_bias_radps.x() * fsw::kRadToDeg, a.vm_gyro_bias_radps.y() * fsw::kRadToDeg,
                                     a.vm_gyro_bias_radps.z() * fsw::kRadToDeg}},
          {"init_vm_accel_bias_mps2", {a.vm_accel_bias_mps2.x(), a.vm_accel_bias_mps2.y(), a.vm_accel_bias_mps2.z()}}};
}

json executive_json(const fsw::ExecutiveHealth& e) {
  json j;
#define SDINS_JSON_COUNTER(type, name, doc) j[#name] = e.name;
  FSW_EXECUTIVE_HEALTH_COUNTERS(SDINS_JSON_COUNTER)
  FSW_EXECUTIVE_PVT_COUNTERS(SDINS_JSON_COUNTER)
#undef SDINS_JSON_COUNTER
  j["cov_repairs"] = e.ekf.cov_repairs;
  j["nonfinite_rejected"] = e.ekf.nonfinite_rejected;
  j["nis_divergence_windows"] = e.ekf.divergence_windows;
  j["filter_resets"] = e.ekf.resets;
  return j;
}

json fsw_summary_json(const hal::FswNode& node) {
  const hal::FswNodeSummary& s = node.summary();
  const fsw::FlightAppHealth& a = node.app_health();
  const auto& tel = node.sink().telemetry();
  json j;
  j["initialised"] = a.initialised;
  j["init_t_s"] = a.init_t_s;
  j["nav_frames"] = s.nav_frames;
  j["digest"] = digest_hex(s.digest);
  j["last_nav"] = last_nav_json(s.last_nav);
  j["app"] = app_json(a);
  j["executive"] = executive_json(node.exec_health());
  {  // the 1 Hz group's thread (lockstep: the 200 Hz group is not timed here; sdins fsw --realtime does)
    const hal::EkfGroupTimes& g = node.ekf_group_times();
    const TimingStats t = timing_stats(g.exec_s);
    const fsw::ExecutiveHealth& e = node.exec_health();
    j["ekf_group"] = {{"thread", !g.exec_s.empty()}, {"runs", t.n},           {"median_us", t.median_us},
                      {"p99_us", t.p99_us},          {"max_us", t.max_us},    {"slips", e.ekf_slips},
                      {"late", e.ekf_late},          {"lockstep_waits", g.waits}, {"lockstep_wait_max_s", g.wait_max_s}};
  }
  j["telemetry"] = {{"network", tel.network_used()},      {"network_given_up", tel.network_given_up()},
                    {"url", tel.url()},                     {"published", tel.published()},
                    {"logged", tel.logged()},               {"send_failures", tel.send_failures()},
                    {"log_failures", tel.log_failures()}};
  return j;
}

void print_configuration_warnings(const fsw::ExecutiveHealth& e) {
  if (e.frame_rate_mismatch > 0)
    std::printf("WARNING: %u one-second windows of navigation frames (nav_rate_hz frames each) were more than 10%% "
                "off 1 s of IMU time: imu_samples_per_frame does not match the IMU's rate, and the rates derived "
                "from nav_rate_hz are wrong (docs/faults.md)\n",
                e.frame_rate_mismatch);
}

std::string telemetry_network_text(const hal::LcmTelemetry& tel) {
  if (tel.url() == "none") return "network off (lcm url 'none')";
  if (!tel.network_used()) return "network unavailable on " + tel.url() + " (log only)";
  if (tel.network_given_up())
    return tel.url() + " (network given up after " + std::to_string(tel.send_failures()) + " failed sends)";
  return tel.url();
}

void print_fsw_summary(const hal::FswNode& node) {
  const hal::FswNodeSummary& s = node.summary();
  const fsw::FlightAppHealth& a = node.app_health();
  const fsw::ExecutiveHealth& e = node.exec_health();
  const auto& tel = node.sink().telemetry();
  if (!a.initialised) {
    std::printf("flight software: NOT initialised (%u IMU samples, %u GNSS epochs, %u GNSS solutions received; no fix "
                "%u, geometry %u, too slow %u, levelling %u, no almanac %u)\n",
                a.imu_received, a.gnss_received, a.pvt_received, a.init_no_fix, a.init_bad_geometry, a.init_too_slow, a.init_not_level,
                a.conversion.no_almanac);
  } else {
    std::printf("flight software: initialised at t = %.3f s (%d satellites, PDOP %.2f); %llu navigation frames, "
                "digest %s\n",
                a.init_t_s, a.init_fix.n_used, a.init_fix.pdop, static_cast<unsigned long long>(s.nav_frames),
                digest_hex(s.digest).c_str());
    std::printf("initialisation: %s, roll %.2f pitch %.2f heading %.2f deg (sigma %.2f %.2f %.2f deg), alignment "
                "window %.2f s\n",
                fsw::to_string(a.init_mode), a.init_euler_rad.x() * fsw::kRadToDeg, a.init_euler_rad.y() * fsw::kRadToDeg,
                a.init_euler_rad.z() * fsw::kRadToDeg, a.init_att_sigma_rad.x() * fsw::kRadToDeg,
                a.init_att_sigma_rad.y() * fsw::kRadToDeg, a.init_att_sigma_rad.z() * fsw::kRadToDeg, a.init_align_s);
  }
  if (a.init_moving + a.init_aligning + a.init_align_restarts + a.init_align_failed > 0)
    std::printf("alignment: %u epochs moving (window restarted), %u aligning, %u window restarts, %u failed\n",
                a.init_moving, a.init_aligning, a.init_align_restarts, a.init_align_failed);
  std::printf("EKF: %u runs, %u updates, %u without GNSS; pr used/gated %u/%u, rate used/gated %u/%u; "
              "overruns %u; fsw errors %u; covariance repairs %u; resets %u\n",
              e.ekf_runs, e.ekf_updates, e.ekf_without_gnss, e.pr_used, e.pr_rejected, e.prr_used, e.prr_rejected,
              e.overruns, e.fsw_errors, e.ekf.cov_repairs, e.ekf.resets);
  print_configuration_warnings(e);
  if (e.pvt_received > 0)
    std::printf("GNSS solutions: %u received, %u stale, %u replaced, %u unused; position used/gated %u/%u, velocity "
                "used/gated %u/%u\n",
                e.pvt_received, e.pvt_stale, e.pvt_replaced, e.pvt_unused, e.pos_used, e.pos_rejected, e.vel_used,
                e.vel_rejected);
  std::printf("telemetry: %s, %llu published, %llu logged\n", telemetry_network_text(tel).c_str(),
              static_cast<unsigned long long>(tel.published()), static_cast<unsigned long long>(tel.logged()));
}

}  // namespace tools
