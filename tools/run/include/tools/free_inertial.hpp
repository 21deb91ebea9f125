// Wires the truth simulator to the fsw mechanization for free-inertial (unaided) runs: the common
// loop behind the perfect-IMU tests, the profile cross-check and the section-II analyses.
#pragma once

#include <functional>
#include <span>

#include "fsw/executive.hpp"
#include "fsw/strapdown.hpp"
#include "sim/imu_model.hpp"
#include "sim/trajectory.hpp"
#include "sim/truth.hpp"

namespace tools {

// The navigation error against truth: one definition, sim/truth.hpp.
using sim::NavErrors;
using sim::nav_errors;

struct FreeInertialConfig {
  double duration_s = 1800.0;
  double imu_rate_hz = 1000.0;
  double nav_rate_hz = fsw::kNavRate_hz;  ///< the 200 Hz rate group (`sdins fly`: config/default.toml's)
  /// Initial attitude error phi applied to the truth attitude at t = 0 (e.g. from alignment).
  fsw::Vec3 initial_phi_enu_rad = fsw::Vec3::Zero();
  /// Reset height and vertical velocity to truth after every frame (an ideal altimeter): the
  /// unaided vertical channel diverges and would otherwise pollute long analyses.
  bool hold_vertical_to_truth = false;
  /// Integrate the truth's ODE on a thread of its own (sim::TruthPipeline), its samples evaluated
  /// beside the flights (the same samples: the results are identical): for a single flight, whose
  /// time is mostly its truth (`sdins fly`); flights already run side by side on every core leave
  /// it off.
  bool truth_thread = false;
};

/// Called after every navigation frame with the truth at the same instant and the solution.
using FreeInertialCallback = std::function<void(const sim::TruthSample&, const fsw::NavState&)>;

/// Flies the motion with the given IMU model (nullptr: perfect IMU), initialised from truth.
/// Returns the last errors. A failing fsw step is reported through `status`; nothing throws but
/// the truth's thread (with truth_thread: std::system_error when it cannot start).
NavErrors run_free_inertial(const sim::Motion& motion, sim::ImuModel* imu, const FreeInertialConfig& cfg,
                            const FreeInertialCallback& on_frame, fsw::Status* status = nullptr);

/// One of several flights through one truth: its IMU model (nullptr: perfect), its callback, and
/// what the flight returns (the status of its first failing step, else kOk; the last errors).
struct FreeInertialFlight {
  sim::ImuModel* imu = nullptr;
  FreeInertialCallback on_frame;
  fsw::Status status = fsw::Status::kOk;
  NavErrors last{};
};

/// Several flights of the same motion and configuration through one truth generator, sample by
/// sample: each flight's result is the one run_free_inertial gives it alone (its own IMU model,
/// mechanization and callback; a failing flight stops, the others go on), and the truth, most of
/// a free-inertial flight's time, is integrated once (the paper's analysis: six misalignments of
/// one bank-to-turn flight).
void run_free_inertial(const sim::Motion& motion, const FreeInertialConfig& cfg, std::span<FreeInertialFlight> flights);

}  // namespace tools
