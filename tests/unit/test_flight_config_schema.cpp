// Flight configuration files (cfg/flight_config.hpp, config/README.md): the data sets' files parse
// into the fields and units they say, and broken files are rejected with the key and position.
#include <gtest/gtest.h>

#include <filesystem>

#include "fsw/frames.hpp"
#include "cfg/flight_config.hpp"

namespace {

// The source tree from CMake (absolute): __FILE__ is relative under ccache's CCACHE_BASEDIR, and CTest
// runs the tests from build/<preset>/tests.
const std::filesystem::path kConfigDir = std::filesystem::path(SDINS_TEST_SOURCE_DIR) / "config/datasets";

cfg::FlightConfig defaults() {
  cfg::FlightConfig f;
  f.app.exec.ekf.arw_rad_per_rts = 2e-7;
  return f;
}

}  // namespace

TEST(FlightConfigSchema, EveryDataSetFileParses) {
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(kConfigDir)) {
    if (e.path().extension() != ".toml") continue;
    cfg::FlightConfig f = defaults();
    const cfg::FlightConfigResult r = cfg::parse_flight_config_file(e.path().string(), f);
    EXPECT_TRUE(r.ok) << r.error;
    EXPECT_FALSE(f.name.empty()) << e.path();
    fsw::FlightApp<fsw::Layout15Full> app;
    EXPECT_EQ(app.init(f.app), fsw::Status::kOk) << e.path();
    ++files;
  }
  EXPECT_GE(files, 1);
}

TEST(FlightConfigSchema, DriveFileSetsFieldsInTheirUnits) {
  cfg::FlightConfig f = defaults();
  const cfg::FlightConfigResult r =
      cfg::parse_flight_config_file((kConfigDir / "gnss-imu-drive.toml").string(), f);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(f.gnss_source, cfg::GnssSource::kPvt);
  EXPECT_EQ(f.app.exec.imu_samples_per_frame, 1);
  EXPECT_DOUBLE_EQ(f.app.exec.nav_rate_hz, 100.0);
  EXPECT_EQ(f.app.exec.frames_per_ekf, 25);  // 100 Hz / 4 Hz
  EXPECT_EQ(f.app.exec.gnss_wait_frames, 10);  // 0.1 s at 100 Hz
  EXPECT_NEAR(f.app.exec.ekf.arw_rad_per_rts, 1.0 * fsw::kDegToRad / 60.0, 1e-15);
  EXPECT_NEAR(f.app.exec.ekf.vrw_mps_per_rts, 0.3 / 60.0, 1e-15);
  EXPECT_NEAR(f.app.exec.ekf.gyro_bias_sigma_radps, 1000.0 * fsw::kDegPerHourToRadps, 1e-15);
  EXPECT_NEAR(f.app.exec.ekf.accel_bias_sigma_mps2, 0.030 * fsw::kStandardGravity_mps2, 1e-12);
  EXPECT_NEAR(f.app.init_att_sigma_rad.z(), 5.0 * fsw::kDegToRad, 1e-15);
  EXPECT_DOUBLE_EQ(f.app.min_init_speed_mps, 3.0);
  EXPECT_EQ(f.app.pvt_max_quality, 2);
  ASSERT_TRUE(f.diagnosis_prior[static_cast<std::size_t>(fsw::Effect::kImuGnssTimeOffset)].has_value());
  EXPECT_DOUBLE_EQ(*f.diagnosis_prior[static_cast<std::size_t>(fsw::Effect::kImuGnssTimeOffset)], 0.2);
  EXPECT_FALSE(f.diagnosis_prior[static_cast<std::size_t>(fsw::Effect::kTroposphericDelay)].has_value());
  ASSERT_TRUE(f.outage_length_s.has_value());
  EXPECT_DOUBLE_EQ(*f.outage_length_s, 15.0);
}

TEST(FlightConfigSchema, KeysNotSetKeepTheBase) {
  cfg::FlightConfig f = defaults();
  const cfg::FlightConfigResult r = cfg::parse_flight_config_text("[gnss]\nsource = \"raw\"\n", "t.toml", f);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(f.gnss_source, cfg::GnssSource::kRaw);
  EXPECT_DOUBLE_EQ(f.app.exec.ekf.arw_rad_per_rts, 2e-7);
  EXPECT_EQ(f.app.exec.frames_per_ekf, 200);
}

TEST(FlightConfigSchema, ChannelErrorStatesAreConfigurable) {
  cfg::FlightConfig f = defaults();
  EXPECT_DOUBLE_EQ(f.app.exec.ekf.range_gm_sigma_m, 8.0);  // the simulated receiver's
  const cfg::FlightConfigResult r = cfg::parse_flight_config_text(
      "[gnss]\nrange_error_sigma_m = 0.5\nrange_error_tau_s = 30.0\nrange_rate_error_sigma_mps = 0.05\n"
      "range_rate_error_tau_s = 5.0\n",
      "t.toml", f);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_DOUBLE_EQ(f.app.exec.ekf.range_gm_sigma_m, 0.5);
  EXPECT_DOUBLE_EQ(f.app.exec.ekf.range_gm_tau_s, 30.0);
  EXPECT_DOUBLE_EQ(f.app.exec.ekf.range_rate_gm_sigma_mps, 0.05);
  EXPECT_DOUBLE_EQ(f.app.exec.ekf.range_rate_gm_tau_s, 5.0);
  cfg::FlightConfig g = defaults();
  const cfg::FlightConfigResult bad = cfg::parse_flight_config_text("[gnss]\nrange_error_tau_s = 0.0\n", "t.toml", g);
  EXPECT_FALSE(bad.ok);
  EXPECT_NE(bad.error.find("gnss.range_error_tau_s"), std::string::npos) << bad.error;
}

