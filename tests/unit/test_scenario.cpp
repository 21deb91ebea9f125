// Scenario TOML parser (sim/src/scenario.cpp) and effect helpers (sim/src/effects.cpp).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "fsw/frames.hpp"
#include "sim/effects.hpp"
#include "cfg/data_dir.hpp"
#include "sim/scenario.hpp"
#include "test_util.hpp"

namespace {

using fsw::Effect;
using sim::Scenario;

void expect_same(const Scenario& a, const Scenario& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.duration_s, b.duration_s);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(a.start.lat_deg, b.start.lat_deg);
  EXPECT_EQ(a.start.lon_deg, b.start.lon_deg);
  EXPECT_EQ(a.start.alt_m, b.start.alt_m);
  EXPECT_EQ(a.start.speed_mps, b.start.speed_mps);
  EXPECT_EQ(a.start.heading_deg, b.start.heading_deg);
  EXPECT_EQ(a.start.pitch_deg, b.start.pitch_deg);
  ASSERT_EQ(a.segments.size(), b.segments.size());
  for (std::size_t i = 0; i < a.segments.size(); ++i) {
    SCOPED_TRACE("segment " + std::to_string(i));
    EXPECT_EQ(a.segments[i].type, b.segments[i].type);
    EXPECT_EQ(a.segments[i].duration_s, b.segments[i].duration_s);
    EXPECT_EQ(a.segments[i].direction, b.segments[i].direction);
    EXPECT_EQ(a.segments[i].bank_deg, b.segments[i].bank_deg);
    EXPECT_EQ(a.segments[i].heading_change_deg, b.segments[i].heading_change_deg);
    EXPECT_EQ(a.segments[i].roll_time_s, b.segments[i].roll_time_s);
  }
  EXPECT_EQ(a.repeat_from, b.repeat_from);
  EXPECT_EQ(a.imu.rate_hz, b.imu.rate_hz);
  EXPECT_EQ(a.imu.errors, b.imu.errors);
  const sim::ImuErrorSigmas& sa = a.imu.sigmas;
  const sim::ImuErrorSigmas& sb = b.imu.sigmas;
  EXPECT_EQ(sa.accel_bias_ug, sb.accel_bias_ug);
  EXPECT_EQ(sa.accel_scale_factor_ppm, sb.accel_scale_factor_ppm);
  EXPECT_EQ(sa.accel_misalignment_arcsec, sb.accel_misalignment_arcsec);
  EXPECT_EQ(sa.gyro_bias_degph, sb.gyro_bias_degph);
  EXPECT_EQ(sa.gyro_scale_factor_ppm, sb.gyro_scale_factor_ppm);
  EXPECT_EQ(sa.gyro_misalignment_arcsec, sb.gyro_misalignment_arcsec);
  EXPECT_EQ(sa.gyro_arw_deg_per_rthr, sb.gyro_arw_deg_per_rthr);
  EXPECT_EQ(sa.accel_vrw_ug_per_rthz, sb.accel_vrw_ug_per_rthz);
  EXPECT_EQ(sa.gyro_bias_instability_degph, sb.gyro_bias_instability_degph);
  EXPECT_EQ(sa.accel_bias_instability_ug, sb.accel_bias_instability_ug);
  EXPECT_EQ(sa.bias_instability_tau_s, sb.bias_instability_tau_s);
  EXPECT_EQ(a.effects.value, b.effects.value);
  const sim::GpsConfig& ga = a.gps;
  const sim::GpsConfig& gb = b.gps;
  EXPECT_EQ(ga.almanac, gb.almanac);
  EXPECT_EQ(ga.start_week, gb.start_week);
  EXPECT_EQ(ga.start_tow_s, gb.start_tow_s);
  EXPECT_EQ(ga.rate_hz, gb.rate_hz);
  EXPECT_EQ(ga.elevation_mask_deg, gb.elevation_mask_deg);
  EXPECT_EQ(ga.pseudorange_gm_sigma_m, gb.pseudorange_gm_sigma_m);
  EXPECT_EQ(ga.pseudorange_gm_tau_s, gb.pseudorange_gm_tau_s);
  EXPECT_EQ(ga.pseudorange_rate_gm_sigma_mps, gb.pseudorange_rate_gm_sigma_mps);
  EXPECT_EQ(ga.pseudorange_rate_gm_tau_s, gb.pseudorange_rate_gm_tau_s);
  EXPECT_EQ(ga.pseudorange_white_sigma_m, gb.pseudorange_white_sigma_m);
  EXPECT_EQ(ga.pseudorange_rate_white_sigma_mps, gb.pseudorange_rate_white_sigma_mps);
  EXPECT_EQ(ga.clock_bias_sigma_m, gb.clock_bias_sigma_m);
  EXPECT_EQ(ga.clock_drift_sigma_mps, gb.clock_drift_sigma_mps);
  EXPECT_EQ(ga.clock_h0_s, gb.clock_h0_s);
  EXPECT_EQ(ga.clock_h_minus2_per_s, gb.clock_h_minus2_per_s);
  EXPECT_EQ(ga.max_channels, gb.max_channels);
}

