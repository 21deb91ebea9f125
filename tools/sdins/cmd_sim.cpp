// sdins sim: measured data without flight software. The truth simulator flies a scenario through
// the same sensor stream as sil/bus-sim (sim::SensorStream) and writes what a recording of the
// aircraft would hold: every IMU sample, every GPS receiver epoch, the almanac, plus truth on the
// TRUTH channel. What was simulated (seed, error set, effects switched on, the drawn IMU errors)
// goes into a JSON sidecar OUT.json next to the log, never into the channels the flight software
// reads: a log from `sdins sim` looks to `sdins replay` like any other recording.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.hpp"
#include "tools/output_file.hpp"
#include "fsw/effect_catalogue.hpp"
#include "hal/lcm_log_sink.hpp"
#include "sim/effects.hpp"
#include "sim/imu_model.hpp"
#include "sim/sensor_stream.hpp"

namespace sdins {
namespace {

struct SimOptions {
  ScenarioOptions scenario;
  std::string truth_errors;  ///< "": keep the scenario's set (the built-in scenario: paper)
  std::string log;
  std::vector<std::string> effects;
  double truth_rate_hz = 10.0;
} sim_opt;

const char* error_set_name(sim::ImuErrorSet s) {
  switch (s) {
    case sim::ImuErrorSet::kPaper: return "paper";
    case sim::ImuErrorSet::kBaseline: return "baseline";
    case sim::ImuErrorSet::kNone: return "none";
  }
  return "?";
}

/// One switched-on effect component for the sidecar and the summary.
struct EffectEntry {
  fsw::Effect effect;
  std::size_t component;
  double value;
  bool from_command_line;
  double scenario_value;  ///< the scenario's own value of this component (replaced when from_command_line)
};

std::vector<EffectEntry> effects_on(const sim::EffectSet& set, const sim::EffectSet& scenario_set,
                                    const std::vector<std::pair<fsw::Effect, std::size_t>>& cli) {
  std::vector<EffectEntry> out;
  for (const fsw::EffectInfo& info : fsw::kEffectCatalogue) {
    for (std::size_t k = 0; k < info.n_components; ++k) {
      const double v = set.get(info.effect, k);
      if (v == 0.0) continue;
      bool from_cli = false;
      for (const auto& [e, c] : cli) from_cli = from_cli || (e == info.effect && c == k);
      out.push_back({info.effect, k, v, from_cli, scenario_set.get(info.effect, k)});
    }
  }
  return out;
}

std::string effect_label(const EffectEntry& e) {
  const fsw::EffectInfo& info = fsw::effect_info(e.effect);
  std::string s = info.name;
  if (info.n_components > 1) s += std::string(".") + info.components[e.component];
  return s;
}

nlohmann::ordered_json xyz(const fsw::Vec3& v, double scale, const char* unit) {
  return {{"unit", unit}, {"x", v.x() * scale}, {"y", v.y() * scale}, {"z", v.z() * scale}};
}

/// The IMU errors in catalogue units (biases in the scenario's units: ug, deg/h), keyed by the
/// catalogue names where the catalogue has the quantity.
nlohmann::ordered_json imu_errors_json(const sim::ImuErrors& e) {
  nlohmann::ordered_json j;
  j["accel_bias"] = xyz(e.accel_bias_mps2, 1.0 / fsw::kMicroG_mps2, "ug");
  j["gyro_bias"] = xyz(e.gyro_bias_radps, 1.0 / fsw::kDegPerHourToRadps, "deg/h");
  j["accel_scale_factor"] = xyz(e.accel_scale_factor, 1e6, "ppm");
  j["gyro_scale_factor"] = xyz(e.gyro_scale_factor, 1e6, "ppm");
  nlohmann::ordered_json am{{"unit", "arcsec"}};
  for (std::size_t k = 0; k < 3; ++k) {
    const auto ax = fsw::kAccelMisalignmentAxes[k];
    am[fsw::effect_info(fsw::Effect::kAccelMisalignment).components[k]] =
        e.accel_misalignment_rad(ax.i, ax.j) * fsw::kRadToArcsec;
  }
  j["accel_misalignment"] = am;
  nlohmann::ordered_json gm{{"unit", "arcsec"}};
  for (std::size_t k = 0; k < 6; ++k) {
    const auto ax = fsw::kGyroMisalignmentAxes[k];
    gm[fsw::effect_info(fsw::Effect::kGyroMisalignment).components[k]] =
        e.gyro_misalignment_rad(ax.i, ax.j) * fsw::kRadToArcsec;
  }
  j["gyro_misalignment"] = gm;
  j["gyro_g_sensitivity"] =
      xyz(e.gyro_g_sensitivity_radps_per_mps2, 1.0 / fsw::effect_info(fsw::Effect::kGyroGSensitivity).unit_to_si,
          fsw::effect_info(fsw::Effect::kGyroGSensitivity).unit);
  j["imu_gnss_time_offset"] = {{"unit", "s"}, {"value", e.time_offset_s}};
  j["gyro_arw"] = {{"unit", "deg/sqrt(h)"}, {"value", e.gyro_arw_rad_per_rts * 60.0 * fsw::kRadToDeg}};
  j["accel_vrw"] = {{"unit", "ug/sqrt(Hz)"}, {"value", e.accel_vrw_mps_per_rts / fsw::kMicroG_mps2}};
  j["gyro_bias_instability"] = {{"unit", "deg/h"}, {"value", e.gyro_bias_instability_radps / fsw::kDegPerHourToRadps}};
  j["accel_bias_instability"] = {{"unit", "ug"}, {"value", e.accel_bias_instability_mps2 / fsw::kMicroG_mps2}};
  j["bias_instability_tau"] = {{"unit", "s"}, {"value", e.bias_instability_tau_s}};
  return j;
}

const hal::LcmLogSink* g_sink = nullptr;  ///< for check()'s message (the writer's errno text)

void check(hal::LcmLogStatus st, const std::string& what) {
  if (st == hal::LcmLogStatus::kOk) return;
  const std::string why = g_sink != nullptr ? g_sink->telemetry().log().error() : std::string();
  throw std::runtime_error("writing " + what + " to " + sim_opt.log + ": " + (why.empty() ? hal::to_string(st) : why) +
                           "; nothing written");
}

}  // namespace

void register_sim(CLI::App& app) {
  CLI::App* sub = app.add_subcommand(
      "sim", "Measured data without flight software: flies a scenario through the truth simulator and writes an LCM "
             "log of IMU (every sample), GNSS_RAW (every epoch), GPS_ALMANAC and TRUTH, plus a JSON sidecar "
             "LOG.json of what was simulated (seed, error set, effects, drawn IMU errors). Replay with `sdins replay`.");
  add_scenario_options(sub, sim_opt.scenario);
  sub->get_option("--seed")->required();
  sub->add_option("--truth-errors", sim_opt.truth_errors,
                  "IMU error set drawn on the truth side: paper (Table 1) or baseline (biases and noise only); "
                  "default: the scenario's own (built-in scenario: paper)")
      ->check(CLI::IsMember({"paper", "baseline"}));
  sub->add_option("--log", sim_opt.log, "the LCM log to write (the sidecar is LOG.json)")->required();
  sub->add_option("--effect", sim_opt.effects,
                  "switch a truth-side effect on, NAME[.COMPONENT]=VALUE in catalogue units (repeatable; on top of "
                  "the scenario's effects, replacing the scenario's value of the same component)")
      ->allow_extra_args(false);
  sub->add_option("--truth-rate", sim_opt.truth_rate_hz, "TRUTH samples per second [Hz]; must divide the IMU rate")
      ->check(CLI::Range(1.0, 1000.0))
      ->capture_default_str();
}

namespace {

/// --effect NAME.COMPONENT=VALUE assignments applied to the scenario's effects; returns the
/// (effect, component) each named, for the sidecar's "source".
std::vector<std::pair<fsw::Effect, std::size_t>> apply_cli_effects(sim::EffectSet& effects,
                                                                    const std::vector<std::string>& assignments) {
  std::vector<std::pair<fsw::Effect, std::size_t>> cli_effects;
  for (const std::string& a : assignments) {
    const std::string err = sim::apply_effect_assignment(effects, a);
    if (!err.empty()) throw std::runtime_error("--effect " + a + ": " + err);
    // The assignment is valid: name and component (for the sidecar's "source").
    std::string lhs = a.substr(0, a.find('='));
    lhs.erase(0, lhs.find_first_not_of(" \t"));
    lhs.erase(lhs.find_last_not_of(" \t") + 1);
    const auto dot = lhs.find('.');
    const fsw::Effect e = *sim::effect_from_name(lhs.substr(0, dot));
    const std::size_t k = *sim::component_from_name(e, dot == std::string::npos ? "" : lhs.substr(dot + 1));
    cli_effects.emplace_back(e, k);
  }
  return cli_effects;
}

/// IMU samples per TRUTH sample; --truth-rate must divide the IMU rate.
long long imu_samples_per_truth(const sim::Scenario& sc, double truth_rate_hz) {
  const double spt = sc.imu.rate_hz / truth_rate_hz;
  if (spt < 1.0 || std::abs(spt - std::round(spt)) > 1e-9) {
    char msg[160];
    std::snprintf(msg, sizeof(msg),
                  "--truth-rate %g Hz does not divide the IMU rate (%d Hz): TRUTH samples must fall on IMU sample "
                  "times (e.g. 1, 10, 100, 1000 Hz)",
                  truth_rate_hz, sc.imu.rate_hz);
    throw std::runtime_error(msg);
  }
  return std::llround(spt);
}

/// What the log holds.
struct SimLogCounts {
  long long imu = 0, gnss = 0, truth = 0;
  std::size_t almanac = 0;
  double t_imu_first = 0.0, t_imu_last = 0.0;
};

/// The sensor stream into the log: the almanac with the first IMU sample, every IMU sample, every
/// raw epoch, and TRUTH at every samples_per_truth-th IMU sample.
SimLogCounts write_sim_log(sim::SensorStream& stream, hal::LcmLogSink& sink, long long samples_per_truth) {
  long long n_imu = 0, n_gnss = 0, n_truth = 0;
  std::size_t n_almanac = 0;
  fsw::InputEvent ev;
  sim::TruthSample truth;
  double t_imu_first = 0.0, t_imu_last = 0.0;
  while (stream.next(ev, &truth)) {
    switch (ev.kind) {
      case fsw::InputEvent::Kind::kAlmanac:
        break;  // written with the first IMU sample, at the start of its interval
      case fsw::InputEvent::Kind::kImu:
        if (n_imu == 0) {
          // The almanac at the start of the data, on the navigation time scale, before any
          // epoch: a receiver that has its almanac at power-up.
          t_imu_first = ev.imu.t_s;
          for (const fsw::GpsAlmanac& a : stream.almanac()) {
            check(sink.write_almanac(a, ev.imu.t_s - ev.imu.dt_s), "GPS_ALMANAC");
            ++n_almanac;
          }
        }
        check(sink.write_imu(ev.imu), "IMU");
        ++n_imu;
        t_imu_last = ev.imu.t_s;
        if (n_imu % samples_per_truth == 0) {
          check(sink.write_truth(truth.t_s, truth.llh, truth.vel_enu_mps, truth.C_b_n), "TRUTH");
          ++n_truth;
        }
        break;
      case fsw::InputEvent::Kind::kGnssRaw:
        check(sink.write_gnss(ev.gnss), "GNSS_RAW");
        ++n_gnss;
        break;
      case fsw::InputEvent::Kind::kGnssPvt:
        break;  // the simulated receiver gives raw epochs only
    }
  }
  return SimLogCounts{n_imu, n_gnss, n_truth, n_almanac, t_imu_first, t_imu_last};
}

/// The sidecar: what was simulated (no wall-clock data: the same command gives the same file).
nlohmann::ordered_json sim_sidecar(const sim::Scenario& sc, const std::vector<EffectEntry>& on,
                                   const sim::SensorStream& stream, const SimLogCounts& n) {
  const sim::ImuErrors drawn = sim::draw_imu_errors(sc.imu, sim::EffectSet{}, sc.seed);
  nlohmann::ordered_json j;
  j["format"] = "sdins-sim-sidecar";
  j["version"] = 1;
  j["log"] = std::filesystem::path(sim_opt.log).filename().string();
  j["scenario"] = sc.name;
  j["scenario_file"] = sim_opt.scenario.file;  // "": the built-in scenario
  j["seed"] = sc.seed;
  j["duration_s"] = sc.duration_s;
  j["truth_errors"] = error_set_name(sc.imu.errors);
  j["imu_rate_hz"] = sc.imu.rate_hz;
  j["gps_rate_hz"] = sc.gps.rate_hz;
  j["truth_rate_hz"] = sim_opt.truth_rate_hz;
  nlohmann::ordered_json ej = nlohmann::ordered_json::array();
  for (const EffectEntry& e : on) {
    const fsw::EffectInfo& info = fsw::effect_info(e.effect);
    nlohmann::ordered_json ejj{{"name", info.name},
                               {"component", info.components[e.component]},
                               {"value", e.value},
                               {"unit", info.unit},
                               {"source", e.from_command_line ? "command_line" : "scenario"}};
    if (e.from_command_line && e.scenario_value != 0.0) ejj["replaces_scenario_value"] = e.scenario_value;
    ej.push_back(ejj);
  }
  j["effects"] = ej;
  j["imu_errors"] = {{"drawn", imu_errors_json(drawn)}, {"applied", imu_errors_json(stream.imu_errors())}};
  j["channels"] = {{hal::kLcmChannelImu, n.imu},
                   {hal::kLcmChannelGnssRaw, n.gnss},
                   {hal::kLcmChannelGpsAlmanac, n.almanac},
                   {hal::kLcmChannelTruth, n.truth}};
  j["time_scales"] =
      "IMU, GNSS_RAW and GPS_ALMANAC t_s: navigation time (IMU time tags = true time + imu_gnss_time_offset); "
      "TRUTH t_s: true time";
  return j;
}

}  // namespace

int run_sim() {
  // Everything that can be wrong with the request is checked before the log is created.
  tools::require_distinct({sim_opt.log, sim_opt.log + ".json"}, {sim_opt.scenario.file});
  sim::Scenario sc = sim_opt.scenario.load();
  if (sim_opt.truth_errors == "paper") sc.imu.errors = sim::ImuErrorSet::kPaper;
  if (sim_opt.truth_errors == "baseline") sc.imu.errors = sim::ImuErrorSet::kBaseline;
  const sim::EffectSet scenario_effects = sc.effects;
  const std::vector<std::pair<fsw::Effect, std::size_t>> cli_effects = apply_cli_effects(sc.effects, sim_opt.effects);
  const long long samples_per_truth = imu_samples_per_truth(sc, sim_opt.truth_rate_hz);

  const auto t_start = std::chrono::steady_clock::now();
  sim::SensorStream stream(sc, sim::TruthThread::kOwn);  // the writer leaves the second core idle
  hal::LcmLogSink sink;
  hal::LcmTelemetryConfig tcfg;
  tcfg.lcm_url = "none";
  tcfg.log_path = sim_opt.log;
  g_sink = &sink;
  check(sink.open(tcfg), "the log");

  const SimLogCounts n = write_sim_log(stream, sink, samples_per_truth);
  if (sink.encode_failures() != 0) throw std::runtime_error("messages that did not encode: " + std::to_string(sink.encode_failures()));

  // Sidecar: what was simulated. No wall-clock data, so the same command gives the same file.
  const std::vector<EffectEntry> on = effects_on(sc.effects, scenario_effects, cli_effects);
  const nlohmann::ordered_json j = sim_sidecar(sc, on, stream, n);
  // docs/faults.md: the log and its sidecar, both or neither. The sidecar is complete in its
  // temporary file before the log is put in place; a failure up to here leaves neither.
  const std::string sidecar = sim_opt.log + ".json";
  tools::TextOutput sidecar_out(sidecar);
  sidecar_out.os() << j.dump(2) << "\n";
  check(sink.close(), "the log (final flush)");
  const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  std::error_code ec;
  const auto bytes = std::filesystem::file_size(sim_opt.log, ec);
  sidecar_out.commit();

  std::string fx;
  for (const EffectEntry& e : on) {
    char v[64];
    std::snprintf(v, sizeof(v), "%g", e.value);
    fx += (fx.empty() ? "" : ", ") + effect_label(e) + "=" + v + " " + fsw::effect_info(e.effect).unit;
  }
  const sim::ImuErrors& ap = stream.imu_errors();
  std::printf(
      "sim: %s, %.0f s, seed %llu, truth errors %s; wrote %s (%llu bytes) in %.2f s: %lld IMU samples (%d Hz, t_s "
      "%.3f .. %.3f), %lld GNSS_RAW epochs, %zu GPS_ALMANAC, %lld TRUTH (%g Hz). Effects on: %s. Applied IMU errors: "
      "gyro bias %.4f %.4f %.4f deg/h, accel bias %.1f %.1f %.1f ug, gyro SF %.1f %.1f %.1f ppm. Sidecar %s. No "
      "flight software ran; replay with `sdins replay %s`.\n",
      sc.name.c_str(), sc.duration_s, static_cast<unsigned long long>(sc.seed), error_set_name(sc.imu.errors),
      sim_opt.log.c_str(), static_cast<unsigned long long>(ec ? 0 : bytes), elapsed_s, n.imu, sc.imu.rate_hz, n.t_imu_first,
      n.t_imu_last, n.gnss, n.almanac, n.truth, sim_opt.truth_rate_hz, fx.empty() ? "none" : fx.c_str(),
      ap.gyro_bias_radps.x() / fsw::kDegPerHourToRadps, ap.gyro_bias_radps.y() / fsw::kDegPerHourToRadps,
      ap.gyro_bias_radps.z() / fsw::kDegPerHourToRadps, ap.accel_bias_mps2.x() / fsw::kMicroG_mps2,
      ap.accel_bias_mps2.y() / fsw::kMicroG_mps2, ap.accel_bias_mps2.z() / fsw::kMicroG_mps2,
      ap.gyro_scale_factor.x() * 1e6, ap.gyro_scale_factor.y() * 1e6, ap.gyro_scale_factor.z() * 1e6, sidecar.c_str(),
      sim_opt.log.c_str());
  return 0;
}

}  // namespace sdins
