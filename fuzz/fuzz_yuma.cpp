// libFuzzer target: the YUMA almanac reader, sim::parse_yuma_text (sim/include/sim/almanac.hpp).
//
// Contract checked on every input (the header's): it never throws (so nothing is caught here:
// an exception escaping is a finding, reported by libFuzzer as a crash); the result is either the
// satellites or "<source>:<line>: <reason>", never both; accepted satellites are sorted by PRN,
// unique, PRN 1..32, eccentricity in [0, 1), sqrt(A) > 0, every value finite.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "sim/almanac.hpp"

namespace {

void check(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "fuzz_yuma: contract violated: %s\n", what);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const sim::AlmanacParseResult r = sim::parse_yuma_text(text, "fuzz.alm");
  check(r.ok() == r.error.empty(), "exactly one of almanac and error");
  if (!r.ok()) {
    check(r.error.rfind("fuzz.alm:", 0) == 0, "the error names the source");
    return 0;
  }
  check(!r.almanac->empty(), "at least one record");
  int last_prn = 0;
  for (const sim::AlmanacEntry& e : *r.almanac) {
    check(e.prn >= 1 && e.prn <= 32 && e.prn > last_prn, "PRNs in 1..32, sorted, unique");
    last_prn = e.prn;
    check(e.eccentricity >= 0.0 && e.eccentricity < 1.0, "eccentricity in [0, 1)");
    check(e.sqrt_a_sqrtm > 0.0, "sqrt(A) > 0");
    for (double v : {e.eccentricity, e.toa_s, e.inclination_rad, e.omega_dot_radps, e.sqrt_a_sqrtm, e.omega0_rad,
                     e.arg_perigee_rad, e.mean_anomaly_rad, e.af0_s, e.af1_sps})
      check(std::isfinite(v), "finite values");
  }
  return 0;
}
