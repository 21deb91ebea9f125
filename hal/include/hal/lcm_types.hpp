// The table of the project's LCM message types for tools that handle any of them (`sdins log
// info`, `sdins log export`): identification by fingerprint, decoding, time, and a flat row of
// named fields for CSV.
//
// Adding a message type: the .lcm file in hal/lcm/, an LcmFields<sdins::new_t> specialisation
// (the fields in CSV order, names with units) in hal/src/lcm_types.cpp, and one line in the
// table there (make_lcm_type<sdins::new_t>()). Everything else is generic.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "hal/lcm_convert.hpp"

namespace hal {

/// One message flattened into named cells, in field order. Field names carry their units
/// (vel_enu_mps[0]); arrays become name[i]; array entries beyond a count field are empty cells.
class LcmRow {
 public:
  void clear();
  void add(const std::string& name, double v);
  void add(const std::string& name, std::int64_t v);
  void add(const std::string& name, std::int32_t v) { add(name, static_cast<std::int64_t>(v)); }
  void add(const std::string& name, std::int16_t v) { add(name, static_cast<std::int64_t>(v)); }
  void add(const std::string& name, std::int8_t v) { add(name, static_cast<std::int64_t>(v)); }
  void add_empty(const std::string& name);
  /// name[0] .. name[n-1]; entries with index >= valid are empty (valid < 0: all valid).
  template <class T>
  void add_array(const std::string& name, const T* v, int n, int valid = -1) {
    for (int i = 0; i < n; ++i) {
      const std::string nm = name + "[" + std::to_string(i) + "]";
      if (valid >= 0 && i >= valid)
        add_empty(nm);
      else
        add(nm, v[i]);
    }
  }

  const std::vector<std::string>& names() const { return names_; }
  const std::vector<std::string>& cells() const { return cells_; }

 private:
  std::vector<std::string> names_;
  std::vector<std::string> cells_;
};

/// Per-type field visitor: static void visit(const Msg&, LcmRow&). Specialised in lcm_types.cpp.
template <class Msg>
struct LcmFields;

struct LcmTypeInfo {
  std::string name;  ///< "sdins.imu_sample_t"
  std::int64_t fingerprint = 0;
  /// Decodes (exact size, fingerprint) and gives the message's t_s.
  LcmInputStatus (*time)(const void* data, std::size_t len, double& t_s) = nullptr;
  /// Decodes and flattens the message into row (cleared first).
  LcmInputStatus (*row)(const void* data, std::size_t len, LcmRow& row) = nullptr;
  /// For the flight software's input types (IMU, GNSS_RAW, GPS_ALMANAC, GNSS_PVT): decodes and runs
  /// the input conversion the replay reader applies (hal::from_msg, default limits); values_dropped
  /// is the number of GNSS measurements removed from an accepted epoch (non-finite values). nullptr
  /// for the output types. `sdins log info` reports the result per channel (docs/faults.md).
  LcmInputStatus (*input)(const void* data, std::size_t len, int& values_dropped) = nullptr;
};

/// Every project message type (sent on a channel).
const std::vector<LcmTypeInfo>& lcm_types();
/// The type with this fingerprint, or nullptr.
const LcmTypeInfo* find_lcm_type(std::int64_t fingerprint);
/// The type with this full name ("sdins.nav_solution_t"), or nullptr.
const LcmTypeInfo* find_lcm_type(std::string_view name);
/// The type a project channel carries (kLcmChannels), or nullptr for other channels.
const LcmTypeInfo* lcm_channel_type(std::string_view channel);

}  // namespace hal
