// LCM telemetry: publishing on UDP multicast (received by an LCM subscriber on loopback when
// multicast works here), the log-only fallback when udpm cannot be created or sends keep
// failing, and the URL resolution.
//
// LcmNetns.* need an isolated network namespace (unshare -n), in which LCM has no multicast
// route until `ip route add 224.0.0.0/4 dev lo`; CTest runs them through
// tests/e2e/lcm_netns.sh (lcm_netns_no_route, lcm_netns_loopback_route). Run directly, they skip.
#include <gtest/gtest.h>
#include <lcm/lcm.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <string>
#include <vector>

#include "hal/lcm_convert.hpp"
#include "hal/lcm_log.hpp"
#include "hal/lcm_log_sink.hpp"
#include "hal/lcm_telemetry.hpp"
#include "lcm_test_util.hpp"

namespace {

struct Warnings {
  std::vector<std::string> messages;
  static void handler(const char* m, void* self) { static_cast<Warnings*>(self)->messages.emplace_back(m); }
};

std::string test_url(int offset) {
  return "udpm://239.255.76.67:" + std::to_string(21000 + (::getpid() * 7 + offset) % 20000) + "?ttl=0";
}

struct Received {
  std::vector<std::string> channels;
  std::vector<std::vector<std::uint8_t>> data;
  static void handler(const lcm_recv_buf_t* rbuf, const char* channel, void* self) {
    auto* r = static_cast<Received*>(self);
    r->channels.emplace_back(channel);
    const auto* d = static_cast<const std::uint8_t*>(rbuf->data);
    r->data.emplace_back(d, d + rbuf->data_size);
  }
};

/// Handles incoming messages on l until want have arrived or timeout_ms passed.
void pump(lcm_t* l, const Received& r, std::size_t want, int timeout_ms) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (r.channels.size() < want && std::chrono::steady_clock::now() < end) lcm_handle_timeout(l, 50);
}

/// Whether a message published on url reaches a subscriber on url (multicast loopback works).
bool multicast_works(const std::string& url, std::string& why) {
  lcm_t* rx = lcm_create(url.c_str());
  if (rx == nullptr) {
    why = "lcm_create('" + url + "') failed (no multicast route?)";
    return false;
  }
  Received r;
  lcm_subscription_t* sub = lcm_subscribe(rx, "SDINS_PROBE", &Received::handler, &r);
  lcm_t* tx = lcm_create(url.c_str());
  bool ok = false;
  if (tx != nullptr) {
    for (int attempt = 0; attempt < 5 && r.channels.empty(); ++attempt) {
      lcm_publish(tx, "SDINS_PROBE", "probe", 5);
      pump(rx, r, 1, 200);
    }
    ok = !r.channels.empty();
    lcm_destroy(tx);
  }
  lcm_unsubscribe(rx, sub);
  lcm_destroy(rx);
  if (!ok) why = "a probe published on " + url + " never arrived (multicast loopback blocked)";
  return ok;
}

fsw::NavState some_nav() {
  fsw::NavState nav;
  nav.t_s = 33.125;
  nav.llh = fsw::Vec3(0.61, 2.21, 4321.5);
  nav.vel_enu_mps = fsw::Vec3(-100.25, 220.5, 1.75);
  nav.q_b_n = fsw::Quat(fsw::C_b_n_from_euler(0.3, -0.05, 1.2));
  return nav;
}