TEST(FlightConfigSchema, InitModeKeysSetTheirFieldsInSiUnits) {
  cfg::FlightConfig f = defaults();
  EXPECT_EQ(f.app.init_mode, fsw::InitMode::kTrack);  // the default
  const char* text =
      "[init]\nmode = \"velocity_matching\"\nalignment_s = 45.0\nstatic_max_speed_mps = 0.1\n"
      "static_max_rate_dev_dps = 0.05\nstatic_max_accel_dev_mps2 = 0.2\nvm_min_s = 1.5\nvm_max_s = 12.0\n"
      "vm_max_heading_sigma_deg = 4.0\nvm_rest_gyro_bias = false\nvm_rest_min_s = 2.0\n";
  const cfg::FlightConfigResult r = cfg::parse_flight_config_text(text, "t.toml", f);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(f.app.init_mode, fsw::InitMode::kVelocityMatching);
  EXPECT_DOUBLE_EQ(f.app.alignment_s, 45.0);
  EXPECT_DOUBLE_EQ(f.app.static_max_speed_mps, 0.1);
  EXPECT_NEAR(f.app.static_max_rate_dev_radps, 0.05 * fsw::kDegToRad, 1e-15);
  EXPECT_DOUBLE_EQ(f.app.static_max_accel_dev_mps2, 0.2);
  EXPECT_DOUBLE_EQ(f.app.vm_min_s, 1.5);
  EXPECT_DOUBLE_EQ(f.app.vm_max_s, 12.0);
  EXPECT_NEAR(f.app.vm_max_heading_sigma_rad, 4.0 * fsw::kDegToRad, 1e-15);
  EXPECT_FALSE(f.app.vm_rest_gyro_bias);
  EXPECT_DOUBLE_EQ(f.app.vm_rest_min_s, 2.0);
  fsw::FlightApp<fsw::Layout15Full> app;
  EXPECT_EQ(app.init(f.app), fsw::Status::kOk);
  for (const auto& [name, mode] : {std::pair<const char*, fsw::InitMode>{"track", fsw::InitMode::kTrack},
                                   {"static", fsw::InitMode::kStatic}}) {
    cfg::FlightConfig g = defaults();
    ASSERT_TRUE(cfg::parse_flight_config_text(std::string("[init]\nmode = \"") + name + "\"\n", "t.toml", g).ok);
    EXPECT_EQ(g.app.init_mode, mode);
    EXPECT_STREQ(fsw::to_string(mode), name);
  }
}

TEST(FlightConfigSchema, BrokenFilesNameTheKeyAndPositionAndChangeNothing) {
  struct Case {
    const char* text;
    const char* error;
  };
  const Case cases[] = {
      {"[imu]\narw = 1.0\n", "t.toml:2:1: unknown key 'imu.arw'"},
      {"[gnss]\nsource = \"loose\"\n", "t.toml:2:10: 'gnss.source' must be \"raw\" or \"pvt\" (got \"loose\")"},
      {"[imu]\narw_deg_per_rthr = -1.0\n", "'imu.arw_deg_per_rthr' must be a finite number >= 0"},
      {"[executive]\nnav_rate_hz = 100.0\nekf_rate_hz = 3.0\n", "must divide 'executive.nav_rate_hz' (100)"},
      {"[mounting]\nlever_arm_b_m = [0.1, 0.2]\n", "'mounting.lever_arm_b_m' must be an array of 3 numbers"},
      {"[diagnosis.prior]\nwheel_slip = 1.0\n", "unknown effect 'diagnosis.prior.wheel_slip'"},
      {"[init]\nlevelling_samples = 2000\n", "'init.levelling_samples' must be an integer in [1, 1024]"},
      {"imu = 3\n", "'imu' must be a table"},
      {"[init]\nmode = \"gyrocompass\"\n",
       "t.toml:2:8: 'init.mode' must be \"track\", \"static\" or \"velocity_matching\" (got \"gyrocompass\")"},
      {"[init]\nmode = 2\n", "t.toml:2:8: 'init.mode' must be"},
      {"[init]\nalignment_s = 0.0\n", "t.toml:2:15: 'init.alignment_s' must be"},
      {"[init]\nstatic_max_rate_dev_dps = -0.1\n", "'init.static_max_rate_dev_dps' must be"},
      {"[init]\nvm_rest_gyro_bias = 1\n", "'init.vm_rest_gyro_bias' must be true or false"},
      {"[imu\n", "t.toml:1:"},
  };
  for (const Case& c : cases) {
    cfg::FlightConfig f = defaults();
    const cfg::FlightConfigResult r = cfg::parse_flight_config_text(c.text, "t.toml", f);
    EXPECT_FALSE(r.ok) << c.text;
    EXPECT_NE(r.error.find(c.error), std::string::npos) << c.text << " -> " << r.error;
    EXPECT_DOUBLE_EQ(f.app.exec.ekf.arw_rad_per_rts, 2e-7);
    EXPECT_EQ(f.gnss_source, cfg::GnssSource::kRaw);
  }
  cfg::FlightConfig f = defaults();
  const cfg::FlightConfigResult r = cfg::parse_flight_config_file("/nonexistent/x.toml", f);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("cannot open flight configuration"), std::string::npos);
}
