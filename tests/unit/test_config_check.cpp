// The one rule table of the flight configuration (fsw/config_check.hpp) and its wording at load
// (cfg::validate, cfg/flight_config.hpp): each rule refuses its value, FlightApp::init refuses the
// same configurations (the table is what it checks), and the refusal names the file, the TOML key,
// the value in the file's unit and the rule.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <memory>
#include <string>

#include "cfg/flight_config.hpp"
#include "fsw/config_check.hpp"
#include "fsw/flight_app.hpp"

namespace {

using F = fsw::ConfigField;
using R = fsw::ConfigRule;

struct Case {
  const char* what;
  std::function<void(fsw::FlightAppConfig&)> change;
  F field;
  R rule;
  const char* message;  ///< what validate() says after "t.toml: "
};

const double kNaN = std::nan("");

std::vector<Case> cases() {
  return {
      {"latency not below the EKF step", [](auto& c) { c.exec.nav_rate_hz = 50.0, c.exec.frames_per_ekf = 10; }, F::kEkfLatencyFrames,
       R::kBelow, "executive.ekf_latency_frames = 10 must be below the 10 frames per EKF step (nav_rate_hz 50 / ekf_rate_hz 5)"},
      {"latency 0", [](auto& c) { c.exec.ekf_latency_frames = 0; }, F::kEkfLatencyFrames, R::kAtLeast,
       "executive.ekf_latency_frames = 0 must be at least 1"},
      {"EKF faster than navigation", [](auto& c) { c.exec.frames_per_ekf = 0; }, F::kFramesPerEkf, R::kAtLeast,
       "executive.ekf_rate_hz gives 0 navigation frames per EKF step"},
      {"no IMU samples per frame", [](auto& c) { c.exec.imu_samples_per_frame = 0; }, F::kImuSamplesPerFrame, R::kAtLeast,
       "executive.imu_samples_per_frame = 0 must be at least 1"},
      {"more IMU samples than the frame buffer",
       [](auto& c) { c.exec.imu_samples_per_frame = fsw::FrameBuilder::kMaxSamplesPerFrame + 1; }, F::kImuSamplesPerFrame,
       R::kAtMost, "must be at most"},
      {"navigation rate NaN", [](auto& c) { c.exec.nav_rate_hz = kNaN; }, F::kNavRate, R::kFinite,
       "executive.nav_rate_hz = nan must be a finite number"},
      {"negative GNSS wait", [](auto& c) { c.exec.gnss_wait_frames = -10; }, F::kGnssWaitFrames, R::kNonNegative,
       "executive.gnss_wait_s = -0.05 must not be negative"},
      {"frame budget 0", [](auto& c) { c.exec.frame_budget_s = 0.0; }, F::kFrameBudget, R::kPositive,
       "executive.frame_budget_s = 0 must be greater than 0"},
      {"NIS window beyond the buffer", [](auto& c) { c.exec.ekf.nis_window = fsw::kMaxNisWindow + 1; }, F::kNisWindow,
       R::kAtMost, "health.nis_window_epochs = 65 must be at most 64 (the flight software's NIS window)"},
      {"levelling beyond the buffer", [](auto& c) { c.levelling_samples = fsw::kMaxLevellingSamples + 1; },
       F::kLevellingSamples, R::kAtMost, "init.levelling_samples = 1025 must be at most 1024"},
      {"three satellites", [](auto& c) { c.min_satellites_for_init = 3; }, F::kMinSatellitesForInit, R::kAtLeast,
       "init.min_satellites = 3 must be at least 4"},
      {"velocity-matching window", [](auto& c) { c.vm_min_s = 5.0, c.vm_max_s = 4.0; }, F::kVmMax, R::kAbove,
       "init.vm_max_s = 4 must be greater than 5 (init.vm_min_s)"},
      {"heading sigma in degrees", [](auto& c) { c.init_att_sigma_rad.z() = -1.0 * fsw::kDegToRad; }, F::kInitHeadingSigma,
       R::kPositive, "init.heading_sigma_deg = -1 must be greater than 0"},
      {"unknown mode", [](auto& c) { c.init_mode = static_cast<fsw::InitMode>(7); }, F::kInitMode, R::kKnown,
       "init.mode = 7 must be"},
      {"gyro bias sigma in deg/h", [](auto& c) { c.exec.ekf.gyro_bias_sigma_radps = -2.0 * fsw::kDegPerHourToRadps; },
       F::kGyroBiasSigma, R::kNonNegative, "imu.gyro_bias_sigma_degph = -2 must not be negative"},
      {"ARW in rad/sqrt(s)", [](auto& c) { c.exec.ekf.arw_rad_per_rts = kNaN; }, F::kArw, R::kFinite,
       "imu.arw_rad_per_rts = nan must be a finite number"},
      {"pseudorange sigma 0", [](auto& c) { c.exec.ekf.pseudorange_sigma_m = 0.0; }, F::kPseudorangeSigma, R::kPositive,
       "gnss.pseudorange_sigma_m = 0 must be greater than 0"},
      {"range error tau 0", [](auto& c) { c.exec.ekf.range_gm_tau_s = 0.0; }, F::kRangeGmTau, R::kPositive,
       "gnss.range_error_tau_s = 0 must be greater than 0"},
      {"lever arm NaN", [](auto& c) { c.exec.ekf.lever_arm_b_m.y() = kNaN; }, F::kLeverArmY, R::kFinite,
       "mounting.lever_arm_b_m[1] = nan must be a finite number"},
      {"substeps 0", [](auto& c) { c.exec.ekf.propagation_substep_frames = 0; }, F::kPropagationSubstepFrames, R::kAtLeast,
       "executive.propagation_substep_frames = 0 must be at least 1"},
      {"runaway negative", [](auto& c) { c.exec.ekf.runaway_epochs = -1; }, F::kRunawayEpochs, R::kNonNegative,
       "health.runaway_epochs = -1 must not be negative"},
      {"an extension block without a key", [](auto& c) { c.exec.ekf.tropo_scale_sigma = -1.0; }, F::kTropoScaleSigma,
       R::kNonNegative, "exec.ekf.tropo_scale_sigma (no file key sets it) = -1 must not be negative"},
      {"PVT quality 0", [](auto& c) { c.pvt_max_quality = 0; }, F::kPvtMaxQuality, R::kAtLeast,
       "gnss.pvt_max_quality = 0 must be at least 1"},
      {"alignment infinite", [](auto& c) { c.alignment_s = INFINITY; }, F::kAlignment, R::kFinite,
       "init.alignment_s = inf must be a finite number"},
  };
}

cfg::FlightConfig from_file() {
  cfg::FlightConfig f;
  f.files = {"t.toml"};
  return f;
}

}  // namespace

