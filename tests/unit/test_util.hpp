// Small helpers shared by the unit tests: one definition each (the test files compile several to a
// unit, tests/CMakeLists.txt, so a helper written again in two files would collide).
#pragma once

#include <gtest/gtest.h>

#include <limits>
#include <string>
#include <vector>

#include "fsw/frames.hpp"
#include "sim/almanac.hpp"
#include "sim/scenario.hpp"  // default_almanac_path

namespace test_util {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr double kDeg = fsw::kDegToRad;

inline bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

/// The product's almanac (data/almanac through the data directory), parsed; a parse error fails
/// the calling test and gives an empty list.
inline std::vector<sim::AlmanacEntry> shipped_almanac() {
  const sim::AlmanacParseResult r = sim::parse_yuma_file(sim::default_almanac_path());
  EXPECT_TRUE(r.ok()) << r.error;
  return r.ok() ? *r.almanac : std::vector<sim::AlmanacEntry>{};
}

}  // namespace test_util
