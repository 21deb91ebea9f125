// One CAN or CAN FD frame as every part of the CAN HAL (codec, assembler, transports, candump
// logs) passes it around. Plain data, fixed size, no allocation.
#pragma once

#include <array>
#include <cstdint>

namespace hal {

inline constexpr std::uint32_t kCanStdIdMask = 0x7FFu;       ///< 11-bit identifier
inline constexpr std::uint32_t kCanExtIdMask = 0x1FFFFFFFu;  ///< 29-bit identifier
inline constexpr int kCanMaxLen = 8;                          ///< classic CAN payload
inline constexpr int kCanFdMaxLen = 64;                       ///< CAN FD payload

struct CanFrame {
  std::uint32_t id = 0;     ///< 11-bit (extended == false) or 29-bit identifier
  bool extended = false;    ///< 29-bit identifier
  bool fd = false;          ///< CAN FD frame (FDF): payload up to 64 bytes
  bool brs = false;         ///< CAN FD bit rate switch
  bool esi = false;         ///< CAN FD error state indicator
  std::uint8_t len = 0;     ///< payload length in bytes (classic: 0..8; FD: a valid FD length)
  double timestamp_s = 0.0; ///< receive time [s, Unix epoch] (transports fill it; 0 when unknown)
  std::array<std::uint8_t, kCanFdMaxLen> data{};
};

/// CAN FD payload lengths are 0..8, 12, 16, 20, 24, 32, 48, 64.
constexpr bool can_fd_len_valid(int len) {
  return (len >= 0 && len <= 8) || len == 12 || len == 16 || len == 20 || len == 24 || len == 32 || len == 48 ||
         len == 64;
}
/// DLC code (0..15) for a valid payload length, -1 otherwise.
constexpr int can_len_to_dlc(int len) {
  if (len >= 0 && len <= 8) return len;
  switch (len) {
    case 12: return 9;
    case 16: return 10;
    case 20: return 11;
    case 24: return 12;
    case 32: return 13;
    case 48: return 14;
    case 64: return 15;
    default: return -1;
  }
}
/// Payload length of a DLC code (FD table for 9..15), -1 outside 0..15.
constexpr int can_dlc_to_len(int dlc) {
  constexpr int kLen[16] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64};
  return (dlc >= 0 && dlc <= 15) ? kLen[dlc] : -1;
}

/// Well-formed: identifier within its width, length valid for the frame type, no BRS/ESI on a
/// classic frame.
constexpr bool can_frame_valid(const CanFrame& f) {
  if (f.id > (f.extended ? kCanExtIdMask : kCanStdIdMask)) return false;
  if (f.fd) return can_fd_len_valid(f.len);
  return f.len <= kCanMaxLen && !f.brs && !f.esi;
}

/// Same identifier, flags, length and payload bytes (the timestamp is not compared).
bool can_frame_equal(const CanFrame& a, const CanFrame& b);

}  // namespace hal