TEST(ConfigCheck, TheDefaultsPass) {
  EXPECT_TRUE(fsw::check_config(fsw::FlightAppConfig{}).ok());
  EXPECT_TRUE(cfg::validate(from_file()).ok);
}

TEST(ConfigCheck, EachRuleRefusesItsValueWithFileKeyValueAndRule) {
  auto app = std::make_unique<fsw::FlightApp<fsw::Layout24Full>>();
  for (const Case& c : cases()) {
    cfg::FlightConfig f = from_file();
    c.change(f.app);
    const fsw::ConfigCheck k = fsw::check_config(f.app);
    EXPECT_EQ(k.status, fsw::Status::kBadConfig) << c.what;
    EXPECT_EQ(k.field, c.field) << c.what << ": " << fsw::to_string(k.field);
    EXPECT_EQ(k.rule, c.rule) << c.what << ": " << fsw::to_string(k.rule);
    // FlightApp::init applies the same table: the configuration is refused at init, not later.
    EXPECT_EQ(app->init(f.app), fsw::Status::kBadConfig) << c.what;
    const cfg::FlightConfigResult r = cfg::validate(f);
    EXPECT_FALSE(r.ok) << c.what;
    EXPECT_EQ(r.error.rfind("t.toml: ", 0), 0u) << r.error;
    EXPECT_NE(r.error.find(c.message), std::string::npos) << c.what << "\n  got: " << r.error;
  }
}

