// One CAN bus interface, several transports chosen by name (the ArduPilot SITL CAN pattern):
//
//   socketcan:IFACE     Linux SocketCAN raw socket on IFACE (vcan0, can0): CAN FD frames,
//                       non-blocking, kernel receive timestamps (SO_TIMESTAMP). Needs AF_CAN in
//                       the kernel; open() returns kNoSupport with the reason where it is missing.
//   udp:PORT            UDP multicast speaking python-can's `udp_multicast` wire format (one
//                       msgpack map per frame) on python-can's default group
//                       ff15:7079:7468:6f6e:6465:6d6f:6d63:6173 (IPv6). Local to this host by
//                       default (hop limit 0, datagrams from other hosts counted and dropped);
//                       udp:PORT?scope=lan[&iface=IFACE]: hop limit 1 and every sender, so
//                       `can.Bus(interface="udp_multicast", port=PORT)` on the LAN is a peer.
//   udp:GROUP:PORT      the same on another group, e.g. udp:239.74.163.2:43113 (python-can's
//                       IPv4 default) or udp:[ff15::1234]:43113.
//   loop:NAME           in-process bus: every CanBus opened on the same NAME in this process
//                       receives what the others send (tests, in-process SIL).
//
// No backend delivers a bus's own frames back to it (SocketCAN: the kernel default; UDP: frames
// whose source address and port are this bus's sending socket are dropped and counted; loop:
// the sender is skipped). Every call returns a status; nothing throws; last_error() says why
// in words (with the errno text where there is one).
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "hal/can_frame.hpp"

namespace hal {

enum class CanBusStatus : std::uint8_t {
  kOk = 0,
  kTimeout,     ///< receive: nothing arrived in time
  kNotOpen,     ///< the bus is not open
  kBadName,     ///< open: unknown transport or malformed name
  kNoSupport,   ///< open: the kernel / host lacks what the transport needs (e.g. no AF_CAN)
  kNoDevice,    ///< open: interface missing or unusable (e.g. not CAN FD capable)
  kBadFrame,    ///< send: invalid identifier or length
  kTxBusy,      ///< send: the transmit queue stayed full for the send timeout
  kIoError,     ///< any other system call failure
  kStopped,     ///< receive(f, timeout, stop): the stop flag was set while waiting
};
const char* to_string(CanBusStatus s);

struct CanBusStats {
  std::uint64_t sent = 0;
  std::uint64_t received = 0;
  std::uint64_t own_dropped = 0;       ///< our own frames seen again (UDP multicast loop), dropped
  std::uint64_t malformed = 0;         ///< datagrams / kernel frames that are not a valid frame
  std::uint64_t unsupported = 0;       ///< remote and error frames (the protocol uses neither)
  std::uint64_t queue_dropped = 0;     ///< loop: frames lost because a receiver's queue was full; socketcan:
                                       ///< frames the kernel dropped, this socket's buffer full (SO_RXQ_OVFL)
  std::uint64_t foreign_dropped = 0;   ///< udp scope=local: datagrams from another host, dropped
};
/// "sent=.. received=.. own_dropped=.. foreign_dropped=.. malformed=.. unsupported=.. queue_dropped=.."
std::string to_string(const CanBusStats& s);

/// One transport backend (see the table above). CanBus owns one.
class CanTransport {
 public:
  virtual ~CanTransport() = default;
  /// arg: the part of the bus name after "KIND:".
  virtual CanBusStatus open(const std::string& arg) = 0;
  virtual CanBusStatus send(const CanFrame& f) = 0;
  /// timeout_s < 0 waits indefinitely, 0 only takes what is already there.
  virtual CanBusStatus receive(CanFrame& f, double timeout_s) = 0;
  virtual int fd() const = 0;
  virtual void close() = 0;

  std::string error;  ///< reason of the last failure
  int sys_errno = 0;  ///< errno of the last failed system call (0 if none)
  CanBusStats stats;
};

class CanBus {
 public:
  CanBus();
  ~CanBus();
  CanBus(const CanBus&) = delete;
  CanBus& operator=(const CanBus&) = delete;
  CanBus(CanBus&&) noexcept;
  CanBus& operator=(CanBus&&) noexcept;

  /// Opens the bus named name (see the table above); closes a bus that was open.
  CanBusStatus open(const std::string& name);
  /// Sends one frame (waits up to send_timeout_s when the transmit queue is full).
  CanBusStatus send(const CanFrame& f);
  /// The next frame from another node, with its receive time in timestamp_s (Unix time, s).
  CanBusStatus receive(CanFrame& f, double timeout_s);
  /// The same, but the wait is cut short (kStopped) within kCanStopCheck_s of stop being set (e.g. by
  /// a SIGINT handler: a recorder keeps what it received and ends at once, docs/faults.md).
  CanBusStatus receive(CanFrame& f, double timeout_s, const std::atomic<bool>& stop);
  /// A descriptor that polls readable when receive() has a frame (-1 when closed).
  int fd() const;
  void close();

  bool is_open() const { return t_ != nullptr; }
  const std::string& name() const { return name_; }
  const std::string& last_error() const;
  int last_errno() const;
  const CanBusStats& stats() const;

 private:
  std::unique_ptr<CanTransport> t_;
  std::string name_;
  std::string error_;  ///< why the last open() failed
  int errno_ = 0;      ///< errno of the last failed open()
};

/// Send timeout of the socket transports [s].
inline constexpr double kCanSendTimeout_s = 0.1;
/// Receive buffer socketcan: asks for [bytes] (a CAN FD frame takes about 1 KiB of it in the kernel).
inline constexpr int kSocketCanRxBufferBytes = 4 << 20;
/// How often receive(f, timeout, stop) looks at the stop flag while waiting [s].
inline constexpr double kCanStopCheck_s = 0.05;

}  // namespace hal
