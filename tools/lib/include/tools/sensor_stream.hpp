// The simulated sensors as the flight software receives them (fsw::InputEvent), in arrival order: the almanac
// first (as a receiver delivers it at power-up), then 1 kHz IMU samples and, after the IMU sample
// of each GPS epoch time, the receiver's raw epoch. SIL (`sdins sil`), the bus simulator
// (`sdins bus-sim`) and `sdins sim --log` all fly a scenario through this one stream, so they see
// the same data for the same scenario and seed.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "fsw/gps_orbit.hpp"
#include "fsw/input_event.hpp"
#include "fsw/strapdown.hpp"
#include "sim/gps_model.hpp"
#include "sim/imu_model.hpp"
#include "sim/scenario.hpp"
#include "sim/trajectory.hpp"

namespace tools {

/// One GPS interval of the stream: the IMU samples of (t - 1/gps_rate, t] and the epoch at t
/// (has_epoch false only for a short last step). The almanac is not part of a step: almanac().
struct SensorStep {
  std::vector<fsw::ImuSample> imu;
  bool has_epoch = false;
  fsw::GnssRawEpoch epoch{};
};

class SensorStream {
 public:
  /// The scenario's own seed.
  explicit SensorStream(const sim::Scenario& sc) : SensorStream(sc, sc.seed) {}
  /// Throws std::runtime_error for a scenario the simulator rejects or an unreadable almanac.
  /// seed: the run's seed (IMU errors, noise, GPS errors, clock).
  SensorStream(const sim::Scenario& sc, std::uint64_t seed);

  /// The next event; false at the end of the scenario (duration reached). `truth` (optional)
  /// receives the truth sample of an IMU event's time.
  bool next(fsw::InputEvent& ev, sim::TruthSample* truth = nullptr);
  /// The next GPS interval (one stream is read either by event or by step, not both); false at
  /// the end. The almanac events are skipped: take them from almanac().
  bool next(SensorStep& step);

  const std::vector<fsw::GpsAlmanac>& almanac() const { return almanac_; }
  int samples_per_epoch() const { return samples_per_epoch_; }
  /// IMU samples of the whole scenario (duration x IMU rate).
  long long total_samples() const { return n_samples_; }

  const sim::ImuErrors& imu_errors() const { return imu_->errors(); }
  const sim::Scenario& scenario() const { return sc_; }
  /// Truth of the last IMU event.
  const sim::TruthSample& truth() const { return gen_->current(); }

 private:
  sim::Scenario sc_;
  std::unique_ptr<sim::FlightMotion> motion_;
  std::unique_ptr<sim::TruthGenerator> gen_;
  std::unique_ptr<sim::ImuModel> imu_;
  std::unique_ptr<sim::GpsModel> gps_;
  std::vector<sim::AlmanacEntry> almanac_;
  std::size_t almanac_sent_ = 0;
  long long sample_ = 0;          ///< IMU samples emitted
  long long n_samples_ = 0;       ///< in the scenario
  int samples_per_epoch_ = 1;
  bool epoch_due_ = false;        ///< the last IMU sample was at an epoch time
};

}  // namespace tools
