// Bare-metal entry of the fsw image (docs/baremetal.md): the flight application with the
// paper's 24-state and 15-state filters, statically allocated, fed the way every harness feeds it
// (fsw::InputEvent through FlightApp::on_event: almanac elements, raw receiver epochs, 1 kHz IMU
// samples) from
// the synthetic receiver at rest of synthetic_sensors.hpp: the almanac at power-up, then the IMU
// and a raw epoch every second. The flight application initialises itself by stationary alignment
// (levelling + gyrocompassing over 60 s, position from the single-point fix) and then runs the
// 200 Hz and 1 Hz groups. A real target takes the samples and epochs from the HAL and waits for its
// sample interrupt instead. The loop keeps every fsw path in the image (raw-epoch conversion,
// single-point solution, alignment, mechanization, EKF propagate/update/feedback): the link proves
// the core needs nothing from a hosted environment.
#include <cstdint>

#include "fsw/flight_app.hpp"
#include "synthetic_sensors.hpp"

namespace {

fsw::FlightApp<fsw::Layout24> g_app24;
fsw::FlightApp<fsw::Layout15> g_app15;
fsw::FrameOutput g_out24, g_out15;
fsw::InputEvent g_event;  ///< the input being delivered (static, not on the stack: 864 B on x86-64)

}  // namespace

// Results where a debugger (or a telemetry task) can read them.
extern "C" {
volatile std::uint32_t g_sdins_ekf_updates = 0;
volatile std::uint32_t g_sdins_fsw_errors = 0;
volatile std::uint32_t g_sdins_initialised = 0;
volatile double g_sdins_lat_rad = 0.0;
}

int main() {
  const fsw::FlightAppConfig cfg = sdins_baremetal::flight_config();
  if (g_app24.init(cfg) != fsw::Status::kOk || g_app15.init(cfg) != fsw::Status::kOk) {
    g_sdins_fsw_errors = g_sdins_fsw_errors + 1u;
    for (;;) {
    }
  }
  for (int k = 0; k < sdins_baremetal::kSatellites; ++k) {
    g_event.kind = fsw::InputEvent::Kind::kAlmanac;
    g_event.almanac = sdins_baremetal::almanac(k);
    if (g_app24.on_event(g_event, g_out24) != fsw::Status::kOk || g_app15.on_event(g_event, g_out15) != fsw::Status::kOk)
      g_sdins_fsw_errors = g_sdins_fsw_errors + 1u;
  }
  constexpr std::uint32_t kSamplesPerEpoch = 1000;  // 1 kHz IMU, 1 Hz receiver
  for (std::uint32_t n = 0;; ++n) {
    const fsw::ImuSample s = sdins_baremetal::imu_sample(n);
    g_event.kind = fsw::InputEvent::Kind::kImu;
    g_event.t_s = s.t_s;
    g_event.imu = s;
    if (g_app24.on_event(g_event, g_out24) != fsw::Status::kOk || g_app15.on_event(g_event, g_out15) != fsw::Status::kOk)
      g_sdins_fsw_errors = g_sdins_fsw_errors + 1u;
    if ((n + 1) % kSamplesPerEpoch == 0u) {  // the epoch of this sample's time, after it (receiver latency)
      g_event.kind = fsw::InputEvent::Kind::kGnssRaw;
      g_event.t_s = s.t_s;
      sdins_baremetal::raw_epoch(s.t_s, g_event.gnss);
      if (g_app24.on_event(g_event, g_out24) != fsw::Status::kOk || g_app15.on_event(g_event, g_out15) != fsw::Status::kOk)
        g_sdins_fsw_errors = g_sdins_fsw_errors + 1u;
    }
    g_sdins_initialised = (g_app24.initialised() ? 1u : 0u) + (g_app15.initialised() ? 1u : 0u);
    g_sdins_ekf_updates = g_app24.executive().health().ekf_updates + g_app15.executive().health().ekf_updates;
    if (g_out24.nav_valid) g_sdins_lat_rad = g_out24.nav.llh.x();
  }
}
