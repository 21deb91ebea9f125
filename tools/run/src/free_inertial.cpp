#include "tools/free_inertial.hpp"

#include <cmath>
#include <vector>

#include "sim/truth_pipeline.hpp"

namespace tools {

void run_free_inertial(const sim::Motion& motion, const FreeInertialConfig& cfg, std::span<FreeInertialFlight> flights) {
  const long long n_samples = std::llround(cfg.duration_s * cfg.imu_rate_hz);
  // With truth_thread the truth's integration runs on a thread of its own (the same samples).
  sim::TruthPipeline source(motion, cfg.imu_rate_hz, n_samples,
                            cfg.truth_thread ? sim::TruthThread::kOwn : sim::TruthThread::kReader);
  const int per_frame = static_cast<int>(std::lround(cfg.imu_rate_hz / cfg.nav_rate_hz));
  struct Nav {  // each flight's own mechanization
    fsw::FrameBuilder fb;
    fsw::Strapdown sd;
  };
  std::vector<Nav> nav(flights.size());
  const sim::TruthSample& t0 = source.current();
  fsw::NavState init;
  init.t_s = 0.0;
  init.llh = t0.llh;
  init.vel_enu_mps = t0.vel_enu_mps;
  // C_hat = (I - [phi x]) C_true, exactly: rotate the truth by -phi in n.
  init.q_b_n = fsw::quat_from_rotvec(-cfg.initial_phi_enu_rad) * fsw::Quat(t0.C_b_n);
  std::size_t flying = 0;
  for (std::size_t f = 0; f < flights.size(); ++f) {
    FreeInertialFlight& fl = flights[f];
    fl.status = nav[f].fb.configure(per_frame);
    if (fl.status == fsw::Status::kOk) fl.status = nav[f].sd.init(init);
    fl.last = nav_errors(nav[f].sd.state(), t0);
    if (fl.status == fsw::Status::kOk) ++flying;
  }
  const auto fly_sample = [&](const sim::TruthSample& truth) {
    for (std::size_t f = 0; f < flights.size(); ++f) {
      FreeInertialFlight& fl = flights[f];
      if (fl.status != fsw::Status::kOk) continue;
      fsw::Status& st = fl.status;
      fsw::FrameBuilder& fb = nav[f].fb;
      fsw::Strapdown& sd = nav[f].sd;
      fsw::ImuSample s;
      if (fl.imu != nullptr) {
        s = fl.imu->measure(truth);
      } else {
        s.t_s = truth.t_s;
        s.dt_s = truth.dt_s;
        s.dtheta_rad = truth.dtheta_rad;
        s.dv_mps = truth.dv_mps;
      }
      const fsw::Status fs = fb.add(s);
      if (fs == fsw::Status::kFrameIncomplete) continue;
      st = fs == fsw::Status::kOk ? sd.step(fb.frame()) : fs;
      if (st == fsw::Status::kOk && cfg.hold_vertical_to_truth) {
        const double dh = sd.state().llh.z() - truth.llh.z();
        const double dvu = sd.state().vel_enu_mps.z() - truth.vel_enu_mps.z();
        st = sd.correct(fsw::Vec3(0.0, 0.0, dh), fsw::Vec3(0.0, 0.0, dvu), fsw::Vec3::Zero());
      }
      if (st != fsw::Status::kOk) {
        --flying;
        continue;
      }
      fl.last = nav_errors(sd.state(), truth);
      if (fl.on_frame) fl.on_frame(truth, sd.state());
    }
  };
  for (long long i = 0; i < n_samples && flying > 0; ++i) fly_sample(source.next());
}

NavErrors run_free_inertial(const sim::Motion& motion, sim::ImuModel* imu, const FreeInertialConfig& cfg,
                            const FreeInertialCallback& on_frame, fsw::Status* status) {
  FreeInertialFlight flight{imu, on_frame};
  run_free_inertial(motion, cfg, std::span<FreeInertialFlight>(&flight, 1));
  if (status != nullptr) *status = flight.status;
  return flight.last;
}

}  // namespace tools