Scenario parse_ok(const std::string& text) {
  const sim::ScenarioParseResult r = sim::parse_scenario_text(text, "test.toml");
  EXPECT_TRUE(r.ok()) << r.error;
  return r.scenario.value_or(Scenario{});
}

/// Parses text expecting a rejection at `line` whose message names `path`; returns the message.
std::string expect_rejected(const std::string& text, int line, const std::string& path) {
  const sim::ScenarioParseResult r = sim::parse_scenario_text(text, "test.toml");
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.error.rfind("test.toml:" + std::to_string(line) + ":", 0), 0u) << r.error;
  EXPECT_NE(r.error.find(path), std::string::npos) << r.error;
  return r.error;
}

using test_util::contains;

TEST(ScenarioDefaults, DefaultSegmentsAreTheBankToTurnPattern) {
  const std::vector<sim::Segment> segs = Scenario::default_segments();
  ASSERT_EQ(segs.size(), 5u);
  EXPECT_EQ(segs[0].type, sim::SegmentType::kStraight);
  EXPECT_EQ(segs[0].duration_s, 60.0);
  EXPECT_EQ(segs[2].type, sim::SegmentType::kStraight);
  EXPECT_EQ(segs[2].duration_s, 30.0);
  EXPECT_EQ(segs[4].type, sim::SegmentType::kStraight);
  EXPECT_EQ(segs[4].duration_s, 30.0);
  for (std::size_t i : {1u, 3u}) {
    EXPECT_EQ(segs[i].type, sim::SegmentType::kTurn);
    EXPECT_EQ(segs[i].bank_deg, 60.0);
    EXPECT_EQ(segs[i].heading_change_deg, 180.0);
    EXPECT_EQ(segs[i].roll_time_s, 5.0);
  }
  EXPECT_EQ(segs[1].direction, sim::TurnDirection::kRight);
  EXPECT_EQ(segs[3].direction, sim::TurnDirection::kLeft);
  EXPECT_EQ(Scenario{}.repeat_from, std::optional<std::size_t>{1});
}

TEST(ScenarioParse, ShippedFileEqualsDefaults) {
  const sim::ScenarioParseResult r = sim::parse_scenario_file(cfg::data_file("scenarios/bank_to_turn.toml"));
  ASSERT_TRUE(r.ok()) << r.error;
  expect_same(*r.scenario, Scenario{});
}

TEST(ScenarioParse, EmptyTextGivesDefaults) {
  expect_same(parse_ok(""), Scenario{});
  expect_same(parse_ok("# only a comment\n[start]\n[imu]\n[effects]\n"), Scenario{});
}

