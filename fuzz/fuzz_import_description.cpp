// libFuzzer target: the recording description reader (tools/import_describe.hpp), the file input of
// `sdins import describe`. Contract: no crash, no hang, no exception (the parser never throws); a
// rejected file gets one error that names it; an accepted one describes at least one stream whose
// columns and unit scales are set, finite and positive where they must be.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "tools/import_describe.hpp"

namespace {
[[noreturn]] void violated(const char* what, const std::string& detail) {
  std::fprintf(stderr, "fuzz_import_description: contract violated: %s: %s\n", what, detail.c_str());
  std::abort();
}
void check_scale(double s, const char* what) {
  if (!std::isfinite(s) || s == 0.0) violated("a unit scale that is not finite and non-zero", what);
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  tools::RecordingDescription d;
  const tools::DescriptionParseResult r = tools::parse_recording_description_text(text, "fuzz.toml", "/data", d);
  if (!r.ok) {
    if (r.error.rfind("fuzz.toml", 0) != 0) violated("an error that does not start with the file", r.error);
    return 0;
  }
  if (!r.error.empty()) violated("an accepted description with an error", r.error);
  if (!d.imu.present && !d.gnss.present && !d.raw.present && !d.reference.present) violated("no stream", "");
  if (d.imu.present) {
    if (d.imu.table.files.empty() || !d.imu.gyro.set() || !d.imu.accel.set() || !d.imu.time.column.set())
      violated("an IMU stream without its file or columns", "");
    check_scale(d.imu.gyro.scale, "imu.gyro");
    check_scale(d.imu.accel.scale, "imu.accel");
    check_scale(d.imu.time.scale_s, "imu.time");
    if (!(d.imu.max_accel_mps2 > 0.0) || !(d.imu.max_gyro_radps > 0.0)) violated("a non-positive IMU range", "");
  }
  if (d.gnss.present && d.gnss.format == "table") {
    if (!d.gnss.pos.lat.set() || !d.gnss.pos.lon.set() || !d.gnss.pos.height.set()) violated("GNSS without position", "");
    check_scale(d.gnss.pos.angle_scale, "gnss angles");
    check_scale(d.gnss.time.scale_s, "gnss.time");
  }
  if (d.reference.present && d.reference.kind.empty()) violated("a reference without its kind", "");
  return 0;
}
