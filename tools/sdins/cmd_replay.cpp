// sdins replay: re-runs the flight software on a log's IMU, GNSS raw and almanac channels (in
// time order, bad events counted and skipped) and writes a new log of the outputs. The same log
// replayed twice gives the same digest; a log written by sil/fsw replays to that run's digest.
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include "commands.hpp"
#include "hal/fsw_node.hpp"
#include "hal/lcm_log_sink.hpp"
#include "tools/fsw_report.hpp"

namespace sdins {
namespace {
struct Options {
  std::string in;
  std::string model = "24";
  std::string log;
  std::string lcm_url = "none";
  std::string json;
  int nav_decimation = 10;
} opt;
}  // namespace

void register_replay(CLI::App& app) {
  CLI::App* sub = app.add_subcommand(
      "replay", "Re-run the flight software on a log's IMU, GNSS_RAW and GPS_ALMANAC channels; prints the summary and "
                "the navigation digest, optionally writes a new log (inputs and outputs).");
  sub->add_option("LOG", opt.in, "LCM log with the input channels")->required();
  sub->add_option("--model", opt.model, "filter model")->check(CLI::IsMember({"15", "24"}))->capture_default_str();
  sub->add_option("--log", opt.log, "write an LCM log of the replay");
  sub->add_option("--lcm-url", opt.lcm_url, "LCM URL for live telemetry ('none': no network)")->capture_default_str();
  sub->add_option("--nav-decimation", opt.nav_decimation, "NAV_SOLUTION every n-th 200 Hz frame")
      ->check(CLI::Range(1, 200))
      ->capture_default_str();
  sub->add_option("--json", opt.json, "write the end-of-run summary as JSON");
}

int run_replay() {
  hal::LcmReplayReader reader;
  const hal::LcmLogStatus os = reader.open(opt.in);
  if (os != hal::LcmLogStatus::kOk) throw std::runtime_error("cannot read " + opt.in + ": " + reader.error());
  hal::FswNodeConfig cfg;
  if (!hal::parse_fsw_model(opt.model, cfg.model)) throw std::runtime_error("--model: 15 or 24");
  cfg.app = hal::default_flight_config();
  cfg.telemetry.lcm_url = opt.lcm_url;
  cfg.telemetry.log_path = opt.log;
  cfg.nav_decimation = opt.nav_decimation;
  hal::FswNode node;
  std::string err;
  if (!node.open(cfg, err)) throw std::runtime_error(err);
  hal::LcmReplayInput in;
  while (reader.next(in) == hal::LcmLogStatus::kOk) {
    switch (in.kind) {
      case hal::LcmReplayInput::Kind::kAlmanac: node.on_almanac(in.almanac, in.t_s); break;
      case hal::LcmReplayInput::Kind::kGnss: node.on_gnss(in.gnss); break;
      case hal::LcmReplayInput::Kind::kImu: node.on_imu(in.imu.sample, in.imu.counter, in.imu.status); break;
    }
  }
  if (!node.close(err)) throw std::runtime_error(err);
  const hal::LcmReplayStats& st = reader.stats();
  const hal::LcmLogReadStats& ls = reader.log_stats();
  std::printf("replay: %s, %llu inputs (%llu IMU, %llu GNSS, %llu almanac accepted), %llu rejected, %llu other events; "
              "log: %llu events, %llu rejections\n",
              opt.in.c_str(), static_cast<unsigned long long>(st.delivered),
              static_cast<unsigned long long>(st.imu.accepted()), static_cast<unsigned long long>(st.gnss.accepted()),
              static_cast<unsigned long long>(st.almanac.accepted()), static_cast<unsigned long long>(st.rejected()),
              static_cast<unsigned long long>(st.other_events), static_cast<unsigned long long>(ls.events),
              static_cast<unsigned long long>(ls.total_rejections()));
  tools::print_fsw_summary(node);
  if (!opt.json.empty()) {
    nlohmann::json j = tools::fsw_summary_json(node);
    j["mode"] = "replay";
    j["model"] = opt.model;
    j["input_log"] = opt.in;
    j["inputs"] = {{"delivered", st.delivered},
                   {"imu_accepted", st.imu.accepted()},
                   {"gnss_accepted", st.gnss.accepted()},
                   {"almanac_accepted", st.almanac.accepted()},
                   {"rejected", st.rejected()},
                   {"out_of_order", st.out_of_order},
                   {"imu_counter_gaps", st.imu_counter_gaps},
                   {"other_events", st.other_events},
                   {"log_events", ls.events},
                   {"log_rejections", ls.total_rejections()}};
    std::ofstream f(opt.json);
    if (!f) throw std::runtime_error("cannot write " + opt.json);
    f << j.dump(2) << "\n";
  }
  return node.summary().initialised ? 0 : 2;
}

}  // namespace sdins
