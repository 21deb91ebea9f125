// Helpers shared by the LCM unit tests: scratch files, whole-file byte access, running LCM's own
// command-line tools, bit-exact comparison, encoding a message, writing a log and replaying it.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "hal/lcm_log_sink.hpp"

namespace lcm_test {

/// A per-process scratch path (removed by the caller or left in /tmp for inspection).
inline std::string scratch(const std::string& name) {
  return "/tmp/sdins_lcm_test_" + std::to_string(::getpid()) + "_" + name;
}

inline std::vector<std::uint8_t> read_bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

inline void write_bytes(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

/// Runs a shell command, returns its exit status (-1 when it could not run).
inline int run(const std::string& cmd) {
  const int rc = std::system(cmd.c_str());
  if (rc == -1 || !WIFEXITED(rc)) return -1;
  return WEXITSTATUS(rc);
}

/// Same bits (NaN payloads, signed zeros): what a bit-exact round trip promises.
inline bool bits_equal(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

/// The encoded bytes of an LCM message (its encoder must fill exactly getEncodedSize()).
template <class Msg>
std::vector<std::uint8_t> encode(const Msg& m) {
  std::vector<std::uint8_t> b(static_cast<std::size_t>(m.getEncodedSize()));
  EXPECT_EQ(m.encode(b.data(), 0, static_cast<int>(b.size())), static_cast<int>(b.size()));
  return b;
}

/// Opens sink to write the log at path and nothing else (no LCM network).
inline hal::LcmLogStatus open_log_only(hal::LcmLogSink& sink, const std::string& path) {
  hal::LcmTelemetryConfig cfg;
  cfg.lcm_url = "none";
  cfg.log_path = path;
  return sink.open(cfg);
}

/// Writes a log at path holding the IMU records make(0), ..., make(n - 1) in that order and
/// nothing else. Call it under ASSERT_NO_FATAL_FAILURE.
template <class Make>
void write_imu_log(const std::string& path, int n, Make&& make) {
  hal::LcmLogSink sink;
  ASSERT_EQ(open_log_only(sink, path), hal::LcmLogStatus::kOk);
  for (int k = 0; k < n; ++k) ASSERT_EQ(sink.write_imu(make(k)), hal::LcmLogStatus::kOk);
  ASSERT_EQ(sink.close(), hal::LcmLogStatus::kOk);
}

/// The time tags of the inputs rd replays from the log at path (default replay settings), in the
/// order delivered; rd's stats are then those of the whole log.
inline std::vector<double> replayed_times(hal::LcmReplayReader& rd, const std::string& path) {
  std::vector<double> t;
  EXPECT_EQ(rd.open(path, hal::LcmReplayConfig{}), hal::LcmLogStatus::kOk);
  fsw::InputEvent in;
  while (rd.next(in) == hal::LcmLogStatus::kOk) t.push_back(in.t_s);
  return t;
}

}  // namespace lcm_test
