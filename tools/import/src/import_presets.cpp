// `sdins import rtklib|psins` as presets of the description import (tools/import_describe.hpp):
// each finds its recording's files and builds the description that docs/datasets/*.import.toml
// spell out; the engine (import_describe.cpp) does the rest, so both routes are one code path.
#include <filesystem>
#include <stdexcept>

#include "fsw/frames.hpp"
#include "import_common.hpp"
#include "tools/import_describe.hpp"

namespace tools {

using namespace import_detail;

namespace {

ColumnRef col(int one_based) { return ColumnRef{"", one_based - 1}; }
ColumnRef col(const char* name) { return ColumnRef{name, -1}; }

}  // namespace

RecordingDescription rtklib_preset(const ImportOptions& opt) {
  const fs::path in(opt.path);
  fs::path dir, pos;
  if (fs::is_directory(in)) {
    dir = in;
    const auto p = files_with(dir, ".pos");
    if (p.empty()) throw std::runtime_error("no RTKLIB solution (*.pos) in " + dir.string());
    if (p.size() > 1) throw std::runtime_error("several .pos files in " + dir.string() + " (" + names(p) + "): name one");
    pos = p.front();
  } else if (fs::is_regular_file(in) && in.extension() == ".pos") {
    pos = in;
    dir = in.parent_path().empty() ? fs::path(".") : in.parent_path();
  } else {
    throw std::runtime_error(opt.path + " is neither a directory nor a .pos file");
  }
  std::vector<fs::path> imu_csv, untagged;
  for (const fs::path& c : files_with(dir, ".csv")) (fs::exists(c.string() + ".tag") ? imu_csv : untagged).push_back(c);
  // docs/faults.md: an IMU log without its time tag is an error, not an import without the IMU.
  if (imu_csv.empty() && !untagged.empty())
    throw std::runtime_error("IMU CSV without its time-tag file in " + dir.string() + " (" + names(untagged) + ": no " +
                             untagged.front().filename().string() + ".tag beside it): the IMU cannot be placed on GPS time");
  if (imu_csv.size() > 1) throw std::runtime_error("several IMU CSVs with a .tag in " + dir.string() + " (" + names(imu_csv) + ")");
  const auto ubx = files_with(dir, ".ubx");
  if (ubx.size() > 1) throw std::runtime_error("several .ubx files in " + dir.string() + " (" + names(ubx) + ")");
  parse_axis_map(opt.axes.empty() ? kAxesGnssImu : opt.axes);  // a bad --axes fails before any file is read

  RecordingDescription d;
  d.format = "rtklib";
  d.source = opt.path;
  d.clip_gnss_to_imu = opt.clip_gnss_to_imu;
  d.max_fit_error_m = opt.max_fit_error_m;
  if (!imu_csv.empty()) {
    // GNSS_IMU layout: accel x, y, z [g], gyro x, y, z [deg/s], tick [ms]; no header.
    ImuStreamSpec& s = d.imu;
    s.present = true;
    s.origin = "preset rtklib";
    s.table.files = {imu_csv.front().string()};
    s.table.fields = 7;
    s.accel = {{col(1), col(2), col(3)}, "g", fsw::kStandardGravity_mps2};
    s.gyro = {{col(4), col(5), col(6)}, "deg/s", fsw::kDegToRad};
    s.time.column = col(7);
    s.time.unit = "ms";
    s.time.scale_s = 1e-3;
    s.time.base = TimeBase::kRtklibTag;
    s.time.tag_file = imu_csv.front().string() + ".tag";
    s.time.clock_ratio = opt.imu_clock_ratio;
    s.axes = opt.axes.empty() ? kAxesGnssImu : opt.axes;
    s.max_accel_mps2 = ImuCsvLimits{}.max_accel_g * fsw::kStandardGravity_mps2;
    s.max_gyro_radps = ImuCsvLimits{}.max_gyro_dps * fsw::kDegToRad;
  }
  d.gnss.present = true;
  d.gnss.format = "rtklib_pos";
  d.gnss.table.files = {pos.string()};
  d.reference.present = true;
  d.reference.kind = "rtk";
  d.reference.from_gnss = true;
  d.reference.max_quality = opt.truth_max_quality;
  if (!ubx.empty()) {
    d.raw.present = true;
    d.raw.format = RawFormat::kUbx;
    d.raw.ubx_file = ubx.front().string();
    d.raw.convbin = opt.convbin;
    d.raw.keep_temp = opt.keep_temp;
  }
  return d;
}

RecordingDescription psins_preset(const ImportOptions& opt) {
  const fs::path dir(opt.path);
  if (!fs::is_directory(dir)) throw std::runtime_error(opt.path + " is not a directory (psins-tc layout expected)");
  const fs::path imu_p = dir / "imu_200hz.csv", obs_p = dir / "gps_obs.csv", eph_p = dir / "gps_eph.csv";
  for (const fs::path& p : {imu_p, obs_p, eph_p})
    if (!fs::exists(p)) throw std::runtime_error("missing " + p.string());
  parse_axis_map(opt.axes.empty() ? kAxesPsins : opt.axes);

  RecordingDescription d;
  d.format = "psins";
  d.source = opt.path;
  d.clip_gnss_to_imu = opt.clip_gnss_to_imu;
  d.max_fit_error_m = opt.max_fit_error_m;
  // imu_200hz.csv: GPS tow [s], delta-theta x, y, z [rad], delta-v x, y, z [m/s] (Right-Front-Up).
  ImuStreamSpec& s = d.imu;
  s.present = true;
  s.origin = "preset psins";
  s.table.files = {imu_p.string()};
  s.table.header = true;
  s.increments = true;
  s.gyro = {{col("dtheta_x_rad"), col("dtheta_y_rad"), col("dtheta_z_rad")}, "rad", 1.0};
  s.accel = {{col("dv_x_mps"), col("dv_y_mps"), col("dv_z_mps")}, "m/s", 1.0};
  s.time.column = col("gps_tow_s");
  s.time.base = TimeBase::kGpsTow;
  s.time.week_from_ephemeris = true;
  s.axes = opt.axes.empty() ? kAxesPsins : opt.axes;
  // gps_obs.csv: tow, PRN, C/A pseudorange [m], L1 carrier, an unused column, Doppler [m/s] = -range rate.
  RawStreamSpec& r = d.raw;
  r.present = true;
  r.format = RawFormat::kTable;
  r.table.files = {obs_p.string()};
  r.table.header = true;
  r.time.column = col("gps_tow_s");
  r.time.base = TimeBase::kGpsTow;
  r.time.week_from_ephemeris = true;
  r.prn = col("prn");
  r.pseudorange = col("C1_pseudorange_m");
  r.range_rate = col("D1_doppler_mps(=-range_rate)");
  r.range_rate_unit = "-m/s";
  r.range_rate_scale = -1.0;
  r.ephemeris_file = eph_p.string();
  r.ephemeris_format = "csv";
  return d;
}

DescribeOptions describe_options(const ImportOptions& opt) {
  DescribeOptions o;
  o.log_path = opt.log_path;
  o.input = opt.path;
  return o;
}

}  // namespace tools
