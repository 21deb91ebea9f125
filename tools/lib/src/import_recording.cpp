// The import drivers of `sdins import` (tools/importers.hpp): find a recording's files, read them,
// convert them to the project's inputs on one time scale, write the LCM log, summarise.
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "hal/input_file.hpp"
#include "hal/lcm_channels.hpp"
#include "hal/lcm_log_sink.hpp"
#include "tools/importers.hpp"

extern char** environ;

namespace tools {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// What goes into the log

enum class EventKind : int { kAlmanac = 0, kImu = 1, kGnssRaw = 2, kGnssPvt = 3, kTruth = 4 };

struct TimedAlmanac {
  double t_s;  ///< when it is written (-inf: at the start of the log)
  fsw::GpsAlmanac almanac;
};

struct Collected {
  std::vector<TimedAlmanac> almanacs;  ///< the first set at the earliest time of the log, updates later
  std::vector<hal::ImuRecord> imu;
  std::vector<fsw::GnssRawEpoch> raw;
  std::vector<hal::GnssPvtSample> pvt;
  std::vector<hal::GnssPvtSample> truth;  ///< reference epochs (RTK solution), position and velocity only
};

struct Event {
  double t_s;
  EventKind kind;
  std::size_t idx;
};

nlohmann::json write_log(const std::string& path, const Collected& c) {
  std::vector<Event> ev;
  ev.reserve(c.imu.size() + c.raw.size() + c.pvt.size() + c.truth.size() + c.almanacs.size());
  double t0 = INFINITY;
  for (std::size_t i = 0; i < c.imu.size(); ++i) ev.push_back({c.imu[i].sample.t_s, EventKind::kImu, i});
  for (std::size_t i = 0; i < c.raw.size(); ++i) ev.push_back({c.raw[i].t_s, EventKind::kGnssRaw, i});
  for (std::size_t i = 0; i < c.pvt.size(); ++i) ev.push_back({c.pvt[i].t_s, EventKind::kGnssPvt, i});
  for (std::size_t i = 0; i < c.truth.size(); ++i) ev.push_back({c.truth[i].t_s, EventKind::kTruth, i});
  for (const Event& e : ev) t0 = std::min(t0, e.t_s);
  if (!std::isfinite(t0)) t0 = 0.0;
  for (std::size_t i = 0; i < c.almanacs.size(); ++i)
    ev.push_back({std::max(t0, c.almanacs[i].t_s), EventKind::kAlmanac, i});
  // Time order; at equal times: almanac, IMU (the sample ending at t), raw epoch, solution, reference.
  std::stable_sort(ev.begin(), ev.end(), [](const Event& a, const Event& b) {
    if (a.t_s != b.t_s) return a.t_s < b.t_s;
    return static_cast<int>(a.kind) < static_cast<int>(b.kind);
  });

  hal::LcmLogSink sink;
  hal::LcmTelemetryConfig cfg;
  cfg.lcm_url = "none";
  cfg.log_path = path;
  if (sink.open(cfg) != hal::LcmLogStatus::kOk)
    throw std::runtime_error("cannot create the log " + sink.telemetry().log().error());
  std::map<std::string, std::uint64_t> per_channel;
  std::uint64_t failures = 0;
  for (const Event& e : ev) {
    hal::LcmLogStatus st = hal::LcmLogStatus::kOk;
    const char* ch = "";
    switch (e.kind) {
      case EventKind::kAlmanac: st = sink.write_almanac(c.almanacs[e.idx].almanac, e.t_s); ch = hal::kLcmChannelGpsAlmanac; break;
      case EventKind::kImu: st = sink.write_imu(c.imu[e.idx]); ch = hal::kLcmChannelImu; break;
      case EventKind::kGnssRaw: st = sink.write_gnss(c.raw[e.idx]); ch = hal::kLcmChannelGnssRaw; break;
      case EventKind::kGnssPvt: st = sink.write_pvt(c.pvt[e.idx]); ch = hal::kLcmChannelGnssPvt; break;
      case EventKind::kTruth: {
        const hal::GnssPvtSample& p = c.truth[e.idx];
        const fsw::Vec3 v = p.has_velocity() ? p.vel_enu_mps : fsw::Vec3::Constant(std::nan(""));
        st = sink.write_reference(p.t_s, p.llh, v);
        ch = hal::kLcmChannelTruth;
        break;
      }
    }
    if (st != hal::LcmLogStatus::kOk)
      ++failures;
    else
      ++per_channel[ch];
  }
  if (failures > 0) {
    // docs/faults.md: an incomplete log is not put in place (the target keeps its old contents).
    const std::string why = sink.telemetry().log().error();
    sink.telemetry().abort_log();
    throw std::runtime_error("writing " + path + " failed (" + std::to_string(failures) + " events could not be written" +
                             (why.empty() ? "" : ": " + why) + "); nothing written");
  }
  if (sink.close() != hal::LcmLogStatus::kOk)
    throw std::runtime_error("writing failed: " + sink.telemetry().log().error() + "; nothing written");
  return {{"path", path}, {"events", ev.size()}, {"per_channel", per_channel}};
}

// ---------------------------------------------------------------------------------------------
// Summaries

nlohmann::json span_json(double t_first, double t_last, std::size_t n) {
  nlohmann::json j;
  if (n == 0) return {{"count", 0}};
  j["count"] = n;
  j["t_first_s"] = t_first;
  j["t_last_s"] = t_last;
  j["span_s"] = t_last - t_first;
  j["rate_hz"] = (n > 1 && t_last > t_first) ? static_cast<double>(n - 1) / (t_last - t_first) : 0.0;
  return j;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

/// IMU records through the IMU input validation (what `sdins replay` would reject is not written),
/// then the time statistics.
nlohmann::json finish_imu(std::vector<hal::ImuRecord>& imu, LineStats& lines, const AxisMap& axes) {
  std::vector<hal::ImuRecord> kept;
  kept.reserve(imu.size());
  std::uint64_t rejected = 0;
  for (const hal::ImuRecord& r : imu) {
    sdins::imu_sample_t m{};
    hal::to_msg(r, m);
    hal::ImuRecord back;
    const hal::LcmInputStatus st = hal::from_msg(m, back);
    if (st != hal::LcmInputStatus::kOk) {
      lines.reject(static_cast<std::uint64_t>(r.counter) + 1, std::string("IMU input validation: ") + hal::to_string(st));
      --lines.accepted;
      ++rejected;
      continue;
    }
    kept.push_back(r);
  }
  imu.swap(kept);
  nlohmann::json j = {{"lines", lines.to_json()}, {"axes", axes.text()}};
  if (imu.empty()) {
    j["samples"] = span_json(0, 0, 0);
    return j;
  }
  j["samples"] = span_json(imu.front().sample.t_s, imu.back().sample.t_s, imu.size());
  std::vector<double> dts;
  dts.reserve(imu.size());
  for (const hal::ImuRecord& r : imu) dts.push_back(r.sample.dt_s);
  const double med = median(dts);
  std::uint64_t gaps = 0;
  for (double d : dts) gaps += d > 1.5 * med ? 1 : 0;
  j["dt_s"] = {{"min", *std::min_element(dts.begin(), dts.end())},
               {"median", med},
               {"max", *std::max_element(dts.begin(), dts.end())}};
  j["gaps"] = gaps;  // intervals longer than 1.5 median intervals
  // Mean specific force and rate over the first second (body axes): at rest f is about (0, 0, -g)
  // when the axis map is right (z down).
  fsw::Vec3 dv = fsw::Vec3::Zero(), dth = fsw::Vec3::Zero();
  double T = 0.0;
  for (const hal::ImuRecord& r : imu) {
    if (r.sample.t_s - imu.front().sample.t_s > 1.0) break;
    dv += r.sample.dv_mps;
    dth += r.sample.dtheta_rad;
    T += r.sample.dt_s;
  }
  if (T > 0.0) {
    const fsw::Vec3 f = dv / T, w = dth / T;
    j["first_second_mean_f_body_mps2"] = {f.x(), f.y(), f.z()};
    j["first_second_mean_omega_body_dps"] = {w.x() * fsw::kRadToDeg, w.y() * fsw::kRadToDeg, w.z() * fsw::kRadToDeg};
  }
  return j;
}

nlohmann::json pvt_json(const std::vector<hal::GnssPvtSample>& pvt, const LineStats& lines, const std::string& file) {
  nlohmann::json j = {{"file", file}, {"lines", lines.to_json()}};
  j["samples"] = pvt.empty() ? span_json(0, 0, 0) : span_json(pvt.front().t_s, pvt.back().t_s, pvt.size());
  std::map<std::string, std::uint64_t> q;
  for (const hal::GnssPvtSample& p : pvt) ++q[std::to_string(p.quality)];
  j["by_quality"] = q;
  return j;
}

// ---------------------------------------------------------------------------------------------
// Almanac from broadcast ephemeris

/// The almanac model has no harmonic corrections, so a fit is exact only over a limited arc (the
/// error grows with the square of the arc: about 10 m over 30 min, 5 cm over 2.5 min). The window
/// [first, first + span_s] is therefore split into 1, 2, 4, ... equal segments (each at least
/// kMinSegment_s) until every observed PRN's fit is within max_err_m (position + clock); each
/// segment's almanacs are written at the segment's start (the flight software replaces a PRN's
/// elements when new ones arrive), fitted over the segment +-10 s. A PRN whose fit is still worse
/// at the finest segmentation is not written (listed in fit_rejected).
nlohmann::json almanacs_from_ephemeris(const std::vector<GpsEphemeris>& ephs, const std::set<int>& observed,
                                       const GpsTime& first, double first_t_s, double span_s, double max_err_m,
                                       std::vector<TimedAlmanac>& out) {
  constexpr double kMargin = 10.0;
  constexpr double kMinSegment_s = 30.0;
  std::vector<int> without;
  std::map<int, const GpsEphemeris*> any;
  for (int prn : observed) {
    for (const GpsEphemeris& e : ephs)
      if (e.prn == prn) any[prn] = &e;
    if (any.find(prn) == any.end()) without.push_back(prn);
  }
  struct PrnResult {
    double max_pos = 0, rms_pos = 0, max_clock = 0, max_vel = 0;
    bool ok = true;
    std::set<int> iodes;
  };
  std::map<int, PrnResult> res;
  std::vector<TimedAlmanac> fitted;
  int segments = 1;
  for (;; segments *= 2) {
    const double seg = span_s / segments;
    res.clear();
    fitted.clear();
    for (int k = 0; k < segments; ++k) {
      const double seg_tow = first.tow_s + seg * k;
      const double centre = seg_tow + 0.5 * seg;
      for (const auto& [prn, unused] : any) {
        (void)unused;
        const GpsEphemeris* best = nullptr;
        const auto score = [&](const GpsEphemeris& x) {
          return std::abs(ephemeris_tk_s(x, first.week, centre)) + (x.health != 0 ? 1e9 : 0.0);
        };
        for (const GpsEphemeris& e : ephs)
          if (e.prn == prn && (best == nullptr || score(e) < score(*best))) best = &e;
        const AlmanacFit f = fit_almanac(*best, first.week, seg_tow - kMargin, seg + 2.0 * kMargin);
        sdins::gps_almanac_t m{};
        hal::to_msg(f.almanac, 0.0, m);
        fsw::GpsAlmanac check;
        const bool valid = hal::from_msg(m, check) == hal::LcmInputStatus::kOk;
        PrnResult& r = res[prn];
        r.max_pos = std::max(r.max_pos, f.max_pos_err_m);
        r.rms_pos = std::max(r.rms_pos, f.rms_pos_err_m);
        r.max_clock = std::max(r.max_clock, f.max_clock_err_m);
        r.max_vel = std::max(r.max_vel, f.max_vel_err_mps);
        r.iodes.insert(best->iode);
        const bool ok = f.converged && valid && f.max_range_err_m() <= max_err_m;
        r.ok = r.ok && ok;
        fitted.push_back({k == 0 ? -INFINITY : first_t_s + seg * k, f.almanac});
      }
    }
    bool all_ok = true;
    for (const auto& [prn, r] : res) all_ok = all_ok && r.ok;
    if (all_ok || span_s / (2 * segments) < kMinSegment_s) break;
  }
  std::vector<int> written, rejected;
  nlohmann::json fits = nlohmann::json::array();
  for (const auto& [prn, r] : res) {
    fits.push_back({{"prn", prn},
                    {"iode", std::vector<int>(r.iodes.begin(), r.iodes.end())},
                    {"max_pos_err_m", r.max_pos},
                    {"rms_pos_err_m", r.rms_pos},
                    {"max_clock_err_m", r.max_clock},
                    {"max_vel_err_mps", r.max_vel},
                    {"written", r.ok}});
    (r.ok ? written : rejected).push_back(prn);
  }
  for (const TimedAlmanac& a : fitted)
    if (res[a.almanac.prn].ok) out.push_back(a);
  return {{"source", "broadcast ephemeris fitted to the almanac model (tools/gps_ephemeris.hpp)"},
          {"max_fit_error_m", max_err_m},
          {"segments", segments},
          {"segment_s", span_s / segments},
          {"messages", out.size()},
          {"written", written},
          {"observed_without_ephemeris", without},
          {"fit_rejected", rejected},
          {"fits", fits}};
}

// ---------------------------------------------------------------------------------------------
// Raw epochs

struct RawCounts {
  std::uint64_t epochs_in = 0, non_gps = 0, no_pseudorange = 0, no_doppler = 0, bad_pseudorange = 0, over_16 = 0,
                duplicate_prn = 0, empty_epochs = 0, measurements = 0;
  std::set<int> prns;
  nlohmann::json to_json() const {
    return {{"epochs_read", epochs_in},
            {"measurements", measurements},
            {"satellites", std::vector<int>(prns.begin(), prns.end())},
            {"skipped",
             {{"non_gps_observations", non_gps},
              {"gps_without_pseudorange", no_pseudorange},
              {"gps_without_doppler", no_doppler},
              {"pseudorange_outside_1e7_5e7_m", bad_pseudorange},
              {"duplicate_prn", duplicate_prn},
              {"beyond_16_per_epoch", over_16},
              {"epochs_without_gps", empty_epochs}}}};
  }
};

struct RawMeas {
  int prn;
  double pr, prr, cn0;
};

/// One epoch from measurements (at most 16, the strongest first when there are more).
bool make_epoch(double t_s, const GpsTime& t, std::vector<RawMeas> m, RawCounts& c, fsw::GnssRawEpoch& e) {
  std::set<int> seen;
  std::vector<RawMeas> u;
  for (const RawMeas& x : m) {
    if (!seen.insert(x.prn).second) {
      ++c.duplicate_prn;
      continue;
    }
    u.push_back(x);
  }
  if (u.size() > static_cast<std::size_t>(fsw::kMaxGnssChannels)) {
    std::stable_sort(u.begin(), u.end(), [](const RawMeas& a, const RawMeas& b) { return a.cn0 > b.cn0; });
    c.over_16 += u.size() - fsw::kMaxGnssChannels;
    u.resize(fsw::kMaxGnssChannels);
  }
  if (u.empty()) {
    ++c.empty_epochs;
    return false;
  }
  e = fsw::GnssRawEpoch{};
  e.t_s = t_s;
  e.gps_week = t.week;
  e.gps_tow_s = t.tow_s;
  e.n_meas = static_cast<int>(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) {
    e.meas[k].prn = static_cast<std::uint8_t>(u[k].prn);
    e.meas[k].pseudorange_m = u[k].pr;
    e.meas[k].pseudorange_rate_mps = u[k].prr;
    e.meas[k].cn0_dbhz = u[k].cn0;
    c.prns.insert(u[k].prn);
  }
  c.measurements += u.size();
  return true;
}

nlohmann::json raw_span(const std::vector<fsw::GnssRawEpoch>& raw) {
  return raw.empty() ? span_json(0, 0, 0) : span_json(raw.front().t_s, raw.back().t_s, raw.size());
}

// ---------------------------------------------------------------------------------------------
// Files

std::vector<fs::path> files_with(const fs::path& dir, const std::string& suffix) {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string n = e.path().filename().string();
    if (e.is_regular_file() && n.size() > suffix.size() && n.compare(n.size() - suffix.size(), suffix.size(), suffix) == 0)
      out.push_back(e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::string names(const std::vector<fs::path>& v) {
  std::string s;
  for (const auto& p : v) s += (s.empty() ? "" : ", ") + p.filename().string();
  return s;
}

std::ifstream open_in(const fs::path& p) {
  // Bounded readers (docs/faults.md): regular files only, at most hal::kMaxRecordingInputBytes.
  const std::string bad = hal::check_input_file(p.string(), hal::kMaxRecordingInputBytes);
  if (!bad.empty()) throw std::runtime_error(bad);
  std::ifstream f(p, std::ios::binary);
  if (!f) throw std::runtime_error("cannot read " + p.string());
  return f;
}

/// A fresh temporary directory (removed by the caller unless kept).
fs::path make_temp_dir() {
  std::string tmpl = (fs::temp_directory_path() / "sdins_import_XXXXXX").string();
  if (::mkdtemp(tmpl.data()) == nullptr) throw std::runtime_error("cannot create a temporary directory " + tmpl);
  return fs::path(tmpl);
}

/// Runs a program (no shell), stdout and stderr to log_path; returns the exit status or -1.
int run_program(const std::vector<std::string>& argv, const std::string& log_path) {
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, args[0], &fa, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) return -1;
  int status = 0;
  if (::waitpid(pid, &status, 0) < 0) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const std::string& a : v) s += (s.empty() ? "" : " ") + a;
  return s;
}

struct TempDir {
  fs::path path;
  bool keep = false;
  ~TempDir() {
    std::error_code ec;
    if (!path.empty() && !keep) fs::remove_all(path, ec);
  }
};

// ---------------------------------------------------------------------------------------------
// rtklib

nlohmann::json import_rtklib(const ImportOptions& opt) {
  const fs::path in(opt.path);
  fs::path dir, pos;
  if (fs::is_directory(in)) {
    dir = in;
    const auto p = files_with(dir, ".pos");
    if (p.empty()) throw std::runtime_error("no RTKLIB solution (*.pos) in " + dir.string());
    if (p.size() > 1) throw std::runtime_error("several .pos files in " + dir.string() + " (" + names(p) + "): name one");
    pos = p.front();
  } else if (fs::is_regular_file(in) && in.extension() == ".pos") {
    pos = in;
    dir = in.parent_path().empty() ? fs::path(".") : in.parent_path();
  } else {
    throw std::runtime_error(opt.path + " is neither a directory nor a .pos file");
  }
  // The IMU log: a CSV with its .tag beside it.
  std::vector<fs::path> imu_csv, untagged;
  for (const fs::path& c : files_with(dir, ".csv"))
    (fs::exists(c.string() + ".tag") ? imu_csv : untagged).push_back(c);
  // docs/faults.md: an IMU log without its time tag is an error, not an import without the IMU.
  if (imu_csv.empty() && !untagged.empty())
    throw std::runtime_error("IMU CSV without its time-tag file in " + dir.string() + " (" + names(untagged) +
                             ": no " + untagged.front().filename().string() +
                             ".tag beside it): the IMU cannot be placed on GPS time");
  if (imu_csv.size() > 1) throw std::runtime_error("several IMU CSVs with a .tag in " + dir.string() + " (" + names(imu_csv) + ")");
  const auto ubx = files_with(dir, ".ubx");
  if (ubx.size() > 1) throw std::runtime_error("several .ubx files in " + dir.string() + " (" + names(ubx) + ")");

  const AxisMap axes = parse_axis_map(opt.axes.empty() ? kAxesGnssImu : opt.axes);
  nlohmann::json sum;
  sum["format"] = "rtklib";
  sum["input"] = opt.path;

  // Solutions.
  std::ifstream pf = open_in(pos);
  PosFile pf_data = read_rtklib_pos(pf);

  // IMU.
  std::vector<ImuCsvSample> imu_samples;
  LineStats imu_lines;
  TimeTag tag;
  TickToGps map;
  const bool have_imu = !imu_csv.empty();
  if (have_imu) {
    std::ifstream f = open_in(imu_csv.front());
    imu_samples = read_gnss_imu_csv(f, imu_lines);
    const std::string tag_path = imu_csv.front().string() + ".tag";
    tag = read_time_tag(tag_path);
    try {
      map = tick_to_gps(tag, imu_samples);
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(tag_path + ": " + e.what());
    }
    // docs/faults.md: the time base is checked, never guessed. The tag's span against the IMU's own
    // ticks (ms) must be a clock ratio, not a truncated CSV or a cut .tag stretching the samples.
    if (tag.non_monotonic > 0)
      throw std::runtime_error(tag_path + ": " + std::to_string(tag.non_monotonic) +
                               " records go backwards in tick or offset: a damaged time-tag file");
    if (imu_lines.time_base_changes > 0 && imu_lines.last_time_jump < 0.0)
      throw std::runtime_error(imu_csv.front().string() + ": the IMU tick goes back by " +
                               std::to_string(-imu_lines.last_time_jump) + " ms near line " +
                               std::to_string(imu_lines.last_time_jump_line) +
                               " and stays there (the IMU restarted): one .tag cannot place both parts on GPS time");
    const double ratio = map.seconds_per_tick * 1e3;
    const double imu_span_s = 1e-3 * static_cast<double>(imu_samples.back().tick_ms - imu_samples.front().tick_ms);
    const std::string why = tag_path + ": the last tag record is " + std::to_string(tag.last_tick_s()) +
                            " s after the start but the IMU's own ticks span " + std::to_string(imu_span_s) +
                            " s (ratio " + std::to_string(ratio) + ", beyond the " +
                            std::to_string(kMaxTagClockDeviation) +
                            " a clock drift can explain): a cut .tag or a truncated IMU CSV";
    if (opt.imu_clock_ratio > 0.0) {
      if (!(std::abs(ratio - 1.0) <= kMaxTagClockDeviation)) {
        std::fprintf(stderr, "sdins import: warning: %s; using --imu-clock-ratio %g (the IMU's own clock)\n",
                     why.c_str(), opt.imu_clock_ratio);
        sum["warnings"].push_back(why + "; the IMU's own clock used (--imu-clock-ratio)");
      }
      map.seconds_per_tick = opt.imu_clock_ratio * 1e-3;
    } else if (!(std::abs(ratio - 1.0) <= kMaxTagClockDeviation)) {
      throw std::runtime_error(why + "; to place the IMU by its own clock from the tag's start time instead, pass "
                               "--imu-clock-ratio 1");
    }
  }

  // Raw GNSS through convbin.
  std::vector<RinexObsEpoch> obs;
  std::vector<GpsEphemeris> ephs;
  RinexObsStats obs_stats;
  LineStats nav_lines;
  TempDir tmp;
  nlohmann::json convbin_json = nullptr;
  if (!ubx.empty()) {
    tmp.path = make_temp_dir();
    tmp.keep = opt.keep_temp;
    const std::string obs_path = (tmp.path / "raw.obs").string(), nav_path = (tmp.path / "raw.nav").string();
    // RINEX 3.04 with Doppler and SNR; only GPS (the flight software is GPS L1 C/A).
    const std::vector<std::string> cmd = {opt.convbin, "-r", "ubx", "-v", "3.04", "-od", "-os", "-y", "R", "-y", "E",
                                          "-y", "J", "-y", "S", "-y", "C", "-y", "I", "-o", obs_path, "-n", nav_path,
                                          ubx.front().string()};
    const int rc = run_program(cmd, (tmp.path / "convbin.log").string());
    if (rc != 0 || !fs::exists(obs_path) || fs::file_size(obs_path) == 0)
      throw std::runtime_error("convbin failed (exit " + std::to_string(rc) + ", is RTKLIB installed? Debian: rtklib): " +
                               join(cmd));
    std::ifstream of = open_in(obs_path);
    obs = read_rinex3_obs(of, obs_stats);
    if (fs::exists(nav_path)) {
      std::ifstream nf = open_in(nav_path);
      ephs = read_rinex3_nav(nf, nav_lines);
    }
    std::set<int> eph_prns;
    for (const GpsEphemeris& e : ephs) eph_prns.insert(e.prn);
    convbin_json = {{"command", join(cmd)},
                    {"exit_status", rc},
                    {"temp_dir", opt.keep_temp ? tmp.path.string() : std::string("(removed)")},
                    {"rinex_version", obs_stats.version},
                    {"obs_bytes", fs::file_size(obs_path)},
                    {"obs_epochs", obs.size()},
                    {"obs_lines", obs_stats.lines.to_json()},
                    {"event_epochs", obs_stats.event_epochs},
                    {"nav_bytes", fs::exists(nav_path) ? fs::file_size(nav_path) : 0},
                    {"nav_gps_ephemerides", ephs.size()},
                    {"nav_gps_prns", std::vector<int>(eph_prns.begin(), eph_prns.end())},
                    {"nav_records", nav_lines.to_json()}};
  }

  // The time scale: the GPS week of the earliest sample.
  int week0 = 1 << 30;
  if (!pf_data.samples.empty()) week0 = std::min(week0, pf_data.samples.front().gps_week);
  if (have_imu) week0 = std::min(week0, map.start.week);
  if (!obs.empty()) week0 = std::min(week0, obs.front().time.week);
  if (week0 == (1 << 30)) throw std::runtime_error("nothing to import in " + opt.path);
  const ImportTimeScale ts{week0};

  Collected c;
  // IMU: g -> m/s^2, deg/s -> rad/s, sensor -> body, rates -> trapezoid increments.
  if (have_imu) {
    const double t_start = ts.t_s(map.start);
    std::vector<RateSample> rs;
    rs.reserve(imu_samples.size());
    for (const ImuCsvSample& s : imu_samples) {
      RateSample r;
      r.t_s = t_start + map.offset_s(s.tick_ms);
      r.f_mps2 = axes.apply(fsw::Vec3(s.accel_g[0], s.accel_g[1], s.accel_g[2]) * fsw::kStandardGravity_mps2);
      r.omega_radps = axes.apply(fsw::Vec3(s.gyro_dps[0], s.gyro_dps[1], s.gyro_dps[2]) * fsw::kDegToRad);
      r.counter = static_cast<std::int32_t>(s.line - 1);  // zero-based line: rejected lines show as counter gaps
      rs.push_back(r);
    }
    c.imu = increments_from_rates(rs);
  }
  for (hal::GnssPvtSample p : pf_data.samples) {
    p.t_s = ts.t_s(GpsTime{p.gps_week, p.gps_tow_s});
    c.pvt.push_back(p);
  }
  RawCounts rc;
  for (const RinexObsEpoch& ep : obs) {
    ++rc.epochs_in;
    std::vector<RawMeas> m;
    for (const RinexObsSat& s : ep.sats) {
      if (s.sys != 'G') {
        ++rc.non_gps;
        continue;
      }
      if (!s.has_c1c) {
        ++rc.no_pseudorange;
        continue;
      }
      if (!s.has_d1c) {
        ++rc.no_doppler;
        continue;
      }
      if (s.c1c_m < 1e7 || s.c1c_m > 5e7) {
        ++rc.bad_pseudorange;
        continue;
      }
      m.push_back({s.prn, s.c1c_m, -s.d1c_hz * kGpsL1Wavelength_m, s.has_s1c ? s.s1c_dbhz : 0.0});
    }
    fsw::GnssRawEpoch e;
    if (make_epoch(ts.t_s(ep.time), ep.time, m, rc, e)) c.raw.push_back(e);
  }

  // Optional clipping to the IMU span.
  std::uint64_t clipped_raw = 0, clipped_pvt = 0;
  if (opt.clip_gnss_to_imu && !c.imu.empty()) {
    const double a = c.imu.front().sample.t_s - 1.0, b = c.imu.back().sample.t_s + 1.0;
    const auto out_raw = [&](const fsw::GnssRawEpoch& e) { return e.t_s < a || e.t_s > b; };
    const auto out_pvt = [&](const hal::GnssPvtSample& p) { return p.t_s < a || p.t_s > b; };
    clipped_raw = static_cast<std::uint64_t>(std::count_if(c.raw.begin(), c.raw.end(), out_raw));
    clipped_pvt = static_cast<std::uint64_t>(std::count_if(c.pvt.begin(), c.pvt.end(), out_pvt));
    c.raw.erase(std::remove_if(c.raw.begin(), c.raw.end(), out_raw), c.raw.end());
    c.pvt.erase(std::remove_if(c.pvt.begin(), c.pvt.end(), out_pvt), c.pvt.end());
  }
  std::uint64_t truth_left_out = 0;
  for (const hal::GnssPvtSample& p : c.pvt) {
    if (p.quality >= 1 && p.quality <= opt.truth_max_quality)
      c.truth.push_back(p);
    else
      ++truth_left_out;
  }
  nlohmann::json alm_json = nullptr;
  if (!c.raw.empty()) {
    const GpsTime first{c.raw.front().gps_week, c.raw.front().gps_tow_s};
    const double span = c.raw.back().t_s - c.raw.front().t_s;
    alm_json = almanacs_from_ephemeris(ephs, rc.prns, first, c.raw.front().t_s, span, opt.max_fit_error_m, c.almanacs);
  }

  sum["time_scale"] = {{"gps_week0", week0},
                       {"definition", "t_s = GPS time in seconds since the start of GPS week " + std::to_string(week0) +
                                          " (= GPS time of week within that week)"}};
  sum["files"] = {{"pos", pos.string()},
                  {"imu_csv", have_imu ? imu_csv.front().string() : std::string()},
                  {"imu_tag", have_imu ? imu_csv.front().string() + ".tag" : std::string()},
                  {"ubx", ubx.empty() ? std::string() : ubx.front().string()}};
  if (have_imu) {
    nlohmann::json ij = finish_imu(c.imu, imu_lines, axes);
    ij["tag"] = {{"label", tag.label},
                 {"start_week", map.start.week},
                 {"start_tow_s", map.start.tow_s},
                 {"records", tag.records.size()},
                 {"last_tick_s", tag.last_tick_s()},
                 {"non_monotonic_records", tag.non_monotonic},
                 {"trailing_bytes", tag.trailing_bytes}};
    ij["tick_ms_first"] = imu_samples.front().tick_ms;
    ij["tick_ms_last"] = imu_samples.back().tick_ms;
    ij["seconds_per_imu_second"] = map.seconds_per_tick * 1e3;
    ij["timing"] = opt.imu_clock_ratio > 0.0
                       ? "first accepted sample at the tag's start time, linear in the IMU tick at --imu-clock-ratio"
                       : "first accepted sample at the tag's start time, last at start + last tag tick, linear in the IMU tick";
    ij["increments"] = "trapezoid of consecutive samples over (t[k-1], t[k]]: n accepted lines give n - 1 samples";
    sum["imu"] = ij;
  } else {
    sum["imu"] = nullptr;
  }
  sum["gnss_pvt"] = pvt_json(c.pvt, pf_data.lines, pos.string());
  sum["gnss_pvt"]["clipped_to_imu"] = clipped_pvt;
  sum["gnss_pvt"]["has_velocity"] = pf_data.has_velocity;
  sum["truth"] = {{"samples", c.truth.size()},
                  {"max_quality", opt.truth_max_quality},
                  {"left_out", truth_left_out},
                  {"note", "the RTK solution as reference (position, velocity; attitude NaN), not truth"}};
  if (!ubx.empty()) {
    nlohmann::json rj = rc.to_json();
    rj["epochs"] = raw_span(c.raw);
    rj["clipped_to_imu"] = clipped_raw;
    rj["pseudorange_rate"] = "-D1C * c / 1575.42 MHz (L1 C/A Doppler)";
    sum["gnss_raw"] = rj;
  } else {
    sum["gnss_raw"] = nullptr;
  }
  sum["convbin"] = convbin_json;
  sum["almanac"] = alm_json;
  sum["log"] = write_log(opt.log_path, c);
  return sum;
}

// ---------------------------------------------------------------------------------------------
// psins

nlohmann::json import_psins(const ImportOptions& opt) {
  const fs::path dir(opt.path);
  if (!fs::is_directory(dir)) throw std::runtime_error(opt.path + " is not a directory (psins-tc layout expected)");
  const fs::path imu_p = dir / "imu_200hz.csv", obs_p = dir / "gps_obs.csv", eph_p = dir / "gps_eph.csv";
  for (const fs::path& p : {imu_p, obs_p, eph_p})
    if (!fs::exists(p)) throw std::runtime_error("missing " + p.string());
  const AxisMap axes = parse_axis_map(opt.axes.empty() ? kAxesPsins : opt.axes);

  LineStats imu_lines, obs_lines, eph_lines;
  std::ifstream fi = open_in(imu_p), fo = open_in(obs_p), fe = open_in(eph_p);
  const std::vector<PsinsImuRow> imu_rows = read_psins_imu(fi, imu_lines);
  const std::vector<PsinsObsRow> obs_rows = read_psins_obs(fo, obs_lines);
  const std::vector<GpsEphemeris> ephs = read_psins_eph(fe, eph_lines);
  if (ephs.empty()) throw std::runtime_error("no usable ephemeris in " + eph_p.string() + ": the GPS week is unknown");
  // The GPS week: the files carry only the time of week; the ephemerides carry the week (WN).
  std::map<int, int> weeks;
  for (const GpsEphemeris& e : ephs) ++weeks[e.week];
  const int week = std::max_element(weeks.begin(), weeks.end(), [](auto& a, auto& b) { return a.second < b.second; })->first;
  const ImportTimeScale ts{week};

  Collected c;
  // IMU: increments over (t[k-1], t[k]]; the first row's interval is the median one.
  {
    std::vector<double> d;
    for (std::size_t k = 1; k < imu_rows.size(); ++k) d.push_back(imu_rows[k].tow_s - imu_rows[k - 1].tow_s);
    const double nominal = d.empty() ? 0.005 : median(d);
    for (std::size_t k = 0; k < imu_rows.size(); ++k) {
      hal::ImuRecord r;
      r.sample.t_s = ts.t_s(GpsTime{week, imu_rows[k].tow_s});
      r.sample.dt_s = k == 0 ? nominal : imu_rows[k].tow_s - imu_rows[k - 1].tow_s;
      r.sample.dtheta_rad = axes.apply(imu_rows[k].dtheta_rad);
      r.sample.dv_mps = axes.apply(imu_rows[k].dv_mps);
      r.counter = static_cast<std::int32_t>(imu_rows[k].line - 1);  // zero-based line (the header is line 0)
      c.imu.push_back(r);
    }
  }
  // Raw epochs: rows of equal time of week; rate = -Doppler (the file's Doppler is -range rate).
  RawCounts rc;
  for (std::size_t i = 0; i < obs_rows.size();) {
    std::size_t j = i;
    std::vector<RawMeas> m;
    while (j < obs_rows.size() && obs_rows[j].tow_s == obs_rows[i].tow_s) {
      m.push_back({obs_rows[j].prn, obs_rows[j].pseudorange_m, -obs_rows[j].doppler_mps, 0.0});
      ++j;
    }
    ++rc.epochs_in;
    const GpsTime t{week, obs_rows[i].tow_s};
    fsw::GnssRawEpoch e;
    if (make_epoch(ts.t_s(t), t, m, rc, e)) c.raw.push_back(e);
    i = j;
  }
  std::uint64_t clipped_raw = 0;
  if (opt.clip_gnss_to_imu && !c.imu.empty()) {
    const double a = c.imu.front().sample.t_s - 1.0, b = c.imu.back().sample.t_s + 1.0;
    const auto out_raw = [&](const fsw::GnssRawEpoch& e) { return e.t_s < a || e.t_s > b; };
    clipped_raw = static_cast<std::uint64_t>(std::count_if(c.raw.begin(), c.raw.end(), out_raw));
    c.raw.erase(std::remove_if(c.raw.begin(), c.raw.end(), out_raw), c.raw.end());
  }
  nlohmann::json alm_json = nullptr;
  if (!c.raw.empty()) {
    const GpsTime first{c.raw.front().gps_week, c.raw.front().gps_tow_s};
    alm_json = almanacs_from_ephemeris(ephs, rc.prns, first, c.raw.front().t_s, c.raw.back().t_s - c.raw.front().t_s,
                                       opt.max_fit_error_m, c.almanacs);
  }

  nlohmann::json sum;
  sum["format"] = "psins";
  sum["input"] = opt.path;
  sum["time_scale"] = {{"gps_week0", week},
                       {"definition", "t_s = GPS time in seconds since the start of GPS week " + std::to_string(week) +
                                          " (= GPS time of week; the week is the ephemerides' WN)"}};
  sum["files"] = {{"imu", imu_p.string()}, {"obs", obs_p.string()}, {"eph", eph_p.string()}};
  nlohmann::json ij = finish_imu(c.imu, imu_lines, axes);
  ij["increments"] = "as recorded (PSINS delta-theta / delta-v), t_s = the row's time (end of the interval)";
  sum["imu"] = ij;
  nlohmann::json rj = rc.to_json();
  rj["lines"] = obs_lines.to_json();
  rj["epochs"] = raw_span(c.raw);
  rj["clipped_to_imu"] = clipped_raw;
  rj["pseudorange_rate"] = "-(the file's Doppler column, which is minus the range rate in m/s); C/N0 unknown: 0";
  sum["gnss_raw"] = rj;
  sum["ephemeris"] = {{"lines", eph_lines.to_json()}, {"gps_week", week}};
  sum["almanac"] = alm_json;
  sum["gnss_pvt"] = nullptr;
  sum["truth"] = nullptr;
  sum["log"] = write_log(opt.log_path, c);
  return sum;
}

// ---------------------------------------------------------------------------------------------
// Text

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof(b), f, v);
  return b;
}

