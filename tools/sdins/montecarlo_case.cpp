#include "montecarlo_case.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "sim/almanac.hpp"

namespace sdins {
namespace {

using nlohmann::json;

json enu(const std::array<double, 3>& v, double scale) {
  return json{{"E", v[0] * scale}, {"N", v[1] * scale}, {"U", v[2] * scale}};
}

/// Index of the first epoch after the first turn has ended, or the last epoch.
std::size_t after_first_turn(const tools::ModelStats& s) {
  bool seen = false;
  for (std::size_t e = 0; e < s.turning.size(); ++e) {
    if (s.turning[e]) seen = true;
    if (seen && !s.turning[e]) return e;
  }
  return s.turning.empty() ? 0 : s.turning.size() - 1;
}

json health_json(const fsw::ExecutiveHealth& h) {
  return json{{"ekf_runs", h.ekf_runs},         {"ekf_updates", h.ekf_updates}, {"ekf_without_gnss", h.ekf_without_gnss},
              {"imu_rejected", h.imu_rejected}, {"gnss_epochs", h.gnss_epochs}, {"gnss_stale", h.gnss_stale},
              {"pr_used", h.pr_used},           {"prr_used", h.prr_used},       {"pr_rejected", h.pr_rejected},
              {"prr_rejected", h.prr_rejected}, {"obs_invalid", h.obs_invalid}, {"fsw_errors", h.fsw_errors}};
}

}  // namespace

CaseResult run_case(const sim::Scenario& sc, const tools::MonteCarloConfig& mc, const std::string& out_dir,
                    const std::string& prefix) {
  const auto t0 = std::chrono::steady_clock::now();
  const sim::AlmanacParseResult alm = sim::parse_yuma_file(sim::almanac_path(sc.gps));
  if (!alm.ok()) throw std::runtime_error(alm.error);
  const tools::TruthTrack truth = tools::TruthTrack::generate(sc);
  const std::vector<tools::RunResult> results = tools::run_many(sc, truth, *alm.almanac, mc);
  CaseResult r;
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.written = true;
  r.models = json::array();
  double sim_s = 0, mech_s = 0, ekf_s = 0;
  for (const auto& x : results) {
    sim_s += x.wall_sim_s;
    mech_s += x.wall_mech_s;
    ekf_s += x.wall_ekf_s;
  }
  for (std::size_t m = 0; m < mc.models.size(); ++m) {
    tools::ModelStats s = tools::reduce(results, m, mc.models[m], truth);
    const std::string csv = prefix + "stats_" + tools::model_name(mc.models[m]) + ".csv";
    tools::write_stats_csv(s, (std::filesystem::path(out_dir) / csv).string());
    const std::size_t last = s.t_s.size() - 1, aft = after_first_turn(s);
    json sensors = json::array();
    for (const auto& x : s.sensors) {
      sensors.push_back({{"name", x.name},
                         {"unit", x.unit},
                         {"initial_sigma", x.initial_sigma},
                         {"rms_residual", x.residual},
                         {"filter_sigma", x.sigma},
                         {"converged", x.residual <= 0.5 * x.initial_sigma}});
    }
    r.models.push_back({{"model", tools::model_name(mc.models[m])},
                        {"runs", s.runs},
                        {"final_residual_sigma_deg", enu(s.att_std_rad[last], fsw::kRadToDeg)},
                        {"final_residual_mean_deg", enu(s.att_mean_rad[last], fsw::kRadToDeg)},
                        {"final_filter_sigma_deg", enu(s.att_filter_sigma_rad[last], fsw::kRadToDeg)},
                        {"u_sigma_after_first_turn_deg", s.att_std_rad[aft][2] * fsw::kRadToDeg},
                        {"first_turn_end_s", s.t_s[aft]},
                        {"mean_nees", s.mean_nees},
                        {"nees_bounds", {s.nees_bounds[0], s.nees_bounds[1]}},
                        {"nees_dof", 9},
                        {"mean_nees_att", s.mean_nees_att},
                        {"nees_att_bounds", {s.nees_att_bounds[0], s.nees_att_bounds[1]}},
                        {"nees_from_s", s.nees_from_s},
                        {"final_pos_rms_m", s.pos_rms_m[last]},
                        {"final_vel_rms_mps", s.vel_rms_mps[last]},
                        {"sensors", sensors},
                        {"health", health_json(s.health)},
                        {"csv", csv}});
    r.stats.push_back(std::move(s));
  }
  const double flown_s = sc.duration_s * mc.runs;
  r.timing = {{"wall_s", r.wall_s},
              {"truth_generation_s", truth.generate_wall_s},
              {"imu_gps_models_cpu_s", sim_s},
              {"mechanization_cpu_s", mech_s},
              {"ekf_cpu_s", ekf_s},
              {"models_flown", mc.models.size()},
              {"real_time_factor", flown_s / r.wall_s}};
  return r;
}

void print_case(const CaseResult& r) {
  std::printf("%-6s %5s %28s %10s %8s %17s\n", "model", "runs", "final residual 1-sigma E/N/U", "U@turn1", "NEES",
              "95% bounds");
  for (const auto& m : r.models) {
    const auto& f = m["final_residual_sigma_deg"];
    std::printf("%-6s %5d %8.5f %8.5f %8.5f deg %10.5f %8.2f [%6.2f, %6.2f]\n", m["model"].get<std::string>().c_str(),
                m["runs"].get<int>(), f["E"].get<double>(), f["N"].get<double>(), f["U"].get<double>(),
                m["u_sigma_after_first_turn_deg"].get<double>(), m["mean_nees"].get<double>(),
                m["nees_bounds"][0].get<double>(), m["nees_bounds"][1].get<double>());
  }
  const auto& t = r.timing;
  std::printf("wall %.1f s (truth %.2f s; cpu: IMU/GPS models %.1f s, mechanization %.1f s, EKF %.1f s), %.0fx real time\n",
              t["wall_s"].get<double>(), t["truth_generation_s"].get<double>(), t["imu_gps_models_cpu_s"].get<double>(),
              t["mechanization_cpu_s"].get<double>(), t["ekf_cpu_s"].get<double>(), t["real_time_factor"].get<double>());
}

}  // namespace sdins
