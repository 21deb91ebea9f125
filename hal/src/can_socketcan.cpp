// SocketCAN raw-socket transport (socketcan:IFACE): CAN FD frames, non-blocking socket bound to
// the interface index, kernel receive timestamps (SO_TIMESTAMP).
#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "hal/can_transports.hpp"

namespace hal {
int to_linux_frame(const CanFrame& f, canfd_frame& out) {
  if (!can_frame_valid(f)) return 0;
  std::memset(&out, 0, sizeof out);
  out.can_id = f.extended ? ((f.id & CAN_EFF_MASK) | CAN_EFF_FLAG) : (f.id & CAN_SFF_MASK);
  out.len = f.len;
  std::memcpy(out.data, f.data.data(), f.len);
  if (!f.fd) return static_cast<int>(CAN_MTU);
  out.flags = static_cast<__u8>(CANFD_FDF | (f.brs ? CANFD_BRS : 0) | (f.esi ? CANFD_ESI : 0));
  return static_cast<int>(CANFD_MTU);
}

bool from_linux_frame(const canfd_frame& in, int nbytes, CanFrame& out, bool& unsupported) {
  unsupported = false;
  if (nbytes != static_cast<int>(CAN_MTU) && nbytes != static_cast<int>(CANFD_MTU)) return false;
  if (in.can_id & (CAN_RTR_FLAG | CAN_ERR_FLAG)) {
    unsupported = true;
    return false;
  }
  CanFrame f{};
  f.extended = (in.can_id & CAN_EFF_FLAG) != 0;
  f.id = in.can_id & (f.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
  f.fd = nbytes == static_cast<int>(CANFD_MTU);
  f.len = in.len;
  if (f.fd) {
    f.brs = (in.flags & CANFD_BRS) != 0;
    f.esi = (in.flags & CANFD_ESI) != 0;
  }
  if (!can_frame_valid(f)) return false;
  std::memcpy(f.data.data(), in.data, f.len);
  out = f;
  return true;
}

CanBusStatus SocketCanTransport::open(const std::string& iface) {
  close();
  auto fail = [this](CanBusStatus st, const std::string& what) {
    sys_errno = errno;
    error = what + ": " + std::strerror(sys_errno);
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    return st;
  };
  if (iface.empty() || iface.size() >= IFNAMSIZ) {
    error = "interface name '" + iface + "' empty or too long";
    return CanBusStatus::kBadName;
  }
  fd_ = ::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
  if (fd_ < 0) {
    if (errno == EAFNOSUPPORT || errno == EPROTONOSUPPORT)
      return fail(CanBusStatus::kNoSupport, "socket(PF_CAN, SOCK_RAW, CAN_RAW): the kernel has no AF_CAN/CAN_RAW "
                                            "support (modules can, can-raw)");
    return fail(CanBusStatus::kIoError, "socket(PF_CAN, SOCK_RAW, CAN_RAW)");
  }
  const int on = 1;
  if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) < 0)
    return fail(CanBusStatus::kNoSupport, "setsockopt(CAN_RAW_FD_FRAMES): no CAN FD support");
  if (::setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMP, &on, sizeof on) < 0)
    return fail(CanBusStatus::kIoError, "setsockopt(SO_TIMESTAMP)");
  // The kernel's count of frames dropped on this socket (receive buffer full): stats.queue_dropped.
  if (::setsockopt(fd_, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on) < 0)
    return fail(CanBusStatus::kIoError, "setsockopt(SO_RXQ_OVFL)");
  // Room for a lockstep window plus other nodes' bursts: the default (net.core.rmem_default, about
  // 200 frames) overflows. SO_RCVBUFFORCE needs CAP_NET_ADMIN; else SO_RCVBUF, capped at
  // net.core.rmem_max. Not fatal: an overflow is counted all the same.
  if (::setsockopt(fd_, SOL_SOCKET, SO_RCVBUFFORCE, &kSocketCanRxBufferBytes, sizeof kSocketCanRxBufferBytes) < 0)
    (void)::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &kSocketCanRxBufferBytes, sizeof kSocketCanRxBufferBytes);
  ifreq ifr{};
  std::strncpy(ifr.ifr_name, iface.c_str(), IFNAMSIZ - 1);
  if (::ioctl(fd_, SIOCGIFINDEX, &ifr) < 0) return fail(CanBusStatus::kNoDevice, "interface " + iface);
  const int ifindex = ifr.ifr_ifindex;
  // The interface must carry CAN FD frames (MTU 72): `ip link set IFACE mtu 72`.
  if (::ioctl(fd_, SIOCGIFMTU, &ifr) == 0 && ifr.ifr_mtu != static_cast<int>(CANFD_MTU)) {
    error = "interface " + iface + " has MTU " + std::to_string(ifr.ifr_mtu) +
            ", not CAN FD (72): ip link set " + iface + " mtu 72";
    ::close(fd_);
    fd_ = -1;
    return CanBusStatus::kNoDevice;
  }
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifindex;
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) < 0)
    return fail(CanBusStatus::kNoDevice, "bind to " + iface);
  const int fl = ::fcntl(fd_, F_GETFL, 0);
  if (fl < 0 || ::fcntl(fd_, F_SETFL, fl | O_NONBLOCK) < 0) return fail(CanBusStatus::kIoError, "fcntl(O_NONBLOCK)");
  return CanBusStatus::kOk;
}

