// The chain of diagnoses (tools/diagnosis_chain.hpp, docs/diagnosis.md "The chain"): a timing or
// geometry finding is applied to the recording and the search repeated; the findings reported are
// those that survive every correction before them, and the headline is the profile's maximum.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include <Eigen/Geometry>

#include "diagnosis_test_util.hpp"
#include "hal/lcm_log_sink.hpp"
#include "lcm_test_util.hpp"
#include "sim/effects.hpp"
#include "tools/diagnosis.hpp"
#include "tools/diagnosis_chain.hpp"
#include "tools/diagnosis_intervals.hpp"

namespace {

using diagnosis_test::baseline_scenario;
using diagnosis_test::kSanitized;
using diagnosis_test::name_of;

/// The scenario's data through an LCM log and its reader (time-tag order), as `sdins diagnose --log`
/// sees it. (In the simulator's own order an epoch follows the IMU sample of its true time, which
/// with IMU tags 250 ms late is older than the executive's max_gnss_age_s at use: no update.)
tools::RecordedData through_a_log(const tools::RecordedData& stream, const std::string& name) {
  const std::string path = lcm_test::scratch(name);
  {
    hal::LcmLogSink sink;
    hal::LcmTelemetryConfig tc;
    tc.lcm_url = "none";
    tc.log_path = path;
    EXPECT_EQ(sink.open(tc), hal::LcmLogStatus::kOk);
    for (const fsw::GpsAlmanac& a : stream.almanac) EXPECT_EQ(sink.write_almanac(a, 0.0), hal::LcmLogStatus::kOk);
    for (const tools::RecordedData::Event& ev : stream.order) {
      if (ev.kind == tools::RecordedData::Kind::kImu) EXPECT_EQ(sink.write_imu(stream.imu[ev.index]), hal::LcmLogStatus::kOk);
      if (ev.kind == tools::RecordedData::Kind::kGnss) EXPECT_EQ(sink.write_gnss(stream.gnss[ev.index]), hal::LcmLogStatus::kOk);
    }
    EXPECT_EQ(sink.close(), hal::LcmLogStatus::kOk);
  }
  tools::RecordedData logged;
  std::string err, report;
  EXPECT_TRUE(tools::load_recorded_data(path, logged, err, report)) << err;
  std::remove(path.c_str());
  return logged;
}

}  // namespace

// A large hidden IMU-GNSS time offset (only it hidden; the default bank-to-turn flight, whose
// coordinated turns confound an offset with a lever arm x of v tau, 60-90 m here): the chain must
// name the offset within 10 ms, its 95% interval covering the truth, and report nothing else (the
// lever arm z and other side effects of the un-applied offset vanish once it is applied). A
// smaller value (the linearised filter's, a first-order fit) fails the 10 ms.
TEST(DiagnosisChain, LargeHiddenTimeOffsetIsNamedWithinTenMillisecondsAndNothingElse) {
  if (kSanitized) GTEST_SKIP() << "statistical test: release stage";
  struct Case {
    double offset_s;
    std::uint64_t seed;
  };
  for (const Case c : {Case{0.25, 7}, Case{-0.4, 8}}) {
    sim::Scenario sc = baseline_scenario(600.0, c.seed);
    ASSERT_EQ(sim::apply_effect_assignment(sc.effects, "imu_gnss_time_offset=" + std::to_string(c.offset_s)), "");
    const tools::DiagnosisChain ch = tools::diagnose_chain(through_a_log(tools::record_scenario(sc, c.seed), "diag_chain_offset.lcmlog"),
                                                       tools::default_diagnosis_config());
    for (const tools::ChainStage& st : ch.stages) {
      std::printf("offset %+.3f s, stage %d: %zu findings, baseline log-likelihood %.1f (%d), applied after: %s\n",
                  c.offset_s, st.stage, st.findings.size(), st.base_log_likelihood, st.common_measurements,
                  st.applied_after.c_str());
      for (const tools::Finding& f : st.findings)
        std::printf("  %s %.5g [%.5g, %.5g] (filter %.5g +- %.3g), z^2 %.1f, %zu members\n", name_of(f).c_str(),
                    f.estimate, f.interval.lo, f.interval.hi, f.filter_estimate, f.filter_sigma, f.z2, f.group.size());
    }
    ASSERT_FALSE(ch.applied.empty()) << c.offset_s;
    EXPECT_EQ(ch.applied.front().name, "imu_gnss_time_offset") << "the first correction applied";
    ASSERT_EQ(ch.findings.size(), 1u) << "only the offset is hidden: exactly one finding after the chain";
    const tools::Finding& f = ch.findings.front();
    EXPECT_EQ(f.effect, fsw::Effect::kImuGnssTimeOffset);
    EXPECT_EQ(f.estimate_method, "profile_maximum");
    EXPECT_TRUE(f.interval.is_profile() && f.interval.bounded);
    EXPECT_NEAR(f.estimate, c.offset_s, 0.010) << "named within 10 ms";
    EXPECT_LE(f.interval.lo, c.offset_s);
    EXPECT_GE(f.interval.hi, c.offset_s);
    EXPECT_DOUBLE_EQ(f.estimate, f.interval.estimate) << "the headline is the profile's maximum";
    // The last stage searched the corrected recording and found nothing more.
    EXPECT_TRUE(ch.last.findings.empty()) << name_of(ch.last.findings.front());
    // The correction explains the data: the baseline on the corrected recording is far more likely.
    ASSERT_GE(ch.stages.size(), 2u);
    EXPECT_GT(ch.stages.back().base_log_likelihood, ch.stages.front().base_log_likelihood + 100.0);
  }
}

