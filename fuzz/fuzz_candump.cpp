// libFuzzer target: the candump log line parser (hal/can_log.hpp parse_candump_line). Every line
// of the input is parsed; contract: no crash, a line is either a frame (valid identifier and
// length) or rejected with a reason.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "hal/can_log.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    hal::CanFrame f;
    std::string iface;
    const hal::CandumpLine r = hal::parse_candump_line(text.substr(start, end - start), f, iface);
    if (r == hal::CandumpLine::kFrame) {
      if (!(f.len <= 64 && (f.fd || f.len <= 8) && (f.extended ? f.id <= 0x1FFFFFFFu : f.id <= 0x7FFu))) {
        std::fprintf(stderr, "fuzz_candump: contract violated: accepted frame out of range\n");
        std::abort();
      }
    }
    start = end + 1;
  }
  return 0;
}
