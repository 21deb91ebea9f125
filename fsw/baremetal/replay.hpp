// The target replay (docs/baremetal-qemu.md): one source file, built into the Cortex-M7 image for
// QEMU's mps2-an500 (fsw/baremetal/mps2) and into the host executable sdins_target (tools/target),
// that runs the flight application of HIL (fsw::FlightApp<Layout24Full> and <Layout15Full>, fed
// only through on_almanac / on_gnss / on_imu) on a recorded input and writes the navigation output
// as exact text (hex of the doubles), so the two builds compare bit for bit.
//
// INPUT (little-endian, written by `sdins_target record` from an LCM log of `sdins sil`):
//   header   "SDTR", u32 version, u32 n_fingerprint, n_fingerprint x u32 (the size of the
//            configuration's encoding and the layout of the event structs below,
//            layout_fingerprint()), u32 n, then n bytes: the flight configuration's values
//            (fsw/flight_app_config_wire.hpp: every field by name order, 8 bytes each, the same on
//            every ABI; the shipped config/default.toml, the one HIL uses, or the one given).
//   events   u32 tag ('A' almanac, 'G' raw GNSS epoch, 'I' IMU sample), u32 payload size, then the
//            object bytes of fsw::GpsAlmanac / fsw::GnssRawEpoch / fsw::ImuSample, in log order.
// OUTPUT (text lines; every double as 16 hex digits of its IEEE-754 bits):
//   "F<m> t lat lon h vE vN vU qw qx qy qz"            one per navigation frame (m = 24 or 15)
//   "E<m> t clock_bias clock_drift nis_sum pr prr P00 .. Pnn"  one per EKF epoch (P's diagonal)
//   "T<m> frame imu_ticks gnss_ticks ekf"             per frame, only with a tick counter (target)
//   "D<m> digest frames epochs"                       at the end: hal::FswNode's navigation digest
//   "S<m> status counters"                            at the end: the apps' health (decimal)
//   "I<m> imu gnss"   with a tick counter: the worst single on_imu / on_gnss before initialisation
// Nothing here does I/O: the board passes read / write / tick functions (semihosting or stdio).
#pragma once

#include <cstddef>
#include <cstdint>

namespace sdins_target {

inline constexpr std::uint32_t kFormatVersion = 2;  ///< 2: the configuration by value, not its object bytes
inline constexpr std::uint32_t kTagAlmanac = 'A';
inline constexpr std::uint32_t kTagGnss = 'G';
inline constexpr std::uint32_t kTagImu = 'I';
inline constexpr int kFingerprintWords = 9;

/// Sizes and member offsets of the recorded structs on this build's ABI.
void layout_fingerprint(std::uint32_t (&out)[kFingerprintWords]);

struct Board {
  /// Reads up to n bytes; returns how many (fewer only at the end of the input or on an error).
  std::size_t (*read)(void* dst, std::size_t n);
  /// Writes n bytes of output text.
  void (*write)(const char* s, std::size_t n);
  /// A free-running down-counter (24-bit SysTick under QEMU -icount) or nullptr: no timing lines.
  std::uint32_t (*ticks)();
  std::uint32_t tick_mask;  ///< the counter's width (0xFFFFFF for SysTick)
};

/// Exit codes of run_replay.
enum class ReplayResult : int {
  kOk = 0,
  kBadHeader = 2,     ///< magic, version or layout fingerprint differ
  kBadConfig = 3,     ///< a configuration value its field cannot hold, or FlightApp::init rejected it
  kBadEvent = 4,      ///< unknown tag or wrong payload size
  kTruncated = 5,     ///< the input ended inside an event
};

ReplayResult run_replay(const Board& board);

/// The libm probe: the functions fsw/ calls (sin, cos, tan, asin, atan2, exp, hypot, pow) on
/// kLibmProbeArgs deterministic arguments each (an integer generator: the same on both builds),
/// one line "L<function> hex" per result. The two C libraries (newlib on the target, glibc on the
/// host) round some results differently in the last bit; the probe counts how often.
inline constexpr int kLibmProbeArgs = 20000;
void run_libm_probe(const Board& board);

}  // namespace sdins_target
