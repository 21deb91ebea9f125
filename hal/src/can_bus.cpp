// hal::CanBus: transport selection by name, and the in-process loopback transport.
#include "hal/can_bus.hpp"

#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <deque>
#include <map>
#include <mutex>
#include <time.h>

#include "hal/can_transports.hpp"

namespace hal {

const char* to_string(CanBusStatus s) {
  switch (s) {
    case CanBusStatus::kOk: return "ok";
    case CanBusStatus::kTimeout: return "timeout";
    case CanBusStatus::kNotOpen: return "not_open";
    case CanBusStatus::kBadName: return "bad_name";
    case CanBusStatus::kNoSupport: return "no_support";
    case CanBusStatus::kNoDevice: return "no_device";
    case CanBusStatus::kBadFrame: return "bad_frame";
    case CanBusStatus::kTxBusy: return "tx_busy";
    case CanBusStatus::kIoError: return "io_error";
    case CanBusStatus::kStopped: return "stopped";
  }
  return "unknown";
}

std::string to_string(const CanBusStats& s) {
  return "sent=" + std::to_string(s.sent) + " received=" + std::to_string(s.received) +
         " own_dropped=" + std::to_string(s.own_dropped) + " foreign_dropped=" + std::to_string(s.foreign_dropped) +
         " malformed=" + std::to_string(s.malformed) + " unsupported=" + std::to_string(s.unsupported) +
         " queue_dropped=" + std::to_string(s.queue_dropped);
}

double can_wall_time_s() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

// ---- CanBus ---------------------------------------------------------------------------------------

CanBus::CanBus() = default;
CanBus::~CanBus() { close(); }
CanBus::CanBus(CanBus&&) noexcept = default;
CanBus& CanBus::operator=(CanBus&&) noexcept = default;

CanBusStatus CanBus::open(const std::string& name) {
  close();
  name_ = name;
  error_.clear();
  errno_ = 0;
  const std::size_t colon = name.find(':');
  if (colon == std::string::npos || colon + 1 >= name.size()) {
    error_ = "bus name '" + name + "': expected socketcan:IFACE, udp:PORT, udp:GROUP:PORT (optionally ?scope=lan"
             "&iface=IFACE) or loop:NAME";
    return CanBusStatus::kBadName;
  }
  const std::string kind = name.substr(0, colon), arg = name.substr(colon + 1);
  std::unique_ptr<CanTransport> t;
  if (kind == "socketcan")
    t = std::make_unique<SocketCanTransport>();
  else if (kind == "udp")
    t = std::make_unique<UdpMulticastTransport>();
  else if (kind == "loop")
    t = std::make_unique<LoopbackTransport>();
  else {
    error_ = "bus name '" + name + "': unknown transport '" + kind + "' (socketcan, udp, loop)";
    return CanBusStatus::kBadName;
  }
  const CanBusStatus st = t->open(arg);
  if (st != CanBusStatus::kOk) {
    error_ = name + ": " + t->error;
    errno_ = t->sys_errno;
    return st;
  }
  t_ = std::move(t);
  return CanBusStatus::kOk;
}

CanBusStatus CanBus::send(const CanFrame& f) {
  if (!t_) return CanBusStatus::kNotOpen;
  if (!can_frame_valid(f)) {
    t_->error = "invalid frame (identifier or length)";
    return CanBusStatus::kBadFrame;
  }
  return t_->send(f);
}

CanBusStatus CanBus::receive(CanFrame& f, double timeout_s) {
  if (!t_) return CanBusStatus::kNotOpen;
  return t_->receive(f, timeout_s);
}

CanBusStatus CanBus::receive(CanFrame& f, double timeout_s, const std::atomic<bool>& stop) {
  if (!t_) return CanBusStatus::kNotOpen;
  // Slices of at most kCanStopCheck_s (a signal does not end a poll() that is restarted after EINTR).
  const double deadline = timeout_s < 0.0 ? 0.0 : can_wall_time_s() + timeout_s;
  for (;;) {
    if (stop.load(std::memory_order_relaxed)) return CanBusStatus::kStopped;
    double slice = kCanStopCheck_s;
    if (timeout_s >= 0.0) slice = std::max(0.0, std::min(slice, deadline - can_wall_time_s()));
    const CanBusStatus st = t_->receive(f, slice);
    if (st != CanBusStatus::kTimeout) return st;
    if (timeout_s >= 0.0 && can_wall_time_s() >= deadline) return CanBusStatus::kTimeout;
  }
}

int CanBus::fd() const { return t_ ? t_->fd() : -1; }

void CanBus::close() {
  if (t_) t_->close();
  t_.reset();
}

const std::string& CanBus::last_error() const { return t_ && !t_->error.empty() ? t_->error : error_; }
int CanBus::last_errno() const { return t_ ? t_->sys_errno : errno_; }
const CanBusStats& CanBus::stats() const {
  static const CanBusStats kNone{};
  return t_ ? t_->stats : kNone;
}

// ---- loopback ------------------------------------------------------------------------------------

struct LoopbackTransport::Endpoint {
  std::mutex mu;
  std::deque<CanFrame> q;
  int efd = -1;
  CanBusStats* stats = nullptr;
  std::string bus;
};

namespace {

struct Hub {
  std::mutex mu;
  std::map<std::string, std::vector<std::weak_ptr<LoopbackTransport::Endpoint>>> buses;
};
Hub& hub() {
  static Hub h;
  return h;
}

}  // namespace

int can_poll_ms(double timeout_s) {
  if (timeout_s < 0.0) return -1;
  const double ms = std::ceil(timeout_s * 1000.0);
  return ms > 2.0e9 ? 2000000000 : static_cast<int>(ms);
}

CanBusStatus can_wait_readable(int fd, double timeout_s, double deadline_s, int& sys_errno, std::string& error) {
  if (errno == EINTR) return CanBusStatus::kOk;
  if (errno != EAGAIN && errno != EWOULDBLOCK) {
    sys_errno = errno;
    error = std::string("recvmsg: ") + std::strerror(errno);
    return CanBusStatus::kIoError;
  }
  const double left = timeout_s < 0.0 ? -1.0 : deadline_s - can_wall_time_s();
  if (timeout_s >= 0.0 && left <= 0.0) return CanBusStatus::kTimeout;
  pollfd p{fd, POLLIN, 0};
  if (::poll(&p, 1, can_poll_ms(left)) < 0 && errno != EINTR) {
    sys_errno = errno;
    error = std::string("poll: ") + std::strerror(errno);
    return CanBusStatus::kIoError;
  }
  return CanBusStatus::kOk;
}

LoopbackTransport::LoopbackTransport() = default;
LoopbackTransport::~LoopbackTransport() { close(); }

CanBusStatus LoopbackTransport::open(const std::string& name) {
  close();
  auto ep = std::make_shared<Endpoint>();
  ep->efd = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (ep->efd < 0) {
    sys_errno = errno;
    error = std::string("eventfd: ") + std::strerror(errno);
    return CanBusStatus::kIoError;
  }
  ep->stats = &stats;
  ep->bus = name;
  {
    std::lock_guard<std::mutex> lk(hub().mu);
    hub().buses[name].push_back(ep);
  }
  ep_ = std::move(ep);
  return CanBusStatus::kOk;
}

CanBusStatus LoopbackTransport::send(const CanFrame& f) {
  if (!ep_) return CanBusStatus::kNotOpen;
  CanFrame g = f;
  g.timestamp_s = can_wall_time_s();
  std::lock_guard<std::mutex> lk(hub().mu);
  for (auto& w : hub().buses[ep_->bus]) {
    auto other = w.lock();
    if (!other || other == ep_) continue;
    std::lock_guard<std::mutex> lq(other->mu);
    if (other->q.size() >= kQueueLimit) {
      ++other->stats->queue_dropped;
      continue;
    }
    other->q.push_back(g);
    const std::uint64_t one = 1;
    (void)!::write(other->efd, &one, sizeof one);
  }
  ++stats.sent;
  return CanBusStatus::kOk;
}

CanBusStatus LoopbackTransport::receive(CanFrame& f, double timeout_s) {
  if (!ep_) return CanBusStatus::kNotOpen;
  const double deadline = timeout_s < 0.0 ? 0.0 : can_wall_time_s() + timeout_s;
  for (;;) {
    {
      std::lock_guard<std::mutex> lq(ep_->mu);
      if (!ep_->q.empty()) {
        f = ep_->q.front();
        ep_->q.pop_front();
        std::uint64_t v;
        if (ep_->q.empty()) (void)!::read(ep_->efd, &v, sizeof v);  // reset the readiness
        ++stats.received;
        return CanBusStatus::kOk;
      }
    }
    const double left = timeout_s < 0.0 ? -1.0 : deadline - can_wall_time_s();
    if (timeout_s >= 0.0 && left <= 0.0) return CanBusStatus::kTimeout;
    pollfd p{ep_->efd, POLLIN, 0};
    const int r = ::poll(&p, 1, can_poll_ms(left));
    if (r < 0 && errno != EINTR) {
      sys_errno = errno;
      error = std::string("poll: ") + std::strerror(errno);
      return CanBusStatus::kIoError;
    }
  }
}

int LoopbackTransport::fd() const { return ep_ ? ep_->efd : -1; }

void LoopbackTransport::close() {
  if (!ep_) return;
  {
    std::lock_guard<std::mutex> lk(hub().mu);
    auto it = hub().buses.find(ep_->bus);
    if (it != hub().buses.end()) {
      auto& eps = it->second;
      for (auto w = eps.begin(); w != eps.end();) {
        auto p = w->lock();
        if (!p || p == ep_)
          w = eps.erase(w);
        else
          ++w;
      }
      if (eps.empty()) hub().buses.erase(it);
    }
  }
  ::close(ep_->efd);
  ep_.reset();
}

}  // namespace hal
