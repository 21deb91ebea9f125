// Single-point GNSS solution (see fsw/gnss_pvt.hpp).
#include "fsw/gnss_pvt.hpp"

#include <Eigen/Cholesky>
#include <cmath>

namespace fsw {
namespace {

using Mat4 = Eigen::Matrix<double, 4, 4>;
using Vec4 = Eigen::Matrix<double, 4, 1>;
constexpr int kMaxIterations = 10;
constexpr double kConverged_m = 1e-4;

bool usable(const GnssObservation& o) {
  const double rs = o.sat_pos_ecef_m.norm();
  return o.sat_pos_ecef_m.allFinite() && o.sat_vel_ecef_mps.allFinite() && std::isfinite(o.pseudorange_m) &&
         std::isfinite(o.pseudorange_rate_mps) && rs > 1.0e7 && rs < 1.0e8;
}

}  // namespace

Status gnss_pvt(const GnssEpoch& epoch, GnssPvt& out) {
  out = GnssPvt{};
  if (epoch.n_obs < 4 || epoch.n_obs > kMaxGnssChannels) return Status::kBadInput;
  int n = 0;
  for (int k = 0; k < epoch.n_obs; ++k) n += usable(epoch.obs[static_cast<std::size_t>(k)]) ? 1 : 0;
  if (n < 4) return Status::kBadInput;

  // Position and clock bias: Gauss-Newton from the Earth's centre (converges for GNSS geometry).
  Vec3 r = Vec3::Zero();
  double b = 0.0;
  bool converged = false;
  Mat4 HtH = Mat4::Zero();
  for (int it = 0; it < kMaxIterations && !converged; ++it) {
    HtH.setZero();
    Vec4 Hty = Vec4::Zero();
    for (int k = 0; k < epoch.n_obs; ++k) {
      const GnssObservation& o = epoch.obs[static_cast<std::size_t>(k)];
      if (!usable(o)) continue;
      const GnssGeometry g = gnss_geometry(o.sat_pos_ecef_m, o.sat_vel_ecef_mps, r, Vec3::Zero());
      Vec4 h;
      h << -g.los_ecef, 1.0;
      const double y = o.pseudorange_m - (g.range_m + b);
      HtH.noalias() += h * h.transpose();
      Hty += h * y;
    }
    const Eigen::LDLT<Mat4> ldlt(HtH);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 1e-9).all()) return Status::kBadInput;
    const Vec4 dx = ldlt.solve(Hty);
    if (!dx.allFinite()) return Status::kBadInput;
    r += dx.head<3>();
    b += dx(3);
    converged = dx.head<3>().norm() < kConverged_m;
  }
  if (!converged) return Status::kNotConverged;
  out.pdop = std::sqrt(HtH.inverse().topLeftCorner<3, 3>().trace());

  // Velocity and clock drift: linear in (v, d) given the position; two passes for the
  // light-time factor.
  Vec3 v = Vec3::Zero();
  double d = 0.0;
  for (int it = 0; it < 3; ++it) {
    Mat4 A = Mat4::Zero();
    Vec4 z = Vec4::Zero();
    for (int k = 0; k < epoch.n_obs; ++k) {
      const GnssObservation& o = epoch.obs[static_cast<std::size_t>(k)];
      if (!usable(o)) continue;
      const GnssGeometry g = gnss_geometry(o.sat_pos_ecef_m, o.sat_vel_ecef_mps, r, v);
      Vec4 h;
      h << -g.los_ecef, 1.0;
      const double y = o.pseudorange_rate_mps - (g.range_rate_mps + d);
      A.noalias() += h * h.transpose();
      z += h * y;
    }
    const Vec4 dx = A.ldlt().solve(z);
    if (!dx.allFinite()) return Status::kBadInput;
    v += dx.head<3>();
    d += dx(3);
  }

  double s_pr = 0.0, s_prr = 0.0;
  for (int k = 0; k < epoch.n_obs; ++k) {
    const GnssObservation& o = epoch.obs[static_cast<std::size_t>(k)];
    if (!usable(o)) continue;
    const GnssGeometry g = gnss_geometry(o.sat_pos_ecef_m, o.sat_vel_ecef_mps, r, v);
    const double e1 = o.pseudorange_m - (g.range_m + b), e2 = o.pseudorange_rate_mps - (g.range_rate_mps + d);
    s_pr += e1 * e1;
    s_prr += e2 * e2;
  }
  out.r_ecef_m = r;
  out.v_ecef_mps = v;
  out.clock_bias_m = b;
  out.clock_drift_mps = d;
  out.n_used = n;
  out.pr_rms_residual_m = std::sqrt(s_pr / n);
  out.prr_rms_residual_mps = std::sqrt(s_prr / n);
  return Status::kOk;
}

}  // namespace fsw
