// The CAN transport backends behind hal::CanBus, and their wire-format helpers (exposed so the
// conversions are unit-tested even where the kernel lacks the transport, e.g. no AF_CAN).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "hal/can_bus.hpp"

struct canfd_frame;  // <linux/can.h>
struct sockaddr_storage;  // <sys/socket.h>

namespace hal {

// ---- SocketCAN ----------------------------------------------------------------------------------

/// CanFrame -> struct canfd_frame (classic frames use the same layout, written as CAN_MTU bytes).
/// Returns the number of bytes to write (CAN_MTU or CANFD_MTU), 0 for an invalid frame.
int to_linux_frame(const CanFrame& f, canfd_frame& out);
/// struct canfd_frame as read (nbytes: CAN_MTU or CANFD_MTU) -> CanFrame. False for a wrong size,
/// an invalid length, or remote / error frames (unsupported set then).
bool from_linux_frame(const canfd_frame& in, int nbytes, CanFrame& out, bool& unsupported);

class SocketCanTransport final : public CanTransport {
 public:
  ~SocketCanTransport() override { close(); }
  CanBusStatus open(const std::string& iface) override;
  CanBusStatus send(const CanFrame& f) override;
  CanBusStatus receive(CanFrame& f, double timeout_s) override;
  int fd() const override { return fd_; }
  void close() override;

 private:
  int fd_ = -1;
};

// ---- UDP multicast (python-can udp_multicast wire format) -----------------------------------------

inline constexpr const char* kUdpDefaultGroupV6 = "ff15:7079:7468:6f6e:6465:6d6f:6d63:6173";
inline constexpr const char* kUdpDefaultGroupV4 = "239.74.163.2";
inline constexpr int kUdpDefaultPort = 43113;
inline constexpr int kUdpHopLimit = 1;       ///< scope=lan: python-can's hop limit (the local segment)
inline constexpr int kUdpLocalHopLimit = 0;  ///< scope=local (the default): the datagrams never leave the host
inline constexpr std::size_t kUdpMaxDatagram = 4096;  ///< python-can's receive buffer

/// One frame as python-can's pack_message() writes it: a msgpack map of timestamp,
/// arbitration_id, is_extended_id, is_remote_frame, is_error_frame, channel (nil), dlc (payload
/// length, as python-can counts it), data (bin), is_fd, bitrate_switch, error_state_indicator.
void udp_pack(const CanFrame& f, double timestamp_s, std::vector<std::uint8_t>& out);
enum class UdpUnpack : std::uint8_t { kOk, kMalformed, kUnsupported };
/// Parses one datagram. kMalformed: not msgpack, not a map, missing/ill-typed arbitration_id or
/// data, dlc != data length, invalid identifier or length; kUnsupported: remote or error frame.
/// The message's own timestamp goes to sender_timestamp_s (the caller sets the receive time).
UdpUnpack udp_unpack(const std::uint8_t* data, std::size_t n, CanFrame& f, double& sender_timestamp_s,
                     std::string& why);

/// Parsed "udp:" argument: PORT, GROUP:PORT or [GROUP]:PORT, optionally followed by
/// "?scope=local" (the default) or "?scope=lan[&iface=IFACE]" (docs/can.md, "Who can talk to the bus").
///  - local: hop limit / TTL 0 (the kernel loops the datagrams back to this host's members and never
///    transmits them); IPv4 groups are joined and sent on the loopback interface; IPv6 groups on the
///    default multicast interface (Linux does not deliver IPv6 multicast over lo), with hop limit 0;
///    a datagram whose source address is not an address of this host is counted
///    (CanBusStats::foreign_dropped) and dropped.
///  - lan: python-can's behaviour: hop limit 1, group joined on IFACE (default: the default multicast
///    interface), every sender accepted.
struct UdpAddress {
  std::string group;
  int port = 0;
  bool lan = false;
  std::string iface;         ///< scope=lan only; "" = the default multicast interface
  unsigned iface_index = 0;  ///< if_nametoindex(iface), 0 for the default
};
bool parse_udp_address(const std::string& arg, UdpAddress& out, std::string& why);

class UdpMulticastTransport final : public CanTransport {
 public:
  ~UdpMulticastTransport() override { close(); }
  CanBusStatus open(const std::string& arg) override;
  CanBusStatus send(const CanFrame& f) override;
  CanBusStatus receive(CanFrame& f, double timeout_s) override;
  int fd() const override { return rx_fd_; }
  void close() override;

 private:
  int rx_fd_ = -1;  ///< bound to the port, member of the group (like python-can's one socket)
  int tx_fd_ = -1;  ///< connected to the group from an ephemeral port: our frames' source
  int family_ = 0;
  std::vector<std::uint8_t> own_addr_;  ///< tx_fd_'s local sockaddr bytes (address + port)
  std::vector<std::uint8_t> buf_;
  bool lan_ = false;
  /// scope=local: whether a source address is one of this host's (getifaddrs, refreshed at most once
  /// a second when an unknown source is seen: addresses can be added while the bus is open).
  bool source_is_local(const sockaddr_storage& src);
  std::vector<std::vector<std::uint8_t>> local_addrs_;  ///< 4 or 16 address bytes each
  double local_addrs_at_s_ = -1.0;
};

// ---- in-process loopback --------------------------------------------------------------------------

class LoopbackTransport final : public CanTransport {
 public:
  static constexpr std::size_t kQueueLimit = 1u << 16;  ///< frames per receiver
  LoopbackTransport();
  ~LoopbackTransport() override;
  CanBusStatus open(const std::string& name) override;
  CanBusStatus send(const CanFrame& f) override;
  CanBusStatus receive(CanFrame& f, double timeout_s) override;
  int fd() const override;
  void close() override;

  struct Endpoint;

 private:
  std::shared_ptr<Endpoint> ep_;
};

/// Wall-clock time [s since the Unix epoch] as transports stamp frames.
double can_wall_time_s();

/// Milliseconds for poll(): -1 for a negative timeout, else rounded up.
int can_poll_ms(double timeout_s);

/// The common tail of the socket transports' receive loops, after a non-blocking receive returned
/// -1 with errno set: kOk to try the receive again (EINTR, or fd became readable), kTimeout past
/// deadline_s (timeout_s >= 0 only), kIoError with sys_errno and error filled otherwise.
CanBusStatus can_wait_readable(int fd, double timeout_s, double deadline_s, int& sys_errno, std::string& error);

}  // namespace hal