TEST(ConfigCheck, TheExecutiveAndTheEkfApplyTheirPartOfTheTable) {
  fsw::ExecutiveConfig x;
  EXPECT_TRUE(fsw::check_config(x).ok());
  x.ekf_latency_frames = x.frames_per_ekf;
  EXPECT_EQ(fsw::check_config(x).field, F::kEkfLatencyFrames);
  auto exec = std::make_unique<fsw::Executive<fsw::Layout15>>();
  EXPECT_EQ(exec->init(x, fsw::NavState{}), fsw::Status::kBadConfig);
  fsw::EkfConfig e;
  e.pos_sigma_m = -1.0;  // the EKF's own initial sigma: FlightApp replaces it by init.pos_sigma_m
  EXPECT_EQ(fsw::check_config(e).field, F::kPosSigma);
  auto ekf = std::make_unique<fsw::Ekf<fsw::Layout15>>();
  EXPECT_EQ(ekf->init(e), fsw::Status::kBadConfig);
  fsw::FlightAppConfig a;
  a.exec.ekf.pos_sigma_m = -1.0;
  EXPECT_TRUE(fsw::check_config(a).ok());
}

// The case: a data set's file at 50 Hz navigation and a 5 Hz EKF leaves the shipped
// latency of 10 frames, which is not below the 10 frames of an EKF step. Refused at load, naming
// the data set's file, the key, the file that set it, and the rule.
TEST(ConfigCheck, AParsedFileIsRefusedAtLoadNamingTheKeyAndWhereItWasSet) {
  cfg::FlightConfig f;
  ASSERT_TRUE(cfg::parse_flight_config_text("[executive]\nekf_latency_frames = 10\n", "default.toml", f).ok);
  ASSERT_TRUE(cfg::parse_flight_config_text("[executive]\nnav_rate_hz = 50.0\nekf_rate_hz = 5.0\n", "my.toml", f).ok);
  const cfg::FlightConfigResult r = cfg::validate(f);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.error,
            "my.toml: executive.ekf_latency_frames = 10 (set in default.toml) must be below the 10 frames per EKF step "
            "(nav_rate_hz 50 / ekf_rate_hz 5)");
  // A key given in its other unit is quoted in that unit.
  cfg::FlightConfig g;
  ASSERT_TRUE(cfg::parse_flight_config_text("[imu]\narw_deg_per_rthr = 0.5\n", "g.toml", g).ok);
  g.app.exec.ekf.arw_rad_per_rts = -g.app.exec.ekf.arw_rad_per_rts;
  EXPECT_NE(cfg::validate(g).error.find("g.toml: imu.arw_deg_per_rthr = -0.5 must not be negative"), std::string::npos)
      << cfg::validate(g).error;
}

TEST(ConfigCheck, AnOverlaidConfigurationIsRefusedNamingTheOverlay) {
  fsw::FlightAppConfig a;
  a.exec.frames_per_ekf = 5;  // e.g. a 40 Hz GPS on 200 Hz navigation
  const cfg::FlightConfigResult r = cfg::validate(a, from_file(), "the Monte Carlo's scenario overlay (scenario x)");
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.error,
            "the Monte Carlo's scenario overlay (scenario x) on t.toml: executive.ekf_latency_frames = 10 must be "
            "below the 5 frames per EKF step (nav_rate_hz 200 / ekf_rate_hz 40)");
}

TEST(ConfigCheck, EveryFieldHasAName) {
  for (int i = 1; i < static_cast<int>(F::kCount); ++i) EXPECT_STRNE(fsw::to_string(static_cast<F>(i)), "") << i;
}