TEST(ScenarioParse, CustomScenarioRoundTrips) {
  const Scenario s = parse_ok(R"(
name = "custom"
duration_s = 600
seed = 42
[start]
lat_deg = -12.5
lon_deg = 359.5
alt_m = -100
speed_mps = 80.0
heading_deg = -90
pitch_deg = 2.5
[trajectory]
repeat_from = 0
[[trajectory.segment]]
type = "turn"
direction = "left"
bank_deg = 30
heading_change_deg = 720.0
roll_time_s = 2.0
[[trajectory.segment]]
type = "straight"
duration_s = 10.5
[imu]
rate_hz = 400
errors = "baseline"
accel_bias_ug = 50
accel_scale_factor_ppm = 1.0
accel_misalignment_arcsec = 2.0
gyro_bias_degph = 0.5
gyro_scale_factor_ppm = 3.0
gyro_misalignment_arcsec = 4.0
gyro_arw_deg_per_rthr = 0.1
accel_vrw_ug_per_rthz = 25.0
gyro_bias_instability_degph = 0.02
accel_bias_instability_ug = 10.0
bias_instability_tau_s = 100
[effects]
gyro_misalignment = { xy = 20.0, zy = -3 }
antenna_lever_arm = { x = 1.0, z = -0.5 }
imu_gnss_time_offset = 0.01
tropospheric_delay = 1
)");
  Scenario want;
  want.name = "custom";
  want.duration_s = 600.0;
  want.seed = 42;
  want.start = {-12.5, 359.5, -100.0, 80.0, -90.0, 2.5};
  sim::Segment turn;
  turn.type = sim::SegmentType::kTurn;
  turn.direction = sim::TurnDirection::kLeft;
  turn.bank_deg = 30.0;
  turn.heading_change_deg = 720.0;
  turn.roll_time_s = 2.0;
  sim::Segment straight;
  straight.duration_s = 10.5;
  want.segments = {turn, straight};
  want.repeat_from = 0;
  want.imu.rate_hz = 400;
  want.imu.errors = sim::ImuErrorSet::kBaseline;
  want.imu.sigmas = {50.0, 1.0, 2.0, 0.5, 3.0, 4.0, 0.1, 25.0, 0.02, 10.0, 100.0};
  want.effects.set(Effect::kGyroMisalignment, 0, 20.0);
  want.effects.set(Effect::kGyroMisalignment, 5, -3.0);
  want.effects.set(Effect::kAntennaLeverArm, 0, 1.0);
  want.effects.set(Effect::kAntennaLeverArm, 2, -0.5);
  want.effects.set(Effect::kImuGnssTimeOffset, 0, 0.01);
  want.effects.set(Effect::kTroposphericDelay, 0, 1.0);
  expect_same(s, want);
}

TEST(ScenarioParse, GpsTableRoundTrips) {
  const Scenario s = parse_ok(R"(
[gps]
almanac = "/data/other.alm"
start_week = 2300
start_tow_s = 0
rate_hz = 5
elevation_mask_deg = 5.5
pseudorange_gm_sigma_m = 3.0
pseudorange_gm_tau_s = 120
pseudorange_rate_gm_sigma_mps = 0.05
pseudorange_rate_gm_tau_s = 2.5
pseudorange_white_sigma_m = 0.5
pseudorange_rate_white_sigma_mps = 0.01
clock_bias_sigma_m = 0
clock_drift_sigma_mps = 0.1
clock_h0_s = 9.4e-20
clock_h_minus2_per_s = 0
max_channels = 16
)");
  Scenario want;
  want.gps = {.almanac = "/data/other.alm", .start_week = 2300, .start_tow_s = 0.0, .rate_hz = 5.0,
              .elevation_mask_deg = 5.5, .pseudorange_gm_sigma_m = 3.0, .pseudorange_gm_tau_s = 120.0,
              .pseudorange_rate_gm_sigma_mps = 0.05, .pseudorange_rate_gm_tau_s = 2.5,
              .pseudorange_white_sigma_m = 0.5, .pseudorange_rate_white_sigma_mps = 0.01, .clock_bias_sigma_m = 0.0,
              .clock_drift_sigma_mps = 0.1, .clock_h0_s = 9.4e-20, .clock_h_minus2_per_s = 0.0, .max_channels = 16};
  expect_same(s, want);
}

