// Google Benchmark of the truth generator (sim/trajectory.hpp, sim/sensor_stream.hpp): the
// simulator's part of every simulated flight, which a single `sdins fly` or `sdins montecarlo
// --runs 1` spends most of its time in (docs/performance.md).
//
// Benchmarks:
//   truth/sample       TruthGenerator::next on the default bank-to-turn scenario, one 1 kHz sample
//                      per iteration (two RK4 steps, two evaluations, the Simpson increments); the
//                      generator flies the scenario from t = 0 and starts again at its end
//   truth/pipeline     TruthPipeline::next, the same samples as truth/sample with the integration on
//                      a thread of its own (its wall time per sample; two cores busy)
//   truth/track/<s>    TruthTrack::generate of the default scenario cut to <s> seconds (the Monte
//                      Carlo's shared truth), per call
//   sensors/imu_measure
//                      ImuModel::measure of one 1 kHz sample with the default scenario's drawn IMU
//                      errors (seed 1), over the first 4096 truth samples of the flight in turn:
//                      the per-run part of a Monte Carlo's simulator
// Counter samples_per_s: 1 kHz truth samples per second of wall time.
#include <benchmark/benchmark.h>

#include <memory>
#include <string>
#include <vector>

#include "sim/imu_model.hpp"
#include "sim/scenario.hpp"
#include "sim/sensor_stream.hpp"
#include "sim/trajectory.hpp"
#include "sim/truth_pipeline.hpp"

namespace {

// The motion of scenario sc; null (the benchmark marked skipped with the reason) if it cannot fly.
std::unique_ptr<sim::FlightMotion> default_motion(benchmark::State& state, const sim::Scenario& sc) {
  std::string err;
  std::unique_ptr<sim::FlightMotion> motion = sim::FlightMotion::create(sc, err);
  if (!motion) state.SkipWithError(("default scenario: " + err).c_str());
  return motion;
}

// One truth sample per iteration through a TruthPipeline (kReader: the generator's next() itself);
// the flight starts again at its end (once in 1.8 M samples).
void truth_samples(benchmark::State& state, sim::TruthThread where) {
  const sim::Scenario sc{};
  const std::unique_ptr<sim::FlightMotion> motion = default_motion(state, sc);
  if (!motion) return;
  const long long n = std::llround(sc.duration_s * sc.imu.rate_hz);
  auto truth = std::make_unique<sim::TruthPipeline>(*motion, sc.imu.rate_hz, n, where);
  long long k = 0;
  for (auto _ : state) {
    if (k == n) {
      truth = std::make_unique<sim::TruthPipeline>(*motion, sc.imu.rate_hz, n, where);
      k = 0;
    }
    const sim::TruthSample& s = truth->next();
    benchmark::DoNotOptimize(s.dv_mps.data());
    ++k;
  }
  state.counters["samples_per_s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

void BM_TruthSample(benchmark::State& state) { truth_samples(state, sim::TruthThread::kReader); }
void BM_TruthPipeline(benchmark::State& state) { truth_samples(state, sim::TruthThread::kOwn); }

void BM_TruthTrack(benchmark::State& state) {
  sim::Scenario sc{};
  sc.duration_s = static_cast<double>(state.range(0));
  long long samples = 0;
  for (auto _ : state) {
    const sim::TruthTrack tt = sim::TruthTrack::generate(sc);
    benchmark::DoNotOptimize(tt.imu.data());
    samples += static_cast<long long>(tt.imu.size());
  }
  state.counters["samples_per_s"] = benchmark::Counter(static_cast<double>(samples), benchmark::Counter::kIsRate);
}

void BM_ImuMeasure(benchmark::State& state) {
  const sim::Scenario sc{};
  const std::unique_ptr<sim::FlightMotion> motion = default_motion(state, sc);
  if (!motion) return;
  sim::TruthGenerator gen(*motion, sc.imu.rate_hz);
  std::vector<sim::TruthSample> truth(4096);
  for (sim::TruthSample& t : truth) t = gen.next();
  sim::ImuModel imu(sim::draw_imu_errors(sc.imu, sc.effects, 1), 1);
  std::size_t k = 0;
  for (auto _ : state) {
    const fsw::ImuSample s = imu.measure(truth[k]);
    benchmark::DoNotOptimize(s.dv_mps.data());
    k = (k + 1) & 4095u;
  }
  state.counters["samples_per_s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

}  // namespace

BENCHMARK(BM_TruthSample)->Name("truth/sample")->UseRealTime();
BENCHMARK(BM_TruthPipeline)->Name("truth/pipeline")->UseRealTime();
BENCHMARK(BM_TruthTrack)->Name("truth/track")->Arg(60)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK(BM_ImuMeasure)->Name("sensors/imu_measure")->UseRealTime();

BENCHMARK_MAIN();
