// Status codes returned across the fsw boundary (no exceptions in fsw/).
#pragma once

#include <cstdint>

namespace fsw {

enum class Status : std::uint8_t {
  kOk = 0,
  kNotInitialised,   ///< step called before init
  kBadInput,         ///< NaN/Inf or out-of-range value rejected before it touched the state
  kBadConfig,        ///< configuration out of its valid range
  kFrameIncomplete,  ///< not enough IMU samples yet for a navigation frame
  kNotConverged,     ///< an iterative computation did not converge (e.g. alignment on a moving base)
};

inline constexpr const char* to_string(Status s) {
  switch (s) {
    case Status::kOk: return "ok";
    case Status::kNotInitialised: return "not_initialised";
    case Status::kBadInput: return "bad_input";
    case Status::kBadConfig: return "bad_config";
    case Status::kFrameIncomplete: return "frame_incomplete";
    case Status::kNotConverged: return "not_converged";
  }
  return "unknown";
}

}  // namespace fsw
