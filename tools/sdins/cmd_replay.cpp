// sdins replay: re-runs the flight software on a log's IMU, GNSS raw and almanac channels, or with
// a filter configuration that takes GNSS solutions (gnss.source = "pvt") on IMU and GNSS_PVT (in
// time order, bad events counted and skipped) and writes a new log of the outputs. The same log
// replayed twice gives the same digest; a log written by sil/fsw replays to that run's digest.
// With --candump the input is a candump -L log of the CAN bus instead: its frames go through the
// receive path of `sdins fsw` (hal::CanFswInput), so a recording of a HIL run replays to its digest.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "commands.hpp"
#include "hal/can_fsw_input.hpp"
#include "hal/can_log.hpp"
#include "hal/fsw_node.hpp"
#include "hal/lcm_log_sink.hpp"
#include "cfg/flight_config.hpp"
#include "tools/fsw_report.hpp"
#include "tools/interrupt.hpp"
#include "tools/output_file.hpp"
#include "tools/replay_score.hpp"

namespace sdins {
namespace {
struct ReplayOptions {
  std::string in;
  FswRunOptions run;
  std::vector<double> outages;  ///< length, period, first (s after initialisation)
  bool candump = false;
  std::string score_json, score_csv, score_plot;
  double score_from_s = 0.0;
  double score_max_gap_s = 1.0;
} replay_opt;
}  // namespace

void register_replay(CLI::App& app) {
  CLI::App* sub = app.add_subcommand(
      "replay", "Re-run the flight software on a log's IMU, GNSS_RAW and GPS_ALMANAC channels; prints the summary and "
                "the navigation digest, optionally writes a new log (inputs and outputs).");
  sub->add_option("LOG", replay_opt.in, "LCM log with the input channels (with --candump: a candump -L log)")->required();
  sub->add_flag("--candump", replay_opt.candump,
                "LOG is a candump -L log of the CAN bus (hal/can/sdins.dbc frames, e.g. `candump -L vcan0` beside "
                "`sdins fsw`): the frames go through the receive path of `sdins fsw`, rejections counted as there, "
                "receive times from the log's timestamps");
  add_fsw_run_options(sub, replay_opt.run, "none");
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
           replay_opt.outages = v;
         },
                  "withhold GNSS (raw epochs and solutions) for LENGTH s every PERIOD s from FIRST s after the "
                  "initialisation, to score the coasting solution against a reference (LENGTH PERIOD FIRST [s]; default: "
                  "none)")
      ->expected(3);
  sub->add_option("--score-json", replay_opt.score_json,
                  "write the score against the log's reference (TRUTH) as JSON: errors, NEES, outages with their drift "
                  "curves (docs/running.md)");
  sub->add_option("--score-csv", replay_opt.score_csv,
                  "write the errors against the reference as CSV (20 rows/s; outage rows carry the time since it began)");
  sub->add_option("--score-plot", replay_opt.score_plot,
                  "with --outages and --score-json: a PNG of the outages' errors vs the time since each began "
                  "(plot_outages.py, python3-matplotlib)");
  sub->add_option("--score-from", replay_opt.score_from_s, "score the frames from this long after initialisation [s]")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e7));
  sub->add_option("--score-max-gap", replay_opt.score_max_gap_s,
                  "the reference samples around a frame may be at most this far apart [s]")
      ->capture_default_str()
      ->check(CLI::Range(1e-3, 1e3));
}

