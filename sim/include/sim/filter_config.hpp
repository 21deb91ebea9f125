// Filter configuration files (TOML): the flight configuration. One schema, one set of defaults
// shipped as a file: config/default.toml, installed as <data dir>/config/default.toml
// (sim/data_dir.hpp), sets every key and is what `sdins sil`, `fsw`, `replay`, `montecarlo`, `paper`,
// `diagnose` and `fly` fly with (load_filter_config). The struct initialisers of fsw::FlightAppConfig
// and FilterConfig are only the schema's field defaults for a key a file leaves out.
// Recorded data come from sensors unlike the simulated aircraft's navigation-grade IMU: a MEMS IMU
// at 100-200 Hz with turn-on biases of a tenth of a degree per second, a GNSS receiver that gives
// position/velocity solutions at 4 Hz, an antenna and IMU mounted at an angle to the direction of
// travel. Each data set gets one file (config/datasets/*.toml) that says, with its reasons in
// comments, how the filter is set for it. The schema (every key optional; unknown keys rejected;
// errors "<file>:<line>:<col>: <message naming the key>") is documented in config/README.md.
//
// The same TOML rules and error format as the scenario files (sim/src/toml_schema.hpp).
#pragma once

#include <array>
#include <optional>
#include <string>

#include "fsw/effect_catalogue.hpp"
#include "fsw/flight_app.hpp"

namespace sim {

/// Which GNSS input feeds the filter.
enum class GnssSource : std::uint8_t {
  kRaw,  ///< pseudorange and pseudorange rate (tightly coupled; GNSS_RAW)
  kPvt,  ///< position/velocity solutions (loosely coupled; GNSS_PVT)
};
const char* to_string(GnssSource s);

struct FilterConfig {
  std::string name;
  std::string description;
  fsw::FlightAppConfig app{};
  GnssSource gnss_source = GnssSource::kRaw;
  /// Diagnosis priors (1-sigma, catalogue units) that the file sets; unset: the tool's default.
  std::array<std::optional<double>, fsw::kEffectCount> diagnosis_prior{};
  std::optional<double> outage_length_s, outage_period_s, outage_first_s, gain_skip_s;
};

struct FilterConfigParseResult {
  bool ok = false;
  std::string error;
};

/// Applies the TOML text onto `cfg` (whose fields are the defaults). On error cfg is unchanged.
FilterConfigParseResult parse_filter_config_text(const std::string& toml_text, const std::string& source_name,
                                                 FilterConfig& cfg);
/// The same for a file ("<path>: cannot open filter configuration" when it cannot be read).
FilterConfigParseResult parse_filter_config_file(const std::string& path, FilterConfig& cfg);

/// The shipped flight configuration: "<data directory>/config/default.toml".
std::string default_filter_config_path();
/// The configuration a command flies: the schema's field defaults, the shipped file on top, then
/// `path` on top of that (a data set's file; empty: the shipped file alone). On error (either file)
/// out is unchanged and the error names the file.
FilterConfigParseResult load_filter_config(const std::string& path, FilterConfig& out);

}  // namespace sim