/// Publishes a NAV_SOLUTION through a sink on url (and into log_path) and checks that an LCM
/// subscriber receives exactly the encoded message.
void expect_nav_solution_received(const std::string& url, const std::string& log_path) {
  lcm_t* rx = lcm_create(url.c_str());
  ASSERT_NE(rx, nullptr);
  Received r;
  lcm_subscription_t* sub = lcm_subscribe(rx, hal::kLcmChannelNavSolution, &Received::handler, &r);
  hal::LcmLogSink sink;
  Warnings w;
  sink.telemetry().set_warning_handler(&Warnings::handler, &w);
  hal::LcmTelemetryConfig cfg;
  cfg.lcm_url = url;
  cfg.log_path = log_path;
  ASSERT_EQ(sink.open(cfg), hal::LcmLogStatus::kOk);
  ASSERT_TRUE(sink.telemetry().network_active());
  EXPECT_TRUE(w.messages.empty());
  const fsw::NavState nav = some_nav();
  for (int attempt = 0; attempt < 5 && r.channels.empty(); ++attempt) {
    ASSERT_EQ(sink.write_nav(nav, true, true), hal::LcmLogStatus::kOk);
    pump(rx, r, 1, 300);
  }
  ASSERT_FALSE(r.channels.empty()) << "NAV_SOLUTION published on " << url << " was not received";
  sdins::nav_solution_t got{};
  ASSERT_EQ(hal::decode_exact(r.data[0].data(), r.data[0].size(), got), hal::LcmInputStatus::kOk);
  sdins::nav_solution_t want{};
  hal::to_msg(nav, true, true, want);
  EXPECT_EQ(got.t_s, want.t_s);
  EXPECT_EQ(got.lat_rad, want.lat_rad);
  EXPECT_EQ(got.height_m, want.height_m);
  EXPECT_EQ(got.vel_enu_mps[1], want.vel_enu_mps[1]);
  EXPECT_EQ(got.heading_rad, want.heading_rad);
  EXPECT_EQ(got.ekf_updated, 1);
  EXPECT_GE(sink.telemetry().published(), 1u);
  EXPECT_EQ(sink.telemetry().send_failures(), 0u);
  ASSERT_EQ(sink.close(), hal::LcmLogStatus::kOk);
  EXPECT_FALSE(sink.telemetry().network_active());
  EXPECT_TRUE(sink.telemetry().network_used());  // what the end-of-run report says
  EXPECT_FALSE(sink.telemetry().network_given_up());
  lcm_unsubscribe(rx, sub);
  lcm_destroy(rx);
  // The log got every published message too.
  hal::LcmLogReader log;
  ASSERT_EQ(log.open(log_path), hal::LcmLogStatus::kOk);
  hal::LcmLogEvent ev;
  ASSERT_EQ(log.next(ev), hal::LcmLogStatus::kOk);
  EXPECT_EQ(ev.channel, hal::kLcmChannelNavSolution);
  EXPECT_EQ(std::vector<std::uint8_t>(ev.data, ev.data + ev.data_len), r.data[0]);
}

bool in_netns(const char* mode) {
  const char* e = std::getenv("SDINS_LCM_NETNS");
  return e != nullptr && std::string(e) == mode;
}

}  // namespace

TEST(LcmTelemetry, SubscriberOnLoopbackReceivesNavSolution) {
  const std::string url = test_url(1);
  std::string why;
  if (!multicast_works(url, why)) GTEST_SKIP() << "UDP multicast does not work on this host: " << why;
  const std::string log = lcm_test::scratch("telemetry_rx.lcmlog");
  expect_nav_solution_received(url, log);
  std::remove(log.c_str());
}

TEST(LcmTelemetry, FallsBackToLogOnlyWithOneWarningWhenUdpmCannotBeCreated) {
  const std::string log = lcm_test::scratch("telemetry_fallback.lcmlog");
  hal::LcmLogSink sink;
  Warnings w;
  sink.telemetry().set_warning_handler(&Warnings::handler, &w);
  hal::LcmTelemetryConfig cfg;
  cfg.lcm_url = "udpm://not-a-multicast-group:7667";  // lcm_create fails
  cfg.log_path = log;
  ASSERT_EQ(sink.open(cfg), hal::LcmLogStatus::kOk);
  EXPECT_FALSE(sink.telemetry().network_active());
  EXPECT_TRUE(sink.telemetry().log_active());
  ASSERT_EQ(w.messages.size(), 1u);
  EXPECT_NE(w.messages[0].find("continuing with the log file only"), std::string::npos) << w.messages[0];
  EXPECT_NE(w.messages[0].find("224.0.0.0/4"), std::string::npos) << w.messages[0];
  for (int k = 0; k < 5; ++k) {
    fsw::NavState nav = some_nav();
    nav.t_s += 0.005 * k;
    ASSERT_EQ(sink.write_nav(nav, true, false), hal::LcmLogStatus::kOk);
  }
  EXPECT_EQ(w.messages.size(), 1u);  // warned once
  EXPECT_EQ(sink.telemetry().published(), 0u);
  ASSERT_EQ(sink.close(), hal::LcmLogStatus::kOk);
  EXPECT_FALSE(sink.telemetry().network_used());
  hal::LcmLogReader r;
  ASSERT_EQ(r.open(log), hal::LcmLogStatus::kOk);
  hal::LcmLogEvent ev;
  int n = 0;
  while (r.next(ev) == hal::LcmLogStatus::kOk) ++n;
  EXPECT_EQ(n, 5);
  std::remove(log.c_str());
}

