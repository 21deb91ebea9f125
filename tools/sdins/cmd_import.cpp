// sdins import FORMAT PATH --log OUT.lcmlog [--json SUMMARY]: a recording (RTKLIB solution + IMU
// log + raw u-blox receiver log, or the PSINS tight-coupling data set) into the project's LCM log
// format. The work is in the tools library (tools/importers.hpp); this file parses options and prints.
#include <cstdio>
#include <stdexcept>

#include "commands.hpp"
#include "numeric_options.hpp"
#include "tools/importers.hpp"
#include "tools/output_file.hpp"

namespace sdins {
namespace {
struct Options {
  tools::ImportOptions imp;
  std::string json;
} opt;
}  // namespace

void register_import(CLI::App& app) {
  CLI::App* sub = app.add_subcommand(
      "import",
      "Convert a recording into an LCM log: IMU (body axes x forward, y right, z down; increments), GNSS_RAW "
      "(pseudorange + rate) with GPS_ALMANAC fitted to the broadcast ephemeris, GNSS_PVT solutions and the RTK "
      "reference on TRUTH; t_s on the GPS time scale (docs/import.md).");
  sub->add_option("FORMAT", opt.imp.format,
                  "rtklib: an RTKLIB .pos, an IMU CSV with its .tag, optionally a u-blox .ubx (through convbin); "
                  "psins: imu_200hz.csv, gps_obs.csv, gps_eph.csv")
      ->required()
      ->check(CLI::IsMember({"rtklib", "psins"}));
  sub->add_option("PATH", opt.imp.path, "the recording's directory (rtklib: or its .pos file)")->required();
  sub->add_option("--log", opt.imp.log_path, "the LCM log to write")->required();
  sub->add_option("--json", opt.json, "write the summary as JSON");
  sub->add_option("--axes", opt.imp.axes,
                  "body x,y,z in sensor axes, e.g. -x,y,-z (default: rtklib -x,y,-z, the GNSS_IMU board x backward / "
                  "z up; psins y,x,-z, Right-Front-Up)");
  sub->add_option("--truth-max-q", opt.imp.truth_max_quality,
                  "solutions with RTKLIB Q from 1 to this also go on TRUTH as the reference (1: RTK fixed only)")
      ->capture_default_str()
      ->check(CLI::Range(0, 7));
  sub->add_option("--max-fit-error", opt.imp.max_fit_error_m,
                  "largest position + clock error [m] of an almanac fitted to the broadcast ephemeris that is written")
      ->capture_default_str()
      ->check(tools::positive());  // docs/faults.md: 0 or less wrote no almanac at all, exit 0
  sub->add_flag("--clip-gnss-to-imu", opt.imp.clip_gnss_to_imu,
                "keep GNSS epochs and solutions only within the IMU's time span (+-1 s)");
  sub->add_option("--imu-clock-ratio", opt.imp.imu_clock_ratio,
                  "rtklib IMU logs: GPS seconds per IMU-clock second [s/s] (default: from the .tag file's start and last "
                  "record); the first sample stays at the tag's start time")
      ->check(CLI::Range(0.99, 1.01));
  sub->add_flag("--keep-temp", opt.imp.keep_temp, "keep convbin's RINEX files (the directory is in the summary)");
  sub->add_option("--convbin", opt.imp.convbin, "RTKLIB's convbin program, for a u-blox .ubx beside the solution")
      ->capture_default_str();
}

int run_import() {
  // docs/faults.md: neither output may be (or lie inside) the recording, nor each other.
  tools::require_distinct({opt.imp.log_path, opt.json}, {opt.imp.path});
  const nlohmann::json summary = tools::import_recording(opt.imp);
  if (!opt.json.empty()) tools::write_json_file(opt.json, summary);
  std::fputs(tools::import_summary_text(summary).c_str(), stdout);
  return 0;
}

}  // namespace sdins
