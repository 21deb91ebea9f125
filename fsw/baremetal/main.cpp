// Bare-metal entry of the fsw image (docs/baremetal.md): the rate-group executive with the
// paper's 24-state and 15-state filters, statically allocated, fed a stationary IMU (gravity and
// Earth rate at the initial position) and a 1 Hz GNSS epoch of six satellites whose pseudoranges
// and rates come from fsw::gnss_geometry at that position. One tick per 5 ms minor frame; a real
// target takes the IMU samples and the epoch from the HAL and waits for its frame timer instead.
// The loop keeps every fsw path in the image (mechanization, EKF propagate/update/feedback): the
// link proves the core needs nothing from a hosted environment.
#include <cstdint>

#include "fsw/executive.hpp"
#include "fsw/frames.hpp"
#include "fsw/gnss.hpp"

namespace {

constexpr int kSamplesPerFrame = 5;  // 1 kHz IMU, 200 Hz frames
constexpr double kImuDt_s = 0.001;
constexpr int kSatellites = 6;

fsw::Executive<fsw::Layout24> g_exec24;
fsw::Executive<fsw::Layout15> g_exec15;
fsw::FrameOutput g_out24, g_out15;
fsw::ImuSample g_imu[kSamplesPerFrame];
fsw::GnssEpoch g_epoch;

}  // namespace

// Results where a debugger (or a telemetry task) can read them.
extern "C" {
volatile std::uint32_t g_sdins_ekf_updates = 0;
volatile std::uint32_t g_sdins_fsw_errors = 0;
volatile double g_sdins_lat_rad = 0.0;
}

namespace {

fsw::NavState initial_state() {
  fsw::NavState s;
  s.llh = fsw::Vec3(35.0 * fsw::kDegToRad, 127.0 * fsw::kDegToRad, 100.0);
  s.q_b_n = fsw::Quat::Identity();
  return s;
}

/// Six satellites 20,000 km above the receiver in fixed directions (elevation 20 ... 80 deg).
void make_epoch(const fsw::NavState& at, double t_s, fsw::GnssEpoch& e) {
  const fsw::Vec3 r = fsw::ecef_from_llh(at.llh);
  const fsw::Mat3 Cne = fsw::C_n_e(at.llh.x(), at.llh.y());
  e.t_s = t_s;
  e.n_obs = kSatellites;
  for (int k = 0; k < kSatellites; ++k) {
    const double az = (30.0 + 60.0 * k) * fsw::kDegToRad;
    const double el = (20.0 + 12.0 * k) * fsw::kDegToRad;
    const fsw::Vec3 u = Cne * fsw::Vec3(std::cos(el) * std::sin(az), std::cos(el) * std::cos(az), std::sin(el));
    fsw::GnssObservation& o = e.obs[static_cast<std::size_t>(k)];
    o.prn = static_cast<std::uint8_t>(k + 1);
    o.sat_pos_ecef_m = r + 2.0e7 * u;
    o.sat_vel_ecef_mps = fsw::Vec3::Zero();
    const fsw::GnssGeometry g = fsw::gnss_geometry(o.sat_pos_ecef_m, o.sat_vel_ecef_mps, r, fsw::Vec3::Zero());
    o.pseudorange_m = g.range_m;
    o.pseudorange_rate_mps = g.range_rate_mps;
    o.elevation_rad = el;
  }
}

}  // namespace

int main() {
  const fsw::NavState init = initial_state();
  const fsw::ExecutiveConfig cfg{};
  if (g_exec24.init(cfg, init) != fsw::Status::kOk || g_exec15.init(cfg, init) != fsw::Status::kOk) {
    g_sdins_fsw_errors = g_sdins_fsw_errors + 1u;
    for (;;) {
    }
  }
  // Stationary, level, body axes along ENU: the specific force is gravity up, the rate Earth's.
  const double lat = init.llh.x();
  const fsw::Vec3 f_b(0.0, 0.0, fsw::normal_gravity_mps2(lat, init.llh.z()));
  const fsw::Vec3 w_b = fsw::omega_ie_n(lat);
  for (std::uint32_t frame = 0;; ++frame) {
    for (int k = 0; k < kSamplesPerFrame; ++k) {
      fsw::ImuSample& s = g_imu[k];
      s.t_s = (static_cast<double>(frame) * kSamplesPerFrame + k + 1) * kImuDt_s;
      s.dt_s = kImuDt_s;
      s.dtheta_rad = w_b * kImuDt_s;
      s.dv_mps = f_b * kImuDt_s;
    }
    const bool epoch = (frame + 1) % 200u == 0u;
    if (epoch) make_epoch(init, g_imu[kSamplesPerFrame - 1].t_s, g_epoch);
    fsw::FrameInput in;
    in.imu = g_imu;
    in.n_imu = kSamplesPerFrame;
    in.gnss = epoch ? &g_epoch : nullptr;
    if (g_exec24.tick(in, g_out24) != fsw::Status::kOk || g_exec15.tick(in, g_out15) != fsw::Status::kOk)
      g_sdins_fsw_errors = g_sdins_fsw_errors + 1u;
    g_sdins_ekf_updates = g_exec24.health().ekf_updates + g_exec15.health().ekf_updates;
    g_sdins_lat_rad = g_out24.nav.llh.x();
  }
}
