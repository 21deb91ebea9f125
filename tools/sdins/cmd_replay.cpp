// sdins replay: re-runs the flight software on a log's IMU, GNSS raw and almanac channels, or with
// a filter configuration that takes GNSS solutions (gnss.source = "pvt") on IMU and GNSS_PVT (in
// time order, bad events counted and skipped) and writes a new log of the outputs. The same log
// replayed twice gives the same digest; a log written by sil/fsw replays to that run's digest.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "commands.hpp"
#include "hal/fsw_node.hpp"
#include "hal/lcm_log_sink.hpp"
#include "tools/fsw_report.hpp"
#include "tools/interrupt.hpp"
#include "tools/output_file.hpp"

namespace sdins {
namespace {
struct Options {
  std::string in;
  FswRunOptions run;
  std::vector<double> outages;  ///< length, period, first (s after initialisation)
} opt;
}  // namespace

void register_replay(CLI::App& app) {
  CLI::App* sub = app.add_subcommand(
      "replay", "Re-run the flight software on a log's IMU, GNSS_RAW and GPS_ALMANAC channels; prints the summary and "
                "the navigation digest, optionally writes a new log (inputs and outputs).");
  sub->add_option("LOG", opt.in, "LCM log with the input channels")->required();
  add_fsw_run_options(sub, opt.run, "none");
  sub->add_option_function<std::vector<double>>(
         "--outages",
         [](const std::vector<double>& v) {
           // docs/faults.md: a combination that would withhold nothing (or everything) is refused.
           const auto bad = [&](const std::string& rule) {
             throw CLI::ValidationError("--outages", "LENGTH " + CLI::detail::to_string(v[0]) + ", PERIOD " +
                                                         CLI::detail::to_string(v[1]) + ", FIRST " +
                                                         CLI::detail::to_string(v[2]) + ": " + rule);
           };
           if (!(v[0] > 0.0)) bad("LENGTH must be > 0 s (nothing would be withheld)");
           if (!(v[1] > 0.0)) bad("PERIOD must be > 0 s");
           if (v[0] > v[1]) bad("LENGTH must not exceed PERIOD (LENGTH = PERIOD withholds every epoch after FIRST)");
           if (!(v[2] >= 0.0)) bad("FIRST must be >= 0 s (it counts from the initialisation)");
           opt.outages = v;
         },
                  "withhold GNSS (raw epochs and solutions) for LENGTH s every PERIOD s from FIRST s after the "
                  "initialisation, to score the coasting solution against a reference (LENGTH PERIOD FIRST [s]; default: "
                  "none)")
      ->expected(3);
}

int run_replay() {
  tools::require_distinct({opt.run.log, opt.run.json}, {opt.in, opt.run.filter_config});
  const sim::FilterConfig filter = opt.run.filter();
  const bool pvt = filter.gnss_source == sim::GnssSource::kPvt;
  hal::LcmReplayConfig rc;
  if (pvt) rc.gnss_pvt_channel = hal::kLcmChannelGnssPvt;
  hal::LcmReplayReader reader;
  const hal::LcmLogStatus os = reader.open(opt.in, rc);
  if (os != hal::LcmLogStatus::kOk) throw std::runtime_error("cannot read " + opt.in + ": " + reader.error());
  const hal::FswNodeConfig cfg = opt.run.node_config(filter);
  hal::FswNode node;
  std::string err;
  if (!node.open(cfg, err)) throw std::runtime_error(err);
  fsw::InputEvent in;
  std::uint64_t raw_not_used = 0, withheld = 0;
  // GNSS outages: inputs at times within [t0 + k period, t0 + k period + length) are withheld.
  const auto in_outage = [&](double t) {
    if (opt.outages.size() != 3 || !node.summary().initialised) return false;
    const double t0 = node.summary().init_t_s + opt.outages[2];
    if (t < t0) return false;
    return std::fmod(t - t0, opt.outages[1]) < opt.outages[0];
  };
  const tools::InterruptPolling polling;  // docs/faults.md: SIGINT/SIGTERM stop the replay cleanly
  while (reader.next(in) == hal::LcmLogStatus::kOk) {
    if (tools::interrupted()) break;
    const bool gnss = in.kind == fsw::InputEvent::Kind::kGnssRaw || in.kind == fsw::InputEvent::Kind::kGnssPvt;
    if (gnss && in_outage(in.t_s)) {
      ++withheld;
      continue;
    }
    if (in.kind == fsw::InputEvent::Kind::kGnssRaw && pvt) {
      ++raw_not_used;  // the configuration takes solutions
      continue;
    }
    node.on_event(in);
  }
  const bool stopped = tools::interrupted();
  if (stopped)
    node.abort();  // an interrupted replay leaves no partial log (the target keeps its old contents)
  else if (!node.close(err))
    throw std::runtime_error(err);
  const hal::LcmReplayStats& st = reader.stats();
  const hal::LcmLogReadStats& ls = reader.log_stats();
  std::printf("replay: %s, %llu inputs (%llu IMU, %llu GNSS, %llu GNSS solutions, %llu almanac accepted; %llu raw "
              "epochs not used: the filter takes solutions), %llu rejected, %llu other events; "
              "log: %llu events, %llu rejections\n",
              opt.in.c_str(), static_cast<unsigned long long>(st.delivered),
              static_cast<unsigned long long>(st.imu.accepted()), static_cast<unsigned long long>(st.gnss.accepted()),
              static_cast<unsigned long long>(st.gnss_pvt.accepted()), static_cast<unsigned long long>(st.almanac.accepted()),
              static_cast<unsigned long long>(raw_not_used), static_cast<unsigned long long>(st.rejected()),
              static_cast<unsigned long long>(st.other_events), static_cast<unsigned long long>(ls.events),
              static_cast<unsigned long long>(ls.total_rejections()));
  if (st.time_tag_rejected > 0 || st.time_base_changes > 0)
  {
    std::printf("time tags: %llu rejected as outliers, %llu new time bases", static_cast<unsigned long long>(st.time_tag_rejected),
                static_cast<unsigned long long>(st.time_base_changes));
    if (st.time_base_changes > 0)
      std::printf(" (last: a jump of %.6f s at t = %.6f s)", st.last_time_base_jump_s, st.last_time_base_at_s);
    std::printf("\n");
  }
  if (st.gnss.measurements_dropped > 0)
    std::printf("GNSS: %llu measurements with non-finite values (pseudorange, rate or C/N0) dropped from accepted "
                "epochs\n",
                static_cast<unsigned long long>(st.gnss.measurements_dropped));
  if (opt.outages.size() == 3)
    std::printf("GNSS outages: %.1f s every %.1f s from %.1f s after initialisation, %llu inputs withheld\n",
                opt.outages[0], opt.outages[1], opt.outages[2], static_cast<unsigned long long>(withheld));
  tools::print_fsw_summary(node);
  if (stopped)
    throw tools::Interrupted("replay stopped after " + std::to_string(st.delivered) + " inputs (the summary so far is "
                             "above); no log or JSON written");
  if (!opt.run.json.empty()) {
    nlohmann::json j = tools::fsw_summary_json(node);
    j["mode"] = "replay";
    j["model"] = opt.run.model;
    j["input_log"] = opt.in;
    j["filter_config"] = opt.run.filter_config;
    j["gnss_source"] = sim::to_string(filter.gnss_source);
    j["inputs"] = {{"delivered", st.delivered},
                   {"imu_accepted", st.imu.accepted()},
                   {"gnss_accepted", st.gnss.accepted()},
                   {"gnss_measurements_dropped", st.gnss.measurements_dropped},
                   {"gnss_pvt_accepted", st.gnss_pvt.accepted()},
                   {"gnss_raw_not_used", raw_not_used},
                   {"gnss_withheld", withheld},
                   {"almanac_accepted", st.almanac.accepted()},
                   {"rejected", st.rejected()},
                   {"out_of_order", st.out_of_order},
                   {"time_tag_rejected", st.time_tag_rejected},
                   {"time_base_changes", st.time_base_changes},
                   {"imu_counter_gaps", st.imu_counter_gaps},
                   {"other_events", st.other_events},
                   {"log_events", ls.events},
                   {"log_rejections", ls.total_rejections()}};
    tools::write_json_file(opt.run.json, j);
  }
  return node.summary().initialised ? 0 : 2;
}

}  // namespace sdins
