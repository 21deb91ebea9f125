#include "tools/diagnosis_model.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <filesystem>
#include <future>
#include <memory>
#include <sstream>

#include "fsw/driver.hpp"
#include "fsw/frames.hpp"
#include "hal/fsw_node.hpp"
#include "hal/lcm_channels.hpp"
#include "hal/lcm_log.hpp"
#include "hal/lcm_log_sink.hpp"
#include "cfg/flight_config.hpp"
#include "sim/sensor_stream.hpp"
#include "tools/reference.hpp"

namespace tools {
namespace {

using fsw::Block;
using fsw::Effect;
using fsw::LayoutDiag;

Block block_of(Effect e) {
  switch (e) {
    case Effect::kGyroMisalignment: return Block::kGyroMisalign;
    case Effect::kAccelMisalignment: return Block::kAccelMisalign;
    case Effect::kGyroScaleFactor: return Block::kGyroScale;
    case Effect::kAccelScaleFactor: return Block::kAccelScale;
    case Effect::kGyroGSensitivity: return Block::kGyroGSens;
    case Effect::kImuGnssTimeOffset: return Block::kTimeOffset;
    case Effect::kAntennaLeverArm: return Block::kLeverArm;
    case Effect::kTroposphericDelay: return Block::kTropoScale;
    case Effect::kIonosphericDelay: return Block::kIonoScale;
    case Effect::kImuClockDrift: return Block::kTimeDrift;
    case Effect::kCount: break;
  }
  return Block::kCount;
}

using App = fsw::FlightApp<LayoutDiag>;

/// The current estimate of a candidate's effect in SI units.
double estimate_si(const App& app, const Candidate& c) {
  const fsw::ImuCompensation& comp = app.executive().compensation();
  const auto& ekf = app.executive().ekf();
  const int k = c.component;
  switch (c.effect) {
    case Effect::kGyroMisalignment: {
      const auto ax = fsw::kGyroMisalignmentAxes[k];
      return comp.gyro_error(ax.i, ax.j);
    }
    case Effect::kAccelMisalignment: {
      const auto ax = fsw::kAccelMisalignmentAxes[k];
      return comp.accel_error(ax.i, ax.j);
    }
    case Effect::kGyroScaleFactor: return comp.gyro_error(k, k);
    case Effect::kAccelScaleFactor: return comp.accel_error(k, k);
    case Effect::kGyroGSensitivity: return comp.gyro_g_sens_radps_per_mps2(k);
    case Effect::kImuGnssTimeOffset: return ekf.time_offset_s();
    case Effect::kAntennaLeverArm: return ekf.lever_arm_b_m()(k) - ekf.config().lever_arm_b_m(k);
    case Effect::kTroposphericDelay: return ekf.tropo_scale();
    case Effect::kIonosphericDelay: return ekf.iono_scale();
    case Effect::kImuClockDrift: return ekf.time_drift();
    case Effect::kCount: break;
  }
  return 0.0;
}

/// Wald statistic of a random-constant state: estimate x, prior variance p0, posterior p.
double wald_z2(double x, double p0, double p) {
  if (!(p0 > 0.0) || !(p > 0.0) || !(p0 - p > 0.0)) return 0.0;
  return x * x * p0 / ((p0 - p) * p);
}

/// Linear interpolation of truth at t (attitude: slerp); false outside the truth's span.
bool truth_at(const std::vector<TruthPoint>& truth, double t, TruthPoint& out) {
  if (truth.empty() || t < truth.front().t_s || t > truth.back().t_s) return false;
  auto it = std::lower_bound(truth.begin(), truth.end(), t, [](const TruthPoint& a, double x) { return a.t_s < x; });
  if (it == truth.begin()) {
    out = *it;
    return true;
  }
  const TruthPoint& b = *it;
  const TruthPoint& a = *(it - 1);
  const double span = b.t_s - a.t_s;
  if (!(span > 0.0) || span > 1.0) return false;  // a gap in the truth: no score
  const double w = (t - a.t_s) / span;
  out.t_s = t;
  out.llh = a.llh + w * (b.llh - a.llh);
  out.vel_enu_mps = a.vel_enu_mps + w * (b.vel_enu_mps - a.vel_enu_mps);
  out.has_attitude = a.has_attitude && b.has_attitude;
  out.q_b_n = out.has_attitude ? a.q_b_n.slerp(w, b.q_b_n) : fsw::Quat::Identity();
  return true;
}

}  // namespace



double prior_sigma_si(const DiagnosisConfig& cfg, Effect e) {
  return cfg.prior[static_cast<std::size_t>(e)] * fsw::effect_info(e).unit_to_si;
}

const std::vector<Candidate>& diagnosis_candidates() {
  static const std::vector<Candidate> list = [] {
    std::vector<Candidate> v;
    for (const fsw::EffectInfo& info : fsw::kEffectCatalogue) {
      const Block b = block_of(info.effect);
      for (std::size_t k = 0; k < info.n_components; ++k)
        v.push_back(Candidate{info.effect, static_cast<int>(k), LayoutDiag::offset(b) + static_cast<int>(k)});
    }
    return v;
  }();
  return list;
}

std::string candidate_name(const Candidate& c) {
  const fsw::EffectInfo& info = fsw::effect_info(c.effect);
  std::string s = info.name;
  if (info.n_components > 1) s += std::string(".") + info.components[c.component];
  return s;
}

bool set_diagnosis_baseline(DiagnosisConfig& cfg, fsw::FilterModel model) {
  if (model != fsw::FilterModel::k15 && model != fsw::FilterModel::k24) return false;
  cfg.baseline_states.clear();
  if (model == fsw::FilterModel::k24) {
    for (std::size_t c = 0; c < diagnosis_candidates().size(); ++c) {
      const Effect e = diagnosis_candidates()[c].effect;
      if (e == Effect::kGyroMisalignment || e == Effect::kAccelMisalignment) cfg.baseline_states.push_back(static_cast<int>(c));
    }
  }
  cfg.baseline = model;
  return true;
}

DiagnosisConfig default_diagnosis_config() {
  DiagnosisConfig c;
  apply_flight_config(c, cfg::shipped_flight_config());  // config/default.toml sets every prior
  return c;
}

void apply_flight_config(DiagnosisConfig& cfg, const cfg::FlightConfig& f) {
  cfg.app = f.app;
  cfg.gnss_source = f.gnss_source;
  for (std::size_t e = 0; e < fsw::kEffectCount; ++e)
    if (f.diagnosis_prior[e]) cfg.prior[e] = *f.diagnosis_prior[e];
  if (f.outage_length_s) cfg.outage_length_s = *f.outage_length_s;
  if (f.outage_period_s) cfg.outage_period_s = *f.outage_period_s;
  if (f.outage_first_s) cfg.outage_first_s = *f.outage_first_s;
  if (f.gain_skip_s) cfg.gain_skip_s = *f.gain_skip_s;
}

// ---------------------------------------------------------------------------------------------
void exclude_damaged_stretches(RecordedData& d) {
  // docs/faults.md: a damaged stretch of a log (lost or rejected events: the IMU stream has a hole
  // longer than kDamagedImuGap_s) must not become a finding. The IMU missed motion there, so the
  // navigation error it causes is not a sensor effect; the diagnosis keeps the longest stretch
  // without such a hole and counts what it leaves out.
  if (d.imu.size() < 2) return;
  std::size_t best_begin = 0, best_end = 0, begin = 0;  // IMU index ranges [begin, end)
  int holes = 0;
  for (std::size_t k = 1; k <= d.imu.size(); ++k) {
    const bool hole = k < d.imu.size() && d.imu[k].t_s - d.imu[k - 1].t_s > kDamagedImuGap_s;
    if (hole) ++holes;
    if (hole || k == d.imu.size()) {
      if (k - begin > best_end - best_begin) {
        best_begin = begin;
        best_end = k;
      }
      begin = k;
    }
  }
  if (holes == 0) return;
  const double t0 = d.imu[best_begin].t_s - d.imu[best_begin].dt_s, t1 = d.imu[best_end - 1].t_s;
  RecordedData kept;
  kept.description = d.description;
  kept.truth = d.truth;
  for (const RecordedData::Event& e : d.order) {
    switch (e.kind) {
      case RecordedData::Kind::kAlmanac:
        kept.order.push_back({e.kind, static_cast<std::uint32_t>(kept.almanac.size())});
        kept.almanac.push_back(d.almanac[e.index]);
        break;
      case RecordedData::Kind::kImu:
        if (e.index < best_begin || e.index >= best_end) break;
        kept.order.push_back({e.kind, static_cast<std::uint32_t>(kept.imu.size())});
        kept.imu.push_back(d.imu[e.index]);
        break;
      case RecordedData::Kind::kGnss:
        if (d.gnss[e.index].t_s < t0 || d.gnss[e.index].t_s > t1) break;
        kept.order.push_back({e.kind, static_cast<std::uint32_t>(kept.gnss.size())});
        kept.gnss.push_back(d.gnss[e.index]);
        break;
      case RecordedData::Kind::kPvt:
        if (d.pvt[e.index].t_s < t0 || d.pvt[e.index].t_s > t1) break;
        kept.order.push_back({e.kind, static_cast<std::uint32_t>(kept.pvt.size())});
        kept.pvt.push_back(d.pvt[e.index]);
        break;
    }
  }
  kept.damaged_stretches = holes;
  kept.excluded_imu_samples = d.imu.size() - kept.imu.size();
  d = std::move(kept);
}

std::vector<TruthPoint> diagnosis_truth(const Reference& ref, std::uint64_t& rejected) {
  rejected = ref.rejected;
  std::vector<TruthPoint> truth;
  truth.reserve(ref.samples.size());
  for (const ReferenceSample& s : ref.samples) {
    if (!s.has_position || !s.has_velocity || s.attitude_not_unit) {
      ++rejected;
      continue;
    }
    truth.push_back(static_cast<const TruthPoint&>(s));  // the reader's identity where there is no attitude
  }
  return truth;
}

bool load_recorded_data(const std::string& path, RecordedData& out, std::string& error, std::string& report) {
  out = RecordedData{};
  out.description = path;
  hal::LcmReplayReader rd;
  hal::LcmReplayConfig rc;
  rc.gnss_pvt_channel = hal::kLcmChannelGnssPvt;
  if (rd.open(path, rc) != hal::LcmLogStatus::kOk) {
    error = "cannot read " + path + ": " + rd.error();
    return false;
  }
  // The arrays sized once for the most IMU samples the file can hold (address space: pages never
  // written cost nothing), capped at 2^26 (18 h at 1 kHz; beyond it they regrow): regrowing them
  // was half of the load's time.
  std::error_code size_error;
  const std::uintmax_t log_bytes = std::filesystem::file_size(path, size_error);
  if (!size_error) {
    const std::uint64_t n = std::min<std::uint64_t>(hal::max_imu_samples(log_bytes, rc.imu_channel), 1ull << 26);
    out.imu.reserve(static_cast<std::size_t>(n));
    out.order.reserve(static_cast<std::size_t>(n) + 4096);
  }
  // Truth / reference: its own channel, never an input; the one reader (tools/reference.hpp) with
  // the diagnosis' rule on top. It reads the log a second time, so on a second thread while this
  // one reads the inputs (the two readers share nothing but the file).
  std::future<Reference> reference = std::async(std::launch::async, [&path] { return load_reference(path); });
  fsw::InputEvent in;
  hal::LcmLogStatus st;
  while ((st = rd.next(in)) == hal::LcmLogStatus::kOk) {
    out.push(in);
  }
  std::uint64_t truth_rejected = 0;
  std::string truth_error;
  try {
    out.truth = diagnosis_truth(reference.get(), truth_rejected);
  } catch (const std::exception& ex) {
    truth_error = ex.what();
  }
  if (st != hal::LcmLogStatus::kEndOfLog) {
    error = "reading " + path + " failed: " + rd.error();
    return false;
  }
  if (!truth_error.empty()) {
    error = truth_error;
    return false;
  }
  exclude_damaged_stretches(out);
  const hal::LcmReplayStats& s = rd.stats();
  std::ostringstream r;
  r << out.imu.size() << " IMU samples, " << out.gnss.size() << " GNSS epochs, " << out.pvt.size()
    << " GNSS solutions, " << out.almanac.size()
    << " almanac entries, " << out.truth.size() << " truth samples; rejected: " << s.rejected() << " inputs, "
    << rd.log_stats().total_rejections() << " log events, " << truth_rejected << " truth samples";
  if (s.gnss.measurements_dropped > 0)  // docs/faults.md: counted where the user looks
    r << "; " << s.gnss.measurements_dropped << " GNSS measurements with non-finite values dropped";
  if (out.damaged_stretches > 0)
    r << "; " << out.damaged_stretches << " damaged stretches (IMU gaps > " << kDamagedImuGap_s
      << " s) excluded: diagnosed on the longest undamaged stretch, " << out.excluded_imu_samples
      << " IMU samples left out";
  report = r.str();
  if (out.imu.empty() || (out.gnss.empty() && out.pvt.empty())) {
    error = path + ": no IMU or no GNSS data (" + report + ")";
    return false;
  }
  return true;
}

void RecordingView::input_event(const RecordedData::Event& e, fsw::InputEvent& ev) const {
  using Kind = RecordedData::Kind;
  switch (e.kind) {
    case Kind::kAlmanac:
      ev.kind = fsw::InputEvent::Kind::kAlmanac;
      ev.t_s = 0.0;
      ev.almanac = data->almanac[e.index];
      return;
    case Kind::kImu:
      ev.kind = fsw::InputEvent::Kind::kImu;
      ev.imu = data->imu[e.index];
      if (imu) imu->apply(ev.imu);
      ev.t_s = ev.imu.t_s;
      ev.imu_counter = -1;
      ev.imu_status = 0;
      return;
    case Kind::kGnss:
      ev.kind = fsw::InputEvent::Kind::kGnssRaw;
      ev.gnss = gnss_epochs()[e.index];
      ev.t_s = ev.gnss.t_s;
      return;
    case Kind::kPvt:
      ev.kind = fsw::InputEvent::Kind::kGnssPvt;
      ev.pvt = data->pvt[e.index];
      ev.t_s = ev.pvt.t_s;
      return;
  }
}

void RecordedData::push(const fsw::InputEvent& ev) {
  const auto add = [this](Kind k, auto& array, const auto& value) {
    order.push_back({k, static_cast<std::uint32_t>(array.size())});
    array.push_back(value);
  };
  switch (ev.kind) {
    case fsw::InputEvent::Kind::kImu:
      if (ev.imu_counter >= 0) imu_counter_tags.emplace_back(ev.imu.t_s, ev.imu_counter);  // a second clock
      return add(Kind::kImu, imu, ev.imu);
    case fsw::InputEvent::Kind::kGnssRaw: return add(Kind::kGnss, gnss, ev.gnss);
    case fsw::InputEvent::Kind::kGnssPvt: return add(Kind::kPvt, pvt, ev.pvt);
    case fsw::InputEvent::Kind::kAlmanac: return add(Kind::kAlmanac, almanac, ev.almanac);
  }
}

RecordedData record_scenario(const sim::Scenario& sc, std::uint64_t seed, double truth_rate_hz) {
  RecordedData out;
  out.description = sc.name + ", seed " + std::to_string(seed);
  sim::SensorStream stream(sc, seed);
  out.imu.reserve(static_cast<std::size_t>(stream.total_samples()));
  out.order.reserve(static_cast<std::size_t>(stream.total_samples()) * 21 / 20 + 64);
  const long long decim = std::max(1LL, std::llround(sc.imu.rate_hz / truth_rate_hz));
  fsw::InputEvent ev;
  sim::TruthSample t;
  long long n_imu = 0;
  while (stream.next(ev, &t)) {
    out.push(ev);
    if (ev.kind == fsw::InputEvent::Kind::kImu && n_imu++ % decim == 0) out.truth.push_back(sim::truth_point(t));
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
namespace {

/// The flight configuration of one diagnosis run: the diagnosis' priors become EKF sigmas on top of
/// the loaded (validated) configuration, and every candidate outside `active` is frozen. The
/// result is checked against the same rules, so a refusal names the prior instead of reading as a
/// flight software that never initialised.
fsw::FlightAppConfig diagnosis_app_config(const DiagnosisConfig& cfg, const std::vector<int>& active) {
  const std::vector<Candidate>& cands = diagnosis_candidates();
  fsw::FlightAppConfig app_cfg = cfg.app;
  fsw::EkfConfig& e = app_cfg.exec.ekf;
  e.gyro_misalign_sigma_rad = prior_sigma_si(cfg, Effect::kGyroMisalignment);
  e.accel_misalign_sigma_rad = prior_sigma_si(cfg, Effect::kAccelMisalignment);
  e.gyro_scale_sigma = prior_sigma_si(cfg, Effect::kGyroScaleFactor);
  e.accel_scale_sigma = prior_sigma_si(cfg, Effect::kAccelScaleFactor);
  e.gyro_g_sens_sigma_radps_per_mps2 = prior_sigma_si(cfg, Effect::kGyroGSensitivity);
  e.time_offset_sigma_s = prior_sigma_si(cfg, Effect::kImuGnssTimeOffset);
  e.lever_arm_sigma_m = prior_sigma_si(cfg, Effect::kAntennaLeverArm);
  e.tropo_scale_sigma = prior_sigma_si(cfg, Effect::kTroposphericDelay);
  e.iono_scale_sigma = prior_sigma_si(cfg, Effect::kIonosphericDelay);
  e.time_drift_sigma_sps = prior_sigma_si(cfg, Effect::kImuClockDrift);
  e.frozen_states = 0;
  for (std::size_t i = 0; i < cands.size(); ++i)
    if (std::find(active.begin(), active.end(), static_cast<int>(i)) == active.end())
      e.frozen_states |= std::uint64_t{1} << cands[i].state;
  if (const fsw::ConfigCheck check = fsw::check_config(app_cfg); !check.ok())
    throw std::runtime_error("the diagnosis' priors on the flight configuration: " +
                             cfg::describe(check, app_cfg, cfg::FlightConfig{}));
  return app_cfg;
}

/// The scoring of one diagnosis run: which inputs the run takes (keep) and, after every navigation
/// frame, what it scores (score: an observer of the driver, fsw/driver.hpp); finish() turns the
/// sums into the run's statistics.
class RunScoring {
 public:
  RunScoring(const RecordedData& data, const DiagnosisConfig& cfg, const App& app, double nav_rate_hz,
             bool with_outages, DiagnosisRun& run)
      : data_(data), cfg_(cfg), app_(app), nav_rate_hz_(nav_rate_hz), with_outages_(with_outages), run_(run) {}

  /// The inputs the configuration takes, in arrival order: the almanac, the IMU samples and the GNSS
  /// input of cfg.gnss_source (raw epochs or solutions; the other is not fed), less the epochs an
  /// outage window withholds.
  bool keep(const fsw::InputEvent& in) {
    const bool raw = in.kind == fsw::InputEvent::Kind::kGnssRaw, pvt = in.kind == fsw::InputEvent::Kind::kGnssPvt;
    if (!raw && !pvt) return true;
    if (cfg_.gnss_source != (raw ? cfg::GnssSource::kRaw : cfg::GnssSource::kPvt)) return false;
    last_gnss_t_s_ = in.t_s;
    if (outage_window(in.t_s) >= 0) {
      ++run_.outages.epochs_withheld;
      in_outage_ = true;
      return false;
    }
    if (in_outage_) await_reacquisition_ = true;
    in_outage_ = false;
    return true;
  }

  void score(const fsw::InputEvent& in, fsw::Status st, const fsw::FrameOutput& out) {
    if (in.kind != fsw::InputEvent::Kind::kImu || st != fsw::Status::kOk || !out.nav_valid) return;
    if (!run_.initialised && app_.initialised()) {
      run_.initialised = true;
      run_.init_t_s = app_.health().init_t_s;
    }
    if (with_outages_ && !data_.truth.empty()) score_outage_error(out);
    if (!with_outages_ && !data_.truth.empty()) score_navigation_error(out);
    if (!out.ekf_ran || !out.ekf_updated) return;
    if (await_reacquisition_) score_reacquisition(out.report);
    score_innovations(out);
    record_traces(out);
  }

  void finish() {
    close_window();
    finish_outages();
    finish_innovations();
    finish_navigation();
  }

 private:
  /// GNSS outages (with_outages): window k covers [t0 + k period, t0 + k period + length), GNSS time.
  long outage_window(double t) const {
    if (!with_outages_ || !run_.initialised) return -1;
    const double t0 = run_.init_t_s + cfg_.outage_first_s;
    if (t < t0) return -1;
    const long k = static_cast<long>(std::floor((t - t0) / cfg_.outage_period_s));
    return t - t0 - static_cast<double>(k) * cfg_.outage_period_s < cfg_.outage_length_s ? k : -1;
  }

  void close_window() {
    if (window_open_ < 0) return;
    ++run_.outages.windows;
    out_h_ss_ += window_err_h_ * window_err_h_;
    out_v_ss_ += window_err_v_ * window_err_v_;
    out_var_h_sum_ += window_var_h_;
    out_nees_sum_ += window_nees_h_;
    run_.outages.horizontal_max_m = std::max(run_.outages.horizontal_max_m, window_err_h_);
    window_open_ = -1;
  }

  /// Navigation error against truth; the solution's time tag is on the IMU clock: the model's own
  /// offset estimate puts it on GNSS time. A reference without attitude is a GNSS solution (what
  /// `sdins import` writes from an RTK .pos): it is of the antenna, so the model's antenna (its
  /// IMU point moved by its own lever-arm estimate) is scored against it; a simulator's truth
  /// (with attitude) is of the IMU point.
  fsw::Vec3 scored_error_enu_m(const fsw::FrameOutput& out, const TruthPoint& t) const {
    const auto& ekf = app_.executive().ekf();
    const fsw::Vec3 llh =
        t.has_attitude ? out.nav.llh
                       : fsw::Vec3(out.nav.llh + fsw::llh_delta_from_enu(out.nav.llh, out.nav.C_b_n() * ekf.lever_arm_b_m()));
    return fsw::Vec3(fsw::enu_difference_m(llh, t.llh));
  }

  /// Every navigation frame: the error at the last frame inside a window is the error after the
  /// whole outage, whatever the navigation rate.
  void score_outage_error(const fsw::FrameOutput& out) {
    const auto& ekf = app_.executive().ekf();
    const double tg = out.nav.t_s - ekf.time_offset_at(out.nav.t_s);
    const long w = outage_window(tg);
    if (w != window_open_) close_window();
    TruthPoint t;
    if (w >= 0 && truth_at(data_.truth, tg, t)) {
      window_open_ = w;
      const fsw::Vec3 dp = scored_error_enu_m(out, t);
      window_err_h_ = dp.head<2>().norm();
      window_err_v_ = (out.nav.vel_enu_mps - t.vel_enu_mps).norm();
      const Eigen::Matrix2d P_h = ekf.P().template block<2, 2>(LayoutDiag::offset(Block::kPosition), LayoutDiag::offset(Block::kPosition));
      window_var_h_ = P_h.trace();
      window_nees_h_ = dp.head<2>().dot(P_h.ldlt().solve(dp.head<2>()));
    }
  }

  /// The RMS over the run: 10 Hz in time (the first frame at or after each multiple of 0.1 s), from
  /// init + gain_skip_s, so that runs at different navigation rates are scored alike.
  void score_navigation_error(const fsw::FrameOutput& out) {
    constexpr double kScoreInterval_s = 0.1;
    if (!(out.nav.t_s >= run_.init_t_s + cfg_.gain_skip_s && out.nav.t_s >= next_score_t_s_)) return;
    next_score_t_s_ = (std::floor(out.nav.t_s / kScoreInterval_s + 1e-9) + 1.0) * kScoreInterval_s;
    TruthPoint t;
    if (!truth_at(data_.truth, out.nav.t_s - app_.executive().ekf().time_offset_at(out.nav.t_s), t)) return;
    const fsw::Vec3 dp = scored_error_enu_m(out, t);
    const sim::NavErrors err = sim::nav_errors(out.nav, t);
    const fsw::Vec3& dv = err.vel_enu_mps;
    nav_pos_ss_ += dp.squaredNorm();
    nav_vel_ss_ += dv.squaredNorm();
    ++run_.nav.samples;
    if (t.has_attitude) {
      const fsw::Vec3& phi = err.att_phi_enu_rad;
      nav_tilt_ss_ += phi.head<2>().squaredNorm();
      nav_head_ss_ += phi.z() * phi.z();
      ++run_.nav.attitude_samples;
      run_.nav.heading_final_deg = phi.z() * fsw::kRadToDeg;
    }
  }

  /// The first update after an outage: its position scalars / pseudoranges, used or gated.
  void score_reacquisition(const fsw::EkfUpdateReport& rep) {
    double z2 = 0.0;
    int n = 0;
    const auto add = [&](fsw::InnovationOutcome o, double nu, double S) {
      if ((o == fsw::InnovationOutcome::kUsed || o == fsw::InnovationOutcome::kGated) && S > 0.0) {
        z2 += nu * nu / S;
        ++n;
      }
    };
    if (rep.pvt)
      for (std::size_t i = 0; i < 3; ++i) add(rep.pvt_obs[i].outcome, rep.pvt_obs[i].innovation, rep.pvt_obs[i].variance);
    for (int k = 0; k < rep.n_obs; ++k) {
      const fsw::ObservationInnovation& o = rep.obs[static_cast<std::size_t>(k)];
      add(o.pr_outcome, o.pr_innovation_m, o.pr_variance_m2);
    }
    if (n > 0) {
      reacq_nis_sum_ += z2 / n;
      ++run_.outages.reacquisitions;
      await_reacquisition_ = false;
    }
  }

  /// An update's innovations: the likelihood's scalars (keyed by the GNSS measurement time, the last
  /// epoch fed, not the IMU clock: runs on re-timed IMU data, diagnosis_intervals.cpp, compare the
  /// same measurements), the gated ones, the sums and the per-epoch RMS traces.
  void score_innovations(const fsw::FrameOutput& out) {
    const fsw::EkfUpdateReport& rep = out.report;
    const std::uint64_t frame = static_cast<std::uint64_t>(std::llround(last_gnss_t_s_ * nav_rate_hz_));
    double epr = 0.0, eprr = 0.0, epos = 0.0, evel = 0.0;
    int npr = 0, nprr = 0, npos = 0, nvel = 0;
    if (rep.pvt) {
      for (int i = 0; i < 6; ++i) {
        const fsw::PvtInnovation& o = rep.pvt_obs[static_cast<std::size_t>(i)];
        if (o.outcome == fsw::InnovationOutcome::kGated) {
          ++run_.innovations.rejected;
          run_.gated.emplace_back(frame, std::uint8_t{0});
        }
        if (o.outcome != fsw::InnovationOutcome::kUsed) continue;
        // Keys above the raw observations' (k < kMaxGnssChannels = 16).
        run_.scalars.push_back({DiagnosisRun::frame_key(frame) | (static_cast<std::uint64_t>(16 + i) << 1), o.innovation, o.variance});
        nis_ += o.innovation * o.innovation / o.variance;
        (i < 3 ? epos : evel) += o.innovation * o.innovation;
        ++(i < 3 ? npos : nvel);
      }
    }
    for (int k = 0; k < rep.n_obs; ++k) {
      const fsw::ObservationInnovation& o = rep.obs[static_cast<std::size_t>(k)];
      const std::uint64_t key = DiagnosisRun::frame_key(frame) | (static_cast<std::uint64_t>(k) << 1);
      if (o.pr_outcome == fsw::InnovationOutcome::kUsed) {
        run_.scalars.push_back({key, o.pr_innovation_m, o.pr_variance_m2});
        epr += o.pr_innovation_m * o.pr_innovation_m;
        nis_ += o.pr_innovation_m * o.pr_innovation_m / o.pr_variance_m2;
        ++npr;
      } else if (o.pr_outcome == fsw::InnovationOutcome::kGated) {
        ++run_.innovations.rejected;
        run_.gated.emplace_back(frame, o.prn);
      }
      if (o.prr_outcome == fsw::InnovationOutcome::kUsed) {
        run_.scalars.push_back({key | 1u, o.prr_innovation_mps, o.prr_variance_m2ps2});
        eprr += o.prr_innovation_mps * o.prr_innovation_mps;
        nis_ += o.prr_innovation_mps * o.prr_innovation_mps / o.prr_variance_m2ps2;
        ++nprr;
      } else if (o.prr_outcome == fsw::InnovationOutcome::kGated) {
        ++run_.innovations.rejected;
        if (o.pr_outcome != fsw::InnovationOutcome::kGated) run_.gated.emplace_back(frame, o.prn);
      }
    }
    pr_ss_ += epr;
    prr_ss_ += eprr;
    pos_ss_ += epos;
    vel_ss_ += evel;
    run_.innovations.pr_used += npr;
    run_.innovations.prr_used += nprr;
    run_.innovations.pos_used += npos;
    run_.innovations.vel_used += nvel;
    ++run_.innovations.epochs;
    run_.t_s.push_back(out.nav.t_s);
    run_.pr_rms_m.push_back(npr > 0 ? std::sqrt(epr / npr) : 0.0);
    run_.prr_rms_mps.push_back(nprr > 0 ? std::sqrt(eprr / nprr) : 0.0);
    run_.pos_rms_m.push_back(npos > 0 ? std::sqrt(epos / npos) : 0.0);
    run_.vel_rms_mps.push_back(nvel > 0 ? std::sqrt(evel / nvel) : 0.0);
  }

  /// At each update: the heading error against truth and the active candidates' estimates and sigmas.
  void record_traces(const fsw::FrameOutput& out) {
    const std::vector<Candidate>& cands = diagnosis_candidates();
    const auto& ekf = app_.executive().ekf();
    double head = NAN;
    if (!data_.truth.empty()) {
      TruthPoint t;
      if (truth_at(data_.truth, out.nav.t_s - ekf.time_offset_s(), t) && t.has_attitude)
        head = sim::nav_errors(out.nav, t).att_phi_enu_rad.z() * fsw::kRadToDeg;
    }
    run_.heading_err_deg.push_back(head);
    const int na = static_cast<int>(run_.active.size());
    std::vector<double> est(static_cast<std::size_t>(na)), sig(static_cast<std::size_t>(na));
    for (int a = 0; a < na; ++a) {
      const Candidate& c = cands[static_cast<std::size_t>(run_.active[a])];
      const double u = fsw::effect_info(c.effect).unit_to_si;
      est[static_cast<std::size_t>(a)] = estimate_si(app_, c) / u;
      sig[static_cast<std::size_t>(a)] = std::sqrt(ekf.P()(c.state, c.state)) / u;
    }
    run_.est_trace.push_back(std::move(est));
    run_.sigma_trace.push_back(std::move(sig));
  }

  void finish_outages() {
    if (run_.outages.windows > 0) {
      run_.outages.horizontal_rms_m = std::sqrt(out_h_ss_ / run_.outages.windows);
      run_.outages.velocity_rms_mps = std::sqrt(out_v_ss_ / run_.outages.windows);
      run_.outages.predicted_horizontal_rms_m = std::sqrt(out_var_h_sum_ / run_.outages.windows);
      run_.outages.horizontal_nees_mean = out_nees_sum_ / run_.outages.windows;
    }
    if (run_.outages.reacquisitions > 0) run_.outages.reacquisition_nis_mean = reacq_nis_sum_ / run_.outages.reacquisitions;
  }

  void finish_innovations() {
    InnovationStats& s = run_.innovations;
    const int nused = s.pr_used + s.prr_used + s.pos_used + s.vel_used;
    s.nis_mean = nused > 0 ? nis_ / nused : 0.0;
    s.pr_rms_m = s.pr_used > 0 ? std::sqrt(pr_ss_ / s.pr_used) : 0.0;
    s.prr_rms_mps = s.prr_used > 0 ? std::sqrt(prr_ss_ / s.prr_used) : 0.0;
    s.pos_rms_m = s.pos_used > 0 ? std::sqrt(pos_ss_ / s.pos_used) : 0.0;
    s.vel_rms_mps = s.vel_used > 0 ? std::sqrt(vel_ss_ / s.vel_used) : 0.0;
    s.log_likelihood = 0.0;
    for (const DiagnosisRun::Scalar& x : run_.scalars) s.log_likelihood -= 0.5 * (std::log(2.0 * fsw::kPi * x.S) + x.nu * x.nu / x.S);
    s.common = static_cast<int>(run_.scalars.size());
  }

  void finish_navigation() {
    if (run_.nav.samples <= 0) return;
    const double n = run_.nav.samples;
    run_.nav.available = true;
    run_.nav.pos_rms_m = std::sqrt(nav_pos_ss_ / n);
    run_.nav.vel_rms_mps = std::sqrt(nav_vel_ss_ / n);
    const double n_att = std::max(1, run_.nav.attitude_samples);
    run_.nav.tilt_rms_deg = run_.nav.attitude_samples > 0 ? std::sqrt(nav_tilt_ss_ / n_att) * fsw::kRadToDeg : NAN;
    run_.nav.heading_rms_deg = run_.nav.attitude_samples > 0 ? std::sqrt(nav_head_ss_ / n_att) * fsw::kRadToDeg : NAN;
  }

  const RecordedData& data_;
  const DiagnosisConfig& cfg_;
  const App& app_;
  const double nav_rate_hz_;
  const bool with_outages_;
  DiagnosisRun& run_;
  // Innovations: sums of squares and of the NIS.
  double pr_ss_ = 0.0, prr_ss_ = 0.0, pos_ss_ = 0.0, vel_ss_ = 0.0, nis_ = 0.0;
  // Navigation error against truth.
  double next_score_t_s_ = -1e300;
  double nav_pos_ss_ = 0.0, nav_vel_ss_ = 0.0, nav_tilt_ss_ = 0.0, nav_head_ss_ = 0.0;
  // Outages: the open window, its error, and the sums over closed windows.
  bool in_outage_ = false, await_reacquisition_ = false;
  double reacq_nis_sum_ = 0.0;
  long window_open_ = -1;
  double window_err_h_ = 0.0, window_err_v_ = 0.0, window_var_h_ = 0.0, window_nees_h_ = 0.0;
  double out_h_ss_ = 0.0, out_v_ss_ = 0.0, out_var_h_sum_ = 0.0, out_nees_sum_ = 0.0;
  double last_gnss_t_s_ = 0.0;
};

/// Final estimates, Wald statistics and the posterior correlation of the active candidates.
void final_estimates(const App& app, const DiagnosisConfig& cfg, DiagnosisRun& run) {
  const std::vector<Candidate>& cands = diagnosis_candidates();
  const std::vector<int>& active = run.active;
  const int na = static_cast<int>(active.size());
  const auto& P = app.executive().ekf().P();
  run.estimate.resize(static_cast<std::size_t>(na));
  run.sigma.resize(static_cast<std::size_t>(na));
  run.z2.resize(static_cast<std::size_t>(na));
  run.correlation = Eigen::MatrixXd::Identity(na, na);
  for (int a = 0; a < na; ++a) {
    const Candidate& c = cands[static_cast<std::size_t>(active[a])];
    const double u = fsw::effect_info(c.effect).unit_to_si;
    const double x = estimate_si(app, c);
    const double p = P(c.state, c.state);
    const double p0 = prior_sigma_si(cfg, c.effect) * prior_sigma_si(cfg, c.effect);
    run.estimate[static_cast<std::size_t>(a)] = x / u;
    run.sigma[static_cast<std::size_t>(a)] = std::sqrt(p) / u;
    run.z2[static_cast<std::size_t>(a)] = wald_z2(x, p0, p);
    for (int b = 0; b < na; ++b) {
      const int sb = cands[static_cast<std::size_t>(active[b])].state;
      const double d = std::sqrt(P(c.state, c.state) * P(sb, sb));
      if (a != b) run.correlation(a, b) = d > 0.0 ? P(c.state, sb) / d : 0.0;
    }
  }
}

}  // namespace

DiagnosisRun run_diagnosis_model(const RecordedData& data, const DiagnosisConfig& cfg, const std::vector<int>& active,
                             bool with_outages) {
  return run_diagnosis_model(RecordingView{&data}, cfg, active, with_outages);
}

DiagnosisRun run_diagnosis_model(const RecordingView& view, const DiagnosisConfig& cfg, const std::vector<int>& active,
                             bool with_outages) {
  const RecordedData& data = *view.data;
  const std::vector<Candidate>& cands = diagnosis_candidates();
  DiagnosisRun run;
  run.active = active;
  const int na = static_cast<int>(active.size());
  const fsw::FlightAppConfig app_cfg = diagnosis_app_config(cfg, active);
  auto driver = std::make_unique<fsw::FlightDriver<LayoutDiag>>();  // the 56-state application: not on the stack
  const App& app = driver->app();
  if (driver->init(app_cfg) != fsw::Status::kOk) return run;
  run.prior_sigma.resize(static_cast<std::size_t>(na));
  for (int a = 0; a < na; ++a)
    run.prior_sigma[static_cast<std::size_t>(a)] = cfg.prior[static_cast<std::size_t>(cands[active[a]].effect)];

  RunScoring scoring(data, cfg, app, app_cfg.exec.nav_rate_hz, with_outages, run);
  RecordedSource recording(view);
  auto inputs = fsw::filtered(recording, [&scoring](const fsw::InputEvent& in) { return scoring.keep(in); });
  auto observer = fsw::after_each([&scoring](const fsw::InputEvent& in, fsw::Status st, const fsw::FrameOutput& out) {
    scoring.score(in, st, out);
  });
  fsw::drive(inputs, *driver, observer);
  scoring.finish();
  final_estimates(app, cfg, run);
  run.exec_health = app.executive().health();
  return run;
}

void compare_likelihood(DiagnosisRun& a, DiagnosisRun& b) {
  auto by_key = [](const DiagnosisRun::Scalar& x, const DiagnosisRun::Scalar& y) { return x.key < y.key; };
  std::sort(a.scalars.begin(), a.scalars.end(), by_key);
  std::sort(b.scalars.begin(), b.scalars.end(), by_key);
  double la = 0.0, lb = 0.0;
  int n = 0;
  std::size_t i = 0, j = 0;
  while (i < a.scalars.size() && j < b.scalars.size()) {
    if (a.scalars[i].key < b.scalars[j].key) {
      ++i;
    } else if (b.scalars[j].key < a.scalars[i].key) {
      ++j;
    } else {
      const auto& x = a.scalars[i++];
      const auto& y = b.scalars[j++];
      la -= 0.5 * (std::log(2.0 * fsw::kPi * x.S) + x.nu * x.nu / x.S);
      lb -= 0.5 * (std::log(2.0 * fsw::kPi * y.S) + y.nu * y.nu / y.S);
      ++n;
    }
  }
  a.innovations.log_likelihood = la;
  b.innovations.log_likelihood = lb;
  a.innovations.common = n;
  b.innovations.common = n;
}


}  // namespace tools
