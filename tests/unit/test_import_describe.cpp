// The recording description (tools/import_describe.hpp, docs/own-recording.md): the parser's
// errors name the file, position and key; hand-made tables with their units, axes and time bases
// come back as the values they hold; the checks warn about a description that contradicts its
// data; the starting filter configuration is valid for the data's rates.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "fsw/frames.hpp"
#include "hal/lcm_log_sink.hpp"
#include "lcm_test_util.hpp"
#include "cfg/flight_config.hpp"
#include "tools/import_describe.hpp"
#include "tools/stream_summary.hpp"

namespace {

namespace fs = std::filesystem;
using Kind = fsw::InputEvent::Kind;

tools::DescriptionParseResult parse(const std::string& text, tools::RecordingDescription& d,
                                    const std::string& base = "/data") {
  return tools::parse_recording_description_text(text, "my.toml", base, d);
}

std::string parse_error(const std::string& text) {
  tools::RecordingDescription d;
  const tools::DescriptionParseResult r = parse(text, d);
  EXPECT_FALSE(r.ok) << text;
  return r.error;
}

const char* kImuHead = R"([imu]
file = "imu.csv"
gyro = { columns = [2, 3, 4], unit = "deg/s" }
accel = { columns = [5, 6, 7], unit = "g" }
time = { column = 1, unit = "ms", base = "gps_tow", week = 2300 }
)";

TEST(ImportDescribe, ErrorsNameTheFilePositionAndKey) {
  std::string e = parse_error(std::string(kImuHead) + "kind = \"rates\"\nfiel = 3\n");
  EXPECT_EQ(e, "my.toml:7:1: unknown key 'imu.fiel'");
  e = parse_error(R"([imu]
file = "imu.csv"
gyro = { columns = [2, 3, 4], unit = "deg" }
accel = { columns = [5, 6, 7], unit = "g" }
time = { column = 1, unit = "ms", week = 2300 }
)");
  EXPECT_NE(e.find("my.toml:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("'imu.gyro.unit' must be an angular rate unit: \"rad/s\" or \"deg/s\" (got \"deg\")"), std::string::npos) << e;
  e = parse_error(R"([imu]
file = "imu.csv"
gyro = { columns = [0, 3, 4], unit = "deg/s" }
)");
  EXPECT_NE(e.find("my.toml:3:21: 'imu.gyro.columns[0]' must be a column"), std::string::npos) << e;
  e = parse_error(R"([gnss]
file = "g.csv"
time = { column = "tow", base = "gps_tow" }
)");
  EXPECT_NE(e.find("'gnss.time.base' = \"gps_tow\" needs the week"), std::string::npos) << e;
  e = parse_error("[gnss]\nfile = \"g.csv\"\ntime = { column = 1, unit = \"min\", week = 1 }\n");
  EXPECT_NE(e.find("'gnss.time.unit' must be a time unit: \"s\", \"ms\", \"us\" or \"ns\""), std::string::npos) << e;
  e = parse_error(R"([gnss]
file = "g.csv"
time = { column = 1, week = 1 }
lat = 2
lon = 3
height = { column = 4, datum = "geoid" }
)");
  EXPECT_NE(e.find("my.toml:6:"), std::string::npos) << e;
  EXPECT_NE(e.find("'gnss.height.datum' must be \"ellipsoid\" or \"msl_egm96\""), std::string::npos) << e;
  e = parse_error(R"([gnss]
file = "g.csv"
time = { column = 1, week = 1 }
lat = 2
lon = 3
height = 4
)");
  EXPECT_NE(e.find("the GNSS sigmas: give 'gnss.pos_sigma' columns or a 'gnss.sigma_model'"), std::string::npos) << e;
  e = parse_error(std::string(kImuHead) + "axes = \"x,x,z\"\n");
  EXPECT_NE(e.find("'imu.axes' = \"x,x,z\""), std::string::npos) << e;
  e = parse_error("name = \"x\"\n");
  EXPECT_NE(e.find("names no stream"), std::string::npos) << e;
  e = parse_error(std::string(kImuHead) + "[gnss]\nfile = \"g.csv\"\nquality = { column = 9, map = { \"x\" = \"single\" } }\n");
  EXPECT_NE(e.find("'gnss.quality.map.x': the key must be the column's integer value"), std::string::npos) << e;
  e = parse_error(R"([imu]
file = "imu.csv"
gyro = { columns = [2, 3, 4], unit = "deg/s" }
accel = { columns = [5, 6, 7], unit = "g" }
time = { column = 1, unit = "ms", base = "local" }
)");
  EXPECT_NE(e.find("needs the clock pair"), std::string::npos) << e;
}

