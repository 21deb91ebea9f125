// One Monte Carlo run's sensors on the shared truth track (tools/montecarlo.hpp): the run's IMU
// and GPS receiver models (errors drawn from seed = scenario seed + run index) turn the truth into
// the flight application's input events, IMU samples and raw receiver epochs. The one sensor side
// of the Monte Carlo, `sdins paper` and the timing audit: they differ only in what they do with
// the flight application's output.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "fsw/gps_orbit.hpp"
#include "sim/gps_model.hpp"
#include "sim/imu_model.hpp"
#include "tools/montecarlo.hpp"

namespace tools {

class RunSensors {
 public:
  RunSensors(const sim::Scenario& sc, const TruthTrack& truth, const std::vector<sim::AlmanacEntry>& almanac,
             std::uint64_t seed)
      : truth_(truth), errors_(sim::draw_imu_errors(sc.imu, sc.effects, seed)), imu_(errors_, seed),
        gps_(sc.gps, almanac, sc.effects, seed), spe_(static_cast<std::size_t>(truth.samples_per_epoch)) {}

  /// IMU sample j (0-based, truth.imu[j]). When a GNSS epoch falls at its time, also measures the
  /// epoch (epoch(), raw(): the receiver delivers it before this sample) and returns its truth;
  /// otherwise nullptr. Call for j = 0, 1, ... in order (the error processes advance with time).
  const sim::TruthSample* measure(std::size_t j, fsw::ImuSample& sample) {
    const TruthTrack::Increment& inc = truth_.imu[j];
    ts_.t_s = inc.t_s;
    ts_.dt_s = inc.dt_s;
    ts_.dtheta_rad = inc.dtheta_rad;
    ts_.dv_mps = inc.dv_mps;
    sample = imu_.measure(ts_);
    if ((j + 1) % spe_ != 0) return nullptr;
    const sim::TruthSample& te = truth_.epochs[(j + 1) / spe_];
    gps_.measure(te, epoch_);
    gps_.raw(epoch_, raw_);
    return &te;
  }
  const fsw::GnssEpoch& epoch() const { return epoch_; }   ///< the last epoch, satellite positions known
  const fsw::GnssRawEpoch& raw() const { return raw_; }    ///< the same as the receiver reports it
  const sim::ImuErrors& errors() const { return errors_; }
  const std::vector<sim::AlmanacEntry>& almanac() const { return gps_.almanac(); }

 private:
  const TruthTrack& truth_;
  sim::ImuErrors errors_;
  sim::ImuModel imu_;
  sim::GpsModel gps_;
  std::size_t spe_;
  sim::TruthSample ts_;  ///< carries the fields the IMU model reads
  fsw::GnssEpoch epoch_{};
  fsw::GnssRawEpoch raw_{};
};

}  // namespace tools
