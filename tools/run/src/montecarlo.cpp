#include "tools/montecarlo.hpp"
#include "tools/interrupt.hpp"
#include "tools/output_file.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <cstdio>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <thread>

#include "fsw/alignment.hpp"
#include "fsw/chi_square.hpp"
#include "fsw/effect_catalogue.hpp"
#include "fsw/driver.hpp"
#include "fsw/flight_app.hpp"
#include "sim/rng.hpp"
#include "sim/sensor_stream.hpp"
#include "sim/truth.hpp"
#include "cfg/flight_config.hpp"
#include "tools/free_inertial.hpp"

namespace tools {
namespace {

using fsw::Block;
using fsw::Vec3;
using Clock = std::chrono::steady_clock;

constexpr std::uint64_t kStreamInitialErrors = 20;

/// kFrames minor frames' events as the simulator delivered them (read before any model runs, so
/// the clock splits the run's time between the models and the flight software), with the truth
/// of each GNSS event beside it. Every model's driver runs over the same batch. Eight frames a
/// batch: the clock is read three times a batch, not three times a frame (at 1.1 M frames a run
/// the reads were 8% of a run's time), and the events in use (40 x 864 B at 5 samples a frame)
/// stay in the cache.
struct FrameEvents {
  static constexpr int kFrames = 8;
  static constexpr int kMaxEvents = kFrames * (fsw::FrameBuilder::kMaxSamplesPerFrame + 1);
  fsw::EventBatch<kMaxEvents> events;
  std::array<sim::TruthSample, kMaxEvents> epoch_truth;  ///< of the GNSS events in events
};

/// One model's flight application plus what the run records from it. A record is taken at every
/// GNSS epoch: the navigation error at the epoch's time (the frame that ends at it, before the
/// epoch's own correction lands) against the filter's covariance after the epoch's update, which
/// the 1 Hz group computes at the next minor frame (sim/sensor_stream.hpp: the epoch arrives after
/// the IMU sample of its time). So the error is taken at the epoch and completed with the
/// covariance when the EKF has run (or at the next epoch or the end, if it did not).
struct ModelRunner {
  virtual ~ModelRunner() = default;
  virtual fsw::Status init(const fsw::FlightAppConfig& cfg) = 0;
  virtual fsw::Status start(const fsw::NavState& nav) = 0;
  /// The batch's events through this model's driver (fsw::drive, the one loop; one virtual call
  /// per model and batch); returns whether the 1 Hz group was released (and so ran: inline).
  virtual bool drive(FrameEvents& batch) = 0;
  /// The end of the run: completes the last record.
  virtual void finish() = 0;
  virtual std::vector<SensorResidual> sensors(const sim::ImuErrors& truth, const fsw::ExecutiveConfig& cfg,
                                              std::vector<double>& cov) const = 0;
  virtual fsw::ExecutiveHealth health() const = 0;
  std::vector<EpochRecord>* records = nullptr;
};

/// The flight application of one layout, as SIL/HIL/replay fly it (fsw::FlightDriver), started
/// from the run's given initial state (InitMode::kGiven). The runner is its driver's observer: the
/// truth scoring of every epoch.
template <class Layout>
struct FlightAppRunner final : ModelRunner {
  fsw::FlightDriver<Layout> driver;
  const fsw::FlightApp<Layout>& app = driver.app();
  bool pending = false;  ///< a record waits for its epoch's covariance
  sim::NavErrors pending_err;
  const FrameEvents* batch = nullptr;  ///< the batch being driven
  bool ekf_released = false;           ///< ... in which the 1 Hz group was released (ran inline)

  fsw::Status init(const fsw::FlightAppConfig& cfg) override { return driver.init(cfg); }
  fsw::Status start(const fsw::NavState& nav) override { return driver.start_given(nav); }
  bool drive(FrameEvents& b) override {
    batch = &b;
    ekf_released = false;
    b.events.rewind();
    fsw::drive(b.events, driver, *this);
    return ekf_released;
  }
  // The observer (fsw/driver.hpp).
  void before(const fsw::InputEvent&) {}
  void after(const fsw::InputEvent& ev, fsw::Status, const fsw::FrameOutput& out) {
    if (ev.kind == fsw::InputEvent::Kind::kImu) {
      // The 1 Hz group runs inside the tick that releases it (ekf_group_inline); its correction
      // lands (ekf_ran) ekf_latency_frames later.
      if (out.ekf_released) ekf_released = true;
      if (out.ekf_ran && pending) complete();
    } else if (ev.kind == fsw::InputEvent::Kind::kGnssRaw) {  // the epoch just delivered: its truth
      if (pending) complete();
      pending_err = nav_errors(out.nav, batch->epoch_truth[static_cast<std::size_t>(batch->events.current())]);
      pending = true;
    }
  }
  void finish() override {
    if (pending) complete();
  }
  fsw::ExecutiveHealth health() const override { return app.executive().health(); }

