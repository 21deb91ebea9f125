// The rate-group executive (see fsw/executive.hpp): the 200 Hz group (NavGroup), the 1 Hz group
// (EkfGroup) and the scheduler that divides each tick among them (Executive).
#include "fsw/executive.hpp"

#include <algorithm>
#include <cmath>

#include "fsw/config_check.hpp"

namespace fsw {

// ---- The 200 Hz group ---------------------------------------------------------------------------

template <class Layout>
Status NavGroup<Layout>::configure(const ExecutiveConfig& cfg, const NavState& initial) {
  const Status st = builder_.configure(cfg.imu_samples_per_frame);
  if (st != Status::kOk) return st;
  return ins_.init(initial);
}

template <class Layout>
void NavGroup<Layout>::reset(const ExecutiveConfig& cfg) {
  comp_ = ImuCompensation{};
  substep_frames_ = cfg.ekf.propagation_substep_frames;
  for (EkfTransition<Layout>& t : transition_) {
    t.set_dead_states({});  // every column until the filter's first propagate() names its dead states
    t.reset(substep_frames_);
  }
  acc_ = 0;
  have_last_sample_ = false;
  rate_window_frames_ = std::max(1, static_cast<int>(std::lround(cfg.nav_rate_hz)));
  rate_window_s_ = rate_window_frames_ / cfg.nav_rate_hz;
  window_frames_ = 0;
  window_imu_s_ = 0.0;
  last_accel_enu_mps2_.setZero();
}

template <class Layout>
bool NavGroup<Layout>::add_sample(const ImuSample& raw, ExecutiveHealth& health) {
  ++health.imu_samples;
  if (have_last_sample_ && std::isfinite(raw.t_s) && raw.t_s - last_sample_t_s_ > 1.5 * raw.dt_s)
    ++health.imu_time_gaps;
  const Status add = builder_.add(comp_.apply(raw));
  if (add == Status::kBadInput) {
    ++health.imu_rejected;
    return false;
  }
  have_last_sample_ = true;
  last_sample_t_s_ = raw.t_s;
  if (add != Status::kOk) return false;  // frame not complete yet

  const FrameIncrement& inc = builder_.frame();
  check_frame_rate(inc.dt_s, health);
  const Vec3 v_before = ins_.state().vel_enu_mps;
  if (ins_.step(inc) != Status::kOk || transition_[acc_].accumulate(inc, ins_.state()) != Status::kOk) {
    ++health.fsw_errors;
    return false;
  }
  last_accel_enu_mps2_ = (ins_.state().vel_enu_mps - v_before) / inc.dt_s;
  ++health.nav_frames;
  return true;
}

template <class Layout>
void NavGroup<Layout>::check_frame_rate(double frame_dt_s, ExecutiveHealth& health) {
  // nav_rate_hz frames are 1 s of IMU time (imu_samples_per_frame samples at the IMU's rate). Far
  // from it, the configuration does not match the IMU, and every rate derived from nav_rate_hz
  // (the 1 Hz group's schedule, the noise per frame) is wrong: counted per 1 s window, not
  // corrected. Seen: a 200 Hz IMU with the 1 kHz default of 5 samples per frame gave 25 ms
  // frames and an "1 Hz" EKF step every 5 s, without a word. A window, not a frame: a real IMU's
  // sample intervals jitter (the walk's millisecond ticks: 4-6 ms samples at 200 Hz, a fifth of
  // its single-sample frames more than 10% off).
  window_imu_s_ += frame_dt_s;
  if (++window_frames_ == rate_window_frames_) {
    if (std::abs(window_imu_s_ - rate_window_s_) > 0.1 * rate_window_s_) ++health.frame_rate_mismatch;
    window_frames_ = 0;
    window_imu_s_ = 0.0;
  }
}

template <class Layout>
int NavGroup<Layout>::hand_over_interval() {
  const int closed = acc_;
  acc_ ^= 1;
  transition_[acc_].reset(substep_frames_);
  return closed;
}

template <class Layout>
Status NavGroup<Layout>::apply_correction(const Vec& x) {
  // The estimate is of frame R; the transition since R carries it to this frame.
  EkfTransition<Layout>& since = transition_[acc_];
  since.flush();
  const Eigen::Matrix<double, 9, 1> dx_nav = since.phi_nav() * x;
  const Status st =
      ins_.correct(dx_nav.template segment<3>(0), dx_nav.template segment<3>(3), dx_nav.template segment<3>(6));
  if (st == Status::kOk) add_sensor_correction<Layout>(x, comp_);
  return st;
}

template <class Layout>
NavState NavGroup<Layout>::aligned(double t_s) const {
  const NavState& nav = ins_.state();
  const double dt = t_s - nav.t_s;
  NavState at = nav;
  at.t_s = t_s;
  at.llh += llh_rate(nav.llh, nav.vel_enu_mps) * dt;
  at.vel_enu_mps += last_accel_enu_mps2_ * dt;
  return at;
}

// ---- The 1 Hz group -----------------------------------------------------------------------------

template <class Layout>
void EkfGroup<Layout>::run(const EkfRequest<Layout>& rq, EkfTransition<Layout>& t, EkfResult<Layout>& r) {
  r.updated = false;
  r.correction_valid = false;
  r.report = EkfUpdateReport{};
  r.fsw_errors = 0;
  if (ekf_.propagate(t) != Status::kOk) ++r.fsw_errors;
  Status st = Status::kOk;
  if (rq.aid == EkfRequest<Layout>::Aid::kRaw)
    st = ekf_.update(rq.epoch, rq.nav_at_aid, rq.omega_ib_b_radps, r.report);
  else if (rq.aid == EkfRequest<Layout>::Aid::kPvt)
    st = ekf_.update_pvt(rq.pvt, rq.nav_at_aid, rq.omega_ib_b_radps, r.report);
  if (st != Status::kOk) ++r.fsw_errors;
  if (rq.aid != EkfRequest<Layout>::Aid::kNone && st == Status::kOk) {
    if (ekf_.take_correction(r.x) == Status::kOk)
      r.correction_valid = true;
    else
      ++r.fsw_errors;
    r.updated = true;
  }
  r.ekf_health = ekf_.health();
  ekf_.output(rq.t_s, r.output);
}

// ---- The scheduler ------------------------------------------------------------------------------

template <class Layout>
Status Executive<Layout>::init(const ExecutiveConfig& cfg, const NavState& initial) {
  if (!check_config(cfg).ok()) return Status::kBadConfig;  // fsw/config_check.hpp
  if (group_state_.load(std::memory_order_acquire) == kReleased) return Status::kBadConfig;  // 1 Hz group running
  cfg_ = cfg;
  Status st = nav_.configure(cfg, initial);
  if (st != Status::kOk) return st;
  st = ekf_group_.init(cfg.ekf);
  if (st != Status::kOk) return st;
  nav_.reset(cfg);
  health_ = ExecutiveHealth{};
  have_pending_ = false;
  have_pending_pvt_ = false;
  frames_since_ekf_ = 0;
  slip_counted_ = false;
  late_counted_ = false;
  apply_frame_ = 0;
  ekf_output_ = EkfOutput<Layout>{};
  group_state_.store(kIdle, std::memory_order_release);
  initialised_ = true;
  return Status::kOk;
}

template <class Layout>
void Executive<Layout>::note_ekf_group_exec_s(double s) {
  if (!(s >= 0.0)) return;
  if (s > health_.worst_ekf_s) health_.worst_ekf_s = s;
  if (s > cfg_.ekf_latency_frames / cfg_.nav_rate_hz) ++health_.ekf_overruns;
}

template <class Layout>
Status Executive<Layout>::tick(const FrameInput& in, FrameOutput& out) {
  out.nav_valid = false;
  out.ekf_released = false;
  out.ekf_ran = false;
  out.ekf_updated = false;
  out.report = EkfUpdateReport{};
  if (!initialised_) return Status::kNotInitialised;
  ++health_.ticks;
  note_tick_exec_s(in.prev_tick_exec_s);
  accept_aids(in);
  const int n = (in.imu == nullptr || in.n_imu < 0) ? 0 : in.n_imu;
  if (n < cfg_.imu_samples_per_frame) ++health_.imu_short_ticks;
  for (int k = 0; k < n; ++k) {
    if (!nav_.add_sample(in.imu[k], health_)) continue;  // the 200 Hz group: no navigation frame yet
    ++frames_since_ekf_;
    out.nav_valid = true;
    schedule_ekf(out);
  }
  out.nav = nav_.ins().state();
  if (out.ekf_released && cfg_.ekf_group_inline) (void)run_ekf_group();
  return Status::kOk;
}

template <class Layout>
void Executive<Layout>::note_tick_exec_s(double s) {
  if (!(s >= 0.0)) return;  // unknown
  if (s > cfg_.frame_budget_s) ++health_.overruns;
  if (s > health_.worst_tick_s) health_.worst_tick_s = s;
}

template <class Layout>
void Executive<Layout>::accept_aids(const FrameInput& in) {
  if (in.gnss != nullptr) {
    ++health_.gnss_epochs;
    if (in.gnss->n_obs < 0 || in.gnss->n_obs > kMaxGnssChannels || !std::isfinite(in.gnss->t_s)) {
      ++health_.gnss_invalid;
    } else {
      if (have_pending_) ++health_.gnss_replaced;
      pending_ = *in.gnss;
      have_pending_ = true;
    }
  }
  if (in.pvt != nullptr) {
    ++health_.pvt_received;
    if (!std::isfinite(in.pvt->t_s)) {
      ++health_.pvt_invalid;
    } else {
      if (have_pending_pvt_) ++health_.pvt_replaced;
      pending_pvt_ = *in.pvt;
      have_pending_pvt_ = true;
    }
  }
}

template <class Layout>
void Executive<Layout>::schedule_ekf(FrameOutput& out) {
  // Land a finished epoch's correction at its frame (or, late, at the first frame after it).
  const std::uint8_t state = group_state_.load(std::memory_order_acquire);
  if (state != kIdle && health_.nav_frames >= apply_frame_) {
    if (state == kDone) {
      land(out);
    } else if (!late_counted_) {
      ++health_.ekf_late;
      late_counted_ = true;
    }
  }
  if (frames_since_ekf_ >= cfg_.frames_per_ekf) maybe_release(out);
}

template <class Layout>
void Executive<Layout>::maybe_release(FrameOutput& out) {
  const NavState& nav = nav_.ins().state();
  const double half_frame_s = 0.5 / cfg_.nav_rate_hz;
  if (have_pending_ && nav.t_s - pending_.t_s > cfg_.max_gnss_age_s) {
    ++health_.gnss_stale;
    have_pending_ = false;
  }
  if (have_pending_pvt_ && nav.t_s - pending_pvt_.t_s > cfg_.max_gnss_age_s) {
    ++health_.pvt_stale;
    have_pending_pvt_ = false;
  }
  const bool epoch_ready = have_pending_ && pending_.t_s <= nav.t_s + half_frame_s;
  const bool pvt_ready = have_pending_pvt_ && pending_pvt_.t_s <= nav.t_s + half_frame_s;
  if (!epoch_ready && !pvt_ready && frames_since_ekf_ < cfg_.frames_per_ekf + cfg_.gnss_wait_frames) return;
  if (group_state_.load(std::memory_order_acquire) != kIdle) {
    // The previous epoch's correction has not landed: the interval keeps growing (the pending
    // measurements stay pending, aged as usual) until it has.
    if (!slip_counted_) {
      ++health_.ekf_slips;
      slip_counted_ = true;
    }
    return;
  }
  slip_counted_ = false;
  frames_since_ekf_ = 0;

  EkfRequest<Layout>& rq = request_;
  rq.aid = EkfRequest<Layout>::Aid::kNone;
  if (epoch_ready) {
    if (pvt_ready) {  // both: the raw epoch wins, the solution is dropped
      ++health_.pvt_unused;
      have_pending_pvt_ = false;
    }
    have_pending_ = false;
    rq.aid = EkfRequest<Layout>::Aid::kRaw;
    rq.epoch = pending_;
    rq.nav_at_aid = nav_.aligned(pending_.t_s);  // align: the solution at the epoch's time tag
  } else if (pvt_ready) {
    have_pending_pvt_ = false;
    rq.aid = EkfRequest<Layout>::Aid::kPvt;
    rq.pvt = pending_pvt_;
    rq.nav_at_aid = nav_.aligned(pending_pvt_.t_s);
  }
  rq.omega_ib_b_radps = nav_.ins().omega_ib_b_radps();
  rq.t_s = nav.t_s;
  rq.transition = nav_.hand_over_interval();
  apply_frame_ = health_.nav_frames + static_cast<std::uint32_t>(cfg_.ekf_latency_frames);
  late_counted_ = false;
  group_state_.store(kReleased, std::memory_order_release);
  out.ekf_released = true;
}

template <class Layout>
Status Executive<Layout>::run_ekf_group() {
  if (group_state_.load(std::memory_order_acquire) != kReleased) return Status::kOk;
  ekf_group_.run(request_, nav_.transition(request_.transition), result_);
  group_state_.store(kDone, std::memory_order_release);
  return Status::kOk;
}

template <class Layout>
void Executive<Layout>::land(FrameOutput& out) {
  const EkfRequest<Layout>& rq = request_;
  const EkfResult<Layout>& r = result_;
  out.ekf_ran = true;
  out.ekf_t_s = rq.t_s;
  ++health_.ekf_runs;
  health_.fsw_errors += r.fsw_errors;
  health_.ekf = r.ekf_health;
  ekf_output_ = r.output;
  if (rq.aid == EkfRequest<Layout>::Aid::kNone) {
    ++health_.ekf_without_gnss;
  } else if (r.updated) {
    out.report = r.report;
    health_.pr_used += static_cast<std::uint32_t>(r.report.pr_used);
    health_.prr_used += static_cast<std::uint32_t>(r.report.prr_used);
    health_.pr_rejected += static_cast<std::uint32_t>(r.report.pr_rejected);
    health_.prr_rejected += static_cast<std::uint32_t>(r.report.prr_rejected);
    health_.obs_invalid += static_cast<std::uint32_t>(r.report.obs_invalid);
    health_.pos_used += static_cast<std::uint32_t>(r.report.pos_used);
    health_.vel_used += static_cast<std::uint32_t>(r.report.vel_used);
    health_.pos_rejected += static_cast<std::uint32_t>(r.report.pos_rejected);
    health_.vel_rejected += static_cast<std::uint32_t>(r.report.vel_rejected);
    if (r.correction_valid && nav_.apply_correction(r.x) != Status::kOk) ++health_.fsw_errors;
    ++health_.ekf_updates;
    out.ekf_updated = true;
  }
  group_state_.store(kIdle, std::memory_order_release);
}

#define FSW_EXECUTIVE_INSTANTIATE(L) \
  template class NavGroup<L>;        \
  template class EkfGroup<L>;        \
  template class Executive<L>;
FSW_FOR_EACH_LAYOUT(FSW_EXECUTIVE_INSTANTIATE)
#undef FSW_EXECUTIVE_INSTANTIATE

}  // namespace fsw
