// The fault mechanisms of docs/faults.md: output-file discipline (hal::OutputFile,
// hal::check_outputs), bounded readers (hal::check_input_file, cfg::read_text_file), time-tag
// sanity (hal::TimeTagGate, in the replay reader and the importers), the one almanac validation.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

#include "fsw/gps_orbit.hpp"
#include "hal/can_bus.hpp"
#include "hal/can_log.hpp"
#include "hal/can_transports.hpp"
#include "hal/input_file.hpp"
#include "hal/lcm_types.hpp"
#include "hal/lcm_log_sink.hpp"
#include "hal/output_file.hpp"
#include "hal/time_tag_gate.hpp"
#include "lcm_test_util.hpp"
#include "sim/almanac.hpp"
#include "cfg/text_file.hpp"
#include "tools/importers.hpp"
#include "tools/output_file.hpp"

namespace fs = std::filesystem;

namespace {

std::string slurp(const std::string& p) {
  std::ifstream f(p, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

void put(const std::string& p, const std::string& text) {
  std::ofstream f(p, std::ios::binary);
  f << text;
}

/// Files in dir whose name contains ".sdins-tmp." (left-over temporaries).
int temporaries_in(const std::string& dir) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().find(".sdins-tmp.") != std::string::npos) ++n;
  return n;
}

struct ScratchDir {
  std::string path = lcm_test::scratch("faults_dir");
  ScratchDir() {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~ScratchDir() { fs::remove_all(path); }
  std::string operator/(const std::string& n) const { return path + "/" + n; }
};

}  // namespace

// ---- output files ----

namespace {
/// Replaces p ("old\n") with new contents; while the file is open and flushed, the target still
/// holds the old contents and `named` temporaries stand beside it; after commit none.
void replace_checking_meanwhile(const ScratchDir& d, const std::string& p, int named) {
  put(p, "old\n");
  hal::OutputFile f;
  ASSERT_TRUE(f.open(p));
  ASSERT_TRUE(f.write("new contents\n"));
  ASSERT_TRUE(f.flush());
  EXPECT_EQ(slurp(p), "old\n");  // still the old file while writing
  EXPECT_EQ(temporaries_in(d.path), named);
  ASSERT_TRUE(f.commit()) << f.error();
  EXPECT_EQ(slurp(p), "new contents\n");
  EXPECT_EQ(temporaries_in(d.path), 0);
}
}  // namespace

TEST(OutputFile, TargetKeepsItsOldContentsUntilCommit) {
  ScratchDir d;
  const std::string p = d / "out.txt";
  replace_checking_meanwhile(d, p, 0);  // the bytes are in an unnamed (O_TMPFILE) file
  EXPECT_EQ(std::distance(fs::directory_iterator(d.path), fs::directory_iterator{}), 1);
  // A new file appears whole, under its own name, at commit.
  const std::string q = d / "new.txt";
  hal::OutputFile g;
  ASSERT_TRUE(g.open(q));
  ASSERT_TRUE(g.write("fresh\n"));
  EXPECT_FALSE(fs::exists(q));
  ASSERT_TRUE(g.commit()) << g.error();
  EXPECT_EQ(slurp(q), "fresh\n");
  EXPECT_EQ(temporaries_in(d.path), 0);
}

TEST(OutputFile, NamedTemporaryFallbackKeepsTheOldContentsUntilCommit) {
  // File systems without O_TMPFILE get a named ".NAME.sdins-tmp.PID.N" beside the target.
  ScratchDir d;
  const std::string p = d / "out.txt";
  hal::set_unnamed_temporaries(false);
  replace_checking_meanwhile(d, p, 1);
  hal::set_unnamed_temporaries(true);
}

TEST(OutputFile, SigkillWhileWritingLeavesTheOldFileAndNothingElse) {
  ScratchDir d;
  const std::string p = d / "out.txt";
  put(p, "old\n");
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {  // child: half a file written, then killed without any chance to clean up
    hal::OutputFile f;
    if (!f.open(p)) ::_exit(2);
    std::string big(300000, 'x');
    (void)f.write(big);
    (void)f.flush();
    ::raise(SIGKILL);
    ::_exit(3);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << status;
  EXPECT_EQ(slurp(p), "old\n");
  EXPECT_EQ(std::distance(fs::directory_iterator(d.path), fs::directory_iterator{}), 1);  // no temporary
}

TEST(OutputFile, AbortAndDestructorLeaveTheOldFileAndNoTemporary) {
  ScratchDir d;
  const std::string p = d / "out.txt";
  put(p, "old\n");
  {
    hal::OutputFile f;
    ASSERT_TRUE(f.open(p));
    f.stream() << "half a file";
  }  // destroyed without commit (an exception, an early return)
  EXPECT_EQ(slurp(p), "old\n");
  EXPECT_EQ(temporaries_in(d.path), 0);
  const std::string q = d / "new.txt";
  {
    hal::OutputFile f;
    ASSERT_TRUE(f.open(q));
    f.write("x");
    f.abort();
  }
  EXPECT_FALSE(fs::exists(q));
}

TEST(OutputFile, FullDeviceIsAnErrorNamingTheFileAndErrno) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  hal::OutputFile f;
  ASSERT_TRUE(f.open("/dev/full"));  // a device: written in place
  std::string big(200000, 'x');      // more than the 64 KiB buffer: the write itself fails
  EXPECT_FALSE(f.write(big));
  EXPECT_FALSE(f.commit());
  EXPECT_NE(f.error().find("/dev/full"), std::string::npos) << f.error();
  EXPECT_NE(f.error().find("No space left on device"), std::string::npos) << f.error();
  hal::OutputFile g;  // a small output fails at commit (the final flush)
  ASSERT_TRUE(g.open("/dev/full"));
  EXPECT_TRUE(g.write("small"));
  EXPECT_FALSE(g.commit());
  EXPECT_NE(g.error().find("No space left on device"), std::string::npos) << g.error();
}

TEST(OutputFile, LinkIsFollowedAndKeptAsALink) {
  ScratchDir d;
  const std::string real = d / "real.txt", link = d / "link.txt";
  put(real, "old\n");
  fs::create_symlink(real, link);
  std::string err;
  ASSERT_TRUE(hal::write_file_atomic(link, "new\n", err)) << err;
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(slurp(real), "new\n");
}

TEST(OutputFile, DirectoryOrMissingParentIsRefused) {
  ScratchDir d;
  hal::OutputFile f;
  EXPECT_FALSE(f.open(d.path));
  EXPECT_NE(f.error().find("is a directory"), std::string::npos);
  EXPECT_FALSE(f.open(d / "no/such/dir/x.csv"));
  EXPECT_NE(f.error().find("No such file or directory"), std::string::npos) << f.error();
}

TEST(OutputFile, ModeOfAReplacedFileIsKept) {
  ScratchDir d;
  const std::string p = d / "x.sh";
  put(p, "a");
  ::chmod(p.c_str(), 0750);
  std::string err;
  ASSERT_TRUE(hal::write_file_atomic(p, "b", err));
  struct stat st {};
  ASSERT_EQ(::stat(p.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0750u);
}

TEST(CheckOutputs, OutputThatIsAnInputIsRefused) {
  ScratchDir d;
  const std::string in = d / "in.lcmlog", link = d / "alias.lcmlog", hard = d / "hard.lcmlog";
  put(in, "data");
  fs::create_symlink(in, link);
  fs::create_hard_link(in, hard);
  EXPECT_NE(hal::check_outputs({in}, {in}).find("is the input"), std::string::npos);
  EXPECT_NE(hal::check_outputs({link}, {in}).find("is the input"), std::string::npos);
  EXPECT_NE(hal::check_outputs({hard}, {in}).find("is the input"), std::string::npos);
  EXPECT_NE(hal::check_outputs({d.path + "/./in.lcmlog"}, {in}).find("is the input"), std::string::npos);
  EXPECT_NE(hal::check_outputs({d / "sub/x.csv"}, {d.path}).find("inside the input directory"), std::string::npos);
  EXPECT_NE(hal::check_outputs({d / "a.json", d / "a.json"}, {}).find("are the same file"), std::string::npos);
  EXPECT_EQ(hal::check_outputs({d / "new.csv", ""}, {in, ""}), "");
  EXPECT_EQ(slurp(in), "data");
}

// ---- bounded readers ----

TEST(InputFile, EndlessAndNonRegularInputsAreRefused) {
  EXPECT_NE(hal::check_input_file("/dev/zero", hal::kMaxTextInputBytes).find("character device"), std::string::npos);
  EXPECT_NE(hal::check_input_file("/tmp", hal::kMaxTextInputBytes).find("directory"), std::string::npos);
  EXPECT_NE(hal::check_input_file("/nonexistent/x", 1).find("No such file"), std::string::npos);
  ScratchDir d;
  put(d / "big", std::string(100, 'x'));
  EXPECT_NE(hal::check_input_file(d / "big", 10).find("above this reader's limit"), std::string::npos);
  EXPECT_EQ(hal::check_input_file(d / "big", 100), "");
  const std::string fifo = d / "fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_NE(hal::check_input_file(fifo, 100).find("FIFO"), std::string::npos);
  // The simulator's text reader (scenario, almanac, profile, filter configuration).
  EXPECT_FALSE(cfg::read_text_file("/dev/zero").has_value());
  EXPECT_FALSE(cfg::read_text_file(fifo).has_value());  // would block for ever if opened
  EXPECT_NE(cfg::text_file_problem("/dev/zero").find("not a regular file"), std::string::npos);
  const sim::AlmanacParseResult a = sim::parse_yuma_file("/dev/zero");
  EXPECT_FALSE(a.ok());
  EXPECT_NE(a.error.find("not a regular file"), std::string::npos) << a.error;
}

TEST(InputFile, OverlongImporterLineIsBoundedAndCounted) {
  std::string text = "1.0,0,0,0,0,0,1000\n";
  text += std::string(1u << 20, '9') + "\n";  // a 1 MiB line
  for (int k = 2; k <= 6; ++k) text += "1.0,0,0,0,0,0," + std::to_string(1000 + 10 * k) + "\n";
  std::istringstream in(text);
  tools::LineStats st;
  const auto v = tools::read_gnss_imu_csv(in, st);
  EXPECT_EQ(v.size(), 6u);
  EXPECT_EQ(st.rejected, 1u);
}

// ---- time tags ----

namespace {
struct GateRun {
  std::vector<double> accepted, rejected;
};
GateRun run_gate(const std::vector<double>& t, const hal::TimeTagGateConfig& cfg) {
  GateRun r;
  hal::TimeTagFilter<double> f(cfg);
  for (double x : t)
    f.push(x, x, [&](double&& a) { r.accepted.push_back(a); }, [&](double&& a, hal::TimeTagRejection) { r.rejected.push_back(a); });
  f.finish([&](double&& a) { r.accepted.push_back(a); }, [&](double&& a, hal::TimeTagRejection) { r.rejected.push_back(a); });
  return r;
}
std::vector<double> ramp(double t0, int n, double dt = 0.01) {
  std::vector<double> v;
  for (int k = 0; k < n; ++k) v.push_back(t0 + k * dt);
  return v;
}
}  // namespace

TEST(TimeTagGate, OneOutlierCostsOnlyItself) {
  for (double wild : {1e9, -1e9, 100.0, -5.0, 1e300}) {
    std::vector<double> t = ramp(0.0, 50);
    t.insert(t.begin() + 20, wild);
    const GateRun r = run_gate(t, {});
    EXPECT_EQ(r.accepted.size(), 50u) << wild;
    ASSERT_EQ(r.rejected.size(), 1u) << wild;
    EXPECT_EQ(r.rejected[0], wild);
  }
}

TEST(TimeTagGate, OutlierAtTheStartOrTheEnd) {
  std::vector<double> t = ramp(0.0, 30);
  t.insert(t.begin(), 5e5);  // first sample wild: no base yet
  GateRun r = run_gate(t, {});
  EXPECT_EQ(r.accepted.size(), 30u);
  EXPECT_EQ(r.rejected.size(), 1u);
  t = ramp(0.0, 30);
  t.push_back(5e5);  // last sample wild: unconfirmed
  r = run_gate(t, {});
  EXPECT_EQ(r.accepted.size(), 30u);
  EXPECT_EQ(r.rejected.size(), 1u);
}

TEST(TimeTagGate, OutlierAmongTheFirstTagsKeepsTheFirstTags) {
  std::vector<double> t = ramp(0.0, 3);
  t.push_back(-1e6);  // before any base: the three agreeing tags win
  for (double x : ramp(0.03, 10)) t.push_back(x);
  const GateRun r = run_gate(t, {});
  EXPECT_EQ(r.accepted.size(), 13u);
  ASSERT_EQ(r.rejected.size(), 1u);
  EXPECT_EQ(r.rejected[0], -1e6);
  // A stream shorter than confirm_samples with a backward step at the end keeps its first tags.
  hal::TimeTagGateConfig strict;
  strict.strictly_increasing = true;
  strict.max_backward_s = 0.0;
  const GateRun s = run_gate({10.0, 11.0, 12.0, 9.0}, strict);
  EXPECT_EQ(s.accepted.size(), 3u);
  EXPECT_EQ(s.rejected.size(), 1u);
}

TEST(TimeTagGate, SustainedJumpIsANewTimeBaseAndLosesNothing) {
  std::vector<double> t = ramp(0.0, 30);
  for (double x : ramp(1000.0, 30)) t.push_back(x);
  hal::TimeTagFilter<double> f;
  std::vector<double> acc;
  for (double x : t) f.push(x, x, [&](double&& a) { acc.push_back(a); }, [](double&&, hal::TimeTagRejection) {});
  f.finish([&](double&& a) { acc.push_back(a); }, [](double&&, hal::TimeTagRejection) {});
  EXPECT_EQ(acc, t);  // all 60, in order
  EXPECT_EQ(f.stats().new_bases, 1u);
  EXPECT_NEAR(f.stats().last_new_base_jump_s, 1000.0 - 0.29, 1e-9);
  EXPECT_EQ(f.stats().last_new_base_at_s, 1000.0);
}

TEST(TimeTagGate, TwoOutliersInARowAndStrictOrder) {
  std::vector<double> t = ramp(0.0, 40);
  t.insert(t.begin() + 10, {700.0, 700.01});  // two agreeing wild samples: fewer than confirm_samples
  hal::TimeTagGateConfig cfg;
  cfg.strictly_increasing = true;
  GateRun r = run_gate(t, cfg);
  EXPECT_EQ(r.accepted.size(), 40u);
  EXPECT_EQ(r.rejected.size(), 2u);
  t = ramp(0.0, 10);
  t.insert(t.begin() + 5, t[4]);  // a repeated tag: rejected on its own
  r = run_gate(t, cfg);
  EXPECT_EQ(r.accepted.size(), 10u);
  EXPECT_EQ(r.rejected.size(), 1u);
}

namespace {
hal::ImuRecord imu_at(int k) {
  hal::ImuRecord r;
  r.sample.t_s = 0.005 * (k + 1);
  r.sample.dt_s = 0.005;
  r.sample.dv_mps = fsw::Vec3(0.0, 0.0, -9.80665 * 0.005);
  r.counter = k;
  return r;
}
}  // namespace

// The issue's case: one far-ahead IMU time tag made the reorder logic drop the rest of the log.
TEST(TimeTagGate, ReplayKeepsTheLogAfterOneFarAheadSample) {
  const std::string path = lcm_test::scratch("faults_far_ahead.lcmlog");
  ASSERT_NO_FATAL_FAILURE(lcm_test::write_imu_log(path, 2000, [](int k) {
    hal::ImuRecord r = imu_at(k);
    if (k == 400) r.sample.t_s += 50.0;  // 50 s ahead
    return r;
  }));
  hal::LcmReplayReader rd;
  const std::vector<double> t = lcm_test::replayed_times(rd, path);
  EXPECT_EQ(t.size(), 1999u);  // every good sample
  EXPECT_TRUE(std::is_sorted(t.begin(), t.end()));
  EXPECT_EQ(rd.stats().time_tag_rejected, 1u);
  EXPECT_EQ(rd.stats().out_of_order, 0u);
  EXPECT_EQ(rd.stats().time_base_changes, 0u);
  std::remove(path.c_str());
}

TEST(TimeTagGate, ImporterOneTickJumpCostsOneLine) {
  std::string text;
  for (int k = 0; k < 100; ++k) text += "0.0,0.0,1.0,0.1,0.2,0.3," + std::to_string(k == 37 ? 99999999 : 5000 + 10 * k) + "\n";
  std::istringstream in(text);
  tools::LineStats st;
  const auto v = tools::read_gnss_imu_csv(in, st);
  EXPECT_EQ(v.size(), 99u);
  EXPECT_EQ(st.rejected, 1u);
  EXPECT_EQ(st.examples.at(0).first, 38u);
  EXPECT_EQ(st.time_base_changes, 0u);
  // PSINS IMU: a time of week 1000 s ahead in the middle of a 200 Hz stream.
  std::string csv = "tow,gx,gy,gz,ax,ay,az\n";
  for (int k = 0; k < 100; ++k) {
    char b[128];
    std::snprintf(b, sizeof b, "%.3f,0,0,0,0,0,0\n", k == 50 ? 91000.0 : 90000.0 + 0.005 * k);
    csv += b;
  }
  std::istringstream pin(csv);
  tools::LineStats pst;
  EXPECT_EQ(tools::read_psins_imu(pin, pst).size(), 99u);
  EXPECT_EQ(pst.rejected, 1u);
}

// ---- almanac: one validation for the simulator and the flight software ----

TEST(AlmanacValidation, SimulatorRefusesWhatTheFlightSoftwareRefuses) {
  const auto record = [](const std::string& sqrt_a, const std::string& af0) {
    return "******** Week 100 almanac for PRN-01 ********\n"
           "ID:                         01\n"
           "Health:                     000\n"
           "Eccentricity:               0.5E-002\n"
           "Time of Applicability(s):  405504.0000\n"
           "Orbital Inclination(rad):   0.97\n"
           "Rate of Right Ascen(r/s):  -0.78E-008\n"
           "SQRT(A)  (m 1/2):           " + sqrt_a + "\n"
           "Right Ascen at Week(rad):   0.1\n"
           "Argument of Perigee(rad):   0.2\n"
           "Mean Anom(rad):             0.3\n"
           "Af0(s):                     " + af0 + "\n"
           "Af1(s/s):                   0.0\n"
           "week:                        100\n\n";
  };
  EXPECT_TRUE(sim::parse_yuma_text(record("5153.6", "1e-4"), "x").ok());
  for (const auto& [sa, af0, field] : std::vector<std::tuple<std::string, std::string, std::string>>{
           {"1e30", "1e-4", "sqrt(A)"}, {"5153.6", "1e6", "af0"}, {"1.0", "0", "sqrt(A)"}}) {
    const sim::AlmanacParseResult r = sim::parse_yuma_text(record(sa, af0), "bad.alm");
    ASSERT_FALSE(r.ok()) << sa << " " << af0;
    EXPECT_NE(r.error.find(field), std::string::npos) << r.error;
    EXPECT_NE(r.error.find("bad.alm"), std::string::npos) << r.error;
  }
  fsw::GpsAlmanac a;
  a.prn = 1;
  a.sqrt_a_sqrtm = 1e30;
  EXPECT_STREQ(fsw::almanac_invalid_field(a), "sqrt(A)");
  EXPECT_FALSE(fsw::almanac_valid(a));
}

// ---- second pass (issue 30): players, recorders, run directories, counted drops, bus scope ----

TEST(CandumpPacer, OneWildTimestampCostsNoSleepAndNoFrame) {
  hal::CandumpPacer p;
  std::vector<std::pair<double, double>> out;  // (log time, play time)
  const auto drain = [&] {
    hal::CanFrame f;
    double play = 0.0;
    while (p.pop(f, play)) out.emplace_back(f.timestamp_s, play);
  };
  for (int k = 0; k < 200; ++k) {
    hal::CanFrame f;
    f.id = 0x10;
    f.len = 8;
    f.timestamp_s = 1000.0 + 0.005 * k + (k == 100 ? 86400.0 : 0.0);  // one a day ahead
    p.push(f);
    drain();
  }
  p.finish();
  drain();
  ASSERT_EQ(out.size(), 200u);  // every frame sent
  EXPECT_EQ(p.stats().outliers, 1u);
  EXPECT_NEAR(out.back().second, 0.005 * 199, 1e-9);  // the log's own play time: the outlier moved nothing
  for (std::size_t i = 1; i < out.size(); ++i) EXPECT_GE(out[i].second, out[i - 1].second);
  EXPECT_DOUBLE_EQ(out[100].first, 1000.0 + 0.5 + 86400.0);  // in log order
}

TEST(CandumpPacer, NewTimeBaseIsAStepOfZero) {
  hal::CandumpPacer p;
  double last_play = 0.0;
  int n = 0;
  for (int k = 0; k < 100; ++k) {
    hal::CanFrame f;
    f.id = 0x10;
    f.len = 8;
    f.timestamp_s = 10.0 + 0.01 * k + (k >= 50 ? 3600.0 : 0.0);
    p.push(f);
    hal::CanFrame g;
    while (p.pop(g, last_play)) ++n;
  }
  p.finish();
  hal::CanFrame g;
  while (p.pop(g, last_play)) ++n;
  EXPECT_EQ(n, 100);
  EXPECT_EQ(p.stats().new_bases, 1u);
  EXPECT_NEAR(last_play, 0.01 * 98, 1e-9);
}

TEST(CanBusStop, AStopFlagEndsTheWaitAtOnce) {
  hal::CanBus bus;
  ASSERT_EQ(bus.open("loop:stop-test"), hal::CanBusStatus::kOk);
  std::atomic<bool> stop{false};
  std::thread t([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    stop = true;
  });
  const auto t0 = std::chrono::steady_clock::now();
  hal::CanFrame f;
  EXPECT_EQ(bus.receive(f, 60.0, stop), hal::CanBusStatus::kStopped);
  t.join();
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 1.0);
  stop = false;
  EXPECT_EQ(bus.receive(f, 0.05, stop), hal::CanBusStatus::kTimeout);  // no flag: the timeout as before
}

TEST(RunDirectory, AReRunRemovesItsStaleOutputsAndNothingElse) {
  const ScratchDir d;
  const std::string dir = d / "run";
  {
    tools::RunDirectory r(dir);
    tools::write_text_file(r.path("a.csv"), "a\n");
    tools::write_text_file(r.path("b.csv"), "b\n");
    r.finish({{"command", "test"}});
    EXPECT_EQ(r.outputs(), (std::vector<std::string>{"a.csv", "b.csv"}));
  }
  put(dir + "/mine.txt", "the user's\n");
  {
    tools::RunDirectory r(dir);
    EXPECT_FALSE(fs::exists(dir + "/summary.json"));  // removed when the run starts
    tools::write_text_file(r.path("b.csv"), "b2\n");
    r.finish({{"command", "test"}});
    EXPECT_EQ(r.removed(), (std::vector<std::string>{"a.csv"}));
  }
  EXPECT_FALSE(fs::exists(dir + "/a.csv"));
  EXPECT_EQ(slurp(dir + "/b.csv"), "b2\n");
  EXPECT_EQ(slurp(dir + "/mine.txt"), "the user's\n");
  std::ifstream in(dir + "/summary.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["outputs"], nlohmann::json::array({"b.csv"}));
  // A manifest naming a path outside the directory is not followed.
  put(d / "outside.txt", "keep\n");
  put(dir + "/.sdins-outputs.json", R"({"files": ["../outside.txt", "/etc/hostname", "b.csv"]})");
  {
    tools::RunDirectory r(dir);
    r.finish({{"command", "test"}});
  }
  EXPECT_EQ(slurp(d / "outside.txt"), "keep\n");
  EXPECT_FALSE(fs::exists(dir + "/b.csv"));  // listed, not written again: stale
  // A run that does not finish (an error, SIGINT) lists what it wrote; the next complete run
  // removes it when it does not write it again.
  {
    tools::RunDirectory r(dir);
    tools::write_text_file(r.path("c.csv"), "c\n");
  }
  EXPECT_FALSE(fs::exists(dir + "/summary.json"));
  {
    tools::RunDirectory r(dir);
    r.finish({{"command", "test"}});
    EXPECT_EQ(r.removed(), (std::vector<std::string>{"c.csv"}));
  }
  EXPECT_FALSE(fs::exists(dir + "/c.csv"));
  EXPECT_EQ(slurp(dir + "/mine.txt"), "the user's\n");
}

TEST(LcmInputCheck, NanPseudorangesAreCountedByTheTypeTable) {
  sdins::gnss_raw_epoch_t m{};
  m.t_s = 10.0;
  m.gps_tow_s = 1000.0;
  m.gps_week = 2200;
  m.n_meas = 3;
  for (int i = 0; i < 3; ++i) {
    m.meas[i].prn = i + 1;
    m.meas[i].pseudorange_m = 2.1e7 + i;
    m.meas[i].pseudorange_rate_mps = 1.0;
    m.meas[i].cn0_dbhz = 45.0;
  }
  m.meas[1].pseudorange_m = std::nan("");
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  ASSERT_GT(m.encode(buf.data(), 0, static_cast<int>(buf.size())), 0);
  const hal::LcmTypeInfo* t = hal::lcm_channel_type("GNSS_RAW");
  ASSERT_NE(t, nullptr);
  ASSERT_NE(t->input, nullptr);
  int dropped = 0;
  EXPECT_EQ(t->input(buf.data(), buf.size(), dropped), hal::LcmInputStatus::kMeasurementsDropped);
  EXPECT_EQ(dropped, 1);
  EXPECT_EQ(hal::lcm_channel_type("NAV_SOLUTION")->input, nullptr);  // an output type
}

TEST(UdpScope, LocalByDefaultLanOnlyWhenAsked) {
  hal::UdpAddress a;
  std::string why;
  ASSERT_TRUE(hal::parse_udp_address("43113", a, why)) << why;
  EXPECT_FALSE(a.lan);
  ASSERT_TRUE(hal::parse_udp_address("239.74.163.2:43113?scope=lan", a, why)) << why;
  EXPECT_TRUE(a.lan);
  EXPECT_EQ(a.group, "239.74.163.2");
  ASSERT_TRUE(hal::parse_udp_address("[ff15::1]:43113?scope=lan&iface=lo", a, why)) << why;
  EXPECT_EQ(a.iface, "lo");
  EXPECT_NE(a.iface_index, 0u);
  ASSERT_TRUE(hal::parse_udp_address("43113?scope=local", a, why)) << why;
  EXPECT_FALSE(a.lan);
  for (const char* bad : {"43113?scope=world", "43113?ttl=1", "43113?iface=lo", "43113?scope=lan&iface=nosuch9"}) {
    EXPECT_FALSE(hal::parse_udp_address(bad, a, why)) << bad;
    EXPECT_FALSE(why.empty());
  }
}