TEST(ScenarioParse, GpsDefaultAlmanacIsTheShippedFile) {
  const Scenario s;
  EXPECT_EQ(s.gps.almanac, "");
  EXPECT_EQ(sim::almanac_path(s.gps), cfg::data_file("almanac/yuma-week431.alm"));
  EXPECT_EQ(sim::default_almanac_path(), sim::almanac_path(s.gps));
  sim::GpsConfig other;
  other.almanac = "/x/y.alm";
  EXPECT_EQ(sim::almanac_path(other), "/x/y.alm");
  // Text parsing keeps a relative path as written.
  EXPECT_EQ(parse_ok("[gps]\nalmanac = \"alm/y.alm\"\n").gps.almanac, "alm/y.alm");
}

TEST(ScenarioParse, GpsAlmanacRelativeToScenarioFile) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(testing::TempDir()) / "sdins_scenario_almanac_test" / "scenarios";
  fs::create_directories(dir);
  const fs::path file = dir / "s.toml";
  {
    std::ofstream out(file);
    out << "[gps]\nalmanac = \"../alm/week.alm\"\n";
  }
  sim::ScenarioParseResult r = sim::parse_scenario_file(file.string());
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(r.scenario->gps.almanac, (fs::absolute(dir).parent_path() / "alm" / "week.alm").lexically_normal().string());
  {
    std::ofstream out(file);
    out << "[gps]\nalmanac = \"/abs/week.alm\"\n";
  }
  r = sim::parse_scenario_file(file.string());
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(r.scenario->gps.almanac, "/abs/week.alm");
  fs::remove_all(dir.parent_path());
}

TEST(ScenarioParse, SegmentsWithoutRepeatFromDoNotRepeat) {
  const Scenario s = parse_ok("[[trajectory.segment]]\ntype = \"straight\"\n");
  ASSERT_EQ(s.segments.size(), 1u);
  EXPECT_EQ(s.segments[0].duration_s, sim::Segment{}.duration_s);
  EXPECT_FALSE(s.repeat_from.has_value());
}

TEST(ScenarioParse, RepeatFromNoneAndDefaultSegments) {
  const Scenario none = parse_ok("[trajectory]\nrepeat_from = \"none\"\n");
  EXPECT_FALSE(none.repeat_from.has_value());
  EXPECT_EQ(none.segments.size(), Scenario::default_segments().size());
  EXPECT_EQ(parse_ok("[trajectory]\nrepeat_from = 4\n").repeat_from, std::optional<std::size_t>{4});
}

TEST(ScenarioReject, UnknownTopLevelKey) {
  expect_rejected("name = \"x\"\n\nduration = 5.0\n", 3, "unknown key 'duration'");
}

TEST(ScenarioReject, UnknownKeyInStart) {
  expect_rejected("[start]\nlat_deg = 1.0\nlatitude = 2.0\n", 3, "unknown key 'start.latitude'");
}

TEST(ScenarioReject, MisspelledKeyInThirdSegment) {
  expect_rejected(R"([[trajectory.segment]]
type = "straight"
[[trajectory.segment]]
type = "straight"
[[trajectory.segment]]
type = "turn"
bnak_deg = 30.0
)",
                  7, "unknown key 'trajectory.segment[2].bnak_deg'");
}

TEST(ScenarioReject, StringForNumber) {
  const std::string e = expect_rejected("[start]\nalt_m = \"high\"\n", 2, "'start.alt_m'");
  EXPECT_TRUE(contains(e, "must be a number in [-400, 30000]")) << e;
}

