// The simulated sensors encoded into CAN frames on a thread of their own, a few GPS intervals
// ahead of the reader: `sdins bus-sim` sends them over a bus, `sdins sil` feeds them in-process to
// the flight-software node. The frames are those the reader would have encoded itself (the same
// encoder, the same order), so the navigation digest does not depend on the thread.
#pragma once

#include <atomic>
#include <cstddef>
#include <string>
#include <vector>

#include "hal/can_frame.hpp"
#include "hal/can_protocol.hpp"
#include "sim/sensor_stream.hpp"
#include "tools/ahead.hpp"

namespace tools {

/// One GPS interval encoded into frames (IMU samples, epoch, almanac with the first step).
struct EncodedStep {
  std::vector<hal::CanFrame> frames;
  hal::can::CanStepEncoder::Result r{};
  bool has_epoch = false;
  int n_alm = 0;
  double truth_t_s = 0.0;           ///< the truth's time at the step's last IMU sample
  bool has_full_truth = false;      ///< SensorStream::full_truth() had one after the step
  sim::TruthSample full_truth{};    ///< that sample (for the log's truth records, the final error)
};

/// Flies the stream on its own thread, kAhead steps ahead of the reader (in real time: simulating
/// the next GPS interval never stalls the bus; in SIL: the sensor models and the encoding run
/// beside the flight software). The stream belongs to the producer until it is destroyed.
class StepProducer {
 public:
  /// stop (optional): the reader's request to stop; the producer ends at its next step.
  StepProducer(sim::SensorStream& stream, const std::atomic<bool>* stop);
  /// The next step; false at the end (error() says whether the stream failed). out's frame buffer
  /// goes back to the producer, so a reader that reuses one EncodedStep allocates nothing.
  bool next(EncodedStep& out) { return ahead_.next(out); }
  std::string error() { return ahead_.error(); }

 private:
  static constexpr std::size_t kAhead = 3;
  Ahead<EncodedStep> ahead_;
};

}  // namespace tools
