// LCM log files: our writer and reader against each other and against LCM's own implementation
// (lcm_eventlog C API, lcm-logplayer, lcm-logger), and the reader on truncated and corrupted logs.
#include <gtest/gtest.h>
#include <lcm/eventlog.h>
#include <lcm/lcm.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "hal/lcm_log.hpp"
#include "hal/lcm_telemetry.hpp"
#include "lcm_test_util.hpp"

namespace {

struct Ev {
  std::string channel;
  std::vector<std::uint8_t> data;
  std::int64_t timestamp_us = 0;
  std::int64_t event_number = 0;
  std::uint64_t offset = 0;  ///< where the writer put it
  std::uint64_t size = 0;    ///< bytes in the file
};

/// Deterministic events whose bytes never contain 0xED (so no sync word can appear inside one by
/// chance: the corruption tests then know exactly which events must survive).
std::vector<Ev> make_events(int n) {
  const char* channels[] = {"IMU", "GNSS_RAW", "NAV_SOLUTION", "X", "A_LONGER_CHANNEL_NAME_42"};
  std::vector<Ev> ev;
  std::uint64_t off = 0;
  std::uint32_t state = 12345;
  for (int k = 0; k < n; ++k) {
    Ev e;
    e.channel = channels[k % 5];
    const int len = (k % 7 == 3) ? 0 : 1 + (k * 37) % 300;
    for (int i = 0; i < len; ++i) {
      state = state * 1664525u + 1013904223u;
      std::uint8_t b = static_cast<std::uint8_t>(state >> 24);
      if (b == 0xED) b = 0x11;
      e.data.push_back(b);
    }
    e.timestamp_us = 1000000 + 5000 * k;
    e.event_number = k;
    e.offset = off;
    e.size = hal::kLcmLogHeaderBytes + e.channel.size() + e.data.size();
    off += e.size;
    ev.push_back(e);
  }
  return ev;
}

void write_log(const std::string& path, const std::vector<Ev>& events) {
  hal::LcmLogWriter w;
  ASSERT_EQ(w.open(path), hal::LcmLogStatus::kOk);
  for (const Ev& e : events)
    ASSERT_EQ(w.write(e.channel.c_str(), e.data.data(), e.data.size(), e.timestamp_us), hal::LcmLogStatus::kOk);
  ASSERT_EQ(w.close(), hal::LcmLogStatus::kOk);
  EXPECT_EQ(w.events_written(), events.size());
}

std::vector<Ev> read_log(const std::string& path, hal::LcmLogReadStats* stats = nullptr) {
  hal::LcmLogReader r;
  std::vector<Ev> out;
  EXPECT_EQ(r.open(path), hal::LcmLogStatus::kOk) << r.error();
  hal::LcmLogEvent ev;
  while (r.next(ev) == hal::LcmLogStatus::kOk) {
    Ev e;
    e.channel = std::string(ev.channel);
    e.data.assign(ev.data, ev.data + ev.data_len);
    e.timestamp_us = ev.timestamp_us;
    e.event_number = ev.event_number;
    e.offset = ev.offset;
    out.push_back(e);
  }
  if (stats != nullptr) *stats = r.stats();
  return out;
}

bool same(const Ev& a, const Ev& b) {
  return a.channel == b.channel && a.data == b.data && a.timestamp_us == b.timestamp_us &&
         a.event_number == b.event_number;
}

/// Events read with LCM's own C reader (lcm_eventlog_read_next_event) until it returns NULL.
std::vector<Ev> read_with_lcm(const std::string& path) {
  std::vector<Ev> out;
  lcm_eventlog_t* l = lcm_eventlog_create(path.c_str(), "r");
  if (l == nullptr) return out;
  while (lcm_eventlog_event_t* e = lcm_eventlog_read_next_event(l)) {
    Ev x;
    x.channel.assign(e->channel, static_cast<std::size_t>(e->channellen));
    const auto* d = static_cast<const std::uint8_t*>(e->data);
    x.data.assign(d, d + e->datalen);
    x.timestamp_us = e->timestamp;
    x.event_number = e->eventnum;
    out.push_back(x);
    lcm_eventlog_free_event(e);
  }
  lcm_eventlog_destroy(l);
  return out;
}

}  // namespace

