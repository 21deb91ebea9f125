#include "sim/truth_pipeline.hpp"

namespace sim {

TruthPipeline::TruthPipeline(const Motion& motion, double rate_hz, long long n_samples, TruthThread where)
    : gen_(motion, rate_hz),
      n_(n_samples),
      split_(where == TruthThread::kOwn),
      ring_(split_ ? static_cast<std::size_t>(kRing) : 0) {}

TruthPipeline::~TruthPipeline() {
  if (!thread_.joinable()) return;
  {
    const std::lock_guard<std::mutex> lk(mu_);
    quit_.store(true);
  }
  cv_.notify_all();
  thread_.join();
}

template <class Pred>
void TruthPipeline::wait_until(std::atomic<bool>& waiting, Pred pred) {
  std::unique_lock<std::mutex> lk(mu_);
  waiting.store(true);  // seq_cst with the other side's store and load in wake(): no lost wake-up
  cv_.wait(lk, pred);
  waiting.store(false);
}

void TruthPipeline::wake(const std::atomic<bool>& waiting) {
  if (!waiting.load()) return;
  { const std::lock_guard<std::mutex> lk(mu_); }  // the waiter is inside wait() or has not checked yet
  cv_.notify_all();
}

void TruthPipeline::integrate_all() {
  for (long long k = 0; k < n_; ++k) {
    if (k >= consumed_.load(std::memory_order_acquire) + kRing) {
      wait_until(producer_waits_, [&] { return quit_.load() || k < consumed_.load() + kRing; });
      if (quit_.load()) return;
    }
    gen_.integrate(ring_[static_cast<std::size_t>(k % kRing)]);
    if ((k + 1) % kBatch == 0 || k + 1 == n_) {
      produced_.store(k + 1);
      wake(reader_waits_);
      if (quit_.load(std::memory_order_relaxed)) return;
    }
  }
}

const TruthSample& TruthPipeline::next() {
  if (!split_) return gen_.next();
  if (taken_ >= n_) {
    // Past the samples asked for: the integration has ended; go on without it.
    if (thread_.joinable()) thread_.join();
    ++taken_;
    return gen_.next();
  }
  if (taken_ == 0) thread_ = std::thread([this] { integrate_all(); });
  if (taken_ >= known_produced_) {
    known_produced_ = produced_.load(std::memory_order_acquire);
    if (taken_ >= known_produced_) {
      wait_until(reader_waits_, [&] { return produced_.load() > taken_; });
      known_produced_ = produced_.load(std::memory_order_acquire);
    }
  }
  const TruthSample& s = gen_.complete(ring_[static_cast<std::size_t>(taken_ % kRing)]);
  ++taken_;
  if (taken_ % kBatch == 0) {
    consumed_.store(taken_);
    wake(producer_waits_);
  }
  return s;
}

}  // namespace sim
