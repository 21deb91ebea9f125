// UDP multicast transport speaking python-can 4.1's udp_multicast wire format
// (can/interfaces/udp_multicast: one msgpack map per datagram, default group
// ff15:7079:7468:6f6e:6465:6d6f:6d63:6173, SO_REUSEADDR, bound to the port on any address, receive
// timestamps from SO_TIMESTAMPNS).
//
// Scope (docs/can.md, "Who can talk to the bus"). By default the bus is local to this host: hop
// limit / TTL 0 (the kernel loops each datagram back to this host's group members and never
// transmits it), IPv4 groups joined and sent on the loopback interface, and every datagram whose
// source address is not one of this host's counted (stats.foreign_dropped) and dropped. IPv6 groups
// are joined on the default multicast interface even then: Linux does not deliver IPv6 multicast on
// lo (measured: a datagram sent with IPV6_MULTICAST_IF = lo never arrives), so the hop limit 0 and
// the source check are what keep the LAN out. "?scope=lan[&iface=IFACE]" is python-can's behaviour:
// hop limit 1, the group joined on IFACE (default: the default multicast interface), every sender.
//
// Own frames: multicast loops every datagram back to all members on the host, including the
// sender. python-can sends from its receiving socket (source port = the bus port), so its own
// frames cannot be told apart; here frames are sent from a second socket connected to the group
// from an ephemeral port, whose local address + port is unique on the host, and datagrams from
// exactly that source are dropped (counted in stats.own_dropped).
#include <arpa/inet.h>
#include <ifaddrs.h>
#include <net/if.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <exception>
#include <msgpack.hpp>

#include "hal/can_transports.hpp"

