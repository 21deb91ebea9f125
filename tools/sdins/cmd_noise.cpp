// sdins noise LOG --out DIR: the sensor noise from the data (docs/noise.md). The rest segments of
// the log, the overlapping Allan deviation of every gyro and accelerometer axis over them, the
// noise terms with their 95% intervals, the filter configuration values that follow, and the same
// analysis of the simulator's IMU model for comparison. The work is in the tools library
// (tools/noise.hpp, tools/allan.hpp); this file parses options, prints and writes.
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "commands.hpp"
#include "fsw/frames.hpp"
#include "cfg/flight_config.hpp"
#include "tools/noise.hpp"
#include "tools/output_file.hpp"

namespace sdins {
namespace {
struct NoiseOptions {
  std::string log;
  std::string out;
  tools::RestDetectorConfig rest;
  bool no_gnss = false;
  ScenarioOptions scenario;
  std::string filter_config;
  bool plots = true;
  int segment = -1;  ///< -1: all rest segments pooled
} noise_opt;

/// The configured filter values beside the data's (config/README.md units).
nlohmann::json configured_json(const cfg::FlightConfig& f) {
  const fsw::EkfConfig& e = f.app.exec.ekf;
  return {{"name", f.name},
          {"arw_deg_per_rthr", e.arw_rad_per_rts * 60.0 / fsw::kDegToRad},
          {"vrw_mps_per_rthr", e.vrw_mps_per_rts * 60.0},
          {"gyro_bias_rw_radps_per_rts", e.gyro_bias_rw_radps_per_rts},
          {"accel_bias_rw_mps2_per_rts", e.accel_bias_rw_mps2_per_rts},
          {"gyro_bias_sigma_degph", e.gyro_bias_sigma_radps / fsw::kDegPerHourToRadps},
          {"accel_bias_sigma_mg", e.accel_bias_sigma_mps2 / fsw::kStandardGravity_mps2 * 1e3}};
}

void print_configured(const nlohmann::json& from_data, const nlohmann::json& cfg) {
  std::printf("filter configuration: from the data vs '%s' (%s):\n", cfg["name"].get<std::string>().c_str(),
              noise_opt.filter_config.empty() ? "the shipped config/default.toml" : noise_opt.filter_config.c_str());
  for (const char* k : {"arw_deg_per_rthr", "vrw_mps_per_rthr", "gyro_bias_rw_radps_per_rts", "accel_bias_rw_mps2_per_rts",
                        "gyro_bias_sigma_degph"}) {
    const double d = from_data[k]["value"].get<double>(), c = cfg[k].get<double>();
    std::printf("  imu.%-28s %11.4g vs %11.4g (configured / data %.3g)\n", k, d, c, d > 0.0 ? c / d : 0.0);
  }
}
}  // namespace

void register_noise(CLI::App& app) {
  CLI::App* sub = app.add_subcommand(
      "noise", "The sensor noise from the data: rest segments of a log (IMU variance + GNSS speed), the overlapping "
               "Allan deviation of every gyro and accelerometer axis with 95% intervals, angle/velocity random walk, "
               "bias instability and rate random walk where the rest supports them, the filter configuration values "
               "with their sources, and the simulator's IMU model for comparison (docs/noise.md).");
  sub->add_option("LOG", noise_opt.log, "LCM log with the IMU channel (and GNSS_PVT or GNSS_RAW + GPS_ALMANAC for the speed)")
      ->required();
  sub->add_option("--out", noise_opt.out,
                  "result directory: summary.json (everything), filter.toml (the [imu] values with their sources), "
                  "sim_imu.toml (the scenario keys that reproduce the terms), allan.png")
      ->required();
  sub->add_option("--window", noise_opt.rest.window_s, "rest detector window [s]")->check(CLI::Range(0.05, 60.0))->capture_default_str();
  sub->add_option("--threshold-factor", noise_opt.rest.threshold_factor,
                  "a window is quiet when its specific-force and rate scatter are at most this x the quiet reference "
                  "(the median of the quietest half-minimum-rest of windows)")
      ->check(CLI::Range(1.0, 100.0))
      ->capture_default_str();
  sub->add_option("--min-rest", noise_opt.rest.min_rest_s, "shortest rest segment kept [s] (after trimming)")
      ->check(CLI::Range(1.0, 86400.0))
      ->capture_default_str();
  sub->add_option("--margin", noise_opt.rest.margin_s, "trimmed at each end of a rest run [s]")->check(CLI::Range(0.0, 60.0))->capture_default_str();
  sub->add_option("--max-speed", noise_opt.rest.max_speed_mps, "GNSS ground speed at rest, at most [m/s]")
      ->check(CLI::Range(0.0, 10.0))
      ->capture_default_str();
  sub->add_flag("--no-gnss", noise_opt.no_gnss, "detect rest from the IMU alone (ignore the log's GNSS)");
  sub->add_option("--segment", noise_opt.segment,
                  "analyse only rest segment K (0-based, in time order; default: all segments pooled)")
      ->check(CLI::Range(0, 1000));
  add_scenario_options(sub, noise_opt.scenario);
  sub->add_option("--flight-config,--filter-config", noise_opt.filter_config,
                  "flight configuration to compare with (e.g. config/datasets/gnss-imu-drive.toml), applied on top of the "
                  "shipped config/default.toml (default: the shipped file alone)");
  sub->add_flag("!--no-plots", noise_opt.plots, "do not draw allan.png");
}

int run_noise() {
  tools::require_distinct({noise_opt.out}, {noise_opt.log, noise_opt.scenario.file, noise_opt.filter_config});
  const sim::Scenario sc = noise_opt.scenario.load();
  const cfg::FlightConfig configured = cfg::flight_config(noise_opt.filter_config);
  const tools::NoiseInput in = tools::read_noise_input(noise_opt.log);
  noise_opt.rest.use_gnss = !noise_opt.no_gnss;
  const tools::RestDetection rest = tools::detect_rest(in, noise_opt.rest);
  std::printf("noise: %s, %zu IMU samples (%llu rejected by the reader, %llu counter gaps), GNSS speed: %s (%zu "
              "solutions)\n",
              noise_opt.log.c_str(), in.imu.size(), static_cast<unsigned long long>(in.imu_rejected),
              static_cast<unsigned long long>(in.imu_counter_gaps), in.speed_source.empty() ? "none" : in.speed_source.c_str(),
              in.speed.size());
  if (rest.segments.empty()) {
    std::fputs(tools::noise_summary_text(rest, tools::NoiseAnalysis{}).c_str(), stdout);
    char len[32];
    std::snprintf(len, sizeof len, "%g", noise_opt.rest.min_rest_s);
    throw std::runtime_error(noise_opt.log + ": no rest segment of at least " + len +
                             " s (see the detector line above; --min-rest, --threshold-factor, --max-speed)");
  }
  std::vector<tools::RestSegment> used = rest.segments;
  if (noise_opt.segment >= 0) {
    if (static_cast<std::size_t>(noise_opt.segment) >= rest.segments.size())
      throw std::runtime_error("--segment " + std::to_string(noise_opt.segment) + ": the log has " +
                               std::to_string(rest.segments.size()) + " rest segments (0-based)");
    used = {rest.segments[static_cast<std::size_t>(noise_opt.segment)]};
  }
  const tools::NoiseAnalysis data = tools::analyse_noise(in.imu, used);
  std::fputs(tools::noise_summary_text(rest, data).c_str(), stdout);
  // Pooling assumes one noise process: each segment alone, and a flag where they disagree.
  nlohmann::json per_segment = nlohmann::json::array();
  if (used.size() > 1) {
    std::vector<tools::NoiseAnalysis> each;
    for (const tools::RestSegment& s : used) each.push_back(tools::analyse_noise(in.imu, {s}));
    const std::string text = tools::segments_text(each, per_segment);
    std::fputs(text.c_str(), stdout);
  }
  // The simulator's model for the scenario's grade and for the terms just read.
  const double lat = in.have_position ? in.lat_rad : sc.start.lat_deg * fsw::kDegToRad;
  const sim::ImuErrors grade = sim::draw_imu_errors(sc.imu, sc.effects, sc.seed);
  const tools::NoiseAnalysis sim_grade = tools::analyse_simulated_rest(grade, data.segment_s, data.tau0_s, lat, sc.seed);
  const sim::ImuErrors fitted = tools::imu_errors_from_analysis(data);
  const tools::NoiseAnalysis sim_fitted = tools::analyse_simulated_rest(fitted, data.segment_s, data.tau0_s, lat, sc.seed);
  const std::string grade_name = "the simulator's IMU model for scenario '" + sc.name + "'";
  std::printf("simulator, scenario '%s' (%s): %s\n", sc.name.c_str(), noise_opt.scenario.file.empty() ? "built in" : noise_opt.scenario.file.c_str(),
              tools::imu_errors_text(grade).c_str());
  std::printf("simulator set to the terms read (sim_imu.toml): %s\n", tools::imu_errors_text(fitted).c_str());
  std::fputs(tools::compare_text(data, sim_grade, grade_name).c_str(), stdout);
  std::fputs(tools::compare_text(data, sim_fitted, "the simulator's IMU model set to the terms read (sim_imu.toml)").c_str(),
             stdout);
  const nlohmann::json values = tools::filter_values_json(data, in);
  const nlohmann::json cfg = configured_json(configured);
  print_configured(values, cfg);

  tools::RunDirectory dir(noise_opt.out);
  const std::string source = noise_opt.log;
  tools::write_text_file(dir.path("filter.toml"), tools::filter_config_toml(data, in, source));
  tools::write_text_file(dir.path("sim_imu.toml"), tools::scenario_imu_toml(fitted));
  nlohmann::json j;
  j["log"] = noise_opt.log;
  j["imu_samples"] = in.imu.size();
  j["speed_source"] = in.speed_source;
  j["rest"] = tools::to_json(rest);
  j["segment_analysed"] = noise_opt.segment;  // -1: all pooled
  j["per_segment"] = per_segment;
  j["data"] = tools::to_json(data);
  j["filter_values"] = values;
  j["configured"] = cfg;
  j["sim_grade"] = {{"scenario", sc.name}, {"analysis", tools::to_json(sim_grade)},
                    {"compare", tools::compare_json(data, sim_grade)}};
  j["sim_fitted"] = {{"analysis", tools::to_json(sim_fitted)}, {"compare", tools::compare_json(data, sim_fitted)}};
  int rc = 0;
  if (noise_opt.plots) {
    // The plot reads the complete results; summary.json (the marker) is written after it.
    tools::write_json_file(dir.path("noise.json"), j);
    rc = run_plot_script("plot_noise.py", shell_quote(dir.path("noise.json")) + " " + shell_quote(dir.path("allan.png")));
    if (rc != 0) std::fprintf(stderr, "sdins noise: the plot failed (results are complete without it)\n");
  }
  dir.finish(j);
  std::printf("written: %s (summary.json, filter.toml, sim_imu.toml%s)\n", noise_opt.out.c_str(), noise_opt.plots ? ", noise.json, allan.png" : "");
  return rc;
}

}  // namespace sdins
