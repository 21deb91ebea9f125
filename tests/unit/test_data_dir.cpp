// The product's run-time data directory (cfg/data_dir.hpp): found beside the executable in the
// build tree as in an install, overridden by SDINS_DATA_DIR and --data-dir, refused when a named
// directory is not sdins data; the staged copy is the source's, and the shipped almanac is the
// documented file (data/almanac/README.md).
#include <gtest/gtest.h>
#include <stdlib.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <tuple>
#include <unistd.h>

#include "sim/almanac.hpp"
#include "cfg/data_dir.hpp"
#include "sim/scenario.hpp"

namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Clears SDINS_DATA_DIR and the override for a test, restores them after.
class DataDir : public ::testing::Test {
 protected:
  void SetUp() override {
    if (const char* e = std::getenv("SDINS_DATA_DIR")) saved_ = e, had_ = true;
    ::unsetenv("SDINS_DATA_DIR");
    cfg::set_data_dir_override("");
    tmp_ = fs::temp_directory_path() / ("sdins_data_dir_" + std::to_string(::getpid()));
    fs::remove_all(tmp_);
    fs::create_directories(tmp_);
  }
  void TearDown() override {
    cfg::set_data_dir_override("");
    if (had_) ::setenv("SDINS_DATA_DIR", saved_.c_str(), 1);
    else ::unsetenv("SDINS_DATA_DIR");
    fs::remove_all(tmp_);
  }
  fs::path make_data_dir(const std::string& name) {
    const fs::path d = tmp_ / name;
    fs::create_directories(d);
    std::ofstream(d / cfg::kDataDirMarker) << "test\n";
    return d;
  }
  fs::path tmp_;
  std::string saved_;
  bool had_ = false;
};

TEST_F(DataDir, FoundBesideTheExecutableInTheBuildTree) {
  const cfg::DataDirLookup d = cfg::find_data_dir();
  ASSERT_TRUE(d.ok()) << d.error;
  EXPECT_EQ(d.source, cfg::DataDirSource::kExecutable);
  EXPECT_EQ(fs::path(d.path).filename(), "sdins");
  EXPECT_EQ(fs::path(d.path).parent_path().filename(), "share");
  EXPECT_TRUE(fs::is_regular_file(fs::path(d.path) / cfg::kDataDirMarker));
  EXPECT_EQ(sim::default_almanac_path(), d.path + "/almanac/yuma-week431.alm");
}

TEST_F(DataDir, InstallLayoutFromAnyPrefix) {
  // PREFIX/bin/sdins finds PREFIX/share/sdins, wherever PREFIX is (relocatable).
  const fs::path prefix = tmp_ / "some where" / "prefix";
  fs::create_directories(prefix / "bin");
  fs::create_directories(prefix / "share" / "sdins");
  std::ofstream(prefix / "share" / "sdins" / cfg::kDataDirMarker) << "test\n";
  std::ofstream(prefix / "bin" / "sdins") << "";
  const cfg::DataDirLookup d = cfg::find_data_dir((prefix / "bin" / "sdins").string());
  ASSERT_TRUE(d.ok()) << d.error;
  EXPECT_EQ(d.path, fs::canonical(prefix / "share" / "sdins").string());
}

TEST_F(DataDir, NothingBesideTheExecutableIsAnErrorThatSaysWhereItLooked) {
  const cfg::DataDirLookup d = cfg::find_data_dir("/nonexistent/bin/sdins");
  EXPECT_FALSE(d.ok());
  EXPECT_NE(d.error.find("/nonexistent/bin/../share/sdins/sdins-data.txt"), std::string::npos) << d.error;
  EXPECT_NE(d.error.find("SDINS_DATA_DIR"), std::string::npos) << d.error;
}

