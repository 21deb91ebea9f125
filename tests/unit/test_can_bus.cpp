// CAN transports behind hal::CanBus: names, in-process loopback, UDP multicast (python-can wire
// format), SocketCAN (skipped with the detected reason where the kernel has no AF_CAN), and the
// SIL/HIL property: the same frames through a bus decode to bit-identical fsw inputs.
#include <gtest/gtest.h>
#include <linux/can.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <vector>

#define MSGPACK_NO_BOOST
#include <msgpack.hpp>

#include "hal/can_bus.hpp"
#include "hal/can_protocol.hpp"
#include "hal/can_rx_assembler.hpp"
#include "hal/can_transports.hpp"
#include "sim/scenario.hpp"
#include "sim/sensor_stream.hpp"

namespace {

using hal::CanBus;
using hal::CanBusStatus;
using hal::CanFrame;

double now_s() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

/// A UDP port for this test process: distinct between the processes CTest runs in parallel.
int test_port(int offset) { return 20000 + static_cast<int>(::getpid() % 10000) * 4 + offset; }

CanFrame fd_frame(std::uint32_t id, int len, std::uint8_t fill) {
  CanFrame f;
  f.id = id;
  f.fd = true;
  f.brs = true;
  f.len = static_cast<std::uint8_t>(len);
  for (int i = 0; i < len; ++i) f.data[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(fill + i);
  return f;
}

std::vector<CanFrame> sim_frames(double duration_s) {
  sim::Scenario sc;
  sc.duration_s = duration_s;
  sim::SensorStream stream(sc);
  hal::can::CanStepEncoder enc;
  std::vector<CanFrame> all;
  sim::SensorStep step;
  bool first = true;
  while (stream.next(step)) {
    const int na = first ? static_cast<int>(stream.almanac().size()) : 0;
    std::vector<CanFrame> out(
        static_cast<std::size_t>(hal::can::CanStepEncoder::max_frames(static_cast<int>(step.imu.size()), na)));
    const auto r = enc.encode(step.imu.data(), static_cast<int>(step.imu.size()), step.has_epoch ? &step.epoch : nullptr,
                              stream.almanac().data(), na, out.data());
    all.insert(all.end(), out.begin(), out.begin() + r.n_frames);
    first = false;
  }
  return all;
}

struct Decoded {
  std::vector<fsw::ImuSample> imu;
  std::vector<fsw::GnssRawEpoch> gps;
  std::vector<fsw::GpsAlmanac> alm;
  hal::CanRxHealth health;
};

void drain(hal::CanRxAssembler& rx, Decoded& d) {
  fsw::ImuSample s;
  while (rx.pop_imu(s)) d.imu.push_back(s);
  fsw::GnssRawEpoch e;
  while (rx.pop_gps(e)) d.gps.push_back(e);
  fsw::GpsAlmanac a;
  while (rx.pop_almanac(a)) d.alm.push_back(a);
}

bool bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Field by field: the structs have padding bytes, which memcmp would compare too.
void expect_bit_identical(const Decoded& a, const Decoded& b) {
  ASSERT_EQ(a.imu.size(), b.imu.size());
  for (std::size_t i = 0; i < a.imu.size(); ++i) {
    const fsw::ImuSample &x = a.imu[i], &y = b.imu[i];
    bool same = bits(x.t_s, y.t_s) && bits(x.dt_s, y.dt_s);
    for (int k = 0; k < 3; ++k) same = same && bits(x.dtheta_rad(k), y.dtheta_rad(k)) && bits(x.dv_mps(k), y.dv_mps(k));
    ASSERT_TRUE(same) << "IMU sample " << i;
  }
  ASSERT_EQ(a.gps.size(), b.gps.size());
  for (std::size_t i = 0; i < a.gps.size(); ++i) {
    const fsw::GnssRawEpoch &x = a.gps[i], &y = b.gps[i];
    ASSERT_TRUE(bits(x.t_s, y.t_s) && x.gps_week == y.gps_week && bits(x.gps_tow_s, y.gps_tow_s) && x.n_meas == y.n_meas)
        << "epoch " << i;
    for (int k = 0; k < x.n_meas; ++k) {
      const fsw::GnssRawMeasurement &m = x.meas[static_cast<std::size_t>(k)], &n = y.meas[static_cast<std::size_t>(k)];
      ASSERT_TRUE(m.prn == n.prn && bits(m.pseudorange_m, n.pseudorange_m) &&
                  bits(m.pseudorange_rate_mps, n.pseudorange_rate_mps) && bits(m.cn0_dbhz, n.cn0_dbhz))
          << "epoch " << i << " measurement " << k;
    }
  }
  ASSERT_EQ(a.alm.size(), b.alm.size());
  for (std::size_t i = 0; i < a.alm.size(); ++i) {
    const fsw::GpsAlmanac &x = a.alm[i], &y = b.alm[i];
    ASSERT_TRUE(x.prn == y.prn && x.health == y.health && x.week_mod_1024 == y.week_mod_1024 &&
                bits(x.eccentricity, y.eccentricity) && bits(x.toa_s, y.toa_s) &&
                bits(x.inclination_rad, y.inclination_rad) && bits(x.omega_dot_radps, y.omega_dot_radps) &&
                bits(x.sqrt_a_sqrtm, y.sqrt_a_sqrtm) && bits(x.omega0_rad, y.omega0_rad) &&
                bits(x.arg_perigee_rad, y.arg_perigee_rad) && bits(x.mean_anomaly_rad, y.mean_anomaly_rad) &&
                bits(x.af0_s, y.af0_s) && bits(x.af1_sps, y.af1_sps))
        << "almanac " << i;
  }
}

/// In-process decoding (SIL).
Decoded decode_direct(const std::vector<CanFrame>& frames) {
  hal::CanRxAssembler rx;
  Decoded d;
  for (const CanFrame& f : frames) {
    rx.push(f, 0.0);
    drain(rx, d);
  }
  rx.flush();
  drain(rx, d);
  d.health = rx.health();
  return d;
}

/// Through a bus (HIL): each frame sent by tx is received by rx, then decoded.
Decoded decode_through(CanBus& tx, CanBus& rxbus, const std::vector<CanFrame>& frames) {
  hal::CanRxAssembler rx;
  Decoded d;
  for (const CanFrame& f : frames) {
    EXPECT_EQ(tx.send(f), CanBusStatus::kOk) << tx.last_error();
    CanFrame g;
    const CanBusStatus st = rxbus.receive(g, 2.0);
    EXPECT_EQ(st, CanBusStatus::kOk) << rxbus.last_error();
    if (st != CanBusStatus::kOk) break;
    EXPECT_TRUE(hal::can_frame_equal(f, g));
    EXPECT_GT(g.timestamp_s, 1.6e9);  // a receive time (Unix seconds)
    rx.push(g, 0.0);
    drain(rx, d);
  }
  rx.flush();
  drain(rx, d);
  d.health = rx.health();
  return d;
}

TEST(CanBus, NamesSelectTheTransport) {
  CanBus bus;
  EXPECT_EQ(bus.open(""), CanBusStatus::kBadName);
  EXPECT_EQ(bus.open("vcan0"), CanBusStatus::kBadName);
  EXPECT_EQ(bus.open("tcp:1234"), CanBusStatus::kBadName);
  EXPECT_NE(bus.last_error().find("unknown transport"), std::string::npos);
  EXPECT_EQ(bus.open("udp:notaport"), CanBusStatus::kBadName);
  EXPECT_EQ(bus.open("udp:70000"), CanBusStatus::kBadName);
  EXPECT_EQ(bus.open("udp:10.1.2.3:5000"), CanBusStatus::kBadName);  // not a multicast group
  EXPECT_EQ(bus.open("socketcan:averyveryverylongname"), CanBusStatus::kBadName);
  EXPECT_FALSE(bus.is_open());
  EXPECT_EQ(bus.send(CanFrame{}), CanBusStatus::kNotOpen);
  CanFrame f;
  EXPECT_EQ(bus.receive(f, 0.0), CanBusStatus::kNotOpen);
  EXPECT_EQ(bus.fd(), -1);

  hal::UdpAddress a;
  std::string why;
  ASSERT_TRUE(hal::parse_udp_address("43113", a, why));
  EXPECT_EQ(a.group, hal::kUdpDefaultGroupV6);
  EXPECT_EQ(a.port, 43113);
  ASSERT_TRUE(hal::parse_udp_address("239.74.163.2:5000", a, why));
  EXPECT_EQ(a.group, "239.74.163.2");
  EXPECT_EQ(a.port, 5000);
  ASSERT_TRUE(hal::parse_udp_address("[ff15::1]:6000", a, why));
  EXPECT_EQ(a.group, "ff15::1");
  ASSERT_TRUE(hal::parse_udp_address("ff15::1:6000", a, why));
  EXPECT_EQ(a.group, "ff15::1");
  EXPECT_EQ(a.port, 6000);
}

TEST(CanBus, LoopbackDeliversToOtherNodesOnlyAndTimesOutWhenSilent) {
  CanBus a, b, other;
  ASSERT_EQ(a.open("loop:test-bus"), CanBusStatus::kOk);
  ASSERT_EQ(b.open("loop:test-bus"), CanBusStatus::kOk);
  ASSERT_EQ(other.open("loop:another-bus"), CanBusStatus::kOk);
  const CanFrame f = fd_frame(0x010, 48, 3);
  ASSERT_EQ(a.send(f), CanBusStatus::kOk);
  pollfd p{b.fd(), POLLIN, 0};
  ASSERT_EQ(::poll(&p, 1, 1000), 1);  // the descriptor polls readable
  CanFrame g;
  ASSERT_EQ(b.receive(g, 1.0), CanBusStatus::kOk);
  EXPECT_TRUE(hal::can_frame_equal(f, g));
  EXPECT_EQ(other.receive(g, 0.0), CanBusStatus::kTimeout);
  // No own frame, and a silent bus returns kTimeout after the timeout.
  const double t0 = now_s();
  EXPECT_EQ(a.receive(g, 0.05), CanBusStatus::kTimeout);
  EXPECT_GE(now_s() - t0, 0.045);
  EXPECT_EQ(b.receive(g, 0.0), CanBusStatus::kTimeout);
  CanFrame bad = f;
  bad.len = 33;
  EXPECT_EQ(a.send(bad), CanBusStatus::kBadFrame);
  EXPECT_EQ(a.stats().sent, 1u);
  EXPECT_EQ(b.stats().received, 1u);
}

TEST(CanBus, SilAndHilOverTheLoopbackGiveBitIdenticalInputs) {
  const std::vector<CanFrame> frames = sim_frames(2.0);
  const Decoded sil = decode_direct(frames);
  CanBus tx, rx;
  ASSERT_EQ(tx.open("loop:sil-hil"), CanBusStatus::kOk);
  ASSERT_EQ(rx.open("loop:sil-hil"), CanBusStatus::kOk);
  const Decoded hil = decode_through(tx, rx, frames);
  EXPECT_EQ(sil.imu.size(), 2000u);
  EXPECT_EQ(sil.gps.size(), 2u);
  EXPECT_EQ(sil.health.rejections(), 0u);
  expect_bit_identical(sil, hil);
}

// ---- UDP multicast ------------------------------------------------------------------------------

TEST(CanBusUdp, PackMatchesPythonCanLayoutAndUnpacks) {
  const CanFrame f = fd_frame(0x021, 20, 0x40);
  std::vector<std::uint8_t> d;
  hal::udp_pack(f, 1700000000.5, d);
  // fixmap of 11 entries, first key "timestamp" (fixstr 9), float64 value: as msgpack-python
  // packs python-can's dict.
  ASSERT_GT(d.size(), 12u);
  EXPECT_EQ(d[0], 0x8B);
  EXPECT_EQ(d[1], 0xA9);
  EXPECT_EQ(std::string(d.begin() + 2, d.begin() + 11), "timestamp");
  EXPECT_EQ(d[11], 0xCB);
  CanFrame g;
  double ts = 0;
  std::string why;
  ASSERT_EQ(hal::udp_unpack(d.data(), d.size(), g, ts, why), hal::UdpUnpack::kOk) << why;
  EXPECT_TRUE(hal::can_frame_equal(f, g));
  EXPECT_EQ(ts, 1700000000.5);

  // Garbage, truncation, dlc/data mismatch, wrong types, remote frames.
  const std::uint8_t junk[] = {0xC1, 0x00, 0x13};
  EXPECT_EQ(hal::udp_unpack(junk, sizeof junk, g, ts, why), hal::UdpUnpack::kMalformed);
  EXPECT_EQ(hal::udp_unpack(d.data(), d.size() - 3, g, ts, why), hal::UdpUnpack::kMalformed);
  auto pack = [](auto&& body) {
    msgpack::sbuffer sb;
    msgpack::packer<msgpack::sbuffer> pk(sb);
    body(pk);
    return std::vector<std::uint8_t>(sb.data(), sb.data() + sb.size());
  };
  const auto mismatch = pack([](auto& pk) {
    pk.pack_map(3);
    pk.pack(std::string("arbitration_id"));
    pk.pack(0x10);
    pk.pack(std::string("dlc"));
    pk.pack(5);
    pk.pack(std::string("data"));
    pk.pack_bin(2);
    pk.pack_bin_body("ab", 2);
  });
  EXPECT_EQ(hal::udp_unpack(mismatch.data(), mismatch.size(), g, ts, why), hal::UdpUnpack::kMalformed);
  EXPECT_NE(why.find("dlc"), std::string::npos);
  const auto wrong_type = pack([](auto& pk) {
    pk.pack_map(1);
    pk.pack(std::string("arbitration_id"));
    pk.pack(std::string("0x10"));
  });
  EXPECT_EQ(hal::udp_unpack(wrong_type.data(), wrong_type.size(), g, ts, why), hal::UdpUnpack::kMalformed);
  const auto remote = pack([](auto& pk) {
    pk.pack_map(2);
    pk.pack(std::string("arbitration_id"));
    pk.pack(0x10);
    pk.pack(std::string("is_remote_frame"));
    pk.pack(true);
  });
  EXPECT_EQ(hal::udp_unpack(remote.data(), remote.size(), g, ts, why), hal::UdpUnpack::kUnsupported);
  // python-can defaults: an absent is_extended_id means extended; data as an array of ints.
  const auto minimal = pack([](auto& pk) {
    pk.pack_map(2);
    pk.pack(std::string("arbitration_id"));
    pk.pack(0x1ABCDE);
    pk.pack(std::string("data"));
    pk.pack_array(2);
    pk.pack(1);
    pk.pack(255);
  });
  ASSERT_EQ(hal::udp_unpack(minimal.data(), minimal.size(), g, ts, why), hal::UdpUnpack::kOk) << why;
  EXPECT_TRUE(g.extended);
  EXPECT_EQ(g.len, 2);
  EXPECT_EQ(g.data[1], 255);
}

/// Whether this host delivers multicast on a group to its own sockets, asked with plain sockets set
/// up like python-can's (independent of the transport under test): join on the default interface,
/// send one datagram, wait up to 1 s.
bool host_multicast_works(const std::string& group, int port, std::string& why) {
  const bool v6 = group.find(':') != std::string::npos;
  const int fam = v6 ? AF_INET6 : AF_INET;
  const int rx = ::socket(fam, SOCK_DGRAM, 0), tx = ::socket(fam, SOCK_DGRAM, 0);
  bool ok = false;
  const int on = 1;
  sockaddr_storage dst{};
  socklen_t len = 0;
  setsockopt(rx, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
  if (v6) {
    sockaddr_in6 b{};
    b.sin6_family = AF_INET6;
    b.sin6_port = htons(static_cast<std::uint16_t>(port));
    ipv6_mreq m{};
    inet_pton(AF_INET6, group.c_str(), &m.ipv6mr_multiaddr);
    if (::bind(rx, reinterpret_cast<sockaddr*>(&b), sizeof b) < 0 ||
        setsockopt(rx, IPPROTO_IPV6, IPV6_JOIN_GROUP, &m, sizeof m) < 0) {
      why = "join " + group + ": " + std::strerror(errno);
    } else {
      b.sin6_addr = m.ipv6mr_multiaddr;
      std::memcpy(&dst, &b, sizeof b);
      len = sizeof b;
    }
  } else {
    sockaddr_in b{};
    b.sin_family = AF_INET;
    b.sin_port = htons(static_cast<std::uint16_t>(port));
    ip_mreq m{};
    inet_pton(AF_INET, group.c_str(), &m.imr_multiaddr);
    if (::bind(rx, reinterpret_cast<sockaddr*>(&b), sizeof b) < 0 ||
        setsockopt(rx, IPPROTO_IP, IP_ADD_MEMBERSHIP, &m, sizeof m) < 0) {
      why = "join " + group + ": " + std::strerror(errno);
    } else {
      b.sin_addr = m.imr_multiaddr;
      std::memcpy(&dst, &b, sizeof b);
      len = sizeof b;
    }
  }
  if (len > 0) {
    const char probe[] = "probe";
    if (::sendto(tx, probe, sizeof probe, 0, reinterpret_cast<sockaddr*>(&dst), len) < 0) {
      why = "send to " + group + ": " + std::strerror(errno);
    } else {
      pollfd p{rx, POLLIN, 0};
      ok = ::poll(&p, 1, 1000) == 1;
      if (!ok) why = "a datagram sent to " + group + " did not come back within 1 s";
    }
  }
  ::close(rx);
  ::close(tx);
  return ok;
}

/// The bus name of a multicast group this host delivers (python-can's IPv6 default first, then
/// its IPv4 default), or "" with the reasons: then the test is skipped, never failed.
std::string usable_udp_bus(int port, std::string& why) {
  std::string why6, why4;
  if (host_multicast_works(hal::kUdpDefaultGroupV6, port, why6)) return "udp:" + std::to_string(port);
  if (host_multicast_works(hal::kUdpDefaultGroupV4, port, why4))
    return std::string("udp:") + hal::kUdpDefaultGroupV4 + ":" + std::to_string(port);
  why = "no multicast delivery on this host (IPv6: " + why6 + "; IPv4: " + why4 +
        "); see docs/can.md: ip link set lo multicast on; ip route add 224.0.0.0/4 dev lo";
  return "";
}

TEST(CanBusUdp, TwoNodesExchangeFramesAndOwnFramesAreFiltered) {
  std::string why;
  const std::string name = usable_udp_bus(test_port(0), why);
  if (name.empty()) GTEST_SKIP() << why;
  CanBus a, b;
  ASSERT_EQ(a.open(name), CanBusStatus::kOk) << a.last_error();
  ASSERT_EQ(b.open(name), CanBusStatus::kOk) << b.last_error();
  EXPECT_GE(a.fd(), 0);
  for (int k = 0; k < 200; ++k) {
    const CanFrame f = fd_frame(0x010, 48, static_cast<std::uint8_t>(k));
    ASSERT_EQ(a.send(f), CanBusStatus::kOk) << a.last_error();
    CanFrame g;
    ASSERT_EQ(b.receive(g, 2.0), CanBusStatus::kOk) << b.last_error();
    ASSERT_TRUE(hal::can_frame_equal(f, g)) << k;
  }
  CanFrame g;
  EXPECT_EQ(a.receive(g, 0.2), CanBusStatus::kTimeout);  // its own 200 frames are dropped
  EXPECT_EQ(a.stats().own_dropped, 200u);
  EXPECT_EQ(a.stats().received, 0u);
  const CanFrame back = fd_frame(0x021, 20, 9);
  ASSERT_EQ(b.send(back), CanBusStatus::kOk);
  ASSERT_EQ(a.receive(g, 2.0), CanBusStatus::kOk);
  EXPECT_TRUE(hal::can_frame_equal(back, g));
  EXPECT_EQ(b.receive(g, 0.1), CanBusStatus::kTimeout);
  EXPECT_EQ(b.stats().own_dropped, 1u);
}

TEST(CanBusUdp, MalformedDatagramsAreCountedAndSkipped) {
  const int port = test_port(1);
  std::string why;
  const std::string name = usable_udp_bus(port, why);
  if (name.empty()) GTEST_SKIP() << why;
  CanBus rx, tx;
  ASSERT_EQ(rx.open(name), CanBusStatus::kOk) << rx.last_error();
  ASSERT_EQ(tx.open(name), CanBusStatus::kOk) << tx.last_error();
  // A foreign sender on the group: a junk datagram, then a valid frame.
  const bool v6 = name == "udp:" + std::to_string(port);
  const int s = ::socket(v6 ? AF_INET6 : AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(s, 0);
  sockaddr_storage dst{};
  socklen_t dst_len = 0;
  if (v6) {
    auto& d = reinterpret_cast<sockaddr_in6&>(dst);
    d.sin6_family = AF_INET6;
    d.sin6_port = htons(static_cast<std::uint16_t>(port));
    inet_pton(AF_INET6, hal::kUdpDefaultGroupV6, &d.sin6_addr);
    dst_len = sizeof d;
  } else {
    auto& d = reinterpret_cast<sockaddr_in&>(dst);
    d.sin_family = AF_INET;
    d.sin_port = htons(static_cast<std::uint16_t>(port));
    inet_pton(AF_INET, hal::kUdpDefaultGroupV4, &d.sin_addr);
    dst_len = sizeof d;
  }
  const char junk[] = "not msgpack at all";
  ASSERT_EQ(::sendto(s, junk, sizeof junk, 0, reinterpret_cast<sockaddr*>(&dst), dst_len),
            static_cast<ssize_t>(sizeof junk));
  ::close(s);
  const CanFrame f = fd_frame(0x010, 48, 1);
  ASSERT_EQ(tx.send(f), CanBusStatus::kOk);
  CanFrame g;
  ASSERT_EQ(rx.receive(g, 2.0), CanBusStatus::kOk) << rx.last_error();
  EXPECT_TRUE(hal::can_frame_equal(f, g));
  EXPECT_EQ(rx.stats().malformed, 1u);
  // Silent bus.
  EXPECT_EQ(rx.receive(g, 0.1), CanBusStatus::kTimeout);
}

TEST(CanBusUdp, SilAndHilOverUdpMulticastGiveBitIdenticalInputs) {
  std::string why;
  const std::string name = usable_udp_bus(test_port(2), why);
  if (name.empty()) GTEST_SKIP() << why;
  CanBus tx, rx;
  ASSERT_EQ(tx.open(name), CanBusStatus::kOk) << tx.last_error();
  ASSERT_EQ(rx.open(name), CanBusStatus::kOk) << rx.last_error();
  const std::vector<CanFrame> frames = sim_frames(2.0);
  const Decoded sil = decode_direct(frames);
  const Decoded hil = decode_through(tx, rx, frames);
  EXPECT_EQ(hil.health.rejections(), 0u);
  expect_bit_identical(sil, hil);
}

TEST(CanBusUdp, BothPythonCanDefaultGroupsWorkWhereTheHostRoutesThem) {
  int checked = 0;
  std::string not_usable;
  for (const char* group : {hal::kUdpDefaultGroupV6, hal::kUdpDefaultGroupV4}) {
    const int port = test_port(3);
    std::string why;
    if (!host_multicast_works(group, port, why)) {
      std::printf("[ INFO     ] group %s not usable on this host (%s): transport not checked on it\n", group, why.c_str());
      not_usable += why + "; ";
      continue;
    }
    ++checked;
    const std::string name = std::string("udp:[") + group + "]:" + std::to_string(port);
    CanBus a, b;
    ASSERT_EQ(a.open(name), CanBusStatus::kOk) << a.last_error();
    ASSERT_EQ(b.open(name), CanBusStatus::kOk) << b.last_error();
    const CanFrame f = fd_frame(0x030, 64, 7);
    ASSERT_EQ(a.send(f), CanBusStatus::kOk);
    CanFrame g;
    ASSERT_EQ(b.receive(g, 2.0), CanBusStatus::kOk) << group << ": " << b.last_error();
    EXPECT_TRUE(hal::can_frame_equal(f, g));
    EXPECT_EQ(a.receive(g, 0.1), CanBusStatus::kTimeout);
    EXPECT_EQ(a.stats().own_dropped, 1u);
  }
  if (checked == 0) GTEST_SKIP() << "no multicast group usable on this host: " << not_usable;
}

// ---- SocketCAN ----------------------------------------------------------------------------------

TEST(CanBusSocketCan, LinuxFrameConversion) {
  const CanFrame f = fd_frame(0x010, 48, 5);
  canfd_frame lf;
  ASSERT_EQ(hal::to_linux_frame(f, lf), static_cast<int>(CANFD_MTU));
  EXPECT_EQ(lf.can_id, 0x010u);
  EXPECT_EQ(lf.len, 48);
  EXPECT_EQ(lf.flags, CANFD_BRS | CANFD_FDF);
  CanFrame g;
  bool unsupported = false;
  ASSERT_TRUE(hal::from_linux_frame(lf, CANFD_MTU, g, unsupported));
  EXPECT_TRUE(hal::can_frame_equal(f, g));

  CanFrame c;
  c.id = 0x1ABCDEF0;
  c.extended = true;
  c.len = 8;
  c.data[7] = 0xAA;
  ASSERT_EQ(hal::to_linux_frame(c, lf), static_cast<int>(CAN_MTU));
  EXPECT_EQ(lf.can_id, 0x1ABCDEF0u | CAN_EFF_FLAG);
  ASSERT_TRUE(hal::from_linux_frame(lf, CAN_MTU, g, unsupported));
  EXPECT_TRUE(hal::can_frame_equal(c, g));

  lf.can_id = 0x123 | CAN_RTR_FLAG;
  EXPECT_FALSE(hal::from_linux_frame(lf, CAN_MTU, g, unsupported));
  EXPECT_TRUE(unsupported);
  lf.can_id = 0x123;
  EXPECT_FALSE(hal::from_linux_frame(lf, 10, g, unsupported));  // neither CAN_MTU nor CANFD_MTU
  EXPECT_FALSE(unsupported);
  lf.len = 9;  // not an FD length
  EXPECT_FALSE(hal::from_linux_frame(lf, CANFD_MTU, g, unsupported));
  CanFrame bad = f;
  bad.len = 13;
  EXPECT_EQ(hal::to_linux_frame(bad, lf), 0);
}

TEST(CanBusSocketCan, MissingKernelSupportIsReportedWithItsReason) {
  // What the kernel says about AF_CAN, asked directly; the transport must report the same.
  const int s = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  const int err = s < 0 ? errno : 0;
  if (s >= 0) ::close(s);
  CanBus bus;
  const CanBusStatus st = bus.open("socketcan:vcan0");
  if (err == EAFNOSUPPORT || err == EPROTONOSUPPORT) {
    EXPECT_EQ(st, CanBusStatus::kNoSupport);
    EXPECT_EQ(bus.last_errno(), err);
    EXPECT_NE(bus.last_error().find("AF_CAN"), std::string::npos) << bus.last_error();
    EXPECT_NE(bus.last_error().find(std::strerror(err)), std::string::npos) << bus.last_error();
  } else if (err == 0) {
    EXPECT_TRUE(st == CanBusStatus::kOk || st == CanBusStatus::kNoDevice) << bus.last_error();
  }
}

TEST(CanBusSocketCan, TwoSocketsOnVcan0ExchangeFdFrames) {
  CanBus a, b;
  const CanBusStatus st = a.open("socketcan:vcan0");
  if (st == CanBusStatus::kNoSupport || st == CanBusStatus::kNoDevice)
    GTEST_SKIP() << "SocketCAN unavailable (" << hal::to_string(st) << "): " << a.last_error()
                 << " -- on a kernel with CAN: ip link add dev vcan0 type vcan; ip link set vcan0 mtu 72 up";
  ASSERT_EQ(st, CanBusStatus::kOk) << a.last_error();
  ASSERT_EQ(b.open("socketcan:vcan0"), CanBusStatus::kOk) << b.last_error();
  const std::vector<CanFrame> frames = sim_frames(1.0);
  const Decoded sil = decode_direct(frames);
  const Decoded hil = decode_through(a, b, frames);
  expect_bit_identical(sil, hil);
  CanFrame g;
  EXPECT_EQ(a.receive(g, 0.1), CanBusStatus::kTimeout);  // no own frames on SocketCAN
}

TEST(CanBusSocketCan, KernelDropsOfAFullReceiveBufferAreCounted) {
  // More frames than the receiver's buffer holds: each one is either received or counted as dropped.
  CanBus a, b;
  const CanBusStatus st = a.open("socketcan:vcan0");
  if (st == CanBusStatus::kNoSupport || st == CanBusStatus::kNoDevice)
    GTEST_SKIP() << "SocketCAN unavailable (" << hal::to_string(st) << "): " << a.last_error();
  ASSERT_EQ(st, CanBusStatus::kOk) << a.last_error();
  ASSERT_EQ(b.open("socketcan:vcan0"), CanBusStatus::kOk) << b.last_error();
  constexpr int kSent = 20000;  // about 5x what a 4 MiB buffer holds
  const CanFrame f = fd_frame(0x030, 64, 3);
  for (int i = 0; i < kSent; ++i) ASSERT_EQ(a.send(f), CanBusStatus::kOk) << i << ": " << a.last_error();
  CanFrame g;
  std::uint64_t received = 0;
  while (b.receive(g, 0.2) == CanBusStatus::kOk) ++received;
  ASSERT_EQ(a.send(f), CanBusStatus::kOk);  // the kernel reports the drop count with the next frame
  ASSERT_EQ(b.receive(g, 2.0), CanBusStatus::kOk) << b.last_error();
  EXPECT_GT(b.stats().queue_dropped, 0u);
  EXPECT_EQ(received + b.stats().queue_dropped, static_cast<std::uint64_t>(kSent));
}

}  // namespace
