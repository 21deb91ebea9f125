#include "tools/can_stream.hpp"

#include <cmath>
#include <stdexcept>

#include "sim/almanac.hpp"
#include "sim/gps_model.hpp"
#include "sim/imu_model.hpp"
#include "sim/trajectory.hpp"

namespace tools {

struct SensorStream::Impl {
  std::unique_ptr<sim::FlightMotion> motion;
  std::unique_ptr<sim::TruthGenerator> gen;
  std::unique_ptr<sim::ImuModel> imu;
  std::unique_ptr<sim::GpsModel> gps;
  int spe = 1;
  long long n_total = 0;
  long long k = 0;
};

SensorStream::SensorStream(const sim::Scenario& sc) : p_(std::make_unique<Impl>()) {
  std::string err;
  p_->motion = sim::FlightMotion::create(sc, err);
  if (!p_->motion) throw std::runtime_error(err);
  const double spe = sc.imu.rate_hz / sc.gps.rate_hz;
  if (std::abs(spe - std::round(spe)) > 1e-9 || spe < 1.0) throw std::runtime_error("the GPS rate must divide the IMU rate");
  p_->spe = static_cast<int>(std::lround(spe));
  p_->n_total = std::llround(sc.duration_s * sc.imu.rate_hz);
  const sim::AlmanacParseResult alm = sim::parse_yuma_file(sim::almanac_path(sc.gps));
  if (!alm.ok()) throw std::runtime_error(alm.error);
  p_->gen = std::make_unique<sim::TruthGenerator>(*p_->motion, sc.imu.rate_hz);
  p_->imu = std::make_unique<sim::ImuModel>(sim::draw_imu_errors(sc.imu, sc.effects, sc.seed), sc.seed);
  p_->gps = std::make_unique<sim::GpsModel>(sc.gps, *alm.almanac, sc.effects, sc.seed);
}

SensorStream::~SensorStream() = default;

bool SensorStream::next(SensorStep& step) {
  step.imu.clear();
  step.has_epoch = false;
  if (p_->k >= p_->n_total) return false;
  for (int i = 0; i < p_->spe && p_->k < p_->n_total; ++i) {
    const sim::TruthSample& s = p_->gen->next();
    ++p_->k;
    step.imu.push_back(p_->imu->measure(s));
    if (p_->k % p_->spe == 0) {
      fsw::GnssEpoch e;
      p_->gps->measure(s, e);
      p_->gps->raw(e, step.epoch);
      step.has_epoch = true;
    }
  }
  return true;
}

const std::vector<fsw::GpsAlmanac>& SensorStream::almanac() const { return p_->gps->almanac(); }
int SensorStream::samples_per_epoch() const { return p_->spe; }

}  // namespace tools
