// A synthetic land vehicle (or walker) for the flight-application tests: flat ground, speed and
// track are sums of smooth (C2) steps, the vehicle frame has x along the track and no roll or
// pitch, and the IMU is mounted at (roll, pitch, yaw) relative to it. ODE state y = (lat, lon, h).
#pragma once

#include <cmath>
#include <utility>
#include <vector>

#include "fsw/frames.hpp"
#include "sim/trajectory.hpp"

namespace land_motion {

class LandMotion final : public sim::Motion {
 public:
  struct Step {
    double t0_s, length_s, delta;
  };
  LandMotion(const fsw::Vec3& llh0, double speed0_mps, double track0_rad, const fsw::Vec3& mount_rpy_rad,
             std::vector<Step> speed, std::vector<Step> track)
      : llh0_(llh0), v0_(speed0_mps), psi0_(track0_rad), speed_(std::move(speed)), track_(std::move(track)) {
    C_b_v_ = fsw::C_ned_enu() * fsw::C_b_n_from_euler(mount_rpy_rad.x(), mount_rpy_rad.y(), mount_rpy_rad.z());
  }
  State initial_state() const override {
    State y = State::Zero();
    y.head<3>() = llh0_;
    return y;
  }
  State derivative(double t_s, const State& y) const override {
    State d = State::Zero();
    double s, ds, psi, dpsi;
    profile(speed_, v0_, t_s, s, ds);
    profile(track_, psi0_, t_s, psi, dpsi);
    d.head<3>() = fsw::llh_rate(y.head<3>(), fsw::Vec3(s * std::sin(psi), s * std::cos(psi), 0.0));
    return d;
  }
  sim::Kinematics eval(double t_s, const State& y) const override {
    sim::Kinematics k;
    double s, ds, psi, dpsi;
    profile(speed_, v0_, t_s, s, ds);
    profile(track_, psi0_, t_s, psi, dpsi);
    k.llh = y.head<3>();
    k.vel_enu_mps = fsw::Vec3(s * std::sin(psi), s * std::cos(psi), 0.0);
    k.acc_enu_mps2 =
        fsw::Vec3(ds * std::sin(psi) + s * dpsi * std::cos(psi), ds * std::cos(psi) - s * dpsi * std::sin(psi), 0.0);
    k.C_b_n = fsw::C_b_n_from_euler(0.0, 0.0, psi) * C_b_v_;
    k.omega_nb_b_radps = C_b_v_.transpose() * fsw::Vec3(0.0, 0.0, dpsi);
    return k;
  }

 private:
  static void profile(const std::vector<Step>& steps, double v0, double t, double& v, double& rate) {
    v = v0;
    rate = 0.0;
    for (const Step& st : steps) {
      const double x = (t - st.t0_s) / st.length_s;
      v += st.delta * sim::smooth_step(x);
      rate += st.delta * sim::smooth_step_rate(x) / st.length_s;
    }
  }
  fsw::Vec3 llh0_;
  double v0_, psi0_;
  fsw::Mat3 C_b_v_;
  std::vector<Step> speed_, track_;
};

}  // namespace land_motion
