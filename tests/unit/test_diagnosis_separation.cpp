// The manoeuvre that separates a confounded group (tools/diagnosis_separation.hpp) and what it
// needs from sim/: the scenario writer (write -> read gives the same scenario) and the flown flight
// with segments appended (sim::append_segments).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>

#include "cfg/data_dir.hpp"
#include "diagnosis_test_util.hpp"
#include "sim/effects.hpp"
#include "sim/scenario.hpp"
#include "sim/trajectory.hpp"
#include "tools/diagnosis.hpp"
#include "tools/diagnosis_separation.hpp"

namespace {

using sim::Scenario;
using sim::Segment;
using sim::SegmentType;
using diagnosis_test::kSanitized;

Scenario read_back(const Scenario& sc) {
  const sim::ScenarioWriteResult w = sim::write_scenario_toml(sc, "a test\nof two lines");
  EXPECT_TRUE(w.ok()) << w.error;
  const sim::ScenarioParseResult r = sim::parse_scenario_text(w.text, "written.toml");
  EXPECT_TRUE(r.ok()) << r.error << "\n" << w.text;
  return r.scenario.value_or(Scenario{});
}

TEST(ScenarioWriter, TheDefaultAndTheShippedFileReadBackEqual) {
  EXPECT_EQ(read_back(Scenario{}), Scenario{});
  const sim::ScenarioParseResult shipped = sim::parse_scenario_file(cfg::data_file("scenarios/bank_to_turn.toml"));
  ASSERT_TRUE(shipped.ok()) << shipped.error;
  EXPECT_EQ(read_back(*shipped.scenario), *shipped.scenario);
}

TEST(ScenarioWriter, EverySegmentTypeAndEveryKeyReadsBackEqual) {
  const sim::ScenarioParseResult p = sim::parse_scenario_text(R"(
name = "every \"key\" \\ once"
duration_s = 1234.5
seed = 9223372036854775807
[start]
lat_deg = -33.25
lon_deg = 359.5
alt_m = 120.0
speed_mps = 61.7
heading_deg = -270.0
pitch_deg = 2.5
[trajectory]
repeat_from = 2
[[trajectory.segment]]
type = "straight"
duration_s = 0.1
[[trajectory.segment]]
type = "turn"
direction = "left"
bank_deg = 33.3
heading_change_deg = 720.0
roll_time_s = 3.0
[[trajectory.segment]]
type = "speed_change"
duration_s = 40.0
delta_speed_mps = -12.5
[[trajectory.segment]]
type = "climb"
duration_s = 0.0
flight_path_deg = -7.0
transition_s = 12.0
[[trajectory.segment]]
type = "roll"
duration_s = 15.0
direction = "right"
bank_deg = 80.0
roll_time_s = 60.0
[[trajectory.segment]]
type = "crab"
duration_s = 0.0
direction = "left"
crab_deg = 45.0
transition_s = 7.5
[imu]
rate_hz = 400
errors = "none"
accel_bias_ug = 1.0
accel_scale_factor_ppm = 2.0
accel_misalignment_arcsec = 3.0
gyro_bias_degph = 0.1
gyro_scale_factor_ppm = 4.0
gyro_misalignment_arcsec = 5.0
gyro_arw_deg_per_rthr = 0.001
accel_vrw_ug_per_rthz = 7.0
gyro_bias_instability_degph = 0.003
accel_bias_instability_ug = 9.0
bias_instability_tau_s = 100.0
[effects]
gyro_misalignment = { xy = 20.0, zy = -0.1 }
imu_gnss_time_offset = 0.013
antenna_lever_arm = { x = 1e-3, z = -0.5 }
imu_clock_drift = 123.456789012345
[gps]
almanac = "dir with space/a \"b\".alm"
start_week = 2000
start_tow_s = 0.0
rate_hz = 5.0
elevation_mask_deg = 0.0
max_channels = 16
pseudorange_gm_sigma_m = 0.0
pseudorange_gm_tau_s = 1e-3
pseudorange_rate_gm_sigma_mps = 0.3
pseudorange_rate_gm_tau_s = 11.0
pseudorange_white_sigma_m = 1.5
pseudorange_rate_white_sigma_mps = 0.05
clock_bias_sigma_m = 0.0
clock_drift_sigma_mps = 2.0
clock_h0_s = 2e-19
clock_h_minus2_per_s = 2e-20
)", "custom.toml");
  ASSERT_TRUE(p.ok()) << p.error;
  const Scenario& sc = *p.scenario;
  ASSERT_EQ(sc.segments.size(), 6u);
  EXPECT_EQ(sc.segments[5].type, SegmentType::kCrab);
  EXPECT_EQ(sc.segments[5].crab_deg, 45.0);
  EXPECT_EQ(read_back(sc), sc);
  // Without a repeat, and numbers that have no short decimal form.
  Scenario s2 = sc;
  s2.repeat_from = std::nullopt;
  s2.duration_s = 1.0 / 3.0;
  s2.start.lat_deg = std::nextafter(35.0, 36.0);
  EXPECT_EQ(read_back(s2), s2);
}

TEST(ScenarioWriter, RefusesWhatTheReaderWouldReject) {
  Scenario sc;
  sc.segments[1].bank_deg = 85.0;
  sim::ScenarioWriteResult w = sim::write_scenario_toml(sc);
  EXPECT_FALSE(w.ok());
  EXPECT_NE(w.error.find("trajectory.segment[1].bank_deg"), std::string::npos) << w.error;
  EXPECT_TRUE(w.text.empty());
  sc = Scenario{};
  sc.segments[0] = Segment{.type = SegmentType::kCrab, .crab_deg = 50.0};
  w = sim::write_scenario_toml(sc);
  EXPECT_FALSE(w.ok());
  EXPECT_NE(w.error.find("trajectory.segment[0].crab_deg"), std::string::npos) << w.error;
  sc = Scenario{};
  sc.start.alt_m = NAN;
  EXPECT_FALSE(sim::write_scenario_toml(sc).ok());
  sc = Scenario{};
  sc.seed = std::numeric_limits<std::uint64_t>::max();
  w = sim::write_scenario_toml(sc);
  EXPECT_FALSE(w.ok());
  EXPECT_NE(w.error.find("seed"), std::string::npos) << w.error;
}

// The flown flight unrolled and then extended: up to the flown duration it is the same timeline.
TEST(AppendSegments, TheFlownFlightIsUnchangedAndTheSegmentsFollowIt) {
  Scenario sc;
  sc.duration_s = 600.0;  // ends inside a turn: the turn is completed
  sim::FlownSegments fs;
  std::string err;
  ASSERT_TRUE(sim::flown_segments(sc, fs, err)) << err;
  EXPECT_GE(fs.end_s, sc.duration_s);
  Segment up;
  up.type = SegmentType::kClimb;
  up.flight_path_deg = 5.0;
  up.duration_s = 10.0;
  up.transition_s = 10.0;
  Scenario ext;
  ASSERT_TRUE(sim::append_segments(sc, {up}, ext, err)) << err;
  EXPECT_EQ(ext.segments.size(), fs.segments.size() + 1);
  EXPECT_FALSE(ext.repeat_from.has_value());
  EXPECT_DOUBLE_EQ(ext.duration_s, fs.end_s + 30.0);
  const auto a = sim::FlightMotion::create(sc, err);
  const auto b = sim::FlightMotion::create(ext, err);
  ASSERT_TRUE(a && b) << err;
  std::size_t compared = 0;
  for (std::size_t k = 0; k < a->timeline().size() && a->timeline()[k].t0_s < sc.duration_s; ++k, ++compared) {
    const sim::FlightPhase &x = a->timeline()[k], &y = b->timeline()[k];
    EXPECT_EQ(x.kind, y.kind);
    EXPECT_DOUBLE_EQ(x.t0_s, y.t0_s);
    EXPECT_DOUBLE_EQ(x.t1_s, y.t1_s);
    EXPECT_EQ(x.bank_rad, y.bank_rad);
    EXPECT_EQ(x.v1_mps, y.v1_mps);
  }
  EXPECT_GT(compared, 20u);
  // A flight without repeat whose segments end early: the straight that filled it is kept.
  Scenario shortlist;
  shortlist.segments = {sc.segments[0]};
  shortlist.repeat_from = std::nullopt;
  shortlist.duration_s = 100.0;
  ASSERT_TRUE(sim::append_segments(shortlist, {up}, ext, err)) << err;
  ASSERT_EQ(ext.segments.size(), 3u);
  EXPECT_EQ(ext.segments[1].type, SegmentType::kStraight);
  EXPECT_DOUBLE_EQ(ext.segments[1].duration_s, 40.0);
  EXPECT_DOUBLE_EQ(ext.duration_s, 130.0);
}

// A sidecar names the scenario of a simulated log; a log without one is a measured recording.
TEST(DiagnosisSeparation, TheSidecarNamesTheFlownScenario) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "sdins_separation_sidecar";
  std::filesystem::create_directories(dir);
  const std::string log = (dir / "run.lcmlog").string();
  std::filesystem::remove(log + ".json");
  tools::FlownScenario none = tools::scenario_from_sidecar(log);
  EXPECT_FALSE(none.known);
  EXPECT_NE(none.note.find("no scenario is known"), std::string::npos) << none.note;
  {
    std::ofstream f(log + ".json");
    f << R"({"format": "sdins-sim-sidecar", "version": 1, "scenario": "bank-to-turn", "scenario_file": "",
             "seed": 42, "duration_s": 300.0, "truth_errors": "baseline", "imu_rate_hz": 1000, "gps_rate_hz": 1.0,
             "effects": [{"name": "antenna_lever_arm", "component": "x", "value": 1.5, "unit": "m",
                          "source": "command_line"}]})";
  }
  const tools::FlownScenario s = tools::scenario_from_sidecar(log);
  ASSERT_TRUE(s.known) << s.note;
  EXPECT_EQ(s.scenario.seed, 42u);
  EXPECT_EQ(s.scenario.duration_s, 300.0);
  EXPECT_EQ(s.scenario.imu.errors, sim::ImuErrorSet::kBaseline);
  EXPECT_EQ(s.scenario.effects.get(fsw::Effect::kAntennaLeverArm, 0), 1.5);
  EXPECT_EQ(s.scenario.segments, Scenario{}.segments);
  {
    std::ofstream f(log + ".json");
    f << R"({"format": "sdins-sim-sidecar", "scenario_file": "missing.toml", "seed": 1})";
  }
  const tools::FlownScenario bad = tools::scenario_from_sidecar(log);
  EXPECT_FALSE(bad.known);
  EXPECT_NE(bad.note.find("missing.toml"), std::string::npos) << bad.note;
  std::filesystem::remove_all(dir);
}

