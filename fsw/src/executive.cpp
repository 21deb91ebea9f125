#include "fsw/executive.hpp"

#include <cmath>

namespace fsw {

template <class Layout>
Status Executive<Layout>::init(const ExecutiveConfig& cfg, const NavState& initial) {
  if (cfg.imu_samples_per_frame < 1 || cfg.imu_samples_per_frame > FrameBuilder::kMaxSamplesPerFrame ||
      cfg.frames_per_ekf < 1 || cfg.gnss_wait_frames < 0 || !(cfg.nav_rate_hz > 0.0) || !(cfg.max_gnss_age_s >= 0.0) ||
      !(cfg.frame_budget_s > 0.0))
    return Status::kBadConfig;
  cfg_ = cfg;
  Status st = builder_.configure(cfg.imu_samples_per_frame);
  if (st != Status::kOk) return st;
  st = ins_.init(initial);
  if (st != Status::kOk) return st;
  st = ekf_.init(cfg.ekf);
  if (st != Status::kOk) return st;
  comp_ = ImuCompensation{};
  health_ = ExecutiveHealth{};
  have_pending_ = false;
  have_pending_pvt_ = false;
  frames_since_ekf_ = 0;
  have_last_sample_ = false;
  last_accel_enu_mps2_.setZero();
  initialised_ = true;
  return Status::kOk;
}

template <class Layout>
Status Executive<Layout>::tick(const FrameInput& in, FrameOutput& out) {
  out.nav_valid = false;
  out.ekf_ran = false;
  out.ekf_updated = false;
  out.report = EkfUpdateReport{};
  if (!initialised_) return Status::kNotInitialised;
  ++health_.ticks;
  if (in.prev_tick_exec_s >= 0.0) {
    if (in.prev_tick_exec_s > cfg_.frame_budget_s) ++health_.overruns;
    if (in.prev_tick_exec_s > health_.worst_tick_s) health_.worst_tick_s = in.prev_tick_exec_s;
  }
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
  const int n = (in.imu == nullptr || in.n_imu < 0) ? 0 : in.n_imu;
  if (n < cfg_.imu_samples_per_frame) ++health_.imu_short_ticks;

  for (int k = 0; k < n; ++k) {
    const ImuSample& raw = in.imu[k];
    ++health_.imu_samples;
    if (have_last_sample_ && std::isfinite(raw.t_s) && raw.t_s - last_sample_t_s_ > 1.5 * raw.dt_s)
      ++health_.imu_time_gaps;
    const Status add = builder_.add(comp_.apply(raw));
    if (add == Status::kBadInput) {
      ++health_.imu_rejected;
      continue;
    }
    have_last_sample_ = true;
    last_sample_t_s_ = raw.t_s;
    if (add != Status::kOk) continue;  // frame not complete yet

    const FrameIncrement& inc = builder_.frame();
    const Vec3 v_before = ins_.state().vel_enu_mps;
    if (ins_.step(inc) != Status::kOk || ekf_.accumulate(inc, ins_.state()) != Status::kOk) {
      ++health_.fsw_errors;
      continue;
    }
    last_accel_enu_mps2_ = (ins_.state().vel_enu_mps - v_before) / inc.dt_s;
    ++health_.nav_frames;
    ++frames_since_ekf_;
    out.nav_valid = true;
    if (frames_since_ekf_ >= cfg_.frames_per_ekf) run_ekf(out);
  }
  out.nav = ins_.state();
  return Status::kOk;
}

template <class Layout>
void Executive<Layout>::run_ekf(FrameOutput& out) {
  const NavState& nav = ins_.state();
  const double half_frame_s = 0.5 / cfg_.nav_rate_hz;
  if (have_pending_) {
    const double age_s = nav.t_s - pending_.t_s;
    if (age_s > cfg_.max_gnss_age_s) {
      ++health_.gnss_stale;
      have_pending_ = false;
    }
  }
  if (have_pending_pvt_ && nav.t_s - pending_pvt_.t_s > cfg_.max_gnss_age_s) {
    ++health_.pvt_stale;
    have_pending_pvt_ = false;
  }
  const bool epoch_ready = have_pending_ && pending_.t_s <= nav.t_s + half_frame_s;
  const bool pvt_ready = have_pending_pvt_ && pending_pvt_.t_s <= nav.t_s + half_frame_s;
  if (!epoch_ready && !pvt_ready && frames_since_ekf_ < cfg_.frames_per_ekf + cfg_.gnss_wait_frames) return;

  frames_since_ekf_ = 0;
  out.ekf_ran = true;
  ++health_.ekf_runs;
  if (ekf_.propagate() != Status::kOk) ++health_.fsw_errors;
  health_.ekf = ekf_.health();
  if (!epoch_ready && !pvt_ready) {
    ++health_.ekf_without_gnss;
    return;
  }
  Status st = Status::kOk;
  if (epoch_ready) {
    if (pvt_ready) {  // both: the raw epoch wins, the solution is dropped
      ++health_.pvt_unused;
      have_pending_pvt_ = false;
    }
    have_pending_ = false;
    // Align: the solution at the epoch's time tag.
    st = ekf_.update(pending_, aligned(pending_.t_s), ins_.omega_ib_b_radps(), out.report);
  } else {
    have_pending_pvt_ = false;
    st = ekf_.update_pvt(pending_pvt_, aligned(pending_pvt_.t_s), ins_.omega_ib_b_radps(), out.report);
  }
  health_.ekf = ekf_.health();
  if (st != Status::kOk) {
    ++health_.fsw_errors;
    return;
  }
  health_.pr_used += static_cast<std::uint32_t>(out.report.pr_used);
  health_.prr_used += static_cast<std::uint32_t>(out.report.prr_used);
  health_.pr_rejected += static_cast<std::uint32_t>(out.report.pr_rejected);
  health_.prr_rejected += static_cast<std::uint32_t>(out.report.prr_rejected);
  health_.obs_invalid += static_cast<std::uint32_t>(out.report.obs_invalid);
  health_.pos_used += static_cast<std::uint32_t>(out.report.pos_used);
  health_.vel_used += static_cast<std::uint32_t>(out.report.vel_used);
  health_.pos_rejected += static_cast<std::uint32_t>(out.report.pos_rejected);
  health_.vel_rejected += static_cast<std::uint32_t>(out.report.vel_rejected);
  if (ekf_.feedback(ins_, comp_) != Status::kOk) ++health_.fsw_errors;
  ++health_.ekf_updates;
  out.ekf_updated = true;
}

template <class Layout>
NavState Executive<Layout>::aligned(double t_s) const {
  const NavState& nav = ins_.state();
  const double dt = t_s - nav.t_s;
  NavState at = nav;
  at.t_s = t_s;
  at.llh += llh_rate(nav.llh, nav.vel_enu_mps) * dt;
  at.vel_enu_mps += last_accel_enu_mps2_ * dt;
  return at;
}

template class Executive<Layout15>;
template class Executive<Layout24>;
template class Executive<Layout15Full>;
template class Executive<Layout24Full>;
template class Executive<Layout15Conv>;
template class Executive<LayoutDiag>;

}  // namespace fsw