namespace {
/// --candump: the bus recording's frames into hal::CanFswInput as `sdins fsw` receives them.
int replay_candump(const cfg::FlightConfig& filter) {
  if (!replay_opt.outages.empty()) throw std::runtime_error("--outages: not with --candump (it withholds LCM-log inputs)");
  if (!replay_opt.score_json.empty() || !replay_opt.score_csv.empty() || !replay_opt.score_plot.empty())
    throw std::runtime_error("--score-json/--score-csv/--score-plot: not with --candump (a bus recording carries no "
                             "reference trajectory to score against)");
  cfg::require_raw_gnss(filter, "--filter-config", "the CAN bus carries raw GNSS epochs (hal/can/sdins.dbc)");
  hal::CandumpReader reader;
  if (!reader.open(replay_opt.in)) throw std::runtime_error("cannot read " + replay_opt.in + ": " + reader.error());
  const tools::InterruptPolling polling;  // docs/faults.md: SIGINT/SIGTERM stop the replay cleanly (from the log's opening on)
  hal::FswNode node;
  std::string err;
  if (!node.open(replay_opt.run.node_config(filter), err)) throw std::runtime_error(err);
  hal::CanFswInput in(node.summary());
  hal::CanFrame f;
  std::string iface;
  while (!tools::interrupted() && reader.next(f, iface)) {
    in.push(f, f.timestamp_s);
    fsw::drive(in, node);
  }
  if (!reader.error().empty()) throw std::runtime_error("cannot read " + replay_opt.in + ": " + reader.error());
  if (reader.frames() == 0)  // docs/faults.md: nothing valid in the input is an error, not an empty success
    throw std::runtime_error(replay_opt.in + ": no valid candump frame in " + std::to_string(reader.lines()) + " lines");
  const bool stopped = tools::interrupted();
  if (stopped) {
    node.abort();
  } else {
    in.finish();
    fsw::drive(in, node);
    if (!node.close(err)) throw std::runtime_error(err);
  }
  std::printf("replay: %s (candump), %d lines, %d frames, %d malformed lines; %llu data frames (%u rejected), %llu "
              "SIM_CONTROL (%llu rejected), %llu FSW_ACK\n",
              replay_opt.in.c_str(), reader.lines(), reader.frames(), reader.bad_lines(),
              static_cast<unsigned long long>(in.data_frames()), in.health().rejections(),
              static_cast<unsigned long long>(in.control_frames()), static_cast<unsigned long long>(in.control_rejected()),
              static_cast<unsigned long long>(in.foreign_acks()));
  for (const std::string& p : reader.problems()) std::printf("  %s\n", p.c_str());
  tools::print_fsw_summary(node);
  if (stopped)
    throw tools::Interrupted("replay stopped after " + std::to_string(reader.frames()) + " frames (the summary so far "
                             "is above); no log or JSON written");
  if (!replay_opt.run.json.empty()) {
    nlohmann::json j = tools::fsw_summary_json(node);
    j["mode"] = "replay";
    j["model"] = replay_opt.run.model;
    j["input_log"] = replay_opt.in;
    j["input_format"] = "candump";
    j["filter_config"] = replay_opt.run.flight_config;
    j["candump"] = {{"lines", reader.lines()}, {"frames", reader.frames()}, {"malformed_lines", reader.bad_lines()}};
    j["frames"] = {{"data", in.data_frames()},
                   {"imu", in.imu_frames()},
                   {"imu_delivered", in.imu_delivered()},
                   {"control", in.control_frames()},
                   {"control_rejected", in.control_rejected()},
                   {"foreign_acks", in.foreign_acks()}};
    j["assembler"] = tools::can_rx_json(in.health());
    tools::write_json_file(replay_opt.run.json, j);
  }
  return node.summary().initialised ? 0 : 2;
}
}  // namespace

