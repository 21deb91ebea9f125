// `sdins import` on the measured data sets (../shared/data), checked for physical consistency:
// the imported raw GNSS epochs, with the almanac fitted to the broadcast ephemeris and run through
// the flight software's own conversion and single-point solution, give fixes where the recording
// was made and speeds that agree with the IMU's; the IMU time scale equals the one the data set's
// source computed. Skipped (with the reason) when the data or RTKLIB's convbin are missing.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "fsw/gnss_pvt.hpp"
#include "fsw/gps_orbit.hpp"
#include "hal/lcm_log_sink.hpp"
#include "lcm_test_util.hpp"
#include "recordings.hpp"
#include "tools/importers.hpp"

namespace {

namespace fs = std::filesystem;
using Kind = fsw::InputEvent::Kind;

const std::string kData = test::recordings_dir();

bool have_convbin() { return lcm_test::run("command -v convbin > /dev/null 2>&1") == 0; }

struct Imported {
  nlohmann::json summary;
  std::vector<fsw::InputEvent> inputs;  ///< every input in time order (GNSS_PVT included)
};

Imported import_and_read(const std::string& format, const std::string& dir, const std::string& name,
                         double imu_clock_ratio = 0.0) {
  tools::ImportOptions opt;
  opt.imu_clock_ratio = imu_clock_ratio;
  opt.format = format;
  opt.path = kData + "/" + dir;
  opt.log_path = lcm_test::scratch(name + ".lcmlog");
  Imported r;
  r.summary = tools::import_recording(opt);
  hal::LcmReplayConfig cfg;
  cfg.gnss_pvt_channel = hal::kLcmChannelGnssPvt;
  hal::LcmReplayReader rd;
  EXPECT_EQ(rd.open(opt.log_path, cfg), hal::LcmLogStatus::kOk);
  fsw::InputEvent in;
  while (rd.next(in) == hal::LcmLogStatus::kOk) r.inputs.push_back(in);
  EXPECT_EQ(rd.stats().rejected(), 0u);
  std::remove(opt.log_path.c_str());
  return r;
}

/// Runs every raw epoch through the flight software's conversion (almanac table fed in log
/// order) and single-point solution.
struct Fix {
  double t_s;
  fsw::GnssPvt pvt;
  fsw::Vec3 llh;
  int n_obs;
};
std::vector<Fix> fixes(const std::vector<fsw::InputEvent>& inputs) {
  fsw::GpsAlmanacTable table;
  std::vector<Fix> out;
  for (const fsw::InputEvent& in : inputs) {
    if (in.kind == Kind::kAlmanac) EXPECT_EQ(table.set(in.almanac), fsw::Status::kOk);
    if (in.kind != Kind::kGnssRaw) continue;
    fsw::GnssEpoch ep;
    fsw::GnssConversionStats st;
    EXPECT_EQ(fsw::gnss_epoch_from_raw(in.gnss, table, nullptr, ep, st), fsw::Status::kOk);
    fsw::GnssPvt p;
    if (ep.n_obs >= 4 && fsw::gnss_pvt(ep, p) == fsw::Status::kOk)
      out.push_back({in.t_s, p, fsw::llh_from_ecef(p.r_ecef_m), ep.n_obs});
  }
  return out;
}

}  // namespace

// PSINS: the README places the recording "about 33.86 N, 108.76 E" and says the first ~50 s of the
// IMU window are quasi-static. Every epoch with 5+ satellites gives a consistent fix (pseudorange
// residuals of decimetres: the almanac fit, the satellite clock and the time tags are right), the
// pseudorange rates give ~0 m/s while the IMU says the vehicle stands still (the Doppler sign is
// right) and metres per second later.
TEST(ImportData, PsinsRawEpochsFixWhereAndWhenTheReadmeSays) {
  if (!fs::exists(kData + "/psins-tc")) GTEST_SKIP() << "no recording " << kData << "/psins-tc (set SDINS_RECORDINGS_DIR, docs/data.md)";
  const Imported r = import_and_read("psins", "psins-tc", "psins_data");
  const std::vector<Fix> f = fixes(r.inputs);
  const double imu_t0 = r.summary["imu"]["samples"]["t_first_s"].get<double>();
  int n5 = 0, still = 0, moving = 0;
  double max_res = 0.0;
  for (const Fix& x : f) {
    if (x.n_obs < 5) continue;
    ++n5;
    max_res = std::max(max_res, x.pvt.pr_rms_residual_m);
    EXPECT_NEAR(x.llh.x() * fsw::kRadToDeg, 33.86, 0.3) << x.t_s;  // measured: 34.03 N (README: "about 33.86")
    EXPECT_NEAR(x.llh.y() * fsw::kRadToDeg, 108.76, 0.05) << x.t_s;
    EXPECT_NEAR(x.llh.z(), 415.0, 30.0) << x.t_s;
    EXPECT_LT(x.pvt.prr_rms_residual_mps, 1.0) << x.t_s;  // measured <= 0.37 m/s; a wrong sign gives hundreds
    if (x.t_s >= imu_t0 && x.t_s < imu_t0 + 40.0) {
      ++still;
      EXPECT_LT(x.pvt.v_ecef_mps.norm(), 0.3) << "quasi-static at " << x.t_s;
    }
    if (x.pvt.v_ecef_mps.norm() > 2.0) ++moving;
  }
  EXPECT_GT(n5, 1500);  // measured 1568 of 1707 epochs with 5+ satellites
  EXPECT_LT(max_res, 3.0);
  EXPECT_GE(still, 35);
  EXPECT_GT(moving, 100);
}