TEST_F(DataDir, EnvironmentOverridesTheExecutablesAndMustBeSdinsData) {
  const fs::path good = make_data_dir("good");
  ::setenv("SDINS_DATA_DIR", good.c_str(), 1);
  cfg::DataDirLookup d = cfg::find_data_dir();
  ASSERT_TRUE(d.ok()) << d.error;
  EXPECT_EQ(d.source, cfg::DataDirSource::kEnvironment);
  EXPECT_EQ(d.path, fs::canonical(good).string());
  EXPECT_EQ(cfg::data_file("almanac/x.alm"), fs::canonical(good).string() + "/almanac/x.alm");

  const fs::path plain = tmp_ / "plain";
  fs::create_directories(plain);
  ::setenv("SDINS_DATA_DIR", plain.c_str(), 1);
  d = cfg::find_data_dir();
  EXPECT_FALSE(d.ok());  // no silent fall-through to the executable's copy
  EXPECT_NE(d.error.find("SDINS_DATA_DIR names '" + plain.string() + "'"), std::string::npos) << d.error;
  EXPECT_NE(d.error.find("sdins-data.txt"), std::string::npos) << d.error;
  // ... and what opens a data file then fails with that reason in its message.
  const sim::AlmanacParseResult a = sim::parse_yuma_file(sim::default_almanac_path());
  EXPECT_FALSE(a.ok());
  EXPECT_NE(a.error.find("not an sdins data directory"), std::string::npos) << a.error;

  ::setenv("SDINS_DATA_DIR", (tmp_ / "missing").c_str(), 1);
  d = cfg::find_data_dir();
  EXPECT_FALSE(d.ok());
  EXPECT_NE(d.error.find("not a directory"), std::string::npos) << d.error;
}

TEST_F(DataDir, DataDirOptionOverridesTheEnvironment) {
  const fs::path env_dir = make_data_dir("env");
  const fs::path opt_dir = make_data_dir("opt");
  ::setenv("SDINS_DATA_DIR", env_dir.c_str(), 1);
  cfg::set_data_dir_override(opt_dir.string());
  const cfg::DataDirLookup d = cfg::find_data_dir();
  ASSERT_TRUE(d.ok()) << d.error;
  EXPECT_EQ(d.source, cfg::DataDirSource::kOverride);
  EXPECT_EQ(d.path, fs::canonical(opt_dir).string());
  cfg::set_data_dir_override((tmp_ / "nope").string());
  EXPECT_FALSE(cfg::find_data_dir().ok());
  EXPECT_NE(cfg::find_data_dir().error.find("--data-dir names"), std::string::npos);
}

TEST_F(DataDir, StagedDataIsTheSourcesAndComplete) {
  const cfg::DataDirLookup d = cfg::find_data_dir();
  ASSERT_TRUE(d.ok()) << d.error;
  const fs::path data(d.path), src(SDINS_TEST_SOURCE_DIR);
  const std::pair<const char*, const char*> pieces[] = {
      {"almanac/yuma-week431.alm", "data/almanac/yuma-week431.alm"},
      {"scenarios/bank_to_turn.toml", "sim/scenarios/bank_to_turn.toml"},
      {"config/README.md", "config/README.md"},
      {"config/datasets/gnss-imu-drive.toml", "config/datasets/gnss-imu-drive.toml"},
      {"can/sdins.dbc", "hal/can/sdins.dbc"},
      {"lcm/nav_solution_t.lcm", "hal/lcm/nav_solution_t.lcm"},
      {"plot/plot_paper.py", "tools/plot/plot_paper.py"},
  };
  for (const auto& [staged, source] : pieces) {
    ASSERT_TRUE(fs::is_regular_file(data / staged)) << staged;
    EXPECT_EQ(slurp(data / staged), slurp(src / source)) << staged << " differs from " << source;
  }
  // Every .lcm definition and plot script, not only the ones named.
  for (const auto& [dir, staged_dir, ext] : {std::tuple{"hal/lcm", "lcm", ".lcm"}, std::tuple{"tools/plot", "plot", ".py"}})
    for (const auto& e : fs::directory_iterator(src / dir))
      if (e.path().extension() == ext)
        EXPECT_TRUE(fs::is_regular_file(data / staged_dir / e.path().filename())) << e.path();
}

TEST_F(DataDir, ShippedAlmanacIsTheDocumentedFile) {
  const std::string path = sim::default_almanac_path();
  const std::string cmd = "sha256sum '" + path + "'";
  FILE* p = ::popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  char buf[65] = {};
  const std::size_t n = std::fread(buf, 1, 64, p);
  ::pclose(p);
  ASSERT_EQ(n, 64u);
  EXPECT_STREQ(buf, "381467589d7b4a469fb7c99a472fbf6b48ddbd6bde3fe78055a7431361731ac0");
  const sim::AlmanacParseResult a = sim::parse_yuma_file(path);
  ASSERT_TRUE(a.ok()) << a.error;
  EXPECT_EQ(a.almanac->size(), 31u);
}

}  // namespace
