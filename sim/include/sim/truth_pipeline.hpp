// The truth generator over two threads: its integration (TruthGenerator::integrate, one RK4 step
// a sample, each step from the last: sequential) on a thread of its own, a bounded number of steps
// ahead of the evaluations (TruthGenerator::complete: the kinematics, rates, specific force and
// increments of each sample) on the reader's thread. The samples are TruthGenerator::next()'s bit
// for bit and in the same order, whatever the threads' timing; the two halves cost about the same,
// so a reader that only wants the truth gets it in about half the wall time (docs/performance.md,
// "The truth on two threads").
#pragma once

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

#include "sim/trajectory.hpp"

namespace sim {

/// Where the truth's integration runs: on the reader's thread (the generator's next(), no thread),
/// or on a thread of its own, for a reader that leaves the second core idle (`sdins fly`, `sdins
/// sim`, `sdins can encode`, TruthTrack::generate). A reader whose other threads keep the cores
/// busy (a Monte Carlo's runs, `sil`, `bus-sim`) keeps it: the split costs 0.07-0.24 cpu-s more for
/// 1800 s, and a third busy thread on two cores slows them all (docs/performance.md, "The truth on
/// two threads").
enum class TruthThread { kReader, kOwn };

class TruthPipeline {
 public:
  /// The motion (which must outlive the pipeline) at rate_hz for n_samples samples after t = 0.
  /// With TruthThread::kOwn the integration's thread starts at the first next().
  TruthPipeline(const Motion& motion, double rate_hz, long long n_samples, TruthThread where);
  /// Stops the integration wherever it is and joins its thread.
  ~TruthPipeline();
  TruthPipeline(const TruthPipeline&) = delete;
  TruthPipeline& operator=(const TruthPipeline&) = delete;

  /// The sample at t = 0 (no increments), then the last one next() returned.
  const TruthSample& current() const { return gen_.current(); }
  /// The next sample: at most n_samples of them (the caller counts, as with TruthGenerator).
  const TruthSample& next();

 private:
  /// Steps are handed over in batches of kBatch, through a ring of kRing: a side that finds nothing
  /// to do sleeps on the condition variable and is woken once a batch is ready for it (a wake-up
  /// costs tens of microseconds on a virtual machine, so a batch is about a millisecond of work).
  static constexpr long long kBatch = 2048;
  static constexpr long long kRing = 8 * kBatch;
  void integrate_all();
  /// Blocks until pred() (checked under the lock); `waiting` says so to the other side meanwhile.
  template <class Pred>
  void wait_until(std::atomic<bool>& waiting, Pred pred);
  /// Wakes the other side if it waits.
  void wake(const std::atomic<bool>& waiting);

  TruthGenerator gen_;
  long long n_;
  bool split_;
  std::vector<TruthGenerator::Step> ring_;  ///< step k in slot k % kRing
  alignas(64) std::atomic<long long> produced_{0};  ///< steps integrated and published
  alignas(64) std::atomic<long long> consumed_{0};  ///< steps completed; their slots are free
  alignas(64) std::atomic<bool> quit_{false};
  std::atomic<bool> producer_waits_{false}, reader_waits_{false};
  std::mutex mu_;
  std::condition_variable cv_;
  alignas(64) long long taken_ = 0;  ///< the reader's own count
  long long known_produced_ = 0;     ///< the reader's last look at produced_
  std::thread thread_;
};

}  // namespace sim
