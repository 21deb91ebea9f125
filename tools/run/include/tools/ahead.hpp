// A producer on a thread of its own, a bounded number of items ahead of its one reader: what the
// SIL and bus-simulator sensor steps (step_producer.hpp) use to run the simulator beside the
// flight software (a free-inertial flight's truth has sim::TruthPipeline). The items reach the
// reader in the order produced, so the results do not depend on the thread.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace tools {

template <class T>
class Ahead {
 public:
  /// Hands one item to the reader; false when the reader has gone (the producer then returns).
  /// spare (optional): an item the reader gave back, to be filled again (no allocation), or left
  /// untouched when there is none.
  struct Sink {
    Ahead* q;
    bool emit(T&& item) const { return q->push(std::move(item)); }
    void spare(T& item) const { q->take_spare(item); }
  };

  /// Starts produce(sink) on its own thread, at most `ahead` items ahead of next(). An exception
  /// from produce ends the items; error() gives its message.
  Ahead(std::size_t ahead, std::function<void(const Sink&)> produce) : ahead_(ahead) {
    th_ = std::thread([this, produce = std::move(produce)] {
      try {
        produce(Sink{this});
      } catch (const std::exception& ex) {
        std::lock_guard<std::mutex> lk(mu_);
        error_ = ex.what();
      }
      std::lock_guard<std::mutex> lk(mu_);
      done_ = true;
      cv_.notify_all();
    });
  }
  ~Ahead() {
    {
      std::lock_guard<std::mutex> lk(mu_);
      quit_ = true;
    }
    cv_.notify_all();
    th_.join();
  }
  Ahead(const Ahead&) = delete;
  Ahead& operator=(const Ahead&) = delete;

  /// The next item into out (out's previous content goes back to the producer as a spare); false
  /// at the end (error() says whether the producer failed).
  bool next(T& out) {
    std::unique_lock<std::mutex> lk(mu_);
    cv_.wait(lk, [this] { return !q_.empty() || done_; });
    if (q_.empty()) return false;
    spare_.push_back(std::move(out));
    out = std::move(q_.front());
    q_.pop_front();
    cv_.notify_all();
    return true;
  }
  std::string error() {
    std::lock_guard<std::mutex> lk(mu_);
    return error_;
  }

 private:
  bool push(T&& item) {
    std::unique_lock<std::mutex> lk(mu_);
    cv_.wait(lk, [this] { return q_.size() < ahead_ || quit_; });
    if (quit_) return false;
    q_.push_back(std::move(item));
    cv_.notify_all();
    return true;
  }
  void take_spare(T& item) {
    std::lock_guard<std::mutex> lk(mu_);
    if (spare_.empty()) return;
    item = std::move(spare_.back());
    spare_.pop_back();
  }

  std::size_t ahead_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<T> q_;
  std::vector<T> spare_;
  bool done_ = false, quit_ = false;
  std::string error_;
  std::thread th_;  // last: started after every other member exists
};

}  // namespace tools