TEST(ImportDescribe, ParsesLayoutUnitsAndResolvesFiles) {
  tools::RecordingDescription d;
  const auto r = parse(std::string(kImuHead) + "format = \"whitespace\"\nheader = true\nskip_lines = 2\naxes = \"-y,x,z\"\n"
                                               "rotation_deg = [0, 0, 90]\n", d);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(d.imu.table.files, std::vector<std::string>{"/data/imu.csv"});
  EXPECT_TRUE(d.imu.table.whitespace);
  EXPECT_TRUE(d.imu.table.header);
  EXPECT_EQ(d.imu.table.skip_lines, 2);
  EXPECT_EQ(d.imu.gyro.cols[0].index, 1);
  EXPECT_DOUBLE_EQ(d.imu.gyro.scale, fsw::kDegToRad);
  EXPECT_DOUBLE_EQ(d.imu.accel.scale, fsw::kStandardGravity_mps2);
  EXPECT_DOUBLE_EQ(d.imu.time.scale_s, 1e-3);
  EXPECT_EQ(d.imu.time.week, 2300);
  EXPECT_TRUE(d.imu.has_rotation);
  EXPECT_EQ(d.imu.axes, "-y,x,z");
}

TEST(ImportDescribe, LeapSecondsFromTheTable) {
  EXPECT_EQ(tools::gps_minus_utc_s(315964800.0), 0);      // 1980-01-06
  EXPECT_EQ(tools::gps_minus_utc_s(1483228799.0), 17);    // 2016-12-31 23:59:59
  EXPECT_EQ(tools::gps_minus_utc_s(1483228800.0), 18);    // 2017-01-01
  EXPECT_EQ(tools::gps_minus_utc_s(1760000000.0), 18);
  EXPECT_THROW(tools::gps_minus_utc_s(1e8), std::runtime_error);
}

TEST(ImportDescribe, Egm96HeightsThroughProj) {
  // EGM96 geoid undulation N (ellipsoid - MSL): +17.16 m at (0, 0) in the Gulf of Guinea.
  const double h = tools::egm96_msl_to_ellipsoid_m(0.0, 0.0, 100.0);
  EXPECT_NEAR(h - 100.0, 17.16, 0.05);
  // India, the geoid low: N about -100 m south of Sri Lanka (4.7 N, 78.8 E).
  const double low = tools::egm96_msl_to_ellipsoid_m(4.7 * fsw::kDegToRad, 78.8 * fsw::kDegToRad, 0.0);
  EXPECT_LT(low, -95.0);
}

/// A scratch directory with files.
struct Dir {
  fs::path path;
  explicit Dir(const std::string& name) : path(lcm_test::scratch(name)) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~Dir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(path / name) << text;
    return (path / name).string();
  }
};

nlohmann::json import(const Dir& dir, const std::string& desc, std::vector<fsw::InputEvent>* inputs = nullptr,
                      std::vector<std::string>* truth_lines = nullptr) {
  tools::RecordingDescription d;
  const auto r = tools::parse_recording_description_text(desc, "t.toml", dir.path.string(), d);
  EXPECT_TRUE(r.ok) << r.error;
  tools::DescribeOptions o;
  o.log_path = (dir.path / "out.lcmlog").string();
  const nlohmann::json s = tools::import_described(d, o);
  if (inputs != nullptr) {
    hal::LcmReplayConfig cfg;
    cfg.gnss_pvt_channel = hal::kLcmChannelGnssPvt;
    hal::LcmReplayReader rd;
    EXPECT_EQ(rd.open(o.log_path, cfg), hal::LcmLogStatus::kOk);
    fsw::InputEvent in;
    while (rd.next(in) == hal::LcmLogStatus::kOk) inputs->push_back(in);
  }
  (void)truth_lines;
  return s;
}

