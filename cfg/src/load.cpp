// The one loader of the flight configuration and its one cache (flight_config.hpp): the shipped
// file, a data set's file on top, validated.
#include <map>
#include <mutex>
#include <stdexcept>

#include "cfg/data_dir.hpp"
#include "cfg/flight_config.hpp"

namespace cfg {

std::string default_flight_config_path() { return data_file("config/default.toml"); }

namespace {

/// The one cache: the shipped file, parsed once per path (the data directory may change with
/// --data-dir or in tests; entries are never removed, so references to them stay valid).
const FlightConfig* shipped(FlightConfigResult& r) {
  static std::mutex mutex;
  static std::map<std::string, FlightConfig> cache;
  const std::string path = default_flight_config_path();
  const std::lock_guard<std::mutex> lock(mutex);
  if (const auto it = cache.find(path); it != cache.end()) {
    r = {true, ""};
    return &it->second;
  }
  FlightConfig c;  // the schema's field defaults, then the shipped file
  r = parse_flight_config_file(path, c);
  if (!r.ok) {
    r.error = "the shipped flight configuration: " + r.error;
    return nullptr;
  }
  return &cache.emplace(path, std::move(c)).first->second;
}

}  // namespace

FlightConfigResult load_flight_config(const std::string& path, FlightConfig& out) {
  FlightConfigResult r;
  const FlightConfig* base = shipped(r);
  if (!base) return r;
  FlightConfig c = *base;
  if (!path.empty()) {
    r = parse_flight_config_file(path, c);
    if (!r.ok) return r;
  }
  r = validate(c);
  if (!r.ok) return r;
  out = std::move(c);
  return r;
}

const FlightConfig& shipped_flight_config() {
  FlightConfigResult r;
  const FlightConfig* c = shipped(r);
  if (c) r = validate(*c);
  if (!r.ok) throw std::runtime_error(r.error);
  return *c;
}

FlightConfig flight_config(const std::string& path) {
  FlightConfig f;
  const FlightConfigResult r = load_flight_config(path, f);
  if (!r.ok) throw std::runtime_error(r.error);
  return f;
}

void require_raw_gnss(const FlightConfig& f, const std::string& what, const std::string& why) {
  if (f.gnss_source != GnssSource::kRaw)
    throw std::runtime_error(what + ": gnss.source = \"" + std::string(to_string(f.gnss_source)) + "\", but " + why +
                             "; use \"raw\"");
}

}  // namespace cfg
