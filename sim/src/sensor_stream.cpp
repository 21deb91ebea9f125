#include "sim/sensor_stream.hpp"

#include <atomic>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "sim/almanac.hpp"

namespace sim {

int imu_samples_per_epoch(const Scenario& sc) {
  const double spe = sc.imu.rate_hz / sc.gps.rate_hz;
  if (!(std::abs(spe - std::round(spe)) <= 1e-9) || spe < 1.0)
    throw std::runtime_error("the GPS rate must divide the IMU rate");
  return static_cast<int>(std::lround(spe));
}

struct TruthTrack::Progress {
  std::unique_ptr<FlightMotion> motion;
  std::unique_ptr<TruthPipeline> gen;
  long long written = 0;              ///< fill()'s own count (its thread only)
  std::atomic<long long> ready{0};    ///< samples published to readers
  mutable std::atomic<bool> stop{false};
  std::atomic<bool> stopped{false};   ///< fill() returned before the end: waits past ready fail
  /// fill() returns before the end: every wait past ready wakes (a new value) and fails.
  void mark_stopped() {
    stopped.store(true, std::memory_order_release);
    ready.store(-1, std::memory_order_release);
    ready.notify_all();
  }
};

TruthTrack TruthTrack::prepare(const Scenario& sc) { return prepare(sc, TruthThread::kReader); }

TruthTrack TruthTrack::prepare(const Scenario& sc, TruthThread where) {
  std::string err;
  auto p = std::make_shared<Progress>();
  p->motion = FlightMotion::create(sc, err);
  if (!p->motion) throw std::runtime_error(err);
  TruthTrack tt;
  tt.samples_per_epoch = imu_samples_per_epoch(sc);
  const long long n = std::llround(sc.duration_s * sc.imu.rate_hz);
  tt.imu.resize(static_cast<std::size_t>(n));
  tt.epochs.resize(static_cast<std::size_t>(n / tt.samples_per_epoch + 1));
  p->gen = std::make_unique<TruthPipeline>(*p->motion, sc.imu.rate_hz, n, where);
  tt.epochs[0] = p->gen->current();
  if (n == 0) tt.last = p->gen->current();
  tt.progress = std::move(p);
  return tt;
}

void TruthTrack::fill() {
  Progress& p = *progress;
  const auto t0 = std::chrono::steady_clock::now();
  const long long n = samples();
  for (long long k = p.written + 1; k <= n; ++k) {
    const TruthSample& s = p.gen->next();
    imu[static_cast<std::size_t>(k - 1)] = {s.t_s, s.dt_s, s.dtheta_rad, s.dv_mps};
    if (k % samples_per_epoch == 0) epochs[static_cast<std::size_t>(k / samples_per_epoch)] = s;
    if (k == n) last = s;
    p.written = k;
    if (k % kPublishSamples == 0 || k == n) {
      p.ready.store(k, std::memory_order_release);
      p.ready.notify_all();
      if (p.stop.load(std::memory_order_relaxed) && k < n) {
        p.mark_stopped();
        break;
      }
    }
  }
  generate_wall_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void TruthTrack::stop_fill() const {
  if (progress) progress->stop.store(true, std::memory_order_relaxed);
}

long long TruthTrack::wait_for(long long k) const {
  if (!progress) return samples();
  const Progress& p = *progress;
  long long r = p.ready.load(std::memory_order_acquire);
  while (r <= k) {
    if (p.stopped.load(std::memory_order_acquire))
      throw std::runtime_error("the truth's integration stopped before sample " + std::to_string(k));
    p.ready.wait(r, std::memory_order_acquire);
    r = p.ready.load(std::memory_order_acquire);
  }
  return r;
}

TruthTrack TruthTrack::generate(const Scenario& sc) {
  TruthTrack tt = prepare(sc, TruthThread::kOwn);  // nothing reads it meanwhile
  tt.fill();
  tt.progress.reset();  // complete: no reader waits
  return tt;
}

TruthFillThread::TruthFillThread(TruthTrack& track) : track_(track), thread_([&track] { track.fill(); }) {}

TruthFillThread::~TruthFillThread() {
  if (!thread_.joinable()) return;
  track_.stop_fill();
  thread_.join();
}

void TruthFillThread::complete() {
  if (thread_.joinable()) thread_.join();
}

SensorStream::SensorStream(const Scenario& sc, std::uint64_t seed, TruthThread truth) : sc_(sc) {
  std::string err;
  motion_ = FlightMotion::create(sc_, err);
  if (!motion_) throw std::runtime_error(err);
  const AlmanacParseResult alm = parse_yuma_file(almanac_path(sc_.gps));
  if (!alm.ok()) throw std::runtime_error(alm.error);
  samples_per_epoch_ = imu_samples_per_epoch(sc_);
  n_samples_ = std::llround(sc_.duration_s * sc_.imu.rate_hz);
  gen_ = std::make_unique<TruthPipeline>(*motion_, sc_.imu.rate_hz, n_samples_, truth);
  epoch_truth_ = &gen_->current();
  imu_ = std::make_unique<ImuModel>(draw_imu_errors(sc_.imu, sc_.effects, seed), seed);
  gps_ = std::make_unique<GpsModel>(sc_.gps, *alm.almanac, sc_.effects, seed);
}

SensorStream::SensorStream(const Scenario& sc, const TruthTrack& track, const std::vector<AlmanacEntry>& almanac,
                           std::uint64_t seed)
    : sc_(sc), track_(&track) {
  samples_per_epoch_ = imu_samples_per_epoch(sc_);
  if (track.samples_per_epoch != samples_per_epoch_ || track.epochs.empty())
    throw std::runtime_error("the truth track was not generated for this scenario");
  n_samples_ = track.samples();
  epoch_truth_ = &track.epochs.front();
  track_sample_ = track.epochs.front();
  imu_ = std::make_unique<ImuModel>(draw_imu_errors(sc_.imu, sc_.effects, seed), seed);
  gps_ = std::make_unique<GpsModel>(sc_.gps, almanac, sc_.effects, seed);
}

SensorStream::~SensorStream() = default;

const TruthSample& SensorStream::next_truth() {
  if (gen_) return gen_->next();
  if (sample_ >= track_ready_) track_ready_ = track_->wait_for(sample_);  // a track being generated
  const TruthTrack::Increment& inc = track_->increment(sample_);
  track_sample_.t_s = inc.t_s;
  track_sample_.dt_s = inc.dt_s;
  track_sample_.dtheta_rad = inc.dtheta_rad;
  track_sample_.dv_mps = inc.dv_mps;
  return track_sample_;
}

bool SensorStream::next(fsw::InputEvent& ev, TruthSample* truth) {
  if (almanac_sent_ < almanac().size()) {
    ev.kind = fsw::InputEvent::Kind::kAlmanac;
    ev.t_s = epoch_truth_->t_s;  // received at power-up, before the first IMU sample
    ev.almanac = almanac()[almanac_sent_++];
    ev.imu_counter = -1;
    return true;
  }
  if (epoch_due_) {
    epoch_due_ = false;
    epoch_truth_ = gen_ ? &gen_->current() : &track_->epoch(sample_ / samples_per_epoch_);
    gps_->measure(*epoch_truth_, epoch_);
    ev.kind = fsw::InputEvent::Kind::kGnssRaw;
    gps_->raw(epoch_, ev.gnss);
    ev.t_s = ev.gnss.t_s;
    ev.imu_counter = -1;
    if (truth != nullptr) *truth = *epoch_truth_;
    return true;
  }
  if (sample_ >= n_samples_) return false;
  const TruthSample& t = next_truth();
  ++sample_;
  ev.kind = fsw::InputEvent::Kind::kImu;
  ev.imu = imu_->measure(t);
  ev.t_s = ev.imu.t_s;
  ev.imu_counter = -1;
  if (truth != nullptr) *truth = t;
  epoch_due_ = sample_ % samples_per_epoch_ == 0;
  return true;
}

const TruthSample* SensorStream::full_truth() const {
  if (gen_) return &gen_->current();
  if (sample_ == n_samples_) return &track_->last;
  if (sample_ % samples_per_epoch_ == 0) return &track_->epoch(sample_ / samples_per_epoch_);
  return nullptr;
}

bool SensorStream::next(SensorStep& step) {
  almanac_sent_ = almanac().size();
  step.imu.clear();
  step.has_epoch = false;
  fsw::InputEvent ev;
  while (next(ev)) {
    if (ev.kind == fsw::InputEvent::Kind::kImu) {
      step.imu.push_back(ev.imu);
    } else if (ev.kind == fsw::InputEvent::Kind::kGnssRaw) {
      step.has_epoch = true;
      step.epoch = ev.gnss;
      return true;
    }
  }
  return !step.imu.empty();
}

}  // namespace sim