TEST(LcmTelemetry, NoneMeansNoNetworkAndNoWarning) {
  hal::LcmTelemetry tel;
  Warnings w;
  tel.set_warning_handler(&Warnings::handler, &w);
  hal::LcmTelemetryConfig cfg;
  cfg.lcm_url = "none";
  ASSERT_EQ(tel.open(cfg), hal::LcmLogStatus::kOk);
  EXPECT_FALSE(tel.network_active());
  EXPECT_FALSE(tel.log_active());
  EXPECT_TRUE(w.messages.empty());
  const std::uint8_t b[3] = {1, 2, 3};
  EXPECT_EQ(tel.publish("X", b, 3, 0), hal::LcmLogStatus::kOk);
  EXPECT_EQ(tel.publish("", b, 3, 0), hal::LcmLogStatus::kBadChannel);
  EXPECT_FALSE(tel.network_used());
}

// The end-of-run report is printed after the node closed its sink: network_used() keeps saying
// that the run published to the network (network_active() is false by then). memq:// is LCM's
// in-process provider, so this runs on any host; reopening with "none" resets it.
TEST(LcmTelemetry, NetworkUsedOutlivesCloseForTheReport) {
  hal::LcmTelemetry tel;
  hal::LcmTelemetryConfig cfg;
  cfg.lcm_url = "memq://";
  ASSERT_EQ(tel.open(cfg), hal::LcmLogStatus::kOk);
  ASSERT_TRUE(tel.network_active());
  const std::uint8_t b[3] = {1, 2, 3};
  for (int k = 0; k < 4; ++k) EXPECT_EQ(tel.publish("X", b, 3, 0), hal::LcmLogStatus::kOk);
  EXPECT_EQ(tel.published(), 4u);
  ASSERT_EQ(tel.close(), hal::LcmLogStatus::kOk);
  EXPECT_FALSE(tel.network_active());
  EXPECT_TRUE(tel.network_used());
  EXPECT_FALSE(tel.network_given_up());
  EXPECT_EQ(tel.published(), 4u);
  cfg.lcm_url = "none";
  ASSERT_EQ(tel.open(cfg), hal::LcmLogStatus::kOk);
  EXPECT_FALSE(tel.network_used());
}

TEST(LcmTelemetry, LogThatCannotBeCreatedIsAnError) {
  hal::LcmTelemetry tel;
  hal::LcmTelemetryConfig cfg;
  cfg.lcm_url = "none";
  cfg.log_path = "/nonexistent-dir-sdins/x.lcmlog";
  EXPECT_EQ(tel.open(cfg), hal::LcmLogStatus::kOpenFailed);
}

TEST(LcmTelemetry, UrlComesFromOptionThenEnvironmentThenDefault) {
  const char* saved = std::getenv("LCM_DEFAULT_URL");
  const std::string saved_value = saved != nullptr ? saved : "";
  ::unsetenv("LCM_DEFAULT_URL");
  EXPECT_EQ(hal::resolve_lcm_url(""), "udpm://239.255.76.67:7667?ttl=0");
  ::setenv("LCM_DEFAULT_URL", "udpm://239.255.76.99:7999?ttl=0", 1);
  EXPECT_EQ(hal::resolve_lcm_url(""), "udpm://239.255.76.99:7999?ttl=0");
  EXPECT_EQ(hal::resolve_lcm_url("udpm://239.1.2.3:1234"), "udpm://239.1.2.3:1234");
  ::setenv("LCM_DEFAULT_URL", "", 1);
  EXPECT_EQ(hal::resolve_lcm_url(""), hal::kLcmDefaultUrl);
  if (saved != nullptr)
    ::setenv("LCM_DEFAULT_URL", saved_value.c_str(), 1);
  else
    ::unsetenv("LCM_DEFAULT_URL");
}