namespace hal {
namespace {

struct VecBuffer {
  std::vector<std::uint8_t>* v;
  void write(const char* p, std::size_t n) {
    const std::size_t at = v->size();
    v->resize(at + n);
    std::memcpy(v->data() + at, p, n);
  }
};

void pack_key(msgpack::packer<VecBuffer>& pk, const char* k) {
  const std::size_t n = std::strlen(k);
  pk.pack_str(static_cast<std::uint32_t>(n));
  pk.pack_str_body(k, static_cast<std::uint32_t>(n));
}
void pack_bool(msgpack::packer<VecBuffer>& pk, bool b) {
  if (b)
    pk.pack_true();
  else
    pk.pack_false();
}

bool as_bool(const msgpack::object& o, bool& out) {
  if (o.type == msgpack::type::BOOLEAN) {
    out = o.via.boolean;
    return true;
  }
  if (o.type == msgpack::type::POSITIVE_INTEGER) {
    out = o.via.u64 != 0;
    return true;
  }
  return false;
}
bool as_double(const msgpack::object& o, double& out) {
  switch (o.type) {
    case msgpack::type::FLOAT32:
    case msgpack::type::FLOAT64: out = o.via.f64; return true;
    case msgpack::type::POSITIVE_INTEGER: out = static_cast<double>(o.via.u64); return true;
    case msgpack::type::NEGATIVE_INTEGER: out = static_cast<double>(o.via.i64); return true;
    default: return false;
  }
}

/// Same address and port (IPv4 / IPv6), ignoring flow info and scope.
bool same_endpoint(const sockaddr_storage& a, const std::vector<std::uint8_t>& own) {
  if (own.size() < sizeof(sa_family_t)) return false;
  sockaddr_storage b{};
  std::memcpy(&b, own.data(), own.size() < sizeof b ? own.size() : sizeof b);
  if (a.ss_family != b.ss_family) return false;
  if (a.ss_family == AF_INET6) {
    const auto& x = reinterpret_cast<const sockaddr_in6&>(a);
    const auto& y = reinterpret_cast<const sockaddr_in6&>(b);
    return x.sin6_port == y.sin6_port && std::memcmp(&x.sin6_addr, &y.sin6_addr, sizeof x.sin6_addr) == 0;
  }
  if (a.ss_family == AF_INET) {
    const auto& x = reinterpret_cast<const sockaddr_in&>(a);
    const auto& y = reinterpret_cast<const sockaddr_in&>(b);
    return x.sin_port == y.sin_port && x.sin_addr.s_addr == y.sin_addr.s_addr;
  }
  return false;
}

}  // namespace

void udp_pack(const CanFrame& f, double timestamp_s, std::vector<std::uint8_t>& out) {
  out.clear();
  VecBuffer b{&out};
  msgpack::packer<VecBuffer> pk(b);
  pk.pack_map(11);
  pack_key(pk, "timestamp");
  pk.pack_double(timestamp_s);
  pack_key(pk, "arbitration_id");
  pk.pack_uint32(f.id);
  pack_key(pk, "is_extended_id");
  pack_bool(pk, f.extended);
  pack_key(pk, "is_remote_frame");
  pack_bool(pk, false);
  pack_key(pk, "is_error_frame");
  pack_bool(pk, false);
  pack_key(pk, "channel");
  pk.pack_nil();
  pack_key(pk, "dlc");
  pk.pack_uint8(f.len);
  pack_key(pk, "data");
  pk.pack_bin(f.len);
  pk.pack_bin_body(reinterpret_cast<const char*>(f.data.data()), f.len);
  pack_key(pk, "is_fd");
  pack_bool(pk, f.fd);
  pack_key(pk, "bitrate_switch");
  pack_bool(pk, f.brs);
  pack_key(pk, "error_state_indicator");
  pack_bool(pk, f.esi);
}

UdpUnpack udp_unpack(const std::uint8_t* data, std::size_t n, CanFrame& f, double& sender_timestamp_s,
                     std::string& why) {
  try {
    std::size_t off = 0;
    const msgpack::object_handle oh = msgpack::unpack(reinterpret_cast<const char*>(data), n, off);
    if (off != n) {
      why = "trailing bytes after the msgpack map";
      return UdpUnpack::kMalformed;
    }
    const msgpack::object& o = oh.get();
    if (o.type != msgpack::type::MAP) {
      why = "not a msgpack map";
      return UdpUnpack::kMalformed;
    }
    // python-can Message defaults for absent keys.
    CanFrame g{};
    g.extended = true;
    bool have_id = false, remote = false, error = false;
    long dlc = -1;
    double ts = 0.0;
    int len = 0;
    for (std::uint32_t i = 0; i < o.via.map.size; ++i) {
      const msgpack::object& k = o.via.map.ptr[i].key;
      const msgpack::object& v = o.via.map.ptr[i].val;
      if (k.type != msgpack::type::STR) {
        why = "map key is not a string";
        return UdpUnpack::kMalformed;
      }
      const std::string key(k.via.str.ptr, k.via.str.size);
      bool ok = true;
      if (key == "timestamp") {
        ok = as_double(v, ts);
      } else if (key == "arbitration_id") {
        ok = v.type == msgpack::type::POSITIVE_INTEGER && v.via.u64 <= kCanExtIdMask;
        if (ok) g.id = static_cast<std::uint32_t>(v.via.u64);
        have_id = ok;
      } else if (key == "is_extended_id") {
        ok = as_bool(v, g.extended);
      } else if (key == "is_remote_frame") {
        ok = as_bool(v, remote);
      } else if (key == "is_error_frame") {
        ok = as_bool(v, error);
      } else if (key == "dlc") {
        ok = v.type == msgpack::type::POSITIVE_INTEGER && v.via.u64 <= 64;
        if (ok) dlc = static_cast<long>(v.via.u64);
      } else if (key == "data") {
        if (v.type == msgpack::type::BIN && v.via.bin.size <= kCanFdMaxLen) {
          len = static_cast<int>(v.via.bin.size);
          std::memcpy(g.data.data(), v.via.bin.ptr, v.via.bin.size);
        } else if (v.type == msgpack::type::ARRAY && v.via.array.size <= kCanFdMaxLen) {
          len = static_cast<int>(v.via.array.size);
          for (int b = 0; b < len && ok; ++b) {
            const msgpack::object& e = v.via.array.ptr[b];
            ok = e.type == msgpack::type::POSITIVE_INTEGER && e.via.u64 <= 255;
            if (ok) g.data[static_cast<std::size_t>(b)] = static_cast<std::uint8_t>(e.via.u64);
          }
        } else if (v.type == msgpack::type::NIL) {
          len = 0;
        } else {
          ok = false;
        }
      } else if (key == "is_fd") {
        ok = as_bool(v, g.fd);
      } else if (key == "bitrate_switch") {
        ok = as_bool(v, g.brs);
      } else if (key == "error_state_indicator") {
        ok = as_bool(v, g.esi);
      }  // "channel" and keys of newer python-can versions are ignored
      if (!ok) {
        why = "field '" + key + "' has the wrong type or range";
        return UdpUnpack::kMalformed;
      }
    }
    if (remote || error) {
      why = remote ? "remote frame" : "error frame";
      return UdpUnpack::kUnsupported;
    }
    if (!have_id) {
      why = "no arbitration_id";
      return UdpUnpack::kMalformed;
    }
    if (dlc >= 0 && dlc != len) {
      why = "dlc " + std::to_string(dlc) + " != data length " + std::to_string(len);
      return UdpUnpack::kMalformed;
    }
    g.len = static_cast<std::uint8_t>(len);
    if (!can_frame_valid(g)) {
      why = "invalid identifier or length for the frame type";
      return UdpUnpack::kMalformed;
    }
    sender_timestamp_s = ts;
    f = g;
    return UdpUnpack::kOk;
  } catch (const std::exception& e) {
    why = std::string("msgpack: ") + e.what();
    return UdpUnpack::kMalformed;
  }
}

namespace {
/// "scope=lan&iface=eth0" -> out.lan / out.iface; false with why for an unknown key or value.
bool parse_udp_query(const std::string& query, UdpAddress& out, std::string& why) {
  std::string scope = "local";
  bool have_iface = false;
  std::size_t at = 0;
  while (at <= query.size()) {
    const std::size_t amp = std::min(query.find('&', at), query.size());
    const std::string kv = query.substr(at, amp - at);
    at = amp + 1;
    const std::size_t eq = kv.find('=');
    const std::string key = kv.substr(0, eq), value = eq == std::string::npos ? "" : kv.substr(eq + 1);
    if (key == "scope") {
      if (value != "local" && value != "lan") {
        why = "scope '" + value + "' is not 'local' (the default: this host only) or 'lan'";
        return false;
      }
      scope = value;
    } else if (key == "iface") {
      if (value.empty() || value.size() >= IF_NAMESIZE) {
        why = "iface '" + value + "' is not an interface name";
        return false;
      }
      out.iface = value;
      have_iface = true;
    } else {
      why = "unknown key '" + key + "' after '?' (keys: scope=local|lan, iface=IFACE)";
      return false;
    }
  }
  out.lan = scope == "lan";
  if (have_iface && !out.lan) {
    why = "iface=" + out.iface + " is for scope=lan (a local bus is not on any network interface)";
    return false;
  }
  if (have_iface) {
    out.iface_index = ::if_nametoindex(out.iface.c_str());
    if (out.iface_index == 0) {
      why = "iface '" + out.iface + "': no such interface";
      return false;
    }
  }
  return true;
}
}  // namespace

bool parse_udp_address(const std::string& full, UdpAddress& out, std::string& why) {
  const std::size_t q = full.find('?');
  const std::string arg = full.substr(0, q);
  UdpAddress parsed;
  if (q != std::string::npos && !parse_udp_query(full.substr(q + 1), parsed, why)) return false;
  std::string group = kUdpDefaultGroupV6, port_s = arg;
  if (!arg.empty() && arg.front() == '[') {
    const std::size_t close = arg.find("]:");
    if (close == std::string::npos) {
      why = "expected [GROUP]:PORT";
      return false;
    }
    group = arg.substr(1, close - 1);
    port_s = arg.substr(close + 2);
  } else if (const std::size_t colon = arg.rfind(':'); colon != std::string::npos) {
    group = arg.substr(0, colon);
    port_s = arg.substr(colon + 1);
  }
  if (port_s.empty() || port_s.size() > 5 || port_s.find_first_not_of("0123456789") != std::string::npos ||
      std::stoi(port_s) < 1 || std::stoi(port_s) > 65535) {
    why = "port '" + port_s + "' is not a number in 1..65535";
    return false;
  }
  in6_addr a6;
  in_addr a4;
  if (inet_pton(AF_INET6, group.c_str(), &a6) == 1) {
    if (a6.s6_addr[0] != 0xFF) {
      why = "'" + group + "' is not an IPv6 multicast address (ff00::/8)";
      return false;
    }
  } else if (inet_pton(AF_INET, group.c_str(), &a4) == 1) {
    if ((ntohl(a4.s_addr) >> 28) != 0xE) {
      why = "'" + group + "' is not an IPv4 multicast address (224.0.0.0/4)";
      return false;
    }
  } else {
    why = "'" + group + "' is not an IPv4 or IPv6 address";
    return false;
  }
  parsed.group = group;
  parsed.port = std::stoi(port_s);
  out = parsed;
  return true;
}

bool UdpMulticastTransport::source_is_local(const sockaddr_storage& src) {
  std::vector<std::uint8_t> a;
  if (src.ss_family == AF_INET6) {
    const auto& x = reinterpret_cast<const sockaddr_in6&>(src);
    if (IN6_IS_ADDR_V4MAPPED(&x.sin6_addr))
      a.assign(x.sin6_addr.s6_addr + 12, x.sin6_addr.s6_addr + 16);
    else
      a.assign(x.sin6_addr.s6_addr, x.sin6_addr.s6_addr + 16);
  } else if (src.ss_family == AF_INET) {
    const auto& x = reinterpret_cast<const sockaddr_in&>(src);
    const auto* b = reinterpret_cast<const std::uint8_t*>(&x.sin_addr.s_addr);
    a.assign(b, b + 4);
  } else {
    return false;
  }
  if (a.size() == 4 && a[0] == 127) return true;  // 127.0.0.0/8
  static const std::uint8_t kLoop6[16] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1};
  if (a.size() == 16 && std::memcmp(a.data(), kLoop6, 16) == 0) return true;
  const auto known = [&] {
    for (const auto& l : local_addrs_)
      if (l == a) return true;
    return false;
  };
  if (known()) return true;
  const double now = can_wall_time_s();
  if (local_addrs_at_s_ >= 0.0 && now - local_addrs_at_s_ < 1.0) return false;
  local_addrs_at_s_ = now;
  local_addrs_.clear();
  ifaddrs* list = nullptr;
  if (::getifaddrs(&list) != 0) return false;
  for (const ifaddrs* i = list; i != nullptr; i = i->ifa_next) {
    if (i->ifa_addr == nullptr) continue;
    if (i->ifa_addr->sa_family == AF_INET6) {
      const auto* x = reinterpret_cast<const sockaddr_in6*>(i->ifa_addr);
      local_addrs_.emplace_back(x->sin6_addr.s6_addr, x->sin6_addr.s6_addr + 16);
    } else if (i->ifa_addr->sa_family == AF_INET) {
      const auto* x = reinterpret_cast<const sockaddr_in*>(i->ifa_addr);
      const auto* b = reinterpret_cast<const std::uint8_t*>(&x->sin_addr.s_addr);
      local_addrs_.emplace_back(b, b + 4);
    }
  }
  ::freeifaddrs(list);
  return known();
}

