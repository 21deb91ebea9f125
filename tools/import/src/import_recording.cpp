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
#include "import_common.hpp"
#include "tools/import_describe.hpp"
#include "tools/importers.hpp"
#include "tools/number_text.hpp"

extern char** environ;

namespace tools {
namespace import_detail {

// ---------------------------------------------------------------------------------------------
// What goes into the log

enum class EventKind : int { kAlmanac = 0, kImu = 1, kGnssRaw = 2, kGnssPvt = 3, kTruth = 4 };

namespace {
struct Event {
  double t_s;
  EventKind kind;
  std::size_t idx;
};
}  // namespace

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
        const ReferenceEpoch& r = c.truth[e.idx];
        st = r.has_attitude ? sink.write_truth(r.t_s, r.llh, r.vel_enu_mps, r.C_b_n)
                            : sink.write_reference(r.t_s, r.llh, r.vel_enu_mps);
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

nlohmann::json speed_stats_json(const std::vector<double>& v, const std::string& source) {
  if (v.empty()) return nullptr;
  std::vector<double> s = v;
  std::sort(s.begin(), s.end());
  double moving = 0;
  for (double x : v) moving += x > 0.5 ? 1 : 0;
  return {{"samples", v.size()},
          {"median_mps", s[s.size() / 2]},
          {"p90_mps", s[static_cast<std::size_t>(0.9 * static_cast<double>(s.size() - 1))]},
          {"max_mps", s.back()},
          {"fraction_above_0_5_mps", moving / static_cast<double>(v.size())},
          {"source", source}};
}

nlohmann::json pvt_speed_json(const std::vector<hal::GnssPvtSample>& pvt) {
  std::vector<double> v;
  for (const auto& p : pvt)
    if (p.has_velocity()) v.push_back(p.vel_enu_mps.head<2>().norm());
  return speed_stats_json(v, "GNSS solutions");
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

/// IMU records through the IMU input validation (what `sdins replay` would reject is not written),
/// then the time statistics.
nlohmann::json finish_imu(std::vector<hal::ImuRecord>& imu, LineStats& lines, const AxisMap& axes,
                          const std::string& source, std::uint64_t duplicates) {
  std::vector<hal::ImuRecord> kept;
  kept.reserve(imu.size());
  for (const hal::ImuRecord& r : imu) {
    sdins::imu_sample_t m{};
    hal::to_msg(r, m);
    hal::ImuRecord back;
    const hal::LcmInputStatus st = hal::from_msg(m, back);
    if (st != hal::LcmInputStatus::kOk) {
      lines.reject(static_cast<std::uint64_t>(r.counter) + 1, std::string("IMU input validation: ") + hal::to_string(st));
      --lines.accepted;
      continue;
    }
    kept.push_back(r);
  }
  imu.swap(kept);
  nlohmann::json j = {{"lines", lines.to_json()}, {"axes", axes.text()}};
  j["samples"] = stream_of("imu", source, imu, [](const hal::ImuRecord& r) { return r.sample.t_s; }, duplicates).to_json();
  if (imu.empty()) return j;
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

nlohmann::json by_quality_json(const std::vector<hal::GnssPvtSample>& pvt) {
  std::map<std::string, std::uint64_t> q;
  for (const hal::GnssPvtSample& p : pvt) ++q[std::to_string(p.quality)];
  return q;
}

nlohmann::json pvt_json(const std::vector<hal::GnssPvtSample>& pvt, const LineStats& lines, const std::string& file,
                        std::uint64_t duplicates) {
  nlohmann::json j = {{"file", file}, {"lines", lines.to_json()}};
  j["samples"] = stream_of("gnss_pvt", file, pvt, [](const hal::GnssPvtSample& p) { return p.t_s; }, duplicates).to_json();
  j["by_quality"] = by_quality_json(pvt);
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

nlohmann::json RawCounts::to_json() const {
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

nlohmann::json raw_stream(const std::vector<fsw::GnssRawEpoch>& raw, const std::string& source) {
  return stream_of("gnss_raw", source, raw, [](const fsw::GnssRawEpoch& e) { return e.t_s; }).to_json();
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

}  // namespace import_detail

namespace {
using namespace import_detail;

// ---------------------------------------------------------------------------------------------
// Text


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
  // One code path: the dedicated formats are presets of the description import.
  if (opt.format == "rtklib") return import_described(rtklib_preset(opt), describe_options(opt));
  if (opt.format == "psins") return import_described(psins_preset(opt), describe_options(opt));
  throw std::runtime_error("unknown import format '" + opt.format + "' (rtklib, psins)");
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
    o << "              samples " << stream_summary_text(i["samples"]);
    if (i["samples"].value("count", std::uint64_t{0}) > 1)
      o << ", interval " << fmt("%.4f", i["samples"]["dt_s"]["min"].get<double>()) << " .. "
        << fmt("%.4f", i["samples"]["dt_s"]["max"].get<double>()) << " s (median "
        << fmt("%.4f", i["samples"]["dt_s"]["median"].get<double>()) << ")";
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
    o << "GNSS_PVT:     " << lines_text(p["lines"]) << "\n              solutions " << stream_summary_text(p["samples"]) << ", Q";
    for (const auto& [k, v] : p["by_quality"].items()) o << " " << k << ":" << v.get<std::uint64_t>();
    o << "\n";
  }
  if (has(j, "truth")) {
    const auto& t = j["truth"];
    o << "TRUTH:        " << t["samples"].value("count", std::uint64_t{0}) << " reference epochs (" << t.value("kind", std::string("rtk"));
    if (t.contains("max_quality"))
      o << " from the solutions, Q <= " << t["max_quality"].get<int>() << "), " << t["left_out"].get<std::uint64_t>()
        << " left out\n";
    else
      o << ", " << t.value("source", std::string()) << ")\n";
  }
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
    o << "epochs " << stream_summary_text(r["samples"]) << ", " << r["measurements"].get<std::uint64_t>() << " measurements, PRN";
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
  o << describe_summary_text(j);
  return o.str();
}

}  // namespace tools
