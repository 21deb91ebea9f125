#include "tools/step_producer.hpp"

namespace tools {

StepProducer::StepProducer(sim::SensorStream& stream, const std::atomic<bool>* stop)
    : ahead_(kAhead, [&stream, stop](const Ahead<EncodedStep>::Sink& sink) {
        hal::can::CanStepEncoder enc;
        sim::SensorStep step;
        bool first = true;
        while (stream.next(step)) {
          if (stop != nullptr && stop->load()) return;
          EncodedStep e;
          sink.spare(e);  // a frame buffer the reader is done with
          e.n_alm = first ? static_cast<int>(stream.almanac().size()) : 0;
          e.has_epoch = step.has_epoch;
          e.frames.resize(static_cast<std::size_t>(
              hal::can::CanStepEncoder::max_frames(static_cast<int>(step.imu.size()), e.n_alm)));
          e.r = enc.encode(step.imu.data(), static_cast<int>(step.imu.size()), step.has_epoch ? &step.epoch : nullptr,
                           stream.almanac().data(), e.n_alm, e.frames.data());
          e.frames.resize(static_cast<std::size_t>(e.r.n_frames));
          e.truth_t_s = stream.truth().t_s;
          e.has_full_truth = false;
          if (const sim::TruthSample* t = stream.full_truth()) {
            e.has_full_truth = true;
            e.full_truth = *t;
          }
          first = false;
          if (!sink.emit(std::move(e))) return;
        }
      }) {}

}  // namespace tools
