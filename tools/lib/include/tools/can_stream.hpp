// The simulator's sensor outputs for the CAN bus: one scenario run as the IMU and the GPS receiver
// would put it on the bus (measured IMU samples from sim::ImuModel, raw receiver epochs from
// sim::GpsModel::raw, the almanac the receiver flies), stepped one GPS epoch interval at a time.
// Feed each step to hal::can::CanStepEncoder for frames; hal::CanRxAssembler turns them back.
#pragma once

#include <memory>
#include <vector>

#include "fsw/gps_orbit.hpp"
#include "fsw/strapdown.hpp"
#include "sim/scenario.hpp"

namespace tools {

struct SensorStep {
  std::vector<fsw::ImuSample> imu;  ///< the IMU samples of (t - 1/gps_rate, t]
  bool has_epoch = false;           ///< a GPS epoch at the step's end (false only for a short last step)
  fsw::GnssRawEpoch epoch{};
};

class SensorStream {
 public:
  /// Throws std::runtime_error for an invalid scenario or an unreadable almanac.
  explicit SensorStream(const sim::Scenario& sc);
  ~SensorStream();
  /// The next step; false after the scenario's duration.
  bool next(SensorStep& step);
  const std::vector<fsw::GpsAlmanac>& almanac() const;
  int samples_per_epoch() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> p_;
};

}  // namespace tools
