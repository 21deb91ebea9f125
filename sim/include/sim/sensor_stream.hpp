// The simulated sensors as the flight software receives them: truth -> the IMU and GPS receiver
// models -> fsw::InputEvent, in arrival order. Every simulated run reads this one stream: SIL
// (`sdins sil`), the bus simulator (`sdins bus-sim`, HIL), `sdins sim --log`, the Monte Carlo and
// `sdins paper`, the timing audit and the diagnosis's simulated flights. For the same scenario and
// seed they all see the same events in the same order.
//
// The order (one definition, docs/architecture-data-path.md): the almanac first, one element per
// event (as a receiver delivers it at power-up), then the IMU samples at the IMU rate and, right
// after the IMU sample of each GPS epoch time t, the receiver's raw epoch of time t. A receiver's
// measurement of time t cannot reach the flight software before the IMU sample of the same
// instant: it is formed at t and sent after it. The flight software therefore releases the EKF
// step of epoch t at the first minor frame after t and aligns the solution to t (fsw/executive.hpp).
//
// The truth comes from one of two sources, with the same values:
//   - a TruthGenerator run alongside the stream (SensorStream(scenario, seed)), or
//   - a TruthTrack generated once and shared by many streams (the Monte Carlo's runs differ only
//     in their sensor errors, so the seed-independent truth is integrated once).
#pragma once

#include <cstdint>
#include <memory>
#include <thread>
#include <vector>

#include "fsw/gps_orbit.hpp"
#include "fsw/input_event.hpp"
#include "fsw/strapdown.hpp"
#include "hal/large_array.hpp"
#include "sim/gps_model.hpp"
#include "sim/imu_model.hpp"
#include "sim/scenario.hpp"
#include "sim/trajectory.hpp"
#include "sim/truth_pipeline.hpp"

namespace sim {

/// The seed-independent truth of a scenario: IMU increments at the IMU rate and full truth at
/// every GNSS epoch and at the last sample.
struct TruthTrack {
  struct Increment {
    double t_s;
    double dt_s;
    fsw::Vec3 dtheta_rad;
    fsw::Vec3 dv_mps;
  };
  hal::LargeVector<Increment> imu;  ///< samples 1..n (the sample at t = 0 has no increment); huge pages
  std::vector<TruthSample> epochs;  ///< truth at t = k / gps_rate, k = 0..; epochs[0] is t = 0
  TruthSample last;                 ///< the full truth of sample n (t = duration), once it is written
  int samples_per_epoch = 1000;     ///< IMU samples between GNSS epochs
  double generate_wall_s = 0.0;     ///< the integration's own wall time (fill())
  /// The whole track before it returns, its integration on a second thread (TruthPipeline).
  /// Throws std::runtime_error for a scenario it cannot fly (e.g. rates that do not divide).
  static TruthTrack generate(const Scenario& sc);

  // Generated while it is read: prepare() sizes the arrays and writes epochs[0]; fill(), on its
  // own thread, integrates the rest and publishes how far it got every kPublishSamples samples;
  // a stream reading sample k waits in wait_for(k) (blocked, not spinning) until it is written.
  // The values are generate()'s, whatever the threads' timing. A Monte Carlo's runs start while
  // the truth they share is integrated instead of after it (docs/performance.md).
  static constexpr long long kPublishSamples = 1000;
  struct Progress;
  std::shared_ptr<Progress> progress;  ///< null: the track is complete (generate())
  /// Throws std::runtime_error like generate(). The integration and the evaluations on fill()'s
  /// one thread: its readers use the other core (with the integration on a third thread a one-run
  /// Monte Carlo took 1.22 times as long: docs/performance.md, "The truth on two threads").
  static TruthTrack prepare(const Scenario& sc);
  /// Integrates every sample not yet written, publishing progress; returns early when stopped.
  void fill();
  /// Makes a fill() in progress return at its next publication and the waits past it fail (an
  /// aborted run).
  void stop_fill() const;
  /// Blocks until imu[k] (and every epoch up to it) is written; returns how many samples are
  /// written. Throws std::runtime_error when fill() stopped before k.
  long long wait_for(long long k) const;
  /// Sample k's increments (0-based: t = (k + 1) / rate) and epoch e's truth.
  const Increment& increment(long long k) const { return imu[static_cast<std::size_t>(k)]; }
  const TruthSample& epoch(long long e) const { return epochs[static_cast<std::size_t>(e)]; }
  /// n: the scenario's IMU samples.
  long long samples() const { return static_cast<long long>(imu.size()); }

