// Time-tag sanity that costs only the bad sample (docs/faults.md). One implementation, used by the
// replay reader (LcmReplayReader, every input of a log in log order) and by the importers (IMU
// ticks, solution and observation epochs).
//
// A stream of time tags normally advances by small steps: step = t - base within
// [-max_backward_s, max_forward_s] (base: the newest accepted tag). A tag outside that band is a
// jump. A single jump (a wild time tag) must not move the base, or everything after it would look
// out of order; so a jumping tag is held, not accepted:
//  - the next tag continues the old base: the held tags were outliers, rejected and counted;
//  - confirm_samples consecutive tags agree with each other (steps within the same band) but not
//    with the old base: a sustained jump, taken as a new time base (counted and reported with its
//    size); the held tags are accepted, nothing is lost.
// Until the first confirm_samples tags agree with each other there is no base (the first tag of a
// stream may be the wild one): they are held; once two or more of them agree, a tag that agrees
// with neither them is the outlier. At the end of the stream (finish()) tags still held
// are accepted if no base was ever established (a stream shorter than confirm_samples) and
// rejected as unconfirmed otherwise. A tag within the band but not after the base when
// strictly_increasing is set (a repeated or slightly earlier tick) is rejected on its own.
// Non-finite tags are rejected.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace hal {

struct TimeTagGateConfig {
  double max_forward_s = 2.0;    ///< a forward step above this is a jump
  double max_backward_s = 1.0;   ///< a backward step beyond this is a jump (within: reordering)
  bool strictly_increasing = false;  ///< a step <= 0 within the band is rejected (importers' ticks)
  int confirm_samples = 5;       ///< consecutive agreeing tags that make a jump a new time base
};

enum class TimeTagRejection : std::uint8_t {
  kNotIncreasing = 0,  ///< strictly_increasing and step <= 0 (within the band)
  kOutlier,            ///< a jump the stream did not confirm
  kUnconfirmed,        ///< held at the end of the stream after a base was established
  kNotFinite,
};
const char* to_string(TimeTagRejection r);

struct TimeTagGateStats {
  std::uint64_t accepted = 0;
  std::uint64_t not_increasing = 0;
  std::uint64_t outliers = 0;
  std::uint64_t unconfirmed = 0;
  std::uint64_t not_finite = 0;
  std::uint64_t new_bases = 0;   ///< sustained jumps taken as a new time base
  double last_new_base_jump_s = 0.0;  ///< size of the last one (new base - old base)
  double last_new_base_at_s = 0.0;    ///< first tag of the new base
  std::uint64_t rejected() const { return not_increasing + outliers + unconfirmed + not_finite; }
};

/// The decision logic (time tags only). TimeTagFilter<T> below holds the items.
class TimeTagGate {
 public:
  enum class Verdict : std::uint8_t { kAccept, kHold, kNewBase, kReject };
  TimeTagGate() = default;
  explicit TimeTagGate(const TimeTagGateConfig& cfg) : cfg_(cfg) {}
  /// One tag. Before acting on the verdict, the caller drops its first dropped() held items
  /// (rejected as outliers). kAccept: accept this tag. kHold: hold it. kNewBase: accept every held
  /// item, then this one. kReject: reject this one (reason()).
  Verdict feed(double t);
  /// End of the stream: true when the held items are accepted (no base established), false when
  /// they are rejected (unconfirmed).
  bool finish();
  int dropped() const { return dropped_; }
  int held() const { return held_; }
  TimeTagRejection reason() const { return reason_; }
  const TimeTagGateStats& stats() const { return stats_; }
  const TimeTagGateConfig& config() const { return cfg_; }
  bool have_base() const { return have_base_; }
  double base() const { return base_; }

 private:
  bool in_band(double step) const {
    return step >= -cfg_.max_backward_s && step <= cfg_.max_forward_s && (!cfg_.strictly_increasing || step > 0.0);
  }
  TimeTagGateConfig cfg_{};
  TimeTagGateStats stats_{};
  bool have_base_ = false;
  double base_ = 0.0;
  int held_ = 0;
  double cand_first_ = 0.0, cand_last_ = 0.0;
  int dropped_ = 0;
  TimeTagRejection reason_ = TimeTagRejection::kOutlier;
};

/// The gate with the held items: push() calls on_accept(T&&) for each item accepted, in stream
/// order, and on_reject(T&&, TimeTagRejection) for each item rejected.
template <class T>
class TimeTagFilter {
 public:
  explicit TimeTagFilter(const TimeTagGateConfig& cfg = {}) : gate_(cfg) {
    held_.reserve(static_cast<std::size_t>(cfg.confirm_samples > 0 ? cfg.confirm_samples : 1));
  }
  template <class A, class R>
  void push(double t, T item, A&& on_accept, R&& on_reject) {
    const TimeTagGate::Verdict v = gate_.feed(t);
    const int d = gate_.dropped();
    for (int i = 0; i < d && i < static_cast<int>(held_.size()); ++i)
      on_reject(std::move(held_[static_cast<std::size_t>(i)]), TimeTagRejection::kOutlier);
    if (d > 0) held_.erase(held_.begin(), held_.begin() + std::min<std::ptrdiff_t>(d, static_cast<std::ptrdiff_t>(held_.size())));
    switch (v) {
      case TimeTagGate::Verdict::kAccept: on_accept(std::move(item)); break;
      case TimeTagGate::Verdict::kHold: held_.push_back(std::move(item)); break;
      case TimeTagGate::Verdict::kNewBase:
        for (T& h : held_) on_accept(std::move(h));
        held_.clear();
        on_accept(std::move(item));
        break;
      case TimeTagGate::Verdict::kReject: on_reject(std::move(item), gate_.reason()); break;
    }
  }
  template <class A, class R>
  void finish(A&& on_accept, R&& on_reject) {
    const bool accept = gate_.finish();
    for (T& h : held_) {
      if (accept)
        on_accept(std::move(h));
      else
        on_reject(std::move(h), TimeTagRejection::kUnconfirmed);
    }
    held_.clear();
  }
  const TimeTagGate& gate() const { return gate_; }
  const TimeTagGateStats& stats() const { return gate_.stats(); }

 private:
  TimeTagGate gate_;
  std::vector<T> held_;
};

}  // namespace hal