  void complete() {
    pending = false;
    const sim::NavErrors& e = pending_err;
    const auto& P = app.executive().ekf().P();
    EpochRecord r{};
    Eigen::Matrix<double, 9, 1> err;
    err << e.pos_enu_m, e.vel_enu_mps, e.att_phi_enu_rad;
    for (int i = 0; i < 3; ++i) {
      r.resid_att_rad[i] = static_cast<float>(e.att_phi_enu_rad(i));
      r.pos_err_m[i] = static_cast<float>(e.pos_enu_m(i));
      r.vel_err_mps[i] = static_cast<float>(e.vel_enu_mps(i));
      r.sigma_pos_m[i] = static_cast<float>(std::sqrt(P(i, i)));
      r.sigma_vel_mps[i] = static_cast<float>(std::sqrt(P(3 + i, 3 + i)));
      r.sigma_att_rad[i] = static_cast<float>(std::sqrt(P(6 + i, 6 + i)));
    }
    const Eigen::Matrix<double, 9, 9> Pn = P.template topLeftCorner<9, 9>();
    r.nees = static_cast<float>(err.dot(Pn.ldlt().solve(err)));
    const Eigen::Matrix3d Pa = P.template block<3, 3>(6, 6);
    r.nees_att = static_cast<float>(e.att_phi_enu_rad.dot(Pa.ldlt().solve(e.att_phi_enu_rad)));
    records->push_back(r);
  }