// In a fresh network namespace (loopback only, no routes) LCM cannot create udpm: the default URL
// falls back to log-only with one warning, and the run goes on.
TEST(LcmNetns, NoMulticastRouteFallsBackToLogOnly) {
  if (!in_netns("no-route")) GTEST_SKIP() << "runs inside `unshare -n` via ctest -R lcm_netns";
  ASSERT_EQ(lcm_test::run("ip route show | grep -q 224.0.0.0"), 1) << "this namespace has a multicast route";
  const std::string log = lcm_test::scratch("netns_noroute.lcmlog");
  hal::LcmLogSink sink;
  Warnings w;
  sink.telemetry().set_warning_handler(&Warnings::handler, &w);
  hal::LcmTelemetryConfig cfg;  // default URL
  cfg.log_path = log;
  ::unsetenv("LCM_DEFAULT_URL");
  ASSERT_EQ(sink.open(cfg), hal::LcmLogStatus::kOk);
  EXPECT_EQ(sink.telemetry().url(), hal::kLcmDefaultUrl);
  EXPECT_FALSE(sink.telemetry().network_active());
  ASSERT_EQ(w.messages.size(), 1u);
  for (int k = 0; k < 3; ++k) ASSERT_EQ(sink.write_nav(some_nav(), true, false), hal::LcmLogStatus::kOk);
  EXPECT_EQ(w.messages.size(), 1u);
  ASSERT_EQ(sink.close(), hal::LcmLogStatus::kOk);
  EXPECT_EQ(sink.telemetry().logged(), 3u);
  std::remove(log.c_str());
}

// The documented route makes udpm work on an isolated loopback; when the route disappears during
// the run, sends fail and the telemetry gives up the network after the configured number of
// consecutive failures, with one warning, and keeps logging.
TEST(LcmNetns, LoopbackRouteMakesUdpmWorkAndLosingItFallsBackToLogOnly) {
  if (!in_netns("loopback-route")) GTEST_SKIP() << "runs inside `unshare -n` via ctest -R lcm_netns";
  const std::string url = hal::kLcmDefaultUrl;
  const std::string log1 = lcm_test::scratch("netns_route.lcmlog");
  expect_nav_solution_received(url, log1);
  std::remove(log1.c_str());

  const std::string log2 = lcm_test::scratch("netns_lost.lcmlog");
  hal::LcmLogSink sink;
  Warnings w;
  sink.telemetry().set_warning_handler(&Warnings::handler, &w);
  hal::LcmTelemetryConfig cfg;
  cfg.lcm_url = url;
  cfg.log_path = log2;
  cfg.max_consecutive_send_failures = 5;
  ASSERT_EQ(sink.open(cfg), hal::LcmLogStatus::kOk);
  ASSERT_TRUE(sink.telemetry().network_active());
  ASSERT_EQ(sink.write_nav(some_nav(), true, false), hal::LcmLogStatus::kOk);
  EXPECT_EQ(sink.telemetry().published(), 1u);
  ASSERT_EQ(lcm_test::run("ip route del 224.0.0.0/4 dev lo && ip link set lo down"), 0);
  for (int k = 0; k < 20; ++k) ASSERT_EQ(sink.write_nav(some_nav(), true, false), hal::LcmLogStatus::kOk);
  EXPECT_FALSE(sink.telemetry().network_active());
  EXPECT_TRUE(sink.telemetry().network_used());
  EXPECT_TRUE(sink.telemetry().network_given_up());
  EXPECT_EQ(sink.telemetry().send_failures(), 5u);
  ASSERT_EQ(w.messages.size(), 1u);
  EXPECT_NE(w.messages[0].find("giving up the network"), std::string::npos) << w.messages[0];
  ASSERT_EQ(sink.close(), hal::LcmLogStatus::kOk);
  EXPECT_EQ(sink.telemetry().logged(), 21u);
  std::remove(log2.c_str());
}