std::string span_text(const nlohmann::json& s) {
  if (s.is_null() || s.value("count", 0) == 0) return "none";
  return std::to_string(s["count"].get<std::uint64_t>()) + ", t_s " + fmt("%.3f", s["t_first_s"].get<double>()) + " .. " +
         fmt("%.3f", s["t_last_s"].get<double>()) + " (" + fmt("%.3f", s["span_s"].get<double>()) + " s, " +
         fmt("%.3f", s["rate_hz"].get<double>()) + " Hz)";
}

std::string lines_text(const nlohmann::json& l) {
  std::string s = std::to_string(l["lines"].get<std::uint64_t>()) + " lines, " +
                  std::to_string(l["accepted"].get<std::uint64_t>()) + " accepted, " +
                  std::to_string(l["rejected"].get<std::uint64_t>()) + " rejected";
  if (!l["rejected_by_reason"].empty()) {
    s += " (";
    bool first = true;
    for (const auto& [k, v] : l["rejected_by_reason"].items()) {
      s += (first ? "" : ", ") + k + ": " + std::to_string(v.get<std::uint64_t>());
      first = false;
    }
    s += ")";
  }
  if (!l["rejected_examples"].empty()) {
    s += "; first at line";
    int n = 0;
    for (const auto& e : l["rejected_examples"]) {
      if (n++ == 5) break;
      s += " " + std::to_string(e["line"].get<std::uint64_t>());
    }
  }
  for (const auto& [k, v] : l["skipped"].items()) s += "; skipped " + std::to_string(v.get<std::uint64_t>()) + " " + k;
  return s;
}

}  // namespace

