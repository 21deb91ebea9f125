// Helpers shared by the LCM unit tests: scratch files, whole-file byte access, running LCM's own
// command-line tools.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

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

}  // namespace lcm_test
