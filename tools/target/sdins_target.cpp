// sdins_target (docs/baremetal-qemu.md): the host side of the Cortex-M7 image's QEMU run.
//   sdins_target record LOG INPUT [FILTER_CONFIG]
//                                   an LCM log's inputs (IMU, GNSS_RAW, GPS_ALMANAC in time order,
//                                   as `sdins replay` reads them) and the flight configuration HIL
//                                   uses (the shipped config/default.toml of the data directory,
//                                   cfg/data_dir.hpp, with FILTER_CONFIG on top as `sdins replay
//                                   --filter-config` applies it) into the target replay's input
//                                   (fsw/baremetal/replay.hpp)
//   sdins_target replay INPUT OUT   the host replay of that input: fsw/baremetal/replay.cpp, the
//                                   source the image runs, linked with the host's sdins_fsw
//   sdins_target libm OUT           the libm probe (replay.hpp) with the host's C library
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "hal/fsw_node.hpp"
#include "hal/lcm_log_sink.hpp"
#include "replay.hpp"
#include "cfg/flight_config.hpp"
#include "fsw/flight_app_config_wire.hpp"

namespace {

std::FILE* g_in = nullptr;
std::FILE* g_out = nullptr;

std::size_t host_read(void* dst, std::size_t n) { return std::fread(dst, 1, n, g_in); }
void host_write(const char* s, std::size_t n) { std::fwrite(s, 1, n, g_out); }

template <class T>
bool put(std::FILE* f, const T& v) {
  return std::fwrite(&v, sizeof v, 1, f) == 1;
}

template <class T>
bool put_event(std::FILE* f, std::uint32_t tag, const T& obj) {
  const std::uint32_t head[2] = {tag, static_cast<std::uint32_t>(sizeof obj)};
  return put(f, head) && std::fwrite(&obj, sizeof obj, 1, f) == 1;
}

int record(const std::string& log, const std::string& path, const std::string& filter_config) {
  cfg::FlightConfig filter;
  const cfg::FlightConfigResult fr = cfg::load_flight_config(filter_config, filter);
  if (!fr.ok) {
    std::fprintf(stderr, "sdins_target: %s\n", fr.error.c_str());
    return 1;
  }
  hal::LcmReplayReader reader;
  if (reader.open(log) != hal::LcmLogStatus::kOk) {
    std::fprintf(stderr, "sdins_target: cannot read %s: %s\n", log.c_str(), reader.error().c_str());
    return 1;
  }
  // Written beside and renamed into place when complete: a failed record leaves no partial input.
  const std::string part = path + ".part";
  std::FILE* f = std::fopen(part.c_str(), "wb");
  if (f == nullptr) {
    std::fprintf(stderr, "sdins_target: cannot write %s\n", part.c_str());
    return 1;
  }
  std::uint32_t fp[sdins_target::kFingerprintWords];
  sdins_target::layout_fingerprint(fp);
  std::vector<std::uint8_t> cfg_wire(fsw::flight_config_wire_bytes());
  bool ok = fsw::encode_flight_config(filter.app, cfg_wire.data(), cfg_wire.size()) == cfg_wire.size();
  ok = ok && std::fwrite("SDTR", 1, 4, f) == 4 && put(f, sdins_target::kFormatVersion) &&
       put(f, static_cast<std::uint32_t>(sdins_target::kFingerprintWords)) && put(f, fp) &&
       put(f, static_cast<std::uint32_t>(cfg_wire.size())) &&
       std::fwrite(cfg_wire.data(), 1, cfg_wire.size(), f) == cfg_wire.size();
  std::uint64_t n_imu = 0, n_gnss = 0, n_alm = 0;
  fsw::InputEvent in;
  while (ok && reader.next(in) == hal::LcmLogStatus::kOk) {
    switch (in.kind) {
      case fsw::InputEvent::Kind::kAlmanac:
        ok = put_event(f, sdins_target::kTagAlmanac, in.almanac);
        ++n_alm;
        break;
      case fsw::InputEvent::Kind::kGnssRaw:
        ok = put_event(f, sdins_target::kTagGnss, in.gnss);
        ++n_gnss;
        break;
      case fsw::InputEvent::Kind::kImu:
        ok = put_event(f, sdins_target::kTagImu, in.imu);
        ++n_imu;
        break;
      case fsw::InputEvent::Kind::kGnssPvt: break;  // not read (no gnss_pvt_channel)
    }
  }
  ok = std::fclose(f) == 0 && ok;
  const std::uint64_t rejected = reader.stats().rejected() + reader.log_stats().total_rejections();
  std::printf("sdins_target record: %llu IMU samples, %llu GNSS epochs, %llu almanac entries, %llu log rejections\n",
              static_cast<unsigned long long>(n_imu), static_cast<unsigned long long>(n_gnss),
              static_cast<unsigned long long>(n_alm), static_cast<unsigned long long>(rejected));
  if (ok) ok = std::rename(part.c_str(), path.c_str()) == 0;
  if (!ok) {
    std::fprintf(stderr, "sdins_target: writing %s failed\n", path.c_str());
    std::remove(part.c_str());
  }
  return ok && rejected == 0 ? 0 : 1;
}

int replay(const std::string& in, const std::string& out) {
  g_in = std::fopen(in.c_str(), "rb");
  g_out = std::fopen(out.c_str(), "w");
  if (g_in == nullptr || g_out == nullptr) {
    std::fprintf(stderr, "sdins_target: cannot open %s or %s\n", in.c_str(), out.c_str());
    return 1;
  }
  const sdins_target::Board board{host_read, host_write, nullptr, 0u};
  const sdins_target::ReplayResult r = sdins_target::run_replay(board);
  std::fprintf(g_out, "END %d 0\n", static_cast<int>(r));
  const bool ok = std::fclose(g_out) == 0;
  std::fclose(g_in);
  if (r != sdins_target::ReplayResult::kOk) std::fprintf(stderr, "sdins_target: replay result %d\n", static_cast<int>(r));
  return r == sdins_target::ReplayResult::kOk && ok ? 0 : 1;
}

int libm(const std::string& out) {
  g_out = std::fopen(out.c_str(), "w");
  if (g_out == nullptr) {
    std::fprintf(stderr, "sdins_target: cannot write %s\n", out.c_str());
    return 1;
  }
  sdins_target::run_libm_probe(sdins_target::Board{host_read, host_write, nullptr, 0u});
  return std::fclose(g_out) == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  if ((argc == 4 || argc == 5) && std::strcmp(argv[1], "record") == 0)
    return record(argv[2], argv[3], argc == 5 ? argv[4] : "");
  if (argc == 4 && std::strcmp(argv[1], "replay") == 0) return replay(argv[2], argv[3]);
  if (argc == 3 && std::strcmp(argv[1], "libm") == 0) return libm(argv[2]);
  std::fprintf(stderr, "usage: sdins_target record LOG INPUT [FILTER_CONFIG] | replay INPUT OUTPUT | libm OUTPUT\n");
  return 64;
}