// Walk: the u-blox log yields broadcast ephemeris for only some satellites (4 here); with exactly
// 4 the fix has no redundancy but must still land within tens of metres (no ionosphere or
// troposphere model in a single-point fix) of the RTK solution at the same time. The IMU times
// equal the GPS times the data set's source computed (imu_1730_sf.csv, GPST seconds since 1970).
TEST(ImportData, WalkRawFixNearTheRtkSolutionAndImuOnTheSourcesTimeScale) {
  if (!fs::exists(kData + "/gnss-imu-walk")) GTEST_SKIP() << "no recording " << kData << "/gnss-imu-walk (set SDINS_RECORDINGS_DIR, docs/data.md)";
  if (!have_convbin()) GTEST_SKIP() << "RTKLIB's convbin is not installed (Debian package rtklib)";
  const Imported r = import_and_read("rtklib", "gnss-imu-walk", "walk_data");
  const std::vector<Fix> f = fixes(r.inputs);
  ASSERT_GT(f.size(), 500u);
  std::vector<hal::GnssPvtSample> pvt;
  for (const auto& in : r.inputs)
    if (in.kind == Kind::kGnssPvt) pvt.push_back(hal::from_fsw(in.pvt));
  ASSERT_EQ(pvt.size(), 536u);
  std::size_t j = 0;
  int compared = 0;
  for (const Fix& x : f) {
    while (j + 1 < pvt.size() && pvt[j + 1].t_s <= x.t_s + 0.01) ++j;
    if (std::abs(pvt[j].t_s - x.t_s) > 0.01) continue;  // raw epochs are 1 ms before the solutions
    const double d = (x.pvt.r_ecef_m - fsw::ecef_from_llh(pvt[j].llh)).norm();
    EXPECT_LT(d, 40.0) << x.t_s;  // measured 8-21 m
    ++compared;
  }
  EXPECT_GT(compared, 500);

  // IMU sample k (k >= 1) ends at the time of good CSV line k; the source's _sf file has one row
  // per good line, its time in GPST seconds since 1970.
  std::ifstream sf(kData + "/gnss-imu-walk/imu_1730_sf.csv");
  ASSERT_TRUE(sf);
  std::vector<double> sf_tow;
  std::string line;
  const int week = r.summary["time_scale"]["gps_week0"].get<int>();
  while (std::getline(sf, line)) {
    const double t = std::stod(line.substr(0, line.find(',')));
    sf_tow.push_back(t - static_cast<double>(tools::kGpsEpochGtime_s) - week * 604800.0);
  }
  std::vector<double> imu_t;
  for (const auto& in : r.inputs)
    if (in.kind == Kind::kImu) imu_t.push_back(in.t_s);
  ASSERT_EQ(imu_t.size() + 1, sf_tow.size());
  double worst = 0.0;
  for (std::size_t k = 0; k < imu_t.size(); ++k) worst = std::max(worst, std::abs(imu_t[k] - sf_tow[k + 1]));
  EXPECT_LT(worst, 1e-6);  // the _sf times are printed to 0.1 us and held in a double near 1.76e9
}

namespace {

// The drive's IMU time scale: by default the tag file's (its start time and last record: 1.000257
// GPS s per IMU-clock s, as the data set's source maps it); --imu-clock-ratio replaces the rate and
// keeps the first sample at the start time. With 1 (the IMU's own millisecond tick) the diagnosis'
// drifting IMU-GNSS time offset of the default import disappears (docs/datasets/gnss-imu-drive.md).
TEST(ImportData, DriveImuClockRatioReplacesTheTagFilesRate) {
  if (!fs::exists(kData + "/gnss-imu-drive")) GTEST_SKIP() << "no recording " << kData << "/gnss-imu-drive (set SDINS_RECORDINGS_DIR, docs/data.md)";
  const Imported tag = import_and_read("rtklib", "gnss-imu-drive", "drive_tag");
  const Imported own = import_and_read("rtklib", "gnss-imu-drive", "drive_own", 1.0);
  EXPECT_NEAR(tag.summary["imu"]["seconds_per_imu_second"].get<double>(), 1.000257, 1e-6);
  EXPECT_EQ(own.summary["imu"]["seconds_per_imu_second"].get<double>(), 1.0);
  std::vector<double> a, b;
  for (const auto& in : tag.inputs)
    if (in.kind == Kind::kImu) a.push_back(in.t_s);
  for (const auto& in : own.inputs)
    if (in.kind == Kind::kImu) b.push_back(in.t_s);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 50000u);
  const double ticks_s = (own.summary["imu"]["tick_ms_last"].get<double>() - own.summary["imu"]["tick_ms_first"].get<double>()) / 1e3;
  // Sample k ends at line k: the first sample ends one line after the start time.
  const double t0 = b.front() - (b[1] - b[0]);
  EXPECT_NEAR(b.back() - t0, ticks_s, 1e-3);
  EXPECT_NEAR(a.front(), b.front(), 1e-4);              // same start
  EXPECT_NEAR(a.back() - b.back(), ticks_s * 257e-6, 2e-3);  // 0.14 s apart after 549 s
}

}  // namespace