TEST(ScenarioReject, BankOutOfRange) {
  const std::string e = expect_rejected("[[trajectory.segment]]\ntype = \"turn\"\nbank_deg = 85\n", 3,
                                        "'trajectory.segment[0].bank_deg'");
  EXPECT_TRUE(contains(e, "must be a number in (0, 80]")) << e;
}

TEST(ScenarioReject, NanAndInfValues) {
  expect_rejected("duration_s = nan\n", 1, "'duration_s'");
  expect_rejected("[imu]\naccel_bias_ug = inf\n", 2, "'imu.accel_bias_ug'");
  expect_rejected("[effects]\nimu_gnss_time_offset = nan\n", 2, "'effects.imu_gnss_time_offset'");
}

TEST(ScenarioReject, TurnKeyInStraightSegment) {
  const std::string e =
      expect_rejected("[[trajectory.segment]]\ntype = \"straight\"\nbank_deg = 30\n", 3, "'trajectory.segment[0].bank_deg'");
  EXPECT_TRUE(contains(e, "not allowed for a straight segment")) << e;
  expect_rejected("[[trajectory.segment]]\ntype = \"turn\"\nduration_s = 3\n", 3, "'trajectory.segment[0].duration_s'");
}

TEST(ScenarioReject, MissingSegmentType) {
  expect_rejected("[[trajectory.segment]]\ntype = \"straight\"\n\n[[trajectory.segment]]\nbank_deg = 30\n", 4,
                  "'trajectory.segment[1].type' is required");
}

TEST(ScenarioReject, BadChoices) {
  const std::string e = expect_rejected(
      "[[trajectory.segment]]\ntype = \"turn\"\ndirection = \"up\"\n", 3, "'trajectory.segment[0].direction'");
  EXPECT_TRUE(contains(e, "must be \"left\" or \"right\"")) << e;
  expect_rejected("[[trajectory.segment]]\ntype = \"loop\"\n", 2, "'trajectory.segment[0].type'");
  expect_rejected("[imu]\nerrors = \"all\"\n", 2, "'imu.errors'");
}

TEST(ScenarioReject, RepeatFromOutOfRange) {
  const std::string e = expect_rejected(
      "[trajectory]\nrepeat_from = 2\n[[trajectory.segment]]\ntype = \"straight\"\n[[trajectory.segment]]\ntype = "
      "\"straight\"\n",
      2, "'trajectory.repeat_from'");
  EXPECT_TRUE(contains(e, "[0, 1]")) << e;
  expect_rejected("[trajectory]\nrepeat_from = 5\n", 2, "'trajectory.repeat_from'");  // 5 default segments
  expect_rejected("[trajectory]\nrepeat_from = -1\n", 2, "'trajectory.repeat_from'");
}

TEST(ScenarioReject, OtherInvalidValues) {
  expect_rejected("[imu]\nrate_hz = 1100\n", 2, "'imu.rate_hz'");
  expect_rejected("[imu]\nrate_hz = 1000.0\n", 2, "'imu.rate_hz'");
  expect_rejected("seed = -1\n", 1, "'seed'");
  expect_rejected("[start]\nspeed_mps = 0\n", 2, "'start.speed_mps'");
  expect_rejected("[start]\nlon_deg = 360\n", 2, "'start.lon_deg'");
  expect_rejected("[imu]\nbias_instability_tau_s = 0\n", 2, "'imu.bias_instability_tau_s'");
  expect_rejected("start = 5\n", 1, "'start' must be a table");
  expect_rejected("[trajectory]\nsegment = []\n", 2, "'trajectory.segment' must not be empty");
}

TEST(ScenarioReject, GpsUnknownKey) {
  expect_rejected("[gps]\nrate_hz = 2\nelevation_mask = 5\n", 3, "unknown key 'gps.elevation_mask'");
}