// 50 Hz IMU rates in deg/s and g, time in ms since boot; 5 Hz GNSS with boot ms and GPS TOW (a
// 40 ppm clock, 0.2 s latency), lat/lon in 1e-7 deg, MSL height, speed + course + vertical speed
// positive down, HDOP/VDOP only, fix types 3 (3D) and 4 (DGPS), one duplicate epoch.
struct Flight {
  static constexpr double kDrift = 40e-6, kLatency = 0.2, kBoot0 = 1234.5, kTow0 = 300000.0;
  static double boot_s(double gps_tow) { return kBoot0 + (gps_tow - kTow0) * (1.0 + kDrift); }
  std::string imu, gnss;
  Flight() {
    char b[256];
    imu = "t_ms,gx,gy,gz,ax,ay,az\n";
    for (int k = 0; k <= 500; ++k) {  // 10 s
      const double tow = kTow0 + 0.02 * k;
      std::snprintf(b, sizeof(b), "%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f\n", boot_s(tow) * 1e3, 1.0, -2.0, 3.0, 0.01, 0.02, -1.0);
      imu += b;
    }
    gnss = "boot_ms tow lat_e7 lon_e7 alt_msl speed course vspd_down hdop vdop fix\n";
    for (int k = 0; k <= 50; ++k) {
      const double tow = kTow0 + 0.2 * k;
      std::snprintf(b, sizeof(b), "%.3f %.3f %d %d %.3f %.3f %.3f %.3f 1.4 2.0 %d\n", boot_s(tow + kLatency) * 1e3, tow,
                    473977000 + k, 85455000, 500.0 + 0.1 * k, 10.0, 90.0, 0.5, k % 10 == 0 ? 4 : 3);
      gnss += b;
      if (k == 20) gnss += b;  // a duplicate epoch
    }
  }
};

const char* kFlightDesc = R"(name = "fixed-wing"
[imu]
file = "imu.csv"
header = true
gyro = { columns = ["gx", "gy", "gz"], unit = "deg/s" }
accel = { columns = ["ax", "ay", "az"], unit = "g" }
axes = "x,y,z"
time = { column = "t_ms", unit = "ms", base = "local" }

[gnss]
file = "gnss.txt"
format = "whitespace"
header = true
time = { column = "tow", unit = "s", base = "gps_tow", week = 2300 }
local_clock = { column = "boot_ms", unit = "ms" }
latency_s = 0.2
lat = { column = "lat_e7", unit = "1e-7 deg" }
lon = { column = "lon_e7", unit = "1e-7 deg" }
height = { column = "alt_msl", unit = "m", datum = "msl_egm96" }
velocity = { form = "speed_course", columns = ["speed", "course", "vspd_down"], unit = "m/s", vertical_positive = "down" }
vel_sigma_mps = 0.3
sigma_model = { hdop = "hdop", vdop = "vdop", uere_by_kind_m = { single = 3.0, dgps = 1.0 } }
quality = { column = "fix", map = { "3" = "single", "4" = "dgps" } }

[reference]
kind = "autopilot_estimate"
from = "gnss"
max_quality = 5
)";

