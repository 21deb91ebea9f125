// The flight configuration: the TOML files that set the flight software (fsw::FlightAppConfig)
// and what a host command reads beside it (the GNSS input, the diagnosis' priors and outages).
// One schema, one set of defaults shipped as a file: config/default.toml, installed as
// <data dir>/config/default.toml (cfg/data_dir.hpp), sets every key and is what `sdins sil`,
// `fsw`, `replay`, `montecarlo`, `paper`, `diagnose`, `fly`, `audit timing` and the target tool fly
// with (load_flight_config), and what the bare-metal image is generated from
// (fsw/baremetal/default_flight_config.hpp). The struct initialisers of fsw::FlightAppConfig and
// FlightConfig are only the schema's field defaults for a key a file leaves out.
//
// Recorded data come from sensors unlike the simulated aircraft's navigation-grade IMU: a MEMS IMU
// at 100-200 Hz with turn-on biases of a tenth of a degree per second, a GNSS receiver that gives
// position/velocity solutions at 4 Hz, an antenna and IMU mounted at an angle to the direction of
// travel. Each data set gets one file (config/datasets/*.toml) that says, with its reasons in
// comments, how the filter is set for it. The schema (every key optional; unknown keys rejected;
// errors "<file>:<line>:<col>: <message naming the key>") is documented in config/README.md.
//
// Two stages of checks, one error format: the schema's per-key ranges while a file is parsed
// (cfg/toml_schema.hpp, the same rules as the scenario files), then validate(): the flight
// software's own rule table (fsw/config_check.hpp, the one FlightApp::init applies) on the
// result, its refusal worded with the file, the TOML key, the value and the rule, e.g.
//   my.toml: executive.ekf_latency_frames = 10 must be below the 10 frames per EKF step
//   (nav_rate_hz 50 / ekf_rate_hz 5)
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "fsw/config_check.hpp"
#include "fsw/effect_catalogue.hpp"
#include "fsw/flight_app.hpp"

namespace cfg {

/// Which GNSS input feeds the filter.
enum class GnssSource : std::uint8_t {
  kRaw,  ///< pseudorange and pseudorange rate (tightly coupled; GNSS_RAW)
  kPvt,  ///< position/velocity solutions (loosely coupled; GNSS_PVT)
};
const char* to_string(GnssSource s);

struct FlightConfig {
  std::string name;
  std::string description;
  fsw::FlightAppConfig app{};
  GnssSource gnss_source = GnssSource::kRaw;
  /// Diagnosis priors (1-sigma, catalogue units) that the file sets; unset: the tool's default.
  std::array<std::optional<double>, fsw::kEffectCount> diagnosis_prior{};
  std::optional<double> outage_length_s, outage_period_s, outage_first_s, gain_skip_s;
  /// The files applied, in order (the shipped file first); empty: the schema's field defaults.
  std::vector<std::string> files;
  /// The file that set each key last, by dotted key ("executive.ekf_latency_frames").
  std::map<std::string, std::string> key_file;
};

struct FlightConfigResult {
  bool ok = false;
  std::string error;
};

/// Applies the TOML text onto `cfg` (whose fields are the defaults): the schema's per-key rules
/// only (validate() checks the result). On error cfg is unchanged.
FlightConfigResult parse_flight_config_text(const std::string& toml_text, const std::string& source_name,
                                            FlightConfig& cfg);
/// The same for a file ("<path>: cannot open flight configuration: ..." when it cannot be read).
FlightConfigResult parse_flight_config_file(const std::string& path, FlightConfig& cfg);

/// The flight software's rules (fsw::check_config, the table FlightApp::init applies) on c.app.
/// The error names the last file of c.files (the one the user gave), the TOML key, the value in
/// the file's unit, the rule, and the file that set the key when it is another one.
FlightConfigResult validate(const FlightConfig& c);
/// The same for a configuration a harness derived from `base` (an overlay such as the Monte
/// Carlo's scenario overlay): the error begins "<overlay> on <base's file>: ".
FlightConfigResult validate(const fsw::FlightAppConfig& app, const FlightConfig& base, const std::string& overlay);
/// The refusal text of a failed check (validate's wording; "" when check.ok()).
std::string describe(const fsw::ConfigCheck& check, const fsw::FlightAppConfig& app, const FlightConfig& origin);

/// The shipped flight configuration: "<data directory>/config/default.toml".
std::string default_flight_config_path();
/// The configuration a command flies: the schema's field defaults, the shipped file on top, then
/// `path` on top of that (a data set's file; empty: the shipped file alone), validated. On error
/// out is unchanged and the error names the file. The shipped file is read once per process.
FlightConfigResult load_flight_config(const std::string& path, FlightConfig& out);

// The forms for tools/ (whose errors are exceptions): std::runtime_error with the error above.
/// The shipped file alone (cached: read once per process).
const FlightConfig& shipped_flight_config();
/// The shipped file with `path` on top (empty: the shipped file alone).
FlightConfig flight_config(const std::string& path);
/// Throws "<what>: gnss.source = "...", but <why>; use "raw"" unless the configuration flies raw
/// receiver epochs (the commands whose input carries no solutions).
void require_raw_gnss(const FlightConfig& f, const std::string& what, const std::string& why);

}  // namespace cfg