// Without a scenario (a measured recording) the segments are suggested, never a prediction.
TEST(DiagnosisSeparation, AMeasuredRecordingGetsSegmentsWithoutAPrediction) {
  tools::DiagnosisResult r;
  tools::Finding f;
  f.effect = fsw::Effect::kAntennaLeverArm;
  f.component = "x";
  tools::GroupMember a, b;
  a.name = "antenna_lever_arm.x";
  b.name = "imu_gnss_time_offset";
  f.group = {a, b};
  r.findings = {f, tools::Finding{}};
  tools::FlownScenario unknown;
  unknown.note = "no scenario is known for this recording";
  const std::vector<tools::Separation> s = tools::suggest_separations(r, tools::default_diagnosis_config(), unknown);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_FALSE(s[0].predicted);
  EXPECT_TRUE(s[0].scenario_toml.empty());
  EXPECT_FALSE(s[0].segments.empty());
  EXPECT_EQ(s[0].note, unknown.note);
  EXPECT_NE(s[0].segments_toml.find("[[trajectory.segment]]"), std::string::npos);
  // The suggested segments are valid scenario segments.
  const sim::ScenarioParseResult p = sim::parse_scenario_text(s[0].segments_toml, "segments.toml");
  ASSERT_TRUE(p.ok()) << p.error;
  EXPECT_EQ(p.scenario->segments, s[0].segments);
  EXPECT_TRUE(s[1].members.empty());  // a separable finding: nothing to separate
}