TEST(ImportDescribe, ANewUsersTablesComeBackAsTheyWereMeant) {
  const Dir dir("describe_flight");
  const Flight f;
  dir.write("imu.csv", f.imu);
  dir.write("gnss.txt", f.gnss);
  std::vector<fsw::InputEvent> in;
  const nlohmann::json s = import(dir, kFlightDesc, &in);
  // The clock pair: GPS = fit(boot), drift -40 ppm as GPS s per boot s, exact on these rows.
  const auto& fit = s["time_fit"];
  EXPECT_EQ(fit["pairs"].get<int>(), 51);  // the duplicate dropped first
  EXPECT_NEAR(fit["drift_ppm"].get<double>(), -Flight::kDrift / (1.0 + Flight::kDrift) * 1e6, 0.01);
  EXPECT_LT(fit["residual_rms_s"].get<double>(), 1e-5);
  EXPECT_EQ(s["gnss_pvt"]["samples"]["duplicates"].get<int>(), 1);
  // Every stream of the summary in the one shape (tools/stream_summary.hpp), under "samples".
  const nlohmann::json shape = tools::StreamSummary{}.to_json();
  for (const char* stream : {"imu", "gnss_pvt", "truth"}) {
    ASSERT_TRUE(s[stream].is_object()) << stream;
    for (const auto& [key, value] : shape.items()) EXPECT_TRUE(s[stream]["samples"].contains(key)) << stream << "." << key;
    EXPECT_EQ(s[stream]["samples"].size(), shape.size()) << stream;
  }
  EXPECT_EQ(s["imu"]["samples"]["name"], "imu");
  EXPECT_EQ(s["truth"]["samples"]["name"], "reference");
  EXPECT_EQ(s["gnss_pvt"]["samples"]["count"].get<int>(), 51);
  EXPECT_EQ(s["gnss_pvt"]["lines"]["rejected_by_reason"]["duplicate time (dropped)"].get<int>(), 1);
  EXPECT_EQ(s["reference"]["kind"], "autopilot_estimate");
  EXPECT_FALSE(s["reference"]["has_attitude"].get<bool>());
  std::size_t n_imu = 0, n_pvt = 0;
  double first_imu_t = NAN;
  for (const fsw::InputEvent& e : in) {
    if (e.kind == Kind::kImu) {
      if (n_imu++ == 0) first_imu_t = e.imu.t_s;
      // Trapezoid of constant rates: the increment is rate x dt (1, -2, 3 deg/s; 0.01, 0.02, -1 g).
      EXPECT_NEAR(e.imu.dtheta_rad.x() / e.imu.dt_s, 1.0 * fsw::kDegToRad, 1e-9);
      EXPECT_NEAR(e.imu.dtheta_rad.z() / e.imu.dt_s, 3.0 * fsw::kDegToRad, 1e-9);
      EXPECT_NEAR(e.imu.dv_mps.z() / e.imu.dt_s, -fsw::kStandardGravity_mps2, 1e-7);
      EXPECT_NEAR(e.imu.dt_s, 0.02, 1e-6);
    } else if (e.kind == Kind::kGnssPvt) {
      const fsw::GnssPvtMeasurement& p = e.pvt;
      if (n_pvt == 0) {
        EXPECT_NEAR(p.t_s, Flight::kTow0, 1e-9);  // week 2300 is the time scale's
        EXPECT_NEAR(p.llh.x() * fsw::kRadToDeg, 47.3977, 1e-9);
        // EGM96 near Zurich: N is about +47-49 m.
        EXPECT_GT(p.llh.z() - 500.0, 45.0);
        EXPECT_LT(p.llh.z() - 500.0, 52.0);
        EXPECT_EQ(p.quality, 4);  // fix type 4 -> DGPS
        EXPECT_NEAR(p.pos_sigma_enu_m.x(), 1.0 * 1.4 / std::sqrt(2.0), 1e-12);
        EXPECT_NEAR(p.pos_sigma_enu_m.z(), 1.0 * 2.0, 1e-12);
      }
      if (n_pvt == 1) {
        EXPECT_EQ(p.quality, 5);
        EXPECT_NEAR(p.pos_sigma_enu_m.y(), 3.0 * 1.4 / std::sqrt(2.0), 1e-12);
      }
      // 10 m/s due east, 0.5 m/s down.
      EXPECT_NEAR(p.vel_enu_mps.x(), 10.0, 1e-9);
      EXPECT_NEAR(p.vel_enu_mps.y(), 0.0, 1e-9);
      EXPECT_NEAR(p.vel_enu_mps.z(), -0.5, 1e-9);
      ++n_pvt;
    }
  }
  EXPECT_EQ(n_imu, 500u);
  EXPECT_EQ(n_pvt, 51u);
  // The IMU's second sample (the first increment ends there) on GPS time through the fit.
  EXPECT_NEAR(first_imu_t, Flight::kTow0 + 0.02, 5e-6);
  // The starting configuration: 50 Hz IMU, 5 Hz GNSS -> 10 frames per EKF step, latency below.
  cfg::FlightConfig cfg;
  const auto pr = cfg::load_flight_config(s["filter_config"].get<std::string>(), cfg);
  ASSERT_TRUE(pr.ok) << pr.error;
  EXPECT_EQ(cfg.app.exec.imu_samples_per_frame, 1);
  EXPECT_DOUBLE_EQ(cfg.app.exec.nav_rate_hz, 50.0);
  EXPECT_EQ(cfg.app.exec.frames_per_ekf, 10);
  EXPECT_GE(cfg.app.exec.ekf_latency_frames, 1);
  EXPECT_LT(cfg.app.exec.ekf_latency_frames, 10);
  EXPECT_EQ(cfg.gnss_source, cfg::GnssSource::kPvt);
  EXPECT_EQ(cfg.app.pvt_max_quality, 5);
  // The sidecar beside the log carries the reference's label.
  std::ifstream side(dir.path / "out.lcmlog.json");
  const nlohmann::json j = nlohmann::json::parse(side);
  EXPECT_EQ(j["format"], "sdins-import-summary");
  EXPECT_EQ(j["reference"]["kind"], "autopilot_estimate");
  EXPECT_TRUE(s["warnings"].empty()) << s["warnings"].dump();
}

