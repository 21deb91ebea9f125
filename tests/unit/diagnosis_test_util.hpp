// Helpers shared by the diagnosis unit tests (test_diagnosis*.cpp): the sanitizer switch of the
// statistical tests, the baseline aircraft scenario and a finding's printed name.
#pragma once

#include <cstdint>
#include <string>

#include "fsw/effect_catalogue.hpp"
#include "sim/scenario.hpp"
#include "tools/diagnosis_result.hpp"

namespace diagnosis_test {

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kSanitized = true;  // ~10x slower: the statistical tests run in the release stage
#else
constexpr bool kSanitized = false;
#endif

/// The default bank-to-turn aircraft with the baseline IMU errors (biases and noise) only.
inline sim::Scenario baseline_scenario(double duration_s, std::uint64_t seed) {
  sim::Scenario sc;
  sc.duration_s = duration_s;
  sc.seed = seed;
  sc.imu.errors = sim::ImuErrorSet::kBaseline;
  return sc;
}

/// "effect" or "effect.component", as the diagnosis prints a finding.
inline std::string name_of(const tools::Finding& f) {
  return std::string(fsw::effect_info(f.effect).name) + (f.component.empty() ? "" : "." + f.component);
}

}  // namespace diagnosis_test
