// The bare-metal image's input (fsw/baremetal/synthetic_sensors.hpp) flown on the host through
// the same flight-application entries and order as fsw/baremetal/main.cpp: the synthetic
// receiver at rest must make the flight application initialise by stationary alignment from its
// raw epochs and then navigate on the spot, so the image runs every fsw path it links.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "../../fsw/baremetal/synthetic_sensors.hpp"
#include "fsw/flight_app.hpp"

namespace {

template <class Layout>
void fly_image_input() {
  auto app = std::make_unique<fsw::FlightApp<Layout>>();
  ASSERT_EQ(app->init(sdins_baremetal::flight_config()), fsw::Status::kOk);
  for (int k = 0; k < sdins_baremetal::kSatellites; ++k)
    ASSERT_EQ(app->on_almanac(sdins_baremetal::almanac(k)), fsw::Status::kOk) << k;
  fsw::FrameOutput out;
  fsw::GnssRawEpoch e;
  int min_sats = 99;
  for (std::uint32_t n = 0; n < 100000; ++n) {  // 100 s
    const fsw::ImuSample s = sdins_baremetal::imu_sample(n);
    ASSERT_EQ(app->on_imu(s, out), fsw::Status::kOk) << n;
    if ((n + 1) % 1000 != 0) continue;
    sdins_baremetal::raw_epoch(s.t_s, e);
    min_sats = std::min(min_sats, e.n_meas);
    ASSERT_EQ(app->on_gnss(e), fsw::Status::kOk) << s.t_s;
  }
  const fsw::FlightAppHealth& h = app->health();
  EXPECT_GE(min_sats, 5);
  ASSERT_TRUE(h.initialised);
  EXPECT_EQ(h.init_mode, fsw::InitMode::kStatic);
  EXPECT_GE(h.init_t_s, 60.0);
  EXPECT_LE(h.init_t_s, 63.0);
  EXPECT_EQ(h.conversion.no_almanac + h.conversion.unhealthy + h.conversion.invalid, 0u);
  EXPECT_EQ(h.gnss_rejected, 0u);
  const fsw::ExecutiveHealth& x = app->executive().health();
  EXPECT_EQ(x.fsw_errors, 0u);
  EXPECT_GE(x.ekf_updates, 30u);
  EXPECT_EQ(x.pr_rejected, 0u);
  // At rest on the spot: the solution stays at the receiver, level, heading along the body axes.
  const fsw::NavState& nav = out.nav;
  const fsw::Vec3 d = fsw::ecef_from_llh(nav.llh) - fsw::ecef_from_llh(sdins_baremetal::receiver_llh());
  EXPECT_LT(d.norm(), 1.0);
  EXPECT_LT(nav.vel_enu_mps.norm(), 0.05);
  EXPECT_LT(fsw::rotvec_from_quat(nav.q_b_n).norm(), 0.1 * fsw::kDegToRad);
}

}  // namespace

TEST(BaremetalInput, The24StateImageInitialisesAndNavigates) { fly_image_input<fsw::Layout24>(); }
TEST(BaremetalInput, The15StateImageInitialisesAndNavigates) { fly_image_input<fsw::Layout15>(); }
