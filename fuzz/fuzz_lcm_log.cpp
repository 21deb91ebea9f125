// libFuzzer target: the LCM log reader and the replay decoder (hal/lcm_log.hpp,
// hal/lcm_log_sink.hpp LcmReplayReader). The reader maps files, so each input is written to a
// scratch file first. Contract: no crash, reading ends, every delivered input is finite and in
// time order (t_s never decreases), and the reader's delivered count matches what it returned.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "hal/lcm_log_sink.hpp"

namespace {

void check(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "fuzz_lcm_log: contract violated: %s\n", what);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = "/tmp/sdins_fuzz_lcm_log_" + std::to_string(::getpid()) + ".lcmlog";
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return 0;
  if (size > 0) std::fwrite(data, 1, size, f);
  std::fclose(f);
  hal::LcmReplayReader reader;
  hal::LcmReplayConfig cfg;
  cfg.max_event_bytes = 1u << 20;
  if (reader.open(path, cfg) != hal::LcmLogStatus::kOk) return 0;
  fsw::InputEvent in;
  std::uint64_t n = 0;
  double last_t_s = 0.0;
  while (reader.next(in) == hal::LcmLogStatus::kOk) {
    check(++n <= size, "no more inputs than bytes");
    check(std::isfinite(in.t_s), "inputs finite");
    if (!(n == 1 || in.t_s >= last_t_s)) std::fprintf(stderr, "order: %.17g after %.17g (n=%llu)\n", in.t_s, last_t_s, (unsigned long long)n);
    check(n == 1 || in.t_s >= last_t_s, "inputs delivered in time order");
    last_t_s = in.t_s;
    if (in.kind == fsw::InputEvent::Kind::kImu)
      check(in.imu.dtheta_rad.allFinite() && in.imu.dv_mps.allFinite() && in.imu.dt_s > 0.0,
            "IMU input finite");
    if (in.kind == fsw::InputEvent::Kind::kGnssRaw)
      check(in.gnss.n_meas >= 0 && in.gnss.n_meas <= fsw::kMaxGnssChannels, "GNSS measurement count in range");
  }
  check(reader.stats().delivered == n, "delivered count matches");
  return 0;
}
