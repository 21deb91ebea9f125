// The bare-metal image flies config/default.toml's values: its configuration is generated from the
// file (fsw/baremetal/default_flight_config.hpp, by cfg/gen/gen_baremetal_config.cpp) and must
// equal, field for field and bit for bit, what the one reader makes of the file. The CTest
// baremetal_config_generated checks that the committed header is the generator's output now.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <string>

#include "../../fsw/baremetal/default_flight_config.hpp"
#include "../../fsw/baremetal/synthetic_sensors.hpp"
#include "cfg/flight_config.hpp"
#include "cfg/flight_config_fields.hpp"

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