TEST(ImportDescribe, ADescriptionThatContradictsItsDataIsWarnedAbout) {
  const Dir dir("describe_contradiction");
  const Flight f;
  dir.write("imu.csv", f.imu);
  dir.write("gnss.txt", f.gnss);
  // The gyro columns (deg/s, 1..3) declared rad/s; the GNSS a week later than the IMU.
  std::string desc = kFlightDesc;
  desc.replace(desc.find("unit = \"deg/s\""), 14, "unit = \"rad/s\"");
  // Rates of 10, -5, 8 "rad/s" (573 deg/s) all the time: deg/s values by their magnitude.
  std::string imu = "t_ms,gx,gy,gz,ax,ay,az\n";
  char b[200];
  for (int k = 0; k <= 500; ++k) {
    std::snprintf(b, sizeof(b), "%.6f,%.6f,%.6f,%.6f,0.01,0.02,-1.0\n", Flight::boot_s(Flight::kTow0 + 0.02 * k) * 1e3,
                  10.0, -5.0, 8.0);
    imu += b;
  }
  dir.write("imu.csv", imu);
  const nlohmann::json s = import(dir, desc);
  bool gyro = false;
  for (const auto& w : s["warnings"]) gyro = gyro || w.get<std::string>().find("imu.gyro") != std::string::npos;
  EXPECT_TRUE(gyro) << s["warnings"].dump();

  // IMU in g declared m/s^2; GNSS spans a week away from the IMU's.
  std::string desc2 = kFlightDesc;
  desc2.replace(desc2.find("unit = \"g\""), 10, "unit = \"m/s^2\"");
  desc2.replace(desc2.find("week = 2300"), 11, "week = 2301");
  dir.write("imu.csv", f.imu);
  const Dir dir2("describe_contradiction2");
  dir2.write("imu.csv", f.imu);
  // The IMU on its own GPS week column-free base: GPS TOW with week 2300 (no clock pair needed).
  std::string desc3 = desc2;
  desc3.replace(desc3.find("base = \"local\""), 14, "base = \"gps_tow\", week = 2300");
  std::string imu_tow = "t_ms,gx,gy,gz,ax,ay,az\n";
  for (int k = 0; k <= 500; ++k) {
    std::snprintf(b, sizeof(b), "%.3f,1,2,3,0.01,0.02,-1.0\n", (Flight::kTow0 + 0.02 * k) * 1e3);
    imu_tow += b;
  }
  dir2.write("imu.csv", imu_tow);
  dir2.write("gnss.txt", f.gnss);
  const nlohmann::json s2 = import(dir2, desc3);
  bool accel = false, overlap = false;
  for (const auto& w : s2["warnings"]) {
    const std::string t = w.get<std::string>();
    accel = accel || t.find("imu.accel") != std::string::npos;
    overlap = overlap || (t.find("gnss:") == 0 && t.find("does not overlap") != std::string::npos);
  }
  EXPECT_TRUE(accel) << s2["warnings"].dump();
  EXPECT_TRUE(overlap) << s2["warnings"].dump();
}

TEST(ImportDescribe, RejectedRowsAreCountedWithReasonAndLine) {
  const Dir dir("describe_rejections");
  const std::string row = " 0.001 0.002 0.003 0.01 0.02 -0.3\n";
  std::string imu = "# a comment\n1000" + row + "1010 1 2 3 4 5\n1020 x 2 3 4 5 6\n1030 nan 2 3 4 5 6\n1040" + row +
                    "1050 0.001 0.002 0.003 0.01 0.02 -0.3";
  dir.write("imu.txt", imu);
  const std::string desc = R"([imu]
file = "imu.txt"
format = "whitespace"
comment = "#"
fields = 7
kind = "increments"
gyro = { columns = [2, 3, 4], unit = "rad" }
accel = { columns = [5, 6, 7], unit = "m/s" }
time = { column = 1, unit = "ms", base = "gps_seconds" }
)";
  const nlohmann::json s = import(dir, desc);
  const auto& l = s["imu"]["lines"];
  EXPECT_EQ(l["lines"].get<int>(), 6);
  EXPECT_EQ(l["rejected_by_reason"]["wrong field count (6, expected 7)"].get<int>(), 1);
  EXPECT_EQ(l["rejected_by_reason"]["unparsable number"].get<int>(), 1);
  EXPECT_EQ(l["rejected_by_reason"]["non-finite value"].get<int>(), 1);
  EXPECT_EQ(l["rejected_by_reason"]["partial last line (no newline)"].get<int>(), 1);
  EXPECT_EQ(l["rejected_examples"][0]["line"].get<int>(), 3);
  EXPECT_EQ(s["rejected_lines_total"].get<int>(), 4);
  EXPECT_THROW(import(dir, std::string(desc).replace(desc.find("[2, 3, 4]"), 9, "[\"gx\", 3, 4]")), std::runtime_error);
}

}  // namespace