TEST(ScenarioReject, GpsBadValues) {
  std::string e = expect_rejected("[gps]\n\nrate_hz = 25\n", 3, "'gps.rate_hz'");
  EXPECT_TRUE(contains(e, "must be a number in (0, 20]")) << e;
  expect_rejected("[gps]\nrate_hz = 0\n", 2, "'gps.rate_hz'");
  e = expect_rejected("[gps]\nmax_channels = 17\n", 2, "'gps.max_channels'");
  EXPECT_TRUE(contains(e, "must be an integer in [1, 16]")) << e;
  expect_rejected("[gps]\nmax_channels = 0\n", 2, "'gps.max_channels'");
  expect_rejected("[gps]\nmax_channels = 12.0\n", 2, "'gps.max_channels'");
  expect_rejected("[gps]\nstart_week = 1455.5\n", 2, "'gps.start_week'");
  expect_rejected("[gps]\nstart_week = -1\n", 2, "'gps.start_week'");
  expect_rejected("[gps]\nstart_tow_s = 604800\n", 2, "'gps.start_tow_s'");
  expect_rejected("[gps]\nstart_tow_s = -1\n", 2, "'gps.start_tow_s'");
  expect_rejected("[gps]\nelevation_mask_deg = 90\n", 2, "'gps.elevation_mask_deg'");
  expect_rejected("[gps]\nelevation_mask_deg = -5\n", 2, "'gps.elevation_mask_deg'");
  expect_rejected("[gps]\npseudorange_gm_sigma_m = -1\n", 2, "'gps.pseudorange_gm_sigma_m'");
  expect_rejected("[gps]\npseudorange_gm_tau_s = 0\n", 2, "'gps.pseudorange_gm_tau_s'");
  expect_rejected("[gps]\npseudorange_rate_gm_tau_s = -3\n", 2, "'gps.pseudorange_rate_gm_tau_s'");
  expect_rejected("[gps]\npseudorange_rate_white_sigma_mps = nan\n", 2, "'gps.pseudorange_rate_white_sigma_mps'");
  expect_rejected("[gps]\nclock_h0_s = -2e-19\n", 2, "'gps.clock_h0_s'");
  expect_rejected("[gps]\nclock_h_minus2_per_s = inf\n", 2, "'gps.clock_h_minus2_per_s'");
  // The keys without their unit were renamed; a file written for the old names fails naming the new one.
  expect_rejected("[gps]\nclock_h0 = 2e-19\n", 2, "'gps.clock_h0' was renamed to 'gps.clock_h0_s'");
  expect_rejected("[gps]\nclock_h_minus2 = 2e-20\n", 2, "'gps.clock_h_minus2' was renamed to 'gps.clock_h_minus2_per_s'");
  expect_rejected("[gps]\nclock_bias_sigma_m = \"30\"\n", 2, "'gps.clock_bias_sigma_m'");
  e = expect_rejected("[gps]\nalmanac = 5\n", 2, "'gps.almanac'");
  EXPECT_TRUE(contains(e, "must be a string")) << e;
  expect_rejected("gps = 1\n", 1, "'gps' must be a table");
}

TEST(ScenarioReject, UnknownEffect) {
  const std::string e = expect_rejected("[effects]\ngyro_misalignment = { xy = 1 }\ngyro_misalign = 3\n", 3,
                                        "'effects.gyro_misalign'");
  EXPECT_TRUE(contains(e, "unknown effect")) << e;
}

TEST(ScenarioReject, UnknownEffectComponent) {
  const std::string e =
      expect_rejected("[effects]\n\naccel_misalignment = { yx = 1, xy = 2 }\n", 3, "'effects.accel_misalignment.xy'");
  EXPECT_TRUE(contains(e, "unknown component")) << e;
  EXPECT_TRUE(contains(e, "yx, zx, zy")) << e;
}

TEST(ScenarioReject, EffectValueShape) {
  expect_rejected("[effects]\ngyro_misalignment = 20.0\n", 2, "'effects.gyro_misalignment' must be a table");
  expect_rejected("[effects]\nimu_gnss_time_offset = { x = 1 }\n", 2, "'effects.imu_gnss_time_offset' must be");
  expect_rejected("[effects.antenna_lever_arm]\nx = \"1\"\n", 2, "'effects.antenna_lever_arm.x'");
}

