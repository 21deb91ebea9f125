// libFuzzer target: the importers' parsers (tools/importers.hpp) and their time-tag gate
// (hal/time_tag_gate.hpp). The first byte picks the reader, the rest is the file. Contract: no
// crash, no hang; every data line is accepted or rejected (accepted + rejected == lines); accepted
// IMU ticks and PSINS times of week increase strictly within one time base; accepted values are
// finite.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "tools/importers.hpp"

namespace {
[[noreturn]] void violated(const char* what) {
  std::fprintf(stderr, "fuzz_importers: contract violated: %s\n", what);
  std::abort();
}
void check_lines(const tools::LineStats& s) {
  if (s.accepted + s.rejected != s.lines) violated("accepted + rejected != lines");
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  std::istringstream in(text);
  tools::LineStats st;
  try {
    switch (data[0] % 8) {
      case 0: {
        const auto v = tools::read_gnss_imu_csv(in, st);
        check_lines(st);
        for (std::size_t k = 1; k < v.size(); ++k)
          if (st.time_base_changes == 0 && !(v[k].tick_ms > v[k - 1].tick_ms)) violated("IMU tick not increasing");
        for (const auto& s : v)
          for (int i = 0; i < 3; ++i)
            if (!std::isfinite(s.accel_g[i]) || !std::isfinite(s.gyro_dps[i])) violated("non-finite IMU value");
        break;
      }
      case 1: {
        const auto v = tools::read_psins_imu(in, st);
        check_lines(st);
        for (std::size_t k = 1; k < v.size(); ++k)
          if (st.time_base_changes == 0 && !(v[k].tow_s > v[k - 1].tow_s)) violated("PSINS time not increasing");
        break;
      }
      case 2: tools::read_psins_obs(in, st); break;
      case 3: tools::read_psins_eph(in, st); break;
      case 4: {
        const tools::PosFile p = tools::read_rtklib_pos(in);
        if (p.samples.size() != p.lines.accepted) violated("pos: samples != accepted");
        break;
      }
      case 5: {
        tools::RinexObsStats rs;
        tools::read_rinex3_obs(in, rs);
        break;
      }
      case 6: tools::read_rinex3_nav(in, st); break;
      case 7: {
        const std::vector<std::uint8_t> bytes(data + 1, data + size);
        const tools::TimeTag t = tools::parse_time_tag(bytes);
        if (t.records.size() * tools::TimeTag::kRecordBytes + t.trailing_bytes + tools::TimeTag::kHeaderBytes != bytes.size())
          violated("time tag: bytes not accounted for");
        break;
      }
    }
  } catch (const std::runtime_error&) {
    // a file that is not of the expected format: a clear error is the contract
  }
  return 0;
}