CanBusStatus SocketCanTransport::send(const CanFrame& f) {
  if (fd_ < 0) return CanBusStatus::kNotOpen;
  canfd_frame lf;
  const int n = to_linux_frame(f, lf);
  if (n == 0) return CanBusStatus::kBadFrame;
  const double deadline = can_wall_time_s() + kCanSendTimeout_s;
  for (;;) {
    const ssize_t w = ::write(fd_, &lf, static_cast<std::size_t>(n));
    if (w == n) {
      ++stats.sent;
      return CanBusStatus::kOk;
    }
    if (w >= 0) {
      error = "short write to the CAN socket";
      return CanBusStatus::kIoError;
    }
    if (errno == EINTR) continue;
    if (errno != EAGAIN && errno != EWOULDBLOCK && errno != ENOBUFS) {
      sys_errno = errno;
      error = std::string("write: ") + std::strerror(errno);
      return CanBusStatus::kIoError;
    }
    // Transmit queue full: wait for room (ENOBUFS does not wake poll, so retry in short steps).
    const double left = deadline - can_wall_time_s();
    if (left <= 0.0) {
      sys_errno = errno;
      error = "transmit queue full for " + std::to_string(kCanSendTimeout_s) + " s";
      return CanBusStatus::kTxBusy;
    }
    pollfd p{fd_, POLLOUT, 0};
    ::poll(&p, 1, 1);
  }
}

CanBusStatus SocketCanTransport::receive(CanFrame& f, double timeout_s) {
  if (fd_ < 0) return CanBusStatus::kNotOpen;
  const double deadline = timeout_s < 0.0 ? 0.0 : can_wall_time_s() + timeout_s;
  for (;;) {
    canfd_frame lf{};
    iovec iov{&lf, sizeof lf};
    alignas(cmsghdr) char ctrl[CMSG_SPACE(sizeof(timeval)) + CMSG_SPACE(sizeof(std::uint32_t))];
    msghdr msg{};
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = ctrl;
    msg.msg_controllen = sizeof ctrl;
    const ssize_t n = ::recvmsg(fd_, &msg, MSG_DONTWAIT);
    if (n >= 0) {
      for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c))
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) {
          std::uint32_t dropped = 0;  // cumulative for the socket
          std::memcpy(&dropped, CMSG_DATA(c), sizeof dropped);
          stats.queue_dropped = dropped;
        }
      bool unsupported = false;
      CanFrame g;
      if (!from_linux_frame(lf, static_cast<int>(n), g, unsupported)) {
        ++(unsupported ? stats.unsupported : stats.malformed);
        continue;
      }
      g.timestamp_s = 0.0;
      for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c))
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_TIMESTAMP) {
          timeval tv;
          std::memcpy(&tv, CMSG_DATA(c), sizeof tv);
          g.timestamp_s = static_cast<double>(tv.tv_sec) + static_cast<double>(tv.tv_usec) * 1e-6;
        }
      if (g.timestamp_s == 0.0) g.timestamp_s = can_wall_time_s();
      f = g;
      ++stats.received;
      return CanBusStatus::kOk;
    }
    const CanBusStatus w = can_wait_readable(fd_, timeout_s, deadline, sys_errno, error);
    if (w != CanBusStatus::kOk) return w;
  }
}

void SocketCanTransport::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

}  // namespace hal