  std::vector<SensorResidual> sensors(const sim::ImuErrors& truth, const fsw::ExecutiveConfig& cfg,
                                      std::vector<double>& cov) const override {
    std::vector<SensorResidual> out_s;
    std::vector<std::pair<int, double>> state_scale;
    const auto& P = app.executive().ekf().P();
    const fsw::ImuCompensation& c = app.executive().compensation();
    auto add = [&](const std::string& name, int state, double truth_v, double est, double sigma0, const char* unit,
                   double scale) {
      bool estimated = true;
      for (int b = 0; b < Layout::kNumBlocks; ++b) {
        const Block blk = Layout::kBlocks[b];
        if (state >= Layout::offset(blk) && state < Layout::offset(blk) + fsw::block_size(blk))
          estimated = !Layout::is_consider(blk);
      }
      out_s.push_back(
          {name, (truth_v - est) * scale, sigma0 * scale, std::sqrt(P(state, state)) * scale, unit, estimated});
      state_scale.emplace_back(state, scale);
    };
    const char* axes[3] = {"x", "y", "z"};
    if constexpr (Layout::has(Block::kAccelBias)) {
      const int o = Layout::offset(Block::kAccelBias);
      for (int i = 0; i < 3; ++i)
        add(std::string("accel_bias.") + axes[i], o + i, truth.accel_bias_mps2(i), c.accel_bias_mps2(i),
            cfg.ekf.accel_bias_sigma_mps2, "ug", 1.0 / fsw::kMicroG_mps2);
    }
    if constexpr (Layout::has(Block::kGyroBias)) {
      const int o = Layout::offset(Block::kGyroBias);
      for (int i = 0; i < 3; ++i)
        add(std::string("gyro_bias.") + axes[i], o + i, truth.gyro_bias_radps(i), c.gyro_bias_radps(i),
            cfg.ekf.gyro_bias_sigma_radps, "deg/h", 1.0 / fsw::kDegPerHourToRadps);
    }
    if constexpr (Layout::has(Block::kAccelMisalign)) {
      const int o = Layout::offset(Block::kAccelMisalign);
      const auto& info = fsw::effect_info(fsw::Effect::kAccelMisalignment);
      for (int k = 0; k < 3; ++k) {
        const auto ax = fsw::kAccelMisalignmentAxes[k];
        add(std::string("accel_mis.") + info.components[k], o + k, truth.accel_misalignment_rad(ax.i, ax.j),
            c.accel_error(ax.i, ax.j), cfg.ekf.accel_misalign_sigma_rad, "arcsec", fsw::kRadToArcsec);
      }
    }
    if constexpr (Layout::has(Block::kGyroMisalign)) {
      const int o = Layout::offset(Block::kGyroMisalign);
      const auto& info = fsw::effect_info(fsw::Effect::kGyroMisalignment);
      for (int k = 0; k < 6; ++k) {
        const auto ax = fsw::kGyroMisalignmentAxes[k];
        add(std::string("gyro_mis.") + info.components[k], o + k, truth.gyro_misalignment_rad(ax.i, ax.j),
            c.gyro_error(ax.i, ax.j), cfg.ekf.gyro_misalign_sigma_rad, "arcsec", fsw::kRadToArcsec);
      }
    }
    const std::size_t k = state_scale.size();
    cov.assign(k * k, 0.0);
    for (std::size_t i = 0; i < k; ++i)
      for (std::size_t j = 0; j < k; ++j)
        cov[i * k + j] = P(state_scale[i].first, state_scale[j].first) * state_scale[i].second * state_scale[j].second;
    return out_s;
  }
};

}  // namespace

namespace {
/// The flight configuration the overlay goes on: --flight-config's, else the shipped file's.
const cfg::FlightConfig& base_flight_config(const MonteCarloConfig& mc) {
  return mc.flight ? *mc.flight : cfg::shipped_flight_config();
}

std::string overlay_name(const sim::Scenario& sc, fsw::FilterModel model) {
  return "the Monte Carlo's scenario overlay (scenario " + sc.name + ", model " + fsw::to_string(model) + ")";
}
}  // namespace

std::optional<cfg::FlightConfig> monte_carlo_flight_config(const std::string& path) {
  if (path.empty()) return std::nullopt;
  cfg::FlightConfig f = cfg::flight_config(path);
  cfg::require_raw_gnss(f, path, "the Monte Carlo simulates raw receiver epochs");
  return f;
}

fsw::ExecutiveConfig executive_config(const sim::Scenario& sc, const MonteCarloConfig& mc) {
  // The flight configuration (shipped, or --filter-config), then the scenario overlay (the header
  // says what it sets).
  fsw::ExecutiveConfig cfg = base_flight_config(mc).app.exec;
  cfg.imu_samples_per_frame = static_cast<int>(sc.imu.rate_hz / cfg.nav_rate_hz);
  cfg.frames_per_ekf = static_cast<int>(std::lround(cfg.nav_rate_hz / sc.gps.rate_hz));
  const sim::ImuErrorSigmas& s = sc.imu.sigmas;
  fsw::EkfConfig& e = cfg.ekf;
  e.pos_sigma_m = std::max(mc.init_pos_sigma_m, 1.0);
  e.vel_sigma_mps = std::max(mc.init_vel_sigma_mps, 0.01);
  // Initial attitude sigma: what self-alignment leaves for the scenario's bias sigmas.
  const double lat = sc.start.lat_deg * fsw::kDegToRad;
  const double g = fsw::normal_gravity_mps2(lat, sc.start.alt_m);
  const double sa = s.accel_bias_ug * fsw::kMicroG_mps2, sg = s.gyro_bias_degph * fsw::kDegPerHourToRadps;
  const double level = sa / g;
  const double up = std::hypot(sg / (fsw::wgs84::omega_ie_radps * std::cos(lat)), level * std::tan(lat));
  e.att_sigma_rad = Vec3(std::max(level, 1e-6), std::max(level, 1e-6), std::max(up, 1e-6));
  const bool paper = sc.imu.errors == sim::ImuErrorSet::kPaper;
  const bool none = sc.imu.errors == sim::ImuErrorSet::kNone;
  e.accel_bias_sigma_mps2 = none ? 1e-7 : std::max(sa, 1e-7);
  e.gyro_bias_sigma_radps = none ? 1e-10 : std::max(sg, 1e-10);
  e.accel_misalign_sigma_rad = paper ? std::max(s.accel_misalignment_arcsec * fsw::kArcsecToRad, 1e-8) : 1e-8;
  e.gyro_misalign_sigma_rad = paper ? std::max(s.gyro_misalignment_arcsec * fsw::kArcsecToRad, 1e-8) : 1e-8;
  e.accel_scale_sigma = paper ? std::max(s.accel_scale_factor_ppm * 1e-6, 1e-9) : 1e-9;
  e.gyro_scale_sigma = paper ? std::max(s.gyro_scale_factor_ppm * 1e-6, 1e-9) : 1e-9;
  e.clock_bias_psd_m2ps = std::max(fsw::clock_bias_psd_m2ps(sc.gps.clock_h0_s), 1e-4);
  e.clock_drift_psd_m2ps3 = std::max(fsw::clock_drift_psd_m2ps3(sc.gps.clock_h_minus2_per_s), 1e-4);
  if (mc.model_gps_errors) {
    // Correlated part as channel states; the white part as measurement noise, at least the shipped
    // file's white noise (which keeps P well conditioned when the simulator adds none).
    const fsw::EkfConfig& shipped = base_flight_config(mc).app.exec.ekf;
    e.range_gm_sigma_m = std::max(sc.gps.pseudorange_gm_sigma_m, 0.01);
    e.range_gm_tau_s = sc.gps.pseudorange_gm_tau_s;
    e.range_rate_gm_sigma_mps = std::max(sc.gps.pseudorange_rate_gm_sigma_mps, 0.001);
    e.range_rate_gm_tau_s = sc.gps.pseudorange_rate_gm_tau_s;
    e.pseudorange_sigma_m = std::max(sc.gps.pseudorange_white_sigma_m, shipped.pseudorange_sigma_m);
    e.pseudorange_rate_sigma_mps = std::max(sc.gps.pseudorange_rate_white_sigma_mps, shipped.pseudorange_rate_sigma_mps);
  } else {
    // The total error as white measurement noise (the paper's plain layouts), with its own floor.
    e.pseudorange_sigma_m = std::max(std::hypot(sc.gps.pseudorange_gm_sigma_m, sc.gps.pseudorange_white_sigma_m), 0.1);
    e.pseudorange_rate_sigma_mps =
        std::max(std::hypot(sc.gps.pseudorange_rate_gm_sigma_mps, sc.gps.pseudorange_rate_white_sigma_mps), 0.005);
  }
  return cfg;
}

fsw::FlightAppConfig flight_app_config(const sim::Scenario& sc, const MonteCarloConfig& mc) {
  fsw::FlightAppConfig c = base_flight_config(mc).app;
  c.exec = executive_config(sc, mc);
  c.init_mode = fsw::InitMode::kGiven;
  c.init_pos_sigma_m = c.exec.ekf.pos_sigma_m;
  c.init_vel_sigma_mps = c.exec.ekf.vel_sigma_mps;
  c.init_att_sigma_rad = c.exec.ekf.att_sigma_rad;
  return c;
}

/// The configuration of one model: the tuned conventional 15-state filter (k15t) takes its raised
/// gyro noise (MonteCarloConfig::tuned15t_*); every other model flies the common configuration.
fsw::FlightAppConfig model_config(const fsw::FlightAppConfig& base, const MonteCarloConfig& mc, fsw::FilterModel model) {
  fsw::FlightAppConfig cfg = base;
  if (model == fsw::FilterModel::k15t) {
    cfg.exec.ekf.arw_rad_per_rts = mc.tuned15t_arw_rad_per_rts;
    cfg.exec.ekf.gyro_bias_rw_radps_per_rts = mc.tuned15t_gyro_bias_rw_radps_per_rts;
  }
  return cfg;
}

void validate_overlay(const sim::Scenario& sc, const MonteCarloConfig& mc) {
  const fsw::FlightAppConfig app_cfg = flight_app_config(sc, mc);
  for (const fsw::FilterModel model : mc.models) {
    const cfg::FlightConfigResult r = cfg::validate(model_config(app_cfg, mc, model), base_flight_config(mc),
                                                    overlay_name(sc, model));
    if (!r.ok) throw std::runtime_error(r.error);
  }
}

fsw::NavState initial_nav_state(const sim::TruthTrack& truth, const sim::ImuErrors& errors, const MonteCarloConfig& mc,
                                std::uint64_t seed) {
  // Initial errors: the attitude that self-alignment leaves for this run's biases (at the start
  // attitude), plus drawn position and velocity errors.
  const sim::TruthSample& t0 = truth.epochs.front();
  const double lat = t0.llh.x();
  const Vec3 phi0 = fsw::predicted_alignment_error(t0.C_b_n * errors.accel_bias_mps2, t0.C_b_n * errors.gyro_bias_radps,
                                                   lat, fsw::normal_gravity_mps2(lat, t0.llh.z()));
  sim::Rng rng(seed, kStreamInitialErrors);
  Vec3 dp, dv;
  for (int i = 0; i < 3; ++i) dp(i) = rng.normal() * mc.init_pos_sigma_m;
  for (int i = 0; i < 3; ++i) dv(i) = rng.normal() * mc.init_vel_sigma_mps;
  fsw::NavState init;
  init.t_s = t0.t_s + errors.time_offset_s;
  init.llh = t0.llh + fsw::llh_delta_from_enu(t0.llh, dp);
  init.vel_enu_mps = t0.vel_enu_mps + dv;
  init.q_b_n = fsw::quat_from_rotvec(-phi0) * fsw::Quat(t0.C_b_n);
  init.q_b_n.normalize();
  return init;
}

RunResult run_one(const sim::Scenario& sc, const sim::TruthTrack& truth, const std::vector<sim::AlmanacEntry>& almanac,
                  const MonteCarloConfig& mc, int run) {
  RunResult res;
  res.run = run;
  res.seed = sc.seed + static_cast<std::uint64_t>(run);
  const std::uint64_t seed = res.seed;
  sim::SensorStream stream(sc, truth, almanac, seed);
  const sim::ImuErrors& errors = stream.imu_errors();
  const fsw::NavState init = initial_nav_state(truth, errors, mc, seed);

  const fsw::FlightAppConfig app_cfg = flight_app_config(sc, mc);
  const fsw::ExecutiveConfig& cfg = app_cfg.exec;
  const std::size_t n_models = mc.models.size();
  res.epochs.assign(n_models, {});
  std::vector<std::unique_ptr<ModelRunner>> runners;
  for (std::size_t m = 0; m < n_models; ++m) {
    const bool is15 = mc.models[m] == fsw::FilterModel::k15;
    if (mc.models[m] == fsw::FilterModel::k15c || mc.models[m] == fsw::FilterModel::k15t)
      runners.push_back(std::unique_ptr<ModelRunner>(new FlightAppRunner<fsw::Layout15Conv>));
    else if (mc.model_gps_errors)
      runners.push_back(is15 ? std::unique_ptr<ModelRunner>(new FlightAppRunner<fsw::Layout15Full>)
                             : std::unique_ptr<ModelRunner>(new FlightAppRunner<fsw::Layout24Full>));
    else
      runners.push_back(is15 ? std::unique_ptr<ModelRunner>(new FlightAppRunner<fsw::Layout15>)
                             : std::unique_ptr<ModelRunner>(new FlightAppRunner<fsw::Layout24>));
    res.epochs[m].reserve(truth.epochs.size());
    runners[m]->records = &res.epochs[m];
    const fsw::FlightAppConfig model_cfg = model_config(app_cfg, mc, mc.models[m]);
    if (runners[m]->init(model_cfg) != fsw::Status::kOk)  // validate_overlay() refused this before the runs
      throw std::runtime_error(cfg::validate(model_cfg, base_flight_config(mc), overlay_name(sc, mc.models[m])).error);
  }

  // Every model reads the one sensor stream's events (sim/sensor_stream.hpp): the almanac, then
  // the IMU samples with each raw epoch right after the sample of its time. The runs start from
  // their given initial state once the almanac is in. The events are read FrameEvents::kFrames
  // minor frames' worth (imu_samples_per_frame IMU samples each: the stream's read-ahead; each
  // model's minor frames are its frame builder's) at a time into a batch (the sensor models do not
  // depend on the flight software), which every model's driver then runs over, so the clock that
  // splits the run's time between the models and the flight software is read three times a batch.
  const int spf = cfg.imu_samples_per_frame;
  auto batch = std::make_unique<FrameEvents>();  // 264 events of 864 B: not on the stack
  fsw::EventBatch<FrameEvents::kMaxEvents>& evs = batch->events;
  Clock::duration d_sim{}, d_mech{}, d_ekf{};
  double frames_mech = 0.0, frames_ekf = 0.0;  // minor frames in the batches without / with a 1 Hz group
  for (std::size_t k = 0, n_alm = stream.almanac().size(); k < n_alm;) {  // delivered first, at power-up
    evs.clear();
    while (k < n_alm && !evs.full() && stream.next(*evs.slot())) {
      evs.commit();
      ++k;
    }
    if (evs.size() == 0) break;
    for (auto& r : runners) r->drive(*batch);
  }
  for (auto& r : runners)
    if (r->start(init) != fsw::Status::kOk) throw std::runtime_error("flight application start failed");
  for (;;) {
    // SIGINT/SIGTERM: a run stops within a batch of 8 frames (run_many then discards it and throws). Under
    // mpirun the launcher kills the ranks 1 s after forwarding the signal, so a rank must not wait
    // for the end of a long run to notice it (docs/faults.md).
    if (interrupted()) break;
    const auto c0 = Clock::now();
    evs.clear();
    int n_imu = 0;
    while (!evs.full() && n_imu < FrameEvents::kFrames * spf && stream.next(*evs.slot())) {
      const fsw::InputEvent& ev = *evs.slot();
      if (ev.kind == fsw::InputEvent::Kind::kImu) ++n_imu;
      if (ev.kind == fsw::InputEvent::Kind::kGnssRaw)
        batch->epoch_truth[static_cast<std::size_t>(evs.size())] = stream.epoch_truth();
      evs.commit();
    }
    if (evs.size() == 0) break;
    const auto c1 = Clock::now();
    d_sim += c1 - c0;
    bool released = false;
    for (auto& r : runners) released |= r->drive(*batch);
    (released ? d_ekf : d_mech) += Clock::now() - c1;
    (released ? frames_ekf : frames_mech) += static_cast<double>(n_imu) / spf;
  }
  for (auto& r : runners) r->finish();
  res.sensors.assign(n_models, {});
  res.sensor_cov.assign(n_models, {});
  res.health.assign(n_models, {});
  for (std::size_t m = 0; m < n_models; ++m) {
    res.sensors[m] = runners[m]->sensors(errors, cfg, res.sensor_cov[m]);
    res.health[m] = runners[m]->health();
  }
  // The batches with a 1 Hz group also ran their frames' 200 Hz work: charge that to the
  // mechanization at the cost per frame of the batches without one.
  const double mech_per_frame = std::chrono::duration<double>(d_mech).count() / std::max(1.0, frames_mech);
  res.wall_sim_s = std::chrono::duration<double>(d_sim).count();
  res.wall_mech_s = std::chrono::duration<double>(d_mech).count() + mech_per_frame * frames_ekf;
  res.wall_ekf_s = std::max(0.0, std::chrono::duration<double>(d_ekf).count() - mech_per_frame * frames_ekf);
  return res;
}

std::vector<RunResult> run_many(const sim::Scenario& sc, const sim::TruthTrack& truth,
                                const std::vector<sim::AlmanacEntry>& almanac, const MonteCarloConfig& mc) {
  validate_overlay(sc, mc);  // the overlaid configuration meets the flight software's rules, or no run starts
  std::vector<RunResult> results(static_cast<std::size_t>(std::max(mc.runs, 0)));
  int threads = mc.threads > 0 ? mc.threads : static_cast<int>(std::thread::hardware_concurrency());
  threads = std::max(1, std::min(threads, mc.runs));
  std::atomic<int> next{0};
  std::vector<std::string> errors(static_cast<std::size_t>(threads));
  std::atomic<int> done{0};
  auto worker = [&](int w) {
    try {
      for (int k = next++; k < mc.runs && !interrupted(); k = next++) {  // docs/faults.md: SIGINT/SIGTERM
        results[static_cast<std::size_t>(k)] = run_one(sc, truth, almanac, mc, mc.first_run + k);
        ++done;
      }
    } catch (const std::exception& e) {
      errors[static_cast<std::size_t>(w)] = e.what();
      next = mc.runs;
    }
  };
  std::vector<std::thread> pool;
  for (int w = 1; w < threads; ++w) pool.emplace_back(worker, w);
  worker(0);
  for (auto& t : pool) t.join();
  for (const auto& e : errors)
    if (!e.empty()) throw std::runtime_error(e);
  throw_if_interrupted("Monte Carlo stopped after " + std::to_string(done.load()) + " of " + std::to_string(mc.runs) +
                       " runs; no results written");
  return results;
}

std::array<double, 2> chi2_mean_bounds(int dof, int runs) {
  // The sum of runs chi2(dof) variables is chi2(dof runs); its 2.5% and 97.5% quantiles / runs.
  const double k = static_cast<double>(dof) * runs;
  return {fsw::chi2_quantile_wilson_hilferty(k, -1.959963985) / runs,
          fsw::chi2_quantile_wilson_hilferty(k, 1.959963985) / runs};
}

ModelStats reduce(const std::vector<RunResult>& results, std::size_t mi, fsw::FilterModel model, const sim::TruthTrack& truth) {
  ModelStats s;
  s.model = model;
  s.runs = static_cast<int>(results.size());
  if (results.empty()) return s;
  const std::size_t ne = results.front().epochs[mi].size();
  const double n = static_cast<double>(results.size());
  s.t_s.resize(ne);
  s.turning.resize(ne);
  s.att_mean_rad.assign(ne, {});
  s.att_std_rad.assign(ne, {});
  s.att_filter_sigma_rad.assign(ne, {});
  s.pos_rms_m.assign(ne, 0.0);
  s.vel_rms_mps.assign(ne, 0.0);
  s.pos_filter_sigma_m.assign(ne, 0.0);
  s.vel_filter_sigma_mps.assign(ne, 0.0);
  s.nees_mean.assign(ne, 0.0);
  s.nees_att_mean.assign(ne, 0.0);
  for (std::size_t e = 0; e < ne; ++e) {
    const sim::TruthSample& t = truth.epochs[e + 1];
    s.t_s[e] = t.t_s;
    s.turning[e] = t.phase.turning ? 1 : 0;
    std::array<double, 3> sum{}, sum2{}, sig{};
    double p2 = 0, v2 = 0, ps = 0, vs = 0, nees = 0, nees_att = 0;
    for (const RunResult& r : results) {  // run order: deterministic
      const EpochRecord& x = r.epochs[mi][e];
      for (int i = 0; i < 3; ++i) {
        sum[i] += x.resid_att_rad[i];
        sum2[i] += static_cast<double>(x.resid_att_rad[i]) * x.resid_att_rad[i];
        sig[i] += x.sigma_att_rad[i];
      }
      for (int i = 0; i < 2; ++i) {
        p2 += static_cast<double>(x.pos_err_m[i]) * x.pos_err_m[i];
        v2 += static_cast<double>(x.vel_err_mps[i]) * x.vel_err_mps[i];
        ps += static_cast<double>(x.sigma_pos_m[i]) * x.sigma_pos_m[i];
        vs += static_cast<double>(x.sigma_vel_mps[i]) * x.sigma_vel_mps[i];
      }
      nees += x.nees;
      nees_att += x.nees_att;
    }
    for (int i = 0; i < 3; ++i) {
      const double m = sum[i] / n;
      s.att_mean_rad[e][i] = m;
      s.att_std_rad[e][i] = n > 1 ? std::sqrt(std::max(0.0, (sum2[i] - n * m * m) / (n - 1))) : 0.0;
      s.att_filter_sigma_rad[e][i] = sig[i] / n;
    }
    s.pos_rms_m[e] = std::sqrt(p2 / n);
    s.vel_rms_mps[e] = std::sqrt(v2 / n);
    s.pos_filter_sigma_m[e] = std::sqrt(ps / n);
    s.vel_filter_sigma_mps[e] = std::sqrt(vs / n);
    s.nees_mean[e] = nees / n;
    s.nees_att_mean[e] = nees_att / n;
  }
  // Consistency: averaged after the first minute (the initial transient of the clock and position).
  s.nees_from_s = 60.0;
  double acc = 0, acc_att = 0;
  int cnt = 0;
  for (std::size_t e = 0; e < ne; ++e)
    if (s.t_s[e] >= s.nees_from_s) {
      acc += s.nees_mean[e];
      acc_att += s.nees_att_mean[e];
      ++cnt;
    }
  // docs/faults.md: a flight shorter than the window has no NEES; NaN (JSON null, "not measured"), never
  // a 0 that would sit inside the bounds as if measured.
  s.nees_epochs = cnt;
  s.mean_nees = cnt ? acc / cnt : std::numeric_limits<double>::quiet_NaN();
  s.mean_nees_att = cnt ? acc_att / cnt : std::numeric_limits<double>::quiet_NaN();
  s.nees_bounds = chi2_mean_bounds(9, s.runs);
  s.nees_att_bounds = chi2_mean_bounds(3, s.runs);
  // Sensor residuals: RMS across runs and the mean filter sigma.
  s.sensors = results.front().sensors[mi];
  for (std::size_t k = 0; k < s.sensors.size(); ++k) {
    double r2 = 0, sg = 0;
    for (const RunResult& r : results) {
      r2 += r.sensors[mi][k].residual * r.sensors[mi][k].residual;
      sg += r.sensors[mi][k].sigma;
    }
    s.sensors[k].residual = std::sqrt(r2 / n);
    s.sensors[k].sigma = sg / n;
  }
  s.sensor_cov.assign(results.front().sensor_cov[mi].size(), 0.0);
  for (const RunResult& r : results) {
    for (std::size_t k = 0; k < s.sensor_cov.size(); ++k) s.sensor_cov[k] += r.sensor_cov[mi][k] / n;
    std::vector<double> res(r.sensors[mi].size());
    for (std::size_t k = 0; k < res.size(); ++k) res[k] = r.sensors[mi][k].residual;
    s.sensor_residuals.push_back(std::move(res));
  }
  for (const RunResult& r : results) {
    const fsw::ExecutiveHealth& h = r.health[mi];
    fsw::ExecutiveHealth& a = s.health;
    fsw::add_health_counters(a, h);
    a.ekf.cov_checks += h.ekf.cov_checks;
    a.ekf.cov_repairs += h.ekf.cov_repairs;
    a.ekf.nonfinite_rejected += h.ekf.nonfinite_rejected;
    a.ekf.divergence_windows += h.ekf.divergence_windows;
    a.ekf.gating_runaway_epochs += h.ekf.gating_runaway_epochs;
    a.ekf.resets += h.ekf.resets;
  }
  return s;
}

std::vector<MisalignmentCombination> misalignment_combinations(const ModelStats& s) {
  std::vector<std::size_t> idx;  // the misalignment states among the sensor states
  for (std::size_t k = 0; k < s.sensors.size(); ++k)
    if (s.sensors[k].estimated && s.sensors[k].name.find("_mis.") != std::string::npos) idx.push_back(k);
  std::vector<MisalignmentCombination> out;
  const std::size_t ks = s.sensors.size(), m = idx.size();
  if (m == 0 || s.sensor_cov.size() != ks * ks) return out;
  // Normalised covariance D0^-1 P D0^-1 (D0: initial sigmas); its eigenvalues are the squared
  // ratios final / initial sigma along each direction.
  Eigen::MatrixXd Pn(m, m);
  for (std::size_t i = 0; i < m; ++i)
    for (std::size_t j = 0; j < m; ++j)
      Pn(i, j) = s.sensor_cov[idx[i] * ks + idx[j]] / (s.sensors[idx[i]].initial_sigma * s.sensors[idx[j]].initial_sigma);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Pn);
  for (std::size_t e = 0; e < m; ++e) {  // ascending eigenvalues: most reduced first
    Eigen::VectorXd v = eig.eigenvectors().col(static_cast<Eigen::Index>(e));
    Eigen::Index big = 0;
    v.cwiseAbs().maxCoeff(&big);
    if (v(big) < 0.0) v = -v;  // sign convention: the largest coefficient positive
    MisalignmentCombination c;
    // Direction in physical units: u_i = v_i / sigma0_i (normalised), sigma along it.
    Eigen::VectorXd u(m);
    for (std::size_t i = 0; i < m; ++i) u(i) = v(i) / s.sensors[idx[i]].initial_sigma;
    u /= u.norm();
    double var0 = 0.0, var = 0.0;
    for (std::size_t i = 0; i < m; ++i)
      for (std::size_t j = 0; j < m; ++j) {
        const double pij = s.sensor_cov[idx[i] * ks + idx[j]];
        var += u(i) * u(j) * pij;
        if (i == j) var0 += u(i) * u(i) * s.sensors[idx[i]].initial_sigma * s.sensors[idx[i]].initial_sigma;
      }
    c.initial_sigma = std::sqrt(var0);
    c.final_sigma = std::sqrt(std::max(0.0, var));
    double r2 = 0.0;
    for (const auto& res : s.sensor_residuals) {
      double p = 0.0;
      for (std::size_t i = 0; i < m; ++i) p += u(i) * res[idx[i]];
      r2 += p * p;
    }
    c.rms_residual = s.sensor_residuals.empty() ? 0.0 : std::sqrt(r2 / static_cast<double>(s.sensor_residuals.size()));
    c.observable = c.final_sigma <= kObservableSigmaRatio * c.initial_sigma;
    char buf[64];
    for (std::size_t i = 0; i < m; ++i) {
      if (std::abs(u(i)) < 0.1) continue;
      c.terms.emplace_back(s.sensors[idx[i]].name, u(i));
      std::snprintf(buf, sizeof buf, "%s%+.2f %s", c.label.empty() ? "" : " ", u(i), s.sensors[idx[i]].name.c_str());
      c.label += buf;
    }
    out.push_back(std::move(c));
  }
  return out;
}

