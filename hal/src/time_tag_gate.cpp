#include "hal/time_tag_gate.hpp"

namespace hal {

const char* to_string(TimeTagRejection r) {
  switch (r) {
    case TimeTagRejection::kNotIncreasing: return "time not increasing";
    case TimeTagRejection::kOutlier: return "time-tag outlier (a jump the following samples did not confirm)";
    case TimeTagRejection::kUnconfirmed: return "time-tag jump unconfirmed at the end of the stream";
    case TimeTagRejection::kNotFinite: return "non-finite time";
  }
  return "unknown";
}

TimeTagGate::Verdict TimeTagGate::feed(double t) {
  dropped_ = 0;
  if (!std::isfinite(t)) {
    ++stats_.not_finite;
    reason_ = TimeTagRejection::kNotFinite;
    return Verdict::kReject;
  }
  const auto near = [this](double step) { return step >= -cfg_.max_backward_s && step <= cfg_.max_forward_s; };
  if (have_base_) {
    const double step = t - base_;
    if (in_band(step)) {
      // Continues the old base: whatever was held jumped alone.
      dropped_ = held_;
      stats_.outliers += static_cast<std::uint64_t>(held_);
      held_ = 0;
      base_ = std::max(base_, t);
      ++stats_.accepted;
      return Verdict::kAccept;
    }
    if (near(step)) {
      ++stats_.not_increasing;
      reason_ = TimeTagRejection::kNotIncreasing;
      return Verdict::kReject;
    }
  }
  // A jump away from the base (or no base yet): a candidate for a new base.
  if (held_ > 0) {
    const double cs = t - cand_last_;
    if (in_band(cs)) {
      ++held_;
      cand_last_ = std::max(cand_last_, t);
      if (held_ < cfg_.confirm_samples) return Verdict::kHold;
      if (have_base_) {
        ++stats_.new_bases;
        stats_.last_new_base_jump_s = cand_first_ - base_;
        stats_.last_new_base_at_s = cand_first_;
      }
      have_base_ = true;
      base_ = cand_last_;
      stats_.accepted += static_cast<std::uint64_t>(held_);
      held_ = 0;
      return Verdict::kNewBase;
    }
    if (near(cs)) {
      ++stats_.not_increasing;
      reason_ = TimeTagRejection::kNotIncreasing;
      return Verdict::kReject;
    }
    if (!have_base_ && held_ >= 2) {
      // No base yet, and tags that agree with each other are held: the one that agrees with
      // neither them nor anything else is the outlier (the first tags of a stream are kept).
      ++stats_.outliers;
      reason_ = TimeTagRejection::kOutlier;
      return Verdict::kReject;
    }
    dropped_ = held_;
    stats_.outliers += static_cast<std::uint64_t>(held_);
    held_ = 0;
  }
  held_ = 1;
  cand_first_ = cand_last_ = t;
  if (cfg_.confirm_samples <= 1) {
    if (have_base_) {
      ++stats_.new_bases;
      stats_.last_new_base_jump_s = t - base_;
      stats_.last_new_base_at_s = t;
    }
    have_base_ = true;
    base_ = t;
    ++stats_.accepted;
    held_ = 0;
    return Verdict::kAccept;
  }
  return Verdict::kHold;
}

bool TimeTagGate::finish() {
  const bool accept = !have_base_;
  if (accept) {
    stats_.accepted += static_cast<std::uint64_t>(held_);
    if (held_ > 0) {
      have_base_ = true;
      base_ = cand_last_;
    }
  } else {
    stats_.unconfirmed += static_cast<std::uint64_t>(held_);
  }
  held_ = 0;
  dropped_ = 0;
  return accept;
}

}  // namespace hal
