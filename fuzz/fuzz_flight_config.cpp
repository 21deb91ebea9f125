// libFuzzer target: the flight configuration reader and its validation (cfg/flight_config.hpp), a
// file input of replay, sil, diagnose, ... (--flight-config). Contract: no crash, no hang; a
// rejected file gets an error that names it.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "cfg/flight_config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  cfg::FlightConfig config;
  cfg::FlightConfigResult r = cfg::parse_flight_config_text(text, "fuzz.toml", config);
  if (r.ok) r = cfg::validate(config);
  if (!r.ok && r.error.find("fuzz.toml") == std::string::npos) {
    std::fprintf(stderr, "fuzz_flight_config: contract violated: an error that does not name the file: %s\n",
                 r.error.c_str());
    std::abort();
  }
  return 0;
}
