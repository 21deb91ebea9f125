// The one reader of a log's reference (TRUTH channel): a simulator's truth or an imported
// reference (an RTK/GNSS solution without attitude, an autopilot's estimate). Every tool that
// scores against a reference reads it here (`sdins replay`'s score, tools/replay_score.hpp; the
// diagnosis, tools/diagnosis_model.hpp, which applies its stricter rule on top).
//
// The rule: a message that does not decode, whose t_s is not finite, or that does not come after
// the last sample kept (strictly increasing time) is rejected; so is one with nothing finite.
// Otherwise each part is kept for what it is: position when lat/lon/height are finite, velocity
// when its three components are, attitude when the quaternion is finite and of unit norm (within
// 1e-3, then normalised). A finite attitude that is not a unit quaternion is flagged
// (attitude_not_unit), not silently taken for "no attitude".
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "fsw/strapdown.hpp"
#include "sim/truth.hpp"

namespace tools {

/// A reference sample: the truth sample (sim/truth.hpp: time, position, velocity, attitude, with
/// q_b_n the identity and has_attitude false when there is none) and which parts are there.
struct ReferenceSample : sim::TruthPoint {
  ReferenceSample() { has_attitude = false; }
  bool has_position = false, has_velocity = false;
  bool attitude_not_unit = false;  ///< the quaternion was finite but not of unit norm (has_attitude false)
};

struct Reference {
  std::vector<ReferenceSample> samples;  ///< strictly increasing t_s
  std::uint64_t messages = 0;            ///< TRUTH messages read (kept + rejected)
  std::uint64_t rejected = 0;            ///< TRUTH messages that did not decode, went back in time or had nothing finite
  /// What the reference is: the import summary beside the log (LOG.json) "reference" object, or
  /// {"kind": "simulator_truth"} for a simulator's sidecar; null when the log has no sidecar.
  nlohmann::json label;
  std::string label_source;  ///< the sidecar's path, or "" without one
};

/// The TRUTH channel of a log and the label from LOG.json when present. Throws std::runtime_error
/// when the log cannot be read.
Reference load_reference(const std::string& log_path);

}  // namespace tools
