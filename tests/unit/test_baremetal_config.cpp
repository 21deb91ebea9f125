// The bare-metal image flies config/default.toml's values: its configuration is generated from the
// file (fsw/baremetal/default_flight_config.hpp, by cfg/gen/gen_baremetal_config.cpp) and must
// equal, field for field and bit for bit, what the one reader makes of the file. The CTest
// baremetal_config_generated checks that the committed header is the generator's output now.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "../../fsw/baremetal/default_flight_config.hpp"
#include "../../fsw/baremetal/synthetic_sensors.hpp"
#include "cfg/flight_config.hpp"
#include "fsw/flight_app_config_fields.hpp"
#include "fsw/flight_app_config_wire.hpp"

namespace {

const std::filesystem::path kSourceFile = std::filesystem::path(SDINS_TEST_SOURCE_DIR) / "config/default.toml";

bool same(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
bool same(const fsw::Vec3& a, const fsw::Vec3& b) { return same(a.x(), b.x()) && same(a.y(), b.y()) && same(a.z(), b.z()); }
template <class T>
bool same(const T& a, const T& b) {
  return a == b;
}

}  // namespace

TEST(BaremetalConfig, TheImageFliesTheValuesOfConfigDefaultToml) {
  cfg::FlightConfig f;
  const cfg::FlightConfigResult r = cfg::parse_flight_config_file(kSourceFile.string(), f);
  ASSERT_TRUE(r.ok) << r.error;
  const fsw::FlightAppConfig image = sdins_baremetal::default_flight_config();
  std::string differ;
#define COMPARE(path, in_schema) \
  if (!same(image.path, f.app.path)) differ += std::string(" ") + #path;
  FLIGHT_CONFIG_FIELDS(COMPARE)
#undef COMPARE
  EXPECT_EQ(differ, "") << "regenerate fsw/baremetal/default_flight_config.hpp (its header says how)";
  // The values the issue found different in the image's old initialisers, now the file's.
  EXPECT_EQ(image.exec.ekf.arw_rad_per_rts, 2e-7);
  EXPECT_EQ(image.exec.ekf.pseudorange_sigma_m, 0.3);
  EXPECT_EQ(image.exec.ekf.pseudorange_rate_sigma_mps, 0.01);
  EXPECT_EQ(image.exec.ekf.clock_bias_sigma_m, 10.0);
  // The image's one departure: stationary alignment for its receiver at rest.
  const fsw::FlightAppConfig flown = sdins_baremetal::flight_config();
  EXPECT_EQ(flown.init_mode, fsw::InitMode::kStatic);
  fsw::FlightAppConfig back = flown;
  back.init_mode = image.init_mode;
  std::string other;
#define COMPARE(path, in_schema) \
  if (!same(back.path, image.path)) other += std::string(" ") + #path;
  FLIGHT_CONFIG_FIELDS(COMPARE)
#undef COMPARE
  EXPECT_EQ(other, "");
}

// The target replay carries the configuration by value (fsw/flight_app_config_wire.hpp): every
// field round-trips bit for bit, whatever its type; a wrong length or a value its field cannot
// hold is refused, never taken.
TEST(FlightConfigWire, EveryFieldRoundTripsAndBadValuesAreRefused) {
  cfg::FlightConfig f;
  ASSERT_TRUE(cfg::parse_flight_config_file(kSourceFile.string(), f).ok);
  fsw::FlightAppConfig c = f.app;
  // Values unlike the defaults, in every field's type: a changed field the codec dropped would show.
  c.exec.ekf.arw_rad_per_rts = -0.0;
  c.exec.ekf.lever_arm_b_m = fsw::Vec3(0.125, -3.5, 1e-300);
  c.exec.ekf.frozen_states = 0xF00000000000000Full;
  c.exec.ekf_group_inline = !c.exec.ekf_group_inline;
  c.pvt_max_quality = -7;
  c.init_mode = fsw::InitMode::kVelocityMatching;
  c.vm_rest_gyro_bias = !c.vm_rest_gyro_bias;
  const std::size_t n = fsw::flight_config_wire_bytes();
  std::vector<std::uint8_t> wire(n + 8);
  ASSERT_EQ(fsw::encode_flight_config(c, wire.data(), n - 1), 0u);  // too small: nothing written
  ASSERT_EQ(fsw::encode_flight_config(c, wire.data(), wire.size()), n);
  fsw::FlightAppConfig back{};
  ASSERT_EQ(fsw::decode_flight_config(wire.data(), n, back), fsw::Status::kOk);
  std::string differ;
#define COMPARE(path, in_schema) \
  if (!same(back.path, c.path)) differ += std::string(" ") + #path;
  FLIGHT_CONFIG_FIELDS(COMPARE)
#undef COMPARE
  EXPECT_EQ(differ, "");
  EXPECT_TRUE(std::signbit(back.exec.ekf.arw_rad_per_rts));
  // 8 bytes a scalar, 24 a Vec3: the size of every field's value, no padding.
  std::size_t words = 0;
#define COUNT(path, in_schema) words += fsw::config_wire::words(c.path);
  FLIGHT_CONFIG_FIELDS(COUNT)
#undef COUNT
  EXPECT_EQ(n, 8 * words);

  EXPECT_EQ(fsw::decode_flight_config(wire.data(), n - 1, back), fsw::Status::kBadInput);
  EXPECT_EQ(fsw::decode_flight_config(wire.data(), n + 8, back), fsw::Status::kBadInput);
  EXPECT_EQ(fsw::decode_flight_config(nullptr, n, back), fsw::Status::kBadInput);
  // The first field is imu_samples_per_frame (an int): a value beyond int is refused.
  std::vector<std::uint8_t> bad = wire;
  bad[4] = 0x01;  // 2^32 + its value
  EXPECT_EQ(fsw::decode_flight_config(bad.data(), n, back), fsw::Status::kBadInput);
  // exec.ekf_group_inline (a bool) is the 8th field: 2 is not a bool.
  bad = wire;
  bad[7 * 8] = 2;
  EXPECT_EQ(fsw::decode_flight_config(bad.data(), n, back), fsw::Status::kBadInput);
}
