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
  FswRunOptions run;
} opt;
}  // namespace

void register_replay(CLI::App& app) {
  CLI::App* sub = app.add_subcommand(
      "replay", "Re-run the flight software on a log's IMU, GNSS_RAW and GPS_ALMANAC channels; prints the summary and "
                "the navigation digest, optionally writes a new log (inputs and outputs).");
  sub->add_option("LOG", opt.in, "LCM log with the input channels")->required();
  add_fsw_run_options(sub, opt.run, "none");
}

int run_replay() {
  hal::LcmReplayReader reader;
  const hal::LcmLogStatus os = reader.open(opt.in);
  if (os != hal::LcmLogStatus::kOk) throw std::runtime_error("cannot read " + opt.in + ": " + reader.error());
  const hal::FswNodeConfig cfg = opt.run.node_config();
  hal::FswNode node;
  std::string err;
  if (!node.open(cfg, err)) throw std::runtime_error(err);
  hal::LcmReplayInput in;
  while (reader.next(in) == hal::LcmLogStatus::kOk) {
    switch (in.kind) {
      case hal::LcmReplayInput::Kind::kAlmanac: node.on_almanac(in.almanac, in.t_s); break;
      case hal::LcmReplayInput::Kind::kGnss: node.on_gnss(in.gnss); break;
      case hal::LcmReplayInput::Kind::kImu: node.on_imu(in.imu.sample, in.imu.counter, in.imu.status); break;
      case hal::LcmReplayInput::Kind::kGnssPvt: break;  // not read: LcmReplayConfig::gnss_pvt_channel is empty
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
  if (!opt.run.json.empty()) {
    nlohmann::json j = tools::fsw_summary_json(node);
    j["mode"] = "replay";
    j["model"] = opt.run.model;
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
    std::ofstream f(opt.run.json);
    if (!f) throw std::runtime_error("cannot write " + opt.run.json);
    f << j.dump(2) << "\n";
  }
  return node.summary().initialised ? 0 : 2;
}

}  // namespace sdins