namespace {

cfg::FlightConfig config_from(const nlohmann::json& summary) {
  const std::string text = tools::starting_filter_config(summary, "t");
  cfg::FlightConfig cfg;
  const auto pr = cfg::parse_flight_config_text(text, "t.toml", cfg);
  EXPECT_TRUE(pr.ok) << pr.error << "\n" << text;
  return cfg;
}

TEST(ImportDescribe, StartingConfigurationFromAMinimalSummary) {
  // What another importer (a ULog reader) may have: rates and qualities only.
  const nlohmann::json s = {{"imu", {{"samples", {{"count", 1001}, {"rate_hz", 250.0}}}}},
                            {"gnss_pvt", {{"samples", {{"count", 51}, {"rate_hz", 5.0}}}, {"by_quality", {{"5", 51}}}}}};
  const cfg::FlightConfig cfg = config_from(s);
  EXPECT_EQ(cfg.app.exec.imu_samples_per_frame, 2);  // 250 Hz -> 125 Hz frames
  EXPECT_DOUBLE_EQ(cfg.app.exec.nav_rate_hz, 125.0);
  EXPECT_EQ(cfg.app.exec.frames_per_ekf, 25);
  EXPECT_EQ(cfg.app.exec.ekf_latency_frames, 6);
  EXPECT_EQ(cfg.app.pvt_max_quality, 5);
  // Nothing known: the flight software's rates, a valid latency.
  const cfg::FlightConfig none = config_from(nlohmann::json::object());
  EXPECT_LT(none.app.exec.ekf_latency_frames, none.app.exec.frames_per_ekf);
  // A 10 Hz IMU with 5 Hz GNSS: 2 frames per EKF step, the latency 1.
  nlohmann::json slow_summary;
  slow_summary["imu"]["samples"] = {{"count", 100}, {"rate_hz", 10.0}};
  slow_summary["gnss_pvt"]["samples"] = {{"count", 50}, {"rate_hz", 5.0}};
  const cfg::FlightConfig slow = config_from(slow_summary);
  EXPECT_EQ(slow.app.exec.frames_per_ekf, 2);
  EXPECT_EQ(slow.app.exec.ekf_latency_frames, 1);
}

TEST(ImportDescribe, StartingRatesFromTheOneStreamShape) {
  // Streams from their time tags, as every importer writes them: a 200 Hz IMU without gaps and 5 Hz
  // solutions with two lost seconds (mean 4 Hz).
  std::vector<double> t_imu, t_gnss;
  for (int k = 0; k <= 2000; ++k) t_imu.push_back(100.0 + k * 0.005);
  for (int k = 0; k <= 50; ++k)
    if (k < 20 || k >= 30) t_gnss.push_back(100.0 + k * 0.2);
  nlohmann::json s;
  s["imu"]["samples"] = tools::summarize_stream("imu", "t", t_imu).to_json();
  s["gnss_pvt"]["samples"] = tools::summarize_stream("gnss_pvt", "t", t_gnss).to_json();
  s["gnss_pvt"]["by_quality"] = {{"5", t_gnss.size()}};
  EXPECT_NEAR(s["gnss_pvt"]["samples"]["mean_rate_hz"].get<double>(), 40.0 / 10.0, 1e-9);
  const cfg::FlightConfig cfg = config_from(s);
  EXPECT_EQ(cfg.app.exec.imu_samples_per_frame, 1);
  EXPECT_DOUBLE_EQ(cfg.app.exec.nav_rate_hz, 200.0);
  EXPECT_EQ(cfg.app.exec.frames_per_ekf, 40);  // the solutions' nominal 5 Hz, not the mean
  // An IMU whose mean rate gaps pull more than 2 % below its nominal one: the nominal 250 Hz.
  std::vector<double> t_gappy;
  for (int k = 0; k <= 1000; ++k)
    if (k % 10 != 5) t_gappy.push_back(k * 0.004);
  s["imu"]["samples"] = tools::summarize_stream("imu", "t", t_gappy).to_json();
  EXPECT_LT(s["imu"]["samples"]["mean_rate_hz"].get<double>(), 0.98 * 250.0);
  EXPECT_EQ(config_from(s).app.exec.imu_samples_per_frame, 2);  // 250 Hz -> 125 Hz frames
}

}  // namespace