// The headline of a separable finding with a profile interval is the profile's maximum, with the
// filter's own estimate kept beside it; without a profile it is the filter's.
TEST(DiagnosisChain, HeadlineIsTheProfileMaximumWhenThereIsAProfile) {
  tools::Finding a;
  a.filter_estimate = 161.5;
  a.filter_sigma = 16.1;
  a.interval.method = "profile_likelihood";
  a.interval.lo = 205.7;
  a.interval.hi = 277.3;
  a.interval.estimate = 241.0;
  tools::Finding b;
  b.filter_estimate = 0.13;
  b.filter_sigma = 0.02;
  b.interval = tools::filter_interval(0.13, 0.02);
  std::vector<tools::Finding> v = {a, b};
  tools::set_headline_estimates(v);
  EXPECT_EQ(v[0].estimate, 241.0);
  EXPECT_EQ(v[0].estimate_method, "profile_maximum");
  EXPECT_NEAR(v[0].sigma, (277.3 - 205.7) / 3.919927969, 1e-9);
  EXPECT_EQ(v[0].filter_estimate, 161.5);
  EXPECT_EQ(v[1].estimate, 0.13);
  EXPECT_EQ(v[1].sigma, 0.02);
  EXPECT_EQ(v[1].estimate_method, "filter");
}

// A lever-arm correction moves the configured antenna; a timing correction re-times the IMU.
TEST(DiagnosisChain, CorrectionsGoToTheModelOrTheData) {
  tools::RecordedData d;
  fsw::ImuSample s{};
  s.t_s = 10.0;
  s.dt_s = 0.005;
  d.imu.push_back(s);
  d.order.push_back({tools::RecordedData::Kind::kImu, 0});
  tools::DiagnosisConfig cfg = tools::default_diagnosis_config();
  const double z0 = cfg.app.exec.ekf.lever_arm_b_m.z();
  tools::apply_correction(d, cfg, tools::candidate_index("antenna_lever_arm.z"), 0.5);
  EXPECT_DOUBLE_EQ(cfg.app.exec.ekf.lever_arm_b_m.z(), z0 + 0.5);
  EXPECT_DOUBLE_EQ(d.imu[0].t_s, 10.0);
  tools::apply_correction(d, cfg, tools::candidate_index("imu_gnss_time_offset"), 0.25);
  EXPECT_DOUBLE_EQ(d.imu[0].t_s, 9.75);
}

// A sensor mounted sideways (90 deg about the vehicle's z, and 5 deg of pitch: the simulator's
// imu.mounting_rpy_deg) on the default aircraft, initialised from the GNSS track: the mounting yaw
// is found by the profile over the initial heading offset, its interval covering 90 deg, and the
// flight then initialises right (the chain's first search starts from it).
TEST(DiagnosisChain, SidewaysMountingYawIsFoundByTheInitialHeadingProfile) {
  if (kSanitized) GTEST_SKIP() << "statistical test: release stage";
  sim::Scenario sc = baseline_scenario(300.0, 21);
  const tools::RecordedData as_configured = tools::record_scenario(sc, 21);
  sc.imu.mounting_rpy_deg = {0.0, 5.0, 90.0};
  const tools::RecordedData data = tools::record_scenario(sc, 21);
  const tools::DiagnosisConfig cfg = tools::default_diagnosis_config();
  const tools::MountingEstimate m = tools::estimate_mounting_yaw(data, cfg);
  std::printf("mounting yaw %.2f deg [%.2f, %.2f], deviance at 0 %.1f, %d runs\n", m.yaw_deg, m.lo_deg, m.hi_deg,
              m.deviance_at_configured, m.runs);
  ASSERT_TRUE(m.searched);
  EXPECT_TRUE(m.found);
  EXPECT_NEAR(m.yaw_deg, 90.0, 2.0);
  EXPECT_LE(m.lo_deg, 90.0);
  EXPECT_GE(m.hi_deg, 90.0);
  // With the sensor mounted as configured, nothing is found (the screen's 8 runs only).
  const tools::MountingEstimate none = tools::estimate_mounting_yaw(as_configured, cfg);
  EXPECT_FALSE(none.found) << none.yaw_deg;
  EXPECT_EQ(none.runs, 8);
}
