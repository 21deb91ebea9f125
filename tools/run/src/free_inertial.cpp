#include "tools/free_inertial.hpp"

#include <cmath>

namespace tools {

NavErrors run_free_inertial(const sim::Motion& motion, sim::ImuModel* imu, const FreeInertialConfig& cfg,
                            const FreeInertialCallback& on_frame, fsw::Status* status) {
  sim::TruthGenerator gen(motion, cfg.imu_rate_hz);
  const int per_frame = static_cast<int>(std::lround(cfg.imu_rate_hz / cfg.nav_rate_hz));
  fsw::FrameBuilder fb;
  fsw::Strapdown sd;
  fsw::Status st = fb.configure(per_frame);
  const sim::TruthSample& t0 = gen.current();
  fsw::NavState init;
  init.t_s = 0.0;
  init.llh = t0.llh;
  init.vel_enu_mps = t0.vel_enu_mps;
  // C_hat = (I - [phi x]) C_true, exactly: rotate the truth by -phi in n.
  init.q_b_n = fsw::quat_from_rotvec(-cfg.initial_phi_enu_rad) * fsw::Quat(t0.C_b_n);
  if (st == fsw::Status::kOk) st = sd.init(init);
  NavErrors last = nav_errors(sd.state(), t0);
  const long long n_samples = std::llround(cfg.duration_s * cfg.imu_rate_hz);
  for (long long i = 0; i < n_samples && st == fsw::Status::kOk; ++i) {
    const sim::TruthSample& truth = gen.next();
    fsw::ImuSample s;
    if (imu != nullptr) {
      s = imu->measure(truth);
    } else {
      s.t_s = truth.t_s;
      s.dt_s = truth.dt_s;
      s.dtheta_rad = truth.dtheta_rad;
      s.dv_mps = truth.dv_mps;
    }
    const fsw::Status fs = fb.add(s);
    if (fs == fsw::Status::kFrameIncomplete) continue;
    if (fs != fsw::Status::kOk) {
      st = fs;
      break;
    }
    st = sd.step(fb.frame());
    if (st != fsw::Status::kOk) break;
    if (cfg.hold_vertical_to_truth) {
      const double dh = sd.state().llh.z() - truth.llh.z();
      const double dvu = sd.state().vel_enu_mps.z() - truth.vel_enu_mps.z();
      st = sd.correct(fsw::Vec3(0.0, 0.0, dh), fsw::Vec3(0.0, 0.0, dvu), fsw::Vec3::Zero());
      if (st != fsw::Status::kOk) break;
    }
    last = nav_errors(sd.state(), truth);
    if (on_frame) on_frame(truth, sd.state());
  }
  if (status != nullptr) *status = st;
  return last;
}

}  // namespace tools