// The issue's case: on the default flight a hidden IMU-GNSS time offset is one of a group with the
// antenna lever arm x (the along-track error of 10 ms at 250 m/s is that of a 2.5 m lever arm,
// which turns with the body as the velocity does in coordinated turns). The suggestion lowers the
// members' correlation, and the prediction is checked against the flight itself: the scenario file
// as written, flown with the same hidden effect at the scenario's own IMU rate, gives the members
// the correlation predicted. (On this flight no candidate of the catalogue gets the pair below 0.9:
// the body x axis stays along the velocity in every segment type; docs/diagnosis-separation.md.)
// Issue 18's separation test, end to end: a time offset confounded with the lever arm x on the
// default flight; the suggested segments (a crab) are flown with the same hidden effect; the
// members' correlation falls as predicted, below the threshold, and the diagnosis of that flight
// names the time offset alone, its interval covering the truth.
TEST(DiagnosisSeparation, TheSuggestedCrabSeparatesATimeOffsetFromTheLeverArmAndTheDiagnosisNamesIt) {
  if (kSanitized) GTEST_SKIP() << "statistical test: release stage";
  const auto t0 = std::chrono::steady_clock::now();
  const auto since = [&t0]() { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  Scenario sc;
  sc.duration_s = 600.0;
  sc.seed = 631;
  sc.imu.errors = sim::ImuErrorSet::kBaseline;
  ASSERT_EQ(sim::apply_effect_assignment(sc.effects, "imu_gnss_time_offset=0.01"), "");
  const tools::DiagnosisConfig cfg = tools::default_diagnosis_config();
  const tools::DiagnosisResult r = tools::diagnose(tools::record_scenario(sc, sc.seed), cfg);
  ASSERT_EQ(r.findings.size(), 1u);
  const tools::Finding& f = r.findings.front();
  ASSERT_FALSE(f.separable()) << "the time offset is separable on the flown flight: no case for a separation";
  std::vector<int> members;
  for (const tools::GroupMember& m : f.group)
    for (std::size_t c = 0; c < tools::diagnosis_candidates().size(); ++c)
      if (tools::candidate_name(tools::diagnosis_candidates()[c]) == m.name) members.push_back(static_cast<int>(c));
  ASSERT_EQ(members.size(), f.group.size());
  bool offset = false, lever = false;
  for (const tools::GroupMember& m : f.group) {
    offset = offset || m.name == "imu_gnss_time_offset";
    lever = lever || m.name == "antenna_lever_arm.x";
  }
  EXPECT_TRUE(offset && lever);
  const double t_diagnose = since();

  tools::FlownScenario flown;
  flown.known = true;
  flown.scenario = sc;
  flown.source = "the test's scenario";
  std::vector<tools::SeparationTrial> trials;
  const std::vector<tools::Separation> seps = tools::suggest_separations(r, cfg, flown, {}, &trials);
  const double t_separation = since() - t_diagnose;
  ASSERT_EQ(seps.size(), 1u);
  const tools::Separation& s = seps.front();
  for (const tools::SeparationTrial& t : trials)
    std::printf("  %-70s +%4.0f s: predicted correlation %.3f %s\n", t.label.c_str(), t.added_s,
                t.evaluated ? t.correlation[0] : NAN, t.error.c_str());
  ASSERT_TRUE(s.predicted) << s.note;
  EXPECT_GT(s.flown_correlation, cfg.max_correlation);
  EXPECT_LT(s.predicted_correlation, s.flown_correlation - 0.03);
  EXPECT_EQ(s.separates, s.predicted_correlation < cfg.max_correlation);
  for (const tools::SeparationTrial& t : trials)  // the suggestion is the best trial
    if (t.evaluated) EXPECT_GE(t.correlation[0], s.predicted_correlation) << t.label;
  ASSERT_FALSE(s.scenario_toml.empty()) << s.note;

  // The scenario file as written, flown with its own seed at its own IMU rate: it carries the
  // hidden effect; the extended model over it gives the members the predicted correlation.
  const sim::ScenarioParseResult p = sim::parse_scenario_text(s.scenario_toml, "separation.toml");
  ASSERT_TRUE(p.ok()) << p.error;
  EXPECT_EQ(p.scenario->effects, sc.effects);
  EXPECT_EQ(p.scenario->seed, sc.seed);
  EXPECT_EQ(p.scenario->imu.rate_hz, sc.imu.rate_hz);
  EXPECT_DOUBLE_EQ(p.scenario->duration_s, sc.duration_s + s.added_s);
  const tools::RecordedData flown_rec = tools::record_scenario(*p.scenario, p.scenario->seed);
  const double t_fly = since();
  const tools::DiagnosisRun run = tools::run_diagnosis_model(flown_rec, cfg, r.extended.active);
  ASSERT_TRUE(run.initialised);
  std::vector<int> pos;
  for (int c : members)
    pos.push_back(static_cast<int>(std::find(run.active.begin(), run.active.end(), c) - run.active.begin()));
  const double flown_after = tools::group_correlation(run.correlation, pos);
  std::printf("members' correlation: flown %.4f, predicted after %s %.4f, flown after it %.4f; times: diagnosis "
              "%.1f s, separation %.1f s\n",
              s.flown_correlation, s.label.c_str(), s.predicted_correlation, flown_after, t_diagnose, t_separation);
  EXPECT_NEAR(flown_after, s.predicted_correlation, 0.02);
  EXPECT_LT(flown_after, s.flown_correlation - 0.03);
  // The crab takes the pair below the threshold (every other segment kind keeps body x on the
  // velocity, where a lever arm along x and a time offset are the same error).
  EXPECT_TRUE(s.separates) << s.label << ": " << s.predicted_correlation;
  EXPECT_NE(s.label.find("crab"), std::string::npos) << s.label;
  EXPECT_LT(flown_after, cfg.max_correlation);

  // The issue's test: the separating flight, diagnosed as a new recording (the whole search, the
  // same hidden 10 ms offset), names the right member alone, its 95% interval covering the truth.
  const double t_diag2 = since();
  const tools::DiagnosisResult r2 = tools::diagnose(flown_rec, cfg);
  const double t_diagnose2 = since() - t_diag2;
  for (const tools::Finding& g : r2.findings)
    std::printf("separating flight: finding %s.%s %.5g +- %.3g %s, 95%% [%.5g, %.5g] (%s), z^2 %.1f, %s\n",
                fsw::effect_info(g.effect).name, g.component.c_str(), g.estimate, g.sigma, g.unit.c_str(),
                g.interval.lo, g.interval.hi, g.interval.method.c_str(), g.z2,
                g.separable() ? "separable" : "a group");
  std::printf("times: flying the separating scenario %.1f s, diagnosing it %.1f s\n", t_fly - t_diagnose - t_separation,
              t_diagnose2);
  ASSERT_EQ(r2.findings.size(), 1u);
  const tools::Finding& g = r2.findings.front();
  EXPECT_TRUE(g.separable());
  EXPECT_EQ(g.effect, fsw::Effect::kImuGnssTimeOffset);
  EXPECT_EQ(g.interval.method, "profile_likelihood");
  EXPECT_TRUE(g.interval.bounded);
  EXPECT_LE(g.interval.lo, 0.01);
  EXPECT_GE(g.interval.hi, 0.01);
}

}  // namespace