TEST(LcmLog, WriteReadRoundTrip) {
  const std::string path = lcm_test::scratch("roundtrip.lcmlog");
  const std::vector<Ev> events = make_events(60);
  write_log(path, events);
  EXPECT_EQ(lcm_test::read_bytes(path).size(), events.back().offset + events.back().size);
  hal::LcmLogReadStats st;
  const std::vector<Ev> got = read_log(path, &st);
  ASSERT_EQ(got.size(), events.size());
  for (std::size_t k = 0; k < events.size(); ++k) {
    EXPECT_TRUE(same(got[k], events[k])) << "event " << k;
    EXPECT_EQ(got[k].offset, events[k].offset);
  }
  EXPECT_EQ(st.total_rejections(), 0u);
  EXPECT_EQ(st.events, events.size());
  std::remove(path.c_str());
}

TEST(LcmLog, EmptyAndMissingFiles) {
  const std::string path = lcm_test::scratch("empty.lcmlog");
  lcm_test::write_bytes(path, {});
  hal::LcmLogReader r;
  ASSERT_EQ(r.open(path), hal::LcmLogStatus::kOk);
  hal::LcmLogEvent ev;
  EXPECT_EQ(r.next(ev), hal::LcmLogStatus::kEndOfLog);
  EXPECT_EQ(r.stats().total_rejections(), 0u);
  std::remove(path.c_str());
  EXPECT_EQ(r.open(path), hal::LcmLogStatus::kOpenFailed);
  EXPECT_NE(r.error().find("No such file"), std::string::npos) << r.error();
  hal::LcmLogReader never_opened;
  EXPECT_EQ(never_opened.next(ev), hal::LcmLogStatus::kNotOpen);
}

TEST(LcmLog, WriterRejectsBadChannelNames) {
  const std::string path = lcm_test::scratch("badchan.lcmlog");
  hal::LcmLogWriter w;
  ASSERT_EQ(w.open(path), hal::LcmLogStatus::kOk);
  const std::uint8_t d[2] = {1, 2};
  EXPECT_EQ(w.write("", d, 2, 0), hal::LcmLogStatus::kBadChannel);
  EXPECT_EQ(w.write("TAB\tNAME", d, 2, 0), hal::LcmLogStatus::kBadChannel);
  EXPECT_EQ(w.write(std::string(256, 'A').c_str(), d, 2, 0), hal::LcmLogStatus::kBadChannel);
  EXPECT_EQ(w.write(std::string(255, 'A').c_str(), d, 2, 0), hal::LcmLogStatus::kOk);
  EXPECT_EQ(w.close(), hal::LcmLogStatus::kOk);
  EXPECT_EQ(read_log(path).size(), 1u);
  std::remove(path.c_str());
}

// A log written by LCM's C API (lcm_eventlog_write_event: the code lcm-logger uses) is read by ours.
TEST(LcmLog, ReadsLogWrittenByLcmEventlogApi) {
  const std::string path = lcm_test::scratch("by_lcm.lcmlog");
  const std::vector<Ev> events = make_events(40);
  lcm_eventlog_t* l = lcm_eventlog_create(path.c_str(), "w");
  ASSERT_NE(l, nullptr);
  for (const Ev& e : events) {
    lcm_eventlog_event_t le{};
    le.timestamp = e.timestamp_us;
    le.channellen = static_cast<std::int32_t>(e.channel.size());
    le.datalen = static_cast<std::int32_t>(e.data.size());
    le.channel = const_cast<char*>(e.channel.c_str());
    le.data = const_cast<std::uint8_t*>(e.data.data());
    ASSERT_EQ(lcm_eventlog_write_event(l, &le), 0);
  }
  lcm_eventlog_destroy(l);
  hal::LcmLogReadStats st;
  const std::vector<Ev> got = read_log(path, &st);
  ASSERT_EQ(got.size(), events.size());
  for (std::size_t k = 0; k < events.size(); ++k) EXPECT_TRUE(same(got[k], events[k])) << "event " << k;
  EXPECT_EQ(st.total_rejections(), 0u);
  // And LCM's reader reads ours: the byte streams are identical.
  const std::string ours = lcm_test::scratch("ours_same.lcmlog");
  write_log(ours, events);
  EXPECT_EQ(lcm_test::read_bytes(ours), lcm_test::read_bytes(path));
  std::remove(path.c_str());
  std::remove(ours.c_str());
}

