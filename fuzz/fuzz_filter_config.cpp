// libFuzzer target: the filter configuration reader (sim/filter_config.hpp), a file input of
// replay, sil and diagnose (--filter-config). Contract: no crash, no hang; a rejected file gets an
// error that names it.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "sim/filter_config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  sim::FilterConfig cfg;
  const sim::FilterConfigParseResult r = sim::parse_filter_config_text(text, "fuzz.toml", cfg);
  if (!r.ok && r.error.find("fuzz.toml") == std::string::npos) {
    std::fprintf(stderr, "fuzz_filter_config: contract violated: an error that does not name the file: %s\n",
                 r.error.c_str());
    std::abort();
  }
  return 0;
}
