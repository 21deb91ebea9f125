#include "tools/sensor_stream.hpp"

#include <cmath>
#include <stdexcept>

#include "sim/almanac.hpp"

namespace tools {

SensorStream::SensorStream(const sim::Scenario& sc, std::uint64_t seed) : sc_(sc) {
  std::string err;
  motion_ = sim::FlightMotion::create(sc_, err);
  if (!motion_) throw std::runtime_error(err);
  const sim::AlmanacParseResult alm = sim::parse_yuma_file(sim::almanac_path(sc_.gps));
  if (!alm.ok()) throw std::runtime_error(alm.error);
  almanac_ = *alm.almanac;
  const double spe = sc_.imu.rate_hz / sc_.gps.rate_hz;
  if (std::abs(spe - std::round(spe)) > 1e-9 || spe < 1.0) throw std::runtime_error("the GPS rate must divide the IMU rate");
  samples_per_epoch_ = static_cast<int>(std::lround(spe));
  n_samples_ = std::llround(sc_.duration_s * sc_.imu.rate_hz);
  gen_ = std::make_unique<sim::TruthGenerator>(*motion_, sc_.imu.rate_hz);
  imu_ = std::make_unique<sim::ImuModel>(sim::draw_imu_errors(sc_.imu, sc_.effects, seed), seed);
  gps_ = std::make_unique<sim::GpsModel>(sc_.gps, almanac_, sc_.effects, seed);
}

bool SensorStream::next(fsw::InputEvent& ev, sim::TruthSample* truth) {
  if (almanac_sent_ < almanac_.size()) {
    ev.kind = fsw::InputEvent::Kind::kAlmanac;
    ev.t_s = gen_->current().t_s;  // received at power-up, before the first IMU sample
    ev.almanac = almanac_[almanac_sent_++];
    return true;
  }
  if (epoch_due_) {
    epoch_due_ = false;
    fsw::GnssEpoch e;
    gps_->measure(gen_->current(), e);
    ev.kind = fsw::InputEvent::Kind::kGnssRaw;
    gps_->raw(e, ev.gnss);
    ev.t_s = ev.gnss.t_s;
    return true;
  }
  if (sample_ >= n_samples_) return false;
  const sim::TruthSample& t = gen_->next();
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
  almanac_sent_ = almanac_.size();
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

}  // namespace tools
