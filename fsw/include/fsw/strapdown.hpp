// Strapdown inertial mechanization in the ENU navigation frame (200 Hz task).
//
// The IMU delivers incremental angles and velocities (delta-theta, delta-v) per sample; the
// FrameBuilder accumulates the samples of one navigation frame (5 ms) and computes, at the sample
// rate, the coning and sculling compensation (Savage's recursive high-rate algorithms, exact for
// the two-sample case and better with more samples). Strapdown::step then performs the
// velocity, position and quaternion attitude updates including Earth and transport rate,
// Coriolis and normal gravity, with midpoint quantities extrapolated from the last two frames.
// Fixed-size, allocation-free, deterministic.
#pragma once

#include <cstdint>

#include "fsw/frames.hpp"
#include "fsw/status.hpp"

namespace fsw {

/// One IMU output sample: increments over (t_s - dt_s, t_s], body frame.
struct ImuSample {
  double t_s = 0.0;
  double dt_s = 0.0;
  Vec3 dtheta_rad = Vec3::Zero();
  Vec3 dv_mps = Vec3::Zero();
};

/// The compensated increments of one navigation frame, ready for the mechanization.
struct FrameIncrement {
  double t_s = 0.0;                    ///< time at the end of the frame
  double dt_s = 0.0;                   ///< frame length
  Vec3 rotvec_rad = Vec3::Zero();      ///< body rotation vector b(k-1)->b(k): alpha + coning
  Vec3 dv_sf_b_mps = Vec3::Zero();     ///< specific-force velocity increment in b(k-1): nu + rotation + sculling
  Vec3 dtheta_sum_rad = Vec3::Zero();  ///< plain sum of the sample delta-thetas (alpha)
  Vec3 dv_sum_mps = Vec3::Zero();      ///< plain sum of the sample delta-vs (nu)
};

/// Accumulates IMU samples into navigation frames with coning and sculling compensation.
class FrameBuilder {
 public:
  static constexpr int kMaxSamplesPerFrame = 32;

  /// samples_per_frame in [1, kMaxSamplesPerFrame].
  Status configure(int samples_per_frame);
  /// Adds one sample. Returns kOk when this sample completed a frame (then call take()),
  /// kFrameIncomplete when more samples are needed, kBadInput for NaN/Inf or dt <= 0.
  Status add(const ImuSample& s);
  /// The frame completed by the last add() that returned kOk.
  const FrameIncrement& frame() const { return frame_; }
  /// Forget the partial frame and the previous-sample memory (e.g. after a data gap).
  void reset();
  int samples_per_frame() const { return n_per_frame_; }
  /// Accepted samples still needed to complete the current frame (1..samples_per_frame): the one
  /// grouping of the IMU samples into minor frames; the flight application batches by it.
  int samples_to_frame_end() const { return n_per_frame_ - n_in_frame_; }

 private:
  int n_per_frame_ = 1;
  int n_in_frame_ = 0;
  bool have_prev_sample_ = false;
  Vec3 prev_dtheta_ = Vec3::Zero();
  Vec3 prev_dv_ = Vec3::Zero();
  Vec3 alpha_ = Vec3::Zero();
  Vec3 nu_ = Vec3::Zero();
  Vec3 beta_ = Vec3::Zero();
  Vec3 scul_ = Vec3::Zero();
  double dt_acc_ = 0.0;
  FrameIncrement frame_{};
};

/// Navigation solution carried by the mechanization.
struct NavState {
  double t_s = 0.0;
  Vec3 llh = Vec3::Zero();          ///< lat [rad], lon [rad], h [m]
  Vec3 vel_enu_mps = Vec3::Zero();  ///< ENU velocity
  Quat q_b_n = Quat::Identity();    ///< attitude, represents C_b_n
  Mat3 C_b_n() const { return q_b_n.toRotationMatrix(); }
};

class Strapdown {
 public:
  Status init(const NavState& s);
  /// Integrates one frame. Returns kBadInput (state untouched) for non-finite input.
  Status step(const FrameIncrement& inc);
  /// Closed-loop correction: subtract the estimated errors (position ENU metres, velocity,
  /// attitude error phi as defined in frames.hpp) from the solution.
  Status correct(const Vec3& dpos_enu_m, const Vec3& dvel_enu_mps, const Vec3& phi_enu_rad);
  const NavState& state() const { return cur_; }
  bool initialised() const { return initialised_; }
  /// Specific force in n of the last frame (average over the frame) [m/s^2].
  const Vec3& f_enu_mps2() const { return f_enu_mps2_; }
  /// Body angular rate of the last frame (average over the frame) [rad/s].
  const Vec3& omega_ib_b_radps() const { return omega_ib_b_radps_; }

 private:
  bool initialised_ = false;
  bool have_prev_ = false;
  NavState cur_{};
  NavState prev_{};
  Vec3 f_enu_mps2_ = Vec3::Zero();
  Vec3 omega_ib_b_radps_ = Vec3::Zero();
};

}  // namespace fsw
