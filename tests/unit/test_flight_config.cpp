// One source of the flight configuration (config/README.md): the shipped config/default.toml sets
// every key of the schema, the staged copy in the data directory is the repository's file, and
// every command's configuration is that file (the Monte Carlo's differs only in its documented
// scenario overlay). Renamed and doubly-given keys are refused with a message that says so.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "fsw/filter_model.hpp"
#include "hal/fsw_node.hpp"
#include "cfg/data_dir.hpp"
#include "cfg/flight_config.hpp"
#include "fsw/flight_app_config_fields.hpp"
#include "tools/diagnosis.hpp"
#include "tools/montecarlo.hpp"

namespace {

const std::filesystem::path kSourceFile = std::filesystem::path(SDINS_TEST_SOURCE_DIR) / "config/default.toml";

// A new field must be listed in FLIGHT_CONFIG_FIELDS (fsw/flight_app_config_fields.hpp; and, if a file
// should set it, get a key in cfg/src/flight_config.cpp and config/default.toml): the sizes are
// those of the structs the list describes (x86-64), so a field added without it stops this test
// from compiling.
static_assert(sizeof(fsw::EkfConfig) == 336, "fsw::EkfConfig changed: update FLIGHT_CONFIG_FIELDS");
static_assert(sizeof(fsw::ExecutiveConfig) == 384, "fsw::ExecutiveConfig changed: update FLIGHT_CONFIG_FIELDS");
static_assert(sizeof(fsw::FlightAppConfig) == 544, "fsw::FlightAppConfig changed: update FLIGHT_CONFIG_FIELDS");

template <class T>
bool same(const T& a, const T& b) {
  return a == b;
}
bool same(const fsw::Vec3& a, const fsw::Vec3& b) { return a == b; }

/// The fields in which a and b differ ("" when none).
std::string differences(const fsw::FlightAppConfig& a, const fsw::FlightAppConfig& b) {
  std::string d;
#define COMPARE(path, in_schema) \
  if (!same(a.path, b.path)) d += std::string(" ") + #path;
  FLIGHT_CONFIG_FIELDS(COMPARE)
#undef COMPARE
  return d;
}

// A value different from v (and valid where the flight application checks it).
double other(double v) { return v * 1.5 + 0.25; }
int other(int v) { return v + 1; }
std::uint64_t other(std::uint64_t v) { return v + 1; }
bool other(bool v) { return !v; }
fsw::Vec3 other(const fsw::Vec3& v) { return v * 1.5 + fsw::Vec3::Constant(0.25); }
fsw::InitMode other(fsw::InitMode m) {
  return m == fsw::InitMode::kStatic ? fsw::InitMode::kTrack : fsw::InitMode::kStatic;
}

cfg::FlightConfig parse_source_file(const cfg::FlightConfig& base) {
  cfg::FlightConfig f = base;
  const cfg::FlightConfigResult r = cfg::parse_flight_config_file(kSourceFile.string(), f);
  EXPECT_TRUE(r.ok) << r.error;
  return f;
}

std::string read(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

TEST(FlightConfig, ShippedFileIsTheRepositorysAndSetsEveryKey) {
  // The copy the commands read (staged beside the build's executables, installed with them) is
  // the repository's file, byte for byte.
  ASSERT_TRUE(std::filesystem::is_regular_file(cfg::default_flight_config_path())) << cfg::default_flight_config_path();
  EXPECT_EQ(read(cfg::default_flight_config_path()), read(kSourceFile));
  // Every schema key is set: the file read onto the field defaults and onto a base in which every
  // field differs gives the same configuration in every field a file can set.
  cfg::FlightConfig poisoned;
#define POISON(path, in_schema) \
  if (in_schema) poisoned.app.path = other(poisoned.app.path);
  FLIGHT_CONFIG_FIELDS(POISON)
#undef POISON
  poisoned.gnss_source = cfg::GnssSource::kPvt;
  const cfg::FlightConfig a = parse_source_file(cfg::FlightConfig{});
  const cfg::FlightConfig b = parse_source_file(poisoned);
  std::string unset;
#define UNSET(path, in_schema) \
  if (in_schema && !same(a.app.path, b.app.path)) unset += std::string(" ") + #path;
  FLIGHT_CONFIG_FIELDS(UNSET)
#undef UNSET
  EXPECT_EQ(unset, "") << "config/default.toml does not set these fields";
  EXPECT_EQ(a.gnss_source, b.gnss_source);
  for (std::size_t e = 0; e < fsw::kEffectCount; ++e) EXPECT_TRUE(a.diagnosis_prior[e].has_value()) << e;
  EXPECT_TRUE(a.outage_length_s && a.outage_period_s && a.outage_first_s && a.gain_skip_s);
  fsw::FlightApp<fsw::Layout24Full> app;
  EXPECT_EQ(app.init(a.app), fsw::Status::kOk);
}

TEST(FlightConfig, EveryCommandFliesTheShippedFile) {
  const cfg::FlightConfig ref = parse_source_file(cfg::FlightConfig{});
  // sil, fsw, replay (FswRunOptions::filter, and HIL's node in test_hil_lockstep), sdins_target
  // record: cfg::flight_config / cfg::load_flight_config with no data-set file.
  EXPECT_EQ(differences(cfg::shipped_flight_config().app, ref.app), "");
  EXPECT_EQ(differences(cfg::flight_config("").app, ref.app), "");
  cfg::FlightConfig loaded;
  ASSERT_TRUE(cfg::load_flight_config("", loaded).ok);
  EXPECT_EQ(differences(loaded.app, ref.app), "");
  // diagnose: the filter, its GNSS input, the priors and the outage pattern.
  const tools::DiagnosisConfig d = tools::default_diagnosis_config();
  EXPECT_EQ(differences(d.app, ref.app), "");
  EXPECT_EQ(d.gnss_source, ref.gnss_source);
  for (std::size_t e = 0; e < fsw::kEffectCount; ++e) EXPECT_EQ(d.prior[e], *ref.diagnosis_prior[e]) << e;
  EXPECT_EQ(d.outage_length_s, *ref.outage_length_s);
  EXPECT_EQ(d.outage_period_s, *ref.outage_period_s);
  EXPECT_EQ(d.outage_first_s, *ref.outage_first_s);
  EXPECT_EQ(d.gain_skip_s, *ref.gain_skip_s);
  // montecarlo / paper: the file with the scenario overlay (montecarlo.hpp, executive_config) on
  // top and nothing else: with the overlay's fields put back to the file's values, they are equal.
  const sim::Scenario sc;
  for (const bool gps_states : {true, false}) {
    tools::MonteCarloConfig mc;
    mc.model_gps_errors = gps_states;
    fsw::FlightAppConfig m = tools::flight_app_config(sc, mc);
    EXPECT_EQ(m.init_mode, fsw::InitMode::kGiven);
    EXPECT_EQ(m.exec.nav_rate_hz, ref.app.exec.nav_rate_hz);
    EXPECT_EQ(m.exec.ekf.clock_bias_sigma_m, ref.app.exec.ekf.clock_bias_sigma_m);
    EXPECT_EQ(m.exec.ekf.arw_rad_per_rts, ref.app.exec.ekf.arw_rad_per_rts);
    const fsw::FlightAppConfig& r = ref.app;
    m.init_mode = r.init_mode;
    m.init_pos_sigma_m = r.init_pos_sigma_m;
    m.init_vel_sigma_mps = r.init_vel_sigma_mps;
    m.init_att_sigma_rad = r.init_att_sigma_rad;
    fsw::ExecutiveConfig& x = m.exec;
    x.imu_samples_per_frame = r.exec.imu_samples_per_frame;
    x.frames_per_ekf = r.exec.frames_per_ekf;
    fsw::EkfConfig& e = x.ekf;
    const fsw::EkfConfig& f = r.exec.ekf;
    e.pos_sigma_m = f.pos_sigma_m;
    e.vel_sigma_mps = f.vel_sigma_mps;
    e.att_sigma_rad = f.att_sigma_rad;
    e.accel_bias_sigma_mps2 = f.accel_bias_sigma_mps2;
    e.gyro_bias_sigma_radps = f.gyro_bias_sigma_radps;
    e.accel_misalign_sigma_rad = f.accel_misalign_sigma_rad;
    e.gyro_misalign_sigma_rad = f.gyro_misalign_sigma_rad;
    e.accel_scale_sigma = f.accel_scale_sigma;
    e.gyro_scale_sigma = f.gyro_scale_sigma;
    e.clock_bias_psd_m2ps = f.clock_bias_psd_m2ps;
    e.clock_drift_psd_m2ps3 = f.clock_drift_psd_m2ps3;
    e.range_gm_sigma_m = f.range_gm_sigma_m;
    e.range_gm_tau_s = f.range_gm_tau_s;
    e.range_rate_gm_sigma_mps = f.range_rate_gm_sigma_mps;
    e.range_rate_gm_tau_s = f.range_rate_gm_tau_s;
    e.pseudorange_sigma_m = f.pseudorange_sigma_m;
    e.pseudorange_rate_sigma_mps = f.pseudorange_rate_sigma_mps;
    EXPECT_EQ(differences(m, r), "") << "model_gps_errors " << gps_states;
  }
}

TEST(FlightConfig, ShippedValuesInTheirUnits) {
  const fsw::FlightAppConfig& a = cfg::shipped_flight_config().app;
  EXPECT_EQ(a.exec.nav_rate_hz, fsw::kNavRate_hz);  // the schema's field default is the file's value
  EXPECT_EQ(a.exec.frames_per_ekf, 200);            // 200 Hz / 1 Hz
  EXPECT_EQ(a.exec.gnss_wait_frames, 40);           // 0.2 s at 200 Hz
  EXPECT_EQ(a.exec.ekf.arw_rad_per_rts, 2e-7);      // SI keys state the paper's values exactly
  EXPECT_EQ(a.exec.ekf.vrw_mps_per_rts, 1e-4);
  EXPECT_EQ(a.exec.ekf.accel_scale_sigma, 1e-4);    // 100 ppm, exactly
  EXPECT_EQ(a.exec.ekf.clock_bias_psd_m2ps, fsw::clock_bias_psd_m2ps(2e-19));
  EXPECT_EQ(a.exec.ekf.clock_drift_psd_m2ps3, fsw::clock_drift_psd_m2ps3(2e-20));
  EXPECT_EQ(a.exec.ekf.accel_bias_sigma_mps2, 100.0 * fsw::kMicroG_mps2);
}

TEST(FlightConfig, RenamedAndDoublyGivenKeysAreRefused) {
  cfg::FlightConfig f;
  cfg::FlightConfigResult r =
      cfg::parse_flight_config_text("[imu]\narw_deg_per_rthr = 0.1\narw_rad_per_rts = 2e-7\n", "x.toml", f);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("'imu.arw_deg_per_rthr' and 'imu.arw_rad_per_rts' set the same value"), std::string::npos)
      << r.error;
  r = cfg::parse_flight_config_text("[imu]\nvrw_mps_per_rthr = 0.1\nvrw_mps_per_rts = 1e-4\n", "x.toml", f);
  EXPECT_FALSE(r.ok) << "vrw given twice";
  // The clock process noise goes through fsw's one formula.
  r = cfg::parse_flight_config_text("[gnss]\nclock_h0_s = 1e-19\nclock_h_minus2_per_s = 0\n", "x.toml", f);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(f.app.exec.ekf.clock_bias_psd_m2ps, fsw::clock_bias_psd_m2ps(1e-19));
  EXPECT_EQ(f.app.exec.ekf.clock_drift_psd_m2ps3, 0.0);
}

TEST(FilterModelSelector, OneListOfNames) {
  for (const fsw::FilterModelInfo& i : fsw::kFilterModels) {
    fsw::FilterModel m{};
    ASSERT_TRUE(fsw::parse_filter_model(i.name, m)) << i.name;
    EXPECT_EQ(m, i.model);
    EXPECT_STREQ(fsw::to_string(m), i.name);
  }
  fsw::FilterModel m = fsw::FilterModel::k24;
  EXPECT_FALSE(fsw::parse_filter_model("16", m));
  EXPECT_FALSE(fsw::parse_filter_model("", m));
  EXPECT_FALSE(fsw::parse_filter_model(nullptr, m));
  EXPECT_EQ(m, fsw::FilterModel::k24);
  // The flight-software node flies 15 and 24 only, and says so.
  hal::FswNodeConfig c;
  c.model = fsw::FilterModel::k15c;
  c.app = cfg::shipped_flight_config().app;
  c.telemetry.lcm_url = "none";
  hal::FswNode node;
  std::string err;
  EXPECT_FALSE(node.open(c, err));
  EXPECT_NE(err.find("flies the models 15 and 24, not 15c"), std::string::npos) << err;
}
