#include "tools/step_producer.hpp"

#include <exception>
#include <utility>

namespace tools {

StepProducer::StepProducer(sim::SensorStream& stream, const std::atomic<bool>* stop) : stream_(stream), stop_(stop) {
  th_ = std::thread([this] { produce(); });
}

StepProducer::~StepProducer() {
  {
    std::lock_guard<std::mutex> lk(mu_);
    quit_ = true;
  }
  cv_.notify_all();
  th_.join();
}

bool StepProducer::next(EncodedStep& out) {
  std::unique_lock<std::mutex> lk(mu_);
  cv_.wait(lk, [this] { return !q_.empty() || done_; });
  if (q_.empty()) return false;
  if (out.frames.capacity() > 0) spare_.push_back(std::move(out.frames));
  out = std::move(q_.front());
  q_.pop_front();
  cv_.notify_all();
  return true;
}

std::string StepProducer::error() {
  std::lock_guard<std::mutex> lk(mu_);
  return error_;
}

void StepProducer::produce() {
  try {
    hal::can::CanStepEncoder enc;
    sim::SensorStep step;
    bool first = true;
    while (stream_.next(step)) {
      EncodedStep e;
      {
        std::lock_guard<std::mutex> lk(mu_);
        if (!spare_.empty()) {
          e.frames = std::move(spare_.back());
          spare_.pop_back();
        }
      }
      e.n_alm = first ? static_cast<int>(stream_.almanac().size()) : 0;
      e.has_epoch = step.has_epoch;
      e.frames.resize(static_cast<std::size_t>(
          hal::can::CanStepEncoder::max_frames(static_cast<int>(step.imu.size()), e.n_alm)));
      e.r = enc.encode(step.imu.data(), static_cast<int>(step.imu.size()), step.has_epoch ? &step.epoch : nullptr,
                       stream_.almanac().data(), e.n_alm, e.frames.data());
      e.frames.resize(static_cast<std::size_t>(e.r.n_frames));
      e.truth_t_s = stream_.truth().t_s;
      if (const sim::TruthSample* t = stream_.full_truth()) {
        e.has_full_truth = true;
        e.full_truth = *t;
      }
      first = false;
      std::unique_lock<std::mutex> lk(mu_);
      cv_.wait(lk, [this] { return q_.size() < kAhead || quit_; });
      if (quit_ || (stop_ && stop_->load())) break;
      q_.push_back(std::move(e));
      cv_.notify_all();
    }
  } catch (const std::exception& ex) {
    std::lock_guard<std::mutex> lk(mu_);
    error_ = ex.what();
  }
  std::lock_guard<std::mutex> lk(mu_);
  done_ = true;
  cv_.notify_all();
}

}  // namespace tools
