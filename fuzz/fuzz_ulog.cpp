// libFuzzer target: the PX4 ULog reader (tools/ulog.hpp). Contract: no crash, no hang; the only
// exception is std::runtime_error for bytes that are not a ULog (short header, wrong magic,
// unknown incompatible flags); every kept data message lies inside the file and fits its format;
// every field value read from it is in bounds (value() returns NaN, never reads outside); the
// bytes skipped are at most the file.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <vector>

#include "tools/ulog.hpp"

namespace {
[[noreturn]] void violated(const char* what) {
  std::fprintf(stderr, "fuzz_ulog: contract violated: %s\n", what);
  std::abort();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  tools::ulog::File f;
  try {
    f = tools::ulog::parse(std::vector<std::uint8_t>(data, data + size));
  } catch (const std::runtime_error&) {
    return 0;  // not a ULog: the documented refusal
  }
  if (f.damage.bytes_skipped > size) violated("more bytes skipped than the file has");
  std::uint64_t kept = 0;
  for (const tools::ulog::Subscription& s : f.subscriptions) {
    if (s.format == nullptr) {
      if (!s.data.empty()) violated("data kept for a topic without a usable format");
      continue;
    }
    if (!s.format->resolved) violated("a subscription bound to an unresolved format");
    for (const tools::ulog::DataRef& d : s.data) {
      if (d.offset + d.size > f.bytes.size()) violated("a data message outside the file");
      if (d.size < s.format->min_size || d.size > s.format->size) violated("a data message that does not fit its format");
      for (const tools::ulog::Field& fl : s.format->fields) {
        if (fl.offset + fl.size > s.format->size) violated("a field outside its format");
        (void)tools::ulog::value(f, d, fl, 0);
        (void)tools::ulog::value(f, d, fl, fl.count);  // past the array: NaN
        (void)tools::ulog::value_u64(f, d, fl);
      }
    }
    kept += s.data.size();
  }
  if (kept != f.data_messages) violated("data_messages does not count the kept data");
  for (const tools::ulog::InfoValue& v : f.info) {
    (void)v.text();
    (void)v.number();
  }
  return 0;
}