// lcm-logplayer reads our log through LCM's reader and republishes every event into a log of its
// own (LCM's file provider); LCM's reader and ours then find the same channels and data.
TEST(LcmLog, LcmLogplayerReplaysOurLog) {
  const std::string ours = lcm_test::scratch("for_logplayer.lcmlog");
  const std::string theirs = lcm_test::scratch("from_logplayer.lcmlog");
  const std::vector<Ev> events = make_events(50);
  write_log(ours, events);
  const std::string cmd = std::string(SDINS_LCM_LOGPLAYER) + " --speed=100 --lcm-url='file://" + theirs +
                          "?mode=w' '" + ours + "' > /dev/null 2>&1";
  ASSERT_EQ(lcm_test::run(cmd), 0) << cmd;
  const std::vector<Ev> by_lcm = read_with_lcm(theirs);
  const std::vector<Ev> by_us = read_log(theirs);
  ASSERT_EQ(by_lcm.size(), events.size());
  ASSERT_EQ(by_us.size(), events.size());
  for (std::size_t k = 0; k < events.size(); ++k) {
    EXPECT_EQ(by_lcm[k].channel, events[k].channel) << k;
    EXPECT_EQ(by_lcm[k].data, events[k].data) << k;
    EXPECT_EQ(by_us[k].channel, events[k].channel) << k;
    EXPECT_EQ(by_us[k].data, events[k].data) << k;
  }
  // LCM's reader on our file directly, too.
  const std::vector<Ev> direct = read_with_lcm(ours);
  ASSERT_EQ(direct.size(), events.size());
  for (std::size_t k = 0; k < events.size(); ++k) EXPECT_TRUE(same(direct[k], events[k])) << k;
  std::remove(ours.c_str());
  std::remove(theirs.c_str());
}

