// Single-point GNSS solution (position, velocity, receiver clock) from one epoch's pseudoranges
// and rates: iterated least squares with the same geometry as the EKF (gnss_geometry: Sagnac,
// light-time factor). Used to initialise the navigation solution in motion, without a host.
#pragma once

#include "fsw/frames.hpp"
#include "fsw/gnss.hpp"
#include "fsw/status.hpp"

namespace fsw {

struct GnssPvt {
  Vec3 r_ecef_m = Vec3::Zero();
  Vec3 v_ecef_mps = Vec3::Zero();
  double clock_bias_m = 0.0;
  double clock_drift_mps = 0.0;
  int n_used = 0;
  double pdop = 0.0;
  double pr_rms_residual_m = 0.0;     ///< RMS pseudorange residual after the fit
  double prr_rms_residual_mps = 0.0;  ///< RMS rate residual after the fit
};

/// Needs at least 4 valid observations (kBadInput otherwise, or for a singular geometry, or when
/// the iteration does not converge within 10 steps: kNotConverged). No allocation.
Status gnss_pvt(const GnssEpoch& epoch, GnssPvt& out);

}  // namespace fsw
