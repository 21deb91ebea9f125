// The Monte Carlo on a short flight: filter consistency (NEES inside its chi-square bounds),
// convergence, no rejected measurements, and determinism across thread counts.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "sim/almanac.hpp"
#include "tools/montecarlo.hpp"

namespace {

struct Fixture {
  sim::Scenario sc;
  std::vector<sim::AlmanacEntry> almanac;
  sim::TruthTrack truth;
  explicit Fixture(double duration_s) {
    sc.duration_s = duration_s;
    const sim::AlmanacParseResult r = sim::parse_yuma_file(sim::almanac_path(sc.gps));
    EXPECT_TRUE(r.ok()) << r.error;
    if (r.ok()) almanac = *r.almanac;
    truth = sim::TruthTrack::generate(sc);
  }
};

}  // namespace

TEST(MonteCarlo, ShortRunFiltersAreConsistentAndConverge) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "statistical test (12 runs x 400 s): release stage; the Monte Carlo code runs under the "
                  "sanitizers in MonteCarlo.ResultsDoNotDependOnThreadCount and e2e_montecarlo_threads";
#endif
  Fixture f(400.0);  // 60 s straight, then the first four turns
  tools::MonteCarloConfig mc;
  mc.runs = 12;
  mc.threads = 2;
  const auto results = tools::run_many(f.sc, f.truth, f.almanac, mc);
  ASSERT_EQ(results.size(), 12u);
  for (std::size_t m = 0; m < mc.models.size(); ++m) {
    const tools::ModelStats s = tools::reduce(results, m, mc.models[m], f.truth);
    SCOPED_TRACE(fsw::to_string(mc.models[m]));
    std::printf("model %s: mean NEES %.2f in [%.2f, %.2f]; attitude NEES %.2f in [%.2f, %.2f]; final U sigma %.1f arcsec\n",
                fsw::to_string(mc.models[m]), s.mean_nees, s.nees_bounds[0], s.nees_bounds[1], s.mean_nees_att,
                s.nees_att_bounds[0], s.nees_att_bounds[1], s.att_std_rad.back()[2] * fsw::kRadToArcsec);
    EXPECT_GT(s.mean_nees, s.nees_bounds[0]);
    EXPECT_LT(s.mean_nees, s.nees_bounds[1]);
    EXPECT_GT(s.mean_nees_att, s.nees_att_bounds[0]);
    EXPECT_LT(s.mean_nees_att, s.nees_att_bounds[1]);
    // Every epoch after the first is a measurement update, the last one's correction landing
    // after the end of the flight (10 frames, the rate groups' latency); the gate rejects
    // (almost) nothing.
    EXPECT_EQ(s.health.ekf_updates, 12u * 399u);
    EXPECT_LT(s.health.pr_rejected + s.health.prr_rejected, (s.health.pr_used + s.health.prr_used) / 200);
    EXPECT_EQ(s.health.fsw_errors, 0u);
    EXPECT_EQ(s.health.imu_rejected, 0u);
    // Heading: from the alignment's ~170 arcsec to a few tens once the turns have made it observable.
    EXPECT_GT(s.att_std_rad.front()[2] * fsw::kRadToArcsec, 80.0);
    EXPECT_LT(s.att_std_rad.back()[2] * fsw::kRadToArcsec, 60.0);
    EXPECT_LT(s.pos_rms_m.back(), 15.0);
    EXPECT_LT(s.vel_rms_mps.back(), 0.3);
  }
}

TEST(MonteCarlo, ResultsDoNotDependOnThreadCount) {
  Fixture f(90.0);
  tools::MonteCarloConfig mc;
  mc.runs = 3;
  mc.threads = 1;
  const auto a = tools::run_many(f.sc, f.truth, f.almanac, mc);
  mc.threads = 3;
  const auto b = tools::run_many(f.sc, f.truth, f.almanac, mc);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t r = 0; r < a.size(); ++r)
    for (std::size_t m = 0; m < a[r].epochs.size(); ++m) {
      ASSERT_EQ(a[r].epochs[m].size(), b[r].epochs[m].size());
      EXPECT_EQ(std::memcmp(a[r].epochs[m].data(), b[r].epochs[m].data(),
                            a[r].epochs[m].size() * sizeof(tools::EpochRecord)),
                0)
          << "run " << r << " model " << m;
    }
  // Different runs differ (the seed reaches the IMU, GPS and initial errors).
  EXPECT_NE(std::memcmp(a[0].epochs[0].data(), a[1].epochs[0].data(), sizeof(tools::EpochRecord) * 10), 0);
}

TEST(MonteCarlo, ChiSquareBoundsMatchTables) {
  // chi2 quantiles / k: 9 dof, 100 runs -> chi2(900) 2.5% = 818.4, 97.5% = 984.8 (tables).
  const auto b = tools::chi2_mean_bounds(9, 100);
  EXPECT_NEAR(b[0], 8.184, 0.01);
  EXPECT_NEAR(b[1], 9.848, 0.01);
  const auto c = tools::chi2_mean_bounds(3, 10);  // chi2(30): 16.79, 46.98
  EXPECT_NEAR(c[0], 1.679, 0.01);
  EXPECT_NEAR(c[1], 4.698, 0.01);
}

TEST(MonteCarlo, FilterConfigFileIsTheBaseUnderTheScenarioOverlay) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("sdins_mc_cfg_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string good = (dir / "good.toml").string(), pvt = (dir / "pvt.toml").string();
  std::ofstream(good) << "name = \"t\"\n[executive]\ngnss_wait_s = 0.1\n[gnss]\ngate_chi2 = 20.0\n";
  std::ofstream(pvt) << "name = \"t\"\n[gnss]\nsource = \"pvt\"\n";
  sim::Scenario sc;
  tools::MonteCarloConfig mc;
  EXPECT_FALSE(tools::monte_carlo_flight_config("").has_value());
  const fsw::FlightAppConfig shipped = tools::flight_app_config(sc, mc);
  mc.flight = tools::monte_carlo_flight_config(good);
  ASSERT_TRUE(mc.flight.has_value());
  const fsw::FlightAppConfig flown = tools::flight_app_config(sc, mc);
  // The file's keys reach the flight software ...
  EXPECT_EQ(flown.exec.gnss_wait_frames, 20);
  EXPECT_NE(shipped.exec.gnss_wait_frames, 20);
  EXPECT_EQ(flown.exec.ekf.gate_chi2, 20.0);
  // ... and the scenario overlay still sets what follows from the scenario.
  EXPECT_EQ(flown.exec.ekf.att_sigma_rad, shipped.exec.ekf.att_sigma_rad);
  EXPECT_EQ(flown.init_mode, fsw::InitMode::kGiven);
  // A GNSS input the simulation does not produce, or a broken file: refused, naming the file.
  try {
    (void)tools::monte_carlo_flight_config(pvt);
    ADD_FAILURE() << "gnss.source = pvt accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("pvt.toml"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)tools::monte_carlo_flight_config((dir / "missing.toml").string()), std::runtime_error);
  std::filesystem::remove_all(dir);
}