// lcm-logger records messages we publish on udpm; our reader reads its log. Needs multicast.
TEST(LcmLog, ReadsLogRecordedByLcmLogger) {
  const std::string url = "udpm://239.255.76.67:" + std::to_string(17000 + ::getpid() % 20000) + "?ttl=0";
  {
    lcm_t* probe = lcm_create(url.c_str());
    if (probe == nullptr) GTEST_SKIP() << "LCM udpm cannot be created here (no multicast route): " << url;
    lcm_destroy(probe);
  }
  const std::string path = lcm_test::scratch("by_logger.lcmlog");
  std::remove(path.c_str());
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::execl(SDINS_LCM_LOGGER, "lcm-logger", "--quiet", "--force", ("--lcm-url=" + url).c_str(), path.c_str(),
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(700));  // logger subscribed
  hal::LcmTelemetry tel;
  hal::LcmTelemetryConfig cfg;
  cfg.lcm_url = url;
  ASSERT_EQ(tel.open(cfg), hal::LcmLogStatus::kOk);
  ASSERT_TRUE(tel.network_active());
  const std::vector<Ev> events = make_events(30);
  for (const Ev& e : events) {
    ASSERT_EQ(tel.publish(e.channel.c_str(), e.data.data(), e.data.size(), e.timestamp_us), hal::LcmLogStatus::kOk);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  ::kill(pid, SIGINT);
  int status = 0;
  ::waitpid(pid, &status, 0);
  hal::LcmLogReadStats st;
  const std::vector<Ev> got = read_log(path, &st);
  EXPECT_EQ(st.total_rejections(), 0u);
  ASSERT_EQ(got.size(), events.size()) << "lcm-logger recorded " << got.size() << " of " << events.size();
  for (std::size_t k = 0; k < events.size(); ++k) {
    EXPECT_EQ(got[k].channel, events[k].channel) << k;
    EXPECT_EQ(got[k].data, events[k].data) << k;
    EXPECT_EQ(got[k].event_number, static_cast<std::int64_t>(k));
  }
  std::remove(path.c_str());
}

// Every possible truncation point: all complete events before it are read, the cut one is
// reported as truncated (when something of it remains), nothing else is rejected.
TEST(LcmLog, TruncatedLogKeepsEveryCompleteEvent) {
  const std::string full = lcm_test::scratch("full.lcmlog");
  const std::string cut = lcm_test::scratch("cut.lcmlog");
  const std::vector<Ev> events = make_events(12);
  write_log(full, events);
  const std::vector<std::uint8_t> bytes = lcm_test::read_bytes(full);
  for (std::size_t n = 0; n <= bytes.size(); ++n) {
    lcm_test::write_bytes(cut, std::vector<std::uint8_t>(bytes.begin(), bytes.begin() + static_cast<long>(n)));
    std::size_t complete = 0;
    bool at_boundary = n == 0;
    for (const Ev& e : events) {
      if (e.offset + e.size <= n) ++complete;
      if (e.offset + e.size == n) at_boundary = true;
    }
    hal::LcmLogReadStats st;
    const std::vector<Ev> got = read_log(cut, &st);
    ASSERT_EQ(got.size(), complete) << "cut at " << n;
    for (std::size_t k = 0; k < complete; ++k) ASSERT_TRUE(same(got[k], events[k])) << "cut at " << n;
    if (at_boundary) {
      ASSERT_EQ(st.total_rejections(), 0u) << "cut at " << n;
    } else {
      // A cut inside the first 4 bytes of an event leaves no sync word: no_sync; else truncated.
      ASSERT_EQ(st.total_rejections(), 1u) << "cut at " << n;
      const bool partial_sync = n - events[complete].offset < 4;
      ASSERT_EQ(st.count(partial_sync ? hal::LcmLogRejection::kNoSync : hal::LcmLogRejection::kTruncatedEvent), 1u)
          << "cut at " << n;
      ASSERT_EQ(st.bytes_skipped, n - events[complete].offset);
    }
  }
  std::remove(full.c_str());
  std::remove(cut.c_str());
}

namespace {

void put_be32(std::vector<std::uint8_t>& b, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(v >> (24 - 8 * i));
}

}  // namespace

// Corruption in the middle of a log: each kind of damage to event 20 is rejected with its reason
// and every other event (before and after) is read intact.
TEST(LcmLog, CorruptionInTheMiddleLosesOnlyTheDamagedEvent) {
  const std::string full = lcm_test::scratch("clean.lcmlog");
  const std::string bad = lcm_test::scratch("corrupt.lcmlog");
  const std::vector<Ev> events = make_events(40);
  write_log(full, events);
  const std::vector<std::uint8_t> clean = lcm_test::read_bytes(full);
  const std::size_t k = 20;
  const Ev& v = events[k];
  ASSERT_GT(v.data.size(), 8u);
  const auto len_of = [&](std::size_t i) { return static_cast<std::uint32_t>(events[i].data.size()); };
  const std::uint32_t swallow_next = len_of(k) + static_cast<std::uint32_t>(events[k + 1].size);
  struct Case {
    const char* what;
    std::function<void(std::vector<std::uint8_t>&)> damage;
    hal::LcmLogRejection reason;
    bool victim_read;
  };
  const std::vector<Case> cases = {
      {"sync word", [&](auto& b) { b[v.offset + 1] ^= 0x40; }, hal::LcmLogRejection::kNoSync, false},
      {"channel length 0", [&](auto& b) { put_be32(b, v.offset + 20, 0); }, hal::LcmLogRejection::kBadChannelLength, false},
      {"channel length huge", [&](auto& b) { put_be32(b, v.offset + 20, 70000); }, hal::LcmLogRejection::kBadChannelLength, false},
      {"data length negative", [&](auto& b) { put_be32(b, v.offset + 24, 0xfffffff0u); }, hal::LcmLogRejection::kBadDataLength, false},
      {"data length past the end", [&](auto& b) { put_be32(b, v.offset + 24, 5000000u); }, hal::LcmLogRejection::kBadDataLength, false},
      {"data length into the next event", [&](auto& b) { put_be32(b, v.offset + 24, len_of(k) + 10); }, hal::LcmLogRejection::kBadDataLength, false},
      {"data length swallows exactly the next event", [&](auto& b) { put_be32(b, v.offset + 24, swallow_next); }, hal::LcmLogRejection::kBadDataLength, false},
      {"data length too short", [&](auto& b) { put_be32(b, v.offset + 24, len_of(k) - 5); }, hal::LcmLogRejection::kNoSync, true},
      {"channel name byte", [&](auto& b) { b[v.offset + 28] = 0x07; }, hal::LcmLogRejection::kBadChannelName, false},
      {"zeroed header", [&](auto& b) { std::fill(b.begin() + static_cast<long>(v.offset), b.begin() + static_cast<long>(v.offset + 28), 0); }, hal::LcmLogRejection::kNoSync, false},
  };
  for (const Case& c : cases) {
    std::vector<std::uint8_t> b = clean;
    c.damage(b);
    lcm_test::write_bytes(bad, b);
    hal::LcmLogReadStats st;
    const std::vector<Ev> got = read_log(bad, &st);
    SCOPED_TRACE(c.what);
    EXPECT_GE(st.count(c.reason), 1u);
    // Every undamaged event, in order.
    std::size_t j = 0;
    for (std::size_t i = 0; i < events.size(); ++i) {
      if (i == k) {
        if (c.victim_read) {
          ASSERT_LT(j, got.size());
          EXPECT_EQ(got[j].offset, v.offset);
          ++j;
        }
        continue;
      }
      ASSERT_LT(j, got.size()) << "event " << i << " missing";
      EXPECT_TRUE(same(got[j], events[i])) << "event " << i;
      ++j;
    }
    EXPECT_EQ(j, got.size()) << "extra events";
  }
  std::remove(full.c_str());
  std::remove(bad.c_str());
}

// Garbage between events and before the first one is skipped and counted as no_sync.
TEST(LcmLog, GarbageBetweenEventsIsSkippedAndCounted) {
  const std::string path = lcm_test::scratch("garbage.lcmlog");
  const std::vector<Ev> events = make_events(10);
  write_log(path, events);
  std::vector<std::uint8_t> b = lcm_test::read_bytes(path);
  std::vector<std::uint8_t> g = {0xED, 0xA1, 0x00, 0x42, 0x42};  // starts like a sync word
  g.insert(g.end(), b.begin(), b.begin() + static_cast<long>(events[5].offset));
  g.insert(g.end(), 37, 0x55);
  g.insert(g.end(), b.begin() + static_cast<long>(events[5].offset), b.end());
  lcm_test::write_bytes(path, g);
  hal::LcmLogReadStats st;
  const std::vector<Ev> got = read_log(path, &st);
  ASSERT_EQ(got.size(), events.size());
  for (std::size_t k = 0; k < events.size(); ++k) EXPECT_TRUE(same(got[k], events[k])) << k;
  EXPECT_EQ(st.count(hal::LcmLogRejection::kNoSync), 2u);
  EXPECT_EQ(st.bytes_skipped, 5u + 37u);
  ASSERT_EQ(st.records.size(), 2u);
  EXPECT_EQ(st.records[0].offset, 0u);
  EXPECT_EQ(st.records[1].offset, 5u + events[5].offset);
  std::remove(path.c_str());
}

// Random damage (bursts of random bytes at random places, many seeds): never a crash, and every
// event whose bytes were not touched is read intact and in order.
TEST(LcmLog, RandomDamageNeverLosesAnUntouchedEvent) {
  const std::string full = lcm_test::scratch("fuzz_clean.lcmlog");
  const std::string bad = lcm_test::scratch("fuzz.lcmlog");
  const std::vector<Ev> events = make_events(80);
  write_log(full, events);
  const std::vector<std::uint8_t> clean = lcm_test::read_bytes(full);
  std::uint64_t s = 0x9E3779B97F4A7C15ull;
  const auto rnd = [&]() {
    s ^= s << 13;
    s ^= s >> 7;
    s ^= s << 17;
    return s;
  };
  for (int trial = 0; trial < 400; ++trial) {
    std::vector<std::uint8_t> b = clean;
    std::vector<bool> touched(events.size(), false);
    const int bursts = 1 + static_cast<int>(rnd() % 3);
    for (int q = 0; q < bursts; ++q) {
      const std::size_t at = rnd() % b.size();
      const std::size_t n = 1 + rnd() % 6;
      for (std::size_t i = at; i < at + n && i < b.size(); ++i) {
        std::uint8_t x = static_cast<std::uint8_t>(rnd());
        if (x == 0xED) x = 0xEE;  // no new sync words: keep the expectation exact
        b[i] = x;
      }
      for (std::size_t e = 0; e < events.size(); ++e)
        if (events[e].offset < at + n && at < events[e].offset + events[e].size) touched[e] = true;
    }
    lcm_test::write_bytes(bad, b);
    hal::LcmLogReadStats st;
    const std::vector<Ev> got = read_log(bad, &st);
    std::size_t j = 0;
    for (std::size_t e = 0; e < events.size(); ++e) {
      if (touched[e]) continue;
      while (j < got.size() && got[j].offset < events[e].offset) ++j;  // damaged events read as such
      ASSERT_LT(j, got.size()) << "trial " << trial << ": untouched event " << e << " lost";
      ASSERT_EQ(got[j].offset, events[e].offset) << "trial " << trial << ": untouched event " << e << " lost";
      ASSERT_TRUE(same(got[j], events[e])) << "trial " << trial << " event " << e;
    }
  }
  std::remove(full.c_str());
  std::remove(bad.c_str());
}

// Why the project has its own reader: LCM's lcm_eventlog_read_next_event trusts the data length,
// and when the read it implies comes up short it returns NULL, which ends the log for every LCM
// tool. On a log whose event 1 (of 3) claims 1 MiB of data, LCM's reader returns one event; ours
// returns events 0 and 2. If a future LCM resynchronises, this test fails and the comment in
// hal/lcm_log.hpp should be revisited.
TEST(LcmLog, LcmEventlogLosesEventsAfterACorruptLength) {
  const std::string path = lcm_test::scratch("lcm_weakness.lcmlog");
  std::vector<Ev> events = make_events(3);
  write_log(path, events);
  std::vector<std::uint8_t> b = lcm_test::read_bytes(path);
  put_be32(b, events[1].offset + 24, 1u << 20);
  lcm_test::write_bytes(path, b);
  EXPECT_EQ(read_with_lcm(path).size(), 1u);
  hal::LcmLogReadStats st;
  const std::vector<Ev> ours = read_log(path, &st);
  ASSERT_EQ(ours.size(), 2u);
  EXPECT_TRUE(same(ours[0], events[0]));
  EXPECT_TRUE(same(ours[1], events[2]));
  EXPECT_EQ(st.count(hal::LcmLogRejection::kBadDataLength), 1u);
  std::remove(path.c_str());
}