CanBusStatus UdpMulticastTransport::open(const std::string& arg) {
  close();
  UdpAddress addr;
  if (!parse_udp_address(arg, addr, error)) return CanBusStatus::kBadName;
  auto fail = [this](CanBusStatus st, const std::string& what) {
    sys_errno = errno;
    error = what + ": " + std::strerror(sys_errno);
    close();
    return st;
  };
  const int on = 1, hops = addr.lan ? kUdpHopLimit : kUdpLocalHopLimit;
  lan_ = addr.lan;
  sockaddr_storage dst{};
  socklen_t dst_len = 0;
  in6_addr a6{};
  in_addr a4{};
  family_ = inet_pton(AF_INET6, addr.group.c_str(), &a6) == 1 ? AF_INET6 : AF_INET;
  if (family_ == AF_INET) inet_pton(AF_INET, addr.group.c_str(), &a4);

  rx_fd_ = ::socket(family_, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (rx_fd_ < 0)
    return fail(CanBusStatus::kNoSupport, family_ == AF_INET6 ? "socket(AF_INET6)" : "socket(AF_INET)");
  if (::setsockopt(rx_fd_, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on) < 0)
    return fail(CanBusStatus::kIoError, "setsockopt(SO_REUSEADDR)");
  if (::setsockopt(rx_fd_, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on) < 0)
    return fail(CanBusStatus::kIoError, "setsockopt(SO_TIMESTAMPNS)");
  const int rcvbuf = 4 << 20;  // absorbs 1 kHz bursts; the kernel caps it at net.core.rmem_max
  (void)::setsockopt(rx_fd_, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
  if (family_ == AF_INET6) {
    sockaddr_in6 b{};
    b.sin6_family = AF_INET6;
    b.sin6_addr = in6addr_any;
    b.sin6_port = htons(static_cast<std::uint16_t>(addr.port));
    if (::bind(rx_fd_, reinterpret_cast<sockaddr*>(&b), sizeof b) < 0)
      return fail(CanBusStatus::kIoError, "bind([::]:" + std::to_string(addr.port) + ")");
    ipv6_mreq mreq{};
    mreq.ipv6mr_multiaddr = a6;
    mreq.ipv6mr_interface = addr.iface_index;  // local: the default interface too (no IPv6 multicast on lo)
    if (::setsockopt(rx_fd_, IPPROTO_IPV6, IPV6_JOIN_GROUP, &mreq, sizeof mreq) < 0)
      return fail(CanBusStatus::kNoSupport, "join IPv6 group " + addr.group + " (no IPv6 multicast route?)");
    auto& d = reinterpret_cast<sockaddr_in6&>(dst);
    d.sin6_family = AF_INET6;
    d.sin6_addr = a6;
    d.sin6_port = htons(static_cast<std::uint16_t>(addr.port));
    dst_len = sizeof(sockaddr_in6);
  } else {
    sockaddr_in b{};
    b.sin_family = AF_INET;
    b.sin_addr.s_addr = htonl(INADDR_ANY);
    b.sin_port = htons(static_cast<std::uint16_t>(addr.port));
    if (::bind(rx_fd_, reinterpret_cast<sockaddr*>(&b), sizeof b) < 0)
      return fail(CanBusStatus::kIoError, "bind(0.0.0.0:" + std::to_string(addr.port) + ")");
    ip_mreqn mreq{};
    mreq.imr_multiaddr = a4;
    mreq.imr_address.s_addr = htonl(INADDR_ANY);
    mreq.imr_ifindex = addr.lan ? static_cast<int>(addr.iface_index) : static_cast<int>(::if_nametoindex("lo"));
    if (::setsockopt(rx_fd_, IPPROTO_IP, IP_ADD_MEMBERSHIP, &mreq, sizeof mreq) < 0)
      return fail(CanBusStatus::kNoSupport,
                  "join IPv4 group " + addr.group + " (no multicast route? ip route add 224.0.0.0/4 dev lo)");
    auto& d = reinterpret_cast<sockaddr_in&>(dst);
    d.sin_family = AF_INET;
    d.sin_addr = a4;
    d.sin_port = htons(static_cast<std::uint16_t>(addr.port));
    dst_len = sizeof(sockaddr_in);
  }

  tx_fd_ = ::socket(family_, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (tx_fd_ < 0) return fail(CanBusStatus::kIoError, "socket (sender)");
  if (family_ == AF_INET6) {
    const unsigned index = addr.iface_index;
    if (::setsockopt(tx_fd_, IPPROTO_IPV6, IPV6_MULTICAST_HOPS, &hops, sizeof hops) < 0 ||
        ::setsockopt(tx_fd_, IPPROTO_IPV6, IPV6_MULTICAST_LOOP, &on, sizeof on) < 0 ||
        (index != 0 && ::setsockopt(tx_fd_, IPPROTO_IPV6, IPV6_MULTICAST_IF, &index, sizeof index) < 0))
      return fail(CanBusStatus::kIoError, "setsockopt(IPV6_MULTICAST_HOPS/LOOP/IF)");
  } else {
    const unsigned char ttl = static_cast<unsigned char>(hops), loop = 1;
    ip_mreqn via{};
    via.imr_ifindex = addr.lan ? static_cast<int>(addr.iface_index) : static_cast<int>(::if_nametoindex("lo"));
    if (::setsockopt(tx_fd_, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl) < 0 ||
        ::setsockopt(tx_fd_, IPPROTO_IP, IP_MULTICAST_LOOP, &loop, sizeof loop) < 0 ||
        (via.imr_ifindex != 0 && ::setsockopt(tx_fd_, IPPROTO_IP, IP_MULTICAST_IF, &via, sizeof via) < 0))
      return fail(CanBusStatus::kIoError, "setsockopt(IP_MULTICAST_TTL/LOOP/IF)");
  }
  if (::connect(tx_fd_, reinterpret_cast<sockaddr*>(&dst), dst_len) < 0)
    return fail(CanBusStatus::kNoSupport, "connect to " + addr.group + " (no multicast route?)");
  sockaddr_storage own{};
  socklen_t own_len = sizeof own;
  if (::getsockname(tx_fd_, reinterpret_cast<sockaddr*>(&own), &own_len) < 0)
    return fail(CanBusStatus::kIoError, "getsockname");
  own_addr_.assign(reinterpret_cast<std::uint8_t*>(&own), reinterpret_cast<std::uint8_t*>(&own) + own_len);
  buf_.reserve(kUdpMaxDatagram);
  return CanBusStatus::kOk;
}

CanBusStatus UdpMulticastTransport::send(const CanFrame& f) {
  if (tx_fd_ < 0) return CanBusStatus::kNotOpen;
  udp_pack(f, can_wall_time_s(), buf_);
  const double deadline = can_wall_time_s() + kCanSendTimeout_s;
  for (;;) {
    const ssize_t w = ::send(tx_fd_, buf_.data(), buf_.size(), 0);
    if (w == static_cast<ssize_t>(buf_.size())) {
      ++stats.sent;
      return CanBusStatus::kOk;
    }
    if (w >= 0) {
      error = "short datagram write";
      return CanBusStatus::kIoError;
    }
    if (errno == EINTR) continue;
    if (errno != EAGAIN && errno != EWOULDBLOCK && errno != ENOBUFS) {
      sys_errno = errno;
      error = std::string("send: ") + std::strerror(errno);
      return CanBusStatus::kIoError;
    }
    const double left = deadline - can_wall_time_s();
    if (left <= 0.0) {
      sys_errno = errno;
      error = "socket send buffer full";
      return CanBusStatus::kTxBusy;
    }
    pollfd p{tx_fd_, POLLOUT, 0};
    ::poll(&p, 1, 1);
  }
}

CanBusStatus UdpMulticastTransport::receive(CanFrame& f, double timeout_s) {
  if (rx_fd_ < 0) return CanBusStatus::kNotOpen;
  const double deadline = timeout_s < 0.0 ? 0.0 : can_wall_time_s() + timeout_s;
  std::uint8_t dgram[kUdpMaxDatagram];
  for (;;) {
    sockaddr_storage src{};
    iovec iov{dgram, sizeof dgram};
    alignas(cmsghdr) char ctrl[CMSG_SPACE(sizeof(timespec))];
    msghdr msg{};
    msg.msg_name = &src;
    msg.msg_namelen = sizeof src;
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = ctrl;
    msg.msg_controllen = sizeof ctrl;
    const ssize_t n = ::recvmsg(rx_fd_, &msg, MSG_DONTWAIT);
    if (n >= 0) {
      if (same_endpoint(src, own_addr_)) {
        ++stats.own_dropped;
        continue;
      }
      if (!lan_ && !source_is_local(src)) {  // docs/can.md: a local bus takes nothing from the network
        ++stats.foreign_dropped;
        continue;
      }
      CanFrame g;
      double sender_ts = 0.0;
      std::string why;
      const UdpUnpack u = (msg.msg_flags & MSG_TRUNC) ? UdpUnpack::kMalformed
                                                       : udp_unpack(dgram, static_cast<std::size_t>(n), g, sender_ts, why);
      if (u != UdpUnpack::kOk) {
        ++(u == UdpUnpack::kUnsupported ? stats.unsupported : stats.malformed);
        error = (msg.msg_flags & MSG_TRUNC) ? "datagram larger than " + std::to_string(kUdpMaxDatagram) + " bytes" : why;
        continue;
      }
      g.timestamp_s = 0.0;
      for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c))
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
          timespec ts;
          std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
          g.timestamp_s = static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
        }
      if (g.timestamp_s == 0.0) g.timestamp_s = can_wall_time_s();
      f = g;
      ++stats.received;
      return CanBusStatus::kOk;
    }
    const CanBusStatus w = can_wait_readable(rx_fd_, timeout_s, deadline, sys_errno, error);
    if (w != CanBusStatus::kOk) return w;
  }
}

void UdpMulticastTransport::close() {
  if (rx_fd_ >= 0) ::close(rx_fd_);
  if (tx_fd_ >= 0) ::close(tx_fd_);
  rx_fd_ = tx_fd_ = -1;
  own_addr_.clear();
}

}  // namespace hal
