// candump log format: round trips, python-can / can-utils syntax, malformed lines counted and skipped.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <string>

#include "hal/can_log.hpp"
#include "hal/can_protocol.hpp"

namespace {

using hal::CandumpLine;
using hal::CanFrame;

std::string temp_path(const char* name) {
  const char* dir = std::getenv("TMPDIR");
  return std::string(dir ? dir : "/tmp") + "/sdins_can_log_" + std::to_string(::getpid()) + "_" + name;
}

TEST(CanLog, ParsesCanUtilsSyntax) {
  CanFrame f;
  std::string iface;
  ASSERT_EQ(hal::parse_candump_line("(1699999999.123456) can0 123#DEADBEEF", f, iface), CandumpLine::kFrame);
  EXPECT_EQ(iface, "can0");
  EXPECT_EQ(f.id, 0x123u);
  EXPECT_FALSE(f.extended || f.fd);
  EXPECT_EQ(f.len, 4);
  EXPECT_EQ(f.data[0], 0xDE);
  EXPECT_EQ(f.data[3], 0xEF);
  EXPECT_DOUBLE_EQ(f.timestamp_s, 1699999999.123456);

  ASSERT_EQ(hal::parse_candump_line("(1699999999.123456) vcan0 123##1DEADBEEF", f, iface), CandumpLine::kFrame);
  EXPECT_TRUE(f.fd && f.brs && !f.esi);
  EXPECT_EQ(f.len, 4);
  ASSERT_EQ(hal::parse_candump_line("(0.000001) can1 1ABCDEF0#", f, iface), CandumpLine::kFrame);
  EXPECT_TRUE(f.extended);
  EXPECT_EQ(f.id, 0x1ABCDEF0u);
  EXPECT_EQ(f.len, 0);
  // python-can's writer may append a direction mark.
  ASSERT_EQ(hal::parse_candump_line("(1.5) can0 010##3" + std::string(24, 'A') + " R", f, iface), CandumpLine::kFrame);
  EXPECT_TRUE(f.fd && f.brs && f.esi);
  EXPECT_EQ(f.len, 12);
  EXPECT_EQ(hal::parse_candump_line("", f, iface), CandumpLine::kBlank);
  EXPECT_EQ(hal::parse_candump_line("# comment", f, iface), CandumpLine::kBlank);
}

TEST(CanLog, FormatParseRoundTrip) {
  hal::can::ImuEncoder enc(41);
  fsw::ImuSample s;
  s.t_s = 3.25;
  s.dt_s = 1e-3;
  s.dtheta_rad = fsw::Vec3(1e-4, -2e-4, 3e-5);
  CanFrame f;
  ASSERT_EQ(enc.encode(s, f), hal::can::CodecStatus::kOk);
  f.timestamp_s = 1700000000.000125;
  const std::string line = hal::format_candump_line(f, "vcan0");
  EXPECT_EQ(line.substr(0, 36), "(1700000000.000125) vcan0 010##12900");
  CanFrame g;
  std::string iface;
  ASSERT_EQ(hal::parse_candump_line(line, g, iface), CandumpLine::kFrame);
  EXPECT_TRUE(hal::can_frame_equal(f, g));
  EXPECT_DOUBLE_EQ(g.timestamp_s, f.timestamp_s);
  CanFrame ext;
  ext.id = 0x18DAF110;
  ext.extended = true;
  ext.len = 3;
  ext.data[2] = 0x7F;
  EXPECT_EQ(hal::format_candump_line(ext, "can0"), "(0.000000) can0 18DAF110#00007F");
}

TEST(CanLog, MalformedLinesAreCountedWithTheirReason) {
  struct Case {
    const char* line;
    CandumpLine want;
  } cases[] = {
      {"1699999999.1 can0 123#00", CandumpLine::kBadTimestamp},
      {"(abc) can0 123#00", CandumpLine::kBadTimestamp},
      {"(1.2.3) can0 123#00", CandumpLine::kBadTimestamp},
      {"(1.0)", CandumpLine::kNoInterface},
      {"(1.0) can0", CandumpLine::kNoFrame},
      {"(1.0) can0 12300", CandumpLine::kNoFrame},
      {"(1.0) can0 12#00", CandumpLine::kBadId},
      {"(1.0) can0 800#00", CandumpLine::kBadId},
      {"(1.0) can0 12G#00", CandumpLine::kBadId},
      {"(1.0) can0 123#0", CandumpLine::kBadData},
      {"(1.0) can0 123#0Z", CandumpLine::kBadData},
      {"(1.0) can0 123#000102030405060708", CandumpLine::kBadLength},
      {"(1.0) can0 123##1000102030405060708", CandumpLine::kBadLength},  // 9 bytes: not an FD length
      {"(1.0) can0 123##", CandumpLine::kBadFdFlags},
      {"(1.0) can0 123##X00", CandumpLine::kBadFdFlags},
      {"(1.0) can0 123#R", CandumpLine::kRemoteFrame},
      {"(1.0) can0 20000080#0000000000000000", CandumpLine::kErrorFrame},
      {"(1.0) can0 123#00 extra", CandumpLine::kTrailing},
      {"(1.0) can0 123#00 R more", CandumpLine::kTrailing},
  };
  for (const Case& c : cases) {
    CanFrame f;
    std::string iface;
    EXPECT_EQ(hal::parse_candump_line(c.line, f, iface), c.want) << c.line;
  }
}

TEST(CanLog, ReaderSkipsBadLinesKeepsGoingAndReports) {
  const std::string path = temp_path("mixed.log");
  {
    std::ofstream o(path);
    o << "(1.000000) can0 010##1" << std::string(96, '0') << "\n"
      << "garbage line\n"
      << "\n"
      << "(1.001000) can0 123#DEADBEEF\r\n"  // CRLF tolerated
      << "(1.002000) can0 123#DEADBEE\n"
      << "(1.003000) can0 123#R\n"
      << "(1.004000) can0 7FF#01";  // no final newline
  }
  hal::CandumpReader r;
  ASSERT_TRUE(r.open(path));
  CanFrame f;
  std::string iface;
  int n = 0;
  while (r.next(f, iface)) ++n;
  EXPECT_EQ(n, 3);
  EXPECT_EQ(r.lines(), 7);
  EXPECT_EQ(r.bad_lines(), 3);
  EXPECT_EQ(r.count(CandumpLine::kBadTimestamp), 1);
  EXPECT_EQ(r.count(CandumpLine::kBadData), 1);
  EXPECT_EQ(r.count(CandumpLine::kRemoteFrame), 1);
  ASSERT_EQ(r.problems().size(), 3u);
  EXPECT_NE(r.problems()[0].find(":2: bad timestamp"), std::string::npos) << r.problems()[0];
  EXPECT_NE(r.problems()[1].find(":5: bad payload"), std::string::npos) << r.problems()[1];
  EXPECT_EQ(f.id, 0x7FFu);
  EXPECT_TRUE(r.error().empty());
  std::remove(path.c_str());

  hal::CandumpReader missing;
  EXPECT_FALSE(missing.open(path));
  EXPECT_NE(missing.error().find("No such file"), std::string::npos);
}

TEST(CanLog, WriterReaderRoundTripOfAStream) {
  const std::string path = temp_path("stream.log");
  hal::can::ImuEncoder enc;
  std::vector<CanFrame> frames;
  for (int k = 0; k < 50; ++k) {
    fsw::ImuSample s;
    s.t_s = 1e-3 * (k + 1);
    s.dt_s = 1e-3;
    s.dv_mps = fsw::Vec3(0.001 * k, 0.0, -0.0098);
    CanFrame f;
    ASSERT_EQ(enc.encode(s, f), hal::can::CodecStatus::kOk);
    f.timestamp_s = 1700000000.0 + s.t_s;
    frames.push_back(f);
  }
  hal::CandumpWriter w;
  ASSERT_TRUE(w.open(path));
  for (const CanFrame& f : frames) ASSERT_TRUE(w.write(f, "can0"));
  CanFrame bad;
  bad.len = 9;  // invalid classic length: refused
  EXPECT_FALSE(w.write(bad, "can0"));
  ASSERT_TRUE(w.close());
  hal::CandumpReader r;
  ASSERT_TRUE(r.open(path));
  CanFrame g;
  std::string iface;
  std::size_t i = 0;
  while (r.next(g, iface)) {
    ASSERT_LT(i, frames.size());
    EXPECT_TRUE(hal::can_frame_equal(g, frames[i]));
    EXPECT_NEAR(g.timestamp_s, frames[i].timestamp_s, 1e-6);
    ++i;
  }
  EXPECT_EQ(i, frames.size());
  EXPECT_EQ(r.bad_lines(), 0);
  std::remove(path.c_str());
}

}  // namespace
