// Bare-metal entry of the fsw image (docs/baremetal.md): the flight application with the
// paper's 24-state and 15-state filters, statically allocated, fed the way every harness feeds it
// (fsw::drive, fsw/driver.hpp: almanac elements, raw receiver epochs, 1 kHz IMU samples) from
// the synthetic receiver at rest of synthetic_sensors.hpp: the almanac at power-up, then the IMU
// and a raw epoch every second. The flight application initialises itself by stationary alignment
// (levelling + gyrocompassing over 60 s, position from the single-point fix) and then runs the
// 200 Hz and 1 Hz groups. A real target takes the samples and epochs from the HAL and waits for its
// sample interrupt instead. The loop keeps every fsw path in the image (raw-epoch conversion,
// single-point solution, alignment, mechanization, EKF propagate/update/feedback): the link proves
// the core needs nothing from a hosted environment.
#include <cstdint>

#include "fsw/driver.hpp"
#include "fsw/flight_app.hpp"
#include "synthetic_sensors.hpp"

namespace {

fsw::FlightDriver<fsw::Layout24> g_drv24;
fsw::FlightDriver<fsw::Layout15> g_drv15;

/// The synthetic receiver at rest as an event source (fsw/driver.hpp): the almanac at power-up,
/// then the 1 kHz IMU samples, each 1000th followed by the raw epoch of its time (receiver
/// latency). It never ends. The event is static, not on the stack (864 B on x86-64).
class SyntheticSensors {
 public:
  const fsw::InputEvent* next() {
    if (sat_ < sdins_baremetal::kSatellites) {
      ev_.kind = fsw::InputEvent::Kind::kAlmanac;
      ev_.almanac = sdins_baremetal::almanac(sat_++);
      return &ev_;
    }
    if (epoch_due_) {
      epoch_due_ = false;
      ev_.kind = fsw::InputEvent::Kind::kGnssRaw;
      sdins_baremetal::raw_epoch(ev_.t_s, ev_.gnss);  // ev_.t_s: the last sample's
      return &ev_;
    }
    ev_.kind = fsw::InputEvent::Kind::kImu;
    ev_.imu = sdins_baremetal::imu_sample(n_);
    ev_.t_s = ev_.imu.t_s;
    epoch_due_ = (n_ + 1) % kSamplesPerEpoch == 0u;
    ++n_;
    return &ev_;
  }

 private:
  static constexpr std::uint32_t kSamplesPerEpoch = 1000;  // 1 kHz IMU, 1 Hz receiver
  fsw::InputEvent ev_{};
  int sat_ = 0;
  std::uint32_t n_ = 0;
  bool epoch_due_ = false;
};
SyntheticSensors g_sensors;

}  // namespace

// Results where a debugger (or a telemetry task) can read them.
extern "C" {
volatile std::uint32_t g_sdins_ekf_updates = 0;
volatile std::uint32_t g_sdins_fsw_errors = 0;
volatile std::uint32_t g_sdins_initialised = 0;
volatile double g_sdins_lat_rad = 0.0;
}

namespace {

/// Both paper models fed each event (the target of the one driver loop), the results published
/// after it.
struct BothModels {
  template <class Observer>
  fsw::Status step(const fsw::InputEvent& ev, Observer&) {
    fsw::NoObserver none;
    const fsw::Status s24 = g_drv24.step(ev, none);
    const fsw::Status s15 = g_drv15.step(ev, none);
    if (s24 != fsw::Status::kOk || s15 != fsw::Status::kOk) g_sdins_fsw_errors = g_sdins_fsw_errors + 1u;
    g_sdins_initialised = (g_drv24.app().initialised() ? 1u : 0u) + (g_drv15.app().initialised() ? 1u : 0u);
    g_sdins_ekf_updates = g_drv24.app().executive().health().ekf_updates + g_drv15.app().executive().health().ekf_updates;
    if (ev.kind == fsw::InputEvent::Kind::kImu && g_drv24.frame().nav_valid) g_sdins_lat_rad = g_drv24.frame().nav.llh.x();
    return s24;
  }
};

}  // namespace

int main() {
  const fsw::FlightAppConfig cfg = sdins_baremetal::flight_config();
  if (g_drv24.init(cfg) != fsw::Status::kOk || g_drv15.init(cfg) != fsw::Status::kOk) {
    g_sdins_fsw_errors = g_sdins_fsw_errors + 1u;
    for (;;) {
    }
  }
  BothModels both;
  fsw::drive(g_sensors, both);  // the sensors never end
  for (;;) {
  }
}
