// validate(): the flight software's rule table (fsw/config_check.hpp) on a loaded configuration,
// its refusal worded with the file, the TOML key, the value in the file's unit and the rule
// (flight_config.hpp).
#include "cfg/flight_config.hpp"
#include "cfg/toml_schema.hpp"
#include "keys.hpp"

namespace cfg {
namespace {
using F = fsw::ConfigField;
using keys::find_key;
using keys::Key;
}  // namespace

namespace {

std::string num(double v) { return toml_schema::format_number(v); }

/// The rule in words, with the limit in the file's unit (conv; nullptr: the SI unit).
std::string rule_text(const fsw::ConfigCheck& k, double (*conv)(double)) {
  const std::string limit = num(conv ? conv(k.limit) : k.limit);
  switch (k.rule) {
    case fsw::ConfigRule::kFinite: return "must be a finite number";
    case fsw::ConfigRule::kPositive: return "must be greater than 0";
    case fsw::ConfigRule::kNonNegative: return "must not be negative";
    case fsw::ConfigRule::kAtLeast: return "must be at least " + limit;
    case fsw::ConfigRule::kAtMost: return "must be at most " + limit;
    case fsw::ConfigRule::kBelow: return "must be below " + limit;
    case fsw::ConfigRule::kAbove: return "must be greater than " + limit;
    case fsw::ConfigRule::kKnown: return "must be \"track\", \"static\", \"velocity_matching\" or \"given\"";
    case fsw::ConfigRule::kNone: break;
  }
  return "breaks rule " + std::string(fsw::to_string(k.rule));
}

/// Where a limit of the flight software comes from, for the rules whose limit is not a key.
std::string limit_reason(const fsw::ConfigCheck& k) {
  using R = fsw::ConfigRule;
  switch (k.field) {
    case F::kVmMax: return k.rule == R::kAbove ? " (init.vm_min_s)" : "";
    case F::kNisWindow: return k.rule == R::kAtMost ? " (the flight software's NIS window)" : "";
    case F::kLevellingSamples: return k.rule == R::kAtMost ? " (the flight software's levelling buffer)" : "";
    case F::kImuSamplesPerFrame: return k.rule == R::kAtMost ? " (the flight software's frame buffer)" : "";
    case F::kMinSatellitesForInit: return k.rule == R::kAtMost ? " (the receiver channels)" : "";
    case F::kVmMaxHeadingSigma: return k.rule == R::kAtMost ? " (180 deg)" : "";
    default: break;
  }
  return "";
}

}  // namespace

std::string describe(const fsw::ConfigCheck& k, const fsw::FlightAppConfig& a, const FlightConfig& origin) {
  if (k.ok()) return "";
  std::string name;
  double value = k.value;
  double (*conv)(double) = nullptr;
  if (k.field == F::kFramesPerEkf) {
    // A rate in the file, whole frames in the flight software.
    return "executive.ekf_rate_hz gives " + num(k.value) + " navigation frames per EKF step (nav_rate_hz " +
           num(a.exec.nav_rate_hz) + "); the EKF step " + rule_text(k, nullptr) + " frame";
  }
  if (k.field == F::kGnssWaitFrames) {
    name = "executive.gnss_wait_s";
    value = k.value / a.exec.nav_rate_hz;
  } else if (const Key* key = find_key(k.field)) {
    const bool alt = key->alt_key && origin.key_file.count(key->alt_key) && !origin.key_file.count(key->key);
    name = alt ? key->alt_key : key->key;
    conv = alt ? key->alt_from_si : key->from_si;
    if (conv) value = conv(k.value);
    if (k.field == F::kLeverArmX || k.field == F::kLeverArmY || k.field == F::kLeverArmZ)
      name += "[" + std::to_string(static_cast<int>(k.field) - static_cast<int>(F::kLeverArmX)) + "]";
  } else {
    name = std::string(fsw::to_string(k.field)) + " (no file key sets it)";
  }
  std::string text = name + " = " + num(value);
  const std::string top = origin.files.empty() ? "" : origin.files.back();
  const std::string base_key = name.substr(0, name.find('['));
  if (const auto it = origin.key_file.find(base_key); it != origin.key_file.end() && it->second != top)
    text += " (set in " + it->second + ")";
  if (k.field == F::kEkfLatencyFrames && k.rule == fsw::ConfigRule::kBelow) {
    // The correction lands inside its own EKF step (fsw/executive.hpp).
    return text + " must be below the " + num(k.limit) + " frames per EKF step (nav_rate_hz " +
           num(a.exec.nav_rate_hz) + " / ekf_rate_hz " + num(a.exec.nav_rate_hz / a.exec.frames_per_ekf) + ")";
  }
  return text + " " + rule_text(k, conv) + limit_reason(k);
}

namespace {
std::string top_file(const FlightConfig& c) { return c.files.empty() ? "the schema's field defaults" : c.files.back(); }
}  // namespace

FlightConfigResult validate(const FlightConfig& c) {
  const fsw::ConfigCheck k = fsw::check_config(c.app);
  if (k.ok()) return {true, ""};
  return {false, top_file(c) + ": " + describe(k, c.app, c)};
}

FlightConfigResult validate(const fsw::FlightAppConfig& app, const FlightConfig& base, const std::string& overlay) {
  const fsw::ConfigCheck k = fsw::check_config(app);
  if (k.ok()) return {true, ""};
  // The overlay, not the files, may have set the field: no "(set in ...)" then.
  FlightConfig origin;
  origin.files = base.files;
  return {false, overlay + " on " + top_file(base) + ": " + describe(k, app, origin)};
}

}  // namespace cfg