void write_stats_csv(const ModelStats& s, const std::string& path) {
  TextOutput out(path);  // docs/faults.md: complete or not there
  std::ostream& f = out.os();
  f << "t_s,turning,mean_E_deg,mean_N_deg,mean_U_deg,std_E_deg,std_N_deg,std_U_deg,filter_sigma_E_deg,"
       "filter_sigma_N_deg,filter_sigma_U_deg,pos_rms_m,pos_filter_sigma_m,vel_rms_mps,vel_filter_sigma_mps,nees,"
       "nees_att\n";
  f.precision(9);
  const double d = fsw::kRadToDeg;
  for (std::size_t e = 0; e < s.t_s.size(); ++e) {
    f << s.t_s[e] << "," << s.turning[e];
    for (int i = 0; i < 3; ++i) f << "," << s.att_mean_rad[e][i] * d;
    for (int i = 0; i < 3; ++i) f << "," << s.att_std_rad[e][i] * d;
    for (int i = 0; i < 3; ++i) f << "," << s.att_filter_sigma_rad[e][i] * d;
    f << "," << s.pos_rms_m[e] << "," << s.pos_filter_sigma_m[e] << "," << s.vel_rms_mps[e] << ","
      << s.vel_filter_sigma_mps[e] << "," << s.nees_mean[e] << "," << s.nees_att_mean[e] << "\n";
  }
  out.commit();
}

}  // namespace tools
