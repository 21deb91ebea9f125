// sdins import FORMAT PATH --log OUT.lcmlog [--json SUMMARY]: a recording (RTKLIB solution + IMU
// log + raw u-blox receiver log, or the PSINS tight-coupling data set) into the project's LCM log
// format. The work is in the tools library (tools/importers.hpp); this file parses options and prints.
#include <cstdio>
#include <filesystem>
#include <vector>
#include <stdexcept>

#include "commands.hpp"
#include "numeric_options.hpp"
#include "tools/import_describe.hpp"
#include "tools/importers.hpp"
#include "tools/output_file.hpp"
#include "tools/ulog_import.hpp"

namespace sdins {
namespace {
struct ImportOptions {
  tools::ImportOptions imp;
  tools::UlogImportOptions ulog;
  std::string json;
  std::string data_dir;
  std::string filter_config;
} import_opt;
CLI::App* import_cmd = nullptr;
}  // namespace

void register_import(CLI::App& app) {
  CLI::App* sub = app.add_subcommand(
      "import",
      "Convert a recording into an LCM log: IMU (body axes x forward, y right, z down; increments), GNSS_RAW "
      "(pseudorange + rate) with GPS_ALMANAC fitted to the broadcast ephemeris, GNSS_PVT solutions and the RTK "
      "reference on TRUTH; t_s on the GPS time scale (docs/import.md). `describe FILE.toml`: any recording described by "
      "a TOML file (docs/own-recording.md); rtklib and psins are presets of the same path. Beside the log: its summary "
      "(LOG.json) and a starting filter configuration (LOG without extension + .filter.toml).");
  import_cmd = sub;
  sub->add_option("FORMAT", import_opt.imp.format,
                  "rtklib: an RTKLIB .pos, an IMU CSV with its .tag, optionally a u-blox .ubx (through convbin); "
                  "psins: imu_200hz.csv, gps_obs.csv, gps_eph.csv; ulog: a PX4 .ulg (docs/ulog.md); describe: a recording "
                  "description (TOML)")
      ->required()
      ->check(CLI::IsMember({"rtklib", "psins", "ulog", "describe"}));
  sub->add_option("PATH", import_opt.imp.path,
                  "the recording's directory (rtklib: or its .pos file; ulog: the .ulg file; describe: the description file)")
      ->required();
  sub->add_option("--data", import_opt.data_dir,
                  "describe: the directory that the description's relative file names are in (default: the "
                  "description's own directory)");
  sub->add_option("--flight-config-out,--filter-config-out", import_opt.filter_config,
                  "where to write the starting flight configuration (default: the log's name with .filter.toml)");
  sub->add_option("--log", import_opt.imp.log_path, "the LCM log to write")->required();
  sub->add_option("--json", import_opt.json, "write the summary as JSON");
  sub->add_option("--axes", import_opt.imp.axes,
                  "body x,y,z in sensor axes, e.g. -x,y,-z (default: rtklib -x,y,-z, the GNSS_IMU board x backward / "
                  "z up; psins y,x,-z, Right-Front-Up)");
  sub->add_option("--truth-max-q", import_opt.imp.truth_max_quality,
                  "solutions with RTKLIB Q from 1 to this also go on TRUTH as the reference (1: RTK fixed only)")
      ->capture_default_str()
      ->check(CLI::Range(0, 7));
  sub->add_option("--max-fit-error", import_opt.imp.max_fit_error_m,
                  "largest position + clock error [m] of an almanac fitted to the broadcast ephemeris that is written")
      ->capture_default_str()
      ->check(tools::positive());  // docs/faults.md: 0 or less wrote no almanac at all, exit 0
  sub->add_flag("--clip-gnss-to-imu", import_opt.imp.clip_gnss_to_imu,
                "keep GNSS epochs and solutions only within the IMU's time span (+-1 s)");
  sub->add_option("--imu-clock-ratio", import_opt.imp.imu_clock_ratio,
                  "rtklib IMU logs: GPS seconds per IMU-clock second [s/s] (default: from the .tag file's start and last "
                  "record); the first sample stays at the tag's start time")
      ->check(CLI::Range(0.99, 1.01));
  sub->add_flag("--keep-temp", import_opt.imp.keep_temp, "keep convbin's RINEX files (the directory is in the summary)");
  sub->add_option("--convbin", import_opt.imp.convbin, "RTKLIB's convbin program, for a u-blox .ubx beside the solution")
      ->capture_default_str();
  sub->add_option("--imu-topic", import_opt.ulog.imu_topic,
                  "ulog: IMU topic (auto: vehicle_imu when it covers its span, else sensor_combined)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "sensor_combined", "vehicle_imu"}));
  sub->add_option("--gnss-topic", import_opt.ulog.gnss_topic,
                  "ulog: GNSS topic (auto: of vehicle_gps_position and sensor_gps the one with more messages)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "vehicle_gps_position", "sensor_gps"}));
  sub->add_option("--gnss-latency", import_opt.ulog.gnss_latency_s,
                  "ulog: receiver latency [s]: a fix's UTC is valid this long before its boot time stamp (the summary "
                  "prints PX4's own EKF2_GPS_DELAY)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
}

namespace {
/// sdins import ulog: the summary and the starting flight configuration go beside the log like
/// every import's (tools::finish_import_outputs; LOG.json is where replay finds the reference's label).
int run_import_ulog(const std::string& filter_out) {
  import_opt.ulog.path = import_opt.imp.path;
  import_opt.ulog.log_path = import_opt.imp.log_path;
  tools::UlogImportResult r = tools::import_ulog(import_opt.ulog);
  tools::finish_import_outputs(r.summary, import_opt.imp.log_path, filter_out,
                               std::filesystem::path(import_opt.imp.log_path).stem().string(), "ulog");
  if (!import_opt.json.empty()) tools::write_json_file(import_opt.json, r.summary);
  std::fputs(tools::ulog_import_summary_text(r.summary).c_str(), stdout);
  std::printf("starting flight configuration: %s (edit the sensor noise from there)\n", filter_out.c_str());
  return 0;
}
}  // namespace

int run_import() {
  const std::string log = import_opt.imp.log_path;
  std::string filter_out = import_opt.filter_config;
  if (filter_out.empty()) filter_out = std::filesystem::path(log).replace_extension(".filter.toml").string();
  // docs/faults.md: no output may be (or lie inside) the recording, nor each other.
  tools::require_distinct({log, import_opt.json, tools::import_sidecar_path(log), filter_out}, {import_opt.imp.path});
  if (import_opt.imp.format == "ulog") return run_import_ulog(filter_out);
  nlohmann::json summary;
  if (import_opt.imp.format == "describe") {
    for (const char* o : {"--axes", "--truth-max-q", "--max-fit-error", "--clip-gnss-to-imu", "--imu-clock-ratio",
                          "--keep-temp", "--convbin"})
      if (import_cmd->count(o) > 0)
        throw std::runtime_error(std::string(o) + " is an option of the rtklib/psins presets; a description states it "
                                 "in its file (docs/own-recording.md)");
    tools::RecordingDescription d;
    const tools::DescriptionParseResult pr = tools::parse_recording_description_file(import_opt.imp.path, import_opt.data_dir, d);
    if (!pr.ok) throw std::runtime_error(pr.error);
    std::vector<std::string> inputs = tools::description_inputs(d);
    inputs.push_back(import_opt.imp.path);
    tools::require_distinct({log, import_opt.json, tools::import_sidecar_path(log), filter_out}, inputs);
    d.filter_config_out = filter_out;
    tools::DescribeOptions o;
    o.log_path = log;
    o.input = import_opt.imp.path;
    summary = tools::import_described(d, o);
  } else {
    if (!import_opt.data_dir.empty()) throw std::runtime_error("--data is an option of `import describe`");
    tools::RecordingDescription d = import_opt.imp.format == "rtklib" ? tools::rtklib_preset(import_opt.imp) : tools::psins_preset(import_opt.imp);
    d.filter_config_out = filter_out;
    summary = tools::import_described(d, tools::describe_options(import_opt.imp));
  }
  if (!import_opt.json.empty()) tools::write_json_file(import_opt.json, summary);
  std::fputs(tools::import_summary_text(summary).c_str(), stdout);
  return 0;
}

}  // namespace sdins
