// `sdins replay` scores itself against the log's reference (TRUTH channel) (docs/running.md,
// "Scoring a replay"): the navigation solution of every frame against the reference interpolated
// to the frame's time; the EKF's published 1-sigma at every EKF run for the NEES; with GNSS
// outages, each outage's error at its end and its drift curve (error vs time since it began).
//
// Errors are solution minus reference: position in ENU metres (fsw::enu_difference_m, the radii at
// the reference), horizontal = |(E, N)|, vertical = U; velocity ENU; attitude as differences of
// roll, pitch and heading (wrapped to +-180 deg). The reference is interpolated linearly (position,
// velocity) and by slerp (attitude) between its two samples around the frame's time when they are
// at most max_reference_gap_s apart; a frame without them is counted, not scored.
//
// NEES: (e / sigma)^2 summed over E, N, U of position and of velocity with the EKF's diagonal
// 1-sigma (EKF_STATE; the axes' correlations are left out), 3 for a consistent filter on average.
// Only as good as the reference's own error: the reference's sigma is in no denominator, so a
// reference whose error is comparable to the filter's (an autopilot's estimate, RTK float) makes
// a consistent filter look inconsistent. The caveat is printed with the figures.
#pragma once

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "fsw/strapdown.hpp"
#include "tools/reference.hpp"

namespace tools {

struct ScoreOptions {
  double from_s = 0.0;               ///< frames from initialisation + this are scored
  double max_reference_gap_s = 1.0;  ///< the reference's bracketing samples may be this far apart
  double curve_step_s = 0.5;         ///< drift-curve sampling
  double csv_step_s = 0.05;          ///< time-series (CSV) sampling: at most 20 rows per second
  /// GNSS outages as the replay withholds them: LENGTH every PERIOD from initialisation + FIRST
  /// (0 length: none).
  double outage_length_s = 0.0, outage_period_s = 0.0, outage_first_s = 0.0;
};

/// Root-mean-square and maximum of |x| over the samples.
struct RmsMax {
  std::uint64_t n = 0;
  double sum2 = 0.0, max = 0.0;
  void add(double x);
  double rms() const;
  nlohmann::json to_json(const char* unit) const;
};

class ReplayScorer {
 public:
  ReplayScorer(Reference ref, const ScoreOptions& opt);
  /// Every completed navigation frame; init_t_s: the flight software's initialisation time.
  void on_frame(const fsw::NavState& nav, double init_t_s);
  /// A frame in which the EKF ran: the solution and the EKF's position/velocity 1-sigma.
  void on_ekf(const fsw::NavState& nav, double init_t_s, const std::array<double, 6>& sigma);
  /// The score (JSON): errors, NEES, outages, the reference's label and the caveat.
  nlohmann::json result() const;
  /// The time series (csv_step_s): time, outage, errors.
  std::string csv() const;
  /// The printed summary of result().
  static std::string text(const nlohmann::json& score);
  const Reference& reference() const { return ref_; }

 private:
  struct Errors {
    bool pos = false, vel = false, att = false;
    fsw::Vec3 dpos = fsw::Vec3::Zero(), dvel = fsw::Vec3::Zero(), datt_deg = fsw::Vec3::Zero();
  };
  struct Window {
    int index = 0;
    double start_s = 0.0, end_s = 0.0;
    bool complete = false, has_end = false;
    double end_h_m = 0.0, end_v_m = 0.0, end_t_s = 0.0;   ///< last scored frame before the end
    double end_nees_h = -1.0, end_sigma_h_m = -1.0;       ///< last EKF run in the window (-1: none)
    double next_curve_s = 0.0;
    std::vector<std::array<double, 3>> curve;  ///< (time since start, horizontal, vertical)
  };
  struct Row {
    double t_s, since_init_s;
    int outage;
    double since_outage_s;
    Errors e;
  };
  bool errors_at(const fsw::NavState& nav, Errors& e) const;
  Window* window_at(double t_s, double init_t_s, double& since_start);

  Reference ref_;
  ScoreOptions opt_;
  std::uint64_t frames_ = 0, scored_ = 0, without_reference_ = 0, before_from_ = 0;
  double first_t_ = 0.0, last_t_ = 0.0, init_t_ = 0.0;
  RmsMax h_, v_, vel_, vel_h_, vel_v_, roll_, pitch_, heading_;
  std::uint64_t nees_n_ = 0, nees_pos_over_ = 0, nees_vel_over_ = 0;
  double nees_pos_sum_ = 0.0, nees_vel_sum_ = 0.0;
  std::vector<Window> windows_;
  std::vector<Row> rows_;
  double next_row_t_ = -1e300;
};

/// The caveat printed and written with every NEES against a reference.
inline constexpr const char* kReferenceNeesCaveat =
    "NEES against the reference is only as good as the reference's own sigma: the reference's error is in no "
    "denominator, so a reference whose error is comparable to the filter's 1-sigma (an autopilot's estimate, an RTK "
    "float or single solution) inflates it";

}  // namespace tools