nlohmann::json import_recording(const ImportOptions& opt) {
  if (opt.log_path.empty()) throw std::runtime_error("no output log (--log)");
  nlohmann::json j;
  if (opt.format == "rtklib")
    j = import_rtklib(opt);
  else if (opt.format == "psins")
    j = import_psins(opt);
  else
    throw std::runtime_error("unknown import format '" + opt.format + "' (rtklib, psins)");
  std::uint64_t rejected = 0;
  for (const char* k : {"imu", "gnss_pvt", "gnss_raw", "ephemeris"})
    if (j.contains(k) && !j[k].is_null() && j[k].contains("lines")) rejected += j[k]["lines"]["rejected"].get<std::uint64_t>();
  j["rejected_lines_total"] = rejected;
  return j;
}

namespace {
bool has(const nlohmann::json& j, const char* key) { return j.contains(key) && !j[key].is_null(); }
}  // namespace

std::string import_summary_text(const nlohmann::json& j) {
  std::ostringstream o;
  o << "import " << j["format"].get<std::string>() << " " << j["input"].get<std::string>() << " -> "
    << j["log"]["path"].get<std::string>() << "\n";
  o << "time scale: " << j["time_scale"]["definition"].get<std::string>() << "\n";
  if (has(j, "imu")) {
    const auto& i = j["imu"];
    o << "IMU:          " << lines_text(i["lines"]) << "\n";
    o << "              samples " << span_text(i["samples"]);
    if (i.contains("dt_s"))
      o << ", dt " << fmt("%.4f", i["dt_s"]["min"].get<double>()) << " .. " << fmt("%.4f", i["dt_s"]["max"].get<double>())
        << " s (median " << fmt("%.4f", i["dt_s"]["median"].get<double>()) << "), " << i["gaps"].get<std::uint64_t>()
        << " gaps";
    o << "\n              body axes = sensor (" << i["axes"].get<std::string>() << ")";
    if (i.contains("first_second_mean_f_body_mps2")) {
      const auto& f = i["first_second_mean_f_body_mps2"];
      o << "; first second mean specific force (body FRD) " << fmt("%.3f", f[0].get<double>()) << " "
        << fmt("%.3f", f[1].get<double>()) << " " << fmt("%.3f", f[2].get<double>()) << " m/s^2";
    }
    o << "\n";
    if (i.contains("tag"))
      o << "              tag '" << i["tag"]["label"].get<std::string>() << "': start GPS week "
        << i["tag"]["start_week"].get<int>() << " tow " << fmt("%.3f", i["tag"]["start_tow_s"].get<double>()) << ", "
        << i["tag"]["records"].get<std::uint64_t>() << " records, last tick " << fmt("%.3f", i["tag"]["last_tick_s"].get<double>())
        << " s; " << fmt("%.6f", i["seconds_per_imu_second"].get<double>()) << " GPS s per IMU-clock s\n";
  }
  if (has(j, "gnss_pvt")) {
    const auto& p = j["gnss_pvt"];
    o << "GNSS_PVT:     " << lines_text(p["lines"]) << "\n              solutions " << span_text(p["samples"]) << ", Q";
    for (const auto& [k, v] : p["by_quality"].items()) o << " " << k << ":" << v.get<std::uint64_t>();
    o << "\n";
  }
  if (has(j, "truth"))
    o << "TRUTH:        " << j["truth"]["samples"].get<std::uint64_t>() << " reference epochs (RTK solution, Q <= "
      << j["truth"]["max_quality"].get<int>() << "), " << j["truth"]["left_out"].get<std::uint64_t>() << " left out\n";
  if (has(j, "convbin")) {
    const auto& c = j["convbin"];
    o << "convbin:      RINEX " << c["rinex_version"].get<std::string>() << ", " << c["obs_epochs"].get<std::uint64_t>()
      << " obs epochs, " << c["nav_gps_ephemerides"].get<std::uint64_t>() << " GPS ephemerides (PRN";
    for (const auto& p : c["nav_gps_prns"]) o << " " << p.get<int>();
    o << ")\n";
  }
  if (has(j, "gnss_raw")) {
    const auto& r = j["gnss_raw"];
    if (r.contains("lines")) {
      o << "GNSS_RAW:     " << lines_text(r["lines"]) << "\n              ";
    } else {
      o << "GNSS_RAW:     ";
    }
    o << "epochs " << span_text(r["epochs"]) << ", " << r["measurements"].get<std::uint64_t>() << " measurements, PRN";
    for (const auto& p : r["satellites"]) o << " " << p.get<int>();
    std::string sk;
    for (const auto& [k, v] : r["skipped"].items())
      if (v.get<std::uint64_t>() > 0) sk += (sk.empty() ? "" : ", ") + k + " " + std::to_string(v.get<std::uint64_t>());
    if (!sk.empty()) o << "; skipped: " << sk;
    o << "\n";
  }
  if (has(j, "ephemeris")) {
    o << "ephemeris:    " << lines_text(j["ephemeris"]["lines"]) << "\n";
  }
  if (has(j, "almanac")) {
    const auto& a = j["almanac"];
    o << "GPS_ALMANAC:  " << a["written"].size() << " PRNs fitted to the broadcast ephemeris (limit "
      << fmt("%.2f", a["max_fit_error_m"].get<double>()) << " m position + clock), " << a["segments"].get<int>()
      << " segment(s) of " << fmt("%.1f", a["segment_s"].get<double>()) << " s, " << a["messages"].get<std::uint64_t>()
      << " messages";
    if (!a["observed_without_ephemeris"].empty()) {
      o << "; observed without ephemeris: PRN";
      for (const auto& p : a["observed_without_ephemeris"]) o << " " << p.get<int>();
    }
    o << "\n";
    for (const auto& f : a["fits"])
      o << "              PRN " << f["prn"].get<int>() << ": max position error " << fmt("%.3f", f["max_pos_err_m"].get<double>())
        << " m, clock " << fmt("%.3f", f["max_clock_err_m"].get<double>()) << " m, velocity "
        << fmt("%.4f", f["max_vel_err_mps"].get<double>()) << " m/s" << (f["written"].get<bool>() ? "" : "  (NOT written)")
        << "\n";
  }
  o << "log:          " << j["log"]["path"].get<std::string>() << ", " << j["log"]["events"].get<std::uint64_t>() << " events (";
  bool first = true;
  for (const auto& [k, v] : j["log"]["per_channel"].items()) {
    o << (first ? "" : ", ") << k << " " << v.get<std::uint64_t>();
    first = false;
  }
  o << "); " << j.value("rejected_lines_total", std::uint64_t{0}) << " input lines rejected in all\n";
  return o.str();
}

}  // namespace tools