TEST(ScenarioReject, TomlSyntaxError) {
  const sim::ScenarioParseResult r = sim::parse_scenario_text("name = \"x\"\n[start]\nlat_deg = = 3\n", "bad.toml");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error.rfind("bad.toml:3:", 0), 0u) << r.error;
}

TEST(ScenarioReject, NonexistentFile) {
  const std::string path = cfg::data_file("scenarios/does_not_exist.toml");
  const sim::ScenarioParseResult r = sim::parse_scenario_file(path);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error, path + ": cannot open scenario file: No such file or directory");
}

TEST(EffectsLookup, NamesAndComponents) {
  EXPECT_EQ(sim::effect_from_name("gyro_misalignment"), Effect::kGyroMisalignment);
  EXPECT_EQ(sim::effect_from_name("ionospheric_delay"), Effect::kIonosphericDelay);
  EXPECT_FALSE(sim::effect_from_name("gyro").has_value());
  EXPECT_EQ(sim::component_from_name(Effect::kGyroMisalignment, "yz"), std::optional<std::size_t>{3});
  EXPECT_EQ(sim::component_from_name(Effect::kAccelMisalignment, "zy"), std::optional<std::size_t>{2});
  EXPECT_FALSE(sim::component_from_name(Effect::kAccelMisalignment, "xy").has_value());
  EXPECT_FALSE(sim::component_from_name(Effect::kAccelMisalignment, "").has_value());
  EXPECT_EQ(sim::component_from_name(Effect::kImuGnssTimeOffset, ""), std::optional<std::size_t>{0});
  EXPECT_FALSE(sim::component_from_name(Effect::kImuGnssTimeOffset, "x").has_value());
}

TEST(EffectsAssignment, SetsComponentAndScalar) {
  sim::EffectSet set;
  EXPECT_EQ(sim::apply_effect_assignment(set, "gyro_misalignment.yz=20"), "");
  EXPECT_EQ(sim::apply_effect_assignment(set, "imu_gnss_time_offset=0.02"), "");
  EXPECT_EQ(sim::apply_effect_assignment(set, "antenna_lever_arm.z = -1.5e-1"), "");
  EXPECT_EQ(set.get(Effect::kGyroMisalignment, 3), 20.0);
  EXPECT_EQ(set.get(Effect::kGyroMisalignment, 0), 0.0);
  EXPECT_EQ(set.get(Effect::kImuGnssTimeOffset), 0.02);
  EXPECT_EQ(set.get(Effect::kAntennaLeverArm, 2), -0.15);
}

TEST(EffectsAssignment, RejectsUnknownEffect) {
  sim::EffectSet set;
  const std::string e = sim::apply_effect_assignment(set, "gyro_misalign.xy=1");
  EXPECT_TRUE(contains(e, "unknown effect 'gyro_misalign'")) << e;
  EXPECT_TRUE(contains(e, "gyro_misalignment, accel_misalignment")) << e;
}

TEST(EffectsAssignment, RejectsUnknownComponent) {
  sim::EffectSet set;
  const std::string e = sim::apply_effect_assignment(set, "accel_misalignment.xy=1");
  EXPECT_TRUE(contains(e, "unknown component 'xy'")) << e;
  EXPECT_TRUE(contains(e, "yx, zx, zy")) << e;
}

TEST(EffectsAssignment, RejectsMissingComponent) {
  sim::EffectSet set;
  const std::string e = sim::apply_effect_assignment(set, "gyro_scale_factor=100");
  EXPECT_TRUE(contains(e, "needs a component")) << e;
  EXPECT_TRUE(contains(e, "x, y, z")) << e;
}

TEST(EffectsAssignment, RejectsComponentOnScalar) {
  sim::EffectSet set;
  const std::string e = sim::apply_effect_assignment(set, "imu_gnss_time_offset.x=0.01");
  EXPECT_TRUE(contains(e, "scalar")) << e;
}