 private:
  /// generate()'s with TruthThread::kOwn.
  static TruthTrack prepare(const Scenario& sc, TruthThread where);
};

/// fill() on a thread of its own while the track's readers run; the destructor stops the
/// integration and joins it (an error path), complete() joins it once the readers are done.
class TruthFillThread {
 public:
  explicit TruthFillThread(TruthTrack& track);
  ~TruthFillThread();
  TruthFillThread(const TruthFillThread&) = delete;
  TruthFillThread& operator=(const TruthFillThread&) = delete;
  void complete();

 private:
  TruthTrack& track_;
  std::thread thread_;
};

/// IMU samples per GNSS epoch of a scenario; throws std::runtime_error unless the GPS rate divides
/// the IMU rate.
int imu_samples_per_epoch(const Scenario& sc);

/// One GPS interval of the stream: the IMU samples of (t - 1/gps_rate, t] and the epoch at t
/// (has_epoch false only for a short last step). The almanac is not part of a step: almanac().
struct SensorStep {
  std::vector<fsw::ImuSample> imu;
  bool has_epoch = false;
  fsw::GnssRawEpoch epoch{};
};

class SensorStream {
 public:
  /// The scenario's own seed, truth generated alongside (its integration where `truth` says).
  explicit SensorStream(const Scenario& sc, TruthThread truth = TruthThread::kReader)
      : SensorStream(sc, sc.seed, truth) {}
  /// Throws std::runtime_error for a scenario the simulator rejects or an unreadable almanac.
  /// seed: the run's seed (IMU errors, noise, GPS errors, clock).
  SensorStream(const Scenario& sc, std::uint64_t seed, TruthThread truth = TruthThread::kReader);
  /// The truth of a shared track (which must outlive the stream) and an almanac already read.
  SensorStream(const Scenario& sc, const TruthTrack& track, const std::vector<AlmanacEntry>& almanac,
               std::uint64_t seed);
  ~SensorStream();
  SensorStream(const SensorStream&) = delete;
  SensorStream& operator=(const SensorStream&) = delete;

  /// The next event; false at the end of the scenario (duration reached). `truth` (optional)
  /// receives, for an IMU event, the truth sample of its time: with a shared track only its time
  /// and increments (t_s, dt_s, dtheta_rad, dv_mps) are filled; for a GNSS event the full truth of
  /// the epoch (as epoch_truth()).
  bool next(fsw::InputEvent& ev, TruthSample* truth = nullptr);
  /// The same as an event source of the one driver (fsw/driver.hpp): the next event, held here
  /// until the following call, or nullptr at the end.
  const fsw::InputEvent* next() { return next(event_) ? &event_ : nullptr; }
  /// The next GPS interval (one stream is read either by event or by step, not both); false at
  /// the end. The almanac events are skipped: take them from almanac().
  bool next(SensorStep& step);

  /// The truth at the time of the last GNSS event (full, from either source); valid until the
  /// next event (a shared track's: as long as the track).
  const TruthSample& epoch_truth() const { return *epoch_truth_; }
  /// The truth of the last IMU event (with a shared track: its time and increments only).
  const TruthSample& truth() const { return gen_ ? gen_->current() : track_sample_; }
  /// The full truth of the last IMU event where the source has it: always from the generator;
  /// from a track at the GNSS epoch times and at the last sample; else nullptr.
  const TruthSample* full_truth() const;
  /// The last GNSS event's epoch with the satellite positions the receiver model used (what the
  /// flight software computes from the raw epoch and the almanac).
  const fsw::GnssEpoch& epoch() const { return epoch_; }

  const std::vector<AlmanacEntry>& almanac() const { return gps_->almanac(); }
  int samples_per_epoch() const { return samples_per_epoch_; }
  /// IMU samples of the whole scenario (duration x IMU rate).
  long long total_samples() const { return n_samples_; }

  const ImuErrors& imu_errors() const { return imu_->errors(); }
  const Scenario& scenario() const { return sc_; }

 private:
  const TruthSample& next_truth();

  Scenario sc_;
  std::unique_ptr<FlightMotion> motion_;  ///< live source only
  std::unique_ptr<TruthPipeline> gen_;    ///< live source only
  const TruthTrack* track_ = nullptr;     ///< shared source only
  TruthSample track_sample_;              ///< shared source: the fields the IMU model reads
  long long track_ready_ = 0;             ///< shared source: samples known written (TruthTrack::wait_for)
  std::unique_ptr<ImuModel> imu_;
  std::unique_ptr<GpsModel> gps_;
  std::size_t almanac_sent_ = 0;
  long long sample_ = 0;     ///< IMU samples emitted
  long long n_samples_ = 0;  ///< in the scenario
  int samples_per_epoch_ = 1;
  bool epoch_due_ = false;   ///< the last IMU sample was at an epoch time
  const TruthSample* epoch_truth_ = nullptr;
  fsw::GnssEpoch epoch_{};
  fsw::InputEvent event_{};  ///< what next() hands out
};

}  // namespace sim
