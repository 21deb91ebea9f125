// Google Benchmark of the truth generator (sim/trajectory.hpp, sim/sensor_stream.hpp): the
// simulator's part of every simulated flight, which a single `sdins fly` or `sdins montecarlo
// --runs 1` spends most of its time in (docs/performance.md).
//
// Benchmarks:
//   truth/sample       TruthGenerator::next on the default bank-to-turn scenario, one 1 kHz sample
//                      per iteration (two RK4 steps, two evaluations, the Simpson increments); the
//                      generator flies the scenario from t = 0 and starts again at its end
//   truth/track/<s>    TruthTrack::generate of the default scenario cut to <s> seconds (the Monte
//                      Carlo's shared truth), per call
// Counter samples_per_s: 1 kHz truth samples per second of wall time.
#include <benchmark/benchmark.h>

#include <memory>
#include <string>

#include "sim/scenario.hpp"
#include "sim/sensor_stream.hpp"
#include "sim/trajectory.hpp"

namespace {

void BM_TruthSample(benchmark::State& state) {
  sim::Scenario sc{};
  std::string err;
  const std::unique_ptr<sim::FlightMotion> motion = sim::FlightMotion::create(sc, err);
  if (!motion) {
    state.SkipWithError(("default scenario: " + err).c_str());
    return;
  }
  const long long n = std::llround(sc.duration_s * sc.imu.rate_hz);
  auto gen = std::make_unique<sim::TruthGenerator>(*motion, sc.imu.rate_hz);
  long long k = 0;
  for (auto _ : state) {
    if (k == n) {  // the end of the flight: from the start again (once in 1.8 M samples)
      gen = std::make_unique<sim::TruthGenerator>(*motion, sc.imu.rate_hz);
      k = 0;
    }
    const sim::TruthSample& s = gen->next();
    benchmark::DoNotOptimize(s.dv_mps.data());
    ++k;
  }
  state.counters["samples_per_s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

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

}  // namespace

BENCHMARK(BM_TruthSample)->Name("truth/sample")->UseRealTime();
BENCHMARK(BM_TruthTrack)->Name("truth/track")->Arg(60)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