TEST(EffectsAssignment, RejectsBadNumberAndSyntax) {
  sim::EffectSet set;
  for (const char* bad : {"gyro_misalignment.xy=abc", "gyro_misalignment.xy=", "gyro_misalignment.xy=1.5x",
                          "gyro_misalignment.xy=nan", "gyro_misalignment.xy=inf"}) {
    EXPECT_TRUE(contains(sim::apply_effect_assignment(set, bad), "bad number")) << bad;
  }
  EXPECT_TRUE(contains(sim::apply_effect_assignment(set, "gyro_misalignment.xy"), "NAME[.COMPONENT]=VALUE"));
  EXPECT_FALSE(set.on(Effect::kGyroMisalignment));
}

TEST(EffectsConversion, OnAndSi) {
  sim::EffectSet set;
  EXPECT_FALSE(set.on(Effect::kGyroMisalignment));
  set.set(Effect::kGyroMisalignment, 1, 20.0);
  EXPECT_TRUE(set.on(Effect::kGyroMisalignment));
  EXPECT_FALSE(set.on(Effect::kAccelMisalignment));
  EXPECT_NEAR(set.si(Effect::kGyroMisalignment, 1), 9.696e-5, 1e-8);
  set.set(Effect::kGyroScaleFactor, 0, 100.0);
  EXPECT_DOUBLE_EQ(set.si(Effect::kGyroScaleFactor, 0), 1e-4);
  set.set(Effect::kGyroGSensitivity, 2, 1.0);  // 1 deg/h/g
  EXPECT_NEAR(set.si(Effect::kGyroGSensitivity, 2), 4.8481368e-6 / 9.80665, 1e-13);
  set.set(Effect::kImuGnssTimeOffset, 0, 0.02);
  EXPECT_DOUBLE_EQ(set.si(Effect::kImuGnssTimeOffset), 0.02);
}

}  // namespace

TEST(ScenarioParse, ImuMountingIsReadAndWrittenOnlyWhenSet) {
  const Scenario s = parse_ok("[imu]\nmounting_rpy_deg = [1.5, -5, 90.0]\n");
  EXPECT_EQ(s.imu.mounting_rpy_deg, (std::array<double, 3>{1.5, -5.0, 90.0}));
  const sim::ScenarioWriteResult w = sim::write_scenario_toml(s);
  ASSERT_TRUE(w.ok()) << w.error;
  EXPECT_EQ(parse_ok(w.text).imu.mounting_rpy_deg, s.imu.mounting_rpy_deg);
  const sim::ScenarioWriteResult none = sim::write_scenario_toml(Scenario{});
  ASSERT_TRUE(none.ok()) << none.error;
  EXPECT_EQ(none.text.find("mounting"), std::string::npos);
}

TEST(ScenarioReject, ImuMountingOutOfRangeOrShape) {
  expect_rejected("[imu]\nmounting_rpy_deg = [0, 0]\n", 2, "'imu.mounting_rpy_deg' must be an array of 3 numbers");
  expect_rejected("[imu]\nmounting_rpy_deg = 90\n", 2, "'imu.mounting_rpy_deg' must be an array of 3 numbers");
  expect_rejected("[imu]\nmounting_rpy_deg = [0, 91, 0]\n", 2, "'imu.mounting_rpy_deg[1]' must be a number in [-90, 90]");
  expect_rejected("[imu]\nmounting_rpy_deg = [0, 0, 181]\n", 2, "'imu.mounting_rpy_deg[2]' must be a number in [-180, 180]");
  expect_rejected("[imu]\nmounting_rpy_deg = [0, 0, nan]\n", 2, "'imu.mounting_rpy_deg[2]'");
  expect_rejected("[imu]\nmounting_rpy_deg = [\"a\", 0, 0]\n", 2, "'imu.mounting_rpy_deg[0]'");
}