namespace {

/// The score's options from --score-from, --score-max-gap and --outages.
tools::ScoreOptions replay_score_options() {
  tools::ScoreOptions so;
  so.from_s = replay_opt.score_from_s;
  so.max_reference_gap_s = replay_opt.score_max_gap_s;
  if (replay_opt.outages.size() == 3) {
    so.outage_length_s = replay_opt.outages[0];
    so.outage_period_s = replay_opt.outages[1];
    so.outage_first_s = replay_opt.outages[2];
  }
  return so;
}

/// The replay's input counts on the terminal: what was delivered, rejected, not used, withheld.
void print_replay_inputs(const hal::LcmReplayStats& st, const hal::LcmLogReadStats& ls, std::uint64_t raw_not_used,
                         std::uint64_t withheld) {
  std::printf("replay: %s, %llu inputs (%llu IMU, %llu GNSS, %llu GNSS solutions, %llu almanac accepted; %llu raw "
              "epochs not used: the filter takes solutions), %llu rejected, %llu other events; "
              "log: %llu events, %llu rejections\n",
              replay_opt.in.c_str(), static_cast<unsigned long long>(st.delivered),
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
  if (replay_opt.outages.size() == 3)
    std::printf("GNSS outages: %.1f s every %.1f s from %.1f s after initialisation, %llu inputs withheld\n",
                replay_opt.outages[0], replay_opt.outages[1], replay_opt.outages[2], static_cast<unsigned long long>(withheld));
}

/// The same counts for the --json summary.
nlohmann::json replay_inputs_json(const hal::LcmReplayStats& st, const hal::LcmLogReadStats& ls,
                                  std::uint64_t raw_not_used, std::uint64_t withheld) {
  return {{"delivered", st.delivered},
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
}

}  // namespace

int run_replay() {
  tools::require_distinct({replay_opt.run.log, replay_opt.run.json, replay_opt.score_json, replay_opt.score_csv, replay_opt.score_plot},
                          {replay_opt.in, replay_opt.run.flight_config});
  if (!replay_opt.score_plot.empty() && (replay_opt.score_json.empty() || replay_opt.outages.size() != 3))
    throw std::runtime_error("--score-plot needs --outages and --score-json (the plot reads the score JSON)");
  const cfg::FlightConfig filter = replay_opt.run.flight();
  if (replay_opt.candump) return replay_candump(filter);
  const bool pvt = filter.gnss_source == cfg::GnssSource::kPvt;
  hal::LcmReplayConfig rc;
  if (pvt) rc.gnss_pvt_channel = hal::kLcmChannelGnssPvt;
  hal::LcmReplayReader reader;
  const hal::LcmLogStatus os = reader.open(replay_opt.in, rc);
  if (os != hal::LcmLogStatus::kOk) throw std::runtime_error("cannot read " + replay_opt.in + ": " + reader.error());
  // Scoring (docs/running.md): against TRUTH when the log has it.
  const tools::ScoreOptions so = replay_score_options();
  tools::ReplayScorer scorer(tools::load_reference(replay_opt.in), so);
  const bool scoring = !scorer.reference().samples.empty();
  if (!scoring && (!replay_opt.score_json.empty() || !replay_opt.score_csv.empty()))
    throw std::runtime_error(replay_opt.in + " has no usable reference on TRUTH: nothing to score (--score-json/--score-csv)");
  // The outputs open last, with the signals polled from then on: reading the reference is setup
  // (a signal during it leaves nothing), and once a log is open a signal ends the replay cleanly.
  const tools::InterruptPolling polling;  // docs/faults.md: SIGINT/SIGTERM stop the replay cleanly
  const hal::FswNodeConfig cfg = replay_opt.run.node_config(filter);
  hal::FswNode node;
  std::string err;
  if (!node.open(cfg, err)) throw std::runtime_error(err);
  std::uint64_t raw_not_used = 0, withheld = 0;
  // GNSS outages: inputs at times within [t0 + k period, t0 + k period + length) are withheld.
  const auto in_outage = [&](double t) {
    if (replay_opt.outages.size() != 3 || !node.summary().initialised) return false;
    const double t0 = node.summary().init_t_s + replay_opt.outages[2];
    if (t < t0) return false;
    return std::fmod(t - t0, replay_opt.outages[1]) < replay_opt.outages[0];
  };
  const auto keep = [&](const fsw::InputEvent& in) {
    const bool gnss = in.kind == fsw::InputEvent::Kind::kGnssRaw || in.kind == fsw::InputEvent::Kind::kGnssPvt;
    if (gnss && in_outage(in.t_s)) {
      ++withheld;
      return false;
    }
    if (in.kind == fsw::InputEvent::Kind::kGnssRaw && pvt) {
      ++raw_not_used;  // the configuration takes solutions
      return false;
    }
    return true;
  };
  // The score is an observer of the node's frames: once per completed frame, and at each EKF run.
  auto score_frames = fsw::after_each([&](const fsw::InputEvent& ev, fsw::Status, const fsw::FrameOutput& out) {
    if (!scoring || ev.kind != fsw::InputEvent::Kind::kImu || !node.frame_completed()) return;
    scorer.on_frame(out.nav, node.summary().init_t_s);
    if (out.ekf_ran) scorer.on_ekf(out.nav, node.summary().init_t_s, node.last_ekf_nav_sigma());
  });
  tools::UntilInterrupted<hal::LcmReplayReader> log{reader};
  auto inputs = fsw::filtered(log, keep);
  fsw::drive(inputs, node, score_frames);
  const bool stopped = tools::interrupted();
  if (stopped)
    node.abort();  // an interrupted replay leaves no partial log (the target keeps its old contents)
  else if (!node.close(err))
    throw std::runtime_error(err);
  const hal::LcmReplayStats& st = reader.stats();
  const hal::LcmLogReadStats& ls = reader.log_stats();
  print_replay_inputs(st, ls, raw_not_used, withheld);
  tools::print_fsw_summary(node);
  const nlohmann::json score = scoring ? scorer.result() : nlohmann::json(nullptr);
  if (scoring) std::fputs(tools::ReplayScorer::text(score).c_str(), stdout);
  if (stopped)
    throw tools::Interrupted("replay stopped after " + std::to_string(st.delivered) + " inputs (the summary so far is "
                             "above); no log or JSON written");
  if (!replay_opt.run.json.empty()) {
    nlohmann::json j = tools::fsw_summary_json(node);
    j["mode"] = "replay";
    j["model"] = replay_opt.run.model;
    j["input_log"] = replay_opt.in;
    j["filter_config"] = replay_opt.run.flight_config;
    j["gnss_source"] = cfg::to_string(filter.gnss_source);
    j["inputs"] = replay_inputs_json(st, ls, raw_not_used, withheld);
    j["score"] = score;
    tools::write_json_file(replay_opt.run.json, j);
  }
  if (!replay_opt.score_json.empty()) tools::write_json_file(replay_opt.score_json, score);
  if (!replay_opt.score_csv.empty()) tools::write_text_file(replay_opt.score_csv, scorer.csv());
  if (!replay_opt.score_plot.empty() &&
      run_plot_script("plot_outages.py", shell_quote(replay_opt.score_json) + " " + shell_quote(replay_opt.score_plot)) != 0)
    throw std::runtime_error("plot_outages.py failed: " + replay_opt.score_plot + " not written (the score JSON and CSV are)");
  return node.summary().initialised ? 0 : 2;
}

}  // namespace sdins
