// What the import paths share (private to tools/import): the collected inputs of a log, the log
// writer, the per-stream summaries, raw epochs, the almanac fit, files and the convbin run. One
// import engine (import_describe.cpp) uses them; the rtklib and psins formats are presets of it
// (import_presets.cpp).
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "fsw/gps_orbit.hpp"
#include "hal/lcm_convert.hpp"
#include "tools/importers.hpp"
#include "tools/stream_summary.hpp"

namespace tools::import_detail {

namespace fs = std::filesystem;

struct TimedAlmanac {
  double t_s;  ///< when it is written (-inf: at the start of the log)
  fsw::GpsAlmanac almanac;
};

/// One reference epoch (TRUTH): position, velocity (NaN: none) and, when the source has it,
/// attitude C_b_n (body -> ENU).
struct ReferenceEpoch {
  double t_s = 0.0;
  fsw::Vec3 llh = fsw::Vec3::Zero();
  fsw::Vec3 vel_enu_mps = fsw::Vec3::Constant(std::nan(""));
  bool has_attitude = false;
  fsw::Mat3 C_b_n = fsw::Mat3::Identity();
};

struct Collected {
  std::vector<TimedAlmanac> almanacs;  ///< the first set at the earliest time of the log, updates later
  std::vector<hal::ImuRecord> imu;
  std::vector<fsw::GnssRawEpoch> raw;
  std::vector<hal::GnssPvtSample> pvt;
  std::vector<ReferenceEpoch> truth;  ///< the reference (TRUTH channel)
};

/// Writes the log atomically (time order; at equal times almanac, IMU, raw, solution, reference).
nlohmann::json write_log(const std::string& path, const Collected& c);

/// The one stream shape (tools/stream_summary.hpp) of any list of samples, from their time tags.
template <class T, class TimeOf>
StreamSummary stream_of(const std::string& name, const std::string& source, const std::vector<T>& v, TimeOf t_of,
                        std::uint64_t duplicates = 0) {
  std::vector<double> t;
  t.reserve(v.size());
  for (const T& x : v) t.push_back(t_of(x));
  StreamSummary s = summarize_stream(name, source, t);
  s.duplicates = duplicates;
  return s;
}
/// The solutions counted by quality: {"Q": n}.
nlohmann::json by_quality_json(const std::vector<hal::GnssPvtSample>& pvt);
/// Ground-speed statistics of the solutions with velocity (median, p90, max, the moving share):
/// what the starting configuration's initialisation speed is read from; null without velocities.
nlohmann::json pvt_speed_json(const std::vector<hal::GnssPvtSample>& pvt);
/// The same statistics of any list of speeds [m/s], labelled with their source; null when empty.
nlohmann::json speed_stats_json(const std::vector<double>& speeds_mps, const std::string& source);
double median(std::vector<double> v);
/// IMU records through the IMU input validation, then the stream ("samples") and the first second's means.
nlohmann::json finish_imu(std::vector<hal::ImuRecord>& imu, LineStats& lines, const AxisMap& axes,
                          const std::string& source, std::uint64_t duplicates);
/// The solutions' lines, stream ("samples") and count by quality.
nlohmann::json pvt_json(const std::vector<hal::GnssPvtSample>& pvt, const LineStats& lines, const std::string& file,
                        std::uint64_t duplicates);
nlohmann::json almanacs_from_ephemeris(const std::vector<GpsEphemeris>& ephs, const std::set<int>& observed,
                                       const GpsTime& first, double first_t_s, double span_s, double max_err_m,
                                       std::vector<TimedAlmanac>& out);

struct RawCounts {
  std::uint64_t epochs_in = 0, non_gps = 0, no_pseudorange = 0, no_doppler = 0, bad_pseudorange = 0, over_16 = 0,
                duplicate_prn = 0, empty_epochs = 0, measurements = 0;
  std::set<int> prns;
  nlohmann::json to_json() const;
};

struct RawMeas {
  int prn;
  double pr, prr, cn0;
};

/// One epoch from measurements (at most 16, the strongest first when there are more).
bool make_epoch(double t_s, const GpsTime& t, std::vector<RawMeas> m, RawCounts& c, fsw::GnssRawEpoch& e);
/// The raw epochs' stream (the one shape).
nlohmann::json raw_stream(const std::vector<fsw::GnssRawEpoch>& raw, const std::string& source);

std::vector<fs::path> files_with(const fs::path& dir, const std::string& suffix);
std::string names(const std::vector<fs::path>& v);
/// Bounded readers (docs/faults.md): regular files only, at most hal::kMaxRecordingInputBytes.
std::ifstream open_in(const fs::path& p);
fs::path make_temp_dir();
int run_program(const std::vector<std::string>& argv, const std::string& log_path);
std::string join(const std::vector<std::string>& v);

struct TempDir {
  fs::path path;
  bool keep = false;
  TempDir() = default;
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  ~TempDir() {
    std::error_code ec;
    if (!path.empty() && !keep) fs::remove_all(path, ec);
  }
};

}  // namespace tools::import_detail
