#include "sim/sensor_stream.hpp"

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

TruthTrack TruthTrack::generate(const Scenario& sc) {
  const auto t0 = std::chrono::steady_clock::now();
  std::string err;
  auto motion = FlightMotion::create(sc, err);
  if (!motion) throw std::runtime_error(err);
  TruthTrack tt;
  tt.samples_per_epoch = imu_samples_per_epoch(sc);
  const long long n = std::llround(sc.duration_s * sc.imu.rate_hz);
  tt.imu.reserve(static_cast<std::size_t>(n));
  tt.epochs.reserve(static_cast<std::size_t>(n / tt.samples_per_epoch + 1));
  TruthGenerator gen(*motion, sc.imu.rate_hz);
  tt.epochs.push_back(gen.current());
  for (long long k = 1; k <= n; ++k) {
    const TruthSample& s = gen.next();
    tt.imu.push_back({s.t_s, s.dt_s, s.dtheta_rad, s.dv_mps});
    if (k % tt.samples_per_epoch == 0) tt.epochs.push_back(s);
  }
  tt.generate_wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return tt;
}

SensorStream::SensorStream(const Scenario& sc, std::uint64_t seed) : sc_(sc) {
  std::string err;
  motion_ = FlightMotion::create(sc_, err);
  if (!motion_) throw std::runtime_error(err);
  const AlmanacParseResult alm = parse_yuma_file(almanac_path(sc_.gps));
  if (!alm.ok()) throw std::runtime_error(alm.error);
  samples_per_epoch_ = imu_samples_per_epoch(sc_);
  n_samples_ = std::llround(sc_.duration_s * sc_.imu.rate_hz);
  gen_ = std::make_unique<TruthGenerator>(*motion_, sc_.imu.rate_hz);
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
  n_samples_ = static_cast<long long>(track.imu.size());
  epoch_truth_ = &track.epochs.front();
  track_sample_ = track.epochs.front();
  imu_ = std::make_unique<ImuModel>(draw_imu_errors(sc_.imu, sc_.effects, seed), seed);
  gps_ = std::make_unique<GpsModel>(sc_.gps, almanac, sc_.effects, seed);
}

SensorStream::~SensorStream() = default;

const TruthSample& SensorStream::next_truth() {
  if (gen_) return gen_->next();
  const TruthTrack::Increment& inc = track_->imu[static_cast<std::size_t>(sample_)];
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
    epoch_truth_ = gen_ ? &gen_->current()
                        : &track_->epochs[static_cast<std::size_t>(sample_ / samples_per_epoch_)];
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
