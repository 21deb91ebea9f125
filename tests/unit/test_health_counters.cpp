// The executive's health counters are declared once (FSW_EXECUTIVE_HEALTH_COUNTERS,
// FSW_EXECUTIVE_PVT_COUNTERS in fsw/executive.hpp; FSW_GNSS_CONVERSION_COUNTERS in
// fsw/gps_orbit.hpp). The struct, the LCM conversion, the CSV export and the JSON summary are
// generated from the lists (a missing message field fails to compile); these tests check the
// message definition itself, both ways, and that every counter arrives with its own value.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <string>

#include "fsw/executive.hpp"
#include "hal/lcm_convert.hpp"
#include "tools/fsw_report.hpp"

namespace {

struct ListEntry {
  std::string name;
  std::string lcm_type;  ///< what the message must declare for it
};

std::vector<ListEntry> counter_list() {
  std::vector<ListEntry> v;
  auto lcm_type = [](const char* type) { return std::string(type) == "double" ? "double" : "int64_t"; };
#define SDINS_LIST(type, name, doc) v.push_back({#name, lcm_type(#type)});
#define SDINS_LIST_CONV(type, name, doc) v.push_back({"conv_" #name, lcm_type(#type)});
  FSW_EXECUTIVE_HEALTH_COUNTERS(SDINS_LIST)
  FSW_GNSS_CONVERSION_COUNTERS(SDINS_LIST_CONV)
  FSW_EXECUTIVE_PVT_COUNTERS(SDINS_LIST)
#undef SDINS_LIST
#undef SDINS_LIST_CONV
  return v;
}

/// Scalar fields of filter_health_t.lcm in declaration order: name -> type.
std::vector<std::pair<std::string, std::string>> message_fields() {
  std::ifstream f(std::string(SDINS_TEST_SOURCE_DIR) + "/hal/lcm/filter_health_t.lcm");
  EXPECT_TRUE(f.good()) << "cannot read hal/lcm/filter_health_t.lcm";
  std::vector<std::pair<std::string, std::string>> out;
  const std::regex field(R"(^\s*(int64_t|int32_t|int16_t|int8_t|double|boolean)\s+(\w+)\s*;)");
  std::string line;
  std::smatch m;
  while (std::getline(f, line))
    if (std::regex_search(line, m, field)) out.emplace_back(m[2], m[1]);
  return out;
}

}  // namespace

TEST(HealthCounters, MessageCarriesEveryCounterOfTheListsInOrder) {
  const auto fields = message_fields();
  ASSERT_GT(fields.size(), 10u);
  // The counters are the message's fields from `ticks` up to the first per-epoch field, in the
  // lists' order and with the list's type: nothing missing, nothing extra, nothing reordered.
  std::size_t first = 0;
  while (first < fields.size() && fields[first].first != "ticks") ++first;
  ASSERT_LT(first, fields.size());
  const auto list = counter_list();
  ASSERT_LE(first + list.size(), fields.size());
  for (std::size_t k = 0; k < list.size(); ++k) {
    EXPECT_EQ(fields[first + k].first, list[k].name) << "position " << k;
    EXPECT_EQ(fields[first + k].second, list[k].lcm_type) << list[k].name;
  }
  EXPECT_EQ(fields[first + list.size()].first, "ekf_updated")
      << "a field after the counters that no list declares";
}

TEST(HealthCounters, EveryCounterArrivesWithItsOwnValue) {
  fsw::ExecutiveHealth h;
  fsw::GnssConversionStats conv;
  std::uint32_t next = 1;
#define SDINS_SET(type, name, doc) h.name = static_cast<type>(next++);
#define SDINS_SET_CONV(type, name, doc) conv.name = static_cast<type>(next++);
  FSW_EXECUTIVE_HEALTH_COUNTERS(SDINS_SET)
  FSW_GNSS_CONVERSION_COUNTERS(SDINS_SET_CONV)
  FSW_EXECUTIVE_PVT_COUNTERS(SDINS_SET)
#undef SDINS_SET
#undef SDINS_SET_CONV
  sdins::filter_health_t msg{};
  hal::to_msg(12.5, h, conv, fsw::FrameOutput{}, 10.83, msg);
  next = 1;
#define SDINS_CHECK(type, name, doc) EXPECT_EQ(static_cast<double>(msg.name), static_cast<double>(next++)) << #name;
#define SDINS_CHECK_CONV(type, name, doc) \
  EXPECT_EQ(static_cast<double>(msg.conv_##name), static_cast<double>(next++)) << #name;
  FSW_EXECUTIVE_HEALTH_COUNTERS(SDINS_CHECK)
  FSW_GNSS_CONVERSION_COUNTERS(SDINS_CHECK_CONV)
  FSW_EXECUTIVE_PVT_COUNTERS(SDINS_CHECK)
#undef SDINS_CHECK
#undef SDINS_CHECK_CONV
  // The JSON summary has every executive counter under its list name.
  const nlohmann::json j = tools::executive_json(h);
  next = 1;
#define SDINS_JSON(type, name, doc) \
  EXPECT_EQ(j.at(#name).get<double>(), static_cast<double>(next++)) << #name;
  FSW_EXECUTIVE_HEALTH_COUNTERS(SDINS_JSON)
  next += 4;  // the conversion counters are not part of ExecutiveHealth
  FSW_EXECUTIVE_PVT_COUNTERS(SDINS_JSON)
#undef SDINS_JSON
}

TEST(HealthCounters, SummingRunsAddsCountersAndKeepsTheWorstTick) {
  fsw::ExecutiveHealth a, b;
  a.ticks = 3;
  a.pvt_unused = 2;
  a.worst_tick_s = 0.004;
  b.ticks = 5;
  b.pvt_unused = 1;
  b.worst_tick_s = 0.003;
  fsw::add_health_counters(a, b);
  EXPECT_EQ(a.ticks, 8u);
  EXPECT_EQ(a.pvt_unused, 3u);
  EXPECT_DOUBLE_EQ(a.worst_tick_s, 0.004);
}
