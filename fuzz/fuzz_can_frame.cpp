// libFuzzer target: the CAN receive side (hal/can_rx_assembler.hpp and the frame decoders of
// hal/can_protocol.hpp). The input is a sequence of frames, each [id: 2 bytes LE][len: 1 byte]
// [flags: 1 byte][payload: len bytes]; frames whose length is not a CAN length are cut short.
// Contract: no crash, every counter consistent (delivered <= frames pushed), every delivered IMU
// sample and GPS epoch finite and within the protocol's ranges.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "hal/can_frame.hpp"
#include "hal/can_rx_assembler.hpp"

namespace {

void check(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "fuzz_can_frame: contract violated: %s\n", what);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static hal::CanRxAssembler* rx = nullptr;
  if (rx == nullptr) rx = new hal::CanRxAssembler();
  *rx = hal::CanRxAssembler();
  std::size_t pos = 0;
  std::uint32_t pushed = 0;
  double t = 0.0;
  while (pos + 4 <= size) {
    hal::CanFrame f;
    f.id = static_cast<std::uint32_t>(data[pos] | (data[pos + 1] << 8)) & 0x7FFu;
    const int len = data[pos + 2] % 65;
    const std::uint8_t flags = data[pos + 3];
    pos += 4;
    f.fd = (flags & 1) != 0;
    f.brs = (flags & 2) != 0;
    f.extended = (flags & 4) != 0;
    const int n = static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(len), size - pos));
    f.len = static_cast<std::uint8_t>(n);
    for (int i = 0; i < n; ++i) f.data[static_cast<std::size_t>(i)] = data[pos + static_cast<std::size_t>(i)];
    pos += static_cast<std::size_t>(n);
    rx->push(f, t);
    ++pushed;
    t += 0.001;
    fsw::ImuSample s;
    while (rx->pop_imu(s)) {
      check(std::isfinite(s.t_s) && s.dt_s > 0.0 && s.dt_s <= 0.1, "delivered IMU time and dt sane");
      check(s.dtheta_rad.allFinite() && s.dv_mps.allFinite(), "delivered IMU increments finite");
    }
    fsw::GnssRawEpoch e;
    while (rx->pop_gps(e)) {
      check(e.n_meas >= 0 && e.n_meas <= fsw::kMaxGnssChannels, "epoch measurement count in range");
      check(std::isfinite(e.gps_tow_s) && std::isfinite(e.t_s), "epoch times finite");
      for (int k = 0; k < e.n_meas; ++k) {
        const auto& m = e.meas[static_cast<std::size_t>(k)];
        check(m.prn >= 1 && m.prn <= 32 && std::isfinite(m.pseudorange_m) && std::isfinite(m.pseudorange_rate_mps),
              "delivered measurement sane");
      }
    }
    fsw::GpsAlmanac a;
    while (rx->pop_almanac(a)) check(fsw::almanac_valid(a), "delivered almanac valid");
  }
  rx->poll(t + 10.0);
  check(rx->health().frames == pushed, "every frame counted");
  return 0;
}
